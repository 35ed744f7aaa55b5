/// \file InitialConditions.hpp
/// \brief Initial conditions: a Gaussian random field of a linear power spectrum
///        displaced from a grid by the Zel'dovich approximation, and a single plane
///        wave (the Zel'dovich pancake, exact until shell crossing); optionally to
///        second order (2LPT), and on a shifted grid for a second species (gas).
///
/// Zel'dovich (1970, A&A 5, 84): x = q + D(a) psi(q), p = a^2 dx/dt = a^2 H f D psi,
/// with delta = -div psi, so psi_k = i k / k^2 delta_k. The field: white noise on
/// the grid (seeded, so a seed gives the same box on any rank count), Fourier
/// transformed and scaled by sqrt(P(k) N^3 / V) (e.g. Bertschinger 2001, ApJS 137,
/// 1); the Nyquist planes are set to zero.
#pragma once

#include <cmath>
#include <complex>
#include <cstdint>
#include <stdexcept>
#include <numbers>
#include <random>
#include <vector>

#include <pik/pm/detail/SlabFft.hpp>

#include "Cosmology.hpp"
#include "Particles.hpp"

namespace cosmo {

/// The mass of each of n^3 equal particles of a box of side L (code units).
inline double particle_mass(const Background& bg, double L, int n) {
  return bg.mean_density() * (L * L * L) / (double(n) * n * n);
}

/// Displacements on the n^3 grid q = (i + offset) L / n per dimension: the first
/// order (Zel'dovich) psi1 and the second order psi2 of 2LPT, x = q + D1 psi1 + D2 psi2.
struct Displacements {
  std::vector<V> psi1, psi2;  ///< index (x n + y) n + z; psi2 empty for first order
};

/// psi1 and (with `second_order`) psi2 of the density field whose Fourier
/// coefficients `delta` are given in FFTW's r2c layout (n * n * (n/2+1) values,
/// normalised so that a backward transform gives delta(q); the Nyquist planes are
/// dropped), sampled at the grid shifted by `offset` cells along each axis.
///
/// Second order (Bouchet et al. 1995, A&A 296, 575; Scoccimarro 1998, MNRAS 299,
/// 1097, eqs. A1-A7; Crocce, Pueblas & Scoccimarro 2006, MNRAS 373, 369, eqs. 3-7):
/// with phi1 the potential of psi1 = -grad phi1, div psi1 = -delta, the second-order
/// potential solves lap phi2 = sum_{i>j} (phi1_ii phi1_jj - phi1_ij^2) and psi2 =
/// grad phi2; the growth factor of the second order is D2 = -3/7 D1^2 Omega_m^-1/143
/// (lpt_d2). All derivatives spectrally; the source is the product of the six
/// second derivatives on the (shifted) grid.
inline Displacements lpt_displacements(const std::vector<std::complex<double>>& delta, int n, double L, double offset,
                                       bool second_order) {
  pik::pm::detail::SlabFft fft(n, pik::SerialComm::world());
  const int nzc = n / 2 + 1;
  const std::size_t nc = std::size_t(n) * n * nzc, N3 = std::size_t(n) * n * n;
  if (delta.size() != nc) throw std::invalid_argument("lpt_displacements: delta has the wrong size");
  const double kf = 2 * std::numbers::pi / L;
  // Fills the transform with f(k) * coefficient (coefficients c, or delta) times the
  // phase of the shifted grid, transforms back, returns the real field.
  auto field = [&](const std::vector<std::complex<double>>& c, double shift, auto&& f) {
    auto* o = reinterpret_cast<std::complex<double>*>(fft.complex_data());
    for (int x = 0; x < n; ++x)
      for (int y = 0; y < n; ++y)
        for (int z = 0; z < nzc; ++z) {
          const std::size_t j = (std::size_t(x) * n + y) * nzc + z;
          const int mx = x <= n / 2 ? x : x - n, my = y <= n / 2 ? y : y - n, mz = z;
          const bool nyquist = 2 * std::abs(mx) == n || 2 * std::abs(my) == n || 2 * mz == n;
          const double kv[3] = {kf * mx, kf * my, kf * mz};
          const double k2 = kv[0] * kv[0] + kv[1] * kv[1] + kv[2] * kv[2];
          if (k2 == 0 || nyquist) {
            o[j] = 0;
            continue;
          }
          const double ph = 2 * std::numbers::pi * shift * double(mx + my + mz) / n;
          o[j] = f(kv, k2) * c[j] * std::complex<double>(std::cos(ph), std::sin(ph));
        }
    fft.backward();
    std::vector<double> r(N3);
    for (int x = 0; x < n; ++x)
      for (int y = 0; y < n; ++y)
        for (int z = 0; z < n; ++z) r[(std::size_t(x) * n + y) * n + z] = fft.real(x, y, z);
    return r;
  };
  const std::complex<double> I(0, 1);
  Displacements out;
  out.psi1.assign(N3, V{});
  for (int d = 0; d < 3; ++d) {  // psi1_k = i k / k^2 delta_k
    const auto r = field(delta, offset, [&](const double* k, double k2) { return I * k[d] / k2; });
    for (std::size_t i = 0; i < N3; ++i) out.psi1[i][d] = r[i];
  }
  if (!second_order) return out;
  // phi1_k = -delta_k / k^2, so phi1_ij has coefficients k_i k_j / k^2 delta_k.
  const int pairs[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
  std::vector<std::vector<double>> p(6);
  for (int q = 0; q < 6; ++q)
    p[q] = field(delta, offset, [&](const double* k, double k2) { return std::complex<double>(k[pairs[q][0]] * k[pairs[q][1]] / k2); });
  for (int x = 0; x < n; ++x)
    for (int y = 0; y < n; ++y)
      for (int z = 0; z < n; ++z) {
        const std::size_t i = (std::size_t(x) * n + y) * n + z;
        fft.real(x, y, z) = p[0][i] * p[1][i] + p[0][i] * p[2][i] + p[1][i] * p[2][i] - p[3][i] * p[3][i] -
                            p[4][i] * p[4][i] - p[5][i] * p[5][i];
      }
  fft.forward();  // the source on the shifted grid: no further phase
  std::vector<std::complex<double>> src(nc);
  const auto* sc = reinterpret_cast<const std::complex<double>*>(fft.complex_data());
  for (std::size_t j = 0; j < nc; ++j) src[j] = sc[j] / double(N3);
  out.psi2.assign(N3, V{});
  for (int d = 0; d < 3; ++d) {  // phi2_k = -S_k / k^2, psi2 = grad phi2: -i k_d S_k / k^2
    const auto r = field(src, 0.0, [&](const double* k, double k2) { return -I * k[d] / k2; });
    for (std::size_t i = 0; i < N3; ++i) out.psi2[i][d] = r[i];
  }
  return out;
}

/// Omega_m(a) of the background.
inline double omega_m_of(const Background& bg, double a) {
  const double h = bg.hubble(a);
  return bg.omega_m / (a * a * a * h * h);
}
/// The second-order growth factor D2 = -3/7 D1^2 Omega_m(a)^(-1/143) (Bouchet et al.
/// 1995, eq. 45; Scoccimarro 1998, eq. A4) and its rate f2 = dln D2 / dln a =
/// 2 Omega_m(a)^(6/11) (Bouchet et al. 1995, eq. 47).
inline double lpt_d2(const Background& bg, double a) {
  const double d1 = bg.growth(a);
  return -3.0 / 7.0 * d1 * d1 * std::pow(omega_m_of(bg, a), -1.0 / 143.0);
}
inline double lpt_f2(const Background& bg, double a) { return 2 * std::pow(omega_m_of(bg, a), 6.0 / 11.0); }

/// Options of the grid initial conditions.
struct GridIcOptions {
  int order = 1;             ///< 1: Zel'dovich; 2: 2LPT
  double offset = 0;         ///< grid shifted by this many cells along each axis (gas: 0.5)
  double mass_fraction = 1;  ///< of the mean matter density this species carries
  std::uint64_t id_base = 0; ///< ids id_base .. id_base + n^3 - 1
};

/// The Fourier coefficients of the linear density at a = 1 on the n^3 grid: white
/// noise (seeded, filled in x, y, z order) transformed and scaled by sqrt(P(k) N^3 /
/// V) / N^3, so that a backward transform gives delta(q).
inline std::vector<std::complex<double>> linear_density_modes(const PowerSpectrum& pk, int n, double L, std::uint64_t seed) {
  pik::pm::detail::SlabFft fft(n, pik::SerialComm::world());
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0, 1);
  for (int x = 0; x < n; ++x)
    for (int y = 0; y < n; ++y)
      for (int z = 0; z < n; ++z) fft.real(x, y, z) = g(rng);
  fft.forward();
  const int nzc = n / 2 + 1;
  const double V = L * L * L, N3 = double(n) * n * n, kf = 2 * std::numbers::pi / L;
  std::vector<std::complex<double>> c(std::size_t(n) * n * nzc);
  const auto* w = reinterpret_cast<const std::complex<double>*>(fft.complex_data());
  for (int x = 0; x < n; ++x)
    for (int y = 0; y < n; ++y)
      for (int z = 0; z < nzc; ++z) {
        const std::size_t j = (std::size_t(x) * n + y) * nzc + z;
        const int mx = x <= n / 2 ? x : x - n, my = y <= n / 2 ? y : y - n;
        const double k = kf * std::sqrt(double(mx * mx + my * my + z * z));
        c[j] = k > 0 ? w[j] * (std::sqrt(pk(k) * N3 / V) / N3) : 0.0;  // backward FFT sums N^3 terms
      }
  return c;
}

/// n^3 particles of a box of side L at scale factor a (all on the calling rank), by
/// the Zel'dovich approximation (order 1) or 2LPT (order 2): x = q + D1 psi1 + D2
/// psi2, p = a^2 H (f1 D1 psi1 + f2 D2 psi2).
inline std::vector<Body> grid_particles(const Background& bg, const PowerSpectrum& pk, int n, double L, double a,
                                        std::uint64_t seed, const GridIcOptions& o = {}) {
  if (o.order != 1 && o.order != 2) throw std::invalid_argument("initial conditions: order must be 1 or 2");
  const Displacements psi = lpt_displacements(linear_density_modes(pk, n, L, seed), n, L, o.offset, o.order == 2);
  const double D = bg.growth(a), aaH = a * a * bg.hubble(a), v1 = aaH * bg.growth_rate(a) * D;
  const double D2 = lpt_d2(bg, a), v2 = aaH * lpt_f2(bg, a) * D2;
  const std::size_t N3 = std::size_t(n) * n * n;
  std::vector<Body> b(N3);
  const double m = o.mass_fraction * particle_mass(bg, L, n), dq = L / n;
  for (int x = 0; x < n; ++x)
    for (int y = 0; y < n; ++y)
      for (int z = 0; z < n; ++z) {
        const std::size_t i = (std::size_t(x) * n + y) * n + z;
        Body& p = b[i];
        p.id = o.id_base + i, p.mass = m;
        p.pos = {(x + o.offset) * dq, (y + o.offset) * dq, (z + o.offset) * dq};
        p.pos += psi.psi1[i] * D, p.mom = psi.psi1[i] * v1;
        if (o.order == 2) p.pos += psi.psi2[i] * D2, p.mom += psi.psi2[i] * v2;
        for (int d = 0; d < 3; ++d) p.pos[d] -= L * std::floor(p.pos[d] / L);
      }
  return b;
}

/// n^3 particles by the Zel'dovich approximation (grid_particles, order 1).
inline std::vector<Body> zeldovich(const Background& bg, const PowerSpectrum& pk, int n, double L, double a,
                                   std::uint64_t seed) {
  return grid_particles(bg, pk, n, L, a, seed);
}

/// The Zel'dovich pancake: an n^3 grid displaced by one plane wave along x,
/// x = q - (D(a) / D(a_cross)) sin(k q) / k, k = 2 pi / L, which crosses shells at
/// q = 0 when a = a_cross. Exact (for a continuous fluid) until then.
struct Pancake {
  Background bg;
  double L, a_cross;
  double k() const { return 2 * std::numbers::pi / L; }
  double amplitude(double a) const { return bg.growth(a) / bg.growth(a_cross); }
  double x(double q, double a) const { return q - amplitude(a) * std::sin(k() * q) / k(); }
  double p(double q, double a) const {
    return -a * a * bg.hubble(a) * bg.growth_rate(a) * amplitude(a) * std::sin(k() * q) / k();
  }
  std::vector<Body> particles(int n, double a) const {
    std::vector<Body> b;
    const double dq = L / n, m = particle_mass(bg, L, n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        for (int l = 0; l < n; ++l) {
          Body p;
          p.id = (std::uint64_t(i) * n + j) * n + l, p.mass = m;
          const double q = (i + 0.5) * dq;
          p.pos = {x(q, a), (j + 0.5) * dq, (l + 0.5) * dq};
          p.mom = {this->p(q, a), 0, 0};
          p.pos.x -= L * std::floor(p.pos.x / L);
          b.push_back(p);
        }
    return b;
  }
};

}  // namespace cosmo
