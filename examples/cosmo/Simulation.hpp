/// \file Simulation.hpp
/// \brief A periodic box of dark matter in comoving coordinates, advanced by the
///        kick-drift-kick leapfrog in the scale factor with TreePM forces.
///
/// Equations of motion per unit mass (Springel 2005, MNRAS 364, 1105, eqs. 27-30):
/// dx/da = p / (a^3 H), dp/da = -grad Phi / (a^2 H), with p = a^2 dx/dt and Phi the
/// potential of the masses at their comoving positions, uniform background
/// subtracted (grad^2 Phi = 4 pi G (rho - rho_bar), what pik::pm::TreePM computes).
/// One step from a0 to a1 kicks over [a0, am], drifts over [a0, a1] and kicks over
/// [am, a1], am = sqrt(a0 a1), with the factors integrated exactly for the
/// background (Quinn et al. 1997).
#pragma once

#include <cmath>
#include <vector>

#include <pik/pik.hpp>
#include <pik/pm/TreePM.hpp>

#include "Cosmology.hpp"
#include "Particles.hpp"

namespace cosmo {

struct GravityParams {
  double box = 100;    ///< side L, Mpc/h
  int n_mesh = 64;     ///< PM cells per side
  double theta = 0.3;  ///< opening angle of the short-range walk
  double eps = 0.01;   ///< comoving Plummer softening, Mpc/h
  int group = 32;      ///< i-group limit of the walk (fewer wasted pairs than 64 at r_cut)
  double r_split_cells = 1.25;  ///< Gaussian split scale r_s in mesh cells (pik::pm::MeshParams)
  double r_cut_split = 5.0;     ///< short-range cut-off in units of r_s (pik::pm::TreePMParams)
  pik::pm::Assignment assignment = pik::pm::Assignment::tsc;  ///< mesh assignment and interpolation window
};

template <class CommT>
class Simulation {
 public:
  using Gravity = pik::pm::TreePM<Force, EPI, EPJ, SPJ, CommT>;

  Simulation(const Background& bg, const GravityParams& gp, CommT comm)
      : bg_(bg), gp_(gp), comm_(comm), gravity_(treepm_params(gp), comm), domain_(comm) {
    domain_.set_periodic_box({{0, 0, 0}, {gp.box, gp.box, gp.box}});
  }

  pik::ParticleSystem<Body> ps;  ///< this rank's particles
  double a = 0;                  ///< scale factor of positions, momenta and forces

  const Background& background() const { return bg_; }
  const GravityParams& gravity_params() const { return gp_; }
  Gravity& gravity() { return gravity_; }
  pik::DomainInfo<double, 3, CommT>& domain() { return domain_; }
  const CommT& comm() const { return comm_; }

  /// Kernels of kernels/gravity_treepm.pik for this box: K(eps2, rcut2, 1/(2 r_s)).
  template <class K>
  K kernel() const {
    return K(float(gp_.eps * gp_.eps), float(gravity_.rcut2()), float(gravity_.inv_2rs()));
  }

  /// Decompose, exchange, TreePM forces at the current positions. Collective.
  template <class K, class KS>
  void compute_forces(const K& k, const KS& ks) {
    const double t0 = pik::wall_time();
    domain_.decompose(ps.vector(), cost_);
    pik::exchange_particles(ps, domain_);
    gravity_.calcForceAllAndWriteBack(k, ks, ps);
    cost_ = pik::wall_time() - t0;
    seconds_force_ += cost_;
  }

  /// One KDK step to a1 (forces must be current). Collective.
  template <class K, class KS>
  void step(double a1, const K& k, const KS& ks) {
    const double a0 = a, am = std::sqrt(a0 * a1);
    const double k1 = bg_.kick(a0, am), d = bg_.drift(a0, a1), k2 = bg_.kick(am, a1);
    const double L = gp_.box;
    for (Body& b : ps) {
      b.mom += b.acc() * k1;
      b.pos += b.mom * d;
      for (int c = 0; c < 3; ++c) {
        b.pos[c] -= L * std::floor(b.pos[c] / L);
        if (b.pos[c] >= L) b.pos[c] = 0;
      }
    }
    a = a1;
    compute_forces(k, ks);
    for (Body& b : ps) b.mom += b.acc() * k2;
  }

  /// Total momentum sum m p and the sum of m |p| (its natural scale), over ranks.
  std::pair<V, double> momentum() const {
    V p{};
    double s = 0;
    for (const Body& b : ps) p += b.mom * b.mass, s += b.mass * pik::norm(b.mom);
    return {comm_.sum(p), comm_.sum(s)};
  }
  double seconds_force() const { return seconds_force_; }

 private:
  static pik::pm::TreePMParams treepm_params(const GravityParams& gp) {
    pik::pm::TreePMParams p;
    p.mesh.box = gp.box, p.mesh.n_mesh = gp.n_mesh, p.mesh.r_split_cells = gp.r_split_cells;
    p.mesh.assignment = gp.assignment;
    p.theta = gp.theta, p.n_group_limit = gp.group, p.r_cut_split = gp.r_cut_split;
    return p;
  }

  Background bg_;
  GravityParams gp_;
  CommT comm_;
  Gravity gravity_;
  pik::DomainInfo<double, 3, CommT> domain_;
  double cost_ = -1, seconds_force_ = 0;
};

}  // namespace cosmo
