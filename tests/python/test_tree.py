"""pik.gravity and pik.neighbours (the runtime's trees) against brute force."""
import numpy as np
import pytest

import pik
from conftest import direct_gravity


@pytest.fixture
def cloud(rng):
    n = 3000
    return rng.normal(size=(n, 3)), rng.uniform(0.5, 1.5, n) / n


def test_theta_zero_is_the_direct_sum(native, cloud):
    pos, mass = cloud
    acc, pot = pik.gravity(pos, mass, eps=0.02, theta=0.0, precision="f64")
    a, p = direct_gravity(pos, mass, 0.02)
    np.testing.assert_allclose(acc, a, rtol=0, atol=1e-12 * np.abs(a).max())
    np.testing.assert_allclose(pot, p, rtol=1e-12)


@pytest.mark.parametrize("precision", ["f32", "f64"])
def test_barnes_hut_error_is_small(native, cloud, precision):
    """Monopole Barnes-Hut at theta = 0.5 (box opening): rms relative force error
    around 1e-3 (Barnes & Hut 1989, ApJS 70, 389, fig. 4 range); we require < 5e-3."""
    pos, mass = cloud
    acc, pot, st = pik.gravity(pos, mass, eps=0.02, theta=0.5, precision=precision, stats=True)
    a, p = direct_gravity(pos, mass, 0.02)
    err = np.sqrt(np.mean(((acc - a) ** 2).sum(1) / (a ** 2).sum(1)))
    assert 1e-6 < err < 5e-3
    assert st["cell_interactions"] > 0  # the tree did use cells
    assert np.abs(pot - p).max() < 1e-2 * np.abs(p).max()


def test_threads_give_identical_forces(native, cloud):
    pos, mass = cloud
    one = pik.gravity(pos, mass, eps=0.02, threads=1)
    two = pik.gravity(pos, mass, eps=0.02, threads=2)
    assert one[0].tobytes() == two[0].tobytes() and one[1].tobytes() == two[1].tobytes()


def test_uniform_sphere_potential_energy(native, rng):
    """W = -3/5 G M^2 / R for a uniform sphere (Binney & Tremaine 2008, eq. 2.41);
    with N = 20000, eps = 0.005 the sampled sphere agrees to 1 %."""
    n = 20000
    x = rng.uniform(-1, 1, size=(3 * n, 3))
    x = x[(x ** 2).sum(1) <= 1][:n]
    m = np.full(n, 1.0 / n)
    _, pot = pik.gravity(x, m, eps=0.005, theta=0.5)
    w = 0.5 * (m * (pot + m / 0.005)).sum()  # without each particle's own -m/eps term
    assert abs(w / -0.6 - 1) < 0.01


def test_bad_arguments(native, cloud):
    pos, mass = cloud
    with pytest.raises(ValueError, match="shape"):
        pik.gravity(pos[:, :2], mass, eps=0.1)
    with pytest.raises(ValueError, match="entries"):
        pik.gravity(pos, mass[:-1], eps=0.1)
    with pytest.raises(ValueError, match="precision"):
        pik.gravity(pos, mass, eps=0.1, precision="f16")
    with pytest.raises(ValueError, match="opening"):
        pik.gravity(pos, mass, eps=0.1, opening="sideways")


def brute_neighbours(pos, r, mode, box=None):
    d = pos[:, None, :] - pos[None, :, :]
    if box is not None:
        L = box[1] - box[0]
        d -= L * np.round(d / L)
    d2 = (d ** 2).sum(-1)
    ri = np.broadcast_to(r, len(pos))
    cut = {"gather": ri[:, None], "scatter": ri[None, :],
           "symmetric": np.maximum(ri[:, None], ri[None, :])}[mode]
    return [np.flatnonzero(row) for row in d2 < cut ** 2]


@pytest.mark.parametrize("mode", ["gather", "scatter", "symmetric"])
def test_neighbours_match_brute_force(native, rng, mode):
    pos = rng.uniform(size=(1500, 3))
    h = rng.uniform(0.05, 0.15, 1500)  # SPH-like varying radii
    nb = pik.neighbours(pos, h, mode=mode)
    ref = brute_neighbours(pos, h, mode)
    assert len(nb) == 1500
    for i in range(1500):
        np.testing.assert_array_equal(nb[i], ref[i])


def test_periodic_neighbours(native, rng):
    pos = rng.uniform(size=(800, 3))
    box = np.array([[0, 0, 0], [1, 1, 1]], float)
    nb = pik.neighbours(pos, 0.12, box=box)
    ref = brute_neighbours(pos, 0.12, "gather", box)
    for i in range(800):
        np.testing.assert_array_equal(nb[i], ref[i])
    i, j = nb.pairs()
    assert len(i) == len(j) == nb.counts().sum()


def test_neighbours_threads_and_errors(native, rng):
    pos = rng.uniform(size=(1000, 3))
    a = pik.neighbours(pos, 0.1, threads=1)
    b = pik.neighbours(pos, 0.1, threads=2)
    assert np.array_equal(a.offsets, b.offsets) and np.array_equal(a.indices, b.indices)
    with pytest.raises(ValueError, match="radius"):
        pik.neighbours(pos, -np.ones(1000))
    with pytest.raises(ValueError, match="mode"):
        pik.neighbours(pos, 0.1, mode="everywhere")


def test_non_finite_positions_are_refused(native):
    with pytest.raises(ValueError, match="non-finite position"):
        pik.gravity(np.array([[np.nan, 0, 0], [1, 1, 1]]), np.ones(2), eps=0.1)
    with pytest.raises(ValueError, match="non-finite position"):
        pik.neighbours(np.array([[np.inf, 0, 0], [1, 1, 1]]), 0.1)
