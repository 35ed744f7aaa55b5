// Long-range forces through local essential trees at any rank count, against the
// single-process tree and a direct sum over the same particles.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <pik/comm/Comm.hpp>
#include <pik/domain/DistributedLongRangeTree.hpp>
#include <pik/domain/DomainInfo.hpp>
#include <pik/domain/ParticleExchange.hpp>
#include <pik/particle/ParticleSystem.hpp>
#include <pik/walk/LongRangeTree.hpp>

namespace {

using V3 = pik::Vec3<double>;
constexpr double eps2 = 1e-6;

struct Result {
  V3 acc;
  double pot;
  void clear() { acc = {}, pot = 0; }
};
struct Body {
  V3 pos;
  double mass;
  std::uint64_t id;
  V3 acc;
  double pot;
  const V3& getPos() const { return pos; }
  void setPos(const V3& p) { pos = p; }
  void copyFromForce(const Result& f) { acc = f.acc, pot = f.pot; }
};
struct EP {
  V3 pos;
  double mass;
  const V3& getPos() const { return pos; }
  double getCharge() const { return mass; }
  void copyFromFP(const Body& b) { pos = b.pos, mass = b.mass; }
};

// Softened monopole gravity, for particles and monopole super-particles.
struct Gravity {
  template <class J>
  void operator()(const EP* ei, int ni, const J* ej, int nj, Result* f) const {
    for (int i = 0; i < ni; ++i)
      for (int j = 0; j < nj; ++j) {
        const double dx = ei[i].pos.x - ej[j].pos.x, dy = ei[i].pos.y - ej[j].pos.y,
                     dz = ei[i].pos.z - ej[j].pos.z;
        const double r2 = dx * dx + dy * dy + dz * dz + eps2, rinv = 1 / std::sqrt(r2);
        const double mr = ej[j].mass * rinv, mr3 = mr * rinv * rinv;
        f[i].acc.x -= mr3 * dx, f[i].acc.y -= mr3 * dy, f[i].acc.z -= mr3 * dz;
        f[i].pot -= mr;
      }
  }
};

// Quadrupole super-particles: Phi = -M/r - x.Q.x / (2 r^5), Q traceless.
struct GravityQuad {
  void operator()(const EP* ei, int ni, const pik::SPJQuadrupole<double>* s, int ns, Result* f) const {
    for (int i = 0; i < ni; ++i)
      for (int j = 0; j < ns; ++j) {
        const double x = ei[i].pos.x - s[j].pos.x, y = ei[i].pos.y - s[j].pos.y, z = ei[i].pos.z - s[j].pos.z;
        const double r2 = x * x + y * y + z * z + eps2, rinv = 1 / std::sqrt(r2), rinv2 = rinv * rinv;
        const double qx = s[j].qxx * x + s[j].qxy * y + s[j].qxz * z;
        const double qy = s[j].qxy * x + s[j].qyy * y + s[j].qyz * z;
        const double qz = s[j].qxz * x + s[j].qyz * y + s[j].qzz * z;
        const double xqx = x * qx + y * qy + z * qz;
        const double r5 = rinv2 * rinv2 * rinv, r7 = r5 * rinv2;
        const double m3 = s[j].mass * rinv * rinv2;
        f[i].acc.x += -m3 * x + qx * r5 - 2.5 * xqx * x * r7;
        f[i].acc.y += -m3 * y + qy * r5 - 2.5 * xqx * y * r7;
        f[i].acc.z += -m3 * z + qz * r5 - 2.5 * xqx * z * r7;
        f[i].pot += -s[j].mass * rinv - 0.5 * xqx * r5;
      }
  }
};

pik::Comm world() { return pik::Comm::world(); }

// The same particles on every rank: a uniform sphere plus a dense off-centre clump.
std::vector<Body> all_bodies(std::size_t n) {
  std::mt19937_64 rng(2024);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Body> b;
  for (std::size_t i = 0; i < n; ++i) {
    V3 x;
    do x = {u(rng), u(rng), u(rng)};
    while (x.x * x.x + x.y * x.y + x.z * x.z > 1);
    if (i % 4 == 0) x = {0.6 + 0.05 * x.x, 0.1 + 0.05 * x.y, -0.3 + 0.05 * x.z};
    b.push_back({x, 1.0 / double(n) * (1 + double(i % 3)), i, {}, 0});
  }
  return b;
}

double rel_err(const V3& a, const V3& ref) {
  const double dx = a.x - ref.x, dy = a.y - ref.y, dz = a.z - ref.z;
  return std::sqrt((dx * dx + dy * dy + dz * dz) / (ref.x * ref.x + ref.y * ref.y + ref.z * ref.z));
}

// Single-process forces on all bodies with the given tree, indexed by id.
template <class SPJ, class KS>
std::vector<Result> single_process(const std::vector<Body>& all, pik::TreeParams p, KS ks) {
  pik::ParticleSystem<Body> ps(all);
  pik::LongRangeTree<Result, EP, EP, SPJ> tree(p);
  tree.calcForceAllAndWriteBack(Gravity{}, ks, ps);
  std::vector<Result> out(all.size());
  for (const Body& b : ps) out[b.id] = {b.acc, b.pot};
  return out;
}

struct Errors {
  double max_vs_single, rms_vs_direct, rms_single_vs_direct;
};

// Distributes `all` over the ranks, computes distributed forces, compares.
template <class SPJ, class KS>
Errors run(const std::vector<Body>& all, pik::TreeParams p, KS ks, int steps = 2) {
  const auto comm = world();
  pik::ParticleSystem<Body> ps;
  for (const Body& b : all)
    if (int(b.id % std::uint64_t(comm.size())) == comm.rank()) ps.add(b);
  pik::DomainInfo<double, 3> dinfo(comm);
  pik::DistributedLongRangeTree<Result, EP, EP, SPJ> tree(p);
  for (int s = 0; s < steps; ++s) {
    // Equal cost per particle (not the measured tree.cost()), so that the domains,
    // and hence the errors checked below, do not depend on timing.
    dinfo.decompose(ps.vector());
    pik::exchange_particles(ps, dinfo);
    tree.calcForceAllAndWriteBack(Gravity{}, ks, ps, comm);
  }
  const auto single = single_process<SPJ>(all, p, ks);
  pik::TreeParams direct = p;
  direct.theta = 0;
  const auto exact = single_process<SPJ>(all, direct, ks);
  double mx = 0, s2 = 0, s2s = 0;
  for (const Body& b : ps) {
    mx = std::max(mx, rel_err(b.acc, single[b.id].acc));
    const double e = rel_err(b.acc, exact[b.id].acc), es = rel_err(single[b.id].acc, exact[b.id].acc);
    s2 += e * e, s2s += es * es;
  }
  EXPECT_EQ(comm.sum(ps.size()), all.size());
  const double n = double(all.size());
  // The LET statistics add up over ranks.
  const auto& st = tree.letStats();
  EXPECT_EQ(comm.sum(st.epj_sent), comm.sum(st.epj_received));
  EXPECT_EQ(comm.sum(st.spj_sent), comm.sum(st.spj_received));
  return {comm.max(mx), std::sqrt(comm.sum(s2) / n), std::sqrt(comm.sum(s2s) / n)};
}

}  // namespace

