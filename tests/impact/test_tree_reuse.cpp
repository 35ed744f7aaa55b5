/// \file test_tree_reuse.cpp
/// \brief One short-range tree build per SPH force evaluation (ShortRangeTree::refresh,
///        buildLike, calcForceOnTreeAndWriteBack, and the masked pass of
///        pik::sph::iterate_smoothing_length) gives the densities of a tree rebuilt for
///        every pass: bit for bit at fixed positions, to rounding after a drift.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <span>
#include <vector>

#include <pik/pik.hpp>
#include <pik/sph/Smoothing.hpp>
#include <pik/sph/SmoothingLength.hpp>

namespace {

using V = pik::Vec3<double>;

struct Dens {
  double rho = 0, drhodh = 0;
  long n = 0;
  void clear() { rho = drhodh = 0, n = 0; }
};
struct Pair {
  double w = 0;
  long n = 0;
  void clear() { w = 0, n = 0; }
};

struct P {
  std::uint32_t id = 0;
  double mass = 1, h = 0, rho = 0, drhodh = 0, h_lo = 0, h_hi = 0, w = 0;
  long n = 0, npair = 0;
  V pos{};
  const V& getPos() const { return pos; }
  void copyFromForce(const Dens& f) { rho = f.rho, drhodh = f.drhodh, n = f.n; }
  void copyFromForce(const Pair& f) { w = f.w, npair = f.n; }
};
struct EP {
  V pos{};
  double h = 0, m = 0;
  const V& getPos() const { return pos; }
  void setPos(const V& x) { pos = x; }  // periodic images
  double getRSearch() const { return h; }
  void copyFromFP(const P& p) { pos = p.pos, h = p.h, m = p.mass; }
};

/// Cubic spline with support h (Monaghan & Lattanzio 1985, normalised in 3D), its h-derivative.
double w3(double r, double h) {
  const double q = r / h, s = 8 / (M_PI * h * h * h);
  if (q >= 1) return 0;
  return q < 0.5 ? s * (1 - 6 * q * q + 6 * q * q * q) : s * 2 * std::pow(1 - q, 3);
}
double dwdh(double r, double h) {
  const double e = 1e-6 * h;
  return (w3(r, h + e) - w3(r, h - e)) / (2 * e);
}

/// Gather density: every candidate tested against h_i.
struct DensityKernel {
  void operator()(const EP* ei, int ni, const EP* ej, int nj, Dens* f) const {
    for (int i = 0; i < ni; ++i)
      for (int j = 0; j < nj; ++j) {
        const double r = pik::norm(ei[i].pos - ej[j].pos);
        if (r >= ei[i].h) continue;
        f[i].rho += ej[j].m * w3(r, ei[i].h), f[i].drhodh += ej[j].m * dwdh(r, ei[i].h), ++f[i].n;
      }
  }
};
/// Symmetric pairs: r < max(h_i, h_j).
struct PairKernel {
  void operator()(const EP* ei, int ni, const EP* ej, int nj, Pair* f) const {
    for (int i = 0; i < ni; ++i)
      for (int j = 0; j < nj; ++j) {
        const double r = pik::norm(ei[i].pos - ej[j].pos), h = std::max(ei[i].h, ej[j].h);
        if (r >= h) continue;
        f[i].w += w3(r, h), ++f[i].n;
      }
  }
};

using GatherTree = pik::ShortRangeTree<Dens, EP, EP, pik::SearchMode::gather>;
using SymTree = pik::ShortRangeTree<Pair, EP, EP, pik::SearchMode::symmetric>;

/// A centrally condensed clump (density falling by ~100 from the centre out), h too large
/// at first so that the iteration needs several passes and most particles settle early.
pik::ParticleSystem<P> clump(int n) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g(0, 1);
  std::uniform_real_distribution<double> u(0.3, 1);
  pik::ParticleSystem<P> ps;
  for (int i = 0; i < n; ++i) {
    P p;
    p.id = std::uint32_t(i);
    p.pos = V{g(rng), g(rng), g(rng)} * u(rng);
    p.h = 0.35;
    ps.add(p);
  }
  return ps;
}

pik::sph::SmoothingLengthParams hparams() { return {.nngb = 50, .tol = 1e-3, .max_passes = 60, .fixed_h = 0}; }

