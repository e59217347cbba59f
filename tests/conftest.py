"""Shared test fixtures (the cloths themselves come from :mod:`clothsim.gallery`)."""

from __future__ import annotations

import os
from pathlib import Path

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


# `make test` hands whole files to its workers (pytest-xdist --dist loadfile: a module's
# fixtures and caches are built once, on one worker), in this order: the files of the
# longest CPU time first (summed --durations of a `-m "not slow" -n 2` run at fasttest3's
# start, longest first), so that no long file starts last while the other worker idles
# (longest processing time first). A file not listed runs after them, in collection order.
LONGEST_FIRST = (
    "ports/test_check_accelerated.py", "ports/test_held_causes.py",
    "ports/test_planted_faults.py", "ports/test_check_held.py", "accuracy/test_robust.py",
    "test_pictures.py", "test_run_pictures.py", "accuracy/test_dominance.py",
    "ports/test_referee_audit.py", "ports/test_docs_example.py", "io/test_round_trip.py",
    "test_docs_outputs.py", "ports/test_check_precision.py", "test_interrupts.py",
    "test_reliability_resume_contact.py", "test_reliability_stops.py",
    "ports/test_causes.py", "test_docs_pages.py", "test_stability_contact.py",
    "ports/test_check_postsolve.py", "test_examples.py", "io/test_frame_process.py",
    "ports/test_liu13.py", "accuracy/test_decide.py", "accuracy/test_study.py",
)


@pytest.hookimpl(trylast=True)   # after pytest's own grouping of items by fixture
def pytest_collection_modifyitems(items):
    """Run the files of :data:`LONGEST_FIRST` first, in its order (a stable sort: each
    file's own order of tests, grouped by its fixtures, is kept)."""
    tests = Path(__file__).resolve().parent
    rank = {str(tests / name): i for i, name in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(str(item.path), len(rank)))
