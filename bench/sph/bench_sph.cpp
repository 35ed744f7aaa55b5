// bench_sph: seconds per SPH step on two 3D shock tubes with fixed smoothing lengths
// (cubic spline), one density pass and one hydro-force pass per step, and the leapfrog
// update (SPSPH: its pseudo-density and density too). One tree build per step: the
// density pass collects each group's candidates once, the hydro pass takes the same
// octree and lists (ShortRangeTree::keepCandidates, buildLike); `--lists walk` gives
// each pass its own tree build and walk instead, as FDPS's sample does:
//
//   pik   pik's own Sod-type tube (not FDPS's setup): rho 1 | 0.125, P 1 | 0.1, cubic
//         lattices of spacing 1/64 | 1/32 in a periodic 5 x 0.25 x 0.25 box, 16,384 +
//         8,192 = 24,576 particles, support h = 2.3 spacings (~50 neighbours). Every
//         scheme (ssph, disph, spsph).
//   fdps  the setup of FDPS's SPH sample (sample/c++/sph, SetupIC): a periodic
//         1 x 1/8 x 1/8 box, x < 0.5 a lattice of spacing 1/128 (rho 1), x >= 0.5
//         spacing 1/64 along x and 1/128 across (rho 0.5), particle mass 0.75 V / N,
//         u = 2.5, fixed h = 0.012 with FDPS's support 2.5 h = 0.03 (pik's h is the
//         support radius: 0.03), 16,384 + 8,192 = 24,576 particles, ~200 neighbours
//         on average (~240 left, ~120 right). SSPH only (the sample's scheme).
//
// Prints a table row per setup, scheme, thread count and group size, with the time
// split into tree build, neighbour search (walk without kernel) and kernel.
//
//   bench_sph [--steps N] [--threads T] [--setup pik|fdps|both] [--lists kept|walk]
//             (default: 10 steps, 1 and 2 threads, both setups, kept lists)
#include <cstdio>
#include <cstdlib>
#include <string>
#include <type_traits>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "SphTypes.hpp"
#include "SphDensity.hpp"
#include "SphForceDisph.hpp"
#include "SphForceSsph.hpp"
#include "SphForceSpsph.hpp"