TEST(SphTreeReuse, IterationOnOneTreeEqualsTreePerPass) {
  auto a = clump(6000), b = a;
  GatherTree ta({.n_leaf_limit = 8, .n_group_limit = 32}), tb({.n_leaf_limit = 8, .n_group_limit = 32});
  const DensityKernel k;
  const int pa = pik::sph::iterate_smoothing_length<3>(a, [&] { ta.calcForceAllAndWriteBack(k, a); }, hparams());
  bool first = true;
  long walked = 0, slots = 0;
  const int pb = pik::sph::iterate_smoothing_length<3>(
      b,
      [&](std::span<const std::uint8_t> active) {
        if (first) tb.build(b);
        else tb.refresh(b);
        tb.calcForceOnTreeAndWriteBack(k, b, first ? std::span<const std::uint8_t>{} : active);
        walked += long(tb.groupsWalked()), slots += long(tb.groups().size());
        first = false;
      },
      hparams());
  EXPECT_EQ(pa, pb);
  EXPECT_GT(pa, 3);                // the test exercises several passes
  EXPECT_LT(walked, slots * 3 / 4);  // and the later ones skip most groups
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].h, b[i].h) << i;
    ASSERT_EQ(a[i].rho, b[i].rho) << i;
    ASSERT_EQ(a[i].drhodh, b[i].drhodh) << i;
    ASSERT_EQ(a[i].n, b[i].n) << i;
  }
}

TEST(SphTreeReuse, BuildLikeEqualsBuild) {
  auto a = clump(4000);
  GatherTree td({.n_leaf_limit = 8, .n_group_limit = 32});
  const DensityKernel k;
  pik::sph::iterate_smoothing_length<3>(a, [&] { td.calcForceAllAndWriteBack(k, a); }, hparams());
  td.build(a);
  auto b = a;
  SymTree s1({.n_leaf_limit = 8, .n_group_limit = 32}), s2({.n_leaf_limit = 8, .n_group_limit = 32});
  s1.calcForceAllAndWriteBack(PairKernel{}, a);
  s2.buildLike(td, b);
  s2.calcForceOnTreeAndWriteBack(PairKernel{}, b);
  EXPECT_EQ(s1.interactions(), s2.interactions());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].w, b[i].w) << i;
    ASSERT_EQ(a[i].npair, b[i].npair) << i;
  }
}

TEST(SphTreeReuse, RefreshAfterDriftEqualsRebuildToRounding) {
  auto a = clump(4000);
  GatherTree t({.n_leaf_limit = 8, .n_group_limit = 32});
  const DensityKernel k;
  pik::sph::iterate_smoothing_length<3>(a, [&] { t.calcForceAllAndWriteBack(k, a); }, hparams());
  t.build(a);
  // Every particle moves by up to ~h/2: the old topology is no longer tight, but the
  // recomputed cell boxes keep the search exact.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> d(-0.1, 0.1);
  for (auto& p : a) p.pos += V{d(rng), d(rng), d(rng)};
  auto b = a;
  t.refresh(b);
  t.calcForceOnTreeAndWriteBack(k, b);
  GatherTree fresh({.n_leaf_limit = 8, .n_group_limit = 32});
  fresh.calcForceAllAndWriteBack(k, a);
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].n, b[i].n) << i;  // the same neighbours
    ASSERT_NEAR(a[i].rho, b[i].rho, 1e-13 * a[i].rho) << i;
  }
}

