/// \file Eos.hpp
/// \brief Equations of state: the interface a material implements, the ideal gas, and
///        the per-particle material table (a particle's `material` id picks its EOS).
///
/// The SPH kernels never see an EOS: they read a particle's pressure and sound speed,
/// which the per-particle update between the density and force passes computes from
/// (rho, u) through this interface. A user adds a material by deriving from Material,
/// without touching a kernel.
#pragma once

#include <cmath>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <pik/Error.hpp>

namespace pik::eos {

/// What an EOS gives for a (density, specific internal energy) pair.
struct State {
  double pressure = 0;
  double sound_speed = 0;
};

/// A material: p(rho, u) and c_s(rho, u). Implementations must refuse non-physical
/// input (rho <= 0, u < 0, NaN) with pik::Error naming the material and the value.
class Material {
 public:
  virtual ~Material() = default;
  virtual std::string name() const = 0;
  virtual State state(double rho, double u) const = 0;
  double pressure(double rho, double u) const { return state(rho, u).pressure; }
  double sound_speed(double rho, double u) const { return state(rho, u).sound_speed; }

 protected:
  void check(double rho, double u) const {
    if (!(rho > 0) || !std::isfinite(rho))
      throw Error(name() + " EOS: density must be positive and finite, not " + std::to_string(rho));
    if (!(u >= 0) || !std::isfinite(u))
      throw Error(name() + " EOS: specific internal energy must be non-negative and finite, not " +
                  std::to_string(u));
  }
};

/// Ideal gas, p = (gamma - 1) rho u, c_s = sqrt(gamma (gamma - 1) u).
class IdealGas final : public Material {
 public:
  explicit IdealGas(double gamma) : gamma_(gamma) {
    if (!(gamma > 1)) throw Error("ideal gas: gamma must be above 1, not " + std::to_string(gamma));
  }
  std::string name() const override { return "ideal gas"; }
  State state(double rho, double u) const override {
    check(rho, u);
    return {(gamma_ - 1) * rho * u, std::sqrt(gamma_ * (gamma_ - 1) * u)};
  }
  double gamma() const { return gamma_; }

 private:
  double gamma_;
};

/// The materials of a run, indexed by the particles' material id (0, 1, ...).
class MaterialTable {
 public:
  /// Adds a material and returns its id.
  int add(std::unique_ptr<Material> m) {
    materials_.push_back(std::move(m));
    return int(materials_.size()) - 1;
  }
  const Material& operator[](int id) const {
    if (id < 0 || std::size_t(id) >= materials_.size())
      throw Error("material id " + std::to_string(id) + " is not defined (the run has " +
                  std::to_string(materials_.size()) + " materials)");
    return *materials_[std::size_t(id)];
  }
  std::size_t size() const { return materials_.size(); }

 private:
  std::vector<std::unique_ptr<Material>> materials_;
};

}  // namespace pik::eos
