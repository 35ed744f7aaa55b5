/// \file Vec.hpp
/// \brief Small fixed-size vectors (Vec2, Vec3, Vec4) with public x, y, z, w members.
///
/// Generated kernels read vector members as `.x`, `.y`, `.z` (`.w`), which is also
/// the layout of FDPS's `PS::F64vec`, so these types and FDPS's are interchangeable
/// in kernels. The types stay aggregates (`Vec3<double>{1, 2, 3}`), so they can sit
/// in user particle structs that are copied with memcpy and read by pikg-reflect;
/// arithmetic lives in free functions below. `Vec<T, D>` names the vector of
/// dimension D, which is how the runtime stays generic over dimension.
#pragma once

#include <cmath>
#include <cstddef>
#include <ostream>
#include <type_traits>

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

namespace detail {
template <class T, int D>
struct VecOfDim;
template <class T>
struct VecOfDim<T, 2> {
  using type = Vec2<T>;
};
template <class T>
struct VecOfDim<T, 3> {
  using type = Vec3<T>;
};
template <class T>
struct VecOfDim<T, 4> {
  using type = Vec4<T>;
};
template <class V>
struct IsPikVec : std::false_type {};
template <class T>
struct IsPikVec<Vec2<T>> : std::true_type {};
template <class T>
struct IsPikVec<Vec3<T>> : std::true_type {};
template <class T>
struct IsPikVec<Vec4<T>> : std::true_type {};
}  // namespace detail

/// The pik vector of dimension D (2, 3 or 4) and component type T.
template <class T, int D>
using Vec = typename detail::VecOfDim<T, D>::type;

/// True for Vec2, Vec3 and Vec4 of any component type.
template <class V>
concept PikVec = detail::IsPikVec<std::remove_cvref_t<V>>::value;

/// Any vector-like type with x/y(/z) members and indexing, such as FDPS's F64vec.
template <class V>
concept VecLike = requires(const V& v) {
  v.x;
  v.y;
};

/// Number of components of a vector-like type (2 without z, 3 with z, 4 with w).
template <class V>
constexpr int vec_dim() {
  if constexpr (requires(const V& v) { v.w; }) {
    return 4;
  } else if constexpr (requires(const V& v) { v.z; }) {
    return 3;
  } else {
    return 2;
  }
}

// ---- element-wise arithmetic -------------------------------------------------

#define PIK_VEC_BINARY_OP(op)                                           \
  template <PikVec V>                                                   \
  constexpr V operator op(const V& a, const V& b) {                     \
    V r{};                                                              \
    for (std::size_t i = 0; i < V::size; ++i) r[i] = a[i] op b[i];      \
    return r;                                                           \
  }                                                                     \
  template <PikVec V>                                                   \
  constexpr V& operator op##=(V & a, const V & b) {                     \
    for (std::size_t i = 0; i < V::size; ++i) a[i] = a[i] op b[i];      \
    return a;                                                           \
  }
PIK_VEC_BINARY_OP(+)
PIK_VEC_BINARY_OP(-)
#undef PIK_VEC_BINARY_OP

template <PikVec V>
constexpr V operator-(const V& a) {
  V r{};
  for (std::size_t i = 0; i < V::size; ++i) r[i] = -a[i];
  return r;
}

template <PikVec V>
constexpr V operator*(const V& a, typename V::value_type s) {
  V r{};
  for (std::size_t i = 0; i < V::size; ++i) r[i] = a[i] * s;
  return r;
}
template <PikVec V>
constexpr V operator*(typename V::value_type s, const V& a) {
  return a * s;
}
template <PikVec V>
constexpr V operator/(const V& a, typename V::value_type s) {
  V r{};
  for (std::size_t i = 0; i < V::size; ++i) r[i] = a[i] / s;
  return r;
}
template <PikVec V>
constexpr V& operator*=(V& a, typename V::value_type s) {
  for (std::size_t i = 0; i < V::size; ++i) a[i] *= s;
  return a;
}
template <PikVec V>
constexpr V& operator/=(V& a, typename V::value_type s) {
  for (std::size_t i = 0; i < V::size; ++i) a[i] /= s;
  return a;
}

template <PikVec V>
constexpr bool operator==(const V& a, const V& b) {
  for (std::size_t i = 0; i < V::size; ++i)
    if (!(a[i] == b[i])) return false;
  return true;
}

// ---- geometry ------------------------------------------------------------------

/// Dot product.
template <PikVec V>
constexpr typename V::value_type dot(const V& a, const V& b) {
  typename V::value_type s{};
  for (std::size_t i = 0; i < V::size; ++i) s += a[i] * b[i];
  return s;
}

/// Cross product of 3-vectors.
template <class T>
constexpr Vec3<T> cross(const Vec3<T>& a, const Vec3<T>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
/// z component of the cross product of 2-vectors.
template <class T>
constexpr T cross(const Vec2<T>& a, const Vec2<T>& b) {
  return a.x * b.y - a.y * b.x;
}

/// Squared Euclidean norm.
template <PikVec V>
constexpr typename V::value_type norm2(const V& a) {
  return dot(a, a);
}
/// Euclidean norm.
template <PikVec V>
typename V::value_type norm(const V& a) {
  return std::sqrt(norm2(a));
}

/// Component-wise minimum and maximum.
template <PikVec V>
constexpr V min(const V& a, const V& b) {
  V r{};
  for (std::size_t i = 0; i < V::size; ++i) r[i] = b[i] < a[i] ? b[i] : a[i];
  return r;
}
template <PikVec V>
constexpr V max(const V& a, const V& b) {
  V r{};
  for (std::size_t i = 0; i < V::size; ++i) r[i] = a[i] < b[i] ? b[i] : a[i];
  return r;
}

/// True when every component is finite (neither NaN nor infinite).
template <PikVec V>
bool isfinite(const V& a) {
  for (std::size_t i = 0; i < V::size; ++i)
    if (!std::isfinite(a[i])) return false;
  return true;
}

/// Converts between component types (and from FDPS-like vectors of the same dimension).
template <class To, class From>
constexpr To vec_cast(const From& v) {
  using T = typename To::value_type;
  if constexpr (To::size == 2) {
    return To{T(v.x), T(v.y)};
  } else if constexpr (To::size == 3) {
    return To{T(v.x), T(v.y), T(v.z)};
  } else {
    return To{T(v.x), T(v.y), T(v.z), T(v.w)};
  }
}

template <PikVec V>
std::ostream& operator<<(std::ostream& os, const V& a) {
  os << '(';
  for (std::size_t i = 0; i < V::size; ++i) os << (i ? ", " : "") << a[i];
  return os << ')';
}

}  // namespace pik
