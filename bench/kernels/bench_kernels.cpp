/// \file bench_kernels.cpp
/// \brief Single-thread throughput and accuracy of the generated pair kernels per ISA.
///
/// Gravity (kernels/gravity.pik in F32, kernels/gravity_f64.pik in F64): G interactions/s
/// for ni in {64, 256, 1024} i-particles against nj = 2048 j-particles (one call per
/// i-group, as a tree walk makes them), and the max relative acceleration error
/// |a - a_ref| / |a_ref| against a direct double-precision sum. Lennard-Jones
/// (kernels/lj.pik, F64, cutoff 2.5 sigma, periodic minimum image): all pairs of N = 1001,
/// in lattice order and again in random order
/// particles at density 0.8 in one call, G pairs/s (N^2 / time) and the error of the
/// force against a double-precision direct sum.
///
/// Each number is the best of 7 repetitions of ~0.1 s of this thread's CPU time
/// (CLOCK_THREAD_CPUTIME_ID: on a shared machine, time the thread spends descheduled
/// does not count; cache and frequency effects of other load still do).
///
/// Comparable across machines: the header names the CPU (model name, family, model);
/// "instr/int" is the instruction count of the compiled hot loop per interaction
/// (hot_loop_counts.hpp, counted from objdump at build time by hot_loop.py); "peak" is
/// the fraction of this core's measured FMA issue rate that the hot loop's instruction
/// stream reaches: G int/s x instr/int / (FMA instructions/s of an in-process probe,
/// 12 independent FMA chains at the ISA's width). 1.0 would mean the kernel issues
/// instructions as fast as the core issues FMAs (its other ports can add to that).
///
///   bench_kernels [--quick]
#include <immintrin.h>
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <pik/Vec.hpp>

#include "hot_loop_counts.hpp"

struct Body {
  pik::Vec3<double> pos;
  double mass;
};
struct Accel {
  pik::Vec3<double> acc;
  double pot;
  double vir;  // lj.pik also accumulates the pair virial
};

#include "GravityF32_avx2.hpp"
#include "GravityF32_avx512.hpp"
#include "GravityF32_reference.hpp"
#include "GravityF64_avx2.hpp"
#include "GravityF64_avx512.hpp"
#include "GravityF64_reference.hpp"
#include "LennardJones_avx2.hpp"
#include "LennardJones_avx512.hpp"
#include "LennardJones_reference.hpp"

