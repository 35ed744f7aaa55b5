// Domain decomposition and particle exchange at any rank count: conservation
// through many decompositions and drifts, load balance, cost weighting, empty
// ranks, periodic wrapping and open boundaries.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include <pik/Vec.hpp>
#include <pik/comm/Comm.hpp>
#include <pik/domain/DomainInfo.hpp>
#include <pik/domain/ParticleExchange.hpp>

namespace {

using V3 = pik::Vec3<double>;

struct Particle {
  V3 pos;
  V3 vel;
  double mass;
  std::uint64_t id;
};

// An FDPS-style particle: position only through getPos/setPos.
class FdpsParticle {
 public:
  V3 getPos() const { return r_; }
  void setPos(const V3& r) { r_ = r; }
  std::uint64_t id = 0;

 private:
  V3 r_{};
};

using Domain = pik::DomainInfo<double, 3>;

pik::Comm world() { return pik::Comm::world(); }

// Particles with integer masses and velocities, so that sums are exact whatever the
// order: conservation can be checked with ==.
std::vector<Particle> make_particles(const pik::Comm& comm, std::size_t n_local, double lo,
                                     double hi, std::uint64_t first_id, unsigned seed) {
  std::mt19937_64 rng(seed + 7919u * unsigned(comm.rank()));
  std::uniform_real_distribution<double> x(lo, hi);
  std::uniform_int_distribution<int> m(1, 8), v(-100, 100);
  std::vector<Particle> ps(n_local);
  for (std::size_t i = 0; i < n_local; ++i) {
    ps[i].pos = {x(rng), x(rng), x(rng)};
    ps[i].vel = {double(v(rng)), double(v(rng)), double(v(rng))};
    ps[i].mass = m(rng);
    ps[i].id = first_id + i;
  }
  return ps;
}

struct Totals {
  std::uint64_t count;
  double mass;
  V3 momentum;
};

Totals totals(const pik::Comm& comm, const std::vector<Particle>& ps) {
  double m = 0;
  V3 p{};
  for (const auto& q : ps) {
    m += q.mass;
    p.x += q.mass * q.vel.x;
    p.y += q.mass * q.vel.y;
    p.z += q.mass * q.vel.z;
  }
  return {comm.sum(std::uint64_t(ps.size())), comm.sum(m), comm.sum(p)};
}

void expect_same(const Totals& a, const Totals& b) {
  EXPECT_EQ(a.count, b.count);
  EXPECT_EQ(a.mass, b.mass);
  EXPECT_EQ(a.momentum.x, b.momentum.x);
  EXPECT_EQ(a.momentum.y, b.momentum.y);
  EXPECT_EQ(a.momentum.z, b.momentum.z);
}

// Every id 0..n-1 exists exactly once across the ranks.
void expect_ids_complete(const pik::Comm& comm, const std::vector<Particle>& ps, std::uint64_t n) {
  std::vector<std::uint64_t> ids;
  for (const auto& p : ps) ids.push_back(p.id);
  auto all = comm.gatherv(std::span<const std::uint64_t>(ids), 0);
  if (!comm.is_root()) return;
  std::sort(all.begin(), all.end());
  ASSERT_EQ(all.size(), n);
  for (std::uint64_t i = 0; i < n; ++i) {
    if (all[i] != i) {
      ADD_FAILURE() << "id " << i << " missing or duplicated";
      return;
    }
  }
}

// Every local particle lies in this rank's domain (and inside the periodic box).
template <class P>
void expect_owned(const Domain& dom, const std::vector<P>& ps) {
  const int me = dom.comm().rank();
  const auto box = dom.domain(me);
  std::size_t bad = 0;
  for (const auto& p : ps) {
    const V3 x = pik::domain_detail::position(p);
    if (dom.owner(x) != me || !box.contains(x)) ++bad;
  }
  EXPECT_EQ(bad, 0u) << "particles on rank " << me << " outside its domain";
}

void drift(std::vector<Particle>& ps, std::mt19937_64& rng, double scale) {
  std::normal_distribution<double> g(0.0, scale);
  for (auto& p : ps) {
    p.pos.x += g(rng);
    p.pos.y += g(rng);
    p.pos.z += g(rng);
  }
}

// Uneven start: rank r holds 40 * (r % 3) particles (so rank 0 holds none).
std::vector<Particle> uneven_start(const pik::Comm& comm, double lo, double hi, std::uint64_t& n) {
  std::uint64_t first = 0;
  for (int r = 0; r < comm.rank(); ++r) first += 40u * unsigned(r % 3);
  n = 0;
  for (int r = 0; r < comm.size(); ++r) n += 40u * unsigned(r % 3);
  if (comm.size() == 1) n = 300;
  const std::size_t mine = comm.size() == 1 ? 300u : 40u * unsigned(comm.rank() % 3);
  return make_particles(comm, mine, lo, hi, first, 11);
}

void run_conservation(Domain& dom, double lo, double hi, double step, bool periodic) {
  const auto comm = dom.comm();
  std::uint64_t n = 0;
  auto ps = uneven_start(comm, lo, hi, n);
  const Totals t0 = totals(comm, ps);
  std::mt19937_64 rng(1234 + unsigned(comm.rank()));
  for (int it = 0; it < 25; ++it) {
    dom.decompose(ps);
    pik::exchange_particles(ps, dom);
    expect_same(totals(comm, ps), t0);
    expect_owned(dom, ps);
    if (periodic) {
      for (const auto& p : ps) {
        ASSERT_TRUE(p.pos.x >= lo && p.pos.x < hi && p.pos.y >= lo && p.pos.y < hi &&
                    p.pos.z >= lo && p.pos.z < hi);
      }
    }
    drift(ps, rng, step);
    // Exchange again without decomposing: particles that drifted out move too.
    pik::exchange_particles(ps, dom);
    expect_owned(dom, ps);
  }
  expect_same(totals(comm, ps), t0);
  expect_ids_complete(comm, ps, n);
}

}  // namespace

