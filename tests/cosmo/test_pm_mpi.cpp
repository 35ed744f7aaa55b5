// The distributed particle mesh and TreePM: on 1, 2 and 4 ranks (FFTW's MPI slabs,
// planes routed to their owners, periodic images and halo from every rank) the
// accelerations equal the single-process ones to rounding, for particles spread
// over the ranks at random and for a periodic domain decomposition.
#include <gtest/gtest.h>

#include <map>

#include "treepm_support.hpp"

using namespace tpm;
#include "TreePMKernel.hpp"
#include "TreePMKernelSP.hpp"

namespace {

constexpr double L = 1.0;

// Largest |a - a_ref| over the particles, relative to the rms of |a_ref|.
double worst_difference(const std::vector<Body>& mine, const std::vector<Body>& all,
                        const pik::Comm& comm, bool total) {
  double num = 0, den = 0;
  for (const Body& b : all) den += pik::norm2(total ? b.acc() : b.acc_long);
  den = std::sqrt(den / double(all.size()));
  for (const Body& b : mine) {
    const Body& r = all[b.id];
    num = std::max(num, pik::norm((total ? b.acc() : b.acc_long) - (total ? r.acc() : r.acc_long)));
  }
  return comm.max(num) / den;
}

TEST(ParticleMeshMpi, DistributedMeshEqualsSingleProcess) {
  const pik::Comm comm = pik::Comm::world();
  for (auto asg : {pik::pm::Assignment::cic, pik::pm::Assignment::tsc}) {
    const auto all_in = make_set(6000, L, true, 9);
    const pik::pm::MeshParams mp{.box = L, .n_mesh = 32, .assignment = asg};
    // Reference: every particle on this rank alone.
    std::vector<Body> all = all_in;
    pik::pm::ParticleMesh<pik::SerialComm> serial(mp, pik::SerialComm::world());
    {
      pik::ParticleSystem<Body> ps(all);
      serial.calcForceAllAndWriteBack(ps);
      all = ps.vector();
    }
    // Distributed: rank r holds every size()-th particle (its planes are then all planes).
    pik::ParticleSystem<Body> mine;
    for (const Body& b : all_in)
      if (int(b.id % std::uint64_t(comm.size())) == comm.rank()) mine.add(b);
    pik::pm::ParticleMesh<pik::Comm> pm(mp, comm);
    EXPECT_EQ(pm.fft().nx() > 0 || comm.size() > mp.n_mesh, true);
    pm.calcForceAllAndWriteBack(mine);
    const double w = worst_difference(mine.vector(), all, comm, false);
    if (comm.is_root()) std::printf("mesh, %d ranks: worst difference %.2e of the rms acceleration\n", comm.size(), w);
    EXPECT_LT(w, 1e-12);
    EXPECT_GT(pik::norm(mine[0].acc_long), 0.0);
  }
}

TEST(TreePMMpi, DecomposedTreePMEqualsSingleProcess) {
  const pik::Comm comm = pik::Comm::world();
  const auto all_in = make_set(6000, L, true, 10);
  pik::pm::TreePMParams p;
  p.mesh = {.box = L, .n_mesh = 16};
  p.theta = 0;  // every pair within r_cut: the same sums on any rank count, to rounding
  std::vector<Body> all;
  {
    pik::pm::TreePM<Force, EPI, EPJ, SPJ> g(p);
    const TreePMKernel k(1e-6f, float(g.rcut2()), float(g.inv_2rs()));
    const TreePMKernelSP ksp(1e-6f, float(g.rcut2()), float(g.inv_2rs()));
    pik::ParticleSystem<Body> ps(all_in);
    g.calcForceAllAndWriteBack(k, ksp, ps);
    all = ps.vector();
  }
  pik::ParticleSystem<Body> mine;
  if (comm.is_root()) mine = pik::ParticleSystem<Body>(all_in);
  pik::DomainInfo<double, 3> dinfo(comm);
  dinfo.set_periodic_box({{0, 0, 0}, {L, L, L}});
  dinfo.decompose(mine.vector());
  pik::exchange_particles(mine, dinfo);
  pik::pm::TreePM<Force, EPI, EPJ, SPJ, pik::Comm> g(p, comm);
  const TreePMKernel k(1e-6f, float(g.rcut2()), float(g.inv_2rs()));
  const TreePMKernelSP ksp(1e-6f, float(g.rcut2()), float(g.inv_2rs()));
  g.calcForceAllAndWriteBack(k, ksp, mine);
  EXPECT_EQ(comm.sum(std::uint64_t(mine.size())), all.size());
  const double w = worst_difference(mine.vector(), all, comm, true);
  if (comm.is_root())
    std::printf("TreePM, %d ranks: worst difference %.2e of the rms acceleration (imports here %zu)\n",
                comm.size(), w, g.importedParticles());
  EXPECT_LT(w, 1e-5);  // F32 kernel sums in another order
}

}  // namespace
