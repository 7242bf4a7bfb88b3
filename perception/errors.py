"""Perception's errors (``perception`` imports no other package of the stack, so its
errors are defined here, apart from the rest of the stack's :mod:`planners.errors`).

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
