// bench_cosmo: the TreePM force step of a cosmological box, split into its parts,
// and (with --ewald) its rms error against an Ewald reference.
//
//   bench_cosmo [--n 64] [--box 100] [--a 0.02,0.5] [--reps 3] [--ic zeldovich|random|FILE] [--mesh M]
//               [--rs-cells R] [--rcut R] [--theta T] [--group G] [--assign tsc|cic] [--eps E]
//               [--scan "rs:rcut:theta[:mesh[:assign]],..."] [--ewald REF]
//
// Zel'dovich initial conditions (examples/cosmo) of n^3 particles at each scale
// factor given (at a = 0.5 the Zel'dovich field stands in for an evolved box: it has
// shell crossings and clumps, though less than a simulated one), uniform random
// positions (as FDPS's TreePM sample's mode 2), or the particles of a positions file
// (`--ic FILE`: int64 n, then n records of 4 doubles x, y, z, m with x in box units
// [0, 1), scaled by --box; bench/cosmo/snapshot_positions.py writes one from a
// snapshot, ewald_ref from an FDPS dump). Defaults: mesh n^3 and the TreePM
// parameters of examples/cosmo (theta 0.3, group 32, TSC, r_s = 1.25 cells, r_cut =
// 5 r_s, eps = 1/30 of the mean spacing). Prints one row per box and setting: seconds
// per force step (decomposition and exchange, mesh with assignment, FFTs and
// interpolation, periodic images, tree build, walk (list making) and kernels), the
// best of --reps, the interactions per particle, and with --ewald REF (written by
// ewald_ref for the same particles) the rms relative error of the accelerations at
// REF's sample against Ewald summation.
#include <cstdio>
#include <cstdint>
#include <fstream>
#include <memory>
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

