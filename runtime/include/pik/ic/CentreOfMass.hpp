/// \file CentreOfMass.hpp
/// \brief Moves a particle set into its centre-of-mass frame (position and velocity).
#pragma once

#include "pik/Vec.hpp"
#include "pik/io/Snapshot.hpp"

namespace pik::ic {

/// Subtracts the mass-weighted mean position and velocity. Sums run in index order,
/// so the result is reproducible bit for bit.
inline void to_centre_of_mass_frame(io::Snapshot& s) {
  double m = 0;
  Vec3<double> x{}, v{};
  for (std::size_t i = 0; i < s.size(); ++i) {
    m += s.mass[i];
    x.x += s.mass[i] * s.pos[i].x, x.y += s.mass[i] * s.pos[i].y, x.z += s.mass[i] * s.pos[i].z;
    v.x += s.mass[i] * s.vel[i].x, v.y += s.mass[i] * s.vel[i].y, v.z += s.mass[i] * s.vel[i].z;
  }
  if (!(m > 0)) return;
  x = {x.x / m, x.y / m, x.z / m};
  v = {v.x / m, v.y / m, v.z / m};
  for (std::size_t i = 0; i < s.size(); ++i) {
    s.pos[i] = {s.pos[i].x - x.x, s.pos[i].y - x.y, s.pos[i].z - x.z};
    s.vel[i] = {s.vel[i].x - v.x, s.vel[i].y - v.y, s.vel[i].z - v.z};
  }
}

}  // namespace pik::ic
