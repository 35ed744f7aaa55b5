/// \file Comm.hpp
/// \brief pik::Comm: ranks, reductions, broadcasts, gathers and all-to-all exchanges.
///
/// BasicComm is a typed front end over a small byte-level backend. pik::Comm is
/// BasicComm over MPI when the runtime is built with MPI (PIK_HAVE_MPI) and over the
/// one-rank SerialBackend otherwise, so simulation code is the same in both builds.
/// All data moved must be trivially copyable: it travels as raw bytes, which is
/// valid between ranks of one program on one kind of machine.
///
/// Every collective must be called by all ranks of the communicator in the same
/// order, from one thread (MPI_THREAD_FUNNELED).
#pragma once

#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <numeric>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include <fmt/core.h>

#include "pik/comm/detail/Scalar.hpp"
#include "pik/comm/detail/SerialBackend.hpp"
#if defined(PIK_HAVE_MPI) && PIK_HAVE_MPI
#include "pik/comm/detail/MpiBackend.hpp"
#endif

namespace pik {

/// Types that may be sent between ranks as raw bytes.
template <class T>
concept Transferable = std::is_trivially_copyable_v<T>;

/// Small fixed-size vectors with `value_type` and `size` (pik::Vec3 and friends);
/// reduced component-wise.
template <class V>
concept ReducibleVector = requires {
  typename V::value_type;
  { V::size } -> std::convertible_to<std::size_t>;
} && comm::Reducible<typename V::value_type> &&
    sizeof(V) == sizeof(typename V::value_type) * V::size && std::is_trivially_copyable_v<V>;

/// A reduced value and the rank that holds it (the lowest such rank on ties).
template <class T>
struct Located {
  T value;
  int rank;
};

/// Data volume this rank has handed to collectives for other ranks, counted by
/// what the operation means (an allgather of n bytes sends n to each other rank),
/// not by the wire protocol MPI chooses.
struct CommStats {
  std::size_t bytes_sent = 0;
  std::size_t collectives = 0;
};

/// A communicator: a group of ranks and the collectives among them.
template <class Backend>
class BasicComm {
 public:
  /// All ranks of the program. The backend must be initialized (pik::Environment).
  static BasicComm world() {
    if (!Backend::initialized()) {
      fmt::print(stderr,
                 "pik: error: the communication layer is not initialized; create a "
                 "pik::Environment at the start of main()\n");
      std::exit(1);
    }
    return BasicComm(Backend::world());
  }

  int rank() const { return backend_.rank(); }
  int size() const { return backend_.size(); }
  bool is_root() const { return rank() == 0; }
  static constexpr const char* backend_name() { return Backend::name(); }
  void barrier() const { backend_.barrier(); }
  /// Wall-clock seconds (MPI_Wtime under MPI).
  static double wtime() { return Backend::wtime(); }
  /// The backend, for libraries that need its native handle (MpiBackend::native()).
  const Backend& backend() const { return backend_; }

  // ---- reductions --------------------------------------------------------------
  /// Element-wise reduction in place over all ranks.
  template <comm::Reducible T>
  void reduce_inplace(std::span<T> data, comm::ReduceOp op) const {
    count(data.size_bytes());
    backend_.allreduce(data.data(), data.size(), comm::scalar_kind<T>(), op);
  }
  template <comm::Reducible T>
  T sum(T v) const { return reduce_one(v, comm::ReduceOp::sum); }
  template <comm::Reducible T>
  T min(T v) const { return reduce_one(v, comm::ReduceOp::min); }
  template <comm::Reducible T>
  T max(T v) const { return reduce_one(v, comm::ReduceOp::max); }
  /// Component-wise reductions of small vectors (Vec3 momentum, bounding corners).
  template <ReducibleVector V>
  V sum(V v) const { return reduce_vec(v, comm::ReduceOp::sum); }
  template <ReducibleVector V>
  V min(V v) const { return reduce_vec(v, comm::ReduceOp::min); }
  template <ReducibleVector V>
  V max(V v) const { return reduce_vec(v, comm::ReduceOp::max); }

