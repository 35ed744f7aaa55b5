/// \file SlabFft.hpp
/// \brief A 3D real-to-complex FFT of an N^3 periodic mesh, in x-slabs over the ranks.
///
/// FFTW's in-place r2c layout: real values at ((ix * N) + iy) * 2(N/2+1) + iz, complex
/// ones at ((ix * N) + iy) * (N/2+1) + kz (rows in x, not transposed). On one rank it
/// is fftw_plan_dft_r2c_3d; on several (with libfftw3-mpi) fftw_mpi_plan_dft_r2c_3d,
/// each rank holding planes [x0, x0 + nx). The transforms are unnormalised (forward
/// then backward multiplies by N^3), as FFTW's.
///
/// FFTW's MPI interface takes an MPI_Comm, which only the comm layer sees: the
/// distributed layout and plans come from pik/comm/detail/FftwMpi.hpp, whose
/// overloads for the communicator's backend exist only in a build with MPI and
/// libfftw3-mpi (no #if here). With libfftw3_omp the transforms are threaded
/// (fftw_plan_threads).
#pragma once

#include <fftw3.h>

#include <algorithm>
#include <cstddef>
#include <string>
#include <type_traits>
#include <vector>

#include "pik/Error.hpp"
#include "pik/comm/Comm.hpp"
#include "pik/comm/detail/FftwMpi.hpp"
#include "pik/detail/Threads.hpp"

namespace pik::pm::detail {

/// With libfftw3_omp (PIK_HAVE_FFTW_OMP), plans made after this call run on the
/// runtime's threads (pik::detail::max_threads()); FFTW wants its thread setup before
/// fftw_mpi_init, which the MPI layout calls.
inline void fftw_plan_threads() {
#if defined(PIK_HAVE_FFTW_OMP) && PIK_HAVE_FFTW_OMP
  static const bool ok = fftw_init_threads() != 0;
  if (ok) fftw_plan_with_nthreads(pik::detail::max_threads());
#endif
}

class SlabFft {
 public:
  template <class CommT>
  SlabFft(int n, const CommT& comm) : n_(n), nzc_(n / 2 + 1) {
    if (n < 2) throw Error("particle mesh: the mesh needs at least 2 cells per side, got " + std::to_string(n));
    fftw_plan_threads();
    std::ptrdiff_t alloc = std::ptrdiff_t(n) * n * nzc_, local_n0 = n, local_0 = 0;
    bool distributed = false;
    if constexpr (requires { pik::comm::fftw_slab_layout(comm.backend(), n, alloc, local_n0, local_0); }) {
      if (comm.size() > 1) {
        pik::comm::fftw_slab_layout(comm.backend(), n, alloc, local_n0, local_0);
        distributed = true;
      }
    }
    if (!distributed && comm.size() > 1)
      throw Error("particle mesh on " + std::to_string(comm.size()) +
                  " ranks needs libfftw3-mpi (pik was built without it)");
    x0_ = int(local_0), nx_ = int(local_n0);
    // Every rank's slab, for routing planes.
    const auto starts = comm.allgather(x0_), counts = comm.allgather(nx_);
    owner_.assign(std::size_t(n), -1);
    for (std::size_t r = 0; r < starts.size(); ++r)
      for (int x = starts[r]; x < starts[r] + counts[r]; ++x) owner_[std::size_t(x)] = int(r);
    for (int o : owner_)
      if (o < 0) throw Error("particle mesh: FFTW left a plane without an owner");
    data_ = fftw_alloc_real(std::size_t(2 * std::max<std::ptrdiff_t>(alloc, 1)));
    if (!data_) throw Error("particle mesh: out of memory for a " + std::to_string(n) + "^3 mesh");
    auto* c = reinterpret_cast<fftw_complex*>(data_);
    if constexpr (requires { pik::comm::fftw_slab_plans(comm.backend(), n, data_, fwd_, bwd_); }) {
      if (distributed) pik::comm::fftw_slab_plans(comm.backend(), n, data_, fwd_, bwd_);
    }
    if (!distributed) {
      fwd_ = fftw_plan_dft_r2c_3d(n, n, n, data_, c, FFTW_ESTIMATE);
      bwd_ = fftw_plan_dft_c2r_3d(n, n, n, c, data_, FFTW_ESTIMATE);
    }
    if (!fwd_ || !bwd_) throw Error("particle mesh: FFTW could not plan the transforms");
  }
  SlabFft(const SlabFft&) = delete;
  SlabFft& operator=(const SlabFft&) = delete;
  ~SlabFft() {
    if (fwd_) fftw_destroy_plan(fwd_);
    if (bwd_) fftw_destroy_plan(bwd_);
    if (data_) fftw_free(data_);
  }

  int n() const { return n_; }
  int x0() const { return x0_; }
  int nx() const { return nx_; }
  /// Rank that owns plane x.
  int owner(int x) const { return owner_[std::size_t(x)]; }
  /// Real values: plane x (global) row iy column iz.
  double& real(int x, int iy, int iz) { return data_[(std::size_t(x - x0_) * n_ + iy) * 2 * nzc_ + iz]; }
  double* real_row(int x, int iy) { return data_ + (std::size_t(x - x0_) * n_ + iy) * 2 * nzc_; }
  /// Doubles from one real row to the next (n padded to 2 (n/2+1)).
  std::size_t padded_row() const { return 2 * std::size_t(nzc_); }
  fftw_complex* complex_data() { return reinterpret_cast<fftw_complex*>(data_); }
  /// Complex values per x-plane of the local slab: n * (n/2+1).
  std::size_t complex_plane() const { return std::size_t(n_) * nzc_; }
  int nzc() const { return nzc_; }
  void zero() {
    const std::size_t m = std::size_t(n_) * 2 * nzc_;
    pik::detail::parallel_for_static(std::ptrdiff_t(nx_), [&](std::ptrdiff_t x) {
      std::fill_n(data_ + std::size_t(x) * m, m, 0.0);
    });
  }
  void forward() { fftw_execute(fwd_); }
  void backward() { fftw_execute(bwd_); }

 private:
  int n_, nzc_, x0_ = 0, nx_ = 0;
  std::vector<int> owner_;
  double* data_ = nullptr;
  fftw_plan fwd_ = nullptr, bwd_ = nullptr;
};

}  // namespace pik::pm::detail