namespace {

bool g_quick = false;

bool supported(const std::string& isa) {
  __builtin_cpu_init();
  if (isa == "AVX-512")
    return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
           __builtin_cpu_supports("avx512vl");
  if (isa == "AVX2") return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return true;
}

double thread_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

/// CPU seconds per call of f(): best of 7 repetitions of at least 0.1 s (0.02 s with --quick).
template <class F>
double time_call(F&& f) {
  const double min_rep = g_quick ? 0.02 : 0.1;
  f();  // warm-up
  double best = 1e300;
  for (int rep = 0; rep < (g_quick ? 2 : 7); ++rep) {
    long calls = 0;
    const double t0 = thread_seconds();
    double dt = 0;
    do {
      f();
      ++calls;
      dt = thread_seconds() - t0;
    } while (dt < min_rep);
    best = std::min(best, dt / calls);
  }
  return best;
}

/// Vector FMA instructions per second of this core at the ISA's width: 12 independent
/// chains (more than latency x pipes on any x86 core), 2^22 iterations, best of 3.
template <class V, class Step>
double fma_probe(Step step) {
  double best = 0;
  for (int rep = 0; rep < 3; ++rep) {
    const long iters = g_quick ? (1L << 22) : (1L << 24);
    const double t0 = thread_seconds();
    const double sink = step(iters);
    const double dt = thread_seconds() - t0;
    if (sink == 12345.678) std::printf(" ");  // keep the result alive
    best = std::max(best, 12.0 * double(iters) / dt);
  }
  return best;
}

// twelve named chains (an array would live in memory); the empty asm keeps them opaque
#define PIK_FMA12(FMA) \
  a0 = FMA(a0, x, y); a1 = FMA(a1, x, y); a2 = FMA(a2, x, y); a3 = FMA(a3, x, y); a4 = FMA(a4, x, y); \
  a5 = FMA(a5, x, y); a6 = FMA(a6, x, y); a7 = FMA(a7, x, y); a8 = FMA(a8, x, y); a9 = FMA(a9, x, y); \
  a10 = FMA(a10, x, y); a11 = FMA(a11, x, y);
#define PIK_FMA_PROBE(NAME, ATTR, V, SET1, FMA, ADD, CAST, C)                                         \
  ATTR double NAME(long iters) {                                                                     \
    V a0 = SET1(1.0f), a1 = a0, a2 = a0, a3 = a0, a4 = a0, a5 = a0, a6 = a0, a7 = a0, a8 = a0, a9 = a0, \
      a10 = a0, a11 = a0;                                                                            \
    const V x = SET1(0.999999f), y = SET1(1e-7f);                                                    \
    for (long n = 0; n < iters; ++n) {                                                               \
      PIK_FMA12(FMA)                                                                                 \
      __asm__ volatile("" : "+" C(a0), "+" C(a1), "+" C(a2), "+" C(a3), "+" C(a4), "+" C(a5),         \
                       "+" C(a6), "+" C(a7), "+" C(a8), "+" C(a9), "+" C(a10), "+" C(a11));           \
    }                                                                                                \
    V s = ADD(ADD(ADD(a0, a1), ADD(a2, a3)), ADD(ADD(a4, a5), ADD(a6, a7)));                         \
    s = ADD(s, ADD(ADD(a8, a9), ADD(a10, a11)));                                                     \
    return double(CAST(s));                                                                          \
  }
PIK_FMA_PROBE(fma_avx2, __attribute__((target("avx2,fma"))), __m256, _mm256_set1_ps, _mm256_fmadd_ps,
              _mm256_add_ps, _mm256_cvtss_f32, "x")
PIK_FMA_PROBE(fma_avx512, __attribute__((target("avx512f"))), __m512, _mm512_set1_ps, _mm512_fmadd_ps,
              _mm512_add_ps, _mm512_cvtss_f32, "v")

double fma_rate(const std::string& isa) {
  static double r2 = 0, r5 = 0;
  if (isa == "AVX2") return r2 ? r2 : (r2 = fma_probe<__m256>(fma_avx2));
  if (isa == "AVX-512") return r5 ? r5 : (r5 = fma_probe<__m512>(fma_avx512));
  return 0;
}

/// "instr/int" and "peak" columns for a kernel (name as in hot_loop_counts.hpp) at rate G int/s.
void print_counts(const std::string& isa, const std::string& name, double g_per_s) {
  const char* suffix = isa == "AVX2" ? "_avx2" : isa == "AVX-512" ? "_avx512" : nullptr;
  if (suffix == nullptr) {
    std::printf("  %9s %6s", "-", "-");
    return;
  }
  for (const auto& h : kHotLoop)
    if (name + suffix == h.name) {
      std::printf("  %9.2f %6.2f", h.per_interaction, g_per_s * 1e9 * h.per_interaction / fma_rate(isa));
      return;
    }
  std::printf("  %9s %6s", "?", "?");
}

std::string cpu_model() {
  std::string model = "unknown CPU", fam, mod;
  if (FILE* f = std::fopen("/proc/cpuinfo", "r")) {
    char line[512];
    while (std::fgets(line, sizeof line, f)) {
      std::string s(line);
      const auto colon = s.find(':');
      if (colon == std::string::npos) continue;
      std::string key = s.substr(0, s.find_last_not_of(" \t", colon - 1) + 1), val = s.substr(colon + 1);
      val.erase(0, val.find_first_not_of(' '));
      val.erase(val.find_last_not_of("\n") + 1);
      if (key == "model name" && model == "unknown CPU") model = val;
      if (key == "cpu family" && fam.empty()) fam = val;
      if (key == "model" && mod.empty()) mod = val;
    }
    std::fclose(f);
  }
  return model + " (family " + fam + ", model " + mod + ")";
}

double max_rel_error(const std::vector<Accel>& got, const std::vector<pik::Vec3<double>>& want) {
  double worst = 0;
  for (std::size_t i = 0; i < want.size(); ++i) {
    const pik::Vec3<double> d{got[i].acc.x - want[i].x, got[i].acc.y - want[i].y, got[i].acc.z - want[i].z};
    worst = std::max(worst, std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z) /
                                std::sqrt(want[i].x * want[i].x + want[i].y * want[i].y + want[i].z * want[i].z));
  }
  return worst;
}

