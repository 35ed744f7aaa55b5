// Several species under MPI: one decomposition and one exchange call for the
// dark matter + gas bundle (pik::decompose, pik::exchange_particles on
// pik::species), then one distributed long-range tree over it. At theta = 0 every
// rank's forces equal a single-process direct sum over all particles, to rounding;
// no particle is lost or duplicated and each species keeps its own type.
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
struct DarkMatter {
  std::uint64_t id;
  double mass;
  V pos, acc;
  const V& getPos() const { return pos; }
  void setPos(const V& x) { pos = x; }
  void copyFromForce(const Force& f) { acc = f.acc; }
};
struct Gas {
  std::uint64_t id;
  double mass, u;
  V pos, acc;
  const V& getPos() const { return pos; }
  void setPos(const V& x) { pos = x; }
  void copyFromForce(const Force& f) { acc = f.acc; }
};
struct EP {
  V pos;
  double mass;
  const V& getPos() const { return pos; }
  double getCharge() const { return mass; }
  void copyFromFP(const DarkMatter& p) { pos = p.pos, mass = p.mass; }
  void copyFromFP(const Gas& p) { pos = p.pos, mass = p.mass; }
};
struct Gravity {
  double eps2;
  template <class J>
  void operator()(const EP* pi, int ni, const J* pj, int nj, Force* f) const {
    for (int i = 0; i < ni; ++i)
      for (int j = 0; j < nj; ++j) {
        const V d = pi[i].pos - pj[j].pos;
        const double r2 = pik::norm2(d) + eps2, rinv = 1 / std::sqrt(r2);
        f[i].acc -= d * (pj[j].mass * rinv * rinv * rinv);
      }
  }
};

TEST(SpeciesMpi, OneDecompositionOneTreeEqualsDirectSum) {
  const pik::Comm comm = pik::Comm::world();
  const std::size_t n_dm = 800, n_gas = 300;
  // Every rank makes the same particles; rank r starts with every size()-th.
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<EP> all;
  pik::ParticleSystem<DarkMatter> dm;
  pik::ParticleSystem<Gas> gas;
  for (std::size_t i = 0; i < n_dm + n_gas; ++i) {
    const V x{u(rng), u(rng), i < n_dm ? u(rng) : 0.5 + 0.1 * u(rng)};
    const double m = i < n_dm ? 1.0 / n_dm : 0.2 / n_gas;
    all.push_back({x, m});
    if (int(i % std::size_t(comm.size())) != comm.rank()) continue;
    if (i < n_dm) dm.add({i, m, x, {}});
    else gas.add({i, m, 1.0, x, {}});
  }
  pik::DomainInfo<double, 3> dinfo(comm);
  pik::DistributedLongRangeTree<Force, EP, EP> tree({.theta = 0});
  for (int step = 0; step < 2; ++step) {  // the second step decomposes by measured cost
    pik::decompose(dinfo, pik::species(dm, gas), tree.cost());
    pik::exchange_particles(pik::species(dm, gas), dinfo);
    tree.calcForceAllAndWriteBack(Gravity{1e-4}, Gravity{1e-4}, pik::species(dm, gas), comm);
  }
  EXPECT_EQ(comm.sum(std::uint64_t(dm.size())), n_dm);
  EXPECT_EQ(comm.sum(std::uint64_t(gas.size())), n_gas);
  std::uint64_t id_sum = 0;
  double worst = 0;
  auto check = [&](std::uint64_t id, const V& x, const V& a) {
    id_sum += id;
    EXPECT_EQ(dinfo.owner(x), comm.rank());
    Force f;
    f.clear();
    Gravity{1e-4}(&all[id], 1, all.data(), int(all.size()), &f);
    worst = std::max(worst, pik::norm(a - f.acc) / pik::norm(f.acc));
  };
  for (const auto& p : dm) {
    check(p.id, p.pos, p.acc);
    EXPECT_LT(p.id, n_dm);
  }
  for (const auto& p : gas) {
    check(p.id, p.pos, p.acc);
    EXPECT_GE(p.id, n_dm);
  }
  const std::uint64_t n = n_dm + n_gas;
  EXPECT_EQ(comm.sum(id_sum), n * (n - 1) / 2);
  EXPECT_LT(comm.max(worst), 1e-12);
}

}  // namespace
