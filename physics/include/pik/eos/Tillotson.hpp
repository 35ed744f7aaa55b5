/// \file Tillotson.hpp
/// \brief The Tillotson (1962) equation of state for solids and their vapour, in the
///        form of Melosh (1989, "Impact Cratering", appendix II), with the granite and
///        iron parameter sets used in giant-impact studies; pressure, its derivatives and
///        the sound speed, with a documented pressure floor for tension.
///
/// With eta = rho / rho0, mu = eta - 1 and omega = u / (u0 eta^2) + 1:
///
///   compressed and cold expanded (rho >= rho0, or u <= u_iv):
///     P_c = (a + b / omega) rho u + A mu + B mu^2
///   hot expanded (rho < rho0 and u >= u_cv), with z = rho0 / rho - 1:
///     P_e = a rho u + [ b rho u / omega + A mu exp(-beta z) ] exp(-alpha z^2)
///   hybrid (rho < rho0 and u_iv < u < u_cv), linear in u between the two:
///     P_h = [ (u - u_iv) P_e + (u_cv - u) P_c ] / (u_cv - u_iv)
///
/// The three agree on their boundaries (P_e = P_c at rho = rho0 since z = mu = 0, and
/// P_h = P_c at u_iv, P_e at u_cv), so P is continuous everywhere.
///
/// Sound speed: c^2 = dP/drho at constant entropy = (dP/drho)_u + P / rho^2 (dP/du)_rho
/// (since du = P / rho^2 drho at constant entropy), from the analytic derivatives.
///
/// Tension. In the cold expanded state P_c < 0 (A mu < 0): a solid in tension. SPH
/// without a strength model cannot represent tension (the tensile instability clumps
/// particles), so the pressure returned is max(P, p_floor) with p_floor = 0 by default,
/// as in hydrocode giant-impact work without strength (e.g. Canup 2004, Reinhardt &
/// Stadel 2017): expanded cold material fragments rather than pulls. A negative floor
/// can be set to allow limited tension. The unfloored value is available as
/// raw_pressure(). c^2 is computed with the floored pressure and never goes below
/// c_min^2 = (0.01)^2 A / rho0 (1 % of the bulk sound speed at rest, our choice), so the
/// Courant step and the artificial viscosity stay finite in stretched cold material.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>

#include <pik/eos/Eos.hpp>

namespace pik::eos {

/// The ten Tillotson constants of one material (SI units: kg/m^3, Pa, J/kg).
struct TillotsonParams {
  std::string name;
  double rho0 = 0;   ///< reference density
  double a = 0, b = 0;
  double A = 0;      ///< bulk modulus-like constant (Pa)
  double B = 0;      ///< nonlinear compression constant (Pa)
  double u0 = 0;     ///< reference specific energy (J/kg)
  double u_iv = 0;   ///< specific energy of incipient vaporisation
  double u_cv = 0;   ///< specific energy of complete vaporisation
  double alpha = 0, beta = 0;

  /// Granite (Melosh 1989, table AII.3; as used by Benz et al. 1986 and Canup & Asphaug 2001).
  static TillotsonParams granite() {
    return {"granite", 2680.0, 0.5, 1.3, 18.0e9, 18.0e9, 16.0e6, 3.5e6, 18.0e6, 5.0, 5.0};
  }
  /// Iron (Melosh 1989, table AII.3; Benz et al. 1986, Canup & Asphaug 2001).
  static TillotsonParams iron() {
    return {"iron", 7800.0, 0.5, 1.5, 128.0e9, 105.0e9, 9.5e6, 2.4e6, 8.67e6, 5.0, 5.0};
  }
};

/// Pressure and its partial derivatives at one (rho, u).
struct PressureDerivatives {
  double p = 0;       ///< pressure (unfloored)
  double dp_drho = 0; ///< (dP/drho) at constant u
  double dp_du = 0;   ///< (dP/du) at constant rho
};

class Tillotson final : public Material {
 public:
  /// Which formula applies at (rho, u).
  enum class Region { compressed, cold_expanded, hybrid, hot_expanded };

