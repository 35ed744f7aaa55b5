/// \file Planet.hpp
/// \brief A differentiated planet (core and mantle, each with its own EOS and specific
///        internal energy): the hydrostatic radial profile and equal-mass particles placed
///        to match it.
///
/// Profile: dm/dr = 4 pi r^2 rho, dP/dr = -G m rho / r^2, with rho(P) from the layer's
/// EOS at the layer's (constant) u, integrated outwards from the centre with fourth-order
/// Runge-Kutta; the material switches from core to mantle where m reaches f_core M, the
/// surface is where P reaches zero. The central pressure is found by bisection so that
/// the mass inside the surface is M (a shooting method, as for polytropes).
///
/// Particles: a cubic lattice cut to the unit sphere, sorted by radius; the k-th of N
/// gets the enclosed mass fraction (k + 1/2)/N and moves along its direction to the
/// radius r with m(r) = (k + 1/2) M / N (a radial stretch, as Evrard 1988 makes his
/// r^-1 sphere from a uniform one). The inner round(f_core N) are core particles, so
/// the core mass fraction is exact to one particle. The stretched lattice is then
/// relaxed with SPH (see Relax in impact.cpp).
#pragma once

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <vector>

#include <pik/Error.hpp>
#include <pik/Vec.hpp>
#include <pik/eos/Eos.hpp>

#include "Units.hpp"

