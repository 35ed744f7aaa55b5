/// \file SmoothingLength.hpp
/// \brief The smoothing-length iteration shared by every SPH program: h_i such that the
///        kernel-smoothed mass in the support is N_ngb particle masses.
///
/// Solves F(h) = V_D h^D rho(h) / m - N_ngb = 0 (Springel & Hernquist 2002, eq. 7, with
/// the kernel-smoothed mass in the support as the neighbour number) by Newton steps
/// with dF/dh from the density pass's drho/dh, each a full gather pass, until
/// |F| < tol N_ngb for every particle. Newton is kept within a factor 1.5 per pass (a
/// fixed-point step when it goes the wrong way) and bisects once it leaves a known
/// bracket [h_lo, h_hi] of the root; the previous step's h usually passes at once.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include <pik/Error.hpp>
#include <pik/detail/Threads.hpp>
#include <pik/sph/Smoothing.hpp>

namespace pik::sph {

struct SmoothingLengthParams {
  double nngb = 50;     ///< neighbour number N_ngb (kernel mass in the support / m)
  double tol = 1e-2;    ///< relative tolerance on the neighbour number
  int max_passes = 50;  ///< passes before giving up with an error
  double fixed_h = 0;   ///< > 0: h is this everywhere, one pass, no iteration
  /// > 0: cap on h. A particle at the cap with too few neighbours counts as converged
  /// (isolated debris keeps a bounded kernel instead of reaching across the system, as
  /// SWIFT's `SPH: h_max`). 0: no cap (the default; other programs unchanged).
  double h_max = 0;
  /// Sum of the per-rank count of unconverged particles (identity in one process; an
  /// MPI program passes comm.sum so that every rank makes the same number of passes).
  std::function<long(long)> global_sum = [](long n) { return n; };
};

/// Particles the iteration works on: a mass, h, the density pass's rho and drho/dh,
/// and room for the bracket.
template <class P>
concept SmoothedParticle = requires(P p) {
  p.id;
  p.mass;
  p.h;
  p.rho;
  p.drhodh;
  p.h_lo;
  p.h_hi;
};

/// h^D by multiplications (std::pow(double, int) is the library's pow: a call per
/// particle and pass).
template <int D>
constexpr double pow_dim(double h) {
  static_assert(D >= 1 && D <= 3, "dimension 1, 2 or 3");
  if constexpr (D == 1) return h;
  else if constexpr (D == 2) return h * h;
  else return h * h * h;
}

/// Runs `gather_pass()` (one density pass filling rho and drhodh of every particle) until
/// the smoothing lengths converge; returns the number of passes. D is the dimension.
///
/// A pass that can be called as `gather_pass(std::span<const std::uint8_t> active)` is
/// told which particles changed h since the last pass (active[i] != 0, i the index in
/// `ps`; every particle on the first pass): it needs to recompute only those (the others
/// keep rho and drhodh, which no longer change: the positions are fixed during the
/// iteration, and a particle's density depends only on its own h). With a short-range
/// tree: build it once before the iteration, and per pass refresh() and
/// calcForceOnTreeAndWriteBack(kernel, ps, active).
///
/// `only` (optional, needs the masked pass): iterate only the particles with only[i] != 0
/// (block time steps: the active ones); the others keep h, and the first pass is told
/// `only` as its mask. An empty span: every particle, as before.
template <int D, class Particles, class Pass>
int iterate_smoothing_length(Particles& ps, Pass&& gather_pass, const SmoothingLengthParams& prm,
                             std::span<const std::uint8_t> only = {}) {
  constexpr bool masked = std::is_invocable_v<Pass&, std::span<const std::uint8_t>>;
  const double vd = unit_ball(D), N = prm.nngb;
  std::vector<std::uint8_t> active;
  auto pass = [&] {
    if constexpr (masked) gather_pass(std::span<const std::uint8_t>(active));
    else gather_pass();
  };
  if (!only.empty()) {
    if (!masked) throw Error("iterate_smoothing_length: a subset (`only`) needs a pass that takes the active mask");
    if (only.size() != ps.size()) throw Error("iterate_smoothing_length: the subset mask does not match the particles");
  }
  if constexpr (masked) {
    if (only.empty()) active.assign(ps.size(), 1);
    else active.assign(only.begin(), only.end());
  }
  if (prm.fixed_h > 0) {
    std::size_t k = 0;
    for (auto& p : ps)
      if (only.empty() || only[k++]) p.h = prm.fixed_h;
    pass();
    return 1;
  }
  if (prm.h_max < 0) throw Error("iterate_smoothing_length: h_max must not be negative");
  // The per-particle loops run on the threads (each touches only its particle and its
  // flag; the same result on any number of threads).
  auto at = ps.begin();
  const std::ptrdiff_t n = std::ptrdiff_t(ps.size());
  detail::parallel_for_static(n, [&](std::ptrdiff_t i) {
    if (!only.empty() && !only[std::size_t(i)]) return;
    auto& p = at[i];
    p.h_lo = p.h_hi = 0;
    if (prm.h_max > 0 && p.h > prm.h_max) p.h = prm.h_max;
  });
  for (int it = 0;; ++it) {
    pass();
    const bool last = it + 1 >= prm.max_passes;
    std::atomic<long> bad{0};
    std::atomic<std::ptrdiff_t> first_failed{n};
    detail::parallel_for_static(n, [&](std::ptrdiff_t i) {
      auto& p = at[i];
      if constexpr (masked) active[std::size_t(i)] = 0;
      if (!only.empty() && !only[std::size_t(i)]) return;
      const double hd = pow_dim<D>(p.h), F = vd * hd * p.rho / p.mass - N;
      if (std::abs(F) < prm.tol * N) return;
      if (prm.h_max > 0 && F < 0 && p.h >= prm.h_max) return;  // at the cap: converged
      if constexpr (masked) active[std::size_t(i)] = 1;
      bad.fetch_add(1, std::memory_order_relaxed);
      if (last) {
        // the first unconverged particle names the failure (below)
        std::ptrdiff_t f = first_failed.load(std::memory_order_relaxed);
        while (i < f && !first_failed.compare_exchange_weak(f, i, std::memory_order_relaxed)) {
        }
        return;
      }
      // The neighbour number grows with h: keep a bracket [h_lo, h_hi] of the root.
      if (F < 0) p.h_lo = std::max(p.h_lo, p.h);
      else p.h_hi = p.h_hi > 0 ? std::min(p.h_hi, p.h) : p.h;
      const double dF = vd * hd / p.h * (D * p.rho + p.h * p.drhodh) / p.mass;
      double h = dF > 1e-3 * N / p.h ? p.h - F / dF : NAN;  // flat F (only the particle itself): no Newton
      if (!(h > p.h / 1.5 && h < p.h * 1.5)) h = p.h * std::clamp(std::pow(N / (N + F), 1.0 / D), 1 / 1.5, 1.5);
      if (p.h_lo > 0 && p.h_hi > 0 && !(h > p.h_lo && h < p.h_hi)) h = std::sqrt(p.h_lo * p.h_hi);
      p.h = prm.h_max > 0 ? std::min(h, prm.h_max) : h;
    });
    // every rank throws after the global count, so none is left waiting in a collective
    std::string failure;
    if (const std::ptrdiff_t f = first_failed.load(); f < n) {
      const auto& p = at[f];
      failure = "smoothing lengths did not converge in " + std::to_string(prm.max_passes) + " passes (particle " +
                std::to_string(p.id) + ": h " + std::to_string(p.h) + ", neighbour number " +
                std::to_string(vd * pow_dim<D>(p.h) * p.rho / p.mass) + ", wanted " + std::to_string(N) + ")";
    }
    const long unconverged = prm.global_sum(bad.load());
    if (unconverged == 0) return it + 1;
    if (last)
      throw Error(!failure.empty() ? failure
                                   : "smoothing lengths did not converge in " + std::to_string(prm.max_passes) +
                                         " passes (on another rank)");
  }
}

}  // namespace pik::sph
