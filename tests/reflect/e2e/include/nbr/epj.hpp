// The j-particle: FDPS-style vector type (user copy constructor) and a typedef.
#pragma once

namespace nbr {
namespace PS {
template <class T>
class Vector3 {
 public:
  T x, y, z;
  Vector3() : x(0), y(0), z(0) {}
  Vector3(const Vector3& s) : x(s.x), y(s.y), z(s.z) {}
  Vector3& operator=(const Vector3& s) { x = s.x; y = s.y; z = s.z; return *this; }
};
typedef Vector3<double> F64vec;
typedef double F64;
}  // namespace PS

struct Source {
  PS::F64 mass;
  PS::F64vec pos;
};
}  // namespace nbr
