// pikg-gen's stand-in for PIKG's C++ vector header, used only when pikg-reflect reads
// a particle header that includes <pikg_vector.hpp> and PIKG's inc/ is not on the
// include path: PIKG's scalar names and vectors of the same layout (components
// x, y (, z, w) of the element type). The operations are declared (not defined) so
// that inline member functions of the user's structs (`acc = 0.0;`) parse; nothing
// here is ever compiled into a program.
#pragma once
// the standard headers the real one includes, which users' files rely on
#include <cassert>
#include <iomanip>
#include <iostream>
namespace PIKG {
typedef double F64;
typedef float F32;
typedef long long S64;
typedef int S32;
typedef unsigned long long U64;
typedef unsigned int U32;
template <class T> struct Vector2 {
  T x, y;
  Vector2() = default;
  Vector2(T s);
  Vector2(T x_, T y_);
  template <class U> Vector2(const Vector2<U>& v);
  Vector2& operator=(T s);
  T& operator[](int i);
  const T& operator[](int i) const;
  Vector2 operator-() const;
  Vector2 operator+(const Vector2& v) const;
  Vector2 operator-(const Vector2& v) const;
  T operator*(const Vector2& v) const;
  Vector2 operator*(T s) const;
  Vector2 operator/(T s) const;
  Vector2& operator+=(const Vector2& v);
  Vector2& operator-=(const Vector2& v);
  Vector2& operator*=(T s);
  Vector2& operator/=(T s);
  friend Vector2 operator*(T s, const Vector2& v) { return v * s; }
};
template <class T> struct Vector3 {
  T x, y, z;
  Vector3() = default;
  Vector3(T s);
  Vector3(T x_, T y_, T z_);
  template <class U> Vector3(const Vector3<U>& v);
  Vector3& operator=(T s);
  T& operator[](int i);
  const T& operator[](int i) const;
  Vector3 operator-() const;
  Vector3 operator+(const Vector3& v) const;
  Vector3 operator-(const Vector3& v) const;
  T operator*(const Vector3& v) const;
  Vector3 operator*(T s) const;
  Vector3 operator/(T s) const;
  Vector3& operator+=(const Vector3& v);
  Vector3& operator-=(const Vector3& v);
  Vector3& operator*=(T s);
  Vector3& operator/=(T s);
  friend Vector3 operator*(T s, const Vector3& v) { return v * s; }
};
template <class T> struct Vector4 {
  T x, y, z, w;
  Vector4() = default;
  Vector4(T s);
  Vector4(T x_, T y_, T z_, T w_);
  template <class U> Vector4(const Vector4<U>& v);
  Vector4& operator=(T s);
  T& operator[](int i);
  const T& operator[](int i) const;
  Vector4 operator-() const;
  Vector4 operator+(const Vector4& v) const;
  Vector4 operator-(const Vector4& v) const;
  T operator*(const Vector4& v) const;
  Vector4 operator*(T s) const;
  Vector4 operator/(T s) const;
  Vector4& operator+=(const Vector4& v);
  Vector4& operator-=(const Vector4& v);
  Vector4& operator*=(T s);
  Vector4& operator/=(T s);
  friend Vector4 operator*(T s, const Vector4& v) { return v * s; }
};
typedef Vector3<F64> F64vec;
typedef Vector3<F32> F32vec;
typedef Vector2<F64> F64vec2;
typedef Vector2<F32> F32vec2;
typedef Vector3<F64> F64vec3;
typedef Vector3<F32> F32vec3;
typedef Vector4<F64> F64vec4;
typedef Vector4<F32> F32vec4;
}  // namespace PIKG
