/// \file Orbit.hpp
/// \brief Two bodies on a collision orbit given by the impact angle and the speed at first
///        contact, started at a chosen separation (two point masses on a Kepler orbit).
///
/// At contact (separation r_c = R_t + R_i) the relative speed is v_imp and the angle
/// between the relative velocity and the line of centres is the impact angle theta
/// (impact parameter b = sin theta; 45 deg is the most probable, Shoemaker 1962).
/// Energy and angular momentum of the relative orbit (reduced mass):
///   E = v_imp^2 / 2 - G M / r_c,  L = r_c v_imp sin(theta),  M = M_t + M_i,
/// give at the start separation r_0: v_0 = sqrt(2 (E + G M / r_0)), tangential L / r_0,
/// radial -sqrt(v_0^2 - (L/r_0)^2) (approaching). The mutual escape speed is
/// v_esc = sqrt(2 G M / r_c) (Canup & Asphaug 2001).
#pragma once

#include <cmath>
#include <string>

#include <pik/Error.hpp>
#include <pik/Vec.hpp>

#include "Units.hpp"

namespace impact {

struct Orbit {
  pik::Vec3<double> dx, dv;  ///< impactor minus target, at the start
  double v_esc = 0, v_imp = 0, r_contact = 0, r_start = 0;
  double l_orbit = 0;        ///< orbital angular momentum (kg m^2/s) about the centre of mass
  double t_contact = 0;      ///< time to contact on the point-mass orbit (s)
};

/// The relative orbit in the x-y plane (angular momentum along +z); speed in units of v_esc.
inline Orbit collision_orbit(double m_t, double m_i, double r_t, double r_i, double angle_deg, double speed_vesc,
                             double start_separation) {
  if (!(speed_vesc >= 0) || !std::isfinite(speed_vesc))
    throw pik::Error("the impact speed must be zero or positive (in units of v_esc), not " + std::to_string(speed_vesc));
  if (!(angle_deg >= 0 && angle_deg < 90))
    throw pik::Error("the impact angle must be in [0, 90) degrees, not " + std::to_string(angle_deg));
  Orbit o;
  const double M = m_t + m_i, gm = G * M;
  o.r_contact = r_t + r_i, o.r_start = start_separation;
  if (!(start_separation > o.r_contact))
    throw pik::Error("the bodies overlap: start separation " + std::to_string(start_separation / 1e3) +
                     " km is not more than R_target + R_impactor = " + std::to_string(o.r_contact / 1e3) + " km");
  o.v_esc = std::sqrt(2 * gm / o.r_contact), o.v_imp = speed_vesc * o.v_esc;
  const double th = angle_deg * M_PI / 180;
  const double E = 0.5 * o.v_imp * o.v_imp - gm / o.r_contact, L = o.r_contact * o.v_imp * std::sin(th);
  const double v2 = 2 * (E + gm / start_separation);
  const double vt = L / start_separation, vr2 = v2 - vt * vt;
  if (!(v2 >= 0) || vr2 < 0)
    throw pik::Error("no orbit reaches contact with these parameters from " + std::to_string(start_separation / 1e3) +
                     " km (bound too tightly: raise the speed or lower the separation)");
  o.dx = {start_separation, 0, 0};
  o.dv = {-std::sqrt(vr2), vt, 0};
  o.l_orbit = m_t * m_i / M * L;
  // Time to contact: integrate dr/dt = -sqrt(2 (E + gm/r) - L^2/r^2) (midpoint rule in r).
  const int steps = 20000;
  const double dr = (start_separation - o.r_contact) / steps;
  for (int k = 0; k < steps; ++k) {
    const double r = start_separation - (k + 0.5) * dr;
    const double vr = std::sqrt(std::max(2 * (E + gm / r) - L * L / (r * r), 1e-300));
    o.t_contact += dr / vr;
  }
  return o;
}

}  // namespace impact
