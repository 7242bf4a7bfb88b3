"""Shared fixtures: toy domains and solver configs with small budgets; the robot world
of ``models/cabinets/drawers_11`` and a control context, one per test module."""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")  # before anything imports mujoco

import numpy as np
import pytest

from strug_manip.domains import TOY_DOMAINS, make_domain


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


@pytest.fixture(params=TOY_DOMAINS)
def toy_domain(request):
    return make_domain(request.param)


@pytest.fixture(scope="module")
def world():
    """The Fetch before the drawers-only cabinet of seed 11 (``drawers_11``), one per
    test module (a module's tests may move it; each resets what it needs)."""
    from strug_manip.world import ManipulationWorld, SceneConfig

    w = ManipulationWorld(SceneConfig(cabinet_seed=11, cabinet_kinds=("drawer",)))
    yield w
    w.close()


@pytest.fixture(scope="module")
def ctx():
    """A fresh :class:`~strug_manip.control.ControlContext` (IK, planners, caches) per
    test module."""
    from strug_manip.control import ControlContext

    return ControlContext()