template <class Kernel>
void bench_gravity(const char* label, const std::vector<Body>& body, double eps2) {
  const char* isa = Kernel::isa_name();
  if (!supported(isa)) {
    std::printf("%-10s %-8s  (skipped: this CPU lacks %s)\n", label, isa, isa);
    return;
  }
  const Kernel kernel(static_cast<decltype(eps2)>(eps2));
  const int nj = 2048;
  std::printf("%-10s %-8s", label, isa);
  double worst = 0, rate1024 = 0;
  for (const int ni : {64, 256, 1024}) {
    std::vector<Accel> force(static_cast<std::size_t>(ni));
    const double t = time_call([&] { kernel(body.data(), ni, body.data() + 1024, nj, force.data()); });
    std::printf("  %8.3f", double(ni) * nj / t * 1e-9);
    rate1024 = double(ni) * nj / t * 1e-9;
    // accuracy: one clean call against the double-precision direct sum
    std::vector<Accel> once(static_cast<std::size_t>(ni));
    kernel(body.data(), ni, body.data() + 1024, nj, once.data());
    std::vector<pik::Vec3<double>> want(static_cast<std::size_t>(ni));
    for (int i = 0; i < ni; ++i) {
      for (int j = 1024; j < 1024 + nj; ++j) {
        const double dx = body[i].pos.x - body[j].pos.x, dy = body[i].pos.y - body[j].pos.y,
                     dz = body[i].pos.z - body[j].pos.z;
        const double r2 = dx * dx + dy * dy + dz * dz + eps2, rinv = 1.0 / std::sqrt(r2);
        const double s = body[j].mass * rinv * rinv * rinv;
        want[i].x -= s * dx, want[i].y -= s * dy, want[i].z -= s * dz;
      }
    }
    worst = std::max(worst, max_rel_error(once, want));
  }
  std::printf("   %9.2e", worst);
  print_counts(isa, std::strcmp(label, "gravity F32") == 0 ? "gravity_f32" : "gravity_f64", rate1024);
  std::printf("\n");
}

struct LJSetup {
  double box, rcut2, eps = 1.0, sigma2 = 1.0;
};

/// Returns the share of the N^2 pairs within the cut-off (0 where the ISA is skipped).
template <class Kernel>
double bench_lj(const char* label, const std::vector<Body>& body, const LJSetup& s) {
  const char* isa = Kernel::isa_name();
  if (!supported(isa)) {
    std::printf("%-10s %-8s  (skipped: this CPU lacks %s)\n", label, isa, isa);
    return 0;
  }
  const Kernel kernel(s.box, s.rcut2, s.eps, s.sigma2);
  const int n = static_cast<int>(body.size());
  std::vector<Accel> force(body.size());
  const double t = time_call([&] { kernel(body.data(), n, body.data(), n, force.data()); });
  std::vector<Accel> once(body.size());
  kernel(body.data(), n, body.data(), n, once.data());
  std::vector<pik::Vec3<double>> want(body.size());
  auto wrap = [&](double d) { return d < -0.5 * s.box ? d + s.box : d >= 0.5 * s.box ? d - s.box : d; };
  long inside = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double dx = wrap(body[i].pos.x - body[j].pos.x), dy = wrap(body[i].pos.y - body[j].pos.y),
                   dz = wrap(body[i].pos.z - body[j].pos.z), r2 = dx * dx + dy * dy + dz * dz;
      if (r2 >= s.rcut2 || r2 == 0) continue;
      ++inside;
      const double s6 = std::pow(s.sigma2 / r2, 3), f = 24 * s.eps * s6 * (2 * s6 - 1) / r2;
      want[i].x += f * dx, want[i].y += f * dy, want[i].z += f * dz;
    }
  std::printf("%-10s %-8s  %8.3f  G pairs/s (N = %d, all N^2 pairs)        %9.2e", label, isa,
              double(n) * n / t * 1e-9, n, max_rel_error(once, want));
  print_counts(isa, "lj_f64", double(n) * n / t * 1e-9);
  std::printf("\n");
  return double(inside) / (double(n) * n);
}

}  // namespace

