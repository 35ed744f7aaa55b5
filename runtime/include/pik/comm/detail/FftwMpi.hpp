/// \file FftwMpi.hpp
/// \brief FFTW's distributed (MPI) 3D real transforms, reached through a
///        communicator's backend: the comm layer's side of pik::pm's slab FFT.
///
/// FFTW's MPI interface takes an MPI_Comm, which only the comm layer may see. This
/// header gives each backend an overload: `fftw_slab_layout(backend, n, ...)` and
/// `fftw_slab_plans(backend, n, ...)` exist for comm::MpiBackend when pik is built
/// with MPI and libfftw3-mpi (PIK_HAVE_FFTW_MPI); for every other backend (and in
/// other builds) only deleted templates match, so a caller asks
/// `requires { pik::comm::fftw_slab_layout(comm.backend(), ...) }` and needs no #if.
/// The layout is FFTW's: ranks own x-slabs [local_0, local_0 + local_n0) of an
/// n x n x (n/2+1) complex array (rows not transposed).
#pragma once

#include <fftw3.h>

#include <cstddef>

namespace pik::comm {
/// No distributed FFT for this backend (the serial one, or a build without FFTW-MPI).
template <class Backend>
void fftw_slab_layout(const Backend&, int, std::ptrdiff_t&, std::ptrdiff_t&, std::ptrdiff_t&) = delete;
template <class Backend>
void fftw_slab_plans(const Backend&, int, double*, fftw_plan&, fftw_plan&) = delete;
}  // namespace pik::comm

#if defined(PIK_HAVE_MPI) && PIK_HAVE_MPI && defined(PIK_HAVE_FFTW_MPI) && PIK_HAVE_FFTW_MPI
#include <fftw3-mpi.h>

#include "pik/comm/detail/MpiBackend.hpp"

namespace pik::comm {

/// Local slab of an n^3 real mesh (in-place r2c) over the backend's ranks: the
/// doubles-pairs to allocate, and the planes [local_0, local_0 + local_n0) it holds.
inline void fftw_slab_layout(const MpiBackend& b, int n, std::ptrdiff_t& alloc, std::ptrdiff_t& local_n0,
                             std::ptrdiff_t& local_0) {
  static const bool init = [] {
    fftw_mpi_init();
    return true;
  }();
  (void)init;
  alloc = fftw_mpi_local_size_3d(n, n, n / 2 + 1, b.native(), &local_n0, &local_0);
}

/// In-place forward (r2c) and backward (c2r) plans of the distributed n^3 mesh.
inline void fftw_slab_plans(const MpiBackend& b, int n, double* data, fftw_plan& fwd, fftw_plan& bwd) {
  auto* c = reinterpret_cast<fftw_complex*>(data);
  fwd = fftw_mpi_plan_dft_r2c_3d(n, n, n, data, c, b.native(), FFTW_ESTIMATE);
  bwd = fftw_mpi_plan_dft_c2r_3d(n, n, n, c, data, b.native(), FFTW_ESTIMATE);
}

}  // namespace pik::comm
#endif
