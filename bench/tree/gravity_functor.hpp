// A softened-gravity pair kernel written so that the compiler vectorises it: the
// i-particles of a group are copied into small structure-of-arrays buffers and the
// inner loop runs over i (independent lanes, no reduction), the same loop shape
// pikg-gen's SIMD backends emit. Same members and maths as kernels/gravity.pik.
#pragma once

#include <algorithm>
#include <cmath>

template <class EPI, class Result>
struct GravityFunctor {
  float eps2;

  static const char* isa_name() { return "C++ functor (compiler-vectorised)"; }

  template <class EPJ>
  void operator()(const EPI* epi, int ni, const EPJ* epj, int nj, Result* force) const {
    constexpr int B = 64;
    alignas(64) float xi[B], yi[B], zi[B], ax[B], ay[B], az[B], ph[B];
    for (int i0 = 0; i0 < ni; i0 += B) {
      const int n = std::min(B, ni - i0);
      const int npad = (n + 15) & ~15;
      for (int i = 0; i < npad; ++i) {
        const auto& p = epi[i0 + std::min(i, n - 1)];
        xi[i] = p.pos.x, yi[i] = p.pos.y, zi[i] = p.pos.z;
        ax[i] = ay[i] = az[i] = ph[i] = 0;
      }
      for (int j = 0; j < nj; ++j) {
        const float xj = epj[j].pos.x, yj = epj[j].pos.y, zj = epj[j].pos.z, mj = epj[j].mass;
        for (int i = 0; i < npad; ++i) {
          const float dx = xi[i] - xj, dy = yi[i] - yj, dz = zi[i] - zj;
          const float r2 = dx * dx + dy * dy + dz * dz + eps2;
          const float rinv = 1.0f / std::sqrt(r2);
          const float mr = mj * rinv, mr3 = mr * rinv * rinv;
          ax[i] -= mr3 * dx;
          ay[i] -= mr3 * dy;
          az[i] -= mr3 * dz;
          ph[i] -= mr;
        }
      }
      for (int i = 0; i < n; ++i) {
        Result& f = force[i0 + i];
        f.acc.x += ax[i], f.acc.y += ay[i], f.acc.z += az[i], f.pot += ph[i];
      }
    }
  }
};
