"""Articulated objects: the procedural cabinet generator and the PartNet-Mobility loader.

- :mod:`strug_manip.objects.generator`: ``generate_cabinet(seed, kinds=...)``.
- :mod:`strug_manip.objects.partnet`: ``write_partnet`` (a generated cabinet as a
  PartNet-Mobility folder).
- :mod:`strug_manip.objects.urdf`: ``parse_urdf`` (URDF + semantics.txt, validated).
- :mod:`strug_manip.objects.mjcf`: a parsed URDF as MuJoCo bodies.
- :mod:`strug_manip.objects.loader`: ``load_articulated_object`` (a folder),
  ``load_cabinet_spec`` (a spec, in memory), ``add_to_spec`` (into a scene).
"""

from strug_manip.objects.generator import (
    HANDLE_KINDS,
    PART_KINDS,
    CabinetSpec,
    PartSpec,
    generate_cabinet,
)
from strug_manip.objects.loader import (
    ArticulatedObject,
    add_to_spec,
    load_articulated_object,
    load_cabinet_spec,
)
from strug_manip.objects.partnet import write_partnet
from strug_manip.objects.urdf import JointInfo, LinkInfo, ParsedUrdf, parse_urdf, parse_urdf_text

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
    "load_cabinet_spec",
    "parse_urdf",
    "parse_urdf_text",
    "write_partnet",
]
