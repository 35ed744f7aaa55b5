// The i-particle: a template with its position in a base class and its own
// members in the derived one (not standard-layout), in namespace sim.
#pragma once
#include "pik/Vec.hpp"

namespace sim {
struct Located {
  pik::Vec3<double> pos;
};
template <class Real>
struct FullParticle : Located {
#ifdef PIK_E2E_SHIFT_EPI
  double inserted_later;  // a struct change after generation: the kernel must not compile
#endif
  Real eps_i;
  long long id;
};
using EPI = FullParticle<double>;
}  // namespace sim