// Kept candidate lists (keepCandidates): the h iteration and a symmetric pass of the same
// step from lists collected once, against a tree walk per pass. The scalar kernels skip
// out-of-reach candidates, so the sums are equal bit for bit.
TEST(SphTreeReuse, KeptListsEqualWalks) {
  for (double margin : {0.0, 0.05}) {
    auto a = clump(6000), b = a;
    GatherTree ta({.n_leaf_limit = 8, .n_group_limit = 32}), tb({.n_leaf_limit = 8, .n_group_limit = 32});
    tb.keepCandidates(margin);
    const DensityKernel k;
    const int pa = pik::sph::iterate_smoothing_length<3>(a, [&] { ta.calcForceAllAndWriteBack(k, a); }, hparams());
    bool first = true;
    const int pb = pik::sph::iterate_smoothing_length<3>(
        b,
        [&](std::span<const std::uint8_t> active) {
          if (first) tb.build(b);
          else tb.refresh(b);
          tb.calcForceOnTreeAndWriteBack(k, b, first ? std::span<const std::uint8_t>{} : active);
          first = false;
        },
        hparams());
    EXPECT_EQ(pa, pb);
    // h starts far off (several passes change it by more than 5 %): the lists are made
    // anew when an h outgrows its reach, and kept otherwise
    EXPECT_GT(tb.keptListSets(), 1u) << margin;
    EXPECT_LT(tb.keptListSets(), std::uint64_t(pb)) << margin;
    for (std::size_t i = 0; i < a.size(); ++i) {
      ASSERT_EQ(a[i].h, b[i].h) << i;
      ASSERT_EQ(a[i].rho, b[i].rho) << i;
      ASSERT_EQ(a[i].n, b[i].n) << i;
    }
    // the symmetric pass of the same step takes the density tree's lists
    SymTree s1({.n_leaf_limit = 8, .n_group_limit = 32}), s2({.n_leaf_limit = 8, .n_group_limit = 32});
    s2.keepCandidates(margin);
    tb.refresh(b);
    tb.calcForceOnTreeAndWriteBack(k, b);  // every list, at reaches no h has outgrown
    const std::uint64_t sets = tb.keptListSets(), collected = tb.keptListsCollected();
    EXPECT_GE(collected, tb.groups().size());  // each list at least once (some again)
    s1.calcForceAllAndWriteBack(PairKernel{}, a);
    s2.buildLike(tb, b);
    s2.calcForceOnTreeAndWriteBack(PairKernel{}, b);
    EXPECT_EQ(s2.keptListSets(), 0u);               // no set of its own
    EXPECT_EQ(tb.keptListsCollected(), collected);  // and no list collected again
    EXPECT_EQ(s2.keptListsCollected(), 0u);         // the lent set is let go after the walk
    EXPECT_EQ(tb.keptListSets(), sets);
    EXPECT_GE(s2.interactions(), s1.interactions());  // a superset (margin, h that shrank)
    for (std::size_t i = 0; i < a.size(); ++i) {
      ASSERT_EQ(a[i].w, b[i].w) << i;
      ASSERT_EQ(a[i].npair, b[i].npair) << i;
    }
    // walked again, the symmetric tree makes its own set; then a few h outgrow their
    // reach: only the lists of the groups within the new reaches are collected again;
    // many: a new set; a moved particle: a new set. Exact each time.
    // (after a move the refreshed tree keeps its old order, a new build sorts anew: the
    // same neighbours, sums to rounding)
    auto check = [&](std::uint64_t sets_wanted, bool moved = false) {
      SCOPED_TRACE("sets " + std::to_string(sets_wanted));
      s2.refresh(b);
      s2.calcForceOnTreeAndWriteBack(PairKernel{}, b);
      s1.calcForceAllAndWriteBack(PairKernel{}, a);
      EXPECT_EQ(s2.keptListSets(), sets_wanted);
      for (std::size_t i = 0; i < a.size(); ++i) {
        if (moved) ASSERT_NEAR(a[i].w, b[i].w, 1e-13 * a[i].w) << i;
        else ASSERT_EQ(a[i].w, b[i].w) << i;
        ASSERT_EQ(a[i].npair, b[i].npair) << i;
      }
    };
    check(1);
    const std::uint64_t before = s2.keptListsCollected();
    EXPECT_EQ(before, s2.groups().size());
    for (auto* ps : {&a, &b}) (*ps)[17].h *= 1.5, (*ps)[4000].h *= 1.3;
    check(1);
    EXPECT_GT(s2.keptListsCollected(), before);
    EXPECT_LT(s2.keptListsCollected(), before + s2.groups().size() / 4);
    for (auto* ps : {&a, &b})
      for (std::size_t i = 0; i < ps->size(); i += 7) (*ps)[i].h *= 1.2;
    check(2);
    for (auto* ps : {&a, &b}) (*ps)[5].pos += V{0.05, 0, 0};
    check(3, true);
  }
}

