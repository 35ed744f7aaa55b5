/// \file BlockAverage.hpp
/// \brief Mean and statistical error of a correlated time series by block averaging.
///
/// Successive MD samples are correlated, so the naive error sigma / sqrt(n) is too
/// small. Cutting the series into B contiguous blocks much longer than the
/// correlation time makes the block means nearly independent; the error of the
/// mean is then std(block means) / sqrt(B) (Flyvbjerg & Petersen, J. Chem. Phys.
/// 91, 461, 1989; Allen & Tildesley 2017, sec. 8.4). blocking_curve() gives the
/// Flyvbjerg-Petersen sequence (halving the series repeatedly): the estimate grows
/// with block length until blocks decorrelate and then levels off, which shows
/// whether a run was long enough.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

namespace md {

class BlockAverage {
 public:
  void add(double x) { x_.push_back(x); }
  void clear() { x_.clear(); }
  std::size_t size() const { return x_.size(); }
  const std::vector<double>& samples() const { return x_; }

  double mean() const {
    double s = 0;
    for (double x : x_) s += x;
    return x_.empty() ? NAN : s / double(x_.size());
  }

  /// Error of the mean from `blocks` equal blocks (a trailing remainder of fewer
  /// than `blocks` samples is dropped). NaN with fewer than 2 samples per block.
  double error(std::size_t blocks = 20) const {
    if (blocks < 2 || x_.size() < 2 * blocks) return NAN;
    const std::size_t len = x_.size() / blocks;
    std::vector<double> m(blocks, 0.0);
    for (std::size_t b = 0; b < blocks; ++b) {
      for (std::size_t i = 0; i < len; ++i) m[b] += x_[b * len + i];
      m[b] /= double(len);
    }
    double mean = 0;
    for (double v : m) mean += v;
    mean /= double(blocks);
    double var = 0;
    for (double v : m) var += (v - mean) * (v - mean);
    var /= double(blocks - 1);  // sample variance of the block means
    return std::sqrt(var / double(blocks));
  }

  /// Flyvbjerg-Petersen blocking: error estimates for block lengths 1, 2, 4, ...
  /// while at least `min_blocks` blocks remain.
  std::vector<double> blocking_curve(std::size_t min_blocks = 8) const {
    std::vector<double> out, y = x_;
    while (y.size() >= min_blocks) {
      const double n = double(y.size());
      double mean = 0;
      for (double v : y) mean += v;
      mean /= n;
      double c0 = 0;
      for (double v : y) c0 += (v - mean) * (v - mean);
      out.push_back(std::sqrt(c0 / n / (n - 1.0)));
      std::vector<double> h(y.size() / 2);
      for (std::size_t i = 0; i < h.size(); ++i) h[i] = 0.5 * (y[2 * i] + y[2 * i + 1]);
      y.swap(h);
    }
    return out;
  }

 private:
  std::vector<double> x_;
};

}  // namespace md
