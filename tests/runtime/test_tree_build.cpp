// The tree build's pieces against plain references: the radix sort (top digits by
// passes, then runs of equal top bits) against std::stable_sort on large inputs of
// every shape, on one and two threads; the near-order sort (the warm start of a
// rebuild) against std::sort; Morton keys by pdep against the shifts; the octree built
// twice into the same object (kept scratch, warm-started sort) equal to a fresh one,
// after small moves, large moves and a reshuffle; every long-range interaction list
// holds every source exactly once.
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

// The warm start's sort: keys in nearly sorted order (a few displaced, some far),
// equal keys with distinct indices, and an input too scrambled (it must refuse).
TEST(RadixSort, NearlySortedEqualsStdSortOrRefuses) {
  std::mt19937_64 g(11);
  for (std::size_t n : {std::size_t(1), std::size_t(2), std::size_t(1000), std::size_t(100000)})
    for (int shape = 0; shape < 4; ++shape) {
      std::vector<KI> a(n);
      for (std::size_t i = 0; i < n; ++i) a[i] = {shape == 3 ? g() % 5 : (g() >> 1), std::uint32_t((i * 2654435761u) % n)};
      std::sort(a.begin(), a.end(), pik::detail::key_index_less);
      if (shape == 1)  // a few elements moved a short way, a few to anywhere
        for (std::size_t k = 0; k < n / 100; ++k) std::swap(a[g() % n], a[std::min(n - 1, std::size_t(g() % n) + 3)]);
      if (shape == 2)
        for (std::size_t k = 0; k < 3; ++k) std::swap(a[g() % n], a[g() % n]);
      if (shape == 3) std::shuffle(a.begin(), a.end(), g);
      auto b = a;
      std::sort(b.begin(), b.end(), pik::detail::key_index_less);
      std::vector<KI> scratch, aside;
      const bool ok = pik::detail::sort_nearly_sorted(a, scratch, aside, std::max<std::size_t>(n / 8, 16));
      if (shape == 3 && n >= 1000) {
        EXPECT_FALSE(ok) << "n " << n;  // a shuffle puts far more than n/8 aside
        continue;
      }
      ASSERT_TRUE(ok) << "n " << n << " shape " << shape;
      for (std::size_t i = 0; i < n; ++i)
        ASSERT_TRUE(a[i].key == b[i].key && a[i].index == b[i].index) << "n " << n << " shape " << shape << " at " << i;
    }
}

TEST(MortonKey, PdepEqualsShifts) {
#ifdef PIK_MORTON_HAS_PDEP
  if (!__builtin_cpu_supports("bmi2")) GTEST_SKIP() << "no BMI2 on this CPU";
  std::mt19937_64 g(3);
  for (int k = 0; k < 100000; ++k) {
    std::uint64_t q3[3] = {g() & 0x1fffff, g() & 0x1fffff, g() & 0x1fffff};
    if (k == 0) q3[0] = q3[1] = q3[2] = 0x1fffff;
    ASSERT_EQ(pik::MortonKey<3>::encode_pdep(q3), pik::MortonKey<3>::encode_by_shifts(q3));
    ASSERT_EQ(pik::MortonKey<3>::encode(q3), pik::MortonKey<3>::encode_by_shifts(q3));
    std::uint64_t q2[2] = {g() & 0x7fffffff, g() & 0x7fffffff};
    if (k == 0) q2[0] = q2[1] = 0x7fffffff;
    ASSERT_EQ(pik::MortonKey<2>::encode_pdep(q2), pik::MortonKey<2>::encode_by_shifts(q2));
    ASSERT_EQ(pik::MortonKey<2>::encode(q2), pik::MortonKey<2>::encode_by_shifts(q2));
  }
#else
  GTEST_SKIP() << "no pdep on this target";
#endif
}

namespace {
void expect_same_tree(const pik::Octree<3>& kept, const pik::Octree<3>& fresh, const char* what) {
  ASSERT_EQ(kept.cells().size(), fresh.cells().size()) << what;
  for (std::size_t c = 0; c < kept.cells().size(); ++c) {
    const auto &x = kept.cells()[c], &y = fresh.cells()[c];
    ASSERT_TRUE(x.begin == y.begin && x.end == y.end && x.child == y.child && x.n_child == y.n_child &&
                x.depth == y.depth)
        << what << " cell " << c;
  }
  ASSERT_EQ(kept.order(), fresh.order()) << what;
}
}  // namespace

