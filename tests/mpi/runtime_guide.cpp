// runtime_guide: the code of docs/runtime.md's "FDPS concepts in pik" section, compiled
// and run (np 1 and 2), so the guide cannot drift from the API. A plain C++ kernel
// stands in for a generated one (same call signature).
#include <cmath>
#include <cstdio>

#include <pik/pik.hpp>

struct Result {
  pik::Vec3<double> acc;
  double pot;
  void clear() { acc = {}, pot = 0; }
};
struct Star {
  pik::Vec3<double> pos;
  double mass, h;
  Result f;
  pik::Vec3<double> getPos() const { return pos; }
  void setPos(const pik::Vec3<double>& x) { pos = x; }
  double getCharge() const { return mass; }
  double getRSearch() const { return h; }
  void copyFromFP(const Star& s) { *this = s; }
  void copyFromForce(const Result& r) { f = r; }
};
struct Gravity {  // accumulates, like every pik kernel
  template <class J>
  void operator()(const Star* epi, int ni, const J* epj, int nj, Result* force) const {
    for (int i = 0; i < ni; ++i)
      for (int j = 0; j < nj; ++j) {
        const auto d = epi[i].pos - pik::vec_cast<pik::Vec3<double>>(epj[j].getPos());
        const double r2 = pik::norm2(d) + 1e-4, rinv = 1 / std::sqrt(r2);
        force[i].acc -= d * (epj[j].getCharge() * rinv * rinv * rinv), force[i].pot -= epj[j].getCharge() * rinv;
      }
  }
};

int main(int argc, char** argv) {
  // --- guide: particle system
  pik::ParticleSystem<Star> ps;
  ps.add(Star{{0.1, 0.2, 0.3}, 1.0, 0.2, {}});
  // --- guide: domain info and exchange
  pik::Environment env(argc, argv);
  const pik::Comm comm = env.world();
  pik::DomainInfo<double, 3> domain(comm);
  domain.decompose(ps.vector());           // multisection from a sample of every rank
  pik::exchange_particles(ps, domain);     // each particle to the rank owning its position
  // --- guide: long-range tree, one call
  pik::DistributedLongRangeTree<Result, Star, Star, pik::SPJMonopole<double>> gravity(
      {.theta = 0.5, .n_leaf_limit = 8, .n_group_limit = 64});
  gravity.calcForceAllAndWriteBack(Gravity{}, Gravity{}, ps, comm);
  domain.decompose(ps.vector(), gravity.cost());  // next step: weighted by measured cost
  // --- guide: short-range tree
  pik::ShortRangeTree<Result, Star, Star, pik::SearchMode::gather> neighbours(
      {}, pik::Boundary<3>::periodic_box({0, 0, 0}, {1, 1, 1}));
  ps.wrapPositions(neighbours.boundary());
  // (distributed: pik::DistributedShortRangeTree<...>::calcForceAllAndWriteBack(kernel, ps, comm))
  // --- guide: list reuse
  pik::LongRangeTree<Result, Star, Star, pik::SPJMonopole<double>> tree({.theta = 0.5});
  tree.calcForceAllAndWriteBack(Gravity{}, Gravity{}, ps, pik::ListMode::make_for_reuse);
  tree.calcForceAllAndWriteBack(Gravity{}, Gravity{}, ps, pik::ListMode::reuse);  // same lists
  // --- guide: timing profile
  const pik::Profiler& prof = tree.profile();
  std::printf("build %.3g s, moments %.3g s, walk+kernel %.3g s, write back %.3g s\n",
              prof.seconds("tree build"), prof.seconds("moments"), prof.seconds("walk+kernel"),
              prof.seconds("write back"));
  // --- end
  const double total = comm.sum(double(ps.size()));
  if (total != comm.size()) return std::fprintf(stderr, "runtime_guide: %g particles\n", total), 1;
  return 0;
}
