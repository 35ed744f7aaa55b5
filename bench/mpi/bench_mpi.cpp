// bench_mpi: distributed Barnes-Hut steps (decompose, exchange, local essential
// tree, force) on a cold uniform sphere; one table row per run. Run it under
// mpirun at several rank counts (bench/mpi/run.sh does the tables in docs/parallel.md).
//
//   mpirun -np P bench_mpi [--log2n 20 | --log2n-per-rank 17] [--steps 4] [--theta 0.5]
//                          [--leaf 8] [--group 64] [--sample 500] [--header]
//                          [--kernel functor|generated] [--opening box|com|offset]
//                          [--neighbours 50]
//
// --kernel and --opening as in bench_tree: `generated` is kernels/gravity.pik through
// pikg-gen (TARGET auto, AVX-512 where the CPU has it), `functor` the hand-written
// functor of bench/tree/gravity_functor.hpp; `offset` is Opening::centre_of_mass_offset.
//
// With --neighbours K it times the distributed neighbour search instead: uniform
// particles in a periodic unit cube, gather radius for K neighbours on average, a
// density-like kernel; columns as below with the halo exchange in place of the LET,
// imported particles per rank and the mean neighbour count.
//
// Columns: ranks, OpenMP threads per rank, N, seconds per step (mean over steps
// 2..; step 1 is cold), CPU seconds per step of the busiest rank divided by its
// threads, the step split into decomposition / particle exchange / LET cut and
// exchange / force (tree, walk, kernel), bytes sent per rank per step (max and mean),
// particles and force cost per rank (max / mean), imported j- and super-particles per
// rank, interactions per particle, and the rms relative acceleration error against a
// direct sum on a sample.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include <sys/resource.h>

#include <pik/comm/Environment.hpp>
#include <pik/detail/Threads.hpp>
#include <pik/domain/DistributedLongRangeTree.hpp>
#include <pik/domain/DistributedShortRangeTree.hpp>
#include <pik/domain/DomainInfo.hpp>
#include <pik/domain/ParticleExchange.hpp>
#include <pik/particle/ParticleSystem.hpp>

#include "../tree/gravity_bench.hpp"

struct Body {
  pik::Vec3<double> pos, vel;
  double mass;
  pik::Vec3<double> acc;
  double pot;
  std::uint64_t id;
  const pik::Vec3<double>& getPos() const { return pos; }
  void setPos(const pik::Vec3<double>& p) { pos = p; }
  void copyFromForce(const Result& f) {
    acc = pik::vec_cast<pik::Vec3<double>>(f.acc);
    pot = f.pot;
  }
};

