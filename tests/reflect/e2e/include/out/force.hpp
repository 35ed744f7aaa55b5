// The result: float accumulators, nested namespaces.
#pragma once
#include "pik/Vec.hpp"

namespace out::grav {
struct Result {
  pik::Vec3<float> acc;
  float pot;
};
}  // namespace out::grav