  explicit Tillotson(TillotsonParams p, double p_floor = 0.0) : p_(std::move(p)), p_floor_(p_floor) {
    const auto bad = [&](const char* what) {
      throw Error("Tillotson EOS '" + p_.name + "': " + what);
    };
    if (!(p_.rho0 > 0)) bad("rho0 must be positive");
    if (!(p_.A > 0) || !(p_.B >= 0)) bad("A must be positive and B non-negative");
    if (!(p_.u0 > 0)) bad("u0 must be positive");
    if (!(p_.u_iv >= 0) || !(p_.u_cv > p_.u_iv)) bad("need 0 <= u_iv < u_cv");
    if (!(p_.a >= 0) || !(p_.b >= 0) || !(p_.alpha >= 0) || !(p_.beta >= 0)) bad("a, b, alpha, beta must be non-negative");
    if (!std::isfinite(p_floor_) || p_floor_ > 0) bad("the pressure floor must be finite and not positive");
  }

  std::string name() const override { return p_.name; }
  const TillotsonParams& params() const { return p_; }
  double pressure_floor() const { return p_floor_; }

  Region region(double rho, double u) const {
    if (rho >= p_.rho0) return Region::compressed;
    if (u <= p_.u_iv) return Region::cold_expanded;
    if (u >= p_.u_cv) return Region::hot_expanded;
    return Region::hybrid;
  }

  /// P(rho, u) before the floor, with its partial derivatives.
  PressureDerivatives raw(double rho, double u) const {
    check(rho, u);
    switch (region(rho, u)) {
      case Region::compressed:
      case Region::cold_expanded: return compressed(rho, u);
      case Region::hot_expanded: return expanded(rho, u);
      case Region::hybrid: {
        const PressureDerivatives c = compressed(rho, u), e = expanded(rho, u);
        const double w = 1.0 / (p_.u_cv - p_.u_iv), fe = (u - p_.u_iv) * w, fc = (p_.u_cv - u) * w;
        return {fe * e.p + fc * c.p, fe * e.dp_drho + fc * c.dp_drho, fe * e.dp_du + fc * c.dp_du + (e.p - c.p) * w};
      }
    }
    return {};
  }
  double raw_pressure(double rho, double u) const { return raw(rho, u).p; }

  State state(double rho, double u) const override {
    const PressureDerivatives d = raw(rho, u);
    const double p = std::max(d.p, p_floor_);
    const double c_min2 = 1e-4 * p_.A / p_.rho0;
    const double c2 = std::max(d.dp_drho + p / (rho * rho) * d.dp_du, c_min2);
    return {p, std::sqrt(c2)};
  }

 private:
  /// P_c and its derivatives; d omega/d rho = -2 (omega - 1) / rho, d omega/d u = 1 / (u0 eta^2).
  PressureDerivatives compressed(double rho, double u) const {
    const double eta = rho / p_.rho0, mu = eta - 1, om = u / (p_.u0 * eta * eta) + 1;
    const double g = p_.a + p_.b / om;  // Grueneisen-like factor
    const double p = g * rho * u + p_.A * mu + p_.B * mu * mu;
    const double dp_drho = g * u + 2 * p_.b * u * (om - 1) / (om * om) + (p_.A + 2 * p_.B * mu) / p_.rho0;
    const double dp_du = g * rho - p_.b * rho * (om - 1) / (om * om);
    return {p, dp_drho, dp_du};
  }
  /// P_e and its derivatives (z = rho0/rho - 1, dz/drho = -rho0/rho^2).
  PressureDerivatives expanded(double rho, double u) const {
    const double eta = rho / p_.rho0, mu = eta - 1, om = u / (p_.u0 * eta * eta) + 1;
    const double z = p_.rho0 / rho - 1, dz = -p_.rho0 / (rho * rho);
    const double eb = std::exp(-p_.beta * z), ea = std::exp(-p_.alpha * z * z);
    const double t = p_.b * rho * u / om, s = p_.A * mu * eb;
    const double dt_drho = p_.b * u / om + 2 * p_.b * u * (om - 1) / (om * om);
    const double dt_du = p_.b * rho / om - p_.b * rho * (om - 1) / (om * om);
    const double ds_drho = p_.A * eb * (1 / p_.rho0 - p_.beta * mu * dz);
    const double dea_drho = -2 * p_.alpha * z * dz * ea;
    const double p = p_.a * rho * u + (t + s) * ea;
    return {p, p_.a * u + (dt_drho + ds_drho) * ea + (t + s) * dea_drho, p_.a * rho + dt_du * ea};
  }

  TillotsonParams p_;
  double p_floor_;
};

}  // namespace pik::eos
