/// \file ParallelSnapshot.hpp
/// \brief Parallel I/O hooks: every rank writes its own part of a snapshot, and any
///        number of ranks reads an output back, each getting an equal share.
///
/// ```cpp
/// pik::io::Snapshot mine = ...;                    // this rank's particles
/// pik::io::write_snapshot_parallel("out/snap_0010.pbin", mine, pik::io::Format::binary, comm);
/// ...                                              // later, at any rank count:
/// pik::io::Snapshot part = pik::io::read_snapshot_parallel("out/snap_0010.pbin", comm);
/// ```
/// Writing: the ranks agree on the global numbering (an exclusive scan of the
/// counts) and each writes `part_path(path, rank, ranks)` in any of the formats of
/// SnapshotIo.hpp, atomically; one rank writes `path` itself. Reading: rank 0 opens
/// part 0 (or the single file) and tells the others the part count and header;
/// part p is read by rank floor(p × ranks / parts), so each part is read once and
/// the parts a rank reads follow each other in global order; the particles are then
/// moved in one all-to-all so that rank r holds global indices
/// [N r / ranks, N (r + 1) / ranks) in their original order. Files of one output
/// can therefore be written at 4 ranks and read at 2 or 1 (or 8), and a later
/// domain decomposition (pik::exchange_particles) puts every particle where it
/// belongs.
///
/// Errors are collective: if writing or reading fails on any rank, every rank
/// throws an IoError carrying the message of the lowest failing rank, so no rank is
/// left waiting in a collective.
#pragma once

#include <sys/stat.h>

#include <cstdint>
#include <cstring>
#include <exception>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "pik/Vec.hpp"
#include "pik/io/IoError.hpp"
#include "pik/io/Snapshot.hpp"
#include "pik/io/SnapshotIo.hpp"

