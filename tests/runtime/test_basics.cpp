// Vectors, boxes, Morton keys, radix sort, the particle system and the profiler.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "support.hpp"

namespace {

TEST(Vec, ArithmeticAndGeometry) {
  pik::Vec3<double> a{1, 2, 3}, b{4, -5, 6};
  EXPECT_EQ(a + b, (pik::Vec3<double>{5, -3, 9}));
  EXPECT_EQ(a - b, (pik::Vec3<double>{-3, 7, -3}));
  EXPECT_EQ(2.0 * a, (pik::Vec3<double>{2, 4, 6}));
  EXPECT_EQ(a / 2.0, (pik::Vec3<double>{0.5, 1, 1.5}));
  EXPECT_DOUBLE_EQ(pik::dot(a, b), 4 - 10 + 18);
  EXPECT_EQ(pik::cross(a, b), (pik::Vec3<double>{27, 6, -13}));
  EXPECT_DOUBLE_EQ(pik::norm(pik::Vec3<double>{3, 4, 12}), 13);
  EXPECT_DOUBLE_EQ(pik::cross(pik::Vec2<double>{1, 0}, pik::Vec2<double>{0, 1}), 1);
  EXPECT_EQ(pik::min(a, b), (pik::Vec3<double>{1, -5, 3}));
  EXPECT_FALSE(pik::isfinite(pik::Vec3<float>{0, NAN, 0}));
  pik::Vec4<float> w{1, 2, 3, 4};
  w += w;
  EXPECT_EQ(w.w, 8);
  static_assert(std::is_aggregate_v<pik::Vec3<double>>);
  static_assert(pik::vec_dim<pik::Vec2<int>>() == 2 && pik::vec_dim<pik::Vec3<int>>() == 3);
}

TEST(Box, ExtendDistanceOverlap) {
  pik::Box<double, 3> b;
  EXPECT_TRUE(b.empty());
  b.extend(pik::Vec3<double>{0, 0, 0});
  b.extend(pik::Vec3<double>{1, 2, 3});
  EXPECT_FALSE(b.empty());
  EXPECT_DOUBLE_EQ(b.max_side(), 3);
  EXPECT_DOUBLE_EQ(b.distance2(pik::Vec3<double>{2, 1, 1}), 1);
  EXPECT_DOUBLE_EQ(b.distance2(pik::Vec3<double>{0.5, 0.5, 0.5}), 0);
  pik::Box<double, 3> c{{3, 4, 5}, {4, 5, 6}};
  EXPECT_FALSE(b.overlaps(c));
  EXPECT_DOUBLE_EQ(b.distance2(c), 4 + 4 + 4);
  EXPECT_TRUE(b.grown(2).overlaps(c));
}

TEST(MortonKey, InterleavesAndOrdersOctants) {
  std::uint64_t q[3] = {1, 0, 0};
  EXPECT_EQ(pik::MortonKey<3>::encode(q), 4u);
  std::uint64_t top[3] = {(1u << 20), 0, (1u << 20)};
  // The top level digit is x:z = 1:1 -> octant 0b101.
  EXPECT_EQ(pik::MortonKey<3>::digit(pik::MortonKey<3>::encode(top), 0), 5u);
  std::uint64_t all[3] = {(1u << 21) - 1, (1u << 21) - 1, (1u << 21) - 1};
  EXPECT_EQ(pik::MortonKey<3>::encode(all), (std::uint64_t(1) << 63) - 1);
  std::uint64_t q2[2] = {(1u << 31) - 1, 0};
  EXPECT_EQ(pik::MortonKey<2>::encode(q2), 0xAAAAAAAAAAAAAAAAULL & ((std::uint64_t(1) << 62) - 1));
}

TEST(RadixSort, MatchesStableSort) {
  std::mt19937_64 g(5);
  std::vector<pik::detail::KeyIndex> a(5000), scratch;
  for (std::uint32_t i = 0; i < a.size(); ++i) a[i] = {g() % 1000 << (i % 3 ? 50 : 2), i};
  auto b = a;
  pik::detail::radix_sort(a, scratch);
  std::stable_sort(b.begin(), b.end(), [](auto& x, auto& y) { return x.key < y.key; });
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_TRUE(a[i].key == b[i].key && a[i].index == b[i].index);
}

TEST(Octree, CellsPartitionParticlesAndGroupsCoverThem) {
  auto ps = pt::make<double>(pt::Dist::clustered, 3000);
  std::vector<pik::Vec3<double>> pos;
  for (auto& b : ps) pos.push_back(b.pos);
  pik::Octree<3> t;
  t.build(pos, {}, 8);
  const auto& cells = t.cells();
  for (const auto& c : cells) {
    if (c.leaf()) {
      EXPECT_TRUE(c.count() <= 8 || c.depth == pik::Octree<3>::max_depth);
      continue;
    }
    std::uint32_t sum = 0, at = c.begin;
    for (std::uint32_t k = c.child; k < c.child + c.n_child; ++k) {
      EXPECT_EQ(cells[k].begin, at);
      at = cells[k].end;
      sum += cells[k].count();
      EXPECT_GT(k, &c - cells.data());  // parents precede children
    }
    EXPECT_EQ(sum, c.count());
  }
  auto groups = t.groups(32);
  std::uint32_t at = 0;
  for (auto g : groups) {
    EXPECT_EQ(g.begin, at);
    EXPECT_LE(g.size(), 32u);
    at = g.end;
  }
  EXPECT_EQ(at, 3000u);
  auto order = t.order();
  std::sort(order.begin(), order.end());
  for (std::uint32_t i = 0; i < order.size(); ++i) ASSERT_EQ(order[i], i);
}

// From 2^16 items the octree splits the subtrees below its top levels on all threads
// and merges them: the cells (breadth first, children contiguous) and the sorted
// order must be exactly what one thread makes, also where keys run out (a clump
// 1e-9 wide gets deeper keys) and where many items sit at one point.
TEST(Octree, ThreadsBuildTheSameTree) {
  const std::size_t n = 70000;
  for (int kind = 0; kind < 3; ++kind) {
    std::vector<pik::Vec3<double>> pos(n);
    std::mt19937_64 rng(17);
    std::uniform_real_distribution<double> u(-1, 1);
    for (std::size_t i = 0; i < n; ++i) {
      pos[i] = {u(rng), u(rng), u(rng)};
      if (kind == 1 && i % 3 == 0) pos[i] = {1e-9 * u(rng), 1e-9 * u(rng), 1e-9 * u(rng)};
      if (kind == 2 && i % 5 == 0) pos[i] = {0.5, 0.5, 0.5};
    }
    const int saved = pik::detail::max_threads();
    pik::Octree<3> one, two;
    pik::detail::set_threads(1);
    one.build(pos, {}, 8);
    pik::detail::set_threads(2);
    two.build(pos, {}, 8);
    pik::detail::set_threads(saved);
    SCOPED_TRACE("distribution " + std::to_string(kind));
    ASSERT_EQ(one.cells().size(), two.cells().size());
    for (std::size_t c = 0; c < one.cells().size(); ++c) {
      const auto &a = one.cells()[c], &b = two.cells()[c];
      ASSERT_TRUE(a.begin == b.begin && a.end == b.end && a.child == b.child && a.n_child == b.n_child &&
                  a.depth == b.depth)
          << "cell " << c;
    }
    EXPECT_EQ(one.order(), two.order());
  }
}

// A loop whose body throws, on two threads: every index still runs, and the error
// rethrown is the one of the lowest index (the one a serial loop meets first), also
// when a higher index on the other thread throws first.
TEST(Threads, ThrowingLoopRethrowsTheLowestIndexError) {
  const std::ptrdiff_t n = 20000;
  const int saved = pik::detail::max_threads();
  pik::detail::set_threads(2);
  std::vector<std::uint8_t> ran(std::size_t(n), 0);
  std::string what;
  try {
    pik::detail::parallel_for_throwing(n, [&](std::ptrdiff_t i) {
      ran[std::size_t(i)] = 1;
      if (i == 17000 || i == 9000 || i == 12000) throw std::runtime_error("index " + std::to_string(i));
    });
  } catch (const std::runtime_error& e) {
    what = e.what();
  }
  pik::detail::set_threads(saved);
  EXPECT_EQ(what, "index 9000");
  EXPECT_EQ(std::count(ran.begin(), ran.end(), 1), n);
}

// checkPositions tests on the threads but names the first bad particle.
TEST(ParticleSystem, CheckPositionsNamesTheFirstBadOne) {
  std::vector<pt::Body<double>> v(20000);
  for (std::size_t i = 0; i < v.size(); ++i) v[i].pos = {double(i), 0, 0};
  pik::ParticleSystem<pt::Body<double>> ps(v);
  const int saved = pik::detail::max_threads();
  pik::detail::set_threads(2);
  EXPECT_NO_THROW(ps.checkPositions());
  ps[15000].pos.z = NAN;
  ps[11000].pos.y = INFINITY;
  try {
    ps.checkPositions();
    ADD_FAILURE() << "no error";
  } catch (const pik::Error& e) {
    EXPECT_NE(std::string(e.what()).find("particle 11000 has a non-finite position"), std::string::npos) << e.what();
  }
  pik::detail::set_threads(saved);
}

TEST(ParticleSystem, AddRemoveSort) {
  pik::ParticleSystem<pt::Body<double>> ps;
  for (int i = 0; i < 10; ++i) {
    pt::Body<double> b;
    b.pos = {double(9 - i), 0, 0};
    b.id = i;
    ps.add(b);
  }
  std::vector<std::size_t> gone{7, 2, 2, 0};
  ps.remove(gone);
  ASSERT_EQ(ps.size(), 7u);
  EXPECT_EQ(ps[0].id, 1);
  EXPECT_EQ(ps[1].id, 3);
  ps.sortByMortonKey();
  for (std::size_t i = 1; i < ps.size(); ++i) EXPECT_LT(ps[i - 1].pos.x, ps[i].pos.x);
  ps.sort([](auto& a, auto& b) { return a.id < b.id; });
  EXPECT_EQ(ps[0].id, 1);
  ps.remove_if([](auto& b) { return b.id > 5; });
  EXPECT_EQ(ps.size(), 4u);  // ids 1, 3, 4, 5
  std::vector<std::size_t> bad{4};
  EXPECT_THROW(ps.remove(bad), pik::Error);
  auto box = pik::Boundary<3>::periodic_box({0, 0, 0}, {2, 2, 2}, {true, false, true});
  ps[0].pos = {-0.5, 7, 4.5};
  ps.wrapPositions(box);
  EXPECT_DOUBLE_EQ(ps[0].pos.x, 1.5);
  EXPECT_DOUBLE_EQ(ps[0].pos.y, 7);
  EXPECT_DOUBLE_EQ(ps[0].pos.z, 0.5);
  // Far outside the box (a blown-up run): still wrapped into [lo, hi), not next to it.
  const auto unit = pik::Boundary<3>::periodic_box({0, 0, 0}, {0.684, 0.684, 0.684});
  for (double x : {-1e17, 1e17, -7.1e22, 3.3e300, -0.684 * 1e9 - 1e-7}) {
    const double y = unit.wrap(x, 0);
    EXPECT_TRUE(y >= 0 && y < 0.684) << x << " -> " << y;
  }
}

TEST(Profiler, NamedRegionsAccumulate) {
  pik::Profiler p;
  { auto s = p.scope("a"); }
  { auto s = p.scope("a"); }
  p.add("b", 1.5);
  ASSERT_EQ(p.regions().size(), 2u);
  EXPECT_EQ(p.regions()[0].calls, 2);
  EXPECT_DOUBLE_EQ(p.seconds("b"), 1.5);
  EXPECT_GE(p.total(), 1.5);
  EXPECT_EQ(p.seconds("missing"), 0);
}

}  // namespace
