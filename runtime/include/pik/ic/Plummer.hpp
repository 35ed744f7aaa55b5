/// \file Plummer.hpp
/// \brief A Plummer sphere in equilibrium, in N-body units (G = M = 1, E = -1/4).
///
/// Sampling follows Aarseth, Hénon & Wielen (1974, A&A 37, 183, appendix): radius
/// from the inverted cumulative mass m(r) = r^3 (1 + r^2)^(-3/2), speed from the
/// isotropic distribution function by rejection on g(q) = q^2 (1 - q^2)^(7/2) with
/// q = v / v_escape, directions isotropic. Model units (scale radius a = 1) become
/// N-body units by r -> r * 3 pi / 16 and v -> v * sqrt(16 / (3 pi)) (total energy
/// -3 pi / 64 in model units). The sample is truncated at the radius enclosing the
/// mass fraction `mass_cutoff` (the outermost shells are few, far, and would
/// dominate the tree's bounding box), and shifted to the centre-of-mass frame.
/// Expected: virial ratio 2K/|W| = 1, half-mass radius 0.769 (N-body units).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <stdexcept>

#include "pik/Vec.hpp"
#include "pik/ic/CentreOfMass.hpp"
#include "pik/ic/Random.hpp"
#include "pik/io/Snapshot.hpp"

namespace pik::ic {

/// Plummer scale radius in N-body units.
inline constexpr double plummer_scale_radius = 3.0 * std::numbers::pi / 16.0;

/// `n` equal-mass particles, ids 0..n-1, reproducible from `seed` (see Random.hpp).
inline io::Snapshot plummer(std::size_t n, std::uint64_t seed, double mass_cutoff = 0.999) {
  if (!(mass_cutoff > 0.0 && mass_cutoff <= 1.0))
    throw std::invalid_argument("plummer: mass_cutoff must be in (0, 1]");
  io::Snapshot s;
  s.resize(n);
  const double a = plummer_scale_radius;
  const double vscale = std::sqrt(1.0 / a);
  for (std::size_t i = 0; i < n; ++i) {
    Stream rng(seed, i);
    // Enclosed mass fraction in (0, mass_cutoff]; r = (m^(-2/3) - 1)^(-1/2).
    double m;
    do m = mass_cutoff * rng.uniform_open0();
    while (m >= 1.0);  // only when mass_cutoff == 1 and uniform_open0() == 1
    const double r = 1.0 / std::sqrt(std::pow(m, -2.0 / 3.0) - 1.0);
    // von Neumann rejection; max of q^2 (1-q^2)^3.5 is 0.0920 < 0.1.
    double q, g;
    do {
      q = rng.uniform();
      g = 0.1 * rng.uniform();
    } while (g > q * q * std::pow(1.0 - q * q, 3.5));
    const double v = q * std::sqrt(2.0) * std::pow(1.0 + r * r, -0.25);
    const auto x = unit_vector<Vec3<double>>(rng);
    const auto u = unit_vector<Vec3<double>>(rng);
    s.id[i] = i;
    s.mass[i] = 1.0 / double(n);
    s.pos[i] = {a * r * x.x, a * r * x.y, a * r * x.z};
    s.vel[i] = {vscale * v * u.x, vscale * v * u.y, vscale * v * u.z};
  }
  to_centre_of_mass_frame(s);
  s.attr.set("ic", "plummer");
  s.attr.set("ic.seed", std::uint64_t(seed));
  s.attr.set("ic.mass_cutoff", mass_cutoff);
  return s;
}

}  // namespace pik::ic
