// cosmo: a periodic box of dark matter from the early universe to today, on pik.
//
// Flat LCDM (or Einstein-de Sitter) background; initial conditions by the
// Zel'dovich approximation (or 2LPT, --lpt 2) from the Eisenstein & Hu 1998 (no-wiggle) or BBKS power
// spectrum on a grid (seeded), or the Zel'dovich pancake; comoving coordinates and
// the kick-drift-kick leapfrog in the scale factor, steps uniform in ln a; TreePM
// gravity (pik::pm::TreePM: FFT mesh + cut-off tree with kernels/gravity_treepm.pik).
// At each output scale factor: a snapshot (GADGET-like HDF5 layout: comoving
// Coordinates in Mpc/h, Velocities = peculiar velocity / sqrt(a) in km/s, masses in
// 1e10 Msun/h), the power spectrum against linear theory, a projected density map
// and the friends-of-friends halo masses. A checkpoint to restart from. Runs under
// mpirun (the mesh in slabs, the domain decomposed). Run `cosmo --help`.
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <new>
#include <sstream>
#include <string>
#include <vector>

#include <pik/io/CommandLine.hpp>
#include <pik/io/ParallelCheckpoint.hpp>
#include <pik/io/ParallelSnapshot.hpp>
#include <pik/io/SnapshotIo.hpp>
#include <pik/pik.hpp>

#include "Analysis.hpp"
#include "Cosmology.hpp"
#include "InitialConditions.hpp"
#include "Simulation.hpp"

#include "CosmoTreePM.hpp"
#include "CosmoTreePMSP.hpp"

using namespace cosmo;

namespace {

// rho_crit = 2.775e11 h^2 Msun / Mpc^3 (e.g. Peebles 1993) and, in code units (G = H0
// = 1), 3 / (8 pi): one code mass unit in Msun/h.
constexpr double mass_unit_msun_h = 2.77536627e11 * 8 * std::numbers::pi / 3;

struct Run {
  Background bg;
  PowerSpectrum pk;
  GravityParams gp;
  int n_side = 0, order = 1;
  double a_start = 0, a_end = 1, fof_b = 0.2;
  std::uint64_t step = 0, n_steps = 0, checkpoint_every = 0, seed = 1, max_steps = 0;
  std::vector<double> outputs;  // scale factors of the outputs
  std::string ic, out;
  pik::io::Format format = pik::io::Format::binary;
  double a_of(std::uint64_t s) const { return a_start * std::exp(std::log(a_end / a_start) * double(s) / double(n_steps)); }
};

std::vector<double> parse_list(const pik::io::CommandLine& cli, const std::string& opt) {
  std::vector<double> v;
  std::stringstream ss(cli.str(opt));
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    const double x = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !(x > 0)) cli.fail(opt + ": '" + item + "' is not a positive number");
    v.push_back(x);
  }
  return v;
}

void set_attributes(pik::io::Snapshot& s, const Run& r) {
  s.attr.set("omega_m", r.bg.omega_m), s.attr.set("omega_b", r.pk.omega_b), s.attr.set("h", r.pk.h);
  s.attr.set("n_s", r.pk.n_s), s.attr.set("sigma8", r.pk.sigma8);
  s.attr.set("spectrum", r.pk.fit == PowerSpectrum::Fit::bbks ? "bbks" : "eh");
  s.attr.set("box", r.gp.box), s.attr.set("mesh", r.gp.n_mesh), s.attr.set("theta", r.gp.theta);
  s.attr.set("eps", r.gp.eps), s.attr.set("n_side", r.n_side), s.attr.set("seed", r.seed), s.attr.set("ic", r.ic);
  s.attr.set("rs_cells", r.gp.r_split_cells), s.attr.set("rcut", r.gp.r_cut_split);
  s.attr.set("lpt", r.order);
  s.attr.set("a_start", r.a_start), s.attr.set("a_end", r.a_end), s.attr.set("steps", r.n_steps);
  s.attr.set("checkpoint_every", r.checkpoint_every), s.attr.set("fof_b", r.fof_b);
  std::string outs;
  for (double a : r.outputs) outs += (outs.empty() ? "" : ",") + std::to_string(a);
  s.attr.set("outputs", outs), s.attr.set("format", pik::io::format_name(r.format)), s.attr.set("out", r.out);
}

