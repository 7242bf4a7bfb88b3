"""Shared fixtures: toy domains and solver configs with small budgets."""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")  # before anything imports mujoco

import numpy as np
import pytest

from strug_manip.domains import DOMAINS, make_domain

TOY_DOMAINS = tuple(DOMAINS)


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


@pytest.fixture(params=TOY_DOMAINS)
def toy_domain(request):
    return make_domain(request.param)
