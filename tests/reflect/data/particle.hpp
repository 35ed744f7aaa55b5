// A user's particle header as pikg-reflect meets it in the wild: includes found
// through -I, a precision macro from -D, namespaces, a template and an alias.
#pragma once
#include <cstdint>

#include "pik/Vec.hpp"
#include "units/real.hpp"

namespace galaxy {
template <class T>
struct Particle {
  pik::Vec3<T> pos;
  T mass;
  std::int64_t id;
};
using Body = Particle<real_t>;
}  // namespace galaxy
