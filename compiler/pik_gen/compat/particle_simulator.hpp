// pikg-gen's stand-in for FDPS's particle_simulator.hpp, used only when pikg-reflect
// reads a particle header that includes it and FDPS's src/ is not on the include path
// (PIKG never compiles the class file, so PIKG users' Makefiles give no -I for it):
// FDPS's scalar and vector names with their layouts. What else a header uses from
// FDPS is skipped with the declaration that uses it (pikg-gen's note says which).
#pragma once
#include <cassert>
#include <cmath>
#include <cstdio>
#include <iostream>
#include "pikg_gen_vectors.hpp"
namespace PS {
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
constexpr int DIMENSION = 3;
}  // namespace PS
