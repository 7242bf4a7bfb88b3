"""Perception's errors (``perception`` imports no other package of the stack, so its
errors are defined here and re-exported with the rest in :mod:`strug_manip.errors`).

Every message names the value and what was expected.
"""

from __future__ import annotations


class PerceptionError(ValueError):
    """Base of perception's errors."""


class BadInputError(PerceptionError):
    """An image, depth map, camera pose or option is malformed (shape, dtype, units,
    non-finite values, too many dropouts)."""


class NoCabinetError(PerceptionError):
    """No cabinet was seen in any view (nothing to build a belief from)."""
