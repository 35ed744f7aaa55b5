/// \file Random.hpp
/// \brief Counter-based random streams for initial conditions: particle i of a set
///        draws from its own stream, derived from (seed, i).
///
/// With one stream per particle the sample does not depend on the order in which
/// particles are generated, on the thread or rank count, or on the standard library
/// (std:: distributions are implementation-defined; these are not): the same seed
/// gives the same particles everywhere. The generator is SplitMix64 (Steele, Lea &
/// Flood 2014, "Fast splittable pseudorandom number generators", OOPSLA).
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>

namespace pik::ic {

class Stream {
 public:
  Stream(std::uint64_t seed, std::uint64_t index) {
    // Two rounds of mixing decorrelate neighbouring (seed, index) pairs.
    state_ = mix(mix(seed) ^ (index * 0xD1B54A32D192ED03ull + 0x8CB92BA72F3D8DD7ull));
  }

  std::uint64_t next_u64() {
    state_ += 0x9E3779B97F4A7C15ull;
    return mix(state_);
  }
  /// Uniform in [0, 1), 53 random bits.
  double uniform() { return double(next_u64() >> 11) * 0x1.0p-53; }
  /// Uniform in (0, 1].
  double uniform_open0() { return 1.0 - uniform(); }
  /// Uniform in [a, b).
  double uniform(double a, double b) { return a + (b - a) * uniform(); }

 private:
  static std::uint64_t mix(std::uint64_t z) {
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  std::uint64_t state_;
};

/// An isotropic unit vector: z uniform in [-1, 1], azimuth uniform (Archimedes'
/// hat-box theorem), written to (x, y, z).
template <class V>
V unit_vector(Stream& s) {
  const double z = s.uniform(-1.0, 1.0);
  const double phi = 2.0 * std::numbers::pi * s.uniform();
  const double rxy = std::sqrt(std::fmax(0.0, 1.0 - z * z));
  return V{rxy * std::cos(phi), rxy * std::sin(phi), z};
}

}  // namespace pik::ic
