/// \file Thermostat.hpp
/// \brief Temperature control: plain velocity rescaling (equilibration) and the
///        stochastic velocity-rescaling thermostat (production, canonical ensemble).
///
/// Equilibration rescales every velocity so the kinetic temperature equals the
/// target exactly (isokinetic; Woodcock 1971): quick, but it samples no ensemble.
/// Production uses canonical sampling through velocity rescaling (CSVR; Bussi,
/// Donadio & Parrinello, J. Chem. Phys. 126, 014101, 2007): the kinetic energy K
/// follows a stochastic differential equation whose stationary distribution is
/// the canonical one, P(K) ~ K^(N_f/2 - 1) exp(-K/T), with relaxation time tau.
/// Velocities are only rescaled (never randomised one by one), so the dynamics is
/// disturbed gently, and configurations sample the NVT ensemble of Monte Carlo
/// references such as NIST's.
#pragma once

#include <cmath>
#include <cstdint>

#include <pik/ic/Random.hpp>

#include "Lattice.hpp"

namespace md {

/// Gamma(shape, 1) deviate (Marsaglia & Tsang, ACM TOMS 26, 363, 2000); shapes
/// below 1 through Gamma(a) = Gamma(a + 1) U^(1/a).
inline double gamma_deviate(pik::ic::Stream& s, double shape) {
  if (shape < 1.0) return gamma_deviate(s, shape + 1.0) * std::pow(s.uniform_open0(), 1.0 / shape);
  const double d = shape - 1.0 / 3.0, c = 1.0 / std::sqrt(9.0 * d);
  for (;;) {
    double x, v;
    do {
      x = normal(s);
      v = 1.0 + c * x;
    } while (v <= 0.0);
    v = v * v * v;
    const double u = s.uniform_open0();
    if (std::log(u) < 0.5 * x * x + d - d * v + d * std::log(v)) return d * v;
  }
}

/// Sum of k squared standard normal deviates (chi-squared with k degrees of freedom).
inline double chi_squared(pik::ic::Stream& s, double k) { return k > 0 ? 2.0 * gamma_deviate(s, 0.5 * k) : 0.0; }

/// The CSVR thermostat: one call per time step returns the factor by which to scale
/// all velocities.
class Csvr {
 public:
  /// target temperature T, relaxation time tau (in time units; 0 = instantaneous
  /// canonical resampling of K), N_f degrees of freedom, random seed.
  Csvr(double temperature, double tau, double dof, std::uint64_t seed)
      : t_(temperature), tau_(tau), nf_(dof), rng_(seed, 0x6373767274686572ull /* "csvrther" */) {}

  /// Scale factor for velocities whose kinetic energy is K, after a step dt (Bussi
  /// et al. 2007, eq. A7: the exact solution of the K equation over dt).
  double factor(double kinetic, double dt) {
    if (!(kinetic > 0)) return 1.0;
    const double kbar = 0.5 * nf_ * t_;  // target mean kinetic energy
    const double c = tau_ > 0 ? std::exp(-dt / tau_) : 0.0;
    const double r1 = normal(rng_);
    const double s = chi_squared(rng_, nf_ - 1.0);
    const double k_new = kinetic + (1.0 - c) * (kbar * (s + r1 * r1) / nf_ - kinetic) +
                         2.0 * r1 * std::sqrt(kinetic * kbar / nf_ * (1.0 - c) * c);
    return std::sqrt(std::max(k_new, 0.0) / kinetic);
  }

 private:
  double t_, tau_, nf_;
  pik::ic::Stream rng_;
};

}  // namespace md
