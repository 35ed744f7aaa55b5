/// \file MpiBackend.hpp
/// \brief The MPI communication backend (Open MPI): the only code in pik that calls MPI.
///
/// Element counts travel as `int` in MPI-3, so user data of any size is sent as a
/// contiguous derived datatype of one element's bytes; a count or displacement that
/// still overflows `int` stops the program with a message instead of corrupting data.
#pragma once

#include <mpi.h>

#include <climits>
#include <cstddef>
#include <cstdio>
#include <memory>
#include <vector>

#include <fmt/core.h>

#include "pik/comm/detail/Scalar.hpp"

namespace pik::comm {

/// A shared handle to an MPI communicator; communicators made by split() are freed
/// when the last copy goes away (unless MPI has already been finalized).
class MpiBackend {
 public:
  static constexpr const char* name() { return "mpi"; }

  /// Starts MPI with MPI_THREAD_FUNNELED: OpenMP threads compute, the master thread
  /// communicates (the hybrid model of the runtime).
  static void init(int* argc, char*** argv) {
    if (initialized()) return;
    int provided = 0;
    MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);
    if (provided < MPI_THREAD_FUNNELED) {
      fmt::print(stderr, "pik: warning: MPI provides no MPI_THREAD_FUNNELED support\n");
    }
  }
  static void finalize() {
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (!finalized && initialized()) MPI_Finalize();
  }
  static bool initialized() {
    int flag = 0;
    MPI_Initialized(&flag);
    int finalized = 0;
    MPI_Finalized(&finalized);
    return flag != 0 && finalized == 0;
  }
  static MpiBackend world() { return MpiBackend(MPI_COMM_WORLD, false); }

  int rank() const { return rank_; }
  int size() const { return size_; }
  void barrier() const { MPI_Barrier(*comm_); }

  void allreduce(void* inout, std::size_t count, ScalarKind kind, ReduceOp op) const {
    if (count == 0) return;
    MPI_Allreduce(MPI_IN_PLACE, inout, checked(count, "allreduce count"), datatype(kind),
                  mpi_op(op), *comm_);
  }

  void broadcast(void* data, std::size_t bytes, int root) const {
    // Large buffers go in int-sized pieces; most calls are one piece.
    auto* p = static_cast<char*>(data);
    constexpr std::size_t piece = std::size_t{1} << 30;
    for (std::size_t off = 0; off < bytes; off += piece) {
      const std::size_t n = bytes - off < piece ? bytes - off : piece;
      MPI_Bcast(p + off, static_cast<int>(n), MPI_BYTE, root, *comm_);
    }
  }

  void gatherv(const void* send, std::size_t n, void* recv, const std::size_t* counts,
               const std::size_t* displs, std::size_t elem, int root, bool all) const {
    Contiguous type(elem);
    const bool receives = all || rank_ == root;
    std::vector<int> c, d;
    if (receives) {
      c = to_int(counts, "gather count");
      d = to_int(displs, "gather displacement");
    }
    const int ns = checked(n, "gather count");
    if (all) {
      MPI_Allgatherv(send, ns, type.t, recv, c.data(), d.data(), type.t, *comm_);
    } else {
      MPI_Gatherv(send, ns, type.t, recv, receives ? c.data() : nullptr,
                  receives ? d.data() : nullptr, type.t, root, *comm_);
    }
  }

  void alltoallv(const void* send, const std::size_t* scounts, const std::size_t* sdispls,
                 void* recv, const std::size_t* rcounts, const std::size_t* rdispls,
                 std::size_t elem) const {
    Contiguous type(elem);
    const auto sc = to_int(scounts, "alltoallv send count");
    const auto sd = to_int(sdispls, "alltoallv send displacement");
    const auto rc = to_int(rcounts, "alltoallv receive count");
    const auto rd = to_int(rdispls, "alltoallv receive displacement");
    MPI_Alltoallv(send, sc.data(), sd.data(), type.t, recv, rc.data(), rd.data(), type.t,
                  *comm_);
  }

  MpiBackend split(int color, int key) const {
    MPI_Comm out = MPI_COMM_NULL;
    MPI_Comm_split(*comm_, color < 0 ? MPI_UNDEFINED : color, key, &out);
    return MpiBackend(out, true);
  }

  [[noreturn]] void abort(int code) const {
    MPI_Abort(*comm_, code == 0 ? 1 : code);
    std::exit(code == 0 ? 1 : code);  // MPI_Abort does not return; keep [[noreturn]] honest
  }

  static double wtime() { return MPI_Wtime(); }

  /// The MPI communicator, for libraries that take one (FFTW's MPI transforms).
  MPI_Comm native() const { return *comm_; }

 private:
  MpiBackend(MPI_Comm c, bool owned) {
    comm_ = std::shared_ptr<MPI_Comm>(new MPI_Comm(c), [owned](MPI_Comm* p) {
      int finalized = 0;
      MPI_Finalized(&finalized);
      if (owned && !finalized && *p != MPI_COMM_NULL) MPI_Comm_free(p);
      delete p;
    });
    if (c != MPI_COMM_NULL) {
      MPI_Comm_rank(c, &rank_);
      MPI_Comm_size(c, &size_);
    }
  }

  /// A committed MPI datatype of `bytes` contiguous bytes, freed on scope exit.
  struct Contiguous {
    MPI_Datatype t{};
    explicit Contiguous(std::size_t bytes) {
      MPI_Type_contiguous(static_cast<int>(bytes), MPI_BYTE, &t);
      MPI_Type_commit(&t);
    }
    ~Contiguous() { MPI_Type_free(&t); }
    Contiguous(const Contiguous&) = delete;
    Contiguous& operator=(const Contiguous&) = delete;
  };

  int checked(std::size_t n, const char* what) const {
    if (n > static_cast<std::size_t>(INT_MAX)) {
      fmt::print(stderr, "pik: rank {}: {} {} exceeds MPI's int range\n", rank_, what, n);
      abort(1);
    }
    return static_cast<int>(n);
  }
  std::vector<int> to_int(const std::size_t* v, const char* what) const {
    std::vector<int> out(static_cast<std::size_t>(size_));
    for (int r = 0; r < size_; ++r) out[static_cast<std::size_t>(r)] = checked(v[r], what);
    return out;
  }

  static MPI_Datatype datatype(ScalarKind k) {
    switch (k) {
      case ScalarKind::i8: return MPI_INT8_T;
      case ScalarKind::u8: return MPI_UINT8_T;
      case ScalarKind::i16: return MPI_INT16_T;
      case ScalarKind::u16: return MPI_UINT16_T;
      case ScalarKind::i32: return MPI_INT32_T;
      case ScalarKind::u32: return MPI_UINT32_T;
      case ScalarKind::i64: return MPI_INT64_T;
      case ScalarKind::u64: return MPI_UINT64_T;
      case ScalarKind::f32: return MPI_FLOAT;
      case ScalarKind::f64: return MPI_DOUBLE;
      case ScalarKind::f80: return MPI_LONG_DOUBLE;
    }
    return MPI_DATATYPE_NULL;
  }
  static MPI_Op mpi_op(ReduceOp op) {
    switch (op) {
      case ReduceOp::sum: return MPI_SUM;
      case ReduceOp::min: return MPI_MIN;
      case ReduceOp::max: return MPI_MAX;
    }
    return MPI_OP_NULL;
  }

  std::shared_ptr<MPI_Comm> comm_;
  int rank_ = 0;
  int size_ = 0;
};

}  // namespace pik::comm
