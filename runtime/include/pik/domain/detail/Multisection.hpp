/// \file Multisection.hpp
/// \brief Weighted multisection of sample points into nx × ny (× nz) cells.
///
/// The multisection method (Makino 2004, PASJ 56, 521; used by GreeM, Ishiyama et
/// al. 2009, and FDPS, Iwasawa et al. 2016, PASJ 68, 54): sort the samples along x
/// and cut them into nx slabs of equal weight; cut each slab along y into ny
/// columns; each column along z into nz cells. Each sample carries the measured
/// cost it stands for, so equal weight means equal work, not equal particle count.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <span>
#include <vector>

namespace pik::domain_detail {

/// One sampled particle position and the cost it stands for.
template <class Real, int Dim>
struct Sample {
  std::array<Real, Dim> x;
  double weight;
};

/// Boundaries of a multisection: level d holds, for each cell of the first d
/// dimensions, its n[d]+1 cuts along dimension d (row-major, x slowest).
template <class Real, int Dim>
struct Cuts {
  std::array<int, Dim> n{};
  std::array<std::vector<Real>, Dim> level;

  void resize(const std::array<int, Dim>& grid) {
    n = grid;
    std::size_t cells = 1;
    for (int d = 0; d < Dim; ++d) {
      level[d].assign(cells * static_cast<std::size_t>(n[d] + 1), Real{});
      cells *= static_cast<std::size_t>(n[d]);
    }
  }
  Real* cuts(int d, std::size_t cell) {
    return level[d].data() + cell * static_cast<std::size_t>(n[d] + 1);
  }
  const Real* cuts(int d, std::size_t cell) const {
    return level[d].data() + cell * static_cast<std::size_t>(n[d] + 1);
  }
};

/// Cuts the sorted samples `s` (along `d`) into `n` parts of equal weight within
/// [lo, hi], writing n+1 monotone cuts to `out`.
template <class Real, int Dim>
void cut_one(std::span<const Sample<Real, Dim>> s, int d, int n, Real lo, Real hi, Real* out) {
  out[0] = lo;
  out[n] = hi;
  double total = 0;
  for (const auto& p : s) total += p.weight;
  if (s.empty() || !(total > 0)) {
    // Nothing to balance: split a finite interval evenly, otherwise give
    // everything to the parts touching the finite side (any monotone cuts are valid).
    const bool finite = std::isfinite(lo) && std::isfinite(hi);
    const Real anchor = std::isfinite(lo) ? lo : (std::isfinite(hi) ? hi : Real{0});
    for (int k = 1; k < n; ++k) out[k] = finite ? lo + (hi - lo) * Real(k) / Real(n) : anchor;
    return;
  }
  std::size_t j = 0;
  double before = 0;  // weight of samples [0, j)
  for (int k = 1; k < n; ++k) {
    const double target = total * k / n;
    // First sample whose weight centre lies at or beyond the target.
    while (j < s.size() && before + 0.5 * s[j].weight < target) before += s[j++].weight;
    Real c;
    if (j == 0) c = s[0].x[d];
    else if (j == s.size()) c = std::nextafter(s[j - 1].x[d], std::numeric_limits<Real>::infinity());
    else c = s[j - 1].x[d] + (s[j].x[d] - s[j - 1].x[d]) / 2;
    c = std::clamp(c, lo, hi);
    out[k] = std::max(c, out[k - 1]);
  }
}

/// Multisection of `s` (reordered in place) into the cuts `cuts`, recursing from
/// dimension `d` in cell `cell` bounded by [lo, hi) along each dimension.
template <class Real, int Dim>
void multisect(std::span<Sample<Real, Dim>> s, Cuts<Real, Dim>& cuts, int d, std::size_t cell,
               const std::array<Real, Dim>& lo, const std::array<Real, Dim>& hi) {
  std::sort(s.begin(), s.end(), [d](const auto& a, const auto& b) { return a.x[d] < b.x[d]; });
  const int n = cuts.n[d];
  Real* c = cuts.cuts(d, cell);
  cut_one<Real, Dim>(s, d, n, lo[d], hi[d], c);
  if (d + 1 == Dim) return;
  auto begin = s.begin();
  for (int k = 0; k < n; ++k) {
    // Part k holds the samples with c[k] <= x < c[k+1] (the last part also any at hi).
    auto end = (k + 1 == n) ? s.end()
                            : std::lower_bound(begin, s.end(), c[k + 1], [d](const auto& a, Real v) {
                                return a.x[d] < v;
                              });
    multisect<Real, Dim>(std::span<Sample<Real, Dim>>(begin, end), cuts, d + 1,
                         cell * static_cast<std::size_t>(n) + static_cast<std::size_t>(k), lo, hi);
    begin = end;
  }
}

}  // namespace pik::domain_detail
