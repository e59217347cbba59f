"""Shared test fixtures: small grid models, kept generic so any test module can use them."""

from __future__ import annotations

import numpy as np
import pytest

import clothsim as cs

GRAVITY = np.array([0.0, -9.81, 0.0])


def make_grid_model(n: int = 5, *, k: float = 800.0, bending: float | None = None,
                    plane: str = "xz", total_mass: float = 1.0, vertex_mass=None,
                    size: float = 1.0, center=(0.0, 0.0, 0.0)) -> cs.Model:
    """An n × n grid cloth with structural and shear springs of stiffness k [N/m] and
    bending springs of stiffness ``bending`` (default k / 10)."""
    mesh = cs.grid(n, n, size=(size, size), center=center, plane=plane)
    springs = cs.grid_springs(mesh, structural=k, shear=k,
                              bending=k / 10 if bending is None else bending)
    return cs.Model.build(mesh, springs, total_mass=total_mass, vertex_mass=vertex_mass)


@pytest.fixture
def grid_model():
    """Factory fixture: ``grid_model(n=5, k=800.0, plane="xz", ...)`` → Model."""
    return make_grid_model


@pytest.fixture
def rng():
    """A seeded numpy Generator (fixed seed: tests are reproducible)."""
    return np.random.default_rng(20131105)
