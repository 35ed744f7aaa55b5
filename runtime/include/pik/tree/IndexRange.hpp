/// \file IndexRange.hpp
/// \brief A half-open range [begin, end) of positions in one of the tree's sorted arrays.
#pragma once

#include <cstdint>

namespace pik {

struct IndexRange {
  std::uint32_t begin = 0, end = 0;
  std::uint32_t size() const { return end - begin; }
};

}  // namespace pik
