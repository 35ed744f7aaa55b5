// bench_shortrange: seconds per SPH step spent in the short-range search
// (pik/walk/ShortRangeTree.hpp) on an impact-like distribution.
//
// Setup: two spheres of uniform density 1 (target 90 % of N, impactor 10 %, touching
// at the impact point), particles on a cubic lattice of spacing dx with a fixed
// deterministic jitter of 0.2 dx, mass dx^3, open boundaries; smoothing lengths from
// the smoothing-length iteration (pik/sph/SmoothingLength.hpp, N_ngb 50, tol 1e-2),
// cubic spline (kernels/sph_density.pik, kernels/sph_force_disph.pik, shape 0).
//
// One step, as the impact program's force evaluation (examples/impact/Model.hpp):
//   - every particle moves by up to 0.02 dx and h is perturbed by up to +-3 %
//     (deterministic, from the particle id and the step): a new tree build;
//   - density: the h iteration, the first pass over every group, later passes over
//     the groups holding a particle whose h changed (refresh() between passes);
//   - hydro: buildLike() of the density tree, one DISPH pass (symmetric search).
// The kernels are timed per call (search = walk+kernel - kernel). After the steps one
// more pass per tree with a kernel that does nothing measures the search alone.
//
//   bench_shortrange [--n N] [--steps S] [--threads T] [--leaf L] [--group G]
//                    (defaults: 100000 particles, 5 steps, the runtime's threads, 8, 32)
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <ctime>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

#include <pik/sph/SmoothingLength.hpp>

#include "SphTypes.hpp"
#include "SrDensity.hpp"
#include "SrDisph.hpp"