namespace {

int thread_id() {
#ifdef _OPENMP
  return omp_get_thread_num();
#else
  return 0;
#endif
}

/// A kernel that also adds the seconds it runs to its thread's slot.
template <class K>
struct Timed {
  const K& k;
  double* seconds;  // one slot per thread, 8 apart (no false sharing)
  template <class EPI, class EPJ, class F>
  void operator()(const EPI* i, int ni, const EPJ* j, int nj, F* f) const {
    const double t0 = pik::wall_time();
    k(i, ni, j, nj, f);
    seconds[8 * thread_id()] += pik::wall_time() - t0;
  }
};

/// Shock tube: x in [-0.5, 0.5) rho 1, P 1 on a lattice of spacing 1/64, 16 x 16
/// across; x in [0.5, 4.5) rho 0.125, P 0.1, spacing 1/32, 8 x 8 across: 16384 + 8192
/// = 24576 particles. Fixed support h = 2.3 spacings (about 50 neighbours).
std::vector<Particle<3>> tube() {
  std::vector<Particle<3>> p;
  const double d = 1.0 / 64, side = 16 * d, gamma = 1.4;
  auto add = [&](double x0, int nx, double dx, double rho, double pres) {
    const int ny = int(side / dx + 0.5);
    for (int i = 0; i < nx; ++i)
      for (int j = 0; j < ny; ++j)
        for (int k = 0; k < ny; ++k) {
          Particle<3> q;
          q.pos = {x0 + (i + 0.5) * dx, (j + 0.5) * dx, (k + 0.5) * dx};
          q.mass = d * d * d, q.u = pres / ((gamma - 1) * rho), q.h = 2.3 * dx;
          q.rho = rho, q.pres = pres, q.cs = std::sqrt(gamma * pres / rho), q.id = std::uint32_t(p.size());
          p.push_back(q);
        }
  };
  add(-0.5, 64, d, 1.0, 1.0);
  add(0.5, 128, 2 * d, 0.125, 0.1);
  return p;
}

/// FDPS's SPH sample's initial condition (its SetupIC, re-expressed): lattice points
/// from the box corner, x < 0.5 spacing dx = 1/128, x >= 0.5 spacing 2 dx along x.
std::vector<Particle<3>> fdps_tube() {
  std::vector<Particle<3>> p;
  const double dx = 1.0 / 128, lx = 1, ly = lx / 8, gamma = 1.4;
  const int ny = int(ly / dx + 0.5);
  const int n = (int(0.5 * lx / dx + 0.5) + int(0.5 * lx / (2 * dx) + 0.5)) * ny * ny;
  const double sv = lx * ly * ly / n;
  auto add = [&](double x0, double x1, double step, double rho) {
    for (double x = x0; x < x1 - 1e-12; x += step)
      for (int j = 0; j < ny; ++j)
        for (int k = 0; k < ny; ++k) {
          Particle<3> q;
          q.pos = {x, j * dx, k * dx};
          q.mass = 0.75 * sv, q.u = 2.5, q.h = 2.5 * 0.012, q.rho = rho;
          q.pres = (gamma - 1) * rho * q.u, q.cs = std::sqrt(gamma * q.pres / rho), q.id = std::uint32_t(p.size());
          p.push_back(q);
        }
  };
  add(0, 0.5 * lx, dx, 1.0);
  add(0.5 * lx, lx, 2 * dx, 0.5);
  return p;
}

struct Row {
  double step, dens_tree, dens_search, dens_kernel, hyd_tree, hyd_search, hyd_kernel, update;
  double pairs_dens, pairs_hyd;
};

bool g_kept = true;  ///< --lists kept (true) or walk

template <class Force>
Row run(const char* setup, const char* scheme, int threads, int group, int steps) {
  pik::detail::set_threads(threads);
  const double gamma = 1.4;
  const bool fdps = std::string(setup) == "fdps";
  const auto box = fdps ? pik::Boundary<3>::periodic_box({0, 0, 0}, {1, 0.125, 0.125})
                        : pik::Boundary<3>::periodic_box({-0.5, 0, 0}, {4.5, 0.25, 0.25});
  pik::ParticleSystem<Particle<3>> ps(fdps ? fdps_tube() : tube());
  const pik::TreeParams tp{.n_leaf_limit = 8, .n_group_limit = group};
  pik::ShortRangeTree<DensityResult, SphEP3, SphEP3, pik::SearchMode::gather> dtree(tp, box);
  pik::ShortRangeTree<HydroResult, SphEP3, SphEP3, pik::SearchMode::symmetric> htree(tp, box);
  if (g_kept) dtree.keepCandidates(0), htree.keepCandidates(0);
  const SphDensity density;
  const Force force = [&] {
    if constexpr (std::is_same_v<Force, SphForceDisph>) return Force(1.0f, float(gamma));
    else if constexpr (std::is_same_v<Force, SphForceSpsph>) return Force(1.0f, 0.1f);  // alpha, alpha_y
    else return Force(1.0f);
  }();
  std::vector<double> kd(8 * 64), kh(8 * 64);
  const Timed<SphDensity> td{density, kd.data()};
  const Timed<Force> th{force, kh.data()};
  Row r{};
  const double dt = 1e-4;
  for (int s = -2; s < steps; ++s) {  // two warm-up steps
    if (s == 0) {
      dtree.profile() = {}, htree.profile() = {};
      std::fill(kd.begin(), kd.end(), 0.0), std::fill(kh.begin(), kh.end(), 0.0);
      r = {};
    }
    const double t0 = pik::wall_time();
    if (g_kept) {
      dtree.build(ps);
      dtree.calcForceOnTreeAndWriteBack(td, ps);
    } else {
      dtree.calcForceAllAndWriteBack(td, ps);
    }
    r.pairs_dens += double(dtree.interactions());
    const double t1 = pik::wall_time();
    constexpr bool spsph = std::is_same_v<Force, SphForceSpsph>;
    for (auto& p : ps) {
      // SPSPH: the pressure from its own density rho_t (integrated, started from the lattice's)
      if (spsph && !(p.rho_t > 0)) p.rho_t = p.rho, p.y = 1;
      p.rho_ep = spsph ? p.rho_t : p.rho;
      p.pres = (gamma - 1) * p.rho_ep * p.u, p.cs = std::sqrt(gamma * (gamma - 1) * p.u), p.balsara = 1, p.fgrad = 1;
      p.pf = spsph ? p.pres / (p.y * p.y) : p.pres / (p.rho * p.rho);
    }
    if (g_kept) {
      htree.buildLike(dtree, ps);  // same positions: the density tree's octree and lists
      htree.calcForceOnTreeAndWriteBack(th, ps);
    } else {
      htree.calcForceAllAndWriteBack(th, ps);
    }
    r.pairs_hyd += double(htree.interactions());
    const double t2 = pik::wall_time();
    for (auto& p : ps) {
      p.vel += p.acc * dt, p.u += p.dudt * dt, p.pos += p.vel * dt;
      if constexpr (spsph) p.rho_t += p.rho_t / p.y * p.dydt * dt, p.y += (p.dydt + p.ydiff) * dt;
    }
    ps.wrapPositions(box);
    const double t3 = pik::wall_time();
    if (s >= 0) r.update += (t1 - t0) * 0 + (t3 - t2), r.step += t3 - t0;
  }
  double ksum_d = 0, ksum_h = 0;
  for (int t = 0; t < 64; ++t) ksum_d += kd[8 * t], ksum_h += kh[8 * t];
  auto& pd = dtree.profile();
  auto& ph = htree.profile();
  const double n = steps;
  r.dens_tree = (pd.seconds("tree build") + pd.seconds("moments") + pd.seconds("write back")) / n;
  r.dens_kernel = ksum_d / threads / n;
  r.dens_search = pd.seconds("walk+kernel") / n - r.dens_kernel;
  r.hyd_tree = (ph.seconds("tree build") + ph.seconds("tree refresh") + ph.seconds("moments") + ph.seconds("write back")) / n;
  r.hyd_kernel = ksum_h / threads / n;
  r.hyd_search = ph.seconds("walk+kernel") / n - r.hyd_kernel;
  r.step /= n, r.update /= n, r.pairs_dens /= n, r.pairs_hyd /= n;
  std::printf("| %-5s | %-5s | %7d | %5d | %8.4f | %6.4f | %6.4f | %6.4f | %6.4f | %6.4f | %6.4f | %6.4f | %5.0f | %5.0f |\n",
              setup, scheme, threads, group, r.step, r.dens_tree, r.dens_search, r.dens_kernel, r.hyd_tree, r.hyd_search,
              r.hyd_kernel, r.update, r.pairs_dens / double(ps.size()), r.pairs_hyd / double(ps.size()));
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  int steps = 10, only_threads = 0;
  std::string setup = "both";
  const char* usage = "usage: bench_sph [--steps N] [--threads T] [--setup pik|fdps|both] [--lists kept|walk]\n";
  for (int a = 1; a < argc; ++a) {
    const std::string s = argv[a];
    if (s == "--help") return std::printf("%s", usage), 0;
    if (s == "--setup" && a + 1 < argc) {
      setup = argv[++a];
      if (setup != "pik" && setup != "fdps" && setup != "both") {
        std::fprintf(stderr, "bench_sph: --setup must be pik, fdps or both, got %s\n", setup.c_str());
        return 2;
      }
      continue;
    }
    if (s == "--lists" && a + 1 < argc) {
      const std::string l = argv[++a];
      if (l != "kept" && l != "walk") {
        std::fprintf(stderr, "bench_sph: --lists must be kept or walk, got %s\n", l.c_str());
        return 2;
      }
      g_kept = l == "kept";
      continue;
    }
    char* end = nullptr;
    const long v = (s == "--steps" || s == "--threads") && a + 1 < argc ? std::strtol(argv[++a], &end, 10) : -1;
    if (!end || *end || end == argv[a] || v < (s == "--steps" ? 1 : 0) || v > 1000000) {
      std::fprintf(stderr, "%s   (N >= 1; T >= 1, 0: 1 and 2)\n", usage);
      return 2;
    }
    (s == "--steps" ? steps : only_threads) = int(v);
  }
  std::printf("bench_sph: 3D shock tubes with fixed h (cubic spline), %d steps; kernels %s\n"
              "  pik:  pik's Sod-type tube, rho 1|0.125, 24576 particles, ~50 neighbours (all schemes)\n"
              "  fdps: the setup of FDPS's SPH sample, rho 1|0.5, 24576 particles, ~200 neighbours (ssph)\n"
              "lists: %s\n"
              "seconds per step (tree = build + moments + write-back of both trees;\n"
              "search = walk without kernel; pairs = candidates per particle handed to the kernel)\n\n",
              steps, SphDensity::isa_name(),
              g_kept ? "kept (one tree build and one candidate walk per step, shared by both passes)"
                     : "walk (each pass builds its tree and walks it)");
  std::printf("| setup | scheme | threads | group | s/step | dens tree | dens search | dens kernel | hydro tree | "
              "hydro search | hydro kernel | update | pairs dens | pairs hydro |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  const int maxt = pik::detail::max_threads();
  for (int threads : {1, 2}) {
    if (only_threads && threads != only_threads) continue;
    if (threads > maxt && !only_threads) continue;
    if (setup != "fdps") {
      for (int group : {16, 32, 64}) run<SphForceSsph>("pik", "ssph", threads, group, steps);
      run<SphForceDisph>("pik", "disph", threads, 32, steps);
      run<SphForceSpsph>("pik", "spsph", threads, 32, steps);
    }
    if (setup != "pik")
      for (int group : {16, 32, 64, 128}) run<SphForceSsph>("fdps", "ssph", threads, group, steps);
  }
  return 0;
}
