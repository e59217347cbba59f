"""Shared test fixtures (the cloths themselves come from :mod:`clothsim.gallery`)."""

from __future__ import annotations

import os

import numpy as np
import pytest

from clothsim.gallery import grid_cloth


@pytest.fixture
def grid_model():
    """Factory fixture: ``grid_model(n=5, k=800.0, plane="xz", ...)`` → Model
    (:func:`clothsim.gallery.grid_cloth`)."""
    return grid_cloth


@pytest.fixture
def rng():
    """A seeded numpy Generator (fixed seed: tests are reproducible)."""
    return np.random.default_rng(20131105)


# The suite never downloads: a test needing the third-party assignment files (jacobson-a8)
# skips when they are absent (tests/data_sets.py); `clothsim data fetch` is tested against
# a local server. Subprocesses the tests start inherit this.
os.environ["CLOTHSIM_OFFLINE"] = "1"
