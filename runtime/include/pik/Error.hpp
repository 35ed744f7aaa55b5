/// \file Error.hpp
/// \brief The exception the runtime throws for a user's mistake (bad input, bad parameters).
#pragma once

#include <stdexcept>
#include <string>

namespace pik {

/// Thrown with a message that names what is wrong and where (which particle, which
/// parameter). The runtime never aborts on user input.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error("pik: " + what) {}
};

}  // namespace pik
