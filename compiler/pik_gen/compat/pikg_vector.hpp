// pikg-gen's stand-in for PIKG's C++ vector header, used only when pikg-reflect reads
// a particle header that includes <pikg_vector.hpp> and PIKG's inc/ is not on the
// include path: PIKG's scalar names and vectors of the same layout.
#pragma once
// the standard headers the real one includes, which users' files rely on
#include <cassert>
#include <iomanip>
#include <iostream>
#include "pikg_gen_vectors.hpp"
namespace PIKG {
typedef double F64;
typedef float F32;
typedef long long S64;
typedef int S32;
typedef unsigned long long U64;
typedef unsigned int U32;
typedef pikg_gen_compat::Vector3<F64> F64vec;
typedef pikg_gen_compat::Vector3<F32> F32vec;
typedef pikg_gen_compat::Vector2<F64> F64vec2;
typedef pikg_gen_compat::Vector2<F32> F32vec2;
typedef pikg_gen_compat::Vector3<F64> F64vec3;
typedef pikg_gen_compat::Vector3<F32> F32vec3;
typedef pikg_gen_compat::Vector4<F64> F64vec4;
typedef pikg_gen_compat::Vector4<F32> F32vec4;
}  // namespace PIKG
