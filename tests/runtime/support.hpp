// Shared by the runtime tests: particle classes, plain C++ kernels, initial
// conditions and brute-force O(N^2) oracles. The kernels are ordinary functors with
// the generated-kernel signature; the runtime never knows what they compute.
#pragma once

#include <cmath>
#include <random>
#include <vector>

#include <pik/pik.hpp>

namespace pt {

template <class T>
struct Accel {
  pik::Vec3<T> acc;
  T pot;
  void clear() { acc = {}, pot = 0; }
};

/// One class in every role (FP, EPI, EPJ), as many FDPS programs do.
template <class T>
struct Body {
  pik::Vec3<T> pos;
  T mass = 0;
  T r = 0;  // search radius
  long id = 0;
  pik::Vec3<T> acc{};
  T pot = 0;
  int count = 0;

  pik::Vec3<T> getPos() const { return pos; }
  void setPos(const pik::Vec3<T>& p) { pos = p; }
  T getCharge() const { return mass; }
  T getRSearch() const { return r; }
  void copyFromFP(const Body& b) { *this = b; }
  void copyFromForce(const Accel<T>& f) { acc = f.acc, pot = f.pot; }
};

/// Softened monopole gravity: works for Body and SPJMonopole/SPJQuadrupole j's.
template <class T>
struct Gravity {
  T eps2;
  template <class EPI, class EPJ>
  void operator()(const EPI* pi, int ni, const EPJ* pj, int nj, Accel<T>* f) const {
    for (int i = 0; i < ni; ++i)
      for (int j = 0; j < nj; ++j) {
        pik::Vec3<T> d = pi[i].pos - pj[j].pos;
        T r2 = pik::norm2(d) + eps2, rinv = T(1) / std::sqrt(r2), mr = pj[j].mass * rinv;
        f[i].acc -= d * (mr * rinv * rinv);
        f[i].pot -= mr;
      }
  }
};

/// Quadrupole super-particle gravity (same expressions as kernels/gravity_quadrupole.pik).
template <class T>
struct GravityQuad {
  T eps2;
  template <class EPI>
  void operator()(const EPI* pi, int ni, const pik::SPJQuadrupole<T>* pj, int nj, Accel<T>* f) const {
    for (int i = 0; i < ni; ++i)
      for (int j = 0; j < nj; ++j) {
        const auto& s = pj[j];
        pik::Vec3<T> d = pi[i].pos - s.pos;
        T r2 = pik::norm2(d) + eps2, rinv = T(1) / std::sqrt(r2), rinv2 = rinv * rinv;
        pik::Vec3<T> qd{s.qxx * d.x + s.qxy * d.y + s.qxz * d.z, s.qxy * d.x + s.qyy * d.y + s.qyz * d.z,
                        s.qxz * d.x + s.qyz * d.y + s.qzz * d.z};
        T dqd = pik::dot(d, qd), rinv5 = rinv2 * rinv2 * rinv, mr3 = s.mass * rinv2 * rinv;
        f[i].acc -= d * (mr3 + T(2.5) * dqd * rinv5 * rinv2);
        f[i].acc += qd * rinv5;
        f[i].pot -= s.mass * rinv + T(0.5) * dqd * rinv5;
      }
  }
};

/// Counts j with |x_i - x_j| < r (r by mode), in double, into Accel::pot.
template <class T, pik::SearchMode M>
struct CountNeighbours {
  template <class EPI, class EPJ>
  void operator()(const EPI* pi, int ni, const EPJ* pj, int nj, Accel<T>* f) const {
    for (int i = 0; i < ni; ++i)
      for (int j = 0; j < nj; ++j) {
        double d2 = 0;
        for (int d = 0; d < 3; ++d) {
          double dx = double(pi[i].pos[d]) - double(pj[j].pos[d]);
          d2 += dx * dx;
        }
        double r = M == pik::SearchMode::gather ? double(pi[i].r)
                   : M == pik::SearchMode::scatter ? double(pj[j].r)
                                                   : std::max(double(pi[i].r), double(pj[j].r));
        if (d2 < r * r) f[i].pot += 1;
      }
  }
};

enum class Dist { uniform, plummer, clustered };
inline const char* name(Dist d) {
  return d == Dist::uniform ? "uniform" : (d == Dist::plummer ? "plummer" : "clustered");
}

/// n particles of total mass 1. uniform: unit cube; plummer: Plummer sphere (scale
/// 1, radius cut at 20); clustered: 5 tight Plummer clumps (scale 1e-3) in a unit cube.
template <class T>
pik::ParticleSystem<Body<T>> make(Dist dist, int n, unsigned seed = 1) {
  std::mt19937_64 g(seed);
  std::uniform_real_distribution<double> u(0, 1);
  auto plummer = [&](double a) {
    double r;
    do r = a / std::sqrt(std::pow(u(g), -2.0 / 3.0) - 1);
    while (r > 20 * a);
    double z = 2 * u(g) - 1, ph = 2 * M_PI * u(g), s = std::sqrt(1 - z * z);
    return pik::Vec3<double>{r * s * std::cos(ph), r * s * std::sin(ph), r * z};
  };
  std::vector<pik::Vec3<double>> centres;
  for (int k = 0; k < 5; ++k) centres.push_back({u(g), u(g), u(g)});
  pik::ParticleSystem<Body<T>> ps;
  for (int i = 0; i < n; ++i) {
    pik::Vec3<double> x;
    if (dist == Dist::uniform) x = {u(g), u(g), u(g)};
    if (dist == Dist::plummer) x = plummer(1.0);
    if (dist == Dist::clustered) x = centres[std::size_t(i % 5)] + plummer(1e-3);
    Body<T> b;
    b.pos = pik::vec_cast<pik::Vec3<T>>(x);
    b.mass = T(1.0 / n);
    b.id = i;
    ps.add(b);
  }
  return ps;
}

/// Direct-sum acceleration on particle i, in double.
template <class T>
pik::Vec3<double> direct_acc(const pik::ParticleSystem<Body<T>>& ps, std::size_t i, double eps2) {
  pik::Vec3<double> a{};
  const auto xi = pik::vec_cast<pik::Vec3<double>>(ps[i].pos);
  for (const auto& b : ps) {
    pik::Vec3<double> d = xi - pik::vec_cast<pik::Vec3<double>>(b.pos);
    double r2 = pik::norm2(d) + eps2, rinv = 1 / std::sqrt(r2);
    a -= d * (double(b.mass) * rinv * rinv * rinv);
  }
  return a;
}

struct ErrorStats {
  double rms = 0, max = 0;
};
/// rms and max relative acceleration error of ps's acc against direct summation.
template <class T>
ErrorStats acc_error(const pik::ParticleSystem<Body<T>>& ps, double eps2) {
  ErrorStats e;
  double s = 0;
  for (std::size_t i = 0; i < ps.size(); ++i) {
    pik::Vec3<double> a = direct_acc(ps, i, eps2);
    double rel = pik::norm(pik::vec_cast<pik::Vec3<double>>(ps[i].acc) - a) / pik::norm(a);
    s += rel * rel;
    e.max = std::max(e.max, rel);
  }
  e.rms = std::sqrt(s / double(ps.size()));
  return e;
}

}  // namespace pt
