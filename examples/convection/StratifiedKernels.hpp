/// \file StratifiedKernels.hpp
/// \brief The generated kernels of the stratified layer, one class per dimension and
///        smoothing function (Wendland C2 and C4; pikg-gen --const dim=D --const shape=S,
///        see CMakeLists.txt): the volume element (kernels/sph_density.pik) and the RSST
///        pair sums (kernels/sph_rsst.pik).
#pragma once

#include "StratifiedTypes.hpp"

#include "StratDensity2_1.hpp"
#include "StratDensity2_2.hpp"
#include "StratDensity3_1.hpp"
#include "StratDensity3_2.hpp"
#include "StratRsst2_1.hpp"
#include "StratRsst2_2.hpp"
#include "StratRsst3_1.hpp"
#include "StratRsst3_2.hpp"

namespace stratified {

template <int D, int S>
struct Kernels;
#define STRATIFIED_KERNELS(D, S)           \
  template <>                              \
  struct Kernels<D, S> {                   \
    using Density = StratDensity##D##_##S; \
    using Rsst = StratRsst##D##_##S;       \
  };
STRATIFIED_KERNELS(2, 1)
STRATIFIED_KERNELS(2, 2)
STRATIFIED_KERNELS(3, 1)
STRATIFIED_KERNELS(3, 2)
#undef STRATIFIED_KERNELS

}  // namespace stratified