  /// Minimum over ranks and the lowest rank holding it. Exact for every type
  /// (no conversion to double as MPI_MINLOC pairs would need). NaN is not ordered:
  /// a NaN anywhere gives an unspecified value.
  template <comm::Reducible T>
  Located<T> min_loc(T v) const { return locate(v, min(v)); }
  template <comm::Reducible T>
  Located<T> max_loc(T v) const { return locate(v, max(v)); }

  // ---- broadcast -----------------------------------------------------------------
  template <Transferable T>
  void broadcast(std::span<T> data, int root = 0) const {
    check_root(root, "broadcast");
    if (rank() == root) count(data.size_bytes() * static_cast<std::size_t>(size() - 1));
    else count(0);
    backend_.broadcast(data.data(), data.size_bytes(), root);
  }
  template <Transferable T>
  T broadcast(T value, int root = 0) const {
    broadcast(std::span<T>(&value, 1), root);
    return value;
  }
  /// Broadcasts a vector whose length is known only on `root`.
  template <Transferable T>
  void broadcast(std::vector<T>& v, int root = 0) const {
    std::size_t n = broadcast(v.size(), root);
    v.resize(n);
    broadcast(std::span<T>(v), root);
  }

  // ---- gather --------------------------------------------------------------------
  /// One value from every rank, in rank order, on `root` (empty elsewhere).
  template <Transferable T>
  std::vector<T> gather(const T& v, int root = 0) const {
    return gatherv(std::span<const T>(&v, 1), root);
  }
  /// Variable-length gather: rank r's elements at offset sum(counts[0..r)) on `root`
  /// (empty elsewhere). `counts`, when given, receives the per-rank counts on root.
  template <Transferable T>
  std::vector<T> gatherv(std::span<const T> send, int root = 0,
                         std::vector<std::size_t>* counts = nullptr) const {
    check_root(root, "gatherv");
    return gather_impl(send, root, false, counts);
  }
  /// One value from every rank, in rank order, on every rank.
  template <Transferable T>
  std::vector<T> allgather(const T& v) const {
    return allgatherv(std::span<const T>(&v, 1));
  }
  template <Transferable T>
  std::vector<T> allgatherv(std::span<const T> send,
                            std::vector<std::size_t>* counts = nullptr) const {
    return gather_impl(send, 0, true, counts);
  }

  // ---- all-to-all ------------------------------------------------------------------
  /// `send` holds size() equal blocks; block r goes to rank r. Returns the blocks
  /// received, block r from rank r.
  template <Transferable T>
  std::vector<T> alltoall(std::span<const T> send) const {
    const auto p = static_cast<std::size_t>(size());
    if (send.size() % p != 0) {
      abort("alltoall: send size " + std::to_string(send.size()) +
            " is not a multiple of the rank count " + std::to_string(p));
    }
    std::vector<std::size_t> counts(p, send.size() / p);
    return alltoallv(send, std::span<const std::size_t>(counts));
  }
  /// `send` holds send_counts[r] elements for each rank r, in rank order. Returns
  /// what every rank sent here, in rank order; `recv_counts` (optional) gets the
  /// number from each rank.
  template <Transferable T>
  std::vector<T> alltoallv(std::span<const T> send, std::span<const std::size_t> send_counts,
                           std::vector<std::size_t>* recv_counts = nullptr) const {
    const auto p = static_cast<std::size_t>(size());
    if (send_counts.size() != p ||
        std::accumulate(send_counts.begin(), send_counts.end(), std::size_t{0}) !=
            send.size()) {
      abort("alltoallv: send_counts must have one entry per rank and sum to the send size");
    }
    // Counts first (one element per pair), then the payload.
    std::vector<std::size_t> ones(p, 1), offs(p);
    std::iota(offs.begin(), offs.end(), std::size_t{0});
    std::vector<std::size_t> rcounts(p);
    backend_.alltoallv(send_counts.data(), ones.data(), offs.data(), rcounts.data(),
                       ones.data(), offs.data(), sizeof(std::size_t));
    const auto sdispls = exclusive_scan(send_counts);
    const auto rdispls = exclusive_scan(std::span<const std::size_t>(rcounts));
    std::vector<T> recv(rdispls.back() + rcounts.back());
    std::size_t out = 0;
    for (std::size_t r = 0; r < p; ++r) {
      if (r != static_cast<std::size_t>(rank())) out += send_counts[r];
    }
    count(out * sizeof(T) + (p - 1) * sizeof(std::size_t));
    backend_.alltoallv(send.data(), send_counts.data(), sdispls.data(), recv.data(),
                       rcounts.data(), rdispls.data(), sizeof(T));
    if (recv_counts) *recv_counts = std::move(rcounts);
    return recv;
  }

