// The particle views and pair kernels shared by bench_tree and bench_mpi: float
// EPI/EPJ/FORCE views of a program's own double-precision full particle (any type
// with `pos` and `mass`), monopole super-particles, the generated kernels
// (kernels/gravity.pik through pik_add_kernel, see pik_bench_gravity_kernels() in
// bench/CMakeLists.txt) and the compiler-vectorised functor.
#pragma once

#include <pik/Vec.hpp>
#include <pik/tree/SuperParticle.hpp>

struct Result {
  pik::Vec3<float> acc;
  float pot;
  void clear() { acc = {}, pot = 0; }
};
struct EPI {
  pik::Vec3<float> pos;
  pik::Vec3<float> getPos() const { return pos; }
  template <class FP>
  void copyFromFP(const FP& b) { pos = pik::vec_cast<pik::Vec3<float>>(b.pos); }
};
struct EPJ {
  pik::Vec3<float> pos;
  float mass;
  pik::Vec3<float> getPos() const { return pos; }
  float getCharge() const { return mass; }
  template <class FP>
  void copyFromFP(const FP& b) { pos = pik::vec_cast<pik::Vec3<float>>(b.pos), mass = float(b.mass); }
};
using SPJ = pik::SPJMonopole<float>;

#include "GravityGenerated.hpp"
#include "GravityGeneratedSP.hpp"
#include "gravity_functor.hpp"
