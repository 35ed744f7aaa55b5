/// \file Particles.hpp
/// \brief The particle types of the cosmological box: what is stored, what the
///        TreePM kernels (kernels/gravity_treepm.pik) read, what they return.
#pragma once

#include <cstdint>

#include <cmath>

#include <pik/Vec.hpp>
#include <pik/sph/KernelResults.hpp>
#include <pik/tree/SuperParticle.hpp>

namespace cosmo {

using V = pik::Vec3<double>;

struct Force {  // the short-range kernel's result
  pik::Vec3<float> acc;
  void clear() { acc = {}; }
};
/// A dark-matter particle: comoving position x (Mpc/h, in [0, L)), canonical
/// momentum p = a^2 dx/dt, the two parts of the acceleration -grad Phi.
struct Body {
  std::uint64_t id = 0;
  double mass = 0;
  V pos{}, mom{}, acc_short{}, acc_long{};
  const V& getPos() const { return pos; }
  void setPos(const V& x) { pos = x; }
  void copyFromForce(const Force& f) { acc_short = pik::vec_cast<V>(f.acc); }
  void copyFromForceParticleMesh(const V& a) { acc_long = a; }
  V acc() const { return acc_short + acc_long; }
};
/// A gas particle (the dark matter + gas box, GasBox.hpp): what a Body holds, the
/// hydrodynamic acceleration and, for the SPH kernels (kernels/sph_density.pik,
/// sph_force_ssph.pik), comoving h and rho, the physical peculiar velocity v = p / a
/// and the entropic variable ut = u a^(3 (gamma - 1)) (u the physical specific
/// internal energy; ut is constant under adiabatic expansion).
///
/// The kernels read the velocity v + hub x (hub = a H: the Hubble flow, so that the
/// viscosity sees pairs recede as they do; GasEP::setPos keeps it for periodic
/// images); with `geometric` set they read x instead (the pass that measures the
/// SPH estimate of the Hubble flow's divergence, stored in `geo`; GasBox.hpp).
struct Gas {
  std::uint64_t id = 0;
  double mass = 0;
  V pos{}, mom{}, acc_short{}, acc_long{}, acc_hydro{};
  double ut = 0, dudt = 0;                          // dudt: the hydro kernel's rate (see GasBox.hpp)
  V vel{};                                          // v = p / a at the force time
  double u = 0;                                     // physical u at the force time
  double hub = 0, geo = 0;                          // a H of the kernel velocity; sum m x_ij . grad W
  bool geometric = false;
  double h = 0, rho = 0, drhodh = 0, h_lo = 0, h_hi = 0, divv = 0, curl = 0, nngb = 0;
  double pres = 0, cs = 0, fgrad = 1, balsara = 1, pf = 0, vsig = 0;
  const V& getPos() const { return pos; }
  void setPos(const V& x) { pos = x; }
  void copyFromForce(const Force& f) { acc_short = pik::vec_cast<V>(f.acc); }
  void copyFromForceParticleMesh(const V& a) { acc_long = a; }
  void copyFromForce(const pik::sph::DensityResult& f) {
    if (geometric) {
      geo = f.divv;
      return;
    }
    rho = f.rho, drhodh = f.drhodh, divv = f.divv, nngb = f.nngb;
    curl = std::sqrt(double(f.rotv.x) * f.rotv.x + double(f.rotv.y) * f.rotv.y + double(f.rotv.z) * f.rotv.z);
  }
  void copyFromForce(const pik::sph::HydroResult& f) { acc_hydro = pik::vec_cast<V>(f.acc), dudt = f.dudt, vsig = f.vsig; }
  V acc() const { return acc_short + acc_long; }  // gravity
};
/// What the SPH kernels read of a gas particle (i and j alike), single precision.
struct GasEP {
  pik::Vec3<float> pos, vel;
  float h, mass, u, rho, pf, cs, balsara, hub;
  const pik::Vec3<float>& getPos() const { return pos; }
  /// A periodic image at x: its Hubble velocity moves with it.
  void setPos(const pik::Vec3<float>& x) {
    vel += (x - pos) * hub;
    pos = x;
  }
  float getRSearch() const { return h; }
  void copyFromFP(const Gas& g) {
    pos = pik::vec_cast<pik::Vec3<float>>(g.pos);
    hub = float(g.geometric ? 1.0 : g.hub);
    vel = pik::vec_cast<pik::Vec3<float>>(g.geometric ? g.pos : g.vel + g.pos * g.hub);
    h = float(g.h), mass = float(g.mass), u = float(g.u), rho = float(g.rho), pf = float(g.pf), cs = float(g.cs);
    balsara = float(g.balsara);
  }
};

/// Kernel views: single precision positions (relative precision 6e-8 of the box).
struct EPI {
  pik::Vec3<float> pos;
  const pik::Vec3<float>& getPos() const { return pos; }
  void copyFromFP(const Body& b) { pos = pik::vec_cast<pik::Vec3<float>>(b.pos); }
  void copyFromFP(const Gas& b) { pos = pik::vec_cast<pik::Vec3<float>>(b.pos); }
};
struct EPJ {
  pik::Vec3<float> pos;
  float mass;
  const pik::Vec3<float>& getPos() const { return pos; }
  void setPos(const pik::Vec3<float>& x) { pos = x; }
  float getCharge() const { return mass; }
  void copyFromFP(const Body& b) { pos = pik::vec_cast<pik::Vec3<float>>(b.pos), mass = float(b.mass); }
  void copyFromFP(const Gas& b) { pos = pik::vec_cast<pik::Vec3<float>>(b.pos), mass = float(b.mass); }
};
using SPJ = pik::SPJMonopole<float>;

}  // namespace cosmo
