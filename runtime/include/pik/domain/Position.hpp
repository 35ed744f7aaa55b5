/// \file Position.hpp
/// \brief How the domain layer reads and writes a user particle's position.
///
/// A particle type needs only its position: either FDPS-style `getPos()` (and
/// `setPos(v)` where positions must be wrapped into a periodic box) or a public
/// `pos` member. Coordinates are read as `v[d]` where the vector has it, else as
/// `.x .y .z`, so pik::Vec3 and FDPS's PS::F64vec both work.
#pragma once

#include <concepts>
#include <utility>

namespace pik {

/// A particle whose position pik can read.
template <class P>
concept HasPosition = requires(const P& p) { p.getPos(); } || requires(const P& p) { p.pos; };

/// A particle whose position pik can also overwrite (periodic wrapping).
template <class P>
concept HasWritablePosition =
    HasPosition<P> &&
    (requires(P& p) { p.setPos(p.getPos()); } || requires(P& p) { p.pos = p.pos; });

namespace domain_detail {

template <HasPosition P>
auto position(const P& p) {
  if constexpr (requires { p.getPos(); }) return p.getPos();
  else return p.pos;
}

template <HasWritablePosition P, class V>
void set_position(P& p, const V& v) {
  if constexpr (requires { p.setPos(v); }) p.setPos(v);
  else p.pos = v;
}

template <class V>
auto coord(const V& v, int d) {
  if constexpr (requires { v[d]; }) {
    return v[d];
  } else if constexpr (requires { v.z; }) {
    return d == 0 ? v.x : (d == 1 ? v.y : v.z);
  } else {
    return d == 0 ? v.x : v.y;
  }
}

template <class V, class T>
void set_coord(V& v, int d, T value) {
  using E = std::remove_cvref_t<decltype(coord(v, 0))>;
  if constexpr (requires { v[d] = E{}; }) {
    v[d] = static_cast<E>(value);
  } else if constexpr (requires { v.z; }) {
    (d == 0 ? v.x : (d == 1 ? v.y : v.z)) = static_cast<E>(value);
  } else {
    (d == 0 ? v.x : v.y) = static_cast<E>(value);
  }
}

}  // namespace domain_detail
}  // namespace pik