namespace impact {

/// One layer of a planet: its EOS, specific internal energy and mass fraction.
struct Layer {
  const pik::eos::Material* eos = nullptr;
  double u = 0;              ///< J/kg
  int material = 0;          ///< material id in the run's table
};

/// Density at pressure p > 0 along the layer's constant-u curve, by bisection
/// (P(rho) at fixed u increases with rho for the materials here).
inline double density_at(const pik::eos::Material& eos, double u, double p) {
  double lo = 1e-3, hi = 1.0;
  while (eos.pressure(hi, u) < p) {
    lo = hi, hi *= 2;
    if (hi > 1e8) throw pik::Error(eos.name() + ": no density below 1e8 kg/m^3 reaches " + std::to_string(p) + " Pa");
  }
  for (int it = 0; it < 200 && hi - lo > 1e-12 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (eos.pressure(mid, u) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}
inline double density_at(const Layer& l, double p) { return density_at(*l.eos, l.u, p); }

/// A tabulated hydrostatic profile, from the centre to the surface.
struct Profile {
  std::vector<double> r, m, rho, p, u;
  std::vector<int> layer;  ///< 0 core, 1 mantle
  double radius = 0, mass = 0, r_core = 0;

  /// The radius enclosing mass mm (linear interpolation in the table).
  double radius_of_mass(double mm) const {
    if (mm <= 0) return 0;
    if (mm >= mass) return radius;
    const auto it = std::lower_bound(m.begin(), m.end(), mm);
    const std::size_t k = std::size_t(it - m.begin());
    if (k == 0) return r[0];
    const double f = (mm - m[k - 1]) / (m[k] - m[k - 1]);
    return r[k - 1] + f * (r[k] - r[k - 1]);
  }
  /// Density (or, with `col`, another column) at radius rr, linear in the table; the
  /// core boundary appears twice, so each side interpolates within its own layer.
  double density(double rr) const { return at(rr, rho); }
  double energy(double rr) const { return at(rr, u); }
  double at(double rr, const std::vector<double>& col) const {
    if (rr >= radius) return col.back();
    const auto it = std::upper_bound(r.begin(), r.end(), rr);
    const std::size_t k = std::max<std::size_t>(1, std::size_t(it - r.begin()));
    if (k >= r.size()) return col.back();
    const double f = r[k] > r[k - 1] ? (rr - r[k - 1]) / (r[k] - r[k - 1]) : 0.0;
    return col[k - 1] + f * (col[k] - col[k - 1]);
  }
};

/// Integrates outwards from central pressure pc; stops at the surface (P = 0) or when the
/// mass exceeds 2 M. Records the table when `keep`.
inline Profile integrate_profile(const Layer& core, const Layer& mantle, double core_mass, double pc, double dr,
                                 double m_stop) {
  Profile pr;
  double r = 0, m = 0, p = pc;
  int lay = core_mass > 0 ? 0 : 1;
  auto rho_of = [&](double pp) { return density_at(lay == 0 ? core : mantle, std::max(pp, 1.0)); };
  auto rhs = [&](double rr, double mm, double pp, double& dm, double& dp) {
    const double rh = rho_of(pp);
    dm = 4 * M_PI * rr * rr * rh;
    dp = rr > 0 ? -G * mm * rh / (rr * rr) : 0.0;
  };
  auto record = [&] {
    pr.r.push_back(r), pr.m.push_back(m), pr.p.push_back(p), pr.rho.push_back(rho_of(p)), pr.layer.push_back(lay);
    pr.u.push_back(lay == 0 ? core.u : mantle.u);
  };
  record();
  while (true) {
    double k1m, k1p, k2m, k2p, k3m, k3p, k4m, k4p;
    rhs(r, m, p, k1m, k1p);
    rhs(r + 0.5 * dr, m + 0.5 * dr * k1m, p + 0.5 * dr * k1p, k2m, k2p);
    rhs(r + 0.5 * dr, m + 0.5 * dr * k2m, p + 0.5 * dr * k2p, k3m, k3p);
    rhs(r + dr, m + dr * k3m, p + dr * k3p, k4m, k4p);
    const double mn = m + dr / 6 * (k1m + 2 * k2m + 2 * k3m + k4m);
    const double pn = p + dr / 6 * (k1p + 2 * k2p + 2 * k3p + k4p);
    if (pn <= 0) {  // surface inside this step: linear in P
      const double f = p / (p - pn);
      r += f * dr, m += f * (mn - m), p = 0;
      pr.r.push_back(r), pr.m.push_back(m), pr.p.push_back(0), pr.layer.push_back(lay);
      pr.rho.push_back(pr.rho.back()), pr.u.push_back(pr.u.back());
      break;
    }
    r += dr, m = mn, p = pn;
    if (lay == 0 && m >= core_mass) {
      pr.r_core = r;
      record();  // the core side at the boundary ...
      lay = 1;   // ... and the mantle side at the same radius and pressure
    }
    record();
    if (m > m_stop) break;
  }
  pr.radius = r, pr.mass = m;
  if (pr.r_core == 0 && core_mass > 0) pr.r_core = r;
  return pr;
}

/// The hydrostatic profile of mass `mass` with core mass fraction `f_core`.
inline Profile hydrostatic_profile(const Layer& core, const Layer& mantle, double mass, double f_core) {
  if (!(mass > 0)) throw pik::Error("planet mass must be positive");
  if (!(f_core >= 0 && f_core < 1)) throw pik::Error("core mass fraction must be in [0, 1)");
  // Step: a 4000th of the radius the mantle alone would give at its reference density.
  const double rho_guess = mantle.eos->pressure(1.0, mantle.u) >= 0 ? density_at(mantle, 1e9) : 3000;
  const double dr = std::cbrt(3 * mass / (4 * M_PI * rho_guess)) / 4000;
  double lo = 1e6, hi = 1e14;  // central pressure bracket, Pa
  for (int it = 0; it < 100; ++it) {
    const double pc = std::sqrt(lo * hi);
    const Profile pr = integrate_profile(core, mantle, f_core * mass, pc, dr, 2 * mass);
    (pr.mass < mass ? lo : hi) = pc;
    if (hi / lo < 1 + 1e-10) break;
  }
  Profile pr = integrate_profile(core, mantle, f_core * mass, std::sqrt(lo * hi), dr, 2 * mass);
  if (std::abs(pr.mass / mass - 1) > 1e-3)
    throw pik::Error("no hydrostatic profile of mass " + std::to_string(mass) + " kg found (got " +
                     std::to_string(pr.mass) + " kg)");
  return pr;
}

/// Integrates inwards from the surface (r = R, m = M, P = 0, u = mantle.u) along
/// isentropes, du = P / rho^2 drho = P / (rho^2 c^2) dP, the core's isentrope anchored at
/// u = core.u on the core side of the boundary (where m falls to core_mass). Returns the
/// mass left when r reaches 0 (> 0: R too small), or minus the radius where m reached 0
/// (R too large); fills `pr` (centre first) when asked.
inline double integrate_isentropic(const Layer& core, const Layer& mantle, double mass, double core_mass, double R,
                                   Profile* pr) {
  const int steps = 4000;
  const double dr = R / steps;
  double r = R, m = mass, p = 0, u = mantle.u;
  int lay = 1;
  std::vector<double> tr, tm, tp, tu, trho;
  std::vector<int> tl;
  auto lay_of = [&](int l) -> const Layer& { return l == 0 ? core : mantle; };
  auto rhs = [&](double rr, double mm, double pp, double uu, double& dm, double& dp, double& du) {
    const auto& L = lay_of(lay);
    const double rh = density_at(*L.eos, std::max(uu, 0.0), std::max(pp, 1.0));
    const double c = L.eos->sound_speed(rh, std::max(uu, 0.0));
    dm = 4 * M_PI * rr * rr * rh;
    dp = -G * std::max(mm, 0.0) * rh / (rr * rr);
    du = std::max(pp, 0.0) / (rh * rh * c * c) * dp;
  };
  auto record = [&] {
    if (!pr) return;
    tr.push_back(r), tm.push_back(m), tp.push_back(p), tu.push_back(u), tl.push_back(lay);
    trho.push_back(density_at(*lay_of(lay).eos, std::max(u, 0.0), std::max(p, 1.0)));
  };
  record();
  for (int k = 0; k < steps; ++k) {
    const double h = -dr;
    double m1, p1, u1, m2, p2, u2, m3, p3, u3, m4, p4, u4;
    rhs(r, m, p, u, m1, p1, u1);
    rhs(r + 0.5 * h, m + 0.5 * h * m1, p + 0.5 * h * p1, u + 0.5 * h * u1, m2, p2, u2);
    rhs(r + 0.5 * h, m + 0.5 * h * m2, p + 0.5 * h * p2, u + 0.5 * h * u2, m3, p3, u3);
    const double rn = std::max(r + h, 1e-6 * R);
    rhs(rn, m + h * m3, p + h * p3, u + h * u3, m4, p4, u4);
    const double mn = m + h / 6 * (m1 + 2 * m2 + 2 * m3 + m4);
    p += h / 6 * (p1 + 2 * p2 + 2 * p3 + p4), u += h / 6 * (u1 + 2 * u2 + 2 * u3 + u4);
    if (mn <= 0) return -(r - dr * m / (m - mn));
    r = rn, m = mn;
    if (lay == 1 && m <= core_mass) {
      record();
      lay = 0, u = core.u;  // the core side of the boundary
    }
    record();
  }
  if (pr) {
    *pr = Profile{};
    for (std::size_t i = tr.size(); i-- > 0;) {
      pr->r.push_back(tr[i]), pr->m.push_back(tm[i]), pr->p.push_back(tp[i]), pr->u.push_back(tu[i]);
      pr->rho.push_back(trho[i]), pr->layer.push_back(tl[i]);
    }
    // The centre: the last step, to r ~ 0 with the leftover mass (below the tolerance)
    // still there, is singular; take the innermost regular point's state.
    pr->r.front() = 0, pr->m.front() = 0;
    pr->p.front() = pr->p[1], pr->u.front() = pr->u[1], pr->rho.front() = pr->rho[1];
    // The last few inward steps go singular too (the leftover mass at r -> 0: densities of
    // 1e11 kg/m^3 a few hundred metres from the centre, which the innermost particles of a
    // 10^5-particle body reach, giving a Courant step of microseconds). Hydrostatic
    // profiles are flat at the centre (dP/dr ~ r): inside 2 % of the radius the state is
    // that of the point at 2 %, and m(r) that of a uniform sphere of its mean density.
    std::size_t kf = 1;
    while (kf + 1 < pr->r.size() && pr->r[kf] < 0.02 * R) ++kf;
    for (std::size_t i = 1; i < kf; ++i) {
      const double x = pr->r[i] / pr->r[kf];
      pr->m[i] = pr->m[kf] * x * x * x;
      pr->p[i] = pr->p[kf], pr->u[i] = pr->u[kf], pr->rho[i] = pr->rho[kf];
    }
    pr->p.front() = pr->p[kf], pr->u.front() = pr->u[kf], pr->rho.front() = pr->rho[kf];
    pr->radius = R, pr->mass = mass;
    for (std::size_t i = 1; i < pr->r.size(); ++i)
      if (pr->layer[i] == 1 && pr->layer[i - 1] == 0) pr->r_core = pr->r[i];
    if (pr->r_core == 0) pr->r_core = core_mass > 0 ? R : 0;
  }
  return m;
}

/// The hydrostatic profile along isentropes: mantle from u = mantle.u at the surface,
/// core from u = core.u at the core boundary. Shooting on the radius R.
inline Profile isentropic_profile(const Layer& core, const Layer& mantle, double mass, double f_core) {
  if (!(mass > 0)) throw pik::Error("planet mass must be positive");
  if (!(f_core >= 0 && f_core < 1)) throw pik::Error("core mass fraction must be in [0, 1)");
  const double rho_s = density_at(mantle, 1e5);
  double lo = 0.2 * std::cbrt(3 * mass / (4 * M_PI * rho_s)), hi = std::cbrt(3 * mass / (4 * M_PI * rho_s));
  while (integrate_isentropic(core, mantle, mass, f_core * mass, hi, nullptr) > 0) hi *= 1.5;
  while (integrate_isentropic(core, mantle, mass, f_core * mass, lo, nullptr) <= 0) lo /= 1.5;
  for (int it = 0; it < 60 && hi - lo > 1e-9 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (integrate_isentropic(core, mantle, mass, f_core * mass, mid, nullptr) > 0 ? lo : hi) = mid;
  }
  Profile pr;
  const double left = integrate_isentropic(core, mantle, mass, f_core * mass, lo, &pr);
  if (left > 1e-3 * mass) throw pik::Error("no isentropic hydrostatic profile of mass " + std::to_string(mass) + " kg found");
  return pr;
}

/// A placed particle: position (m), mass (kg), layer (0 core, 1 mantle), density (kg/m^3), u (J/kg).
struct Placed {
  pik::Vec3<double> pos;
  double mass, rho, u;
  int layer;
};

/// About n equal-mass particles matching the profile (a radially stretched lattice).
inline std::vector<Placed> place_particles(const Profile& pr, std::size_t n, double f_core) {
  if (n < 10) throw pik::Error("a planet needs at least 10 particles");
  const double d = std::cbrt(4 * M_PI / (3 * double(n)));
  const int half = int(std::ceil(1 / d)) + 1;
  std::vector<pik::Vec3<double>> lat;
  for (int i = -half; i <= half; ++i)
    for (int j = -half; j <= half; ++j)
      for (int k = -half; k <= half; ++k) {
        // offset by a quarter spacing so no point sits exactly at the centre
        const pik::Vec3<double> x{(i + 0.25) * d, (j + 0.25) * d, (k + 0.25) * d};
        if (pik::norm(x) < 1) lat.push_back(x);
      }
  std::vector<std::size_t> order(lat.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return pik::norm2(lat[a]) < pik::norm2(lat[b]); });
  const std::size_t np = lat.size(), n_core = std::size_t(std::lround(f_core * double(np)));
  std::vector<Placed> out(np);
  for (std::size_t k = 0; k < np; ++k) {
    const auto& x = lat[order[k]];
    const double f = (double(k) + 0.5) / double(np);
    const double r = pr.radius_of_mass(f * pr.mass);
    out[k].pos = x * (r / pik::norm(x));
    out[k].mass = pr.mass / double(np);
    out[k].layer = k < n_core ? 0 : 1;
    // the side of the core boundary the particle belongs to
    const double rs = out[k].layer == 0 ? std::min(r, pr.r_core * (1 - 1e-9)) : std::max(r, pr.r_core * (1 + 1e-9));
    out[k].rho = pr.density(rs), out[k].u = pr.energy(rs);
  }
  return out;
}

}  // namespace impact
