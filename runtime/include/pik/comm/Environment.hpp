/// \file Environment.hpp
/// \brief pik::Environment: starts and stops the communication layer around main().
///
/// ```cpp
/// int main(int argc, char** argv) {
///   pik::Environment env(argc, argv);   // MPI_Init_thread (FUNNELED) under MPI
///   pik::Comm comm = env.world();
///   ...
/// }                                      // MPI_Finalize
/// ```
/// Only the Environment that started MPI finalizes it, so a program that manages
/// MPI itself can still create one.
#pragma once

#include <algorithm>
#include <cstdlib>

#include "pik/comm/Comm.hpp"

namespace pik {

/// Ranks of the job this process was started in by mpirun (Open MPI, MPICH/PMI, PMIx),
/// read from the launcher's environment, so before MPI is initialised (a program can
/// refuse a command that runs in one process only before it starts MPI); 1 outside
/// mpirun.
inline int launcher_ranks() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"})
    if (const char* s = std::getenv(v)) return std::max(1, std::atoi(s));
  return 1;
}

template <class Backend>
class BasicEnvironment {
 public:
  BasicEnvironment(int& argc, char**& argv) {
    if (!Backend::initialized()) {
      Backend::init(&argc, &argv);
      owns_ = true;
    }
  }
  /// For programs without command-line arguments (tests, libraries).
  BasicEnvironment() {
    if (!Backend::initialized()) {
      Backend::init(nullptr, nullptr);
      owns_ = true;
    }
  }
  ~BasicEnvironment() {
    if (owns_) Backend::finalize();
  }
  BasicEnvironment(const BasicEnvironment&) = delete;
  BasicEnvironment& operator=(const BasicEnvironment&) = delete;

  BasicComm<Backend> world() const { return BasicComm<Backend>::world(); }

 private:
  bool owns_ = false;
};

#if defined(PIK_HAVE_MPI) && PIK_HAVE_MPI
using Environment = BasicEnvironment<comm::MpiBackend>;
#else
using Environment = BasicEnvironment<comm::SerialBackend>;
#endif

}  // namespace pik
