// pikg-gen's stand-in vector templates for PIKG's and FDPS's vector types (same
// layout: components x, y (, z, w) of the element type), for pikg-reflect only. The
// operations are declared (not defined) so that inline member functions of users'
// structs (`acc = 0.0;`) parse; nothing here is ever compiled into a program.
#pragma once
namespace pikg_gen_compat {
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
}  // namespace pikg_gen_compat
