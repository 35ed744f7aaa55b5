/// \file pik.hpp
/// \brief Umbrella header: everything a pik simulation program needs.
#pragma once

#include "pik/version.hpp"
#include "pik/Vec.hpp"
