/// \file Concepts.hpp
/// \brief What the runtime asks of user particle classes, as C++20 concepts.
///
/// The split follows FDPS: a *full particle* (FP) is what the user stores; an
/// *EPI* is the part of it an i-particle needs, an *EPJ* the part a j-particle
/// needs, and a *FORCE* the result written back. Each is the user's own type;
/// the runtime only calls the hooks below (FDPS's names, so FDPS particle classes
/// work unchanged). One class may play several roles.
///
/// The trees check these concepts with `static_assert`, so a missing hook gives one
/// line such as "pik: the EPJ type needs getCharge() (the mass of a j-particle)".
#pragma once

#include <concepts>
#include <type_traits>

#include "pik/Vec.hpp"

namespace pik {

/// `p.getPos()` returns a vector with x, y (and z) members.
template <class P>
concept HasPos = requires(const P& p) {
  { p.getPos() } -> VecLike;
};

/// `p.setPos(v)` moves the particle (needed to wrap into a periodic box and to hand
/// the kernel shifted periodic images).
template <class P>
concept HasSetPos = HasPos<P> && requires(P& p, std::remove_cvref_t<decltype(p.getPos())> v) {
  p.setPos(v);
};

/// `p.getCharge()` returns the mass (or charge) of a j-particle, a number.
template <class P>
concept HasCharge = requires(const P& p) {
  { p.getCharge() } -> std::convertible_to<double>;
};

/// `p.getRSearch()` returns the search radius of a particle, a number.
template <class P>
concept HasRSearch = requires(const P& p) {
  { p.getRSearch() } -> std::convertible_to<double>;
};

/// An EPI or EPJ made from a full particle: `copyFromFP(const FP&)`.
template <class E, class FP>
concept CopiesFromFP = std::default_initializable<E> && requires(E& e, const FP& fp) {
  e.copyFromFP(fp);
};

/// A result type: default-constructible and zeroed by `clear()` (kernels accumulate).
template <class F>
concept ForceResult = std::default_initializable<F> && requires(F& f) { f.clear(); };

/// A full particle that receives a result: `copyFromForce(const FORCE&)`.
template <class FP, class F>
concept TakesForce = requires(FP& fp, const F& f) { fp.copyFromForce(f); };

/// A full particle: has a position.
template <class FP>
concept FullParticle = HasPos<FP> && std::copy_constructible<FP>;

/// Position vector type of a particle type.
template <HasPos P>
using pos_type_of = std::remove_cvref_t<decltype(std::declval<const P&>().getPos())>;

/// Spatial dimension of a particle type (2 or 3).
template <HasPos P>
inline constexpr int dim_of = vec_dim<pos_type_of<P>>();

/// Kernel signature shared with FDPS and every generated kernel:
/// `k(const EPI*, int ni, const EPJ*, int nj, FORCE*)`, accumulating into FORCE.
template <class K, class EPI, class EPJ, class F>
concept PairKernel = requires(K& k, const EPI* i, const EPJ* j, F* f) { k(i, 0, j, 0, f); };

}  // namespace pik
