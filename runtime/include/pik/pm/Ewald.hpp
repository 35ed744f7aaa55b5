/// \file Ewald.hpp
/// \brief pik::pm::ewald_accelerations: periodic gravitational accelerations by Ewald
///        summation at chosen particles of a large set (the reference TreePM and
///        other periodic solvers are measured against).
///
/// The acceleration at x_i of the masses m_j at x_j in the periodic cube [0, L)^3,
/// G = 1, the uniform background subtracted (so that the k = 0 mode is absent), is
/// split at the Ewald scale 1/alpha into a real-space and a Fourier-space sum
/// (Ewald 1921; Hernquist, Bouchet & Suto 1991, ApJS 75, 231, eqs. 2.14-2.15):
///
///     a_i = - sum_j m_j r_ij / r^3 [erfc(alpha r) + 2 alpha r / sqrt(pi) exp(-alpha^2 r^2)]
///           - (4 pi / V) sum_{k != 0} k / k^2 exp(-k^2 / 4 alpha^2) sum_j m_j sin(k . (x_i - x_j)).
///
/// The real-space sum takes the minimum image of every pair and stops at r_c = L/2
/// (so that no pair is counted twice), with alpha = s / r_c; the Fourier sum takes
/// the modes with |k| <= 2 s alpha. With s = 4 (the default) both omitted tails are
/// below 5e-7 of the pair force at r_c, which is below 1e-6 of a typical force in
/// sets of more than a few thousand particles. The cost is N per target particle in
/// real space and N times the number of modes (about 2200 at s = 4) once for the
/// structure factors, so a thousand targets in 2^21 particles take seconds to a
/// minute, where a sum over all images |n| <= 1 would take hours.
///
/// Plummer softening `eps` (> 0) replaces the nearest image's Newtonian 1/r^2 by
/// r / (r^2 + eps^2)^{3/2}, as in TreePM codes whose short-range kernels soften the
/// nearest image only: the reference is then the softened periodic force.
///
/// `tests/cosmo/test_treepm.cpp` (EwaldMatchesImageSum) compares it with the direct
/// sum over 27 images and 726 modes of tests/cosmo/treepm_support.hpp.
#pragma once

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstddef>
#include <numbers>
#include <span>
#include <vector>

#include "pik/Error.hpp"
#include "pik/Vec.hpp"
#include "pik/detail/Threads.hpp"

