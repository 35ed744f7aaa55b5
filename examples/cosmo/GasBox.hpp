/// \file GasBox.hpp
/// \brief A periodic box of dark matter and adiabatic gas in comoving coordinates:
///        both species in one TreePM gravity (pik::species), SPH on the gas only.
///
/// Gravity: pik::pm::TreePM over the bundle pik::species(dm, gas) — one mesh, one
/// short-range tree, each particle's result written back into its own species.
/// Hydrodynamics: the SPH kernel library (kernels/sph_density.pik with the layer's
/// smoothing-length iteration, pik/sph/SmoothingLength.hpp; kernels/sph_force_ssph.pik:
/// grad-h SPH, Monaghan 1997 viscosity with the Balsara 1995 switch) on the gas in a
/// periodic short-range tree.
///
/// Comoving SPH (Springel 2005, MNRAS 364, 1105, sect. 3). With comoving x, the
/// canonical momentum p = a^2 dx/dt = a v (v the physical peculiar velocity), the
/// comoving density rho_c = a^3 rho and the comoving pressure P_c = (gamma - 1) rho_c u
/// (u physical), the physical SPH equations become
///   dp/dt = -grad Phi / a + A,  A = -sum_j m_j (P_c,i f_i/rho_c,i^2 + P_c,j f_j/rho_c,j^2 + Pi_c,ij) grad_x W_ij,
///   du/dt = -3 (gamma - 1) H u + U / a,  U = sum_j m_j (f_i P_c,i/rho_c,i^2 + Pi_c,ij/2) v_ij . grad_x W_ij,
/// where A and U are exactly what the kernels return when they are given comoving
/// x, h, rho_c, P_c and physical v and sound speed c = sqrt(gamma (gamma - 1) u)
/// (each a^-3 of rho and a^-1 of the gradient cancel; the viscosity Pi_c = Pi a^-3).
/// The Hubble term of du/dt is integrated exactly by the entropic variable
/// ut = u a^(3 (gamma - 1)), dut/dt = a^(3 gamma - 4) U; in the scale factor (dt =
/// da / (a H)):
///   dp/da = -grad Phi / (a^2 H) + A / (a H),  dut/da = a^(3 gamma - 5) U / H.
/// The viscosity must see the Hubble flow between a pair (as GADGET-2's does):
/// before turnaround neighbours recede, and a viscosity of the peculiar velocities
/// alone heats smoothly converging linear flows as if they were shocks (by four
/// orders of magnitude in T at z = 9 in a 16^3 test box). So the kernels read
/// v + a H x; the pressure part of their du/dt then holds the SPH estimate of the
/// Hubble compression, pf_i a H S_i with S_i = sum_j m_j x_ij . grad_i W(h_i) (the
/// density kernel's divv with x for v: one more gather pass), which is taken out
/// again, since ut integrates the Hubble term exactly:
///   U = U_kernel - a H pf_i S_i,  div v (peculiar, for the Balsara switch) from divv - a H S_i.
///
/// Steps: KDK (Quinn et al. 1997) from a0 to a1, split into equal substeps in ln a
/// when the Courant condition of the gas, dln a <= C H a h / v_sig (h the comoving
/// support radius, v_sig the largest signal speed), asks for more; v and u are
/// predicted to the end of each drift for the SPH passes. One process (the SPH
/// layer's limit, docs/physics-layer.md).
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <pik/pik.hpp>
#include <pik/pm/TreePM.hpp>
#include <pik/sph/SmoothingLength.hpp>

#include "Cosmology.hpp"
#include "Particles.hpp"
#include "Simulation.hpp"

namespace cosmo {

struct GasParams {
  double gamma = 5.0 / 3.0;  ///< adiabatic index
  double alpha = 1.0;        ///< artificial viscosity (Monaghan 1997)
  double nngb = 100;         ///< neighbour number (Wendland C2, Dehnen & Aly 2012)
  double cfl = 0.25;         ///< Courant factor on the support radius
  bool balsara = true;       ///< Balsara (1995) switch
};

/// Mean molecular weight of neutral primordial gas (X = 0.76): 1 / (X + Y/4) = 1.22.
inline constexpr double mu_neutral = 1.2195;
/// k_B / m_p in (100 km/s)^2 per kelvin: 1.380649e-23 / 1.67262192e-27 m^2 s^-2 K^-1.
inline constexpr double kb_over_mp = 8254.4e-10;
/// Specific internal energy (code units, (100 km/s)^2) of gas at temperature T.
inline double u_of_temperature(double T, double gamma, double mu = mu_neutral) { return kb_over_mp * T / ((gamma - 1) * mu); }
inline double temperature_of_u(double u, double gamma, double mu = mu_neutral) { return u * (gamma - 1) * mu / kb_over_mp; }

template <class DensityKernel, class HydroKernel>
class GasBox {
 public:
  using Gravity = pik::pm::TreePM<Force, EPI, EPJ, SPJ, pik::SerialComm>;
  using DensityTree = pik::ShortRangeTree<pik::sph::DensityResult, GasEP, GasEP, pik::SearchMode::gather>;
  using HydroTree = pik::ShortRangeTree<pik::sph::HydroResult, GasEP, GasEP, pik::SearchMode::symmetric>;

