"""Domains: the toy POMDPs of Table I and the manipulation tasks (Shelf, OpenDrawer,
OpenDoor: :mod:`strug_manip.domains.manipulation`, imported on first use, since they
load MuJoCo worlds and the perception network).

``make_domain(name)`` builds one by its canonical name (``DOMAINS`` lists them) or,
for a user's own domain, by ``"package.module:Class"``: the module is imported (the
current directory first on the import path, as ``strug`` is run from a project's
folder), and ``Class()``, built without arguments, must be a ``GenerativePOMDP``.
"""

from __future__ import annotations

import importlib
import os
import sys
from collections.abc import Callable
from typing import Any

from planners.errors import ConfigError, UnknownNameError
from planners.pomdp import GenerativePOMDP
from strug_manip.domains.lightdark import LightDark1D, LightDark2D
from strug_manip.domains.tiger import ExtendedTiger, Tiger, TigerClassic


def _manipulation(cls_name: str) -> Callable[..., GenerativePOMDP]:
    def make(**params: Any) -> GenerativePOMDP:
        from strug_manip.domains.manipulation import tasks

        return getattr(tasks, cls_name)(**params)

    make.__name__ = make.__qualname__ = cls_name
    return make


#: The toy domains, in the column order of the paper's Table I.
TOY_DOMAINS: dict[str, Callable[..., GenerativePOMDP]] = {
    "tiger": Tiger,
    "tigerclassic": TigerClassic,
    "extendedtiger": ExtendedTiger,
    "lightdark1d": LightDark1D,
    "lightdark2d": LightDark2D,
}
#: The manipulation tasks (constructors that import their module on first use).
MANIPULATION_DOMAINS: dict[str, Callable[..., GenerativePOMDP]] = {
    "shelf": _manipulation("ShelfTask"),
    "opendrawer": _manipulation("OpenDrawerTask"),
    "opendoor": _manipulation("OpenDoorTask"),
}
#: Simulations per decision on the manipulation tasks when none are asked for (CLI and
#: bench): each costs a twin's skill (tens of ms) where a toy domain's costs microseconds.
#: 100 (issue 37): STRUG's root puts them where its particles' plans begin (PUCT), so
#: most revisit cached twin outcomes, and a decision takes about 2 s (20 simulations
#: over every root action took 3-4 s and decided by the luckiest single return).
MANIPULATION_SIMS = 100
#: Root particles M of STRUG's compatibility matrix and of Entropy Regularized's and
#: Active Learning's estimates on the manipulation tasks when none are asked for: each
#: particle's plan pays its own Place placement search (about 0.2-0.4 s cold), and the
#: belief holds at most 24 models.
MANIPULATION_PARTICLES = 12
#: Canonical domain name -> constructor, in the column order of the paper's Table I.
DOMAINS: dict[str, Callable[..., GenerativePOMDP]] = {**TOY_DOMAINS, **MANIPULATION_DOMAINS}

#: One-line descriptions for ``strug list``.
DOMAIN_SUMMARIES: dict[str, str] = {
    "tiger": "Tiger at the paper's scale: listen -1, doors -10/+10, ends when a door opens",
    "tigerclassic": "classic Tiger (-100/+10/-1), doors reset the tiger, 10 steps",
    "extendedtiger": "Tiger whose listening informs only after 3 listens in a row",
    "lightdark1d": "LightDark1D as POMDPModels.jl: localise near y=5, declare at |y|<1",
    "lightdark2d": "2D room: x is precise near the right wall, y near the top; goal |x-5|<0.5",
    "shelf": "Fetch puts the object on an open shelf cell of an unseen cabinet (+10, drag -10)",
    "opendrawer": "Fetch opens the target drawer of an unseen cabinet, puts the object in it",
    "opendoor": "Fetch opens the target door of an unseen cabinet, puts the object behind it",
}


def is_user_domain(name: str) -> bool:
    """True when ``name`` has the form ``package.module:Class`` (a user's own domain)."""
    return ":" in name


def domain_class(name: str) -> Callable[..., GenerativePOMDP]:
    """The constructor of domain ``name``: a key of ``DOMAINS`` or ``package.module:Class``.

    Raises:
        UnknownNameError: ``name`` is neither.
        ConfigError: the module cannot be imported, has no such class, or the class is
            not a ``GenerativePOMDP``.
    """
    if not is_user_domain(name):
        try:
            return DOMAINS[name]
        except KeyError:
            raise UnknownNameError("domain", name, [*DOMAINS, "package.module:Class"]) from None
    module_name, _, attr = name.partition(":")
    if not module_name or not attr:
        raise ConfigError(f"a user domain is named package.module:Class, got {name!r}")
    if os.getcwd() not in sys.path:
        sys.path.insert(0, os.getcwd())
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        raise ConfigError(f"domain {name!r}: cannot import {module_name!r} ({exc})") from None
    cls = getattr(module, attr, None)
    if not (isinstance(cls, type) and issubclass(cls, GenerativePOMDP)):
        what = "no such attribute" if cls is None else f"{cls!r} is not a GenerativePOMDP class"
        raise ConfigError(f"domain {name!r}: {what}")
    return cls


def make_domain(name: str, **params: Any) -> GenerativePOMDP:
    """The domain called ``name`` (see ``domain_class``), built with ``params``."""
    return domain_class(name)(**params)


__all__ = [
    "DOMAINS",
    "DOMAIN_SUMMARIES",
    "MANIPULATION_DOMAINS",
    "MANIPULATION_PARTICLES",
    "MANIPULATION_SIMS",
    "TOY_DOMAINS",
    "ExtendedTiger",
    "LightDark1D",
    "LightDark2D",
    "Tiger",
    "TigerClassic",
    "domain_class",
    "is_user_domain",
    "make_domain",
]
