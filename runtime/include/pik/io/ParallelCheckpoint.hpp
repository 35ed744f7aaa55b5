/// \file ParallelCheckpoint.hpp
/// \brief Checkpoints of a run spread over ranks: each rank writes its own part,
///        and a restart at the same rank count gives every rank back exactly its
///        own part (particles in order, per-rank attributes), so the run continues
///        bit for bit; at another rank count the particles come back in equal
///        shares (the run continues, the same physics, not the same bits).
///
/// ```cpp
/// pik::io::write_checkpoint_parallel("out/checkpoint.pbin", mine, comm);
/// auto [state, exact] = pik::io::read_checkpoint_parallel("out/checkpoint.pbin", comm);
/// if (exact) ... restore per-rank state (decomposition, cost) from state.attr ...
/// ```
/// On one rank the checkpoint is the single file `path`; on P ranks the files
/// part_path(path, r, P) (`checkpoint.3.pbin`), each written atomically. A crash
/// between two parts' renames leaves parts of different steps; reading refuses
/// them (the step and time of every part must agree). Errors are collective.
/// encode_exact()/decode_exact() store doubles in an attribute exactly (hex
/// floats), e.g. DomainInfo::state().
#pragma once

#include <sys/stat.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <span>
#include <iterator>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "pik/io/Checkpoint.hpp"
#include "pik/io/IoError.hpp"
#include "pik/io/ParallelSnapshot.hpp"
#include "pik/io/Snapshot.hpp"

namespace pik::io {

/// Doubles as text, exactly ("%a" hex floats separated by spaces; inf and nan too).
inline std::string encode_exact(std::span<const double> v) {
  std::string out;
  for (double x : v) fmt::format_to(std::back_inserter(out), "{}{:a}", out.empty() ? "" : " ", x);
  return out;
}

/// The inverse of encode_exact; `where` names the source in the error.
inline std::vector<double> decode_exact(const std::string& text, const std::string& where) {
  std::vector<double> out;
  const char* p = text.c_str();
  while (*p) {
    char* end = nullptr;
    out.push_back(std::strtod(p, &end));
    if (end == p || (*end != ' ' && *end != '\0')) throw IoError(where, "not a list of numbers: '" + text + "'");
    p = *end ? end + 1 : end;
  }
  return out;
}

/// Writes this rank's part of a checkpoint (pik binary, marked as a checkpoint,
/// atomically). `time`, `step` and the extra columns must agree across ranks; the
/// attributes may differ (per-rank state). Collective.
template <class CommT>
void write_checkpoint_parallel(const std::string& path, Snapshot mine, const CommT& comm) {
  mine.attr.set(checkpoint_kind_key, checkpoint_kind);
  write_snapshot_parallel(path, std::move(mine), Format::binary, comm);
}

/// A checkpoint read back: this rank's particles and whether they are exactly the
/// part this rank wrote (same rank count), attributes included.
struct ParallelCheckpoint {
  Snapshot state;
  bool exact = false;
};

/// Reads a checkpoint written by write_checkpoint_parallel (or write_checkpoint).
/// At the rank count that wrote it, rank r reads part r; otherwise every rank gets
/// an equal share in global order (read_snapshot_parallel) and the attributes of
/// part 0. Refuses a file that is not a checkpoint or lacks a required column or
/// attribute. Collective.
template <class CommT>
ParallelCheckpoint read_checkpoint_parallel(const std::string& path, const CommT& comm,
                                            const std::vector<std::string>& required_columns = {},
                                            const std::vector<std::string>& required_attributes = {}) {
  using parallel_detail::collectively;
  const int me = comm.rank(), nranks = comm.size();
  auto check = [&](const Snapshot& s, const std::string& file) {
    if (!s.attr.has(checkpoint_kind_key) || s.attr.get_string(checkpoint_kind_key) != checkpoint_kind)
      throw IoError(file, "is a snapshot, not a checkpoint (no 'pik.kind = checkpoint')");
    for (const auto& c : required_columns)
      if (!s.find(c)) throw IoError(file, "checkpoint lacks the column '" + c + "'");
    for (const auto& a : required_attributes)
      if (!s.attr.has(a)) throw IoError(file, "checkpoint lacks the attribute '" + a + "'");
  };
  // Rank 0 finds the part count from the single file or part 0.
  ParallelCheckpoint out;
  std::uint32_t n_parts = 0;
  collectively(comm, path, [&] {
    if (me != 0) return;
    const std::string file = first_part_file(path);
    const bool single = file == path;
    out.state = read_snapshot(file);
    check(out.state, file);
    if (single && out.state.n_parts != 1)
      throw IoError(file, "is part " + std::to_string(out.state.part) + " of " +
                              std::to_string(out.state.n_parts) + "; name the checkpoint without the part number");
    n_parts = out.state.n_parts;
  });
  n_parts = comm.broadcast(n_parts, 0);
  if (n_parts != std::uint32_t(nranks)) {
    out.state = read_snapshot_parallel(path, comm);
    collectively(comm, path, [&] { check(out.state, path); });
    return out;
  }
  collectively(comm, path, [&] {
    const std::string file = part_path(path, std::uint32_t(me), n_parts);
    if (me != 0) out.state = read_snapshot(file);
    if (out.state.part != std::uint32_t(me) || out.state.n_parts != n_parts)
      throw IoError(file, "is part " + std::to_string(out.state.part) + " of " +
                              std::to_string(out.state.n_parts) + ", expected part " + std::to_string(me) +
                              " of " + std::to_string(n_parts));
    check(out.state, file);
  });
  // Parts of one checkpoint hold one step (a crash between renames would mix them).
  const auto step = out.state.step;
  std::uint64_t time_bits;
  std::memcpy(&time_bits, &out.state.time, sizeof time_bits);
  const bool same = comm.min(step) == comm.max(step) && comm.min(time_bits) == comm.max(time_bits);
  const std::uint64_t n = comm.sum(std::uint64_t(out.state.size()));
  collectively(comm, path, [&] {
    if (!same)
      throw IoError(path, "the parts hold different steps (an interrupted write?); restart from an older checkpoint");
    if (n != out.state.total())
      throw IoError(path, "the parts hold " + std::to_string(n) + " particles, the header says " +
                              std::to_string(out.state.total()));
  });
  out.exact = true;
  return out;
}

}  // namespace pik::io
