"""Shared fixtures of the pik package tests: seeded particles and the bindings."""
import numpy as np
import pytest


@pytest.fixture
def rng():
    return np.random.default_rng(20261201)


@pytest.fixture(scope="session")
def native():
    """pik's compiled bindings; the tests needing them skip, saying why, without them."""
    import pik._native
    try:
        return pik._native.native()
    except ImportError as e:
        pytest.skip(str(e))


def direct_gravity(pos, mass, eps):
    """Softened gravity by direct summation in float64 (the oracle)."""
    d = pos[None, :, :] - pos[:, None, :]  # x_j - x_i
    r2 = (d * d).sum(-1) + eps * eps
    rinv = 1.0 / np.sqrt(r2)
    acc = (mass[None, :, None] * d * (rinv ** 3)[..., None]).sum(1)
    pot = -(mass[None, :] * rinv).sum(1)
    return acc, pot
