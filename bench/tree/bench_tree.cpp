// bench_tree: time per Barnes-Hut force step for a cold uniform sphere, split into
// tree build / moments / walk / kernel, with interactions per particle, rms relative
// acceleration error against a direct sum on a sample, peak memory, and the blocks of
// sibling cells the list making judged per i-group (blk/grp: the walk's work).
//
//   bench_tree [--min-log2n 14] [--max-log2n 20] [--threads 2] [--steps 3]
//              [--theta 0.5] [--leaf 12] [--group 128] [--sample 1000]
//              [--kernel functor|generated] [--opening box|com|offset]
//              [--multipole mono|quad] [--write-ic FILE]
//
// --write-ic FILE (one N only) writes the initial positions, uint64 n then n (x, y, z)
// doubles, so that another code (the FDPS driver of docs/bench-tree.md) starts from the
// same particles.
#include <sys/resource.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <pik/pik.hpp>

#include "gravity_bench.hpp"

using SPQ = pik::SPJQuadrupole<float>;
#include "GravityGeneratedQuad.hpp"

struct Body {
  pik::Vec3<double> pos, vel;
  double mass;
  pik::Vec3<double> acc;
  double pot;
  const pik::Vec3<double>& getPos() const { return pos; }
  void copyFromForce(const Result& f) {
    acc = pik::vec_cast<pik::Vec3<double>>(f.acc);
    pot = f.pot;
  }
};

namespace {

struct Options {
  std::string kernel = "functor";
  bool quad = false;
  pik::Opening opening = pik::Opening::box;
  // Leaf 12, not the library's 8 (pik::TreeParams): with 8 the sphere's cells at these
  // N split once more into leaves of ~3 particles, and a step costs 8-11 % more at the
  // same error (docs/bench-tree.md). Group 128, not 64: at 2^20 on 2 threads it gave the
  // fastest step of 64-256 for both the box and the offset criterion (Intel family 6
  // model 207 in session 3, AMD Zen 5 in session 7; docs/bench-tree.md).
  int min_log2n = 14, max_log2n = 20, threads = 2, steps = 3, leaf = 12, group = 128, sample = 1000;
  double theta = 0.5;
  std::string write_ic;
};

Options parse(int argc, char** argv) {
  Options o;
  for (int a = 1; a < argc; ++a) {
    std::string k = argv[a];
    if (k == "--help" || k == "-h") {
      std::printf("usage: bench_tree [--min-log2n 14] [--max-log2n 20] [--threads 2] [--steps 3]\n"
                  "                  [--theta 0.5] [--leaf 12] [--group 128] [--sample 1000]\n"
                  "                  [--kernel functor|generated] [--opening box|com|offset]\n"
                  "                  [--multipole mono|quad]   (quad: quadrupole cells, generated kernel)\n"
                  "                  [--write-ic FILE]         (initial positions, one N only)\n");
      std::exit(0);
    }
    if (a + 1 >= argc) {
      std::fprintf(stderr, "bench_tree: error: option %s needs a value\n", k.c_str());
      std::exit(2);
    }
    const char* v = argv[++a];
    if (k == "--opening") {
      const std::string w = v;
      if (w == "box") o.opening = pik::Opening::box;
      else if (w == "com") o.opening = pik::Opening::centre_of_mass;
      else if (w == "offset") o.opening = pik::Opening::centre_of_mass_offset;
      else {
        std::fprintf(stderr, "bench_tree: error: --opening must be box, com or offset, got %s\n", v);
        std::exit(2);
      }
      continue;
    }
    if (k == "--multipole") {
      const std::string w = v;
      if (w != "mono" && w != "quad") {
        std::fprintf(stderr, "bench_tree: error: --multipole must be mono or quad, got %s\n", v);
        std::exit(2);
      }
      o.quad = w == "quad";
      continue;
    }
    if (k == "--write-ic") {
      o.write_ic = v;
      continue;
    }
    if (k == "--kernel") {
      o.kernel = v;
      if (o.kernel != "functor" && o.kernel != "generated") {
        std::fprintf(stderr, "bench_tree: error: --kernel must be functor or generated, got %s\n", v);
        std::exit(2);
      }
      continue;
    }
    char* end = nullptr;
    double x = std::strtod(v, &end);
    if (end == v || *end) {
      std::fprintf(stderr, "bench_tree: error: %s: not a number: %s\n", k.c_str(), v);
      std::exit(2);
    }
    if (k == "--min-log2n") o.min_log2n = int(x);
    else if (k == "--max-log2n") o.max_log2n = int(x);
    else if (k == "--threads") o.threads = int(x);
    else if (k == "--steps") o.steps = int(x);
    else if (k == "--theta") o.theta = x;
    else if (k == "--leaf") o.leaf = int(x);
    else if (k == "--group") o.group = int(x);
    else if (k == "--sample") o.sample = int(x);
    else {
      std::fprintf(stderr, "bench_tree: error: unknown option %s (try --help)\n", k.c_str());
      std::exit(2);
    }
  }
  if (o.min_log2n < 1 || o.max_log2n > 26 || o.min_log2n > o.max_log2n || o.steps < 1 ||
      o.sample < 1) {
    std::fprintf(stderr, "bench_tree: error: bad sizes (need 1 <= min-log2n <= max-log2n <= 26)\n");
    std::exit(2);
  }
  if (o.leaf < 1 || o.group < 1 || o.threads < 1 || !(o.theta >= 0 && o.theta <= 2)) {
    std::fprintf(stderr, "bench_tree: error: need --leaf >= 1, --group >= 1, --threads >= 1, 0 <= --theta <= 2\n");
    std::exit(2);
  }
  if (!o.write_ic.empty() && o.min_log2n != o.max_log2n) {
    std::fprintf(stderr, "bench_tree: error: --write-ic needs one N (--min-log2n = --max-log2n)\n");
    std::exit(2);
  }
  if (o.quad && o.kernel != "generated") {
    std::fprintf(stderr, "bench_tree: error: --multipole quad needs --kernel generated\n");
    std::exit(2);
  }
  return o;
}

const char* opening_name(pik::Opening o) {
  switch (o) {
    case pik::Opening::box: return "box";
    case pik::Opening::centre_of_mass: return "com";
    case pik::Opening::centre_of_mass_offset: return "offset";
  }
  return "?";
}

/// CPU seconds (user + system) the process has used so far, all threads.
double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

double peak_rss_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;
}