namespace pik::pm {

struct EwaldParams {
  /// Accuracy parameter s: alpha r_c = s and k_max = 2 s alpha (tails ~ exp(-s^2)).
  double s = 4.0;
  /// Plummer softening of the nearest image (0: Newtonian).
  double eps = 0.0;
};

/// Accelerations at the particles `at` (indices into pos/mass) of the periodic set.
inline std::vector<Vec3<double>> ewald_accelerations(std::span<const Vec3<double>> pos, std::span<const double> mass,
                                                     std::span<const std::size_t> at, double L, EwaldParams p = {}) {
  if (pos.size() != mass.size()) throw Error("ewald: positions and masses differ in length");
  if (!(L > 0)) throw Error("ewald: the box side must be positive");
  if (!(p.s > 0)) throw Error("ewald: s must be positive");
  for (std::size_t t : at)
    if (t >= pos.size()) throw Error("ewald: target index out of range");
  const double pi = std::numbers::pi, rc = 0.5 * L, alpha = p.s / rc, V3 = L * L * L;
  const double kmax = 2 * p.s * alpha, twopi_L = 2 * pi / L;
  const int nmax = int(std::floor(kmax / twopi_L));
  const std::size_t n = pos.size();
  const int nthreads = std::max(1, pik::detail::max_threads());

  // Modes of the half space (c > 0, or c = 0 and b > 0, or c = b = 0 and a > 0).
  struct Mode {
    int a, b, c;
  };
  std::vector<Mode> modes;
  for (int a = -nmax; a <= nmax; ++a)
    for (int b = -nmax; b <= nmax; ++b)
      for (int c = 0; c <= nmax; ++c) {
        if (c == 0 && (b < 0 || (b == 0 && a <= 0))) continue;
        if (double(a * a + b * b + c * c) * twopi_L * twopi_L > kmax * kmax) continue;
        modes.push_back({a, b, c});
      }
  const int w = 2 * nmax + 1;  // index of (a, b) planes
  auto idx = [&](int a, int b, int c) { return (std::size_t(a + nmax) * std::size_t(w) + std::size_t(b + nmax)) * std::size_t(nmax + 1) + std::size_t(c); };
  const std::size_t ncube = std::size_t(w) * std::size_t(w) * std::size_t(nmax + 1);

  // Structure factors S(k) = sum_j m_j exp(-i k . x_j) on the (a, b, c >= 0) cube,
  // per thread, from per-particle phase factors (two complex products per mode).
  std::vector<std::vector<std::complex<double>>> part(static_cast<std::size_t>(nthreads));
  const std::ptrdiff_t nblocks = std::ptrdiff_t(std::min<std::size_t>(std::size_t(nthreads) * 16, std::max<std::size_t>(n, 1)));
  pik::detail::parallel_for(nblocks, [&](std::ptrdiff_t blk, int th) {
    auto& S = part[std::size_t(th)];
    if (S.empty()) S.assign(ncube, {0.0, 0.0});
    const std::size_t sw = static_cast<std::size_t>(w);
    std::vector<std::complex<double>> ex(sw), ey(sw), ez(static_cast<std::size_t>(nmax + 1)), exy(sw * sw);
    const std::size_t lo = n * std::size_t(blk) / std::size_t(nblocks), hi = n * std::size_t(blk + 1) / std::size_t(nblocks);
    for (std::size_t j = lo; j < hi; ++j) {
      const Vec3<double>& x = pos[j];
      const std::complex<double> fx = std::polar(1.0, -twopi_L * x.x), fy = std::polar(1.0, -twopi_L * x.y),
                                 fz = std::polar(1.0, -twopi_L * x.z);
      ex[std::size_t(nmax)] = ey[std::size_t(nmax)] = ez[0] = 1.0;
      for (int m = 1; m <= nmax; ++m) {
        ex[std::size_t(nmax + m)] = ex[std::size_t(nmax + m - 1)] * fx;
        ey[std::size_t(nmax + m)] = ey[std::size_t(nmax + m - 1)] * fy;
        ez[std::size_t(m)] = ez[std::size_t(m - 1)] * fz;
      }
      for (int m = 1; m <= nmax; ++m) {
        ex[std::size_t(nmax - m)] = std::conj(ex[std::size_t(nmax + m)]);
        ey[std::size_t(nmax - m)] = std::conj(ey[std::size_t(nmax + m)]);
      }
      for (int a = 0; a < w; ++a)
        for (int b = 0; b < w; ++b) exy[std::size_t(a) * std::size_t(w) + std::size_t(b)] = mass[j] * ex[std::size_t(a)] * ey[std::size_t(b)];
      for (const Mode& md : modes) S[idx(md.a, md.b, md.c)] += exy[std::size_t(md.a + nmax) * std::size_t(w) + std::size_t(md.b + nmax)] * ez[std::size_t(md.c)];
    }
  });
  std::vector<std::complex<double>> S(ncube, {0.0, 0.0});
  for (const auto& s : part)
    for (std::size_t q = 0; q < s.size(); ++q) S[q] += s[q];

  struct KMode {
    Vec3<double> k;
    std::complex<double> s;  // S(k) times 2 (both halves) 4 pi / V exp(-k^2/4a^2) / k^2
  };
  std::vector<KMode> km;
  km.reserve(modes.size());
  for (const Mode& md : modes) {
    const Vec3<double> k{twopi_L * md.a, twopi_L * md.b, twopi_L * md.c};
    const double k2 = norm2(k);
    km.push_back({k, S[idx(md.a, md.b, md.c)] * (2 * 4 * pi / V3 * std::exp(-k2 / (4 * alpha * alpha)) / k2)});
  }

  std::vector<Vec3<double>> acc(at.size());
  const double rc2 = rc * rc, eps2 = p.eps * p.eps, two_a_sqrtpi = 2 * alpha / std::sqrt(pi);
  pik::detail::parallel_for(std::ptrdiff_t(at.size()), [&](std::ptrdiff_t t, int) {
    const Vec3<double> xi = pos[at[std::size_t(t)]];
    Vec3<double> a{};
    for (std::size_t j = 0; j < n; ++j) {
      Vec3<double> r = xi - pos[j];
      for (int d = 0; d < 3; ++d) r[d] -= L * std::round(r[d] / L);
      const double d2 = norm2(r);
      if (d2 >= rc2 || d2 == 0) continue;
      const double d = std::sqrt(d2);
      double f = (std::erfc(alpha * d) + two_a_sqrtpi * d * std::exp(-alpha * alpha * d2)) / (d2 * d);
      if (eps2 > 0) f += 1.0 / ((d2 + eps2) * std::sqrt(d2 + eps2)) - 1.0 / (d2 * d);  // soften the nearest image
      a -= r * (mass[j] * f);
    }
    // -(4 pi / V) sum_k k / k^2 exp(-k^2/4a^2) Im(exp(i k . x_i) S(k)), S(k) = sum_j m_j exp(-i k . x_j).
    for (const KMode& m : km) {
      const double ph = dot(m.k, xi);
      const double s = std::sin(ph) * m.s.real() + std::cos(ph) * m.s.imag();
      a -= m.k * s;
    }
    acc[std::size_t(t)] = a;
  });
  return acc;
}

}  // namespace pik::pm
