// Distributed neighbour search (ShortRangeHalo + ShortRangeTree) at any rank count:
// every particle's neighbour count and neighbour-id sums equal the single-process
// ones exactly, in gather, scatter and symmetric modes, open, periodic and partly
// periodic boxes, radii up to more than half the box, and ranks without particles.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <type_traits>
#include <vector>

#include <pik/Boundary.hpp>
#include <pik/comm/Comm.hpp>
#include <pik/domain/DistributedShortRangeTree.hpp>
#include <pik/domain/DomainInfo.hpp>
#include <pik/domain/ParticleExchange.hpp>
#include <pik/particle/ParticleSystem.hpp>
#include <pik/walk/ShortRangeTree.hpp>

namespace {

using V3 = pik::Vec3<double>;
using pik::SearchMode;

// Neighbour count and two sums of neighbour ids: integers, so exact on any rank
// count and in any order; equal sums mean the same neighbour multiset with high
// probability, not just the same number.
struct Hits {
  std::uint64_t n, s1, s2;
  void clear() { n = s1 = s2 = 0; }
  bool operator==(const Hits&) const = default;
};
struct Body {
  V3 pos;
  double r;
  std::uint64_t id;
  Hits hits;
  const V3& getPos() const { return pos; }
  void setPos(const V3& p) { pos = p; }
  void copyFromForce(const Hits& h) { hits = h; }
};
struct EP {
  V3 pos;
  double r;
  std::uint64_t id;
  const V3& getPos() const { return pos; }
  void setPos(const V3& p) { pos = p; }
  double getRSearch() const { return r; }
  void copyFromFP(const Body& b) { pos = b.pos, r = b.r, id = b.id; }
};

// Single precision: the kernel's float cut must find the same pairs on any rank count.
struct EPf {
  pik::Vec3<float> pos;
  float r;
  std::uint64_t id;
  pik::Vec3<float> getPos() const { return pos; }
  void setPos(const pik::Vec3<float>& p) { pos = p; }
  float getRSearch() const { return r; }
  void copyFromFP(const Body& b) { pos = pik::vec_cast<pik::Vec3<float>>(b.pos), r = float(b.r), id = b.id; }
};

// The exact cut of each mode, as a user kernel applies it (in the EP's precision).
template <SearchMode M, class E = EP>
struct Count {
  void operator()(const E* ei, int ni, const E* ej, int nj, Hits* f) const {
    using T = decltype(ei[0].r);
    for (int i = 0; i < ni; ++i)
      for (int j = 0; j < nj; ++j) {
        const T dx = ei[i].pos.x - ej[j].pos.x, dy = ei[i].pos.y - ej[j].pos.y,
                     dz = ei[i].pos.z - ej[j].pos.z;
        const T r = M == SearchMode::gather    ? ei[i].r
                         : M == SearchMode::scatter ? ej[j].r
                                                    : std::max(ei[i].r, ej[j].r);
        if (dx * dx + dy * dy + dz * dz < r * r) {
          const std::uint64_t k = ej[j].id + 1;
          ++f[i].n, f[i].s1 += k, f[i].s2 += k * k;
        }
      }
  }
};

pik::Comm world() { return pik::Comm::world(); }

pik::Boundary<3> make_boundary(bool px, bool py, bool pz) {
  if (!(px || py || pz)) return pik::Boundary<3>::open();
  return pik::Boundary<3>::periodic_box({0, 0, 0}, {1, 1, 1}, {px, py, pz});
}

// The same particles on every rank: uniform in the unit cube plus a dense clump,
// radii uniform in [rmin, rmax].
std::vector<Body> all_bodies(std::size_t n, double rmin, double rmax, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Body> b;
  for (std::size_t i = 0; i < n; ++i) {
    V3 x{u(rng), u(rng), u(rng)};
    if (i % 5 == 0) x = {0.9 + 0.08 * x.x, 0.05 * x.y, 0.5 + 0.05 * x.z};  // near faces
    b.push_back({x, rmin + (rmax - rmin) * u(rng), i, {}});
  }
  return b;
}

// A deterministic drift by id, wrapped in the periodic dimensions, so that every
// rank and the single-process reference move particles identically.
void drift(Body& b, const pik::Boundary<3>& bd) {
  const double a = 0.37 * double(b.id);
  b.pos = {b.pos.x + 0.2 * std::sin(a), b.pos.y + 0.2 * std::cos(1.3 * a), b.pos.z - 0.15 * std::sin(0.7 * a)};
  b.pos = {bd.wrap(b.pos.x, 0), bd.wrap(b.pos.y, 1), bd.wrap(b.pos.z, 2)};
}

template <SearchMode M, class E>
std::vector<Hits> single_process(const std::vector<Body>& all, const pik::Boundary<3>& bd) {
  pik::ParticleSystem<Body> ps(all);
  pik::ShortRangeTree<Hits, E, E, M> tree({}, bd);
  tree.calcForceAllAndWriteBack(Count<M, E>{}, ps);
  std::vector<Hits> out(all.size());
  for (const Body& b : ps) out[b.id] = b.hits;
  return out;
}

// Two rounds of decompose + exchange + distributed search (with a drift between),
// each compared particle by particle with the single-process search.
template <SearchMode M, class E = EP>
void check_mode(std::vector<Body> all, const pik::Boundary<3>& bd) {
  const auto comm = world();
  pik::ParticleSystem<Body> ps;
  for (const Body& b : all)
    if (int(b.id % std::uint64_t(comm.size())) == comm.rank()) ps.add(b);
  pik::DomainInfo<double, 3> dinfo(comm);
  dinfo.set_root_domain(bd);
  pik::DistributedShortRangeTree<Hits, E, E, M> tree({.n_leaf_limit = 4, .n_group_limit = 16}, bd);
  for (int round = 0; round < 2; ++round) {
    if (round > 0) {
      for (Body& b : all) drift(b, bd);
      for (Body& b : ps) drift(b, bd);
    }
    dinfo.decompose(ps.vector());
    pik::exchange_particles(ps, dinfo);
    tree.calcForceAllAndWriteBack(Count<M, E>{}, ps, comm);
    const auto ref = single_process<M, E>(all, bd);
    std::size_t wrong = 0, pairs = 0;
    for (const Body& b : ps) {
      wrong += !(b.hits == ref[b.id]);
      pairs += b.hits.n;
    }
    EXPECT_EQ(wrong, 0u) << pik::to_string(M) << " round " << round << " on rank " << comm.rank();
    EXPECT_EQ(comm.sum(ps.size()), all.size());
    std::size_t ref_pairs = 0;
    for (const Hits& h : ref) ref_pairs += h.n;
    EXPECT_EQ(comm.sum(pairs), ref_pairs);
    const auto& st = tree.haloStats();
    EXPECT_EQ(comm.sum(st.sent), comm.sum(st.received));
    // The per-particle query sees the imports too (a particle once per image).
    const auto& t = tree.tree();
    std::vector<std::size_t> idx;
    for (std::size_t i = 0; i < std::min<std::size_t>(ps.size(), 8); ++i) {
      E e;
      e.copyFromFP(ps[i]);
      if (M == SearchMode::gather && std::is_same_v<E, EP>) {  // the query's cut is the kernel's
        t.neighbourIndices(e, idx);
        EXPECT_EQ(idx.size(), ps[i].hits.n) << "query of particle id " << ps[i].id;
      }
    }
  }
}

void check_all_modes(const std::vector<Body>& all, const pik::Boundary<3>& bd) {
  check_mode<SearchMode::gather>(all, bd);
  check_mode<SearchMode::scatter>(all, bd);
  check_mode<SearchMode::symmetric>(all, bd);
}

}  // namespace

