/// \file InitialConditions.hpp
/// \brief Initial conditions: a Gaussian random field of a linear power spectrum
///        displaced from a grid by the Zel'dovich approximation, and a single plane
///        wave (the Zel'dovich pancake, exact until shell crossing).
///
/// Zel'dovich (1970, A&A 5, 84): x = q + D(a) psi(q), p = a^2 dx/dt = a^2 H f D psi,
/// with delta = -div psi, so psi_k = i k / k^2 delta_k. The field: white noise on
/// the grid (seeded, so a seed gives the same box on any rank count), Fourier
/// transformed and scaled by sqrt(P(k) N^3 / V) (e.g. Bertschinger 2001, ApJS 137,
/// 1); the Nyquist planes are set to zero.
#pragma once

#include <cmath>
#include <cstdint>
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

/// n^3 particles of a box of side L at scale factor a (all on the calling rank).
inline std::vector<Body> zeldovich(const Background& bg, const PowerSpectrum& pk, int n, double L, double a,
                                   std::uint64_t seed) {
  pik::pm::detail::SlabFft fft(n, pik::SerialComm::world());
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0, 1);
  for (int x = 0; x < n; ++x)
    for (int y = 0; y < n; ++y)
      for (int z = 0; z < n; ++z) fft.real(x, y, z) = g(rng);
  fft.forward();
  const std::size_t nc = std::size_t(n) * fft.complex_plane();
  const double* c = reinterpret_cast<const double*>(fft.complex_data());
  const std::vector<double> white(c, c + 2 * nc);
  const double V = L * L * L, N3 = double(n) * n * n, kf = 2 * std::numbers::pi / L;
  const double D = bg.growth(a), vel = a * a * bg.hubble(a) * bg.growth_rate(a) * D;
  std::vector<Body> b(static_cast<std::size_t>(N3));
  const double m = particle_mass(bg, L, n), dq = L / n;
  for (int x = 0; x < n; ++x)
    for (int y = 0; y < n; ++y)
      for (int z = 0; z < n; ++z) {
        Body& p = b[(std::size_t(x) * n + y) * n + z];
        p.id = (std::uint64_t(x) * n + y) * n + z, p.mass = m, p.pos = {x * dq, y * dq, z * dq};
      }
  for (int d = 0; d < 3; ++d) {
    double* o = reinterpret_cast<double*>(fft.complex_data());
    for (int x = 0; x < n; ++x)
      for (int y = 0; y < n; ++y)
        for (int z = 0; z <= n / 2; ++z) {
          const std::size_t j = (std::size_t(x) * n + y) * (n / 2 + 1) + z;
          const int mx = x <= n / 2 ? x : x - n, my = y <= n / 2 ? y : y - n, mz = z;
          const bool nyquist = 2 * std::abs(mx) == n || 2 * std::abs(my) == n || 2 * mz == n;
          const double k2 = kf * kf * double(mx * mx + my * my + mz * mz);
          if (k2 == 0 || nyquist) {
            o[2 * j] = o[2 * j + 1] = 0;
            continue;
          }
          const double kd = kf * (d == 0 ? mx : (d == 1 ? my : mz));
          const double amp = std::sqrt(pk(std::sqrt(k2)) * N3 / V) / N3;  // backward FFT sums N^3 terms
          // psi_k = i k_d / k^2 delta_k
          const double re = white[2 * j] * amp, im = white[2 * j + 1] * amp;
          o[2 * j] = -kd / k2 * im, o[2 * j + 1] = kd / k2 * re;
        }
    fft.backward();
    for (int x = 0; x < n; ++x)
      for (int y = 0; y < n; ++y)
        for (int z = 0; z < n; ++z) {
          Body& p = b[(std::size_t(x) * n + y) * n + z];
          const double psi = fft.real(x, y, z);
          p.pos[d] += D * psi, p.mom[d] = vel * psi;
        }
  }
  for (Body& p : b)
    for (int d = 0; d < 3; ++d) p.pos[d] -= L * std::floor(p.pos[d] / L);
  return b;
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
