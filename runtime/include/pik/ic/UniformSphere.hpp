/// \file UniformSphere.hpp
/// \brief A cold uniform sphere: particles uniform in a ball, at rest.
///
/// The classic collapse test (and the standard tree-code benchmark distribution).
/// With total mass 1 and radius R, the potential energy is W = -3/(5R) (G = 1) and
/// the free-fall time t_ff = (pi/2) sqrt(R^3 / 2).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <stdexcept>

#include "pik/Vec.hpp"
#include "pik/ic/CentreOfMass.hpp"
#include "pik/ic/Random.hpp"
#include "pik/io/Snapshot.hpp"

namespace pik::ic {

/// `n` equal-mass particles (total mass 1), ids 0..n-1, in a ball of `radius`
/// centred on their centre of mass, zero velocities; reproducible from `seed`.
inline io::Snapshot uniform_sphere(std::size_t n, std::uint64_t seed, double radius = 1.0) {
  if (!(radius > 0.0)) throw std::invalid_argument("uniform_sphere: radius must be positive");
  io::Snapshot s;
  s.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    Stream rng(seed, i);
    // r = R u^(1/3) makes the density uniform in the ball.
    const double r = radius * std::cbrt(rng.uniform());
    const auto x = unit_vector<Vec3<double>>(rng);
    s.id[i] = i;
    s.mass[i] = 1.0 / double(n);
    s.pos[i] = {r * x.x, r * x.y, r * x.z};
    s.vel[i] = {0.0, 0.0, 0.0};
  }
  to_centre_of_mass_frame(s);
  s.attr.set("ic", "uniform");
  s.attr.set("ic.seed", std::uint64_t(seed));
  s.attr.set("ic.radius", radius);
  return s;
}

}  // namespace pik::ic
