/// \file ListMode.hpp
/// \brief Whether a force call builds interaction lists, keeps them, or reuses them.
#pragma once

namespace pik {

/// FDPS's MAKE_LIST / MAKE_LIST_FOR_REUSE / REUSE_LIST.
enum class ListMode {
  rebuild,         ///< build the tree and lists, use them once
  make_for_reuse,  ///< build the tree and lists, and keep the lists
  reuse,           ///< keep the tree topology and the lists; reload particles, redo moments
};

}  // namespace pik