template <class Sim>
pik::io::Snapshot to_snapshot(const Run& r, const Sim& sim, bool checkpoint) {
  pik::io::Snapshot s;
  if (checkpoint) s.column("Momentum", 3);
  s.resize(sim.ps.size());
  const double vel = 100 / std::pow(sim.a, 1.5);  // p = a^2 dx/dt -> GADGET's sqrt(a) dx/dt... in km/s
  for (std::size_t i = 0; i < sim.ps.size(); ++i) {
    const Body& b = sim.ps[i];
    s.id[i] = b.id, s.mass[i] = b.mass * mass_unit_msun_h / 1e10, s.pos[i] = b.pos, s.vel[i] = b.mom * vel;
    if (checkpoint)
      for (int d = 0; d < 3; ++d) s.extra[0].data[3 * i + d] = b.mom[d];
  }
  s.time = sim.a, s.step = r.step;
  set_attributes(s, r);
  s.attr.set("redshift", 1 / sim.a - 1);
  s.attr.set("units", "Coordinates Mpc/h comoving; Velocities km/s (peculiar / sqrt(a)); Masses 1e10 Msun/h");
  return s;
}

/// pk_NNN.txt, proj_NNN.txt and fof_NNN.txt at the current scale factor.
template <class Sim>
void analyse(const Run& r, Sim& sim, int index) {
  const auto& comm = sim.comm();
  const double L = r.gp.box, total = r.bg.mean_density() * L * L * L;
  const auto pk = power_spectrum(sim.gravity().mesh(), total, comm);
  const std::uint64_t n_total = comm.sum(std::uint64_t(sim.ps.size()));
  // Projected density along z on the mesh: counts per column / mean.
  const int nm = r.gp.n_mesh;
  std::vector<double> proj(std::size_t(nm) * nm, 0.0);
  for (const Body& b : sim.ps) {
    const int i = std::min(nm - 1, int(b.pos.x / L * nm)), j = std::min(nm - 1, int(b.pos.y / L * nm));
    proj[std::size_t(i) * nm + j] += 1;
  }
  comm.reduce_inplace(std::span<double>(proj), pik::comm::ReduceOp::sum);
  std::vector<V> pos;
  for (const Body& b : sim.ps) pos.push_back(b.pos);
  const auto all = comm.gatherv(std::span<const V>(pos), 0);
  if (!comm.is_root()) return;
  char name[64];
  std::snprintf(name, sizeof name, "/pk_%03d.txt", index);
  std::FILE* f = std::fopen((r.out + name).c_str(), "w");
  if (!f) throw pik::Error("cannot write " + r.out + name);
  const double D = r.bg.growth(sim.a);
  std::fprintf(f, "# a %.6g z %.6g D %.6g box %g n %" PRIu64 " shot_noise %.6g\n# k[h/Mpc] P[(Mpc/h)^3] modes P_linear\n",
               sim.a, 1 / sim.a - 1, D, L, n_total, L * L * L / double(n_total));
  for (const auto& b : pk) std::fprintf(f, "%.6e %.6e %.0f %.6e\n", b.k, b.power, b.modes, r.pk(b.k) * D * D);
  std::fclose(f);
  std::snprintf(name, sizeof name, "/proj_%03d.txt", index);
  f = std::fopen((r.out + name).c_str(), "w");
  if (!f) throw pik::Error("cannot write " + r.out + name);
  const double mean = double(n_total) / (double(nm) * nm);
  std::fprintf(f, "# a %.6g: particles per column (x rows, y columns) / mean, box %g Mpc/h\n", sim.a, L);
  for (int i = 0; i < nm; ++i) {
    for (int j = 0; j < nm; ++j) std::fprintf(f, "%.4g ", proj[std::size_t(i) * nm + j] / mean);
    std::fprintf(f, "\n");
  }
  std::fclose(f);
  const double spacing = L / std::cbrt(double(n_total));
  const auto groups = friends_of_friends(all, L, r.fof_b * spacing, 20);
  std::snprintf(name, sizeof name, "/fof_%03d.txt", index);
  f = std::fopen((r.out + name).c_str(), "w");
  if (!f) throw pik::Error("cannot write " + r.out + name);
  const double mp = r.bg.mean_density() * L * L * L / double(n_total) * mass_unit_msun_h;
  std::fprintf(f, "# a %.6g: friends-of-friends haloes (b = %g, >= 20 particles), box %g Mpc/h, particle mass %.4e Msun/h\n# particles mass[Msun/h]\n",
               sim.a, r.fof_b, L, mp);
  for (std::size_t g : groups) std::fprintf(f, "%zu %.4e\n", g, double(g) * mp);
  std::fclose(f);
  std::printf("\n  output %d at a = %.4f: P(k) %s, %zu haloes (largest %.3g Msun/h)\n", index, sim.a,
              (r.out + "/pk_*.txt").c_str(), groups.size(), groups.empty() ? 0.0 : double(groups[0]) * mp);
}

