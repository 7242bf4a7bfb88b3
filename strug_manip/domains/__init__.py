"""Domains: the toy POMDPs of Table I (and, later, the manipulation tasks).

``make_domain(name)`` builds one by its canonical name; ``DOMAINS`` lists them.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from planners.errors import UnknownNameError
from planners.pomdp import GenerativePOMDP
from strug_manip.domains.lightdark import LightDark1D, LightDark2D
from strug_manip.domains.tiger import ExtendedTiger, Tiger, TigerClassic

#: Canonical domain name -> constructor, in the column order of the paper's Table I.
DOMAINS: dict[str, Callable[..., GenerativePOMDP]] = {
    "tiger": Tiger,
    "tigerclassic": TigerClassic,
    "extendedtiger": ExtendedTiger,
    "lightdark1d": LightDark1D,
    "lightdark2d": LightDark2D,
}

#: One-line descriptions for ``strug list``.
DOMAIN_SUMMARIES: dict[str, str] = {
    "tiger": "Tiger at the paper's scale: listen -1, doors -10/+10, ends when a door opens",
    "tigerclassic": "classic Tiger (-100/+10/-1), doors reset the tiger, 10 steps",
    "extendedtiger": "Tiger whose listening informs only after 3 listens in a row",
    "lightdark1d": "LightDark1D as POMDPModels.jl: localise near y=5, declare at |y|<1",
    "lightdark2d": "2D room: x is precise near the right wall, y near the top; goal |x-5|<0.5",
}


def make_domain(name: str, **params: Any) -> GenerativePOMDP:
    """The domain called ``name`` (see ``DOMAINS``), built with ``params``."""
    try:
        ctor = DOMAINS[name]
    except KeyError:
        raise UnknownNameError("domain", name, list(DOMAINS)) from None
    return ctor(**params)


__all__ = [
    "DOMAINS",
    "DOMAIN_SUMMARIES",
    "ExtendedTiger",
    "LightDark1D",
    "LightDark2D",
    "Tiger",
    "TigerClassic",
    "make_domain",
]
