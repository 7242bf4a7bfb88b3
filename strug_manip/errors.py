"""The stack's exception hierarchy (defined in ``planners`` so that it stays numpy-only)."""

from planners.errors import (
    BeliefError,
    ConfigError,
    ObservationError,
    StrugError,
    UnknownNameError,
)

__all__ = ["BeliefError", "ConfigError", "ObservationError", "StrugError", "UnknownNameError"]
