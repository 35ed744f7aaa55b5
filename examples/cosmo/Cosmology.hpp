/// \file Cosmology.hpp
/// \brief The background of a flat LCDM (or Einstein-de Sitter) universe: expansion
///        rate, linear growth, the leapfrog's drift and kick factors, and the linear
///        power spectrum (Eisenstein & Hu 1998 no-wiggle, or BBKS 1986).
///
/// Code units: lengths in Mpc/h (comoving), time in 1/H0, G = 1; the mean comoving
/// density of matter is then Omega_m * 3 / (8 pi), so a particle of an N-particle box
/// of side L has mass 3 Omega_m L^3 / (8 pi N). Velocities: the canonical momentum
/// per unit mass p = a^2 dx/dt (Springel 2005, MNRAS 364, 1105, sect. 3), in units
/// of 100 km/s (Mpc/h times H0).
#pragma once

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace cosmo {

struct Background {
  double omega_m = 0.3;  ///< matter; Omega_Lambda = 1 - Omega_m (flat)

  double omega_l() const { return 1 - omega_m; }
  /// H(a) / H0.
  double hubble(double a) const { return std::sqrt(omega_m / (a * a * a) + omega_l()); }

  /// Linear growth factor, D(1) = 1, of the growing mode for matter + Lambda
  /// (Heath 1977, MNRAS 179, 351): D(a) ∝ H(a) ∫_0^a da' / (a' H(a'))^3.
  double growth(double a) const { return growth_unnormalised(a) / growth_unnormalised(1.0); }
  /// f = dln D / dln a.
  double growth_rate(double a) const {
    const double h = hubble(a), i = integral(a);
    const double dh = -1.5 * omega_m / (a * a * a * a) / h;  // dH/da
    const double dd = dh * i + h / std::pow(a * h, 3);
    return a * dd / (h * i);
  }

  /// Leapfrog factors for KDK in the scale factor (Quinn et al. 1997, astro-ph/9710043;
  /// Springel 2005 eqs. 31-33): drift ∫ da / (a^3 H) (x += p * drift), kick
  /// ∫ da / (a^2 H) (p += acc * kick), by Simpson's rule.
  double drift(double a0, double a1) const { return simpson([&](double a) { return 1 / (a * a * a * hubble(a)); }, a0, a1); }
  double kick(double a0, double a1) const { return simpson([&](double a) { return 1 / (a * a * hubble(a)); }, a0, a1); }
  /// Mean comoving matter density in code units (G = H0 = 1).
  double mean_density() const { return 3 * omega_m / (8 * std::numbers::pi); }

 private:
  double integral(double a) const {
    // ∫_0^a da' / (a' H)^3: the integrand ~ a'^{3/2} near 0; substitute a' = u^2.
    // (a' H)^3 = (Omega_m / a' + Omega_L a'^2)^{3/2}, so the integrand is
    // 2 u^4 / (Omega_m + Omega_L u^6)^{3/2}: finite at u = 0.
    return simpson([&](double u) {
      const double u2 = u * u;
      return 2 * u2 * u2 / std::pow(omega_m + omega_l() * u2 * u2 * u2, 1.5);
    }, 0.0, std::sqrt(a), 2000);
  }
  double growth_unnormalised(double a) const { return hubble(a) * integral(a); }
  template <class F>
  static double simpson(F f, double lo, double hi, int n = 512) {
    if (hi == lo) return 0;
    const double h = (hi - lo) / n;
    double s = f(lo) + f(hi);
    for (int i = 1; i < n; ++i) s += f(lo + i * h) * (i % 2 ? 4 : 2);
    return s * h / 3;
  }
};

/// The linear matter power spectrum at a = 1, P(k) = A k^n_s T(k)^2, normalised to
/// sigma_8; k in h/Mpc, P in (Mpc/h)^3.
struct PowerSpectrum {
  enum class Fit { eisenstein_hu, bbks };
  double omega_m = 0.3, omega_b = 0.045, h = 0.7, n_s = 0.96, sigma8 = 0.8, t_cmb = 2.7255;
  Fit fit = Fit::eisenstein_hu;

  void normalise() {
    amplitude_ = 1;
    amplitude_ = sigma8 * sigma8 / sigma2(8.0);
  }
  double operator()(double k) const {
    const double t = transfer(k);
    return amplitude_ * std::pow(k, n_s) * t * t;
  }
  /// Transfer function. Eisenstein & Hu 1998 (ApJ 496, 605), the shape without
  /// baryon oscillations, eqs. 26, 28-31; BBKS: Bardeen, Bond, Kaiser & Szalay
  /// 1986 (ApJ 304, 15) eq. G3 with the shape Gamma = Omega_m h exp(-Omega_b (1 +
  /// sqrt(2h) / Omega_m)) of Sugiyama 1995 (ApJS 100, 281, eq. 3.9).
  double transfer(double k) const {
    if (k <= 0) return 1;
    if (fit == Fit::bbks) {
      const double gamma = omega_m * h * std::exp(-omega_b * (1 + std::sqrt(2 * h) / omega_m));
      const double q = k / gamma;
      return std::log(1 + 2.34 * q) / (2.34 * q) *
             std::pow(1 + 3.89 * q + std::pow(16.1 * q, 2) + std::pow(5.46 * q, 3) + std::pow(6.71 * q, 4), -0.25);
    }
    const double theta = t_cmb / 2.7, wm = omega_m * h * h, wb = omega_b * h * h, fb = omega_b / omega_m;
    const double s = 44.5 * std::log(9.83 / wm) / std::sqrt(1 + 10 * std::pow(wb, 0.75));      // eq. 26, Mpc
    const double alpha = 1 - 0.328 * std::log(431 * wm) * fb + 0.38 * std::log(22.3 * wm) * fb * fb;  // eq. 31
    const double kmpc = k * h;                                                                   // 1/Mpc
    const double gamma = omega_m * h * (alpha + (1 - alpha) / (1 + std::pow(0.43 * kmpc * s, 4)));  // eq. 30
    const double q = k * theta * theta / gamma;                                                  // eq. 28
    const double l0 = std::log(2 * std::numbers::e + 1.8 * q), c0 = 14.2 + 731 / (1 + 62.5 * q);  // eq. 29
    return l0 / (l0 + c0 * q * q);
  }
  /// rms of the linear density in spheres of radius r (Mpc/h), top-hat window.
  double sigma2(double r) const {
    const int n = 4000;
    const double lo = std::log(1e-5), hi = std::log(1e3), d = (hi - lo) / n;
    double s = 0;
    for (int i = 0; i <= n; ++i) {
      const double k = std::exp(lo + i * d), x = k * r;
      const double w = x < 1e-3 ? 1 - x * x / 10 : 3 * (std::sin(x) - x * std::cos(x)) / (x * x * x);
      const double f = k * k * k * (*this)(k) * w * w / (2 * std::numbers::pi * std::numbers::pi);
      s += f * ((i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2));
    }
    return s * d / 3;
  }

 private:
  double amplitude_ = 1;
};

}  // namespace cosmo
