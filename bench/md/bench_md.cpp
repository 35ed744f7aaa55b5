// bench_md: Lennard-Jones MD step rate vs N (examples/md's System: pik's periodic
// short-range tree + kernels/lj.pik), and where the time goes: neighbour search
// (tree build or reload, cell boxes, the walk collecting candidates and handing
// them over) vs the kernel itself. Liquid state point rho* = 0.86, T* = 0.85,
// r_c = 3. Run `bench_md --help`.
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <numbers>

#include <pik/io/CommandLine.hpp>
#include <pik/pik.hpp>

#include "Lattice.hpp"
#include "System.hpp"

int main(int argc, char** argv) {
  pik::io::CommandLine cli("bench_md", "Lennard-Jones MD steps/s and pairs/s vs N (rho 0.86, T 0.85, r_c 3).");
  cli.option("--cells", "5,8,12,16,20", "fcc cells per side, comma separated (N = 4 M^3)", "LIST");
  cli.option("--skins", "0,0.3", "Verlet skins to compare, comma separated (0: search every step)", "LIST");
  cli.option("--seconds", "1.5", "minimum measured time per row", "S");
  cli.parse(argc, argv);
  const double rho = 0.86, t = 0.85, rc = 3.0, dt = 0.005, min_seconds = cli.real("--seconds");
  auto list = [&](const std::string& name) {
    std::vector<double> v;
    std::string s = cli.str(name);
    for (std::size_t a = 0; a < s.size();) {
      std::size_t b = s.find(',', a);
      if (b == std::string::npos) b = s.size();
      char* end = nullptr;
      const std::string item = s.substr(a, b - a);
      const double x = std::strtod(item.c_str(), &end);
      if (item.empty() || *end || !(x >= 0)) cli.fail(name + ": '" + item + "' is not a non-negative number");
      v.push_back(x);
      a = b + 1;
    }
    return v;
  };
  const auto cells = list("--cells"), skins = list("--skins");
  std::printf("bench_md: LJ liquid rho %g, T %g, r_c %g, dt %g; kernel %s, %d threads\n", rho, t, rc, dt,
              md::System::kernel_isa(), pik::detail::max_threads());
  std::printf("pairs in range = N/2 * rho * 4/3 pi r_c^3 per step (the useful work); kernel pairs = the\n"
              "candidates (i, j) handed to the kernel; search = force time outside the kernel.\n\n");
  std::printf("%8s %5s %9s %12s %12s %10s %10s %10s %8s\n", "N", "skin", "steps/s", "pairs(rc)/s",
              "kernel pr/s", "search ms", "kernel ms", "other ms", "rebuild");
  for (double m : cells) {
    if (m < 1 || m != std::floor(m)) cli.fail("--cells: " + std::to_string(m) + " is not a positive integer");
    for (double skin : skins) {
      const std::uint64_t n = 4 * std::uint64_t(m) * std::uint64_t(m) * std::uint64_t(m);
      md::System sys(md::fcc_lattice(std::uint64_t(m), rho, t, 1), md::box_side(n, rho), rc, skin);
      sys.compute_forces();
      for (int s = 0; s < 200; ++s) sys.step(dt);  // melt the lattice: measure a liquid
      sys.reset_stats();
      const double t0 = pik::wall_time();
      std::uint64_t steps = 0;
      while (pik::wall_time() - t0 < min_seconds || steps < 10) sys.step(dt), ++steps;
      const double wall = pik::wall_time() - t0;
      const md::ForceStats& st = sys.stats();
      const double in_range = 0.5 * double(n) * rho * 4.0 / 3.0 * std::numbers::pi * rc * rc * rc;
      const double per = 1e3 / double(steps);
      std::printf("%8" PRIu64 " %5.2f %9.1f %12.3g %12.3g %10.3f %10.3f %10.3f %7.0f%%\n", n, skin,
                  double(steps) / wall, in_range * double(steps) / wall, double(st.pair_evals) / wall,
                  (st.seconds_total - st.seconds_kernel) * per, st.seconds_kernel * per,
                  (wall - st.seconds_total) * per, 100.0 * double(st.list_builds) / double(st.force_calls));
    }
  }
  std::printf("\nsearch ms: per step, tree build/reload + cell boxes + walk, kernel excluded; kernel ms:\n"
              "time inside the kernel (summed over threads / threads); other ms: integration and\n"
              "list-age checks; rebuild: share of steps that rebuilt the tree and lists.\n");
  return 0;
}
