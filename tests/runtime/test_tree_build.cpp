// The tree build's pieces against plain references: the radix sort (top digits by
// passes, then runs of equal top bits) against std::stable_sort on large inputs of
// every shape, on one and two threads; the octree built twice into the same object
// (kept scratch) equal to a fresh one; every long-range interaction list holds every
// source exactly once.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "support.hpp"

namespace {

using KI = pik::detail::KeyIndex;

std::vector<KI> keys(std::size_t n, int shape, std::mt19937_64& g) {
  std::vector<KI> a(n);
  for (std::size_t i = 0; i < n; ++i) {
    std::uint64_t k = g();
    if (shape == 1) k >>= 1;                        // Morton-like: 63 bits
    if (shape == 2) k = (g() % 64) << 40 | (k & 0xffff);  // long runs of equal top bits
    if (shape == 3) k = g() % 7;                    // many equal keys, all top bits zero
    if (shape == 4) k = (std::uint64_t(i % 3000) << 30) | (g() % 5);  // runs across blocks
    a[i] = {k, std::uint32_t((i * 2654435761u) % n)};  // indices not in input order
  }
  return a;
}

TEST(RadixSort, EqualsStableSortForEveryShapeAndThreadCount) {
  std::mt19937_64 g(7);
  for (int threads : {1, 2}) {
    pik::detail::set_threads(threads);
    for (std::size_t n : {std::size_t(3), std::size_t(40000), std::size_t(1) << 18, std::size_t(300001)})
      for (int shape = 0; shape < 5; ++shape) {
        auto a = keys(n, shape, g), b = a;
        std::vector<KI> scratch;
        pik::detail::radix_sort(a, scratch);
        std::stable_sort(b.begin(), b.end(), [](const KI& x, const KI& y) { return x.key < y.key; });
        for (std::size_t i = 0; i < n; ++i)
          ASSERT_TRUE(a[i].key == b[i].key && a[i].index == b[i].index)
              << "n " << n << " shape " << shape << " threads " << threads << " at " << i;
      }
  }
  pik::detail::set_threads(pik::detail::max_threads());
}

TEST(Octree, RebuildIntoTheSameTreeEqualsAFreshBuild) {
  for (int threads : {1, 2}) {
    pik::detail::set_threads(threads);
    pik::Octree<3> kept;
    for (int round = 0; round < 3; ++round) {
      auto ps = pt::make<double>(round == 1 ? pt::Dist::clustered : pt::Dist::uniform, 70000 + 5000 * round,
                                 unsigned(round));
      std::vector<pik::Vec3<double>> pos;
      for (auto& b : ps) pos.push_back(b.pos);
      kept.build(pos, {}, 8);
      pik::Octree<3> fresh;
      fresh.build(pos, {}, 8);
      ASSERT_EQ(kept.cells().size(), fresh.cells().size());
      for (std::size_t c = 0; c < kept.cells().size(); ++c) {
        const auto &x = kept.cells()[c], &y = fresh.cells()[c];
        ASSERT_TRUE(x.begin == y.begin && x.end == y.end && x.child == y.child && x.n_child == y.n_child &&
                    x.depth == y.depth);
      }
      ASSERT_EQ(kept.order(), fresh.order());
      std::vector<pik::IndexRange> gr;
      kept.groups(64, gr);
      const auto gf = fresh.groups(64);
      ASSERT_EQ(gr.size(), gf.size());
      for (std::size_t i = 0; i < gr.size(); ++i) ASSERT_TRUE(gr[i].begin == gf[i].begin && gr[i].end == gf[i].end);
    }
  }
  pik::detail::set_threads(pik::detail::max_threads());
}

// Every i-particle's interaction list must hold every source exactly once, as a
// particle or inside one super-particle: a kernel that sums the j masses then gives
// each particle the total mass (particles, imported particles and imported
// super-particles), whatever the opening criterion and angle, for clustered and
// uniform sets. This checks the walk's list making and gathering (no source lost or
// counted twice), which the force tests see only through their error bounds.
struct MassSum {
  template <class EPI, class J>
  void operator()(const EPI*, int ni, const J* pj, int nj, pt::Accel<double>* f) const {
    double m = 0;
    for (int j = 0; j < nj; ++j) m += double(pj[j].mass);
    for (int i = 0; i < ni; ++i) f[i].pot += m;
  }
};

TEST(LongRangeWalk, EveryListHoldsEverySourceOnce) {
  using B = pt::Body<double>;
  for (pt::Dist d : {pt::Dist::uniform, pt::Dist::clustered})
    for (auto o : {pik::Opening::box, pik::Opening::centre_of_mass, pik::Opening::centre_of_mass_offset})
      for (double theta : {0.0, 0.5, 1.0})
        for (bool imports : {false, true}) {
          auto ps = pt::make<double>(d, 6000, 5);
          pik::LongRangeTree<pt::Accel<double>, B, B> tree({theta, 8, 64, o});
          double total = 1.0;  // make() gives the local particles total mass 1
          if (imports) {
            auto far = pt::make<double>(pt::Dist::uniform, 500, 9);
            std::vector<B> epj(far.begin(), far.end());
            for (auto& b : epj) b.pos += pik::Vec3<double>{0.5, 0, 0}, b.mass = 0.25 / 500;
            std::vector<pik::SPJMonopole<double>> spj(3);
            for (int k = 0; k < 3; ++k) spj[std::size_t(k)].pos = {3.0 + k, -1, 2}, spj[std::size_t(k)].mass = 0.5;
            tree.setImportedParticles(epj);
            tree.setImportedSuperParticles(spj);
            total += 0.25 + 1.5;
          }
          tree.calcForceAllAndWriteBack(MassSum{}, MassSum{}, ps);
          SCOPED_TRACE(std::string(pt::name(d)) + " theta " + std::to_string(theta) + " opening " +
                       std::to_string(int(o)) + (imports ? " with imports" : ""));
          double worst = 0;
          for (const auto& b : ps) worst = std::max(worst, std::abs(b.pot - total));
          EXPECT_LT(worst, 1e-12 * total);
          EXPECT_GT(tree.blocksVisited(), 0u);
          if (theta == 0.0) {
            // Direct summation: every local and imported particle is a j-particle of every i.
            EXPECT_EQ(tree.interactionsEP(), std::uint64_t(ps.size()) * (ps.size() + (imports ? 500 : 0)));
          }
        }
}

}  // namespace
