/// \file Vec.hpp
/// \brief Small fixed-size vectors (Vec2, Vec3, Vec4) with public x, y, z, w members.
///
/// Generated kernels read vector members as `.x`, `.y`, `.z` (`.w`), which is also
/// the layout of FDPS's `PS::F64vec`, so these types and FDPS's are interchangeable
/// in kernels.
#pragma once

#include <cmath>
#include <cstddef>
#include <ostream>

namespace pik {

template <class T>
struct Vec2 {
  using value_type = T;
  static constexpr std::size_t size = 2;
  T x{}, y{};

  constexpr T& operator[](std::size_t i) { return i == 0 ? x : y; }
  constexpr const T& operator[](std::size_t i) const { return i == 0 ? x : y; }
};

template <class T>
struct Vec3 {
  using value_type = T;
  static constexpr std::size_t size = 3;
  T x{}, y{}, z{};

  constexpr T& operator[](std::size_t i) { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr const T& operator[](std::size_t i) const { return i == 0 ? x : (i == 1 ? y : z); }
};

template <class T>
struct Vec4 {
  using value_type = T;
  static constexpr std::size_t size = 4;
  T x{}, y{}, z{}, w{};

  constexpr T& operator[](std::size_t i) { return i == 0 ? x : (i == 1 ? y : (i == 2 ? z : w)); }
  constexpr const T& operator[](std::size_t i) const {
    return i == 0 ? x : (i == 1 ? y : (i == 2 ? z : w));
  }
};

}  // namespace pik
