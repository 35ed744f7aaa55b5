/// \file ConvectionKernels.hpp
/// \brief The generated kernels of the convection program, one class per dimension and
///        smoothing function (pikg-gen --const dim=D --const shape=S; see CMakeLists.txt).
#pragma once

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
#include "ConvGrad2_0.hpp"
#include "ConvGrad2_1.hpp"
#include "ConvGrad2_2.hpp"
#include "ConvGrad3_0.hpp"
#include "ConvGrad3_1.hpp"
#include "ConvGrad3_2.hpp"

namespace convection {

template <int D, int S>
struct Kernels;
#define CONVECTION_KERNELS(D, S)           \
  template <>                              \
  struct Kernels<D, S> {                   \
    using Density = ConvDensity##D##_##S;  \
    using Viscous = ConvViscous##D##_##S;  \
    using Grad = ConvGrad##D##_##S;        \
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
