// Several species in one long-range tree (pik::Species): the forces of a dark matter
// + gas bundle equal those of one merged particle system holding the same particles
// in the same order, bit for bit (the tree sorts the same positions into the same
// order, so every interaction list and every sum is the same), for monopole and
// quadrupole cells and with interaction-list reuse; each result lands in the
// particle of its own species.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>

#include <pik/pik.hpp>

namespace {

using V = pik::Vec3<double>;

struct Force {
  V acc;
  double pot;
  void clear() { acc = {}, pot = 0; }
};
// Two species with different members; a third, merged type for the reference.
struct DarkMatter {
  std::uint64_t id;
  double mass;
  V pos, vel, acc;
  double pot = 0;
  const V& getPos() const { return pos; }
  void copyFromForce(const Force& f) { acc = f.acc, pot = f.pot; }
};
struct Gas {
  double mass, u, h;
  V pos, acc;
  float pot = 0;
  const V& getPos() const { return pos; }
  void copyFromForce(const Force& f) { acc = f.acc, pot = float(f.pot); }
};
struct Merged {
  double mass;
  V pos, acc;
  double pot = 0;
  const V& getPos() const { return pos; }
  void copyFromForce(const Force& f) { acc = f.acc, pot = f.pot; }
};
struct EP {  // EPI and EPJ: one copyFromFP per full-particle type
  V pos;
  double mass;
  const V& getPos() const { return pos; }
  double getCharge() const { return mass; }
  void copyFromFP(const DarkMatter& p) { pos = p.pos, mass = p.mass; }
  void copyFromFP(const Gas& p) { pos = p.pos, mass = p.mass; }
  void copyFromFP(const Merged& p) { pos = p.pos, mass = p.mass; }
};

struct Gravity {  // softened monopole, also for SPJMonopole j's
  double eps2;
  template <class J>
  void operator()(const EP* pi, int ni, const J* pj, int nj, Force* f) const {
    for (int i = 0; i < ni; ++i)
      for (int j = 0; j < nj; ++j) {
        const V d = pi[i].pos - pj[j].pos;
        const double r2 = pik::norm2(d) + eps2, rinv = 1 / std::sqrt(r2), mr = pj[j].mass * rinv;
        f[i].acc -= d * (mr * rinv * rinv);
        f[i].pot -= mr;
      }
  }
};
struct GravityQuad {
  double eps2;
  void operator()(const EP* pi, int ni, const pik::SPJQuadrupole<double>* pj, int nj, Force* f) const {
    for (int i = 0; i < ni; ++i)
      for (int j = 0; j < nj; ++j) {
        const auto& s = pj[j];
        const V d = pi[i].pos - s.pos;
        const double r2 = pik::norm2(d) + eps2, rinv = 1 / std::sqrt(r2), rinv2 = rinv * rinv;
        const V qd{s.qxx * d.x + s.qxy * d.y + s.qxz * d.z, s.qxy * d.x + s.qyy * d.y + s.qyz * d.z,
                   s.qxz * d.x + s.qyz * d.y + s.qzz * d.z};
        const double dqd = pik::dot(d, qd), rinv5 = rinv2 * rinv2 * rinv, mr3 = s.mass * rinv2 * rinv;
        f[i].acc -= d * (mr3 + 2.5 * dqd * rinv5 * rinv2);
        f[i].acc += qd * rinv5;
        f[i].pot -= s.mass * rinv + 0.5 * dqd * rinv5;
      }
  }
};

struct Sets {
  pik::ParticleSystem<DarkMatter> dm;
  pik::ParticleSystem<Gas> gas;
  pik::ParticleSystem<Merged> merged;
};

// A clustered dark-matter set and a smaller, more concentrated gas set.
Sets make_sets(std::size_t n_dm, std::size_t n_gas, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0, 1);
  std::uniform_real_distribution<double> u(-1, 1);
  Sets s;
  for (std::size_t i = 0; i < n_dm; ++i) {
    const V x = i % 3 ? V{u(rng), u(rng), u(rng)} : V{0.2 * g(rng) + 0.3, 0.1 * g(rng), 0.2 * g(rng)};
    s.dm.add({i, 1.0 / double(n_dm), x, {}, {}, 0});
    s.merged.add({1.0 / double(n_dm), x, {}, 0});
  }
  for (std::size_t i = 0; i < n_gas; ++i) {
    const V x{0.3 * g(rng), 0.3 * g(rng) - 0.2, 0.3 * g(rng)};
    s.gas.add({0.2 / double(n_gas), 1.0, 0.05, x, {}, 0});
    s.merged.add({0.2 / double(n_gas), x, {}, 0});
  }
  return s;
}