int simulate(Run& r, std::vector<Body> particles, const pik::Comm& comm) {
  Simulation<pik::Comm> sim(r.bg, r.gp, comm);
  sim.ps = pik::ParticleSystem<Body>(std::move(particles));
  sim.a = r.a_of(r.step);
  const auto k = sim.kernel<CosmoTreePM>();
  const auto ks = sim.kernel<CosmoTreePMSP>();
  if (comm.is_root()) {
    std::filesystem::create_directories(r.out);
    // The linear spectrum at a = 1 (for plot.py: sigma(M) and the halo mass function).
    std::FILE* f = std::fopen((r.out + "/linear_pk.txt").c_str(), "w");
    if (!f) throw pik::Error("cannot write " + r.out + "/linear_pk.txt");
    std::fprintf(f, "# linear P(k) at a = 1: omega_m %g omega_b %g h %g n_s %g sigma8 %g %s\n# k[h/Mpc] P[(Mpc/h)^3]\n",
                 r.bg.omega_m, r.pk.omega_b, r.pk.h, r.pk.n_s, r.pk.sigma8,
                 r.pk.fit == PowerSpectrum::Fit::bbks ? "BBKS" : "Eisenstein-Hu no-wiggle");
    for (int i = 0; i <= 600; ++i) {
      const double kk = std::pow(10.0, -4 + 6.0 * i / 600);
      std::fprintf(f, "%.6e %.6e\n", kk, r.pk(kk));
    }
    std::fclose(f);
    f = std::fopen((r.out + "/growth.txt").c_str(), "w");
    if (!f) throw pik::Error("cannot write " + r.out + "/growth.txt");
    std::fprintf(f, "# a D(a) (D(1) = 1), omega_m %g\n", r.bg.omega_m);
    for (int i = 0; i <= 200; ++i) {
      const double aa = std::pow(10.0, -3 + 3.0 * i / 200);
      std::fprintf(f, "%.6e %.6e\n", aa, r.bg.growth(aa));
    }
    std::fclose(f);
  }
  comm.barrier();
  const std::uint64_t n_total = comm.sum(std::uint64_t(sim.ps.size()));
  std::printf("cosmo: %" PRIu64 " particles, box %g Mpc/h, mesh %d^3, Omega_m %g, sigma8 %g, a %g -> %g in %" PRIu64
              " steps (from %" PRIu64 "), kernel %s, %d ranks x %d threads\n",
              n_total, r.gp.box, r.gp.n_mesh, r.bg.omega_m, r.pk.sigma8, r.a_start, r.a_end, r.n_steps, r.step,
              CosmoTreePM::isa_name(), comm.size(), pik::detail::max_threads());
  // Forces at the start; a restart recomputes them from the checkpoint's positions
  // (the same to rounding: the tree sorts the particles afresh).
  sim.compute_forces(k, ks);
  std::size_t next_out = 0;
  while (next_out < r.outputs.size() && r.outputs[next_out] < sim.a * (1 - 1e-12)) ++next_out;
  auto snapshot = [&](int index) {
    char name[64];
    std::snprintf(name, sizeof name, "/snap_%03d%s", index, pik::io::extension(r.format));
    pik::io::write_snapshot_parallel(r.out + name, to_snapshot(r, sim, false), r.format, comm);
    analyse(r, sim, index);
  };
  if (r.step == 0) snapshot(0);
  const double wall0 = pik::wall_time();
  double mesh_s = 0, tree_s = 0, images_s = 0;
  const std::uint64_t first = r.step;
  while (r.step < r.n_steps && !(r.max_steps && r.step - first >= r.max_steps)) {
    sim.step(r.a_of(r.step + 1), k, ks);
    ++r.step;
    mesh_s += sim.gravity().secondsMesh(), tree_s += sim.gravity().secondsTree(), images_s += sim.gravity().secondsImages();
    const auto [p, s] = sim.momentum();
    const double el = pik::wall_time() - wall0, per = el / double(r.step - first);
    if (comm.is_root())
      std::printf("\rstep %" PRIu64 "/%" PRIu64 "  a %.4f  z %7.3f  |sum m p|/sum m|p| %.1e  %.2f s/step  eta %.0f s   ",
                  r.step, r.n_steps, sim.a, 1 / sim.a - 1, pik::norm(p) / s, per, per * double(r.n_steps - r.step));
    std::fflush(stdout);
    while (next_out < r.outputs.size() && sim.a >= r.outputs[next_out] * (1 - 1e-9)) snapshot(int(++next_out));
    const bool last = r.step == r.n_steps || (r.max_steps && r.step - first == r.max_steps);
    if ((r.checkpoint_every && r.step % r.checkpoint_every == 0) || (last && (r.checkpoint_every || r.max_steps)))
      pik::io::write_checkpoint_parallel(r.out + "/checkpoint.pbin", to_snapshot(r, sim, true), comm);
  }
  const auto [p, s] = sim.momentum();
  const double wall = pik::wall_time() - wall0;
  if (r.step < r.n_steps) std::printf("\n\nstopped after --max-steps %" PRIu64 ": continue with --restart %s/checkpoint.pbin", r.max_steps, r.out.c_str());
  std::printf("\n\nsummary\n  particles         %" PRIu64 "\n  steps             %" PRIu64 " (a = %.4f, z = %.4f)\n",
              n_total, r.step - first, sim.a, 1 / sim.a - 1);
  std::printf("  wall time         %.2f s: mesh %.2f s, images/halo %.2f s, tree %.2f s (this rank)\n", wall, mesh_s,
              images_s, tree_s);
  std::printf("  momentum          |sum m p| / sum m|p| = %.2e\n", pik::norm(p) / s);
  std::printf("  output            %s/ (snapshots, pk_*.txt, proj_*.txt, fof_*.txt, checkpoint.pbin)\n", r.out.c_str());
  return 0;
}