int main(int argc, char** argv) {
  for (int a = 1; a < argc; ++a) {
    if (std::strcmp(argv[a], "--quick") == 0) {
      g_quick = true;
    } else {
      std::fprintf(stderr, "usage: bench_kernels [--quick]\n");
      return 2;
    }
  }
  // Gravity: a Gaussian cloud, i-particles [0, 1024), j-particles [1024, 3072).
  std::mt19937_64 rng(2026);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<Body> body(3072);
  for (auto& b : body) b = {{g(rng), g(rng), g(rng)}, 1.0 / 3072};
  const double eps2 = 1e-4;

  std::printf("pik bench_kernels on %s\n", cpu_model().c_str());
  std::printf("single thread (CPU time), G interactions/s for nj = 2048; FMA probe: AVX2 %.2f, AVX-512 %.2f G FMA/s\n",
              supported("AVX2") ? fma_rate("AVX2") * 1e-9 : 0.0, supported("AVX-512") ? fma_rate("AVX-512") * 1e-9 : 0.0);
  std::printf("%-10s %-8s  %8s  %8s  %8s   %9s  %9s %6s\n", "kernel", "ISA", "ni=64", "ni=256", "ni=1024", "max rel err",
              "instr/int", "peak");
  bench_gravity<GravityF32_reference>("gravity F32", body, eps2);
  bench_gravity<GravityF32_avx2>("gravity F32", body, eps2);
  bench_gravity<GravityF32_avx512>("gravity F32", body, eps2);
  bench_gravity<GravityF64_reference>("gravity F64", body, eps2);
  bench_gravity<GravityF64_avx2>("gravity F64", body, eps2);
  bench_gravity<GravityF64_avx512>("gravity F64", body, eps2);

  // Lennard-Jones: N = 1001 on a jittered cubic lattice at density 0.8 (sigma = 1).
  const int n = 1001;
  LJSetup s;
  s.box = std::cbrt(n / 0.8);
  s.rcut2 = 2.5 * 2.5;
  std::vector<Body> atoms(n);
  const int side = 11;  // 11^3 = 1331 >= 1001 sites
  std::uniform_real_distribution<double> jitter(-0.1, 0.1);
  for (int p = 0; p < n; ++p) {
    const double a = s.box / side;
    atoms[p] = {{(p % side + 0.5) * a + jitter(rng), (p / side % side + 0.5) * a + jitter(rng),
                 (p / side / side + 0.5) * a + jitter(rng)},
                1.0};
  }
  const double inside = bench_lj<LennardJones_reference>("lj F64", atoms, s);  // the reference runs everywhere
  bench_lj<LennardJones_avx2>("lj F64", atoms, s);
  bench_lj<LennardJones_avx512>("lj F64", atoms, s);
  // The same atoms in random order: an i-vector's lanes are then far apart, and whether a
  // vector of pairs has a lane within the cut-off changes at random from one j to the next.
  std::shuffle(atoms.begin(), atoms.end(), rng);
  bench_lj<LennardJones_reference>("lj random", atoms, s);
  bench_lj<LennardJones_avx2>("lj random", atoms, s);
  bench_lj<LennardJones_avx512>("lj random", atoms, s);
  std::printf("lj: %.1f %% of the pairs lie within the cut-off. The AVX2/AVX-512 loops skip a vector of pairs with\n"
              "no lane inside (docs/simd.md, \"Skipped branches\"): in lattice order most vectors skip, so instr/int\n"
              "(every instruction of the loop) and peak overstate the work done; in random order the branch\n"
              "mispredicts until the loop turns to running every vector (the lj random rows; docs/simd.md).\n",
              100.0 * inside);
  return 0;
}