namespace {

int thread_id() {
#ifdef _OPENMP
  return omp_get_thread_num();
#else
  return 0;
#endif
}

/// The clock of every figure: with one thread the CPU time of this thread (true under
/// load: the machine's other jobs do not count), else the wall-clock time.
bool g_thread_clock = false;
double now() {
  if (!g_thread_clock) return pik::wall_time();
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

/// A kernel that also adds the seconds it runs to its thread's slot.
template <class K>
struct Timed {
  const K& k;
  double* seconds;  // one slot per thread, 8 apart (no false sharing)
  template <class EPI, class EPJ, class F>
  void operator()(const EPI* i, int ni, const EPJ* j, int nj, F* f) const {
    const double t0 = now();
    k(i, ni, j, nj, f);
    seconds[8 * thread_id()] += now() - t0;
  }
};
struct NullKernel {
  template <class EPI, class EPJ, class F>
  void operator()(const EPI*, int, const EPJ*, int, F*) const {}
};

/// A deterministic number in [0, 1) from two integers (splitmix64).
double hash01(std::uint64_t a, std::uint64_t b) {
  std::uint64_t z = a * 0x9E3779B97F4A7C15ull + b + 0x632BE59BD9B4E019ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return double(z >> 11) * 0x1.0p-53;
}

/// Two lattice spheres: target of radius 1 (0.9 n) and impactor (0.1 n) touching it.
std::vector<Particle<3>> two_spheres(long n, double& dx) {
  const double pi = std::acos(-1.0);
  const double r_t = 1.0, r_i = std::cbrt(0.1 / 0.9);
  const double volume = 4.0 / 3.0 * pi * (r_t * r_t * r_t + r_i * r_i * r_i);
  dx = std::cbrt(volume / double(n));
  std::vector<Particle<3>> p;
  auto sphere = [&](Vec3d c, double r) {
    const int m = int(std::ceil(r / dx)) + 1;
    for (int i = -m; i <= m; ++i)
      for (int j = -m; j <= m; ++j)
        for (int k = -m; k <= m; ++k) {
          const std::uint64_t id = p.size();
          Vec3d x{(i + 0.2 * (hash01(id, 1) - 0.5)) * dx, (j + 0.2 * (hash01(id, 2) - 0.5)) * dx,
                  (k + 0.2 * (hash01(id, 3) - 0.5)) * dx};
          if (pik::norm2(x) >= r * r) continue;
          Particle<3> q;
          q.id = std::uint32_t(id), q.pos = c + x, q.mass = dx * dx * dx, q.u = 1, q.h = 2.3 * dx;
          q.rho = 1, q.pres = 0.4, q.cs = std::sqrt(1.4 * 0.4), q.pf = 0.4, q.balsara = 1;
          p.push_back(q);
        }
  };
  sphere({0, 0, 0}, r_t);
  // the impactor at 45 degrees, just touching
  const double s = (r_t + r_i + 0.5 * dx) / std::sqrt(2.0);
  sphere({s, s, 0}, r_i);
  return p;
}

struct Acc {
  double build = 0, refresh = 0, dsearch = 0, dkernel = 0, like = 0, hsearch = 0, hkernel = 0, wb = 0;
  double step = 0, passes = 0, walked = 0, slots = 0, cand_d = 0, cand_h = 0;
};

}  // namespace

int main(int argc, char** argv) {
  long n = 100000;
  int steps = 5, threads = 0, leaf = 8, group = 32;
  const char* usage =
      "usage: bench_shortrange [--n N] [--steps S] [--threads T] [--leaf L] [--group G]\n"
      "  (defaults: 100000 particles, 5 steps, the runtime's threads, leaf 8, group 32)\n";
  for (int a = 1; a < argc; ++a) {
    const std::string s = argv[a];
    if (s == "--help") return std::printf("%s", usage), 0;
    const bool known = s == "--n" || s == "--steps" || s == "--threads" || s == "--leaf" || s == "--group";
    char* end = nullptr;
    const long v = known && a + 1 < argc ? std::strtol(argv[++a], &end, 10) : -1;
    if (!known || !end || *end || end == argv[a] || v < 1 || v > 100000000) {
      std::fprintf(stderr, "bench_shortrange: bad option or value: %s\n%s", s.c_str(), usage);
      return 2;
    }
    if (s == "--n") n = v;
    else if (s == "--steps") steps = int(v);
    else if (s == "--threads") threads = int(v);
    else if (s == "--leaf") leaf = int(v);
    else group = int(v);
  }
  if (n < 100) return std::fprintf(stderr, "bench_shortrange: --n must be at least 100\n"), 2;
  if (threads) pik::detail::set_threads(threads);
  threads = pik::detail::max_threads();
  g_thread_clock = threads == 1;

  double dx = 0;
  pik::ParticleSystem<Particle<3>> ps(two_spheres(n, dx));
  const pik::TreeParams tp{.n_leaf_limit = leaf, .n_group_limit = group};
  pik::ShortRangeTree<DensityResult, SphEP3, SphEP3, pik::SearchMode::gather> dtree(tp);
  pik::ShortRangeTree<HydroResult, SphEP3, SphEP3, pik::SearchMode::symmetric> htree(tp);
  const SrDensity density;
  const SrDisph disph(1.0f, 1.4f);
  std::vector<double> kd(8 * 256), kh(8 * 256);
  const Timed<SrDensity> td{density, kd.data()};
  const Timed<SrDisph> th{disph, kh.data()};
  const pik::sph::SmoothingLengthParams hp{.nngb = 50, .tol = 1e-2, .max_passes = 50, .fixed_h = 0};

  std::printf("bench_shortrange: two lattice spheres (90 %% / 10 %%), %zu particles, N_ngb 50, leaf %d, group %d, "
              "%d thread(s), %d steps; kernels %s\n",
              ps.size(), leaf, group, threads, steps, SrDensity::isa_name());

  Acc acc;
  auto ksum = [&](std::vector<double>& k) {
    double s = 0;
    for (int t = 0; t < 256; ++t) s += k[8 * t];
    std::fill(k.begin(), k.end(), 0.0);
    return s / threads;
  };
  for (int step = -1; step < steps; ++step) {  // step -1: converges h from the setup (not counted)
    if (step >= 0)
      for (auto& p : ps) {
        // small moves of every particle; a few (0.2 %) get an h off by 10 %, so that the
        // iteration makes a second pass over a few groups, as in the impact program
        const std::uint64_t id = p.id, st = std::uint64_t(step) * 8;
        p.pos += Vec3d{hash01(id, st + 4) - 0.5, hash01(id, st + 5) - 0.5, hash01(id, st + 6) - 0.5} * (0.04 * dx);
        if (hash01(id, st + 7) < 0.002) p.h *= 1.1;
      }
    ksum(kd), ksum(kh);
    double t_build = 0, t_refresh = 0, t_dwalk = 0;
    const double t0 = now();
    bool first = true;
    double walked = 0, slots = 0, cand = 0;
    auto pass = [&](std::span<const std::uint8_t> active) {
      const double a0 = now();
      if (first) dtree.build(ps);
      else dtree.refresh(ps);
      const double a1 = now();
      dtree.calcForceOnTreeAndWriteBack(td, ps, first ? std::span<const std::uint8_t>{} : active);
      const double a2 = now();
      (first ? t_build : t_refresh) += a1 - a0, t_dwalk += a2 - a1;
      if (first) cand = double(dtree.interactions());
      walked += double(dtree.groupsWalked()), slots += double(dtree.groups().size());
      first = false;
    };
    const int passes = pik::sph::iterate_smoothing_length<3>(ps, pass, hp);
    for (auto& p : ps) {  // an ideal-gas EOS at the new density (what the hydro kernel reads)
      p.rho_ep = p.rho, p.pres = 0.4 * p.rho * p.u, p.cs = std::sqrt(1.4 * 0.4 * p.u), p.pf = p.pres / (p.rho * p.rho);
    }
    const double b0 = now();
    htree.buildLike(dtree, ps);
    const double b1 = now();
    htree.calcForceOnTreeAndWriteBack(th, ps);
    const double t1 = now();
    if (step < 0) continue;
    const double dk = ksum(kd), hk = ksum(kh);
    acc.step += t1 - t0;
    acc.build += t_build, acc.refresh += t_refresh;
    acc.dkernel += dk, acc.dsearch += t_dwalk - dk;
    acc.like += b1 - b0;
    acc.hkernel += hk, acc.hsearch += t1 - b1 - hk;
    acc.passes += passes, acc.walked += walked, acc.slots += slots;
    acc.cand_d += cand, acc.cand_h += double(htree.interactions());
  }
  // The search alone: one full pass per tree with a kernel that does nothing (into a
  // copy of the particles, which it fills with zeros).
  pik::ParticleSystem<Particle<3>> scratch = ps;
  const NullKernel none;
  double null_d = 0, null_h = 0;
  for (int r = 0; r < steps; ++r) {
    const double c0 = now();
    dtree.calcForceOnTreeAndWriteBack(none, scratch);
    const double c1 = now();
    htree.calcForceOnTreeAndWriteBack(none, scratch);
    null_d += c1 - c0, null_h += now() - c1;
  }
  null_d /= steps, null_h /= steps;

  const double k = 1.0 / steps, np = double(ps.size());
  std::printf("\n%s seconds per step (mean of %d; search = walk + write-back minus the kernel's own time)\n\n",
              g_thread_clock ? "CPU (one thread)" : "wall", steps);
  std::printf("| part | s/step |\n|---|---|\n");
  std::printf("| density: tree build (first pass) | %.4f |\n", acc.build * k);
  std::printf("| density: refresh (later passes) | %.4f |\n", acc.refresh * k);
  std::printf("| density: search | %.4f |\n", acc.dsearch * k);
  std::printf("| density: kernel | %.4f |\n", acc.dkernel * k);
  std::printf("| hydro: buildLike | %.4f |\n", acc.like * k);
  std::printf("| hydro: search | %.4f |\n", acc.hsearch * k);
  std::printf("| hydro: kernel | %.4f |\n", acc.hkernel * k);
  std::printf("| **step** (incl. h update, EOS) | **%.4f** |\n", acc.step * k);
  std::printf("\n| counts per step | |\n|---|---|\n");
  std::printf("| density passes | %.2f |\n", acc.passes * k);
  std::printf("| groups walked / (groups x passes) | %.3f |\n", acc.walked / acc.slots);
  std::printf("| density candidates per particle (first pass) | %.1f |\n", acc.cand_d * k / np);
  std::printf("| hydro candidates per particle | %.1f |\n", acc.cand_h * k / np);
  std::printf("\nsearch alone (a kernel that does nothing, full pass): density %.4f s, hydro %.4f s\n", null_d, null_h);
  std::printf("summary: search %.4f s/step of %.4f (density %.4f, hydro %.4f); null-kernel pass %.4f + %.4f s\n",
              (acc.dsearch + acc.hsearch) * k, acc.step * k, acc.dsearch * k, acc.hsearch * k, null_d, null_h);
  return 0;
}
