// md: Lennard-Jones molecular dynamics on pik (reduced units sigma = epsilon = m = k_B = 1).
//
// Atoms start on an fcc lattice in a periodic cube; forces come from kernels/lj.pik
// (truncated at r_c, not shifted) through pik's periodic short-range tree;
// velocity-Verlet steps. Equilibration rescales velocities to T every step;
// production runs in the canonical ensemble with the CSVR thermostat (or NVE with
// --ensemble nve). Prints U/N and P with the standard tail corrections, and T, each
// with a block-averaged statistical error. See docs/md.md; run `md --help`.
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

#include <pik/io/AtomicFile.hpp>
#include <pik/io/CommandLine.hpp>
#include <pik/pik.hpp>

#include "BlockAverage.hpp"
#include "Lattice.hpp"
#include "System.hpp"
#include "TailCorrection.hpp"
#include "Thermostat.hpp"

namespace {

struct Options {
  std::uint64_t cells, n, steps_equil, steps_prod, seed, blocks;
  double rho, temperature, dt, rc, skin, tau;
  bool nve;
  std::string series;
};

Options parse(int argc, char** argv) {
  pik::io::CommandLine cli("md", "Lennard-Jones fluid: fcc start, velocity-Verlet, periodic cube, "
                                 "cutoff r_c with tail corrections (reduced units).");
  cli.option("--cells", "5", "fcc cells per box side: N = 4 M^3 atoms", "M");
  cli.option("--n", "", "number of atoms instead of --cells (must be 4 M^3: 32, 108, 256, 500, 864, ...)", "N");
  cli.option("--rho", "0.86", "number density rho*", "RHO");
  cli.option("--temperature", "0.85", "temperature T*", "T");
  cli.option("--dt", "0.005", "time step", "DT");
  cli.option("--steps-equil", "2000", "equilibration steps (velocities rescaled to T every step)", "S");
  cli.option("--steps-prod", "10000", "production steps (averaged)", "S");
  cli.option("--seed", "1", "random seed of the initial velocities and the thermostat", "S");
  cli.option("--rc", "3", "cutoff radius r_c", "RC");
  cli.option("--skin", "0.3", "Verlet skin: neighbour lists reused until an atom moves skin/2 (0: every step)", "S");
  cli.option("--ensemble", "nvt", "production ensemble: nvt (CSVR thermostat) or nve", "E");
  cli.option("--tau", "0.1", "CSVR relaxation time (nvt)", "TAU");
  cli.option("--blocks", "20", "blocks for the statistical errors", "B");
  cli.option("--series", "", "write the production time series (step U/N P T) to this file", "FILE");
  cli.parse(argc, argv);

  Options o{};
  o.rho = cli.real("--rho"), o.temperature = cli.real("--temperature"), o.dt = cli.real("--dt");
  o.rc = cli.real("--rc"), o.skin = cli.real("--skin"), o.tau = cli.real("--tau");
  o.steps_equil = cli.count("--steps-equil"), o.steps_prod = cli.count("--steps-prod");
  o.seed = cli.count("--seed"), o.blocks = cli.count("--blocks"), o.series = cli.str("--series");
  const std::string ens = cli.str("--ensemble");
  if (ens != "nvt" && ens != "nve") cli.fail("--ensemble must be nvt or nve, got '" + ens + "'");
  o.nve = ens == "nve";
  if (cli.given("--n")) {
    if (cli.given("--cells")) cli.fail("give --n or --cells, not both");
    o.n = cli.count("--n");
    o.cells = std::uint64_t(std::llround(std::cbrt(double(o.n) / 4.0)));
    if (o.n == 0 || 4 * o.cells * o.cells * o.cells != o.n) {
      const std::uint64_t lo = std::max<std::uint64_t>(1, std::uint64_t(std::cbrt(double(o.n) / 4.0)));
      cli.fail("--n " + std::to_string(o.n) + " does not fill an fcc lattice (N = 4 M^3; nearest: " +
               std::to_string(4 * lo * lo * lo) + " or " + std::to_string(4 * (lo + 1) * (lo + 1) * (lo + 1)) + ")");
    }
  } else {
    o.cells = cli.count("--cells");
    if (o.cells == 0) cli.fail("--cells must be at least 1");
    if (o.cells > 200) cli.fail("--cells " + std::to_string(o.cells) + " is more than 32 million atoms");
    o.n = 4 * o.cells * o.cells * o.cells;
  }
  if (!(o.rho > 0)) cli.fail("--rho must be positive");
  if (!(o.temperature > 0)) cli.fail("--temperature must be positive");
  if (!(o.dt > 0)) cli.fail("--dt must be positive");
  if (!(o.rc > 0)) cli.fail("--rc must be positive");
  if (!(o.skin >= 0)) cli.fail("--skin must be non-negative");
  if (!(o.tau >= 0)) cli.fail("--tau must be non-negative");
  if (o.blocks < 2) cli.fail("--blocks must be at least 2");
  if (o.steps_prod < 2 * o.blocks)
    cli.fail("--steps-prod must be at least 2 x --blocks (" + std::to_string(2 * o.blocks) + ")");
  return o;
}

void print_stat(const char* name, const md::BlockAverage& s, std::size_t blocks, const char* extra = "") {
  std::printf("  %-18s %12.6f +- %.6f%s\n", name, s.mean(), s.error(blocks), extra);
}

}  // namespace

