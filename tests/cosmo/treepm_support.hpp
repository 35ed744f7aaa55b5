// Shared by the TreePM tests: particle types for kernels/gravity_treepm.pik, the
// particle sets, and periodic forces by Ewald summation (the reference).
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include <pik/pik.hpp>
#include <pik/pm/TreePM.hpp>

namespace tpm {

using V = pik::Vec3<double>;

struct Force {
  pik::Vec3<float> acc;
  void clear() { acc = {}; }
};
struct Body {
  std::uint64_t id = 0;
  double mass = 0;
  V pos{}, acc_short{}, acc_long{};
  const V& getPos() const { return pos; }
  void setPos(const V& x) { pos = x; }
  void copyFromForce(const Force& f) { acc_short = pik::vec_cast<V>(f.acc); }
  void copyFromForceParticleMesh(const V& a) { acc_long = a; }
  double getChargeParticleMesh() const { return mass; }
  V acc() const { return acc_short + acc_long; }
};
struct EPI {
  pik::Vec3<float> pos;
  const pik::Vec3<float>& getPos() const { return pos; }
  void copyFromFP(const Body& b) { pos = pik::vec_cast<pik::Vec3<float>>(b.pos); }
};
struct EPJ {
  pik::Vec3<float> pos;
  float mass;
  const pik::Vec3<float>& getPos() const { return pos; }
  void setPos(const pik::Vec3<float>& x) { pos = x; }
  float getCharge() const { return mass; }
  void copyFromFP(const Body& b) { pos = pik::vec_cast<pik::Vec3<float>>(b.pos), mass = float(b.mass); }
};
using SPJ = pik::SPJMonopole<float>;

/// n particles of total mass 1 in [0, L)^3: uniform, or (clustered) 70 % in five
/// Gaussian clumps of widths 0.01-0.05 L (wrapped), 30 % uniform.
inline std::vector<Body> make_set(std::size_t n, double L, bool clustered, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> g(0, 1);
  std::vector<Body> b(n);
  V centre[5];
  double width[5];
  for (int c = 0; c < 5; ++c) centre[c] = {u(rng) * L, u(rng) * L, u(rng) * L}, width[c] = (0.01 + 0.01 * c) * L;
  auto wrap = [&](double x) {
    x -= L * std::floor(x / L);
    return x >= L ? 0.0 : x;
  };
  for (std::size_t i = 0; i < n; ++i) {
    V x{u(rng) * L, u(rng) * L, u(rng) * L};
    if (clustered && u(rng) < 0.7) {
      const int c = int(u(rng) * 5) % 5;
      x = {wrap(centre[c].x + width[c] * g(rng)), wrap(centre[c].y + width[c] * g(rng)),
           wrap(centre[c].z + width[c] * g(rng))};
    }
    b[i].id = i, b[i].mass = 1.0 / double(n), b[i].pos = x;
  }
  return b;
}

/// Periodic accelerations (G = 1, no softening, uniform background subtracted) at
/// the particles `at` of the set `all`, by Ewald summation (Ewald 1921; e.g. Hernquist,
/// Bouchet & Suto 1991, ApJS 75, 231, eqs. 2.14-2.15): real-space images |n| <= 1
/// and Fourier modes |n_d| <= 5 with alpha = 2.5 / L, so both omitted tails are
/// below 1e-7 of a typical force.
inline std::vector<V> ewald(const std::vector<Body>& all, const std::vector<std::size_t>& at, double L) {
  const double alpha = 2.5 / L, pi = std::numbers::pi, V3 = L * L * L;
  const int kmax = 5;
  struct Mode {
    V k;
    double c, s, f;  // sum_j m_j cos(k x_j), sum_j m_j sin(k x_j), 4 pi / V exp(-k^2 / 4 alpha^2) / k^2
  };
  std::vector<Mode> modes;
  for (int a = -kmax; a <= kmax; ++a)
    for (int b = -kmax; b <= kmax; ++b)
      for (int c = 0; c <= kmax; ++c) {
        if (c == 0 && (b < 0 || (b == 0 && a <= 0))) continue;  // half space: k and -k together
        const V k{2 * pi * a / L, 2 * pi * b / L, 2 * pi * c / L};
        const double k2 = pik::norm2(k);
        Mode m{k, 0, 0, 2 * 4 * pi / V3 * std::exp(-k2 / (4 * alpha * alpha)) / k2};  // x2: both halves
        for (const Body& p : all) {
          const double ph = pik::dot(k, p.pos);
          m.c += p.mass * std::cos(ph), m.s += p.mass * std::sin(ph);
        }
        modes.push_back(m);
      }
  std::vector<V> acc(at.size());
  for (std::size_t t = 0; t < at.size(); ++t) {
    const V xi = all[at[t]].pos;
    V a{};
    for (const Body& p : all) {
      V r = xi - p.pos;
      for (int d = 0; d < 3; ++d) r[d] -= L * std::round(r[d] / L);
      for (int nx = -1; nx <= 1; ++nx)
        for (int ny = -1; ny <= 1; ++ny)
          for (int nz = -1; nz <= 1; ++nz) {
            const V rn = r + V{nx * L, ny * L, nz * L};
            const double d2 = pik::norm2(rn);
            if (d2 == 0) continue;
            const double d = std::sqrt(d2);
            const double g = std::erfc(alpha * d) + 2 * alpha * d / std::sqrt(pi) * std::exp(-alpha * alpha * d2);
            a -= rn * (p.mass * g / (d2 * d));
          }
    }
    // Fourier part: -(4 pi / V) sum_k k / k^2 exp(-k^2/4a^2) sum_j m_j sin(k (x_i - x_j)).
    for (const Mode& m : modes) {
      const double ph = pik::dot(m.k, xi);
      const double s = std::sin(ph) * m.c - std::cos(ph) * m.s;
      a -= m.k * (m.f * s);
    }
    acc[t] = a;
  }
  return acc;
}

/// rms over the sample of |a - a_ref| / |a_ref|.
inline double rms_relative(const std::vector<V>& a, const std::vector<V>& ref) {
  double s = 0;
  for (std::size_t i = 0; i < a.size(); ++i) s += pik::norm2(a[i] - ref[i]) / pik::norm2(ref[i]);
  return std::sqrt(s / double(a.size()));
}

}  // namespace tpm
