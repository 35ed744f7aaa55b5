/// \file SuperParticle.hpp
/// \brief Super-particles (SPJ): a tree cell's moments as a j-particle for kernels.
///
/// The long-range walk hands kernels two lists: real j-particles (the user's EPJ)
/// and super-particles (one of these types, or the user's own type satisfying
/// `SuperParticle`). Member names follow the kernel library: `pos`, `mass`, and for
/// the quadrupole `qxx qyy qzz qxy qxz qyz` (see kernels/gravity_quadrupole.pik).
#pragma once

#include <concepts>

#include "pik/Vec.hpp"
#include "pik/tree/Multipole.hpp"

namespace pik {

/// A super-particle type: knows its multipole order (0 or 2) and dimension, is made
/// from cell moments and gives them back (imported super-particles from other ranks
/// are merged into the local tree through getMoments()).
template <class S>
concept SuperParticle = std::default_initializable<S> && requires(S& s, const S& cs) {
  { S::order } -> std::convertible_to<int>;
  { S::dim } -> std::convertible_to<int>;
  s.setMoments(Multipole<S::dim>{});
  { cs.getMoments() } -> std::same_as<Multipole<S::dim>>;
};

/// Monopole super-particle: total mass at the centre of mass.
template <class T, int D = 3>
struct SPJMonopole {
  static constexpr int order = 0;
  static constexpr int dim = D;
  Vec<T, D> pos{};
  T mass{};

  void setMoments(const Multipole<D>& m) {
    pos = vec_cast<Vec<T, D>>(m.pos);
    mass = T(m.mass);
  }
  Multipole<D> getMoments() const {
    Multipole<D> m;
    m.mass = double(mass);
    m.pos = vec_cast<Vec<double, D>>(pos);
    return m;
  }
  const Vec<T, D>& getPos() const { return pos; }
  void setPos(const Vec<T, D>& p) { pos = p; }
  T getCharge() const { return mass; }
};

/// Quadrupole super-particle (3D): mass, centre of mass and traceless quadrupole.
template <class T>
struct SPJQuadrupole {
  static constexpr int order = 2;
  static constexpr int dim = 3;
  Vec3<T> pos{};
  T mass{};
  T qxx{}, qyy{}, qzz{}, qxy{}, qxz{}, qyz{};

  void setMoments(const Multipole<3>& m) {
    pos = vec_cast<Vec3<T>>(m.pos);
    mass = T(m.mass);
    qxx = T(m.quad[0]), qyy = T(m.quad[1]), qzz = T(m.quad[2]);
    qxy = T(m.quad[3]), qxz = T(m.quad[4]), qyz = T(m.quad[5]);
  }
  Multipole<3> getMoments() const {
    Multipole<3> m;
    m.mass = double(mass);
    m.pos = vec_cast<Vec3<double>>(pos);
    const T q[6] = {qxx, qyy, qzz, qxy, qxz, qyz};
    for (int k = 0; k < 6; ++k) m.quad[k] = double(q[k]);
    return m;
  }
  const Vec3<T>& getPos() const { return pos; }
  void setPos(const Vec3<T>& p) { pos = p; }
  T getCharge() const { return mass; }
};

}  // namespace pik