template <class PS>
void write_positions(const std::string& file, const PS& ps) {
  std::FILE* f = std::fopen(file.c_str(), "wb");
  const std::uint64_t n = ps.size();
  bool ok = f && std::fwrite(&n, sizeof n, 1, f) == 1;
  for (const Body& b : ps) {
    const double x[3] = {b.pos.x, b.pos.y, b.pos.z};
    ok = ok && std::fwrite(x, sizeof x, 1, f) == 1;
  }
  if (f && std::fclose(f) != 0) ok = false;
  if (!ok) {
    std::fprintf(stderr, "bench_tree: error: --write-ic: cannot write %s\n", file.c_str());
    std::exit(2);
  }
}

}  // namespace

template <class KernelEP, class KernelSP, class SP = SPJ>
int run(const Options& o);

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  if (o.quad) return run<GravityGenerated, GravityGeneratedQuad, SPQ>(o);
  if (o.kernel == "generated") return run<GravityGenerated, GravityGeneratedSP>(o);
  return run<GravityFunctor<EPI, Result>, GravityFunctor<EPI, Result>>(o);
}

template <class KernelEP, class KernelSP, class SP>
int run(const Options& o) {
  pik::detail::set_threads(o.threads);
  std::printf("bench_tree: cold uniform sphere, theta=%.2f (opening %s), leaf %d, group %d, %d threads, %s cells, kernel: %s\n",
              o.theta, opening_name(o.opening), o.leaf, o.group, o.threads, o.quad ? "quadrupole" : "monopole",
              KernelEP::isa_name());
  std::printf("time per force step = mean over steps 2..%d (step 1 is cold); error vs direct sum on %d particles\n",
              std::max(2, o.steps + 1), o.sample);
  std::printf("cpu/thr = CPU seconds per step / threads: the step time of an idle machine with perfect\n"
              "balance (run with OMP_WAIT_POLICY=passive so that waiting threads do not count)\n");
  std::printf("%8s %9s %9s %9s %9s %9s %9s %9s %9s %10s %9s %8s %9s\n", "N", "step[s]", "cpu/thr", "build",
              "moments", "walk", "kernel", "wback", "EP/part", "SP/part", "rms err", "peak MB", "blk/grp");
  for (int lg = o.min_log2n; lg <= o.max_log2n; ++lg) {
    const std::size_t n = std::size_t(1) << lg;
    const double eps = 1.0 / 64, dt = 1.0 / 256;
    pik::ParticleSystem<Body> ps;
    ps.resize(n);
    std::mt19937_64 rng(12345 + lg);
    std::uniform_real_distribution<double> u(-1, 1);
    for (Body& b : ps) {
      double x, y, z;
      do x = u(rng), y = u(rng), z = u(rng);
      while (x * x + y * y + z * z > 1);
      b = Body{{x, y, z}, {}, 1.0 / double(n), {}, 0};
    }
    if (!o.write_ic.empty()) write_positions(o.write_ic, ps);
    pik::LongRangeTree<Result, EPI, EPJ, SP> tree({o.theta, o.leaf, o.group, o.opening});
    KernelEP kernel(float(eps * eps));
    KernelSP kernel_sp(float(eps * eps));
    double t_step = 0, t_cpu = 0;
    std::uint64_t ep = 0, sp = 0, visits = 0;
    // Leapfrog with the force of the step: particles move, as in a real run.
    for (int s = 0; s <= o.steps; ++s) {
      if (s == 1) tree.profile().clear();
      const double t0 = pik::wall_time(), c0 = cpu_seconds();
      tree.calcForceAllAndWriteBack(kernel, kernel_sp, ps);
      if (s >= 1) t_step += pik::wall_time() - t0, t_cpu += cpu_seconds() - c0;
      ep = tree.interactionsEP(), sp = tree.interactionsSP(), visits = tree.blocksVisited();
      if (s == o.steps) break;
      for (Body& b : ps) {
        b.vel += b.acc * dt;
        b.pos += b.vel * dt;
      }
    }
    // Error of the last force against a direct sum in double on a sample.
    const int ns = int(std::min<std::size_t>(std::size_t(o.sample), n));
    std::vector<double> err(static_cast<std::size_t>(ns));
    pik::detail::parallel_for(ns, [&](std::ptrdiff_t k, int) {
      const Body& bi = ps[std::size_t(k) * (n / std::size_t(ns))];
      pik::Vec3<double> a{};
      for (const Body& bj : ps) {
        pik::Vec3<double> d = bi.pos - bj.pos;
        double r2 = norm2(d) + eps * eps, rinv = 1 / std::sqrt(r2);
        a -= d * (bj.mass * rinv * rinv * rinv);
      }
      err[std::size_t(k)] = norm2(bi.acc - a) / norm2(a);
    });
    double e2 = 0;
    for (double e : err) e2 += e;
    const double steps = o.steps;
    const auto& p = tree.profile();
    std::printf("%8zu %9.4f %9.4f %9.4f %9.4f %9.4f %9.4f %9.4f %9.0f %10.0f %9.2e %8.0f %9.0f\n", n,
                t_step / steps, t_cpu / steps / o.threads, p.seconds("tree build") / steps, p.seconds("moments") / steps, p.seconds("walk") / steps,
                p.seconds("kernel") / steps, p.seconds("write back") / steps, double(ep) / double(n),
                double(sp) / double(n), std::sqrt(e2 / ns), peak_rss_mb(),
                double(visits) / double(std::max<std::size_t>(1, tree.groups().size())));
    std::fflush(stdout);
  }
  return 0;
}