int main(int argc, char** argv) try {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // progress lines show up in log files as they come
  const Options o = parse(argc, argv);
  // The series file is opened (as a temporary next to it) before the run, so a
  // wrong path fails at once; it appears complete at the end or not at all.
  std::optional<pik::io::AtomicFile> series;
  if (!o.series.empty()) series.emplace(o.series), series->write("# step U/N(tail) P(tail) T\n");
  const double box = md::box_side(o.n, o.rho);
  md::System sys(md::fcc_lattice(o.cells, o.rho, o.temperature, o.seed), box, o.rc, o.skin);

  std::printf("md: %" PRIu64 " atoms (fcc, %" PRIu64 "^3 cells), rho %g, box %.6g, r_c %g, skin %g, "
              "kernel %s, %d threads\n",
              o.n, o.cells, o.rho, box, o.rc, o.skin, md::System::kernel_isa(), pik::detail::max_threads());
  std::printf("    T %g, dt %g; equilibration %" PRIu64 " steps (velocity rescaling), production %" PRIu64
              " steps (%s)\n",
              o.temperature, o.dt, o.steps_equil, o.steps_prod,
              o.nve ? "NVE" : ("NVT, CSVR thermostat tau " + std::to_string(o.tau)).c_str());
  std::printf("    tail corrections: U/N %+.6f, P %+.6f\n", md::energy_tail(o.rho, o.rc),
              md::pressure_tail(o.rho, o.rc));
  if (box < 2 * o.rc)
    std::printf("    note: box < 2 r_c; every periodic image within r_c interacts (no minimum image)\n");

  const double wall0 = pik::wall_time();
  sys.compute_forces();
  for (std::uint64_t s = 0; s < o.steps_equil; ++s) {
    sys.step(o.dt);
    sys.scale_velocities(std::sqrt(o.temperature / sys.temperature()));
  }
  std::printf("after equilibration: U/N %.6f, P %.6f, T %.6f\n", sys.potential_per_atom(true),
              sys.pressure(true), sys.temperature());

  md::Csvr thermostat(o.temperature, o.tau, md::degrees_of_freedom(o.n), o.seed);
  md::BlockAverage u, p, t, e;
  sys.reset_stats();
  const double prod0 = pik::wall_time();
  const std::uint64_t report = std::max<std::uint64_t>(1, o.steps_prod / 10);
  double e_shift = 0;  // kinetic energy taken out by the thermostat (CSVR conserved quantity)
  for (std::uint64_t s = 1; s <= o.steps_prod; ++s) {
    sys.step(o.dt);
    if (!o.nve) {
      const double k = sys.kinetic(), f = thermostat.factor(k, o.dt);
      sys.scale_velocities(f);
      e_shift += k * (f * f - 1.0);
    }
    u.add(sys.potential_per_atom(true));
    p.add(sys.pressure(true));
    t.add(sys.temperature());
    e.add((sys.kinetic() - e_shift) / double(o.n) + sys.potential_per_atom(false));
    if (series) {
      char row[128];
      std::snprintf(row, sizeof row, "%" PRIu64 " %.10g %.10g %.10g\n", s, u.samples().back(),
                    p.samples().back(), t.samples().back());
      series->write(std::string(row));
    }
    if (s % report == 0)
      std::printf("  step %8" PRIu64 "  t %9.3f  U/N %10.6f  P %10.6f  T %8.5f\n", s, double(s) * o.dt,
                  u.samples().back(), p.samples().back(), t.samples().back());
  }
  if (series) series->commit();
  const double wall = pik::wall_time() - wall0, prod = pik::wall_time() - prod0;
  const md::ForceStats& st = sys.stats();

  const std::size_t b = o.blocks;
  std::printf("\nresults (production: %" PRIu64 " steps, t = %g, %zu blocks of %" PRIu64 " steps)\n",
              o.steps_prod, double(o.steps_prod) * o.dt, b, o.steps_prod / b);
  print_stat("U/N (with tail)", u, b);
  print_stat("P (with tail)", p, b);
  print_stat("T", t, b);
  double e_lo = e.samples()[0], e_hi = e_lo;
  for (double v : e.samples()) e_lo = std::min(e_lo, v), e_hi = std::max(e_hi, v);
  std::printf("  %-18s %12.6f (max - min over the run %.2e; truncated-potential jumps included)\n",
              o.nve ? "E/N" : "E/N + thermostat", e.mean(), e_hi - e_lo);
  const auto curve = u.blocking_curve();
  std::printf("  U/N blocking error vs block length 1, 2, 4, ...:");
  for (double c : curve) std::printf(" %.2e", c);
  std::printf("\n  |P_total| %.2e\n", pik::norm(sys.momentum()));
  std::printf("timing: %.2f s total, production %.2f s = %.0f steps/s, %.3g pair evaluations/s, "
              "%" PRIu64 " list builds in %" PRIu64 " force calls\n",
              wall, prod, double(o.steps_prod) / prod, double(st.pair_evals) / prod, st.list_builds,
              st.force_calls);
  std::printf("        forces %.2f s: tree build + cell boxes %.2f s, walk + kernel %.2f s (kernel %.2f s)\n",
              st.seconds_total, st.seconds_build, st.seconds_walk, st.seconds_kernel);
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "md: error: %s\n", e.what());
  return 1;
}
