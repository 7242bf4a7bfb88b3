"""Articulated objects: the procedural cabinet generator and the PartNet-Mobility loader.

- :mod:`strug_manip.objects.generator`: ``generate_cabinet(seed, kinds=...)``.
- :mod:`strug_manip.objects.partnet`: ``write_partnet``, ``load_articulated_object``,
  ``add_to_spec``, ``parse_urdf``.
"""

from strug_manip.objects.generator import (
    HANDLE_KINDS,
    PART_KINDS,
    CabinetSpec,
    PartSpec,
    generate_cabinet,
)
from strug_manip.objects.partnet import (
    ArticulatedObject,
    JointInfo,
    LinkInfo,
    ParsedUrdf,
    add_to_spec,
    load_articulated_object,
    parse_urdf,
    write_partnet,
)

__all__ = [
    "HANDLE_KINDS",
    "PART_KINDS",
    "ArticulatedObject",
    "CabinetSpec",
    "JointInfo",
    "LinkInfo",
    "ParsedUrdf",
    "PartSpec",
    "add_to_spec",
    "generate_cabinet",
    "load_articulated_object",
    "parse_urdf",
    "write_partnet",
]
