/// \file ConvectionKernels.hpp
/// \brief The generated kernels of the convection program, one class per dimension and
///        smoothing function (pikg-gen --const dim=D --const shape=S; see CMakeLists.txt).
#pragma once

#include <algorithm>
#include <cmath>

#include <pik/sph/Smoothing.hpp>

#include "ConvectionTypes.hpp"

#include "ConvDensity2_0.hpp"
#include "ConvDensity2_1.hpp"
#include "ConvDensity2_2.hpp"
#include "ConvDensity3_0.hpp"
#include "ConvDensity3_1.hpp"
#include "ConvDensity3_2.hpp"
#include "ConvViscous2_0.hpp"
#include "ConvViscous2_1.hpp"
#include "ConvViscous2_2.hpp"
#include "ConvViscous3_0.hpp"
#include "ConvViscous3_1.hpp"
#include "ConvViscous3_2.hpp"

namespace convection {

/// Pass 2 of --stress symmetric, a symmetric pair kernel in C++ (the interface of the
/// generated kernels): the force of the deviatoric stress of pass 1,
///
///   F_i = sum_j V_i V_j (tau_i + tau_j) . grad W_ij,   acc_i = ainv_i F_i
///
/// with grad W_ij the mean of the two smoothing lengths' gradients (grad_i W_ij(h) =
/// sigma / h^(D+2) g(r/h) (x_i - x_j), g = f'(q)/q of kernels/sph_viscous.pik), so
/// F_ij = -F_ji: the pair forces conserve linear momentum. It is the SPH form of div tau
/// (cf. the pressure term, tau = -p I); no viscous heating (the Boussinesq equations of
/// Blankenbach et al. 1989 have none).
template <int D, int S>
class StressKernel {
 public:
  static float g(float q) {
    const float a = std::max(1.0f - q, 0.0f);
    if constexpr (S == 0) return q < 0.5f ? 18.0f * q - 12.0f : -6.0f * a * a / q;
    else if constexpr (S == 1) return -20.0f * a * a * a;
    else return -56.0f / 3.0f * a * a * a * a * a * (1.0f + 5.0f * q);
  }
  static float norm(float h) {  // sigma / h^(D+2)
    static const float sig = float(pik::sph::kernel_sigma(D, pik::sph::Shape(S)));
    float hi = 1.0f / h, p = hi * hi * hi * hi;
    if constexpr (D == 3) p *= hi;
    return sig * p;
  }
  void operator()(const SEP<D>* epi, int ni, const SEP<D>* epj, int nj, StressResult* force) const {
    for (int i = 0; i < ni; ++i) {
      const SEP<D>& a = epi[i];
      const float hinvi = 1.0f / a.h, ni_ = norm(a.h);
      float fx = 0, fy = 0, fz = 0;
      for (int j = 0; j < nj; ++j) {
        const SEP<D>& b = epj[j];
        const float rx = a.pos.x - b.pos.x, ry = a.pos.y - b.pos.y, rz = a.pos.z - b.pos.z;
        const float r2 = rx * rx + ry * ry + rz * rz;
        const float hmax = std::max(a.h, b.h);
        if (r2 >= hmax * hmax || r2 == 0) continue;
        const float r = std::sqrt(r2);
        const float gi = ni_ * g(std::min(r * hinvi, 1.0f)), gj = norm(b.h) * g(std::min(r / b.h, 1.0f));
        const float w = a.vol * b.vol * 0.5f * (gi + gj);  // V_i V_j grad W_ij = w r_ij
        const float t0 = a.tau[0] + b.tau[0], t1 = a.tau[1] + b.tau[1], t2 = a.tau[2] + b.tau[2];
        const float t3 = a.tau[3] + b.tau[3], t4 = a.tau[4] + b.tau[4], t5 = a.tau[5] + b.tau[5];
        fx += w * (t0 * rx + t3 * ry + t4 * rz);
        fy += w * (t3 * rx + t1 * ry + t5 * rz);
        fz += w * (t4 * rx + t5 * ry + t2 * rz);
      }
      force[i].acc.x += a.ainv * fx, force[i].acc.y += a.ainv * fy, force[i].acc.z += a.ainv * fz;
    }
  }
};

template <int D, int S>
struct Kernels;
#define CONVECTION_KERNELS(D, S)           \
  template <>                              \
  struct Kernels<D, S> {                   \
    using Density = ConvDensity##D##_##S;  \
    using Viscous = ConvViscous##D##_##S;  \
    using Stress = StressKernel<D, S>;     \
  };
CONVECTION_KERNELS(2, 0)
CONVECTION_KERNELS(2, 1)
CONVECTION_KERNELS(2, 2)
CONVECTION_KERNELS(3, 0)
CONVECTION_KERNELS(3, 1)
CONVECTION_KERNELS(3, 2)
#undef CONVECTION_KERNELS

}  // namespace convection