namespace {

struct Options {
  int log2n = 20, log2n_per_rank = -1, steps = 4, leaf = 8, group = 64, sample = 500;
  int neighbours = 0;  ///< > 0: neighbour-search benchmark
  double theta = 0.5;
  pik::Opening opening = pik::Opening::box;
  bool generated = false;  ///< --kernel generated: kernels/gravity.pik through pikg-gen
  bool header = false;
};

const char* const usage =
    "usage: mpirun -np P bench_mpi [--log2n 20 | --log2n-per-rank 17] [--steps 4] [--theta 0.5]\n"
    "                              [--leaf 8] [--group 64] [--sample 500] [--header] [--neighbours 50]\n"
    "                              [--kernel functor|generated] [--opening box|com|offset]\n";

/// Thrown by parse() to end the program with this status (MPI finalized normally).
struct UsageExit {
  int status;
};

/// Every rank parses the same arguments, so a usage error ends every rank alike:
/// one message from rank 0 and exit status 2, without MPI_Abort's noise.
Options parse(int argc, char** argv, const pik::Comm& comm) {
  Options o;
  auto fail = [&](const std::string& why) {
    if (comm.is_root()) std::fprintf(stderr, "bench_mpi: error: %s\n%s", why.c_str(), usage);
    throw UsageExit{2};
  };
  for (int a = 1; a < argc; ++a) {
    const std::string k = argv[a];
    if (k == "--help") {
      if (comm.is_root()) std::printf("%s", usage);
      throw UsageExit{0};
    }
    if (k == "--header") {
      o.header = true;
      continue;
    }
    if (a + 1 >= argc) fail("option " + k + " needs a value");
    const char* v = argv[++a];
    const std::string w = v;
    if (k == "--opening") {
      if (w == "box") o.opening = pik::Opening::box;
      else if (w == "com") o.opening = pik::Opening::centre_of_mass;
      else if (w == "offset") o.opening = pik::Opening::centre_of_mass_offset;
      else fail("--opening must be box, com or offset, got " + w);
      continue;
    }
    if (k == "--kernel") {
      if (w != "functor" && w != "generated") fail("--kernel must be functor or generated, got " + w);
      o.generated = w == "generated";
      continue;
    }
    char* end = nullptr;
    const double x = std::strtod(v, &end);
    if (end == v || *end || !std::isfinite(x)) fail("option " + k + ": not a number: " + v);
    const bool log2 = k == "--log2n" || k == "--log2n-per-rank";
    if (k != "--theta" && !(x >= 0 && x <= (log2 ? 40 : 1e9))) fail("option " + k + ": out of range: " + v);
    if (k == "--log2n") o.log2n = int(x);
    else if (k == "--log2n-per-rank") o.log2n_per_rank = int(x);
    else if (k == "--steps") o.steps = int(x);
    else if (k == "--theta") o.theta = x;
    else if (k == "--leaf") o.leaf = int(x);
    else if (k == "--group") o.group = int(x);
    else if (k == "--sample") o.sample = int(x);
    else if (k == "--neighbours") o.neighbours = int(x);
    else fail("unknown option " + k);
  }
  if (o.steps < 2) fail("--steps must be at least 2");
  return o;
}

// Rank r's share of a cold uniform sphere of radius 1 and mass 1; particle i is
// drawn from its own seeded stream, so the global set does not depend on the ranks.
std::vector<Body> make_sphere(std::uint64_t n, const pik::Comm& comm) {
  std::vector<Body> out;
  const auto p = std::uint64_t(comm.size()), r = std::uint64_t(comm.rank());
  const std::uint64_t b = n * r / p, e = n * (r + 1) / p;
  out.reserve(e - b);
  std::mt19937_64 rng;
  std::uniform_real_distribution<double> u(-1, 1);
  for (std::uint64_t i = b; i < e; ++i) {
    rng.seed(0x5eed0000ull + i);
    pik::Vec3<double> x;
    do x = {u(rng), u(rng), u(rng)};
    while (x.x * x.x + x.y * x.y + x.z * x.z > 1);
    out.push_back({x, {}, 1.0 / double(n), {}, 0, i});
  }
  return out;
}

/// CPU seconds (user + system, all threads) of this process so far.
double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

struct MaxMean {
  double max, mean;
};
MaxMean max_mean(const pik::Comm& c, double v) { return {c.max(v), c.sum(v) / c.size()}; }

// rms relative acceleration error on particles with id % stride == 0, against a
// direct sum in double over all particles (every rank adds its part).
double rms_error(const pik::ParticleSystem<Body>& ps, const pik::Comm& comm, std::uint64_t stride,
                 float eps2) {
  struct Probe {
    pik::Vec3<double> pos, acc;
  };
  std::vector<Probe> mine;
  for (const Body& b : ps)
    if (b.id % stride == 0) mine.push_back({b.pos, b.acc});
  const auto probes = comm.allgatherv(std::span<const Probe>(mine));
  std::vector<double> acc(3 * probes.size(), 0.0);
  for (std::size_t k = 0; k < probes.size(); ++k) {
    double ax = 0, ay = 0, az = 0;
    for (const Body& b : ps) {
      const double dx = probes[k].pos.x - b.pos.x, dy = probes[k].pos.y - b.pos.y, dz = probes[k].pos.z - b.pos.z;
      const double r2 = dx * dx + dy * dy + dz * dz + eps2, rinv = 1 / std::sqrt(r2);
      const double m3 = b.mass * rinv * rinv * rinv;
      ax -= m3 * dx, ay -= m3 * dy, az -= m3 * dz;
    }
    acc[3 * k] = ax, acc[3 * k + 1] = ay, acc[3 * k + 2] = az;
  }
  comm.reduce_inplace(std::span<double>(acc), pik::comm::ReduceOp::sum);
  double s2 = 0;
  for (std::size_t k = 0; k < probes.size(); ++k) {
    const double ex = probes[k].acc.x - acc[3 * k], ey = probes[k].acc.y - acc[3 * k + 1],
                 ez = probes[k].acc.z - acc[3 * k + 2];
    s2 += (ex * ex + ey * ey + ez * ez) /
          (acc[3 * k] * acc[3 * k] + acc[3 * k + 1] * acc[3 * k + 1] + acc[3 * k + 2] * acc[3 * k + 2]);
  }
  return probes.empty() ? 0.0 : std::sqrt(s2 / double(probes.size()));
}

// ---- neighbour search -------------------------------------------------------------
struct Density {
  float rho;
  std::uint32_t n;
  void clear() { rho = 0, n = 0; }
};
struct Gas {
  pik::Vec3<double> pos;
  double mass, h;
  float rho;
  std::uint32_t n;
  std::uint64_t id;
  const pik::Vec3<double>& getPos() const { return pos; }
  void setPos(const pik::Vec3<double>& p) { pos = p; }
  void copyFromForce(const Density& d) { rho = d.rho, n = d.n; }
};
struct GasEP {
  pik::Vec3<float> pos;
  float mass, h;
  pik::Vec3<float> getPos() const { return pos; }
  void setPos(const pik::Vec3<float>& p) { pos = p; }
  float getRSearch() const { return h; }
  void copyFromFP(const Gas& g) { pos = pik::vec_cast<pik::Vec3<float>>(g.pos), mass = float(g.mass), h = float(g.h); }
};
// Gather density with the kernel (1 - q^2)^3 inside q = r / h < 1 (unnormalised).
struct DensityKernel {
  void operator()(const GasEP* ei, int ni, const GasEP* ej, int nj, Density* f) const {
    for (int i = 0; i < ni; ++i) {
      const float hinv2 = 1 / (ei[i].h * ei[i].h);
      float rho = 0;
      std::uint32_t n = 0;
      for (int j = 0; j < nj; ++j) {
        const float dx = ei[i].pos.x - ej[j].pos.x, dy = ei[i].pos.y - ej[j].pos.y, dz = ei[i].pos.z - ej[j].pos.z;
        const float q2 = (dx * dx + dy * dy + dz * dz) * hinv2;
        const float w = q2 < 1 ? (1 - q2) * (1 - q2) * (1 - q2) : 0.0f;
        rho += ej[j].mass * w;
        n += q2 < 1;
      }
      f[i].rho += rho, f[i].n += n;
    }
  }
};

int run_short(const Options& o, const pik::Comm& comm, std::uint64_t n) {
  const auto p = std::uint64_t(comm.size()), r = std::uint64_t(comm.rank());
  const double h = std::cbrt(3.0 * o.neighbours / (4 * M_PI * double(n)));
  std::vector<Gas> mine;
  std::mt19937_64 rng;
  std::uniform_real_distribution<double> u(0, 1);
  for (std::uint64_t i = n * r / p; i < n * (r + 1) / p; ++i) {
    rng.seed(0x6a5ull + i);
    mine.push_back({{u(rng), u(rng), u(rng)}, 1.0 / double(n), h, 0, 0, i});
  }
  pik::ParticleSystem<Gas> ps(std::move(mine));
  const auto box = pik::Boundary<3>::periodic_box({0, 0, 0}, {1, 1, 1});
  pik::DomainInfo<double, 3> dinfo(comm);
  dinfo.set_root_domain(box);
  pik::TreeParams tp;
  tp.n_leaf_limit = o.leaf, tp.n_group_limit = o.group;
  pik::DistributedShortRangeTree<Density, GasEP, GasEP, pik::SearchMode::gather> tree(tp, box);
  double t_dec = 0, t_exch = 0, t_halo = 0, t_force = 0, bytes = 0, imported = 0, cost = 0;
  for (int s = 0; s < o.steps; ++s) {
    comm.barrier();
    comm.reset_stats();
    const double t0 = comm.wtime();
    dinfo.decompose(ps.vector(), tree.cost());
    const double t1 = comm.wtime();
    pik::exchange_particles(ps, dinfo);
    const double t2 = comm.wtime();
    tree.calcForceAllAndWriteBack(DensityKernel{}, ps, comm);
    const double t3 = comm.wtime();
    // A random walk of a tenth of the radius (wrapped by the next exchange).
    for (Gas& g : ps) {
      rng.seed(0x77ull * (g.id + 1) + std::uint64_t(s));
      g.pos += pik::Vec3<double>{u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5} * (0.2 * h);
    }
    if (s == 0) continue;
    t_dec += comm.max(t1 - t0);
    t_exch += comm.max(t2 - t1);
    t_halo += comm.max(tree.haloSeconds());
    t_force += comm.max(t3 - t2 - tree.haloSeconds());
    bytes += double(comm.stats().bytes_sent);
    imported += double(tree.haloStats().received);
    cost += tree.cost();
  }
  double nb = 0;
  for (const Gas& g : ps) nb += g.n;
  nb = comm.sum(nb) / double(n);
  const double k = o.steps - 1;
  const auto b = max_mean(comm, bytes / k);
  const auto np = max_mean(comm, double(ps.size()));
  const auto c = max_mean(comm, cost / k);
  const auto im = max_mean(comm, imported / k);
  if (comm.is_root()) {
    if (o.header) {
      std::printf("| ranks | threads | N | s/step | decomp | exch | halo | force | MB sent/rank max | mean | "
                  "particles max/mean | cost max/mean | imported max | mean | neighbours |\n");
      std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    }
    std::printf("| %d | %d | 2^%.0f | %.3f | %.3f | %.3f | %.3f | %.3f | %.2f | %.2f | %.3f | %.3f | %.0f | %.0f | %.1f |\n",
                comm.size(), pik::detail::max_threads(), std::log2(double(n)), (t_dec + t_exch + t_halo + t_force) / k,
                t_dec / k, t_exch / k, t_halo / k, t_force / k, b.max / 1e6, b.mean / 1e6, np.max / np.mean,
                c.mean > 0 ? c.max / c.mean : 1.0, im.max, im.mean, nb);
  }
  return 0;
}

// The long-range benchmark with the pair kernels KernelEP (EPJ) and KernelSP (SPJ).
template <class KernelEP, class KernelSP>
int run_long(const Options& o, const pik::Comm& comm, std::uint64_t n) {
  const float eps2 = float(1e-4 / std::cbrt(double(n) / 1048576.0));
  const KernelEP kernel{eps2};
  const KernelSP kernel_sp{eps2};

  pik::ParticleSystem<Body> ps(make_sphere(n, comm));
  pik::DomainInfo<double, 3> dinfo(comm);
  pik::TreeParams tp;
  tp.theta = o.theta, tp.n_leaf_limit = o.leaf, tp.n_group_limit = o.group, tp.opening = o.opening;
  pik::DistributedLongRangeTree<Result, EPI, EPJ, SPJ> tree(tp);

  double t_dec = 0, t_exch = 0, t_let = 0, t_force = 0;
  double bytes = 0, imp_epj = 0, imp_spj = 0, cost = 0, cpu = 0, inter = 0;
  const double dt = 1.0 / 256;
  for (int s = 0; s < o.steps; ++s) {
    comm.barrier();
    comm.reset_stats();
    const double t0 = comm.wtime(), c0 = cpu_seconds();
    dinfo.decompose(ps.vector(), tree.cost());
    const double t1 = comm.wtime();
    pik::exchange_particles(ps, dinfo);
    const double t2 = comm.wtime();
    tree.calcForceAllAndWriteBack(kernel, kernel_sp, ps, comm);
    const double t3 = comm.wtime(), c1 = cpu_seconds();
    // Kick and drift (leapfrog, kick-drift form), so particles move between steps.
    for (Body& b : ps) {
      b.vel += b.acc * dt;
      b.pos += b.vel * dt;
    }
    if (s == 0) continue;  // step 1 is cold (first allocations, first decomposition)
    t_dec += comm.max(t1 - t0);
    t_exch += comm.max(t2 - t1);
    t_let += comm.max(tree.letSeconds());
    t_force += comm.max(t3 - t2 - tree.letSeconds());
    bytes += double(comm.stats().bytes_sent);
    imp_epj += double(tree.letStats().epj_received);
    imp_spj += double(tree.letStats().spj_received);
    cost += tree.cost();
    cpu += c1 - c0;
    inter += double(tree.tree().interactionsEP() + tree.tree().interactionsSP());
  }
  const double k = o.steps - 1;
  const auto b = max_mean(comm, bytes / k);
  const auto np = max_mean(comm, double(ps.size()));
  const auto c = max_mean(comm, cost / k);
  const double cpu_thr = comm.max(cpu / k / pik::detail::max_threads());
  const double per_particle = comm.sum(inter / k) / double(n);
  const auto ie = max_mean(comm, imp_epj / k), is = max_mean(comm, imp_spj / k);
  const std::uint64_t stride = std::max<std::uint64_t>(1, n / std::uint64_t(std::max(1, o.sample)));
  const double err = rms_error(ps, comm, stride, eps2);
  if (comm.is_root()) {
    if (o.header) {
      std::printf("| ranks | threads | N | s/step | cpu/thr | decomp | exch | LET | force | MB sent/rank max | mean | "
                  "particles max/mean | cost max/mean | imported EPJ | SPJ | EP+SP/part | rms err |\n");
      std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    }
    const double step = (t_dec + t_exch + t_let + t_force) / k;
    std::printf("| %d | %d | 2^%.0f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.2f | %.2f | %.3f | %.3f | %.0f | %.0f | %.0f | %.2e |\n",
                comm.size(), pik::detail::max_threads(), std::log2(double(n)), step, cpu_thr, t_dec / k, t_exch / k,
                t_let / k, t_force / k, b.max / 1e6, b.mean / 1e6, np.max / np.mean,
                c.mean > 0 ? c.max / c.mean : 1.0, ie.mean, is.mean, per_particle, err);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  pik::Environment env(argc, argv);
  const pik::Comm comm = env.world();
  Options o;
  try {
    o = parse(argc, argv, comm);
  } catch (const UsageExit& e) {
    return e.status;
  }
  const std::uint64_t n = o.log2n_per_rank >= 0
                              ? (std::uint64_t(1) << o.log2n_per_rank) * std::uint64_t(comm.size())
                              : std::uint64_t(1) << o.log2n;
  if (o.neighbours > 0) return run_short(o, comm, n);
  if (o.generated) return run_long<GravityGenerated, GravityGeneratedSP>(o, comm, n);
  return run_long<GravityFunctor<EPI, Result>, GravityFunctor<EPI, Result>>(o, comm, n);
}
