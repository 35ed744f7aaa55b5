/// \file KernelResults.hpp
/// \brief The FORCE types of the SPH kernel library, shared by every SPH program, and
///        the projection of 3-vectors onto the D dimensions a tree of dimension D sees.
///
/// kernels/sph_density.pik fills DensityResult; kernels/sph_force_ssph.pik,
/// sph_force_disph.pik, sph_force_spsph.pik and sph_force_disph_eos.pik fill
/// HydroResult (spsph adds its pseudo-density rate in its own type); kernels/gravity.pik
/// fills GravityResult. The kernels accumulate in single precision.
#pragma once

#include <pik/Vec.hpp>

namespace pik::sph {

/// rho, drho/dh, the smoothed q = sum m u W (DISPH's energy density, or the caller's
/// volume-element quantity), sum m v_ij . grad W, the neighbour count, sum m v_ij x grad W.
struct DensityResult {
  float rho, drhodh, q, divv, nngb;
  Vec3<float> rotv;
  void clear() { rho = drhodh = q = divv = nngb = 0, rotv = {}; }
};

/// Hydrodynamic acceleration, du/dt and the largest signal velocity among the neighbours.
struct HydroResult {
  Vec3<float> acc;
  float dudt, vsig;
  void clear() { acc = {}, dudt = vsig = 0; }
};

/// Gravitational acceleration and potential.
struct GravityResult {
  Vec3<float> acc;
  float pot;
  void clear() { acc = {}, pot = 0; }
};

/// The first D components of a 3-vector: the position a D-dimensional tree sees (2D
/// runs keep z = 0).
template <int D, class T>
Vec<T, D> first_dims(const Vec3<T>& v) {
  if constexpr (D == 2) return {v.x, v.y};
  else return v;
}

/// Sets the first D components of a 3-vector (the rest are left as they are).
template <int D, class T>
void set_first_dims(Vec3<T>& v, const Vec<T, D>& p) {
  v.x = p.x, v.y = p.y;
  if constexpr (D == 3) v.z = p.z;
}

}  // namespace pik::sph
