/// \file Particles.hpp
/// \brief The particle types of the Lennard-Jones example: the stored atom, what the
///        kernel reads of an i- and a j-atom, and what it returns.
#pragma once

#include <cstdint>

#include <pik/Vec.hpp>

namespace md {

using pik::Vec3;

/// Kernel result (kernels/lj.pik accumulates into it): acceleration (= force, m = 1),
/// potential energy and virial sum_j r_ij . F_ij of one atom.
struct Force {
  Vec3<double> acc;
  double pot;
  double vir;
  void clear() { acc = {}, pot = 0, vir = 0; }
};

/// The stored atom (reduced units: sigma = epsilon = m = k_B = 1).
struct Atom {
  std::uint64_t id;
  Vec3<double> pos, vel, acc;
  double pot, vir;
  double rsearch;  ///< neighbour-search radius r_c + skin, set by md::System
  const Vec3<double>& getPos() const { return pos; }
  void setPos(const Vec3<double>& x) { pos = x; }
  void copyFromForce(const Force& f) { acc = f.acc, pot = f.pot, vir = f.vir; }
};

/// An i-atom: position and the search radius r_c + skin (gather search).
struct EPI {
  Vec3<double> pos;
  double rsearch;
  const Vec3<double>& getPos() const { return pos; }
  double getRSearch() const { return rsearch; }
  void copyFromFP(const Atom& a) { pos = a.pos, rsearch = a.rsearch; }
};

/// A j-atom: its position; setPos lets the tree hand the kernel periodic images.
struct EPJ {
  Vec3<double> pos;
  const Vec3<double>& getPos() const { return pos; }
  void setPos(const Vec3<double>& x) { pos = x; }
  void copyFromFP(const Atom& a) { pos = a.pos; }
};

}  // namespace md
