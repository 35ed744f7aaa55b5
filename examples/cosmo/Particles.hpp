/// \file Particles.hpp
/// \brief The particle types of the cosmological box: what is stored, what the
///        TreePM kernels (kernels/gravity_treepm.pik) read, what they return.
#pragma once

#include <cstdint>

#include <pik/Vec.hpp>
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
/// Kernel views: single precision positions (relative precision 6e-8 of the box).
struct EPI {
  pik::Vec3<float> pos;
  const pik::Vec3<float>& getPos() const { return pos; }
  void copyFromFP(const Body& b) { pos = pik::vec_cast<pik::Vec3<float>>(b.pos); }
};
struct EPJ {
  pik::Vec3<float> pos;
  float mass;
  const pik::Vec3<float>& getPos() const { return pos; }
  void setPos(const pik::Vec3<float>& x) { pos = x; }
  float getCharge() const { return mass; }
  void copyFromFP(const Body& b) { pos = pik::vec_cast<pik::Vec3<float>>(b.pos), mass = float(b.mass); }
};
using SPJ = pik::SPJMonopole<float>;

}  // namespace cosmo