  GasBox(const Background& bg, const GravityParams& gp, const GasParams& gas)
      : bg_(bg), gp_(gp), gas_p_(gas), gravity_(treepm_params(gp), pik::SerialComm::world()),
        density_tree_({.n_leaf_limit = 8, .n_group_limit = 32}, box()),
        hydro_tree_({.n_leaf_limit = 8, .n_group_limit = 32}, box()), hydro_(float(gas.alpha)) {
    h_params_.nngb = gas.nngb;
  }

  pik::ParticleSystem<Body> dm;  ///< dark matter
  pik::ParticleSystem<Gas> gas;  ///< gas
  double a = 0;                  ///< scale factor of positions, momenta and forces

  const Background& background() const { return bg_; }
  const GasParams& gas_params() const { return gas_p_; }
  Gravity& gravity() { return gravity_; }
  const pik::SerialComm& comm() const { return comm_; }

  /// Kernels of kernels/gravity_treepm.pik for this box.
  template <class K>
  K kernel() const {
    return K(float(gp_.eps * gp_.eps), float(gravity_.rcut2()), float(gravity_.inv_2rs()));
  }

  /// A first smoothing length for gas without one: the radius holding nngb particles
  /// at the mean gas density.
  void initial_smoothing_lengths() {
    const double L = gp_.box, n = double(gas.size());
    const double h0 = std::cbrt(3 * gas_p_.nngb / (4 * std::numbers::pi) * L * L * L / n);
    for (Gas& g : gas)
      if (!(g.h > 0)) g.h = h0;
  }

  /// Gravity of both species (one TreePM call over the bundle), then density and
  /// hydrodynamic forces of the gas, at the current positions and predicted
  /// velocities and energies.
  template <class K, class KS>
  void compute_forces(const K& k, const KS& ks) {
    const double t0 = pik::wall_time();
    gravity_.calcForceAllAndWriteBack(k, ks, pik::species(dm, gas));
    const double t1 = pik::wall_time();
    hydro();
    seconds_gravity_ += t1 - t0, seconds_sph_ += pik::wall_time() - t1;
  }

  /// One KDK step to a1 in substeps that keep the gas's Courant condition. Returns
  /// the number of substeps.
  template <class K, class KS>
  int step(double a1, const K& k, const KS& ks) {
    const double dl = std::log(a1 / a), lim = courant_dlna();
    const int n = std::max(1, int(std::ceil(dl / lim * (1 - 1e-12))));
    const double a0 = a;
    for (int s = 1; s <= n; ++s) substep(s == n ? a1 : a0 * std::exp(dl * s / n), k, ks);
    return n;
  }

  /// The largest step in ln a the gas's Courant condition allows now.
  double courant_dlna() const {
    double lim = 1e30;
    for (const Gas& g : gas)
      if (g.vsig > 0) lim = std::min(lim, gas_p_.cfl * bg_.hubble(a) * a * g.h / g.vsig);
    return lim;
  }

  /// Total momentum sum m p (both species) and the sum of m |p|.
  std::pair<V, double> momentum() const {
    V p{};
    double s = 0;
    for (const Body& b : dm) p += b.mom * b.mass, s += b.mass * pik::norm(b.mom);
    for (const Gas& g : gas) p += g.mom * g.mass, s += g.mass * pik::norm(g.mom);
    return {p, s};
  }
  /// Mass-weighted mean temperature of the gas (K).
  double mean_temperature() const {
    double mt = 0, m = 0;
    for (const Gas& g : gas) mt += g.mass * temperature_of_u(g.u, gas_p_.gamma), m += g.mass;
    return mt / m;
  }
  double seconds_gravity() const { return seconds_gravity_; }
  double seconds_sph() const { return seconds_sph_; }
  int density_passes() const { return passes_; }

 private:
  pik::Boundary<3> box() const { return pik::Boundary<3>::periodic_box({0, 0, 0}, {gp_.box, gp_.box, gp_.box}); }
  static pik::pm::TreePMParams treepm_params(const GravityParams& gp) {
    pik::pm::TreePMParams p;
    p.mesh.box = gp.box, p.mesh.n_mesh = gp.n_mesh, p.mesh.r_split_cells = gp.r_split_cells;
    p.theta = gp.theta, p.n_group_limit = gp.group, p.r_cut_split = gp.r_cut_split;
    return p;
  }