template <class SPJ, class KS>
void expect_same_forces(double theta, const KS& kernel_sp, pik::ListMode mode) {
  Sets s = make_sets(3001, 1203, 7);
  const Gravity kernel{1e-4};
  pik::LongRangeTree<Force, EP, EP, SPJ> t2({.theta = theta}), t1({.theta = theta});
  t2.calcForceAllAndWriteBack(kernel, kernel_sp, pik::species(s.dm, s.gas), mode);
  t1.calcForceAllAndWriteBack(kernel, kernel_sp, s.merged, mode);
  if (mode == pik::ListMode::make_for_reuse) {  // move everything a little, reuse the lists
    for (auto& p : s.dm) p.pos += V{1e-3, -2e-3, 5e-4};
    for (auto& p : s.gas) p.pos += V{1e-3, -2e-3, 5e-4};
    for (auto& p : s.merged) p.pos += V{1e-3, -2e-3, 5e-4};
    t2.calcForceAllAndWriteBack(kernel, kernel_sp, pik::species(s.dm, s.gas), pik::ListMode::reuse);
    t1.calcForceAllAndWriteBack(kernel, kernel_sp, s.merged, pik::ListMode::reuse);
  }
  EXPECT_EQ(t2.interactionsEP(), t1.interactionsEP());
  EXPECT_EQ(t2.interactionsSP(), t1.interactionsSP());
  ASSERT_EQ(s.merged.size(), s.dm.size() + s.gas.size());
  for (std::size_t i = 0; i < s.dm.size(); ++i) {
    ASSERT_EQ(s.dm[i].acc.x, s.merged[i].acc.x) << "dark matter " << i;
    ASSERT_EQ(s.dm[i].acc.y, s.merged[i].acc.y) << "dark matter " << i;
    ASSERT_EQ(s.dm[i].acc.z, s.merged[i].acc.z) << "dark matter " << i;
    ASSERT_EQ(s.dm[i].pot, s.merged[i].pot) << "dark matter " << i;
  }
  for (std::size_t i = 0; i < s.gas.size(); ++i) {
    const Merged& m = s.merged[s.dm.size() + i];
    ASSERT_EQ(s.gas[i].acc.x, m.acc.x) << "gas " << i;
    ASSERT_EQ(s.gas[i].acc.y, m.acc.y) << "gas " << i;
    ASSERT_EQ(s.gas[i].acc.z, m.acc.z) << "gas " << i;
    ASSERT_EQ(s.gas[i].pot, float(m.pot)) << "gas " << i;
  }
  // Not all zero: the test would pass trivially otherwise.
  EXPECT_GT(pik::norm(s.gas[0].acc), 0.0);
  EXPECT_GT(pik::norm(s.dm[0].acc), 0.0);
}

TEST(Species, TwoSpeciesTreeEqualsMergedSetBitForBit) {
  expect_same_forces<pik::SPJMonopole<double>>(0.5, Gravity{1e-4}, pik::ListMode::rebuild);
}
TEST(Species, QuadrupoleCells) {
  expect_same_forces<pik::SPJQuadrupole<double>>(0.7, GravityQuad{1e-4}, pik::ListMode::rebuild);
}
TEST(Species, InteractionListReuse) {
  expect_same_forces<pik::SPJMonopole<double>>(0.5, Gravity{1e-4}, pik::ListMode::make_for_reuse);
}
TEST(Species, DirectSumAgainstBruteForce) {
  // theta = 0: every pair, compared with an O(N^2) double loop over both species.
  Sets s = make_sets(301, 97, 3);
  pik::LongRangeTree<Force, EP, EP> t({.theta = 0});
  t.calcForceAllAndWriteBack(Gravity{1e-4}, Gravity{1e-4}, pik::species(s.dm, s.gas));
  std::vector<EP> all(s.merged.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i].copyFromFP(s.merged[i]);
  double worst = 0;
  for (std::size_t i = 0; i < all.size(); ++i) {
    Force f;
    f.clear();
    Gravity{1e-4}(&all[i], 1, all.data(), int(all.size()), &f);
    const V a = i < s.dm.size() ? s.dm[i].acc : s.gas[i - s.dm.size()].acc;
    worst = std::max(worst, pik::norm(a - f.acc) / pik::norm(f.acc));
  }
  EXPECT_LT(worst, 1e-12);
}
TEST(Species, EmptySpeciesAndBadPositions) {
  Sets s = make_sets(100, 0, 5);
  pik::LongRangeTree<Force, EP, EP> t;
  t.calcForceAllAndWriteBack(Gravity{1e-4}, Gravity{1e-4}, pik::species(s.dm, s.gas));
  EXPECT_GT(pik::norm(s.dm[3].acc), 0.0);
  const auto sp = pik::species(s.dm, s.gas);
  EXPECT_EQ(sp.size(), 100u);
  EXPECT_EQ(sp.offset(1), 100u);
  s.gas.add({1.0, 1.0, 0.1, V{0, std::nan(""), 0}, {}, 0});
  try {
    t.calcForceAllAndWriteBack(Gravity{1e-4}, Gravity{1e-4}, pik::species(s.dm, s.gas));
    FAIL() << "a NaN position must be refused";
  } catch (const pik::Error& e) {
    EXPECT_NE(std::string(e.what()).find("species 1: particle 0"), std::string::npos) << e.what();
  }
}

}  // namespace
