/// \file Parallel.hpp
/// \brief What the shared SPH layer does across MPI ranks: the global time step (every
///        criterion's minimum over ranks), global sums and maxima for diagnostics, and one
///        snapshot file gathered on rank 0 in particle-id order.
///
/// A model opts in by defining `const pik::Comm& comm() const` (any pik::BasicComm);
/// Driver.hpp then reduces the step limits, writes the log, progress line and reports on
/// rank 0 only, gathers snapshots and checkpoints into one file (ordered by id, the same
/// layout a single process writes) and restarts from such a file on any number of ranks
/// (pik::io::read_checkpoint_parallel hands each rank an equal share in file order). A
/// model without comm() runs exactly as before. The runtime (pik::Comm) knows no physics;
/// the reductions here are plain sums, minima and maxima over doubles.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <span>
#include <utility>
#include <vector>

#include <pik/comm/Comm.hpp>
#include <pik/io/Snapshot.hpp>
#include <pik/sph/TimeStep.hpp>

namespace pik::sph {

/// Does the model run on ranks (it defines comm())?
template <class Model>
concept ParallelModel = requires(const Model& m) {
  m.comm().rank();
  m.comm().size();
};

/// Every criterion's minimum over ranks (every rank must add the same criteria in the
/// same order, as a model's limits() does). Exact: a minimum does not round. Collective.
template <class CommT>
StepLimits global_limits(const StepLimits& local, const CommT& comm) {
  if (comm.size() == 1) return local;
  std::vector<double> v;
  for (const auto& [n, dt] : local.all()) v.push_back(dt);
  comm.reduce_inplace(std::span<double>(v), pik::comm::ReduceOp::min);
  StepLimits out;
  for (std::size_t k = 0; k < v.size(); ++k) out.add(local.all()[k].first, v[k]);
  return out;
}

/// Sums (in place) over ranks; identity on one rank. Collective.
template <class CommT>
void global_sum(std::span<double> v, const CommT& comm) {
  if (comm.size() > 1) comm.reduce_inplace(v, pik::comm::ReduceOp::sum);
}
/// Maxima (in place) over ranks. Collective.
template <class CommT>
void global_max(std::span<double> v, const CommT& comm) {
  if (comm.size() > 1) comm.reduce_inplace(v, pik::comm::ReduceOp::max);
}
/// Minima (in place) over ranks. Collective.
template <class CommT>
void global_min(std::span<double> v, const CommT& comm) {
  if (comm.size() > 1) comm.reduce_inplace(v, pik::comm::ReduceOp::min);
}

/// The snapshot of every rank's particles on `root`, ordered by id (the other ranks get
/// an empty snapshot with the same header). Columns and attributes are rank 0's (extra
/// columns must agree; attributes that differ per rank are the caller's to reduce
/// before). One process: `local` unchanged. Collective.
template <class CommT>
io::Snapshot gather_snapshot(io::Snapshot local, const CommT& comm, int root = 0) {
  if (comm.size() == 1) return local;
  const bool me_root = comm.rank() == root;
  io::Snapshot all;
  all.time = local.time, all.step = local.step, all.attr = local.attr;
  auto ids = comm.gatherv(std::span<const std::uint64_t>(local.id), root);
  auto mass = comm.gatherv(std::span<const double>(local.mass), root);
  auto pos = comm.gatherv(std::span<const Vec3<double>>(local.pos), root);
  auto vel = comm.gatherv(std::span<const Vec3<double>>(local.vel), root);
  std::vector<std::vector<double>> cols;
  for (const auto& c : local.extra) cols.push_back(comm.gatherv(std::span<const double>(c.data), root));
  if (!me_root) {
    for (const auto& c : local.extra) all.column(c.name, c.components);
    return all;
  }
  const std::size_t n = ids.size();
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t(0));
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return ids[a] < ids[b]; });
  all.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = order[k];
    all.id[k] = ids[i], all.mass[k] = mass[i], all.pos[k] = pos[i], all.vel[k] = vel[i];
  }
  for (std::size_t c = 0; c < local.extra.size(); ++c) {
    const auto& src = local.extra[c];
    auto& dst = all.column(src.name, src.components);
    const std::size_t w = std::size_t(src.components);
    for (std::size_t k = 0; k < n; ++k)
      for (std::size_t j = 0; j < w; ++j) dst.data[w * k + j] = cols[c][w * order[k] + j];
  }
  return all;
}

/// The equal share [N r / P, N (r + 1) / P) of n items that rank r of P holds when a run
/// starts (and that read_checkpoint_parallel hands it back from a single file).
inline std::pair<std::size_t, std::size_t> equal_share(std::size_t n, int rank, int ranks) {
  const auto a = std::uint64_t(n) * std::uint64_t(rank) / std::uint64_t(ranks);
  const auto b = std::uint64_t(n) * std::uint64_t(rank + 1) / std::uint64_t(ranks);
  return {std::size_t(a), std::size_t(b)};
}

}  // namespace pik::sph