// A rebuild of the same number of items starts from the last build's order (a warm
// start); the tree must be the fresh build's whatever the items did in between:
// moved a little (a leapfrog step), some jumped far, some now share one position
// (equal keys: ties go by index), a tight cluster below the key resolution (re-keyed
// in the split), or all were reshuffled (too far from the old order: sorted anew).
TEST(Octree, WarmRebuildAfterMovesEqualsAFreshBuild) {
  for (int threads : {1, 2}) {
    pik::detail::set_threads(threads);
    for (auto dist : {pt::Dist::uniform, pt::Dist::clustered}) {
      auto ps = pt::make<double>(dist, 60000, 5);
      std::vector<pik::Vec3<double>> pos;
      for (auto& b : ps) pos.push_back(b.pos);
      pik::Octree<3> kept;
      kept.build(pos, {}, 8);
      std::mt19937_64 g(9);
      std::normal_distribution<double> nd(0, 1);
      for (int step = 0; step < 5; ++step) {
        for (auto& x : pos) x += pik::Vec3<double>{nd(g), nd(g), nd(g)} * 1e-4;
        if (step == 1)
          for (int k = 0; k < 200; ++k) pos[g() % pos.size()] = pos[g() % pos.size()];  // shared positions
        if (step == 2)
          for (int k = 0; k < 50; ++k) pos[g() % pos.size()] = {nd(g), nd(g), nd(g)};  // far jumps
        if (step == 3)
          for (int k = 0; k < 300; ++k) pos[std::size_t(k) * 7] = pos[0] + pik::Vec3<double>{nd(g), nd(g), nd(g)} * 1e-12;
        if (step == 4) std::shuffle(pos.begin(), pos.end(), g);
        kept.build(pos, {}, 8);
        pik::Octree<3> fresh;
        fresh.build(pos, {}, 8);
        expect_same_tree(kept, fresh, pt::name(dist));
      }
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

// The split on two threads (top levels serial, the frontier's subtrees on the threads)
// must give the serial split's cells, also where a few far items (an impact's debris)
// put nearly all the others into one cell for several levels or a dense clump keeps one
// cell big past the widest serial level, and the cell array is breadth first (depth
// never decreases: ShortRangeTree's cell passes rely on it).
TEST(Octree, ThreadedSplitEqualsSerialWithFarOutliers) {
  for (auto dist : {pt::Dist::uniform, pt::Dist::clustered}) {
    for (double far : {0.0, 1e3, 1e7}) {
      auto ps = pt::make<double>(dist, 80000, 3);
      std::vector<pik::Vec3<double>> pos;
      for (auto& b : ps) pos.push_back(b.pos);
      if (far > 0)
        for (int k = 0; k < 5; ++k) pos[std::size_t(k) * 1000] = pik::Vec3<double>{far, -far * 0.3 * k, far * 0.1};
      pik::Octree<3> serial, threaded;
      pik::detail::set_threads(1);
      serial.build(pos, {}, 8);
      pik::detail::set_threads(2);
      threaded.build(pos, {}, 8);
      expect_same_tree(threaded, serial, pt::name(dist));
      for (std::size_t c = 1; c < serial.cells().size(); ++c)
        ASSERT_LE(serial.cells()[c - 1].depth, serial.cells()[c].depth) << "cell " << c;
    }
  }
  {
    // a dense clump (1/8 of the items, 10^-6 across) in a uniform cube: the top split
    // ends at a level of more than 8192 cells with the clump's cell still whole
    std::mt19937_64 g(4);
    std::uniform_real_distribution<double> u(0, 1);
    std::vector<pik::Vec3<double>> pos(120000);
    for (std::size_t i = 0; i < pos.size(); ++i) {
      const double s = i % 8 == 0 ? 1e-6 : 1.0, o = i % 8 == 0 ? 0.3 : 0.0;
      pos[i] = {o + s * u(g), o + s * u(g), o + s * u(g)};
    }
    pik::Octree<3> serial, threaded;
    pik::detail::set_threads(1);
    serial.build(pos, {}, 8);
    pik::detail::set_threads(2);
    threaded.build(pos, {}, 8);
    expect_same_tree(threaded, serial, "clump");
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