int run(const pik::io::CommandLine& cli, const pik::Comm& comm) {
  Run r;
  std::vector<Body> particles;
  auto format_option = [&](const std::string& name) {
    try {
      return pik::io::format_from_name(name);
    } catch (const std::invalid_argument& e) {
      cli.fail(e.what());
    }
  };
  if (cli.given("--restart")) {
    const std::string file = cli.str("--restart");
    auto [s, exact] = pik::io::read_checkpoint_parallel(file, comm, {"Momentum"}, {"omega_m", "box"});
    (void)exact;
    const auto& a = s.attr;
    for (const char* key : {"box", "omega_m", "mesh", "theta", "eps", "steps", "a_start", "a_end"}) {
      const std::string opt = std::string("--") + (std::string(key) == "omega_m" ? "omega-m" : std::string(key) == "a_start" ? "a-start" : std::string(key) == "a_end" ? "a-end" : key);
      if (cli.given(opt) && cli.real(opt) != a.get_double(key)) cli.fail(opt + " differs from the checkpoint's " + key);
    }
    r.bg.omega_m = a.get_double("omega_m"), r.pk.omega_m = r.bg.omega_m;
    r.pk.omega_b = a.get_double("omega_b"), r.pk.h = a.get_double("h"), r.pk.n_s = a.get_double("n_s");
    r.pk.sigma8 = a.get_double("sigma8");
    r.pk.fit = a.get_string("spectrum") == "bbks" ? PowerSpectrum::Fit::bbks : PowerSpectrum::Fit::eisenstein_hu;
    r.gp.box = a.get_double("box"), r.gp.n_mesh = int(a.get_int("mesh")), r.gp.theta = a.get_double("theta");
    r.gp.eps = a.get_double("eps"), r.n_side = int(a.get_int("n_side")), r.seed = std::uint64_t(a.get_int("seed"));
    // checkpoints written before --rs-cells/--rcut existed ran at the defaults
    if (a.has("rs_cells")) r.gp.r_split_cells = a.get_double("rs_cells"), r.gp.r_cut_split = a.get_double("rcut");
    for (const auto& [opt, v] : {std::pair{"--rs-cells", r.gp.r_split_cells}, std::pair{"--rcut", r.gp.r_cut_split}})
      if (cli.given(opt) && cli.real(opt) != v) cli.fail(std::string(opt) + " differs from the checkpoint's " + std::to_string(v));
    r.ic = a.get_string("ic"), r.a_start = a.get_double("a_start"), r.a_end = a.get_double("a_end");
    r.n_steps = std::uint64_t(a.get_int("steps")), r.fof_b = a.get_double("fof_b");
    r.max_steps = cli.count("--max-steps");
    r.checkpoint_every = cli.given("--checkpoint-every") ? cli.count("--checkpoint-every") : std::uint64_t(a.get_int("checkpoint_every"));
    r.format = format_option(cli.given("--format") ? cli.str("--format") : a.get_string("format"));
    r.out = cli.given("--out") ? cli.str("--out") : a.get_string("out");
    std::stringstream ss(a.get_string("outputs"));
    for (std::string item; std::getline(ss, item, ',');) r.outputs.push_back(std::stod(item));
    r.step = s.step;
    const auto* mom = s.find("Momentum");
    particles.resize(s.size());
    const double m = particle_mass(r.bg, r.gp.box, r.n_side);  // exactly the initial conditions' mass
    for (std::size_t i = 0; i < s.size(); ++i) {
      Body& b = particles[i];
      b.id = s.id[i], b.mass = m, b.pos = s.pos[i];
      b.mom = {mom->data[3 * i], mom->data[3 * i + 1], mom->data[3 * i + 2]};
    }
  } else {
    r.bg.omega_m = cli.real("--omega-m"), r.pk.omega_m = r.bg.omega_m;
    r.pk.omega_b = cli.real("--omega-b"), r.pk.h = cli.real("--h"), r.pk.n_s = cli.real("--ns");
    r.pk.sigma8 = cli.real("--sigma8");
    const std::string sp = cli.str("--spectrum");
    if (sp != "eh" && sp != "bbks") cli.fail("--spectrum must be eh or bbks, got " + sp);
    r.pk.fit = sp == "bbks" ? PowerSpectrum::Fit::bbks : PowerSpectrum::Fit::eisenstein_hu;
    r.n_side = int(cli.count("--n"));
    r.gp.box = cli.real("--box");
    r.gp.n_mesh = cli.given("--mesh") ? int(cli.count("--mesh")) : r.n_side;
    r.gp.theta = cli.real("--theta");
    r.gp.eps = cli.real("--eps") * r.gp.box / std::max(1, r.n_side);
    r.gp.r_split_cells = cli.real("--rs-cells"), r.gp.r_cut_split = cli.real("--rcut");
    r.a_start = cli.real("--a-start"), r.a_end = cli.real("--a-end");
    r.n_steps = cli.count("--steps"), r.checkpoint_every = cli.count("--checkpoint-every");
    r.max_steps = cli.count("--max-steps");
    r.seed = cli.count("--seed"), r.fof_b = cli.real("--fof-b"), r.ic = cli.str("--ic");
    const std::string lpt = cli.str("--lpt");
    if (lpt != "1" && lpt != "2") cli.fail("--lpt must be 1 (Zel'dovich) or 2 (2LPT), got " + lpt);
    r.order = lpt == "2" ? 2 : 1;
    r.outputs = parse_list(cli, "--outputs");
    r.format = format_option(cli.str("--format"));
    r.out = cli.str("--out");
    if (r.n_side < 2 || r.n_side > 1024) cli.fail("--n must be in [2, 1024]");
    if (!(r.bg.omega_m > 0 && r.bg.omega_m <= 1)) cli.fail("--omega-m must be in (0, 1] (flat: Omega_Lambda = 1 - Omega_m)");
    if (!(r.pk.omega_b >= 0 && r.pk.omega_b < r.bg.omega_m)) cli.fail("--omega-b must be in [0, omega-m)");
    if (!(r.pk.h > 0) || !(r.pk.sigma8 > 0)) cli.fail("--h and --sigma8 must be positive");
    if (!(r.a_start > 0 && r.a_start < r.a_end && r.a_end <= 10)) cli.fail("need 0 < --a-start < --a-end <= 10");
    if (r.n_steps < 1) cli.fail("--steps must be at least 1");
    if (r.ic != "zeldovich" && r.ic != "pancake") cli.fail("--ic must be zeldovich or pancake, got " + r.ic);
    r.pk.normalise();
    if (comm.is_root()) {
      particles = r.ic == "pancake" ? Pancake{r.bg, r.gp.box, r.a_end}.particles(r.n_side, r.a_start)
                                    : grid_particles(r.bg, r.pk, r.n_side, r.gp.box, r.a_start, r.seed, {.order = r.order});
    }
  }
  if (!(r.gp.box > 0)) cli.fail("--box must be positive");
  if (r.gp.n_mesh < 4) cli.fail("--mesh must be at least 4");
  if (!(r.gp.theta >= 0 && r.gp.theta <= 1)) cli.fail("--theta must be in [0, 1]");
  if (!(r.gp.eps > 0)) cli.fail("--eps must be positive");
  if (!(r.gp.r_split_cells > 0)) cli.fail("--rs-cells must be positive");
  if (!(r.gp.r_cut_split > 0 && r.gp.r_cut_split <= 6)) cli.fail("--rcut must be in (0, 6] (units of r_s)");
  if (!(r.gp.r_split_cells * r.gp.r_cut_split < 0.5 * r.gp.n_mesh))
    cli.fail("--rs-cells x --rcut must be below half the mesh (the short-range cut-off must fit in half the box)");
  if (!(r.fof_b > 0 && r.fof_b < 1)) cli.fail("--fof-b must be in (0, 1)");
  r.pk.normalise();
  return simulate(r, std::move(particles), comm);
}

}  // namespace

