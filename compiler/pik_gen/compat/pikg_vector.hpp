// pikg-gen's stand-in for PIKG's C++ vector header, used only when pikg-reflect reads
// a particle header that includes <pikg_vector.hpp> and PIKG's inc/ is not on the
// include path: PIKG's scalar names and vectors of the same layout (components
// x, y (, z, w) of the element type).
#pragma once
namespace PIKG {
typedef double F64;
typedef float F32;
typedef long long S64;
typedef int S32;
typedef unsigned long long U64;
typedef unsigned int U32;
template <class T> struct Vector2 { T x, y; };
template <class T> struct Vector3 { T x, y, z; };
template <class T> struct Vector4 { T x, y, z, w; };
typedef Vector3<F64> F64vec;
typedef Vector3<F32> F32vec;
typedef Vector2<F64> F64vec2;
typedef Vector2<F32> F32vec2;
typedef Vector3<F64> F64vec3;
typedef Vector3<F32> F32vec3;
typedef Vector4<F64> F64vec4;
typedef Vector4<F32> F32vec4;
}  // namespace PIKG
