/// \file TimeStep.hpp
/// \brief Time-step criteria of the SPH programs: each criterion adds its limit by name,
///        the step is the smallest and the name of the one that set it is reported.
#pragma once

#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace pik::sph {

/// The limits of one step: `add("courant", dt)` per criterion (the minimum over the
/// particles), then `dt()` and `limiter()`.
class StepLimits {
 public:
  void add(const std::string& name, double dt) {
    for (auto& [n, v] : all_)
      if (n == name) {
        v = std::min(v, dt);
        return;
      }
    all_.emplace_back(name, dt);
  }
  double dt() const {
    double m = std::numeric_limits<double>::infinity();
    for (const auto& [n, v] : all_) m = std::min(m, v);
    return m;
  }
  /// Name of the criterion that sets the step ("none" when there is none).
  std::string limiter() const {
    std::string best = "none";
    double m = std::numeric_limits<double>::infinity();
    for (const auto& [n, v] : all_)
      if (v < m) m = v, best = n;
    return best;
  }
  const std::vector<std::pair<std::string, double>>& all() const { return all_; }

 private:
  std::vector<std::pair<std::string, double>> all_;
};

/// Courant condition with the signal velocity: C h / v_sig (Monaghan 1997; Springel 2005, eq. 16).
inline double courant(double h, double vsig, double c) { return c * h / std::max(vsig, 1e-300); }

/// Acceleration criterion C sqrt(length / |a|) (length: softening or smoothing length).
inline double acceleration(double length, double accel, double c) {
  return c * std::sqrt(length / std::max(accel, 1e-300));
}

/// Explicit diffusion (kinematic viscosity, thermal diffusivity): C h^2 / D, the stability
/// limit of an explicit diffusion step; the caller chooses C for its kernel and for h
/// being the support radius.
inline double diffusion(double h, double diffusivity, double c) {
  return c * h * h / std::max(diffusivity, 1e-300);
}

}  // namespace pik::sph
