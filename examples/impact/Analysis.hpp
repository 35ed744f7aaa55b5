/// \file Analysis.hpp
/// \brief After an impact: which particles are the planet, the disk and the escaping
///        debris; the disk's mass, angular momentum and iron fraction; the satellite mass
///        the disk predicts (Ida, Canup & Stewart 1997).
///
/// Classification (Canup & Asphaug 2001; Canup 2004, sec. 3): relative to the planet's
/// centre of mass, a particle with specific orbital energy E = v^2/2 - G M_p / r >= 0
/// escapes; a bound one is in the disk when the periapsis q = a (1 - e) of its Kepler
/// orbit about a point mass M_p lies outside the planet radius R_p (or, with
/// `equivalent_circular`, when the radius of the circular orbit of the same angular
/// momentum, L^2 / (G M_p), does), else it belongs to the planet. Particles inside R_p
/// are planet. M_p, its centre and R_p = R_ref (M_p / M_ref)^(1/3) (the planet at the
/// reference body's mean density) are iterated to a fixed point.
///
/// Predicted satellite mass (Ida, Canup & Stewart 1997, eq. 7 as used by Canup 2004, eq. 1):
///   M_M = 1.9 L_D / sqrt(G M_p a_R) - 1.1 M_D - 1.9 M_esc,
/// a_R = 2.9 R_p the Roche limit, M_esc = 0.05 M_D the mass lost from the disk (Canup 2004).
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

#include <pik/Vec.hpp>

#include "Units.hpp"

namespace impact {

struct AnalysisInput {
  std::vector<double> mass;
  std::vector<pik::Vec3<double>> pos, vel;
  std::vector<int> material;
  int iron_material = 0;   ///< the material id counted for the iron fraction
  double ref_mass = 0;     ///< the reference body (target) mass and radius for R_p
  double ref_radius = 0;
  bool equivalent_circular = false;
};

struct AnalysisResult {
  double planet_mass = 0, planet_radius = 0, disk_mass = 0, escape_mass = 0;
  double disk_lz = 0;          ///< disk angular momentum about the planet's centre, along the total L
  double disk_iron = 0;        ///< iron mass fraction of the disk
  double moon_mass = 0;        ///< predicted satellite mass (may be negative: no moon)
  double total_l = 0;          ///< |L| of everything about the centre of mass
  std::vector<int> kind;       ///< per particle: 0 planet, 1 disk, 2 escaping
  int iterations = 0;
};

inline AnalysisResult analyse(const AnalysisInput& in) {
  using V = pik::Vec3<double>;
  const std::size_t n = in.mass.size();
  AnalysisResult res;
  res.kind.assign(n, 0);
  // Total angular momentum about the centre of mass, for the disk's axis.
  double mt = 0;
  V xc{}, vc{};
  for (std::size_t i = 0; i < n; ++i) mt += in.mass[i], xc += in.pos[i] * in.mass[i], vc += in.vel[i] * in.mass[i];
  xc = xc * (1 / mt), vc = vc * (1 / mt);
  V lt{};
  for (std::size_t i = 0; i < n; ++i) lt += pik::cross(in.pos[i] - xc, in.vel[i] - vc) * in.mass[i];
  res.total_l = pik::norm(lt);
  const V axis = res.total_l > 0 ? lt * (1 / res.total_l) : V{0, 0, 1};

  // Start: the planet is the densest concentration, approximated by everything within
  // the reference radius of the potential minimum's neighbourhood: the mass-weighted
  // centre of all particles, then iterate.
  V xp = xc, vp = vc;
  double mp = mt;
  for (int it = 0; it < 50; ++it) {
    res.iterations = it + 1;
    const double rp = in.ref_radius * std::cbrt(mp / in.ref_mass);
    double m_new = 0;
    V x_new{}, v_new{};
    for (std::size_t i = 0; i < n; ++i) {
      const V r = in.pos[i] - xp, v = in.vel[i] - vp;
      const double d = pik::norm(r), gm = G * mp;
      const double e = 0.5 * pik::norm2(v) - gm / std::max(d, 1e-3 * rp);
      int k = 0;
      if (d >= rp) {
        if (e >= 0) k = 2;
        else {
          const double l2 = pik::norm2(pik::cross(r, v));
          if (in.equivalent_circular) k = l2 / gm > rp ? 1 : 0;
          else {
            const double a = -gm / (2 * e), ecc = std::sqrt(std::max(0.0, 1 + 2 * e * l2 / (gm * gm)));
            k = a * (1 - ecc) > rp ? 1 : 0;
          }
        }
      }
      res.kind[i] = k;
      if (k == 0) m_new += in.mass[i], x_new += in.pos[i] * in.mass[i], v_new += in.vel[i] * in.mass[i];
    }
    if (m_new <= 0) break;
    x_new = x_new * (1 / m_new), v_new = v_new * (1 / m_new);
    const bool done = std::abs(m_new - mp) <= 1e-12 * mt && pik::norm(x_new - xp) <= 1e-9 * rp;
    mp = m_new, xp = x_new, vp = v_new;
    if (done) break;
  }
  res.planet_mass = mp;
  res.planet_radius = in.ref_radius * std::cbrt(mp / in.ref_mass);
  double iron = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (res.kind[i] == 1) {
      res.disk_mass += in.mass[i];
      res.disk_lz += in.mass[i] * pik::dot(pik::cross(in.pos[i] - xp, in.vel[i] - vp), axis);
      if (in.material[i] == in.iron_material) iron += in.mass[i];
    } else if (res.kind[i] == 2) {
      res.escape_mass += in.mass[i];
    }
  }
  res.disk_iron = res.disk_mass > 0 ? iron / res.disk_mass : 0;
  const double a_roche = 2.9 * res.planet_radius;
  res.moon_mass = 1.9 * res.disk_lz / std::sqrt(G * mp * a_roche) - 1.1 * res.disk_mass - 1.9 * 0.05 * res.disk_mass;
  return res;
}

}  // namespace impact
