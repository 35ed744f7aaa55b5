"""pik.Kernel.neighbour_sum: a .pik kernel through the runtime's short-range tree."""
import numpy as np
import pytest

import pik

# -- the kernel through the runtime's neighbour search ------------------------------
POLY6 = """\
// SPH density with the poly6 smoothing function (Mueller, Charypar & Gross 2003,
// SCA, eq. 20): W(r, h) = 315 / (64 pi h^9) (h^2 - r^2)^3 for r < h; and a count.
EPI F64vec xi:pos
EPI F64    hi:h
EPJ F64vec xj:pos
EPJ F64    mj:mass
FORCE F64  rho:rho
FORCE F64  nn:nn
d = xi - xj
r2 = d * d
h2 = hi * hi
a = max(h2 - r2, 0.0)
rho += mj * 315.0 / (64.0 * 3.14159265358979323846) * a * a * a / (h2 * h2 * h2 * hi * hi * hi)
if r2 < h2
  nn += 1.0
endif
"""


def test_neighbour_sum_sph_density_matches_brute_force(tmp_path, rng):
    src = tmp_path / "poly6.pik"
    src.write_text(POLY6)
    k = pik.Kernel(src)
    n = 1500
    p = np.zeros(n, k.particle_dtype)
    p["pos"] = rng.uniform(size=(n, 3))
    p["h"] = rng.uniform(0.08, 0.15, n)
    p["mass"] = 1.0 / n
    f = k.neighbour_sum(p, p["h"], threads=2)  # gather: j within h_i
    d2 = ((p["pos"][:, None, :] - p["pos"][None, :, :]) ** 2).sum(-1)
    h2 = p["h"][:, None] ** 2
    w = 315 / (64 * np.pi) * np.maximum(h2 - d2, 0) ** 3 / h2 ** 4.5
    np.testing.assert_allclose(f["rho"], (p["mass"][None, :] * w).sum(1), rtol=1e-12)
    np.testing.assert_array_equal(f["nn"], (d2 < h2).sum(1))
    # the direct kernel call over all pairs gives the same (the cut is in the kernel)
    np.testing.assert_allclose(k(p)["rho"], f["rho"], rtol=1e-12)
    # one thread, the same bits
    assert k.neighbour_sum(p, p["h"], threads=1).tobytes() == f.tobytes()


def test_neighbour_sum_periodic(tmp_path, rng):
    src = tmp_path / "poly6.pik"
    src.write_text(POLY6)
    k = pik.Kernel(src)
    n = 800
    p = np.zeros(n, k.particle_dtype)
    p["pos"] = rng.uniform(size=(n, 3))
    p["h"] = 0.12
    p["mass"] = 1.0 / n
    f = k.neighbour_sum(p, 0.12, box=[[0, 0, 0], [1, 1, 1]])
    d = p["pos"][:, None, :] - p["pos"][None, :, :]
    d -= np.round(d)
    d2 = (d ** 2).sum(-1)
    np.testing.assert_array_equal(f["nn"], (d2 < 0.0144).sum(1))
    w = 315 / (64 * np.pi) * np.maximum(0.0144 - d2, 0) ** 3 / 0.12 ** 9
    np.testing.assert_allclose(f["rho"], (w / n).sum(1), rtol=1e-12)
    with pytest.raises(ValueError, match="mode"):
        k.neighbour_sum(p, 0.1, mode="everywhere")
