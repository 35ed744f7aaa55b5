/// \file Checkpoint.hpp
/// \brief Checkpoints: the complete state of a run, so that a restarted run continues
///        bit for bit like one that was never stopped.
///
/// A checkpoint is a pik binary snapshot (exact doubles, checksummed, written
/// atomically) marked with the attribute `pik.kind = checkpoint`. What "complete"
/// means is the program's business, and it must store all of it: positions,
/// velocities, masses and ids in particle order (the order fixes the summation order
/// of forces), the time and step, every run parameter, any random-number state, and
/// for a kick-drift-kick leapfrog the accelerations of the last force step (the next
/// step opens with a half kick from them; recomputing them after a restart would
/// give the same bits only if the force computation were independent of everything
/// but positions). Helpers here encode doubles and random-generator states exactly.
#pragma once

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "pik/io/BinarySnapshot.hpp"
#include "pik/io/IoError.hpp"
#include "pik/io/Snapshot.hpp"

namespace pik::io {

inline constexpr const char* checkpoint_kind_key = "pik.kind";
inline constexpr const char* checkpoint_kind = "checkpoint";

/// Writes a checkpoint atomically (pik binary format, marked as a checkpoint).
inline void write_checkpoint(const std::string& path, Snapshot state) {
  state.attr.set(checkpoint_kind_key, checkpoint_kind);
  write_binary(path, state);
}

/// Reads a checkpoint; refuses a file that is not one, or that lacks one of the
/// `required_columns` or `required_attributes`.
inline Snapshot read_checkpoint(const std::string& path,
                                const std::vector<std::string>& required_columns = {},
                                const std::vector<std::string>& required_attributes = {}) {
  Snapshot s = read_binary(path);
  if (!s.attr.has(checkpoint_kind_key) || s.attr.get_string(checkpoint_kind_key) != checkpoint_kind)
    throw IoError(path, "is a snapshot, not a checkpoint (no 'pik.kind = checkpoint')");
  for (const auto& c : required_columns)
    if (!s.find(c)) throw IoError(path, "checkpoint lacks the column '" + c + "'");
  for (const auto& a : required_attributes)
    if (!s.attr.has(a)) throw IoError(path, "checkpoint lacks the attribute '" + a + "'");
  return s;
}

/// The state of a standard random engine as text (its operator<< form), for storing
/// as an attribute; restore with restore_engine().
template <class Engine>
std::string engine_state(const Engine& e) {
  std::ostringstream ss;
  ss << e;
  return ss.str();
}

template <class Engine>
void restore_engine(Engine& e, const std::string& state, const std::string& where) {
  std::istringstream ss(state);
  ss >> e;
  if (ss.fail()) throw IoError(where, "corrupt random-number generator state");
}

}  // namespace pik::io
