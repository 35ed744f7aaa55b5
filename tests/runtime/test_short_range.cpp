// Short-range tree: neighbour lists and kernel candidate lists against brute force,
// for every search mode, open, periodic and partly periodic boundaries.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>

#include "support.hpp"

namespace {

using pt::Accel;
using pt::Body;
using Mode = pik::SearchMode;

/// Brute-force neighbours of particle i: every particle j and periodic image k with
/// |x_i - (x_j + k L)| < r (r by the mode), distances in double as the tree does.
template <class T>
std::vector<std::size_t> brute(const pik::ParticleSystem<Body<T>>& ps, std::size_t i, Mode m,
                               const pik::Boundary<3>& b) {
  std::vector<std::size_t> out;
  int K[3];
  double rmax = 0;
  for (auto& p : ps) rmax = std::max(rmax, double(p.r));
  for (int d = 0; d < 3; ++d) K[d] = b.periodic[d] ? int(std::ceil(rmax / b.period(d))) + 1 : 0;
  for (std::size_t j = 0; j < ps.size(); ++j) {
    double r = m == Mode::gather ? double(ps[i].r)
               : m == Mode::scatter ? double(ps[j].r)
                                    : std::max(double(ps[i].r), double(ps[j].r));
    for (int a = -K[0]; a <= K[0]; ++a)
      for (int c = -K[1]; c <= K[1]; ++c)
        for (int e = -K[2]; e <= K[2]; ++e) {
          const int k[3] = {a, c, e};
          double d2 = 0;
          for (int d = 0; d < 3; ++d) {
            const double s = double(k[d]) * (b.periodic[d] ? b.period(d) : 0.0);
            const double dx = double(ps[i].pos[d]) - (double(ps[j].pos[d]) + s);
            d2 += dx * dx;
          }
          if (d2 < r * r) out.push_back(j);
        }
  }
  return out;
}

template <class T>
pik::ParticleSystem<Body<T>> cloud(int n, double rmin, double rmax, unsigned seed) {
  auto ps = pt::make<T>(pt::Dist::uniform, n, seed);
  std::mt19937 g(seed);
  std::uniform_real_distribution<double> u(rmin, rmax);
  for (auto& p : ps) p.r = T(u(g));
  return ps;
}

struct Case {
  Mode mode;
  bool px, py, pz;
  double rmin, rmax;
};

template <class T>
class ShortRange : public ::testing::Test {};
using Reals = ::testing::Types<float, double>;
TYPED_TEST_SUITE(ShortRange, Reals);

template <class T, Mode M>
void check_case(const Case& c) {
  auto ps = cloud<T>(600, c.rmin, c.rmax, 17);
  const pik::Boundary<3> b = (c.px || c.py || c.pz)
                                 ? pik::Boundary<3>::periodic_box({0, 0, 0}, {1, 1, 1}, {c.px, c.py, c.pz})
                                 : pik::Boundary<3>::open();
  pik::ShortRangeTree<Accel<T>, Body<T>, Body<T>, M> tree({0.5, 4, 16}, b);
  tree.calcForceAllAndWriteBack(pt::CountNeighbours<T, M>{}, ps);
  std::vector<std::size_t> got;
  for (std::size_t i = 0; i < ps.size(); ++i) {
    auto want = brute(ps, i, M, b);
    tree.neighbourIndices(ps[i], got);
    std::sort(got.begin(), got.end());
    ASSERT_EQ(got, want) << "particle " << i;
    if constexpr (std::is_same_v<T, double>) {  // kernel sees shifted copies in T
      ASSERT_EQ(double(ps[i].pot), double(want.size())) << "kernel count, particle " << i;
    }
  }
}

template <class T>
void check_all(const Case& c) {
  SCOPED_TRACE(std::string(pik::to_string(c.mode)) + " periodic " + std::to_string(c.px) +
               std::to_string(c.py) + std::to_string(c.pz) + " r " + std::to_string(c.rmax));
  if (c.mode == Mode::gather) check_case<T, Mode::gather>(c);
  if (c.mode == Mode::scatter) check_case<T, Mode::scatter>(c);
  if (c.mode == Mode::symmetric) check_case<T, Mode::symmetric>(c);
}

TYPED_TEST(ShortRange, NeighbourListsEqualBruteForce) {
  for (Mode m : {Mode::gather, Mode::scatter, Mode::symmetric}) {
    check_all<TypeParam>({m, false, false, false, 0.02, 0.15});
    check_all<TypeParam>({m, true, true, true, 0.02, 0.15});
    check_all<TypeParam>({m, true, false, true, 0.02, 0.15});
  }
}

// Radii larger than the periodic box: every image in range counts.
TYPED_TEST(ShortRange, SearchRadiusLargerThanBox) {
  for (Mode m : {Mode::gather, Mode::symmetric}) {
    check_all<TypeParam>({m, true, true, true, 1.1, 1.6});
    check_all<TypeParam>({m, false, false, false, 1.1, 3.0});
  }
}

template <class T, Mode M>
std::vector<Accel<T>> run_mode(pik::ParticleSystem<Body<T>> ps, const pik::Boundary<3>& b) {
  pik::ShortRangeTree<Accel<T>, Body<T>, Body<T>, M> tree({0.5, 8, 32}, b);
  // A kernel whose result depends on the order of the j's: any difference in the
  // candidate lists shows.
  auto k = [](const Body<T>* pi, int ni, const Body<T>* pj, int nj, Accel<T>* f) {
    for (int i = 0; i < ni; ++i)
      for (int j = 0; j < nj; ++j) {
        auto d = pi[i].pos - pj[j].pos;
        f[i].acc += d * (T(1) + T(j) * T(1e-3));
        f[i].pot = f[i].pot * T(0.5) + pik::norm2(d);
      }
  };
  tree.calcForceAllAndWriteBack(k, ps);
  std::vector<Accel<T>> out;
  for (auto& p : ps) out.push_back({p.acc, p.pot});
  return out;
}

// With one radius for every particle, gather, scatter and symmetric must hand the
// kernel the same candidates in the same order: bitwise identical results.
TYPED_TEST(ShortRange, ModesAgreeBitwiseWithEqualRadii) {
  using T = TypeParam;
  for (bool periodic : {false, true}) {
    auto ps = cloud<T>(800, 0.08, 0.08, 23);
    auto b = periodic ? pik::Boundary<3>::periodic_box({0, 0, 0}, {1, 1, 1}) : pik::Boundary<3>::open();
    auto g = run_mode<T, Mode::gather>(ps, b);
    auto s = run_mode<T, Mode::scatter>(ps, b);
    auto y = run_mode<T, Mode::symmetric>(ps, b);
    EXPECT_EQ(std::memcmp(g.data(), s.data(), g.size() * sizeof(g[0])), 0) << "periodic " << periodic;
    EXPECT_EQ(std::memcmp(g.data(), y.data(), g.size() * sizeof(g[0])), 0) << "periodic " << periodic;
  }
}

TYPED_TEST(ShortRange, ThreadCountAndReuse) {
  using T = TypeParam;
  auto ps = cloud<T>(1000, 0.03, 0.1, 29);
  auto b = pik::Boundary<3>::periodic_box({0, 0, 0}, {1, 1, 1});
  pik::ShortRangeTree<Accel<T>, Body<T>, Body<T>, Mode::symmetric> tree({0.5, 8, 32}, b);
  pt::CountNeighbours<T, Mode::symmetric> k;
  const int saved = pik::detail::max_threads();
  pik::detail::set_threads(1);
  tree.calcForceAllAndWriteBack(k, ps, pik::ListMode::make_for_reuse);
  std::vector<T> one;
  for (auto& p : ps) one.push_back(p.pot);
  pik::detail::set_threads(2);
  tree.calcForceAllAndWriteBack(k, ps, pik::ListMode::reuse);
  for (std::size_t i = 0; i < ps.size(); ++i) ASSERT_EQ(one[i], ps[i].pot);
  tree.calcForceAllAndWriteBack(k, ps);
  pik::detail::set_threads(saved);
  for (std::size_t i = 0; i < ps.size(); ++i) ASSERT_EQ(one[i], ps[i].pot);
}

// ---- candidate lists: what each kernel call gets, in order, against brute force ----

/// One candidate as a kernel saw it: the particle's id and its (shifted) position.
template <class T>
struct Seen {
  long id;
  pik::Vec3<T> pos;
  bool operator==(const Seen&) const = default;
};

/// Records every kernel call's candidate list under the index of its first i-particle.
template <class T>
struct Recorder {
  const Body<T>* epi0;
  std::vector<std::vector<Seen<T>>>* out;
  void operator()(const Body<T>* pi, int, const Body<T>* pj, int nj, Accel<T>*) const {
    auto& v = (*out)[std::size_t(pi - epi0)];
    v.clear();
    for (int j = 0; j < nj; ++j) v.push_back({pj[j].id, pj[j].pos});
  }
};

/// The candidate list of one group by brute force, as ShortRangeTree.hpp defines it: for
/// every periodic image of the tree's box that can reach the group's search box (first
/// dimension slowest, shifts ascending), every j-particle in the tree's order (leaves
/// depth first, a leaf's local then imported particles) whose distance to the group's
/// bounding box is at most its radius by the mode (gather r_i,max; scatter r_j;
/// symmetric the larger), times (1 + 1e-12) on the square. No cell is pruned.
template <class T, Mode M, class Tree>
std::vector<Seen<T>> brute_candidates(const Tree& tree, const pik::IndexRange& grp, const pik::Boundary<3>& b) {
  const auto epi = tree.sortedEPI();
  const auto epj = tree.sortedEPJ();
  const std::size_t nl = tree.numberOfLocalParticles();
  auto dv = [](const pik::Vec3<T>& x) { return pik::Vec3<double>{double(x.x), double(x.y), double(x.z)}; };
  pik::Box<double, 3> g, all;
  double ri = 0, rmax = 0;
  for (std::uint32_t i = grp.begin; i < grp.end; ++i) {
    g.extend(dv(epi[i].pos));
    if (M != Mode::scatter) ri = std::max(ri, double(epi[i].r));
  }
  for (const auto& p : epj) all.extend(dv(p.pos)), rmax = std::max(rmax, double(p.r));
  // the tree's order: leaves depth first
  std::vector<std::size_t> order;
  const auto& cells = tree.octree().cells();
  std::vector<std::uint32_t> st{0};
  while (!st.empty()) {
    const auto& c = cells[st.back()];
    st.pop_back();
    if (c.leaf()) {
      for (std::uint32_t j = c.kind_begin[0]; j < c.kind_end[0]; ++j) order.push_back(j);
      for (std::uint32_t j = c.kind_begin[1]; j < c.kind_end[1]; ++j) order.push_back(nl + j);
    } else {
      for (std::uint32_t k = c.n_child; k-- > 0;) st.push_back(c.child + k);
    }
  }
  EXPECT_EQ(order.size(), epj.size());
  constexpr double slack = 1 + 1e-12;
  const double reach = M == Mode::gather ? ri : std::max(ri, rmax);
  const auto search = g.grown(reach * slack);
  std::vector<pik::Vec3<double>> shifts{{0, 0, 0}};
  for (int d = 0; d < 3; ++d) {
    if (!b.periodic[d]) continue;
    const double L = b.period(d);
    // one image more on each side than can reach the search box: an image the walk
    // wrongly skips shows up here (images out of reach add no candidate, so the order holds)
    const long k0 = long(std::floor((search.lo[d] - all.hi[d]) / L)) - 1;
    const long k1 = long(std::ceil((search.hi[d] - all.lo[d]) / L)) + 1;
    std::vector<pik::Vec3<double>> next;
    for (const auto& s : shifts)
      for (long k = k0; k <= k1; ++k) {
        auto t = s;
        t[d] = double(k) * L;
        next.push_back(t);
      }
    shifts.swap(next);
  }
  std::vector<Seen<T>> out;
  for (const auto& sh : shifts)
    for (std::size_t j : order) {
      const auto& p = epj[j];
      const double r = M == Mode::gather ? ri : M == Mode::scatter ? double(p.r) : std::max(ri, double(p.r));
      if (g.distance2(dv(p.pos) + sh) <= r * r * slack) {
        const bool zero = sh[0] == 0 && sh[1] == 0 && sh[2] == 0;
        pik::Vec3<T> x = p.pos;
        if (!zero) x = {T(double(x.x) + sh[0]), T(double(x.y) + sh[1]), T(double(x.z) + sh[2])};
        out.push_back({p.id, x});
      }
    }
  return out;
}

/// Imported j-particles: copies of local ones moved by (0.37, 0, 0) with their own ids
/// (kept inside the unit box where it is periodic: wrapped along x).
template <class T>
std::vector<Body<T>> some_imports(const pik::ParticleSystem<Body<T>>& ps, int every) {
  std::vector<Body<T>> imp;
  for (std::size_t i = 0; i < ps.size(); i += std::size_t(every)) {
    Body<T> q = ps[i];
    q.id = long(ps.size() + imp.size());
    q.pos.x = T(std::fmod(double(q.pos.x) + 0.37, 1.0));
    imp.push_back(q);
  }
  return imp;
}

template <class T, Mode M>
void check_candidates(pik::Boundary<3> b, pt::Dist dist, double rmin, double rmax, bool imports) {
  SCOPED_TRACE(std::string(pik::to_string(M)) + " periodic " + std::to_string(b.any_periodic()) + " dist " +
               pt::name(dist) + " r " + std::to_string(rmin) + ".." + std::to_string(rmax) + " imports " +
               std::to_string(imports));
  auto ps = pt::make<T>(dist, 1500, 41);
  std::mt19937 rng(43);
  std::uniform_real_distribution<double> u(rmin, rmax);
  for (std::size_t i = 0; i < ps.size(); ++i) ps[i].r = T(u(rng)), ps[i].id = long(i);
  if (b.any_periodic()) ps.wrapPositions(b);
  pik::ShortRangeTree<Accel<T>, Body<T>, Body<T>, M> tree({0.5, 8, 32}, b);
  if (imports) tree.setImportedParticles(some_imports(ps, 7));
  tree.build(ps);
  std::vector<std::vector<Seen<T>>> got(ps.size());
  tree.calcForceOnTreeAndWriteBack(Recorder<T>{tree.sortedEPI().data(), &got}, ps);
  for (const auto& grp : tree.groups()) {
    const auto want = brute_candidates<T, M>(tree, grp, b);
    ASSERT_EQ(got[grp.begin].size(), want.size()) << "group at " << grp.begin;
    ASSERT_TRUE(got[grp.begin] == want) << "group at " << grp.begin << ": same candidates, other order";
  }
}

// The lists the kernels get are the brute-force candidates, in the same order (the
// tree's order), for every mode, with periodic images and imported particles, on
// uniform and clustered particles with radii from small to larger than the leaves.
TYPED_TEST(ShortRange, CandidateListsEqualBruteForceInOrder) {
  using T = TypeParam;
  const auto open = pik::Boundary<3>::open();
  const auto per = pik::Boundary<3>::periodic_box({0, 0, 0}, {1, 1, 1});
  const auto part = pik::Boundary<3>::periodic_box({0, 0, 0}, {1, 1, 1}, {true, false, true});
  for (auto dist : {pt::Dist::uniform, pt::Dist::clustered})
    for (bool imp : {false, true}) {
      check_candidates<T, Mode::gather>(open, dist, 0.02, 0.12, imp);
      check_candidates<T, Mode::symmetric>(open, dist, 0.02, 0.12, imp);
      check_candidates<T, Mode::scatter>(open, dist, 0.02, 0.12, imp);
    }
  for (bool imp : {false, true}) {
    check_candidates<T, Mode::gather>(per, pt::Dist::uniform, 0.05, 0.3, imp);
    check_candidates<T, Mode::symmetric>(per, pt::Dist::uniform, 0.01, 0.08, imp);
    check_candidates<T, Mode::scatter>(part, pt::Dist::uniform, 0.01, 0.08, imp);
  }
}

/// An order-sensitive kernel's results: any change in the candidate lists shows.
template <class T>
struct OrderSensitive {
  void operator()(const Body<T>* pi, int ni, const Body<T>* pj, int nj, Accel<T>* f) const {
    for (int i = 0; i < ni; ++i)
      for (int j = 0; j < nj; ++j) {
        auto d = pi[i].pos - pj[j].pos;
        f[i].acc += d * (T(1) + T(j) * T(1e-3));
        f[i].pot = f[i].pot * T(0.5) + pik::norm2(d) + T(pj[j].r);
      }
  }
};
template <class T>
std::vector<T> results(const pik::ParticleSystem<Body<T>>& ps) {
  std::vector<T> v;
  for (const auto& p : ps) v.push_back(p.pot), v.push_back(p.acc.x), v.push_back(p.acc.z);
  return v;
}

// refresh() and buildLike() on trees that hold imported particles (e.g. wall images):
// new radii for local and imported particles give what a new build gives, bit for bit.
TYPED_TEST(ShortRange, RefreshAndBuildLikeWithImports) {
  using T = TypeParam;
  const auto b = pik::Boundary<3>::periodic_box({0, 0, 0}, {1, 1, 1}, {true, true, false});
  auto ps = cloud<T>(1200, 0.03, 0.09, 51);
  for (std::size_t i = 0; i < ps.size(); ++i) ps[i].id = long(i);
  ps.wrapPositions(b);
  auto imp = some_imports(ps, 5);
  pik::ShortRangeTree<Accel<T>, Body<T>, Body<T>, Mode::gather> dens({0.5, 8, 32}, b);
  pik::ShortRangeTree<Accel<T>, Body<T>, Body<T>, Mode::symmetric> hyd({0.5, 8, 32}, b), fresh_h({0.5, 8, 32}, b);
  pik::ShortRangeTree<Accel<T>, Body<T>, Body<T>, Mode::gather> fresh_d({0.5, 8, 32}, b);
  dens.setImportedParticles(imp);
  dens.build(ps);
  // new radii, the imports' following their originals'
  for (auto& p : ps) p.r = T(double(p.r) * 1.13);
  for (std::size_t k = 0; k < imp.size(); ++k) imp[k].r = ps[5 * k].r;
  dens.setImportedParticles(imp);
  dens.refresh(ps);
  auto a = ps;
  dens.calcForceOnTreeAndWriteBack(OrderSensitive<T>{}, a);
  fresh_d.setImportedParticles(imp);
  auto c = ps;
  fresh_d.calcForceAllAndWriteBack(OrderSensitive<T>{}, c);
  EXPECT_TRUE(results(a) == results(c)) << "refresh with imports against a new build";
  hyd.setImportedParticles(imp);
  hyd.buildLike(dens, ps);
  auto h1 = ps;
  hyd.calcForceOnTreeAndWriteBack(OrderSensitive<T>{}, h1);
  fresh_h.setImportedParticles(imp);
  auto h2 = ps;
  fresh_h.calcForceAllAndWriteBack(OrderSensitive<T>{}, h2);
  EXPECT_TRUE(results(h1) == results(h2)) << "buildLike with imports against a new build";
  // a different number of imports is refused
  imp.pop_back();
  hyd.setImportedParticles(imp);
  EXPECT_THROW(hyd.buildLike(dens, ps), pik::Error);
  dens.setImportedParticles(imp);
  EXPECT_THROW(dens.refresh(ps), pik::Error);
}

// refresh(ps, changed), the smoothing-length pass's refresh (new radii for a few
// particles, the same positions), gives what refresh(ps) and a new build give, bit for
// bit, in gather and symmetric mode, with candidate lists kept or not; a changed particle
// that moved, a flag array of the wrong length and a tree with imports are refused.
template <class T, Mode M>
void check_refresh_changed(double keep) {
  const auto b = pik::Boundary<3>::periodic_box({0, 0, 0}, {1, 1, 1}, {true, true, false});
  auto ps = cloud<T>(1500, 0.03, 0.09, 77);
  for (std::size_t i = 0; i < ps.size(); ++i) ps[i].id = long(i);
  ps.wrapPositions(b);
  pik::ShortRangeTree<Accel<T>, Body<T>, Body<T>, M> part({0.5, 8, 32}, b), full({0.5, 8, 32}, b), fresh({0.5, 8, 32}, b);
  if (keep >= 0) part.keepCandidates(keep), full.keepCandidates(keep);
  part.build(ps), full.build(ps);
  auto a0 = ps, c0 = ps;  // lists collected at the old radii, where kept
  part.calcForceOnTreeAndWriteBack(OrderSensitive<T>{}, a0);
  full.calcForceOnTreeAndWriteBack(OrderSensitive<T>{}, c0);
  std::vector<std::uint8_t> changed(ps.size(), 0);
  for (std::size_t i = 0; i < ps.size(); i += 7) {  // some grow (past the lists' reach), some shrink
    changed[i] = 1;
    ps[i].r = T(double(ps[i].r) * (i % 2 ? 2.0 : 0.8));
  }
  part.refresh(ps, changed);
  full.refresh(ps);
  auto a = ps, c = ps, d = ps;
  part.calcForceOnTreeAndWriteBack(OrderSensitive<T>{}, a);
  full.calcForceOnTreeAndWriteBack(OrderSensitive<T>{}, c);
  fresh.calcForceAllAndWriteBack(OrderSensitive<T>{}, d);
  EXPECT_TRUE(results(a) == results(c)) << "refresh of the changed particles against refresh of all";
  if (keep < 0) {
    EXPECT_TRUE(results(a) == results(d)) << "refresh of the changed particles against a new build";
  }
  auto moved = ps;
  moved[14].pos.x = T(double(moved[14].pos.x) * 0.5 + 0.25);
  EXPECT_THROW(part.refresh(moved, changed), pik::Error);  // particle 14 is flagged (14 = 2 x 7)
  changed.pop_back();
  EXPECT_THROW(part.refresh(ps, changed), pik::Error);
}

TYPED_TEST(ShortRange, RefreshOfChangedParticlesEqualsAFullRefresh) {
  using T = TypeParam;
  for (double keep : {-1.0, 0.0, 0.05}) {
    check_refresh_changed<T, Mode::gather>(keep);
    check_refresh_changed<T, Mode::symmetric>(keep);
  }
  // a tree with imported particles refreshes whole (their contents come with refresh(ps))
  auto ps = cloud<T>(300, 0.03, 0.09, 5);
  pik::ShortRangeTree<Accel<T>, Body<T>, Body<T>, Mode::gather> t({0.5, 8, 32});
  t.setImportedParticles(some_imports(ps, 5));
  t.build(ps);
  std::vector<std::uint8_t> changed(ps.size(), 1);
  EXPECT_THROW(t.refresh(ps, changed), pik::Error);
}

TEST(ShortRangeErrors, ParticleOutsidePeriodicBoxIsNamed) {
  auto ps = cloud<double>(20, 0.1, 0.1, 3);
  ps[13].pos.y = 1.5;
  pik::ShortRangeTree<Accel<double>, Body<double>, Body<double>, Mode::gather> tree(
      {}, pik::Boundary<3>::periodic_box({0, 0, 0}, {1, 1, 1}));
  try {
    tree.build(ps);
    FAIL() << "no error";
  } catch (const pik::Error& e) {
    EXPECT_NE(std::string(e.what()).find("particle 13 lies outside the periodic box"), std::string::npos)
        << e.what();
  }
}

}  // namespace