TEST(Exchange, ConservesEverythingOpen) {
  Domain dom(world());
  run_conservation(dom, -1.0, 1.0, 0.3, false);
}

TEST(Exchange, ConservesEverythingPeriodic) {
  Domain dom(world());
  dom.set_periodic_box({{-1.0, -1.0, -1.0}, {1.0, 1.0, 1.0}});
  // Drifts as large as the box, so particles cross it (and its images) often.
  run_conservation(dom, -1.0, 1.0, 0.8, true);
}

TEST(Exchange, ConservesEverythingPartlyPeriodicWithSmoothing) {
  Domain::Options opt;
  opt.smoothing = 0.3;
  opt.samples_per_rank = 64;
  Domain dom(world(), opt);
  dom.set_root_domain({{0.0, 0.0, 0.0}, {2.0, 2.0, 0.0}}, {true, true, false});
  std::uint64_t n = 0;
  auto ps = uneven_start(world(), 0.0, 2.0, n);
  const Totals t0 = totals(world(), ps);
  std::mt19937_64 rng(99 + unsigned(world().rank()));
  for (int it = 0; it < 20; ++it) {
    dom.decompose(ps);
    pik::exchange_particles(ps, dom);
    expect_owned(dom, ps);
    for (const auto& p : ps) ASSERT_TRUE(p.pos.x >= 0 && p.pos.x < 2 && p.pos.y >= 0 && p.pos.y < 2);
    drift(ps, rng, 0.5);
  }
  pik::exchange_particles(ps, dom);
  expect_same(totals(world(), ps), t0);
  expect_ids_complete(world(), ps, n);
}

TEST(Exchange, WorksOnGetPosSetPosParticles) {
  Domain dom(world());
  dom.set_periodic_box({{0, 0, 0}, {1, 1, 1}});
  std::vector<FdpsParticle> ps(world().rank() == 0 ? 200 : 0);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> x(-3.0, 3.0);
  for (std::size_t i = 0; i < ps.size(); ++i) {
    ps[i].setPos({x(rng), x(rng), x(rng)});
    ps[i].id = i;
  }
  const auto st = pik::exchange_particles(ps, dom);  // before any decompose: rank 0 owns all
  EXPECT_EQ(st.sent, 0u);
  EXPECT_EQ(st.wrapped, world().rank() == 0 ? 200u : 0u);  // x in [-3,3) is almost surely outside [0,1)^3
  dom.decompose(ps);
  pik::exchange_particles(ps, dom);
  expect_owned(dom, ps);
  EXPECT_EQ(world().sum(ps.size()), 200u);
}

TEST(Decomposition, BalancesUniformParticles) {
  const auto comm = world();
  Domain dom(comm);
  auto ps = make_particles(comm, 1000, 0.0, 1.0, 1000u * unsigned(comm.rank()), 3);
  dom.decompose(ps);
  pik::exchange_particles(ps, dom);
  const double mean = 1000.0;
  EXPECT_LE(comm.max(double(ps.size())) / mean, 1.2);
  EXPECT_GE(comm.min(double(ps.size())) / mean, 0.8);
}

