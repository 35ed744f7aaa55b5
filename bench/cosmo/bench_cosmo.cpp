// bench_cosmo: the TreePM force step of a cosmological box, split into its parts.
//
//   bench_cosmo [--n 64] [--box 100] [--a 0.02,0.5] [--reps 3] [--ic zeldovich|random] [--mesh M]
//
// Zel'dovich initial conditions (examples/cosmo) of n^3 particles at each scale
// factor given (at a = 0.5 the Zel'dovich field stands in for an evolved box: it has
// shell crossings and clumps, though less than a simulated one), mesh n^3, default
// TreePM parameters of examples/cosmo (theta 0.3, group 32, TSC, r_s = 1.25 cells,
// r_cut = 5 r_s). Prints one row per scale factor: seconds per force step of the
// mesh (assignment, FFTs, interpolation), periodic images, tree build, walk (list
// making) and kernels, the best of --reps, and the interactions per particle.
#include <cstdio>
#include <random>
#include <sstream>
#include <string>

#include <pik/io/CommandLine.hpp>

#include "Cosmology.hpp"
#include "InitialConditions.hpp"
#include "Simulation.hpp"

#include "BenchTreePM.hpp"
#include "BenchTreePMSP.hpp"

using namespace cosmo;

int main(int argc, char** argv) {
  pik::io::CommandLine cli("bench_cosmo", "TreePM force step of a cosmological box: mesh / images / tree / walk / kernel.");
  cli.option("--n", "64", "particles per side", "N");
  cli.option("--box", "100", "box side, Mpc/h", "L");
  cli.option("--a", "0.02,0.5", "scale factors of the Zel'dovich boxes", "A,A");
  cli.option("--reps", "3", "force steps per box (the best is shown)", "R");
  cli.option("--ic", "zeldovich", "zeldovich (boxes at each --a) or random (uniform random positions, as FDPS's TreePM sample)", "IC");
  cli.option("--mesh", "", "PM mesh cells per side (default --n)", "M");
  cli.option("--rs-cells", "1.25", "split scale r_s in mesh cells", "R");
  cli.option("--rcut", "5", "short-range cut-off in units of r_s (FDPS's sample: 3 cells, e.g. --rs-cells 0.6 --rcut 5)", "R");
  cli.parse(argc, argv);
  pik::Environment env(argc, argv);
  const int n = int(cli.count("--n"));
  const double L = cli.real("--box");
  const int reps = int(std::max<std::uint64_t>(1, cli.count("--reps")));
  const int mesh = cli.given("--mesh") ? int(cli.count("--mesh")) : n;
  const std::string ic = cli.str("--ic");
  if (ic != "zeldovich" && ic != "random") cli.fail("--ic must be zeldovich or random, got " + ic);
  std::vector<double> as;
  std::stringstream ss(cli.str("--a"));
  for (std::string item; std::getline(ss, item, ',');) as.push_back(std::stod(item));
  const Background bg{0.3};
  PowerSpectrum pk;
  pk.normalise();
  std::printf("bench_cosmo: %d^3 particles (%s), box %g Mpc/h, mesh %d^3, r_s %g cells, r_cut %g r_s, kernel %s, %d threads\n",
              n, ic.c_str(), L, mesh, cli.real("--rs-cells"), cli.real("--rcut"),
              BenchTreePM::isa_name(), pik::detail::max_threads());
  std::printf("| a | mesh s | images s | tree build s | walk s | kernel s | total s | interactions/particle |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (double a : as) {
    GravityParams gp{.box = L, .n_mesh = mesh, .theta = 0.3, .eps = L / n / 30, .group = 32,
                     .r_split_cells = cli.real("--rs-cells"), .r_cut_split = cli.real("--rcut")};
    Simulation<pik::SerialComm> sim(bg, gp, pik::SerialComm::world());
    sim.a = a;
    if (ic == "random") {
      std::mt19937_64 rng(1);
      std::uniform_real_distribution<double> u(0, L);
      std::vector<Body> b(std::size_t(n) * n * n);
      for (std::size_t i = 0; i < b.size(); ++i) b[i].id = i, b[i].mass = particle_mass(bg, L, n), b[i].pos = {u(rng), u(rng), u(rng)};
      sim.ps = pik::ParticleSystem<Body>(std::move(b));
    } else {
      sim.ps = pik::ParticleSystem<Body>(zeldovich(bg, pk, n, L, a, 1));
    }
    const auto k = sim.kernel<BenchTreePM>();
    const auto ks = sim.kernel<BenchTreePMSP>();
    double best[6] = {1e30, 1e30, 1e30, 1e30, 1e30, 1e30};
    double inter = 0;
    for (int r = 0; r < reps; ++r) {
      auto& g = sim.gravity();
      g.tree().profile().clear();
      const double t0 = pik::wall_time();
      sim.compute_forces(k, ks);
      const double total = pik::wall_time() - t0;
      const auto& p = g.tree().profile();
      const double v[6] = {g.secondsMesh(), g.secondsImages(), p.seconds("tree build"), p.seconds("walk"),
                           p.seconds("kernel"), total};
      if (total < best[5])
        for (int i = 0; i < 6; ++i) best[i] = v[i];
      inter = double(g.tree().interactionsEP() + g.tree().interactionsSP()) / double(sim.ps.size());
    }
    std::printf("| %.3g | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.0f |\n", a, best[0], best[1], best[2], best[3],
                best[4], best[5], inter);
  }
  return 0;
}