TEST(LocalEssentialTree, DirectSumEqualsSingleProcessToRounding) {
  pik::TreeParams p;
  p.theta = 0;  // every cell opened: all particles travel, forces are direct sums
  const auto e = run<pik::SPJMonopole<double>>(all_bodies(1500), p, Gravity{});
  EXPECT_LT(e.max_vs_single, 1e-12);
}

TEST(LocalEssentialTree, MonopoleMatchesSingleProcessAccuracy) {
  pik::TreeParams p;
  p.theta = 0.5;
  p.n_group_limit = 32;
  const auto e = run<pik::SPJMonopole<double>>(all_bodies(3000), p, Gravity{});
  // Different cells are opened on different ranks, so forces agree to the tree's
  // error, and the error against the direct sum stays of the single tree's size:
  // imported super-particles carry their cells' boxes into the receiver's cells, so
  // it does not grow with the rank count (at most 8% above one process's at np 2-8;
  // with the super-particles as points it was up to 25% above).
  EXPECT_GT(e.rms_single_vs_direct, 0);
  EXPECT_LT(e.rms_vs_direct, 1.15 * e.rms_single_vs_direct);
  if (world().is_root())
    std::printf("monopole theta 0.5: rms err distributed %.3e, single %.3e, max diff %.3e\n",
                e.rms_vs_direct, e.rms_single_vs_direct, e.max_vs_single);
}

TEST(LocalEssentialTree, FollowsTheOffsetOpeningCriterion) {
  // The LET must use the force walk's own criterion: with d > s/theta + delta (to
  // the centre of mass) the distributed error stays that of one process.
  pik::TreeParams p;
  p.theta = 0.5;
  p.opening = pik::Opening::centre_of_mass_offset;
  const auto e = run<pik::SPJMonopole<double>>(all_bodies(3000), p, Gravity{});
  EXPECT_LT(e.rms_vs_direct, 1.15 * e.rms_single_vs_direct);
  if (world().is_root())
    std::printf("offset criterion theta 0.5: rms err distributed %.3e, single %.3e\n", e.rms_vs_direct,
                e.rms_single_vs_direct);
}

