// One header that gathers the three particle types from three files.
#pragma once
#include "sim/epi.hpp"
#include "nbr/epj.hpp"
#include "out/force.hpp"
