/// \file version.hpp
/// \brief The pik version, for programs and generated kernels that check it.
#pragma once

#define PIK_VERSION_MAJOR 0
#define PIK_VERSION_MINOR 1
#define PIK_VERSION_PATCH 0

namespace pik {
inline constexpr const char* version_string = "0.1.0";
}  // namespace pik
