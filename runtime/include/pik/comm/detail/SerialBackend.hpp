/// \file SerialBackend.hpp
/// \brief The one-process communication backend: every collective is a local copy.
///
/// Used when pik is built without MPI, and usable in any build (tests use it to
/// check the typed front end without launching ranks).
#pragma once

#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <chrono>

#include "pik/comm/detail/Scalar.hpp"

namespace pik::comm {

/// A communicator of exactly one rank.
class SerialBackend {
 public:
  static constexpr const char* name() { return "serial"; }

  static void init(int*, char***) {}
  static void finalize() {}
  static bool initialized() { return true; }
  static SerialBackend world() { return SerialBackend{}; }

  int rank() const { return 0; }
  int size() const { return 1; }
  void barrier() const {}

  void allreduce(void*, std::size_t, ScalarKind, ReduceOp) const {}
  void broadcast(void*, std::size_t, int) const {}

  /// Gathers `n` elements of `elem` bytes from every rank into `recv` at
  /// `displs[r]` (in elements) on `root` (on every rank when `all`).
  void gatherv(const void* send, std::size_t n, void* recv, const std::size_t*,
               const std::size_t* displs, std::size_t elem, int, bool) const {
    copy(send, n * elem, recv, displs[0] * elem);
  }

  /// Sends `scounts[r]` elements from `send + sdispls[r]` to rank r; receives
  /// `rcounts[r]` elements into `recv + rdispls[r]` (counts in elements).
  void alltoallv(const void* send, const std::size_t* scounts, const std::size_t* sdispls,
                 void* recv, const std::size_t*, const std::size_t* rdispls,
                 std::size_t elem) const {
    copy(static_cast<const char*>(send) + sdispls[0] * elem, scounts[0] * elem, recv,
         rdispls[0] * elem);
  }

  SerialBackend split(int, int) const { return SerialBackend{}; }

  [[noreturn]] void abort(int code) const { std::exit(code == 0 ? 1 : code); }

  static double wtime() {
    using clock = std::chrono::steady_clock;
    return std::chrono::duration<double>(clock::now().time_since_epoch()).count();
  }

 private:
  static void copy(const void* src, std::size_t bytes, void* dst, std::size_t offset) {
    if (bytes > 0) std::memcpy(static_cast<char*>(dst) + offset, src, bytes);
  }
};

}  // namespace pik::comm
