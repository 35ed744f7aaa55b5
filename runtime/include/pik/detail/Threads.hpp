/// \file Threads.hpp
/// \brief The runtime's only contact with OpenMP: a parallel loop and thread queries.
///
/// Tree and walk code call these functions and never see `#pragma omp`, so a build
/// without OpenMP is the same code running on one thread.
#pragma once

#include <cstddef>
#include <exception>
#include <mutex>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace pik::detail {

/// Threads a parallel_for would use.
inline int max_threads() {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

/// The calling thread's number in the current parallel loop (0 outside one).
inline int thread_num() {
#ifdef _OPENMP
  return omp_get_thread_num();
#else
  return 0;
#endif
}

/// Sets the number of threads later parallel loops use (no effect without OpenMP).
inline void set_threads(int n) {
#ifdef _OPENMP
  if (n > 0) omp_set_num_threads(n);
#else
  (void)n;
#endif
}

/// Calls body(i, thread) for i in [0, n), scheduled dynamically in chunks of `chunk`
/// (work items such as tree walks of i-groups have uneven costs). `thread` is in
/// [0, max_threads()), for per-thread scratch buffers.
template <class Body>
void parallel_for(std::ptrdiff_t n, Body&& body, std::ptrdiff_t chunk = 1) {
#ifdef _OPENMP
  if (n > 1 && omp_get_max_threads() > 1 && !omp_in_parallel()) {
#pragma omp parallel for schedule(dynamic, chunk)
    for (std::ptrdiff_t i = 0; i < n; ++i) body(i, omp_get_thread_num());
    return;
  }
#endif
  (void)chunk;
  for (std::ptrdiff_t i = 0; i < n; ++i) body(i, 0);
}

/// Calls body(i) for i in [0, n) split into equal static blocks (cheap, even work).
/// Loops of at most `serial_below` items run on the calling thread (the default suits
/// one particle per item; a loop over i-groups, each dozens of particles, passes less).
template <class Body>
void parallel_for_static(std::ptrdiff_t n, Body&& body, std::ptrdiff_t serial_below = 4096) {
#ifdef _OPENMP
  if (n > serial_below && omp_get_max_threads() > 1 && !omp_in_parallel()) {
#pragma omp parallel for schedule(static)
    for (std::ptrdiff_t i = 0; i < n; ++i) body(i);
    return;
  }
#endif
  (void)serial_below;
  for (std::ptrdiff_t i = 0; i < n; ++i) body(i);
}

/// parallel_for_static for a body that may throw (an exception must not leave an OpenMP
/// loop): every i runs, and the exception of the lowest i that threw, the one the
/// serial loop would have met first, is rethrown after the loop.
template <class Body>
void parallel_for_throwing(std::ptrdiff_t n, Body&& body) {
  std::exception_ptr first;
  std::ptrdiff_t at = n;
  std::mutex mu;
  parallel_for_static(n, [&](std::ptrdiff_t i) {
    try {
      body(i);
    } catch (...) {
      const std::lock_guard<std::mutex> lock(mu);
      if (i < at) at = i, first = std::current_exception();
    }
  });
  if (first) std::rethrow_exception(first);
}

}  // namespace pik::detail
