/// \file ProcessGrid.hpp
/// \brief Choosing the nx × ny × nz rank grid of a multisection decomposition.
#pragma once

#include <array>
#include <cstddef>

namespace pik {

/// The factorization of `nranks` into Dim factors that is closest to a cube
/// (smallest sum of factors, i.e. least domain surface for a cubic root domain),
/// largest factor first: 8 → 2×2×2, 12 → 3×2×2, 3 → 3×1×1, 6 → 3×2×1.
template <int Dim>
std::array<int, Dim> choose_process_grid(int nranks) {
  std::array<int, Dim> best{};
  best.fill(1);
  best[0] = nranks;
  if constexpr (Dim == 1) {
    return best;
  } else {
    long best_sum = nranks + Dim - 1;
    // Enumerate non-increasing factor tuples recursively.
    std::array<int, Dim> cur{};
    auto rec = [&](auto&& self, int d, int remaining, int max_factor, long sum) -> void {
      if (d == Dim - 1) {
        if (remaining > max_factor) return;
        cur[d] = remaining;
        if (sum + remaining < best_sum) {
          best_sum = sum + remaining;
          best = cur;
        }
        return;
      }
      for (int f = max_factor < remaining ? max_factor : remaining; f >= 1; --f) {
        if (remaining % f != 0) continue;
        cur[d] = f;
        self(self, d + 1, remaining / f, f, sum + f);
      }
    };
    rec(rec, 0, nranks, nranks, 0);
    return best;
  }
}

}  // namespace pik