  // ---- communicators and errors ----------------------------------------------------
  /// Ranks with the same `color` (>= 0) form a new communicator, ordered by `key`
  /// then by rank here.
  BasicComm split(int color, int key) const {
    if (color < 0) abort("split: color must be non-negative, got " + std::to_string(color));
    return BasicComm(backend_.split(color, key));
  }

  /// Prints `pik: rank R/P: error: why` to stderr and stops every rank of the
  /// program with a non-zero status. Callable from one rank alone.
  [[noreturn]] void abort(std::string_view why, int code = 1) const {
    fmt::print(stderr, "pik: rank {}/{}: error: {}\n", rank(), size(), why);
    std::fflush(stderr);
    backend_.abort(code);
  }

  const CommStats& stats() const { return *stats_; }
  void reset_stats() const { *stats_ = CommStats{}; }

 private:
  explicit BasicComm(Backend b) : backend_(std::move(b)) {}

  void count(std::size_t bytes) const {
    stats_->bytes_sent += bytes;
    ++stats_->collectives;
  }
  void check_root(int root, const char* what) const {
    if (root < 0 || root >= size()) {
      abort(std::string(what) + ": root " + std::to_string(root) + " is not a rank of " +
            std::to_string(size()));
    }
  }
  template <class T>
  T reduce_one(T v, comm::ReduceOp op) const {
    reduce_inplace(std::span<T>(&v, 1), op);
    return v;
  }
  template <class V>
  V reduce_vec(V v, comm::ReduceOp op) const {
    using E = typename V::value_type;
    E a[V::size];
    std::memcpy(a, &v, sizeof(V));
    reduce_inplace(std::span<E>(a, V::size), op);
    std::memcpy(&v, a, sizeof(V));
    return v;
  }
  template <class T>
  Located<T> locate(T mine, T best) const {
    const int candidate = (mine == best) ? rank() : size();
    const int r = min(candidate);
    return {best, r < size() ? r : 0};
  }
  static std::vector<std::size_t> exclusive_scan(std::span<const std::size_t> c) {
    std::vector<std::size_t> d(c.size(), 0);
    for (std::size_t i = 1; i < c.size(); ++i) d[i] = d[i - 1] + c[i - 1];
    return d;
  }
  template <class T>
  std::vector<T> gather_impl(std::span<const T> send, int root, bool all,
                             std::vector<std::size_t>* counts_out) const {
    const auto p = static_cast<std::size_t>(size());
    const bool receives = all || rank() == root;
    // Counts first: every receiver needs them to size its buffer.
    std::size_t n = send.size();
    std::vector<std::size_t> counts(receives ? p : 0);
    std::vector<std::size_t> ones(p, 1), offs(p);
    std::iota(offs.begin(), offs.end(), std::size_t{0});
    backend_.gatherv(&n, 1, counts.data(), ones.data(), offs.data(), sizeof(std::size_t), root,
                     all);
    const std::size_t others = all ? p - 1 : (rank() == root ? 0 : 1);
    count((send.size_bytes() + sizeof(std::size_t)) * others);
    std::vector<T> recv;
    std::vector<std::size_t> displs(p, 0);
    if (receives) {
      displs = exclusive_scan(std::span<const std::size_t>(counts));
      recv.resize(displs.back() + counts.back());
    }
    backend_.gatherv(send.data(), n, recv.data(), counts.data(), displs.data(), sizeof(T), root,
                     all);
    if (counts_out) *counts_out = std::move(counts);
    return recv;
  }

  Backend backend_;
  std::shared_ptr<CommStats> stats_ = std::make_shared<CommStats>();
};

/// The single-rank communicator, available in every build.
using SerialComm = BasicComm<comm::SerialBackend>;

#if defined(PIK_HAVE_MPI) && PIK_HAVE_MPI
/// The program's communicator type: MPI in this build.
using Comm = BasicComm<comm::MpiBackend>;
#else
/// The program's communicator type: one rank in this build (no MPI).
using Comm = SerialComm;
#endif

}  // namespace pik