namespace pik::io {

namespace parallel_detail {

/// Runs `f` on every rank; if it throws anywhere, every rank throws.
template <class CommT, class F>
void collectively(const CommT& comm, const std::string& path, F&& f) {
  if (comm.size() == 1) {  // nobody to wait for: the error as it is, without "on rank 0"
    f();
    return;
  }
  std::string err;
  try {
    f();
  } catch (const std::exception& e) {
    err = e.what();
    if (err.empty()) err = "unknown error";
  }
  const auto failed = comm.max_loc(int(!err.empty()));
  if (failed.value == 0) return;
  std::vector<char> msg(err.begin(), err.end());
  comm.broadcast(msg, failed.rank);
  throw IoError(path, "on rank " + std::to_string(failed.rank) + ": " + std::string(msg.begin(), msg.end()));
}

/// Column names and components, one "name\tcomponents\n" line each.
inline std::string column_layout(const Snapshot& s) {
  std::string out;
  for (const Column& c : s.extra) out += c.name + "\t" + std::to_string(c.components) + "\n";
  return out;
}

/// Splits "a\tb\n" lines.
inline std::vector<std::pair<std::string, std::string>> split_lines(const std::string& text) {
  std::vector<std::pair<std::string, std::string>> out;
  for (std::size_t p = 0; p < text.size();) {
    const auto nl = text.find('\n', p), tab = text.find('\t', p);
    out.emplace_back(text.substr(p, tab - p), text.substr(tab + 1, nl - tab - 1));
    p = nl + 1;
  }
  return out;
}

template <class CommT>
std::string broadcast_text(const CommT& comm, const std::string& text, int root) {
  std::vector<char> v(text.begin(), text.end());
  comm.broadcast(v, root);
  return std::string(v.begin(), v.end());
}

/// Appends src's particles to dst (same columns, checked by the caller).
inline void append(Snapshot& dst, const Snapshot& src) {
  dst.id.insert(dst.id.end(), src.id.begin(), src.id.end());
  dst.mass.insert(dst.mass.end(), src.mass.begin(), src.mass.end());
  dst.pos.insert(dst.pos.end(), src.pos.begin(), src.pos.end());
  dst.vel.insert(dst.vel.end(), src.vel.begin(), src.vel.end());
  for (std::size_t c = 0; c < src.extra.size(); ++c)
    dst.extra[c].data.insert(dst.extra[c].data.end(), src.extra[c].data.begin(), src.extra[c].data.end());
}

/// Sends the slices of one per-particle array (`width` values a particle).
template <class CommT, class T>
std::vector<T> move_slices(const CommT& comm, const std::vector<T>& v, std::span<const std::size_t> counts,
                           std::size_t width) {
  std::vector<std::size_t> c(counts.begin(), counts.end());
  for (auto& x : c) x *= width;
  return comm.alltoallv(std::span<const T>(v), std::span<const std::size_t>(c));
}

}  // namespace parallel_detail

/// Writes this rank's particles `local` as its part of the output `path`; the part
/// numbers, global first index and total are set here (the header fields `time`,
/// `step`, `attr` and the extra columns are the caller's and must agree across
/// ranks). Collective; returns when every part is written.
template <class CommT>
void write_snapshot_parallel(const std::string& path, Snapshot local, Format format, const CommT& comm) {
  const int nranks = comm.size(), me = comm.rank();
  const auto counts = comm.allgather(std::uint64_t(local.size()));
  std::uint64_t first = 0, total = 0;
  for (int r = 0; r < nranks; ++r) {
    if (r < me) first += counts[std::size_t(r)];
    total += counts[std::size_t(r)];
  }
  const std::size_t layout = std::hash<std::string>{}(parallel_detail::column_layout(local));
  const bool agree = comm.min(local.time) == comm.max(local.time) && comm.min(local.step) == comm.max(local.step) &&
                     comm.min(layout) == comm.max(layout);
  parallel_detail::collectively(comm, path, [&] {
    if (!agree) throw IoError(path, "ranks disagree on the time, step or extra columns of the snapshot");
    local.first_index = first;
    local.n_total = total;
    local.part = std::uint32_t(me);
    local.n_parts = std::uint32_t(nranks);
    write_snapshot_part(path, local, format);
  });
}

/// Reads the output `path` (written by write_snapshot_parallel at any rank count,
/// by write_snapshot_part, or a single file) and returns this rank's equal share
/// in global order: part = rank, n_parts = ranks, first_index and n_total set.
/// Collective.
template <class CommT>
Snapshot read_snapshot_parallel(const std::string& path, const CommT& comm) {
  using namespace parallel_detail;
  const int nranks = comm.size(), me = comm.rank();
  // Rank 0 learns the part count and header from part 0 (or the single file).
  struct Header {
    double time;
    std::uint64_t step, n_total;
    std::uint32_t n_parts;
    bool single;
  } h{};
  Snapshot first;
  collectively(comm, path, [&] {
    if (me != 0) return;
    const std::string file = first_part_file(path);
    h.single = file == path;
    first = read_snapshot(file);
    if (h.single && first.n_parts != 1)
      throw IoError(file, "is part " + std::to_string(first.part) + " of " + std::to_string(first.n_parts) +
                              "; name the output without the part number");
    if (first.part != 0 || first.first_index != 0) throw IoError(file, "expected part 0 starting at particle 0");
    h = {first.time, first.step, first.total(), first.n_parts, h.single};
  });
  h = comm.broadcast(h, 0);
  const std::string attrs = broadcast_text(comm, me == 0 ? binary::encode_attributes(first.attr) : "", 0);
  const std::string layout = broadcast_text(comm, me == 0 ? column_layout(first) : "", 0);

  Snapshot mine;
  mine.time = h.time;
  mine.step = h.step;
  for (const auto& [k, v] : split_lines(attrs)) mine.attr.set(k, v);
  for (const auto& [name, comps] : split_lines(layout)) mine.column(name, std::stoi(comps));
  std::uint64_t my_first = 0;
  bool have_first = false;
  collectively(comm, path, [&] {
    for (std::uint32_t p = 0; p < h.n_parts; ++p) {
      if (int(std::uint64_t(p) * std::uint64_t(nranks) / h.n_parts) != me) continue;
      const std::string file = h.single ? path : part_path(path, p, h.n_parts);
      Snapshot s = (p == 0) ? std::move(first) : read_snapshot(file);
      if (s.part != p || s.n_parts != h.n_parts || s.total() != h.n_total || s.step != h.step ||
          std::memcmp(&s.time, &h.time, sizeof(double)) != 0)
        throw IoError(file, "header does not match part 0 (part, count, step or time)");
      if (column_layout(s) != layout) throw IoError(file, "has different extra columns than part 0");
      if (have_first && s.first_index != my_first + mine.size())
        throw IoError(file, "starts at particle " + std::to_string(s.first_index) + ", expected " +
                                std::to_string(my_first + mine.size()));
      if (!have_first) my_first = s.first_index, have_first = true;
      append(mine, s);
    }
  });
  // The parts must tile 0..n_total in rank order.
  const auto firsts = comm.allgather(have_first ? my_first : ~std::uint64_t(0));
  const auto sizes = comm.allgather(std::uint64_t(mine.size()));
  std::uint64_t next = 0;
  bool tiled = true;
  for (int r = 0; r < nranks; ++r) {
    if (sizes[std::size_t(r)] == 0) continue;
    tiled = tiled && firsts[std::size_t(r)] == next;
    next += sizes[std::size_t(r)];
  }
  collectively(comm, path, [&] {
    if (!tiled || next != h.n_total)
      throw IoError(path, "the parts hold " + std::to_string(next) + " particles, the header says " +
                              std::to_string(h.n_total) + (tiled ? "" : " (or they overlap / leave gaps)"));
  });

  // Equal shares: rank t gets [N t / P, N (t + 1) / P).
  const std::uint64_t n_total = h.n_total, a = have_first ? my_first : 0, b = a + mine.size();
  auto share = [&](int t) { return n_total * std::uint64_t(t) / std::uint64_t(nranks); };
  std::vector<std::size_t> counts(std::size_t(nranks), 0);
  for (int t = 0; t < nranks; ++t) {
    const std::uint64_t lo = std::max(a, share(t)), hi = std::min(b, share(t + 1));
    counts[std::size_t(t)] = hi > lo ? std::size_t(hi - lo) : 0;
  }
  Snapshot out;
  out.time = mine.time;
  out.step = mine.step;
  out.attr = mine.attr;
  out.id = move_slices(comm, mine.id, counts, 1);
  out.mass = move_slices(comm, mine.mass, counts, 1);
  out.pos = move_slices(comm, mine.pos, counts, 1);
  out.vel = move_slices(comm, mine.vel, counts, 1);
  for (const Column& c : mine.extra)
    out.extra.push_back({c.name, c.components, move_slices(comm, c.data, counts, std::size_t(c.components))});
  out.first_index = share(me);
  out.n_total = n_total;
  out.part = std::uint32_t(me);
  out.n_parts = std::uint32_t(nranks);
  collectively(comm, path, [&] { out.validate(path); });
  return out;
}

}  // namespace pik::io