int main(int argc, char** argv) {
  pik::io::CommandLine cli("cosmo", "Dark matter in a periodic LCDM box: Zel'dovich ICs, TreePM gravity, "
                                    "leapfrog in the scale factor (lengths Mpc/h comoving, G = H0 = 1).");
  cli.option("--n", "64", "particles per side (n^3 in all)", "N");
  cli.option("--box", "100", "box side in Mpc/h", "L");
  cli.option("--mesh", "", "PM mesh cells per side (default: --n)", "M");
  cli.option("--omega-m", "0.3", "matter density (flat: Omega_Lambda = 1 - Omega_m; 1 = Einstein-de Sitter)", "X");
  cli.option("--omega-b", "0.045", "baryon density (shape of the Eisenstein & Hu spectrum)", "X");
  cli.option("--h", "0.7", "Hubble constant / 100 km/s/Mpc", "X");
  cli.option("--ns", "0.96", "spectral index", "X");
  cli.option("--sigma8", "0.8", "normalisation of the linear spectrum at a = 1", "X");
  cli.option("--spectrum", "eh", "linear spectrum: eh (Eisenstein & Hu 1998 no-wiggle) or bbks", "S");
  cli.option("--ic", "zeldovich", "initial conditions: zeldovich (Gaussian field) or pancake (plane wave crossing at --a-end)", "IC");
  cli.option("--lpt", "1", "order of the initial displacements: 1 (Zel'dovich) or 2 (2LPT, Scoccimarro 1998)", "ORDER");
  cli.option("--seed", "1", "random seed of the initial field", "S");
  cli.option("--a-start", "0.02", "initial scale factor (z = 49)", "A");
  cli.option("--a-end", "1", "final scale factor", "A");
  cli.option("--steps", "128", "leapfrog steps, uniform in ln a", "N");
  cli.option("--theta", "0.3", "opening angle of the short-range tree walk", "THETA");
  cli.option("--eps", "1/30", "Plummer softening in units of the mean particle spacing", "EPS");
  cli.option("--rs-cells", "1.25", "TreePM split scale r_s in mesh cells (0.65 with --rcut 3.5: the accuracy of "
                                   "FDPS's TreePM sample, about 10x below the default's; docs/cosmo.md)", "RS");
  cli.option("--rcut", "5", "short-range cut-off in units of r_s, at most 6", "X");
  cli.option("--outputs", "0.1,0.25,0.5,1", "scale factors of snapshots, P(k), maps and haloes (also at the start)", "A,A,...");
  cli.option("--fof-b", "0.2", "friends-of-friends linking length in mean spacings", "B");
  cli.option("--checkpoint-every", "16", "write out/checkpoint.pbin every N steps and at the end (0: never)", "N");
  cli.option("--max-steps", "0", "stop after N steps of this run, with a checkpoint (0: run to --a-end)", "N");
  cli.option("--format", pik::io::have_hdf5 ? "hdf5" : "binary",
             std::string("snapshot format: ascii, binary") + (pik::io::have_hdf5 ? ", hdf5" : ""), "F");
  cli.option("--out", "cosmo_out", "output directory", "DIR");
  cli.option("--restart", "", "continue the run of this checkpoint", "FILE");
  cli.parse(argc, argv);
  pik::Environment env(argc, argv);
  const pik::Comm comm = env.world();
  if (!comm.is_root()) (void)std::freopen("/dev/null", "w", stdout);
  try {
    return run(cli, comm);
  } catch (const std::bad_alloc&) {
    const std::string what = "out of memory (fewer particles with --n, or more ranks under mpirun)";
    if (comm.size() > 1) comm.abort("cosmo: " + what);
    std::fprintf(stderr, "cosmo: error: %s\n", what.c_str());
    return 1;
  } catch (const std::exception& e) {
    if (comm.size() > 1) comm.abort(std::string("cosmo: ") + e.what());
    std::fprintf(stderr, "cosmo: error: %s\n", e.what());
    return 1;
  }
}
