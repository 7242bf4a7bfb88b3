"""The library's one exception hierarchy, re-exported by :mod:`planners`.

Every error the planners raise on bad input derives from :class:`PlannersError`, so a
caller can catch the family with one ``except`` and a user sees one sentence naming
the bad value and what was expected, never a traceback from deep inside numpy. The
rest of the stack (the robot world, skills, the command line) raises these same
classes; ``perception`` keeps its own (:mod:`perception.errors`) because it imports
no other package of the stack.
"""

from __future__ import annotations


class PlannersError(Exception):
    """Base class of every error raised on bad input or impossible requests."""


class ConfigError(PlannersError, ValueError):
    """A hyper-parameter or option has an impossible value (negative count, NaN, ...)."""


class ModelError(PlannersError, ValueError):
    """A domain (a :class:`planners.pomdp.GenerativePOMDP`) is incomplete or malformed:
    a missing class attribute, an attribute of the wrong type, a bad action space."""


class UnknownNameError(PlannersError, ValueError):
    """A name (domain, solver, config field) is not one of the valid choices."""

    def __init__(self, kind: str, name: object, choices: list[str] | tuple[str, ...]) -> None:
        self.kind = kind
        self.name = name
        self.choices = tuple(choices)
        super().__init__(f"unknown {kind} {name!r}; expected one of: {', '.join(self.choices)}")


class BeliefError(PlannersError, ValueError):
    """A belief cannot be formed or updated (all weights zero, NaN weights, empty set)."""


class ObservationError(PlannersError, ValueError):
    """An observation is malformed (NaN, wrong shape) for the domain it was given to."""


def check_positive_int(name: str, value: object, *, allow_zero: bool = False) -> int:
    """Return ``value`` as an int, or raise :class:`ConfigError` naming ``name``.

    Booleans and non-integral floats are rejected: ``sims=2.5`` is a typo, not a request.
    """
    ok = (
        isinstance(value, int | float) and not isinstance(value, bool) and float(value).is_integer()
    )
    low = 0 if allow_zero else 1
    if not ok or int(value) < low:  # type: ignore[arg-type]
        bound = ">= 0" if allow_zero else ">= 1"
        raise ConfigError(f"{name} must be an integer {bound}, got {value!r}")
    return int(value)  # type: ignore[arg-type]


def check_positive_float(
    name: str, value: object, *, allow_zero: bool = False, upper: float | None = None
) -> float:
    """Return ``value`` as a finite float > 0 (or >= 0), optionally <= ``upper``."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ConfigError(f"{name} must be a number, got {value!r}")
    x = float(value)
    if x != x or x in (float("inf"), float("-inf")):
        raise ConfigError(f"{name} must be finite, got {value!r}")
    if x < 0 or (x == 0 and not allow_zero):
        raise ConfigError(f"{name} must be {'>= 0' if allow_zero else '> 0'}, got {value!r}")
    if upper is not None and x > upper:
        raise ConfigError(f"{name} must be <= {upper}, got {value!r}")
    return x
