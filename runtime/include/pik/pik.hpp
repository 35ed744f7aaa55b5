/// \file pik.hpp
/// \brief Umbrella header: everything a pik simulation program needs.
#pragma once

#include "pik/version.hpp"
#include "pik/Vec.hpp"
#include "pik/Box.hpp"
#include "pik/Boundary.hpp"
#include "pik/Error.hpp"
#include "pik/Profiler.hpp"
#include "pik/particle/Concepts.hpp"
#include "pik/particle/ParticleSystem.hpp"
#include "pik/tree/MortonKey.hpp"
#include "pik/tree/Multipole.hpp"
#include "pik/tree/Octree.hpp"
#include "pik/tree/SuperParticle.hpp"
#include "pik/tree/TreeParams.hpp"
#include "pik/walk/InteractionList.hpp"
#include "pik/walk/ListMode.hpp"
#include "pik/walk/LongRangeTree.hpp"
#include "pik/walk/SearchMode.hpp"
#include "pik/walk/ShortRangeTree.hpp"