TEST(Decomposition, AllParticlesStartOnOneRank) {
  const auto comm = world();
  Domain dom(comm);
  auto ps = make_particles(comm, comm.rank() == 0 ? 4000 : 0, 0.0, 1.0, 0, 4);
  const Totals t0 = totals(comm, ps);
  dom.decompose(ps);
  pik::exchange_particles(ps, dom);
  expect_same(totals(comm, ps), t0);
  expect_owned(dom, ps);
  EXPECT_LE(comm.max(double(ps.size())) / (4000.0 / comm.size()), 1.25);
}

TEST(Decomposition, FewerParticlesThanRanks) {
  const auto comm = world();
  Domain dom(comm);
  // Three particles in all, on the last rank: most ranks end up empty.
  auto ps = make_particles(comm, comm.rank() == comm.size() - 1 ? 3 : 0, 0.0, 1.0, 0, 5);
  const Totals t0 = totals(comm, ps);
  for (int it = 0; it < 3; ++it) {
    dom.decompose(ps);
    pik::exchange_particles(ps, dom);
    expect_owned(dom, ps);
  }
  expect_same(totals(comm, ps), t0);
  expect_ids_complete(comm, ps, 3);
  // With no particles anywhere, decompose keeps the domains and nothing breaks.
  std::vector<Particle> none;
  Domain empty(comm);
  empty.decompose(none);
  pik::exchange_particles(none, empty);
  EXPECT_EQ(empty.decompositions(), 0);
}

TEST(Decomposition, SlowRankGetsFewerParticles) {
  const auto comm = world();
  if (comm.size() == 1) GTEST_SKIP() << "needs two ranks or more";
  const int slow = comm.size() - 1;
  Domain dom(comm);
  auto ps = make_particles(comm, 2000, 0.0, 1.0, 2000u * unsigned(comm.rank()), 6);
  dom.decompose(ps);
  pik::exchange_particles(ps, dom);
  const double before = double(comm.broadcast(ps.size(), slow));
  // The slow rank takes 4× as long per particle; costs are reported per rank.
  auto cost_of = [&](const std::vector<Particle>& q) {
    return double(q.size()) * (comm.rank() == slow ? 4.0 : 1.0);
  };
  dom.decompose(ps, cost_of(ps));
  pik::exchange_particles(ps, dom);
  const double after = double(comm.broadcast(ps.size(), slow));
  EXPECT_LT(after, 0.7 * before);
  // Repeated steps converge to equal cost, not equal count.
  for (int it = 0; it < 6; ++it) {
    dom.decompose(ps, cost_of(ps));
    pik::exchange_particles(ps, dom);
  }
  const double c = cost_of(ps);
  const double mean_cost = comm.sum(c) / comm.size();
  EXPECT_LE(comm.max(c) / mean_cost, 1.3);
  const double n_slow = double(comm.broadcast(ps.size(), slow));
  const double n_mean = double(comm.sum(ps.size())) / comm.size();
  EXPECT_LT(n_slow, 0.5 * n_mean);
  EXPECT_GT(n_slow, 0.1 * n_mean);
}

TEST(Decomposition, SmoothingMovesPartway) {
  const auto comm = world();
  if (comm.size() == 1) GTEST_SKIP() << "needs two ranks or more";
  const int slow = comm.size() - 1;
  auto run = [&](double smoothing) {
    Domain::Options opt;
    opt.smoothing = smoothing;
    Domain dom(comm, opt);
    auto ps = make_particles(comm, 2000, 0.0, 1.0, 0, 8);
    dom.decompose(ps);
    pik::exchange_particles(ps, dom);
    const double before = double(comm.broadcast(ps.size(), slow));
    dom.decompose(ps, double(ps.size()) * (comm.rank() == slow ? 4.0 : 1.0));
    pik::exchange_particles(ps, dom);
    return std::pair{before, double(comm.broadcast(ps.size(), slow))};
  };
  const auto [b1, full] = run(1.0);
  const auto [b2, half] = run(0.5);
  EXPECT_EQ(b1, b2);  // same seed, same first decomposition
  EXPECT_LT(full, half);
  EXPECT_LT(half, b2);
}

