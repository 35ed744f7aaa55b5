/// \file Analysis.hpp
/// \brief What a cosmological box is checked by: the matter power spectrum and
///        friends-of-friends haloes.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <numeric>
#include <vector>

#include <pik/pm/ParticleMesh.hpp>

#include "Particles.hpp"

namespace cosmo {

struct PowerBin {
  double k = 0;       ///< mean |k| of the modes in the bin, h/Mpc
  double power = 0;   ///< P(k), (Mpc/h)^3
  double modes = 0;   ///< number of modes
};

/// P(k) from the density the particle mesh assigned in its last force computation
/// (its Fourier modes, every rank's slab): |delta_k|^2 V divided by the square of
/// the assignment window (Hockney & Eastwood 1988; as in the force), in bins of
/// width the fundamental mode 2 pi / L up to the Nyquist frequency. No shot noise
/// is subtracted: particles start on a grid, whose discreteness noise at large
/// scales is far below Poisson's V / N. Collective.
template <class CommT>
std::vector<PowerBin> power_spectrum(const pik::pm::ParticleMesh<CommT>& pm, double total_mass, const CommT& comm) {
  const auto& fft = pm.fft();
  const int n = fft.n(), nzc = fft.nzc(), p = int(pm.params().assignment);
  const double L = pm.params().box, kf = 2 * std::numbers::pi / L, V = L * L * L, N3 = double(n) * n * n;
  // rho_k (FFTW sum over cells of mass / h^3) -> delta_k = rho_k / (N^3 rho_bar)
  const double rho_bar = total_mass / V;
  const std::size_t nb = std::size_t(n / 2);
  std::vector<double> sk(nb, 0), sp(nb, 0), sn(nb, 0);
  const auto modes = pm.densityModes();
  auto sinc = [&](int m) {
    if (m == 0) return 1.0;
    const double x = std::numbers::pi * m / n;
    return std::sin(x) / x;
  };
  for (int ix = 0; ix < fft.nx(); ++ix) {
    const int gx = fft.x0() + ix, mx = gx <= n / 2 ? gx : gx - n;
    for (int iy = 0; iy < n; ++iy) {
      const int my = iy <= n / 2 ? iy : iy - n;
      for (int mz = 0; mz < nzc; ++mz) {
        const double kk = std::sqrt(double(mx * mx + my * my + mz * mz));
        const std::size_t b = std::size_t(std::floor(kk + 0.5)) - 1;  // bin i: |k|/kf in [i + 0.5, i + 1.5)
        if (kk == 0 || b >= nb) continue;
        const std::size_t j = (std::size_t(ix) * n + iy) * nzc + mz;
        const double re = modes[2 * j] / (N3 * rho_bar), im = modes[2 * j + 1] / (N3 * rho_bar);
        const double w = std::pow(sinc(mx) * sinc(my) * sinc(mz), 2 * p);
        const double weight = (mz == 0 || 2 * mz == n) ? 1.0 : 2.0;  // +-k in the half space
        sk[b] += weight * kk * kf, sp[b] += weight * (re * re + im * im) * V / w, sn[b] += weight;
      }
    }
  }
  comm.reduce_inplace(std::span<double>(sk), pik::comm::ReduceOp::sum);
  comm.reduce_inplace(std::span<double>(sp), pik::comm::ReduceOp::sum);
  comm.reduce_inplace(std::span<double>(sn), pik::comm::ReduceOp::sum);
  std::vector<PowerBin> out;
  for (std::size_t b = 0; b < nb; ++b)
    if (sn[b] > 0) out.push_back({sk[b] / sn[b], sp[b] / sn[b], sn[b]});
  return out;
}

/// P(k) of one species alone (one process) on an n_mesh^3 mesh, as power_spectrum.
/// `shift` is taken off every position first (P(k) does not change): a species
/// laid out on the grid shifted by half a cell (the gas) is measured with its
/// lattice on the mesh nodes, as the unshifted one is, so the two share their
/// discreteness terms and can be compared mode by mode.
template <class PS>
std::vector<PowerBin> species_power(const PS& ps, double L, int n_mesh, double shift) {
  pik::pm::MeshParams mp;
  mp.box = L, mp.n_mesh = n_mesh;
  pik::pm::ParticleMesh<pik::SerialComm> pm(mp, pik::SerialComm::world());
  std::vector<V> pos, acc(ps.size());
  std::vector<double> mass;
  double total = 0;
  for (const auto& p : ps) {
    V x = p.pos - V{shift, shift, shift};
    for (int d = 0; d < 3; ++d) x[d] -= L * std::floor(x[d] / L);
    pos.push_back(x), mass.push_back(p.mass), total += p.mass;
  }
  pm.accelerations(pos, mass, acc);
  return power_spectrum(pm, total, pik::SerialComm::world());
}

/// Friends-of-friends groups (Davis et al. 1985, ApJ 292, 371): particles closer
/// than `link` (periodic box of side L) are in one group. Returns the particle
/// counts of the groups with at least `n_min` members, largest first. A chaining
/// mesh of cells of side >= link and union-find: O(N) for a clustered box.
inline std::vector<std::size_t> friends_of_friends(const std::vector<V>& x, double L, double link, std::size_t n_min) {
  const std::size_t n = x.size();
  std::vector<std::uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t i) {
    while (parent[i] != i) parent[i] = parent[parent[i]], i = parent[i];
    return i;
  };
  const int nc = std::max(1, std::min(512, int(L / link)));
  const double cell = L / nc;
  std::vector<std::uint32_t> head(std::size_t(nc) * nc * nc, UINT32_MAX), next(n, UINT32_MAX);
  auto cell_of = [&](double c) { return std::min(nc - 1, std::max(0, int(c / cell))); };
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t c = (std::size_t(cell_of(x[i].x)) * nc + cell_of(x[i].y)) * nc + cell_of(x[i].z);
    next[i] = head[c], head[c] = std::uint32_t(i);
  }
  const double l2 = link * link;
  for (std::size_t i = 0; i < n; ++i) {
    const int cx = cell_of(x[i].x), cy = cell_of(x[i].y), cz = cell_of(x[i].z);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const int ax = (cx + dx + nc) % nc, ay = (cy + dy + nc) % nc, az = (cz + dz + nc) % nc;
          for (std::uint32_t j = head[(std::size_t(ax) * nc + ay) * nc + az]; j != UINT32_MAX; j = next[j]) {
            if (j <= i) continue;
            V d = x[i] - x[j];
            for (int c = 0; c < 3; ++c) d[c] -= L * std::round(d[c] / L);
            if (pik::norm2(d) < l2) {
              const std::uint32_t a = find(std::uint32_t(i)), b = find(j);
              if (a != b) parent[std::max(a, b)] = std::min(a, b);
            }
          }
        }
  }
  std::vector<std::size_t> size(n, 0);
  for (std::size_t i = 0; i < n; ++i) ++size[find(std::uint32_t(i))];
  std::vector<std::size_t> groups;
  for (std::size_t s : size)
    if (s >= n_min) groups.push_back(s);
  std::sort(groups.rbegin(), groups.rend());
  return groups;
}

}  // namespace cosmo
