"""The stack's exception hierarchy (defined in ``planners`` so that it stays numpy-only;
perception's own errors, defined in :mod:`perception.errors` because ``perception``
imports no other package of the stack, are re-exported here too)."""

from perception.errors import BadInputError, NoCabinetError, PerceptionError
from planners.errors import (
    BeliefError,
    ConfigError,
    ObservationError,
    StrugError,
    UnknownNameError,
)

__all__ = [
    "BadInputError",
    "BeliefError",
    "ConfigError",
    "NoCabinetError",
    "ObservationError",
    "PerceptionError",
    "StrugError",
    "UnknownNameError",
]