// Kept lists in a periodic box: the lists hold periodic images (their shifts), the
// symmetric pass takes them through buildLike. Particles near every face, h up to a
// fifth of the box, so that groups see images across the faces.
TEST(SphTreeReuse, KeptListsPeriodic) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0, 1), hr(0.08, 0.2);
  pik::ParticleSystem<P> a;
  for (int i = 0; i < 3000; ++i) {
    P p;
    p.id = std::uint32_t(i);
    p.pos = V{u(rng), u(rng), u(rng)};
    p.h = hr(rng);
    a.add(p);
  }
  auto b = a;
  const auto box = pik::Boundary<3>::periodic_box({0, 0, 0}, {1, 1, 1});
  const pik::TreeParams tp{.n_leaf_limit = 8, .n_group_limit = 32};
  GatherTree ta(tp, box), tb(tp, box);
  SymTree sa(tp, box), sb(tp, box);
  tb.keepCandidates(0), sb.keepCandidates(0);
  ta.calcForceAllAndWriteBack(DensityKernel{}, a);
  sa.calcForceAllAndWriteBack(PairKernel{}, a);
  tb.build(b);
  tb.calcForceOnTreeAndWriteBack(DensityKernel{}, b);
  sb.buildLike(tb, b);
  sb.calcForceOnTreeAndWriteBack(PairKernel{}, b);
  EXPECT_EQ(tb.keptListSets(), 1u);
  EXPECT_EQ(sb.keptListSets(), 0u);  // the density tree's lists
  long periodic = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].n, b[i].n) << i;
    ASSERT_EQ(a[i].rho, b[i].rho) << i;
    ASSERT_EQ(a[i].npair, b[i].npair) << i;
    ASSERT_EQ(a[i].w, b[i].w) << i;
    periodic += b[i].npair;
  }
  // the same particles in open space have fewer pairs: the lists did hold images
  auto c = a;
  SymTree open(tp);
  open.calcForceAllAndWriteBack(PairKernel{}, c);
  long direct = 0;
  for (const auto& p : c) direct += p.npair;
  EXPECT_GT(periodic, direct + direct / 10);

  // Walked again, the symmetric tree makes its own set; then the h of the particles by
  // one face grow past their reach. Their new reaches cross the faces: the groups by
  // the opposite face, which meet them only as images, must collect again too. One set,
  // some lists collected again, the pairs of a walk, bit for bit.
  sb.refresh(b);
  sb.calcForceOnTreeAndWriteBack(PairKernel{}, b);
  ASSERT_EQ(sb.keptListSets(), 1u);
  const std::uint64_t collected = sb.keptListsCollected();
  std::size_t grown = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a[i].pos.x < 0.01) a[i].h *= 1.3, b[i].h *= 1.3, ++grown;
  ASSERT_GT(grown, 15u);
  ASSERT_LT(grown, a.size() / 20);  // below the share that starts a new set
  sa.calcForceAllAndWriteBack(PairKernel{}, a);
  sb.refresh(b);
  sb.calcForceOnTreeAndWriteBack(PairKernel{}, b);
  EXPECT_EQ(sb.keptListSets(), 1u);
  EXPECT_GT(sb.keptListsCollected(), collected);
  EXPECT_LT(sb.keptListsCollected(), collected + sb.groups().size() * 3 / 4);
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].npair, b[i].npair) << i;
    ASSERT_EQ(a[i].w, b[i].w) << i;
  }
}

TEST(SphTreeReuse, Refusals) {
  auto a = clump(100);
  GatherTree t;
  EXPECT_THROW(t.refresh(a), pik::Error);  // never built
  t.build(a);
  std::vector<std::uint8_t> mask(50, 1);
  EXPECT_THROW(t.calcForceOnTreeAndWriteBack(DensityKernel{}, a, mask), pik::Error);
  auto more = clump(120);
  EXPECT_THROW(t.refresh(more), pik::Error);
  EXPECT_THROW(t.calcForceOnTreeAndWriteBack(DensityKernel{}, more), pik::Error);
  SymTree s;
  EXPECT_THROW(s.buildLike(t, more), pik::Error);
  EXPECT_THROW(s.keepCandidates(1.0), pik::Error);
  EXPECT_THROW(s.keepCandidates(std::nan("")), pik::Error);
}

}  // namespace