TEST(ShortRangeHalo, OpenBoxEqualsSingleProcess) {
  check_all_modes(all_bodies(900, 0.03, 0.12, 11), make_boundary(false, false, false));
}

TEST(ShortRangeHalo, PeriodicBoxEqualsSingleProcess) {
  check_all_modes(all_bodies(700, 0.03, 0.15, 12), make_boundary(true, true, true));
}

TEST(ShortRangeHalo, PartlyPeriodicEqualsSingleProcess) {
  check_all_modes(all_bodies(700, 0.05, 0.2, 13), make_boundary(true, false, true));
}

TEST(ShortRangeHalo, RadiusComparableToDomainSize) {
  // Radii up to 0.6 of the periodic box (domains are 0.5 wide at np 8): particles
  // are needed by every rank and reach their neighbours through several images.
  check_all_modes(all_bodies(200, 0.3, 0.6, 14), make_boundary(true, true, true));
  check_all_modes(all_bodies(200, 0.3, 0.6, 15), make_boundary(false, false, false));
}

TEST(ShortRangeHalo, RanksWithoutParticles) {
  // Five particles for up to eight ranks.
  check_all_modes(all_bodies(5, 0.2, 0.7, 16), make_boundary(true, true, true));
  check_all_modes(all_bodies(5, 0.2, 0.4, 17), make_boundary(false, false, false));
  check_all_modes(all_bodies(0, 0.2, 0.4, 18), make_boundary(true, false, false));
}

TEST(ShortRangeHalo, SinglePrecisionEqualsSingleProcess) {
  // Float positions and radii, a float cut in the kernel, and (last case)
  // coordinates far from the origin where float rounding is coarse. (Pairs whose
  // float and double verdicts differ are too rare here to single out the halo's
  // rounding pad: this checks the mixed-precision path, not the pad's size.)
  auto all = all_bodies(600, 0.03, 0.15, 19);
  check_mode<SearchMode::gather, EPf>(all, make_boundary(true, true, true));
  check_mode<SearchMode::symmetric, EPf>(all, make_boundary(true, false, true));
  for (Body& b : all) b.pos = {b.pos.x + 1000, b.pos.y - 3000, b.pos.z + 77};
  check_mode<SearchMode::scatter, EPf>(all, make_boundary(false, false, false));
}
