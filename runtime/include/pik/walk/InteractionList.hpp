/// \file InteractionList.hpp
/// \brief One i-group's interaction list: ranges of j-particles and super-particle ids.
///
/// j-particles are stored as ranges of the tree's sorted EPJ array (a leaf's
/// particles are contiguous), so a list is small, and copying the particles for a
/// kernel call is a few memcpy's. Kept lists let a later step reuse them
/// (ListMode::reuse) after the particles' contents are reloaded.
#pragma once

#include <cstddef>
#include <algorithm>
#include <cstdint>
#include <vector>

#include "pik/tree/IndexRange.hpp"

namespace pik {

namespace detail {
/// A growable array of trivially copyable T whose push_back is a compare and a store
/// (the list-making loop appends to it for every far cell; GCC 12 stopped inlining
/// std::vector::push_back there). Memory is kept by clear().
template <class T>
class ListBuffer {
 public:
  [[gnu::always_inline]] void push_back(const T& x) {
    if (n_ == v_.size()) [[unlikely]] grow();
    v_[n_++] = x;
  }
  /// Room for `k` more elements past the end; returns where they go (append() then
  /// commits how many were written).
  [[gnu::always_inline]] T* room(std::size_t k) {
    if (n_ + k > v_.size()) [[unlikely]] grow(n_ + k);
    return v_.data() + n_;
  }
  void append(std::size_t k) { n_ += k; }
  void clear() { n_ = 0; }
  bool empty() const { return n_ == 0; }
  std::size_t size() const { return n_; }
  T& back() { return v_[n_ - 1]; }
  const T& back() const { return v_[n_ - 1]; }
  T& operator[](std::size_t i) { return v_[i]; }
  const T& operator[](std::size_t i) const { return v_[i]; }
  const T* data() const { return v_.data(); }
  const T* begin() const { return v_.data(); }
  const T* end() const { return v_.data() + n_; }

 private:
  [[gnu::noinline]] void grow(std::size_t need = 0) {
    v_.resize(std::max(need, v_.size() < 32 ? std::size_t(64) : 2 * v_.size()));
  }
  std::vector<T> v_;
  std::size_t n_ = 0;
};
}  // namespace detail

struct InteractionList {
  detail::ListBuffer<IndexRange> epj;      ///< ranges of the sorted EPJ array
  detail::ListBuffer<std::uint32_t> spj;   ///< indices of super-particles (cells, then imported)

  void clear() {
    epj.clear();
    spj.clear();
  }
  /// Appends a range, merging it with the previous one when they touch.
  void add_epj(std::uint32_t b, std::uint32_t e) {
    if (b == e) return;
    if (!epj.empty() && epj.back().end == b) {
      epj.back().end = e;
    } else {
      epj.push_back({b, e});
    }
  }
  std::size_t epj_count() const {
    std::size_t n = 0;
    for (const IndexRange& r : epj) n += r.end - r.begin;
    return n;
  }
};

}  // namespace pik