namespace {

struct Setting {
  double rs = 1.25, rcut = 5, theta = 0.3;
  int mesh = 0;
  pik::pm::Assignment assign = pik::pm::Assignment::tsc;
};

pik::pm::Assignment parse_assign(const std::string& s, pik::io::CommandLine& cli) {
  if (s == "tsc") return pik::pm::Assignment::tsc;
  if (s == "cic") return pik::pm::Assignment::cic;
  cli.fail("assignment must be tsc or cic, got " + s);
  return pik::pm::Assignment::tsc;
}

std::vector<Body> read_positions(const std::string& path, double L, pik::io::CommandLine& cli) {
  std::ifstream f(path, std::ios::binary);
  if (!f) cli.fail("cannot open positions file " + path);
  std::int64_t n = 0;
  f.read(reinterpret_cast<char*>(&n), 8);
  if (!f || n <= 0 || n > (std::int64_t(1) << 34)) cli.fail("positions file " + path + ": bad particle count");
  std::vector<Body> b(static_cast<std::size_t>(n));
  for (std::size_t i = 0; i < b.size(); ++i) {
    double r[4];
    f.read(reinterpret_cast<char*>(r), sizeof r);
    if (!f) cli.fail("positions file " + path + " is short: " + std::to_string(i) + " of " + std::to_string(n));
    for (int d = 0; d < 3; ++d) {
      if (!(r[d] >= 0 && r[d] <= 1)) cli.fail("positions file " + path + ": coordinate outside [0, 1] at particle " + std::to_string(i));
      b[i].pos[d] = r[d] >= 1 ? 0.0 : r[d] * L;
    }
    b[i].id = i, b[i].mass = r[3];
  }
  return b;
}

struct Reference {
  std::vector<std::uint64_t> id;
  std::vector<V> acc;
};
Reference read_reference(const std::string& path, pik::io::CommandLine& cli) {
  std::ifstream f(path, std::ios::binary);
  if (!f) cli.fail("cannot open Ewald reference " + path);
  std::int64_t n = 0;
  f.read(reinterpret_cast<char*>(&n), 8);
  if (!f || n <= 0 || n > 100000000) cli.fail("Ewald reference " + path + ": bad sample count");
  Reference r;
  for (std::int64_t i = 0; i < n; ++i) {
    std::int64_t id;
    double a[3];
    f.read(reinterpret_cast<char*>(&id), 8);
    f.read(reinterpret_cast<char*>(a), sizeof a);
    if (!f) cli.fail("Ewald reference " + path + " is short");
    r.id.push_back(std::uint64_t(id)), r.acc.push_back({a[0], a[1], a[2]});
  }
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  pik::io::CommandLine cli("bench_cosmo", "TreePM force step of a cosmological box: mesh / images / tree / walk / kernel, and its error against Ewald.");
  cli.option("--n", "64", "particles per side (zeldovich, random)", "N");
  cli.option("--box", "100", "box side, Mpc/h (a positions file is scaled by it)", "L");
  cli.option("--a", "0.02,0.5", "scale factors of the Zel'dovich boxes", "A,A");
  cli.option("--reps", "3", "force steps per box and setting (the best is shown)", "R");
  cli.option("--ic", "zeldovich", "zeldovich (boxes at each --a), random (uniform random positions, as FDPS's TreePM sample) or a positions file", "IC");
  cli.option("--mesh", "", "PM mesh cells per side (default: n, or the cube root of a file's count)", "M");
  cli.option("--rs-cells", "1.25", "split scale r_s in mesh cells", "R");
  cli.option("--rcut", "5", "short-range cut-off in units of r_s", "R");
  cli.option("--theta", "0.3", "opening angle of the short-range walk", "T");
  cli.option("--group", "32", "i-group limit of the walk", "G");
  cli.option("--assign", "tsc", "mesh assignment: tsc or cic", "S");
  cli.option("--eps", "", "Plummer softening (default 1/30 of the mean spacing)", "E");
  cli.option("--scan", "", "settings to run instead of the single one: rs:rcut:theta[:mesh[:assign]],...", "LIST");
  cli.option("--ewald", "", "Ewald reference of the same particles (ewald_ref --out-ref): print the rms error", "REF");
  cli.parse(argc, argv);
  pik::Environment env(argc, argv);
  const double L = cli.real("--box");
  if (!(L > 0)) cli.fail("--box must be positive");
  const int reps = int(std::max<std::uint64_t>(1, cli.count("--reps")));
  const std::string ic = cli.str("--ic");
  const bool from_file = ic != "zeldovich" && ic != "random";
  std::vector<Body> file_set;
  int n = int(cli.count("--n"));
  if (from_file) {
    file_set = read_positions(ic, L, cli);
    n = int(std::lround(std::cbrt(double(file_set.size()))));
  }
  const int mesh_default = cli.given("--mesh") ? int(cli.count("--mesh")) : n;
  std::vector<Setting> settings;
  if (cli.given("--scan")) {
    std::stringstream ss(cli.str("--scan"));
    for (std::string item; std::getline(ss, item, ',');) {
      std::stringstream is(item);
      std::vector<std::string> f;
      for (std::string x; std::getline(is, x, ':');) f.push_back(x);
      if (f.size() < 3 || f.size() > 5) cli.fail("--scan item '" + item + "' is not rs:rcut:theta[:mesh[:assign]]");
      Setting s;
      try {
        s.rs = std::stod(f[0]), s.rcut = std::stod(f[1]), s.theta = std::stod(f[2]);
        s.mesh = f.size() > 3 ? std::stoi(f[3]) : mesh_default;
      } catch (const std::exception&) {
        cli.fail("--scan item '" + item + "' has a malformed number");
      }
      if (f.size() > 4) s.assign = parse_assign(f[4], cli);
      settings.push_back(s);
    }
  } else {
    settings.push_back({cli.real("--rs-cells"), cli.real("--rcut"), cli.real("--theta"), mesh_default,
                        parse_assign(cli.str("--assign"), cli)});
  }
  Reference ref;
  if (cli.given("--ewald")) {
    if (!from_file) cli.fail("--ewald needs --ic FILE (the reference is of a file's particles)");
    ref = read_reference(cli.str("--ewald"), cli);
    for (auto id : ref.id)
      if (id >= file_set.size()) cli.fail("Ewald reference names particle " + std::to_string(id) + ", beyond the file");
  }
  std::vector<double> as;
  if (from_file || ic == "random") as.push_back(1.0);
  else {
    std::stringstream ss(cli.str("--a"));
    for (std::string item; std::getline(ss, item, ',');) as.push_back(std::stod(item));
  }
  const Background bg{0.3};
  PowerSpectrum pk;
  pk.normalise();
  const double eps = cli.given("--eps") ? cli.real("--eps") : L / n / 30;
  std::printf("bench_cosmo: %zu particles (%s), box %g, eps %g, kernel %s, %d threads\n",
              from_file ? file_set.size() : std::size_t(n) * n * n, ic.c_str(), L, eps, BenchTreePM::isa_name(),
              pik::detail::max_threads());
  std::printf("| a | mesh | r_s cells | r_cut / r_s | theta | assign | decomp s | mesh s | images s | tree build s | walk s | kernel s | total s | interactions/particle | rms error |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (double a : as) {
    std::vector<Body> set;
    if (from_file) set = file_set;
    else if (ic == "random") {
      std::mt19937_64 rng(1);
      std::uniform_real_distribution<double> u(0, L);
      set.resize(std::size_t(n) * n * n);
      for (std::size_t i = 0; i < set.size(); ++i) set[i].id = i, set[i].mass = particle_mass(bg, L, n), set[i].pos = {u(rng), u(rng), u(rng)};
    } else {
      set = zeldovich(bg, pk, n, L, a, 1);
    }
    for (const Setting& st : settings) {
      GravityParams gp{.box = L, .n_mesh = st.mesh, .theta = st.theta, .eps = eps, .group = int(cli.count("--group")),
                       .r_split_cells = st.rs, .r_cut_split = st.rcut};
      gp.assignment = st.assign;
      auto owned = std::make_unique<Simulation<pik::SerialComm>>(bg, gp, pik::SerialComm::world());
      Simulation<pik::SerialComm>* s = owned.get();
      s->a = a;
      s->ps = pik::ParticleSystem<Body>(set);
      const auto k = s->kernel<BenchTreePM>();
      const auto ks = s->kernel<BenchTreePMSP>();
      double best[7] = {1e30, 1e30, 1e30, 1e30, 1e30, 1e30, 1e30};
      double inter = 0;
      for (int r = 0; r < reps; ++r) {
        auto& g = s->gravity();
        g.tree().profile().clear();
        const double t0 = pik::wall_time();
        s->compute_forces(k, ks);
        const double total = pik::wall_time() - t0;
        const auto& p = g.tree().profile();
        const double v[7] = {total - g.secondsMesh() - g.secondsImages() - g.secondsTree(), g.secondsMesh(),
                             g.secondsImages(), p.seconds("tree build"), p.seconds("walk"), p.seconds("kernel"), total};
        if (total < best[6])
          for (int i = 0; i < 7; ++i) best[i] = v[i];
        inter = double(g.tree().interactionsEP() + g.tree().interactionsSP()) / double(s->ps.size());
      }
      std::string err = "-";
      if (!ref.id.empty()) {
        std::vector<V> acc(file_set.size());
        for (const Body& b : s->ps) acc[b.id] = b.acc();
        double sum = 0;
        for (std::size_t t = 0; t < ref.id.size(); ++t) sum += pik::norm2(acc[ref.id[t]] - ref.acc[t]) / pik::norm2(ref.acc[t]);
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.3e", std::sqrt(sum / double(ref.id.size())));
        err = buf;
      }
      std::printf("| %.3g | %d | %.3g | %.3g | %.2g | %s | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.0f | %s |\n", a,
                  st.mesh, st.rs, st.rcut, st.theta, st.assign == pik::pm::Assignment::tsc ? "TSC" : "CIC", best[0],
                  best[1], best[2], best[3], best[4], best[5], best[6], inter, err.c_str());
      std::fflush(stdout);
    }
  }
  return 0;
}