TEST(Boundaries, PeriodicWrapsAnOutsideParticle) {
  const auto comm = world();
  Domain dom(comm);
  dom.set_periodic_box({{0, 0, 0}, {1, 1, 1}});
  auto ps = make_particles(comm, 100, 0.0, 1.0, 1 + 100u * unsigned(comm.rank()), 9);
  dom.decompose(ps);
  std::vector<Particle> odd = ps;
  if (comm.rank() == 0) odd.push_back({{1.5, -0.25, 3.0}, {1, 2, 3}, 1.0, 0});
  pik::exchange_particles(odd, dom);
  const V3 expected{0.5, 0.75, 0.0};
  int found = 0;
  for (const auto& p : odd) {
    if (p.id != 0) continue;
    ++found;
    EXPECT_EQ(p.pos.x, expected.x);
    EXPECT_EQ(p.pos.y, expected.y);
    EXPECT_EQ(p.pos.z, expected.z);
    EXPECT_EQ(comm.rank(), dom.owner(expected));
  }
  EXPECT_EQ(comm.sum(found), 1);
  // Exact multiples of the period and values just below the box.
  V3 a{-1.0, 2.0, -1e-300};
  EXPECT_TRUE(dom.wrap(a));
  EXPECT_EQ(a.x, 0.0);
  EXPECT_EQ(a.y, 0.0);
  EXPECT_TRUE(a.z >= 0.0 && a.z < 1.0);
}

TEST(Boundaries, OpenBoxOwnsFarParticles) {
  const auto comm = world();
  Domain dom(comm);
  auto ps = make_particles(comm, 100, 0.0, 1.0, 3 + 100u * unsigned(comm.rank()), 10);
  dom.decompose(ps);
  if (comm.rank() == comm.size() - 1) {
    ps.push_back({{1e6, 0.5, 0.5}, {}, 1.0, 0});
    ps.push_back({{-1e30, -1e30, 1e30}, {}, 1.0, 1});
    ps.push_back({{0.5, 1e300, -0.5}, {}, 1.0, 2});
  }
  pik::exchange_particles(ps, dom);
  expect_owned(dom, ps);
  int found = 0;
  for (const auto& p : ps) found += p.id < 3;
  EXPECT_EQ(comm.sum(found), 3);
  EXPECT_EQ(comm.sum(ps.size()), 100u * unsigned(comm.size()) + 3);
  // Domains tile space: the outer faces are infinite.
  std::vector<std::pair<double, double>> xs;
  for (int r = 0; r < comm.size(); ++r) {
    const auto b = dom.domain(r);
    EXPECT_TRUE(b.lo[0] < b.hi[0] || b.empty());
  }
  EXPECT_TRUE(std::isinf(dom.domain(0).lo[0]));
  EXPECT_TRUE(std::isinf(dom.domain(comm.size() - 1).hi[2]));
}

TEST(Decomposition, GivenGridIsUsed) {
  const auto comm = world();
  Domain::Options opt;
  opt.grid = {1, 1, comm.size()};
  Domain dom(comm, opt);
  auto ps = make_particles(comm, 300, 0.0, 1.0, 0, 12);
  dom.decompose(ps);
  pik::exchange_particles(ps, dom);
  const auto b = dom.domain(comm.rank());
  EXPECT_TRUE(std::isinf(b.lo[0]) && std::isinf(b.hi[0]));
  EXPECT_TRUE(std::isinf(b.lo[1]) && std::isinf(b.hi[1]));
  for (const auto& p : ps) EXPECT_TRUE(p.pos.z >= b.lo[2] && p.pos.z < b.hi[2]);
}

namespace {
// Shapes of pik::Boundary<3> and pik::ParticleSystem<FP> as the domain layer sees them.
struct BoundaryLike {
  struct {
    V3 lo, hi;
  } box;
  bool periodic[3];
};
struct ContainerLike {
  std::vector<Particle> p;
  std::vector<Particle>& vector() { return p; }
};
}  // namespace

TEST(Decomposition, AcceptsBoundaryAndParticleSystemShapes) {
  const auto comm = world();
  Domain dom(comm);
  dom.set_root_domain(BoundaryLike{{{0, 0, 0}, {4, 4, 4}}, {false, true, false}});
  EXPECT_FALSE(dom.periodic(0));
  EXPECT_TRUE(dom.periodic(1));
  EXPECT_EQ(dom.root_domain().hi[1], 4.0);
  ContainerLike c{make_particles(comm, 50, -2.0, 6.0, 50u * unsigned(comm.rank()), 13)};
  dom.decompose(c.p);
  pik::exchange_particles(c, dom);
  expect_owned(dom, c.p);
  for (const auto& p : c.p) EXPECT_TRUE(p.pos.y >= 0 && p.pos.y < 4);
  EXPECT_EQ(comm.sum(c.p.size()), 50u * unsigned(comm.size()));
}