TEST(LocalEssentialTree, QuadrupoleMomentsTravel) {
  pik::TreeParams p;
  p.theta = 0.6;
  const auto all = all_bodies(3000);
  const auto q = run<pik::SPJQuadrupole<double>>(all, p, GravityQuad{});
  const auto m = run<pik::SPJMonopole<double>>(all, p, Gravity{});
  EXPECT_LT(q.rms_vs_direct, 1.6 * q.rms_single_vs_direct);  // 1.31x measured at np 8
  EXPECT_LT(q.rms_vs_direct, 0.5 * m.rms_vs_direct);
  if (world().is_root())
    std::printf("theta 0.6: rms err quadrupole %.3e (single %.3e), monopole %.3e\n", q.rms_vs_direct,
                q.rms_single_vs_direct, m.rms_vs_direct);
}

TEST(LocalEssentialTree, RanksWithoutParticles) {
  pik::TreeParams p;
  p.theta = 0;
  p.n_leaf_limit = 1;
  // Five particles for up to eight ranks: empty ranks send, receive and compute nothing.
  const auto e = run<pik::SPJMonopole<double>>(all_bodies(5), p, Gravity{}, 3);
  EXPECT_LT(e.max_vs_single, 1e-12);
}

TEST(LocalEssentialTree, ImportsInTheirOwnTreeGiveTheCombinedTreesForces) {
  // The distributed step walks the local tree and a separate tree of the imports
  // (calcForceWithImportsAndWriteBack); at theta = 0 that is the same direct sum as
  // one tree over local particles and imports together (setImported* and
  // calcForceAll), so the two agree to rounding. At theta 0.5 both are tree
  // approximations of that sum with the same error size. (One process: no MPI.)
  const auto all = all_bodies(600);
  std::vector<Body> mine(all.begin(), all.begin() + 400);
  std::vector<EP> epj;
  std::vector<pik::SPJMonopole<double>> spj;
  std::vector<pik::Box<double, 3>> ext;
  for (std::size_t i = 400; i < all.size(); ++i) {
    const EP e{all[i].pos + V3{2.5, 0, 0}, all[i].mass};  // a neighbour domain
    if (i % 3 == 0) {
      pik::Multipole<3> m;
      m.mass = e.mass, m.pos = e.pos;
      pik::SPJMonopole<double> s;
      s.setMoments(m);
      spj.push_back(s);
      pik::Box<double, 3> b;
      b.extend(e.pos - V3{0.01, 0.01, 0.01}), b.extend(e.pos + V3{0.01, 0.01, 0.01});
      ext.push_back(b);
    } else {
      epj.push_back(e);
    }
  }
  for (const double theta : {0.0, 0.5}) {
    pik::TreeParams p;
    p.theta = theta;
    pik::ParticleSystem<Body> a(mine), b(mine), direct(mine);
    pik::LongRangeTree<Result, EP, EP> apart(p), together(p);
    EXPECT_THROW(apart.calcForceWithImportsAndWriteBack(Gravity{}, Gravity{}, a), pik::Error);
    apart.buildTreeAndMoments(a);
    apart.setImportedParticles(epj);
    apart.setImportedSuperParticles(spj, ext);
    apart.calcForceWithImportsAndWriteBack(Gravity{}, Gravity{}, a);
    // The local tree is used up: the next step must build it again.
    EXPECT_THROW(apart.calcForceWithImportsAndWriteBack(Gravity{}, Gravity{}, a), pik::Error);
    together.setImportedParticles(epj);
    together.setImportedSuperParticles(spj, ext);
    together.calcForceAllAndWriteBack(Gravity{}, Gravity{}, b);
    pik::TreeParams d = p;
    d.theta = 0;
    pik::LongRangeTree<Result, EP, EP> exact(d);
    exact.setImportedParticles(epj);
    exact.setImportedSuperParticles(spj, ext);
    exact.calcForceAllAndWriteBack(Gravity{}, Gravity{}, direct);
    double mx = 0, s2a = 0, s2b = 0;
    for (std::size_t i = 0; i < mine.size(); ++i) {
      mx = std::max(mx, rel_err(a[i].acc, b[i].acc));
      const double ea = rel_err(a[i].acc, direct[i].acc), eb = rel_err(b[i].acc, direct[i].acc);
      s2a += ea * ea, s2b += eb * eb;
    }
    if (theta == 0) {
      EXPECT_LT(mx, 1e-12);
    } else {
      EXPECT_GT(s2b, 0);
      EXPECT_LT(s2a, 1.3 * 1.3 * s2b);  // rms within 30 % of the combined tree's
    }
  }
}