  /// Density (smoothing-length iteration), equation of state, grad-h factor,
  /// Balsara switch, hydrodynamic forces. Uses g.vel and g.u (set by the caller).
  void hydro() {
    const double gm = gas_p_.gamma, aH = a * bg_.hubble(a);
    for (Gas& g : gas) g.hub = aH;
    passes_ += pik::sph::iterate_smoothing_length<3>(
        gas, [&] { density_tree_.calcForceAllAndWriteBack(density_, gas); }, h_params_);
    for (Gas& g : gas) g.geometric = true;
    density_tree_.calcForceAllAndWriteBack(density_, gas);
    ++passes_;
    for (Gas& g : gas) {
      g.geometric = false;
      g.divv -= aH * g.geo;  // peculiar part
      g.pres = (gm - 1) * g.rho * g.u;  // comoving pressure P_c
      g.cs = std::sqrt(gm * (gm - 1) * g.u);
      const double om = 1 + g.h / (3 * g.rho) * g.drhodh;  // Springel & Hernquist 2002, eq. 8
      g.fgrad = om > 0.2 ? 1 / om : 1.0;
      const double div = std::abs(g.divv) / g.rho, curl = g.curl / g.rho;
      g.balsara = gas_p_.balsara ? div / (div + curl + 1e-4 * g.cs / g.h + 1e-300) : 1.0;
      g.pf = g.fgrad * g.pres / (g.rho * g.rho);
    }
    hydro_tree_.calcForceAllAndWriteBack(hydro_, gas);
    for (Gas& g : gas) g.dudt -= aH * g.pf * g.geo;  // the Hubble compression, integrated exactly by ut
  }

  /// dut/da = a^(3 gamma - 5) U / H at the force time a.
  double ut_rate(const Gas& g) const { return std::pow(a, 3 * gas_p_.gamma - 5) * g.dudt / bg_.hubble(a); }
  /// u of the entropic variable at scale factor s.
  double u_of(double ut, double s) const { return ut * std::pow(s, -3 * (gas_p_.gamma - 1)); }

  template <class K, class KS>
  void substep(double a1, const K& k, const KS& ks) {
    const double a0 = a, am = std::sqrt(a0 * a1), L = gp_.box;
    const double kg1 = bg_.kick(a0, am), kg2 = bg_.kick(am, a1);          // ∫ da / (a^2 H)
    const double kh1 = hydro_kick(a0, am), kh2 = hydro_kick(am, a1);      // ∫ da / (a H)
    const double d = bg_.drift(a0, a1);
    auto wrap = [&](V& x) {
      for (int c = 0; c < 3; ++c) {
        x[c] -= L * std::floor(x[c] / L);
        if (x[c] >= L) x[c] = 0;
      }
    };
    for (Body& b : dm) {
      b.mom += b.acc() * kg1;
      b.pos += b.mom * d;
      wrap(b.pos);
    }
    for (Gas& g : gas) {
      const V kick2 = g.acc() * kg2 + g.acc_hydro * kh2;  // the predictor's second half
      const double du = ut_rate(g);
      g.mom += g.acc() * kg1 + g.acc_hydro * kh1;
      g.ut = std::max(g.ut + du * (am - a0), 0.5 * g.ut);
      g.pos += g.mom * d;
      wrap(g.pos);
      // Predicted to a1 for the SPH passes (the old rates over the second half).
      g.vel = (g.mom + kick2) / a1;
      g.u = u_of(std::max(g.ut + du * (a1 - am), 0.5 * g.ut), a1);
    }
    a = a1;
    compute_forces(k, ks);
    for (Body& b : dm) b.mom += b.acc() * kg2;
    for (Gas& g : gas) {
      g.mom += g.acc() * kg2 + g.acc_hydro * kh2;
      g.ut = std::max(g.ut + ut_rate(g) * (a1 - am), 0.5 * g.ut);
      g.vel = g.mom / a1, g.u = u_of(g.ut, a1);
    }
  }
  double hydro_kick(double a0, double a1) const {  // ∫ da / (a H), Simpson
    const int n = 64;
    const double h = (a1 - a0) / n;
    auto f = [&](double x) { return 1 / (x * bg_.hubble(x)); };
    double s = f(a0) + f(a1);
    for (int i = 1; i < n; ++i) s += f(a0 + i * h) * (i % 2 ? 4 : 2);
    return s * h / 3;
  }

  Background bg_;
  GravityParams gp_;
  GasParams gas_p_;
  pik::SerialComm comm_ = pik::SerialComm::world();
  Gravity gravity_;
  DensityTree density_tree_;
  HydroTree hydro_tree_;
  DensityKernel density_;
  HydroKernel hydro_;
  pik::sph::SmoothingLengthParams h_params_;
  int passes_ = 0;
  double seconds_gravity_ = 0, seconds_sph_ = 0;
};

}  // namespace cosmo
