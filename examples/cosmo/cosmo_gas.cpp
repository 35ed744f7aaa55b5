// cosmo_gas: a periodic box of dark matter and adiabatic gas, on pik.
//
// Two species, two particle systems: dark matter (cosmo::Body) and gas (cosmo::Gas).
// Both feel the same TreePM gravity through one call over pik::species(dm, gas);
// SPH (density with the layer's smoothing-length iteration, grad-h SPH with
// artificial viscosity) acts on the gas only. Comoving coordinates, KDK in the
// scale factor (GasBox.hpp). Initial conditions: the same linear field for both
// (Zel'dovich or 2LPT), the gas on the grid shifted by half a cell, masses split by
// the baryon fraction, the gas at a uniform temperature. At each output: a
// snapshot (HDF5 with PartType0 = gas and PartType1 = dark matter), pk_NNN.txt
// (P(k) of the dark matter, the gas and linear theory) and a line of gas
// statistics in gas.txt; a checkpoint to restart from. One process. Run
// `cosmo_gas --help`.
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <new>
#include <sstream>
#include <string>
#include <vector>

#include <pik/io/Checkpoint.hpp>
#include <pik/io/CommandLine.hpp>
#include <pik/io/SnapshotIo.hpp>
#include <pik/pik.hpp>

#include "Analysis.hpp"
#include "Cosmology.hpp"
#include "GasBox.hpp"
#include "GasSnapshot.hpp"
#include "InitialConditions.hpp"

#include "CosmoTreePM.hpp"
#include "CosmoTreePMSP.hpp"
#include "GasDensity.hpp"
#include "GasHydro.hpp"

using namespace cosmo;

namespace {

constexpr double mass_unit_msun_h = 2.77536627e11 * 8 * std::numbers::pi / 3;  // as in cosmo.cpp
using Box = GasBox<GasDensity, GasHydro>;

struct Run {
  Background bg;
  PowerSpectrum pk;
  GravityParams gp;
  GasParams gas;
  int n_side = 0, order = 1;
  double a_start = 0, a_end = 1, baryon_fraction = 0, t_start = 0;
  std::uint64_t step = 0, n_steps = 0, checkpoint_every = 0, seed = 1, max_steps = 0;
  std::vector<double> outputs;
  std::string out;
  pik::io::Format format = pik::io::Format::binary;
  double a_of(std::uint64_t s) const { return a_start * std::exp(std::log(a_end / a_start) * double(s) / double(n_steps)); }
};

void set_attributes(pik::io::Snapshot& s, const Run& r) {
  s.attr.set("omega_m", r.bg.omega_m), s.attr.set("omega_b", r.pk.omega_b), s.attr.set("h", r.pk.h);
  s.attr.set("n_s", r.pk.n_s), s.attr.set("sigma8", r.pk.sigma8);
  s.attr.set("spectrum", r.pk.fit == PowerSpectrum::Fit::bbks ? "bbks" : "eh");
  s.attr.set("box", r.gp.box), s.attr.set("mesh", r.gp.n_mesh), s.attr.set("theta", r.gp.theta);
  s.attr.set("eps", r.gp.eps), s.attr.set("n_side", r.n_side), s.attr.set("seed", r.seed), s.attr.set("lpt", r.order);
  s.attr.set("a_start", r.a_start), s.attr.set("a_end", r.a_end), s.attr.set("steps", r.n_steps);
  s.attr.set("checkpoint_every", r.checkpoint_every), s.attr.set("baryon_fraction", r.baryon_fraction);
  s.attr.set("t_start", r.t_start), s.attr.set("gamma", r.gas.gamma), s.attr.set("alpha", r.gas.alpha);
  s.attr.set("nngb", r.gas.nngb), s.attr.set("cfl", r.gas.cfl), s.attr.set("balsara", r.gas.balsara ? 1 : 0);
  std::string outs;
  for (double a : r.outputs) outs += (outs.empty() ? "" : ",") + std::to_string(a);
  s.attr.set("outputs", outs), s.attr.set("format", pik::io::format_name(r.format)), s.attr.set("out", r.out);
  s.attr.set("units", "Coordinates Mpc/h comoving; Velocities km/s (peculiar / sqrt(a)); Masses 1e10 Msun/h; "
                      "InternalEnergy (km/s)^2 physical; Density 1e10 Msun/h / (Mpc/h)^3 comoving");
}

/// The dark matter (checkpoint: exact momenta) and gas (also ut and h) as snapshots.
std::pair<pik::io::Snapshot, pik::io::Snapshot> to_snapshots(const Run& r, const Box& box, bool checkpoint) {
  pik::io::Snapshot d, g;
  const double vel = 100 / std::pow(box.a, 1.5);
  if (checkpoint) d.column("Momentum", 3), g.column("Momentum", 3), g.column("Ut", 1), g.column("H", 1);
  else g.column("InternalEnergy", 1), g.column("Density", 1), g.column("SmoothingLength", 1);
  d.resize(box.dm.size()), g.resize(box.gas.size());
  for (std::size_t i = 0; i < box.dm.size(); ++i) {
    const Body& b = box.dm[i];
    d.id[i] = b.id, d.mass[i] = b.mass * mass_unit_msun_h / 1e10, d.pos[i] = b.pos, d.vel[i] = b.mom * vel;
    if (checkpoint)
      for (int c = 0; c < 3; ++c) d.extra[0].data[3 * i + c] = b.mom[c];
  }
  for (std::size_t i = 0; i < box.gas.size(); ++i) {
    const Gas& p = box.gas[i];
    g.id[i] = p.id, g.mass[i] = p.mass * mass_unit_msun_h / 1e10, g.pos[i] = p.pos, g.vel[i] = p.mom * vel;
    if (checkpoint) {
      for (int c = 0; c < 3; ++c) g.extra[0].data[3 * i + c] = p.mom[c];
      g.extra[1].data[i] = p.ut, g.extra[2].data[i] = p.h;
    } else {
      g.extra[0].data[i] = p.u * 1e4, g.extra[1].data[i] = p.rho * mass_unit_msun_h / 1e10, g.extra[2].data[i] = p.h;
    }
  }
  for (auto* s : {&d, &g}) {
    s->time = box.a, s->step = r.step;
    set_attributes(*s, r);
    s->attr.set("redshift", 1 / box.a - 1);
  }
  d.attr.set("species", "dark matter"), g.attr.set("species", "gas");
  return {std::move(d), std::move(g)};
}

void analyse(const Run& r, Box& box, int index) {
  const double dq = r.gp.box / r.n_side;
  const auto pd = species_power(box.dm, r.gp.box, r.gp.n_mesh, 0.0), pg = species_power(box.gas, r.gp.box, r.gp.n_mesh, 0.5 * dq);
  char name[64];
  std::snprintf(name, sizeof name, "/pk_%03d.txt", index);
  std::FILE* f = std::fopen((r.out + name).c_str(), "w");
  if (!f) throw pik::Error("cannot write " + r.out + name);
  const double D = r.bg.growth(box.a);
  std::fprintf(f, "# a %.6g z %.6g D %.6g box %g n %d^3 + %d^3\n# k[h/Mpc] P_dm P_gas [(Mpc/h)^3] modes P_linear\n", box.a,
               1 / box.a - 1, D, r.gp.box, r.n_side, r.n_side);
  for (std::size_t i = 0; i < pd.size() && i < pg.size(); ++i)
    std::fprintf(f, "%.6e %.6e %.6e %.0f %.6e\n", pd[i].k, pd[i].power, pg[i].power, pd[i].modes, r.pk(pd[i].k) * D * D);
  std::fclose(f);
  // Gas statistics: mass-weighted T, T a^2 (constant for adiabatic expansion), the
  // largest overdensity, the fraction of gas above 1e5 K.
  double tmax = 0, hot = 0, m = 0, rmax = 0, rho_bar = r.baryon_fraction * r.bg.mean_density();
  for (const Gas& g : box.gas) {
    const double T = temperature_of_u(g.u, r.gas.gamma);
    tmax = std::max(tmax, T), m += g.mass, hot += T > 1e5 ? g.mass : 0, rmax = std::max(rmax, g.rho / rho_bar);
  }
  const double T = box.mean_temperature();
  f = std::fopen((r.out + "/gas.txt").c_str(), index == 0 ? "w" : "a");
  if (!f) throw pik::Error("cannot write " + r.out + "/gas.txt");
  if (index == 0) std::fprintf(f, "# output a z T_mean[K] T_mean*a^2 T_max[K] hot_fraction(>1e5K) max_overdensity\n");
  std::fprintf(f, "%d %.6g %.6g %.6e %.6e %.6e %.4g %.4g\n", index, box.a, 1 / box.a - 1, T, T * box.a * box.a, tmax,
               hot / m, rmax);
  std::fclose(f);
  std::printf("\n  output %d at a = %.4f: T_gas %.3g K (T a^2 %.4g), hot fraction %.3g, max overdensity %.3g\n", index,
              box.a, T, T * box.a * box.a, hot / m, rmax);
}

int simulate(Run& r, Box& box) {
  const auto k = box.kernel<CosmoTreePM>();
  const auto ks = box.kernel<CosmoTreePMSP>();
  std::filesystem::create_directories(r.out);
  std::printf("cosmo_gas: %zu dark matter + %zu gas particles, box %g Mpc/h, mesh %d^3, Omega_m %g, f_b %g, "
              "a %g -> %g in %" PRIu64 " steps (from %" PRIu64 "), %s ICs, kernel %s, %d threads\n",
              box.dm.size(), box.gas.size(), r.gp.box, r.gp.n_mesh, r.bg.omega_m, r.baryon_fraction, r.a_start, r.a_end,
              r.n_steps, r.step, r.order == 2 ? "2LPT" : "Zel'dovich", CosmoTreePM::isa_name(), pik::detail::max_threads());
  box.compute_forces(k, ks);
  std::size_t next_out = 0;
  while (next_out < r.outputs.size() && r.outputs[next_out] < box.a * (1 - 1e-12)) ++next_out;
  auto snapshot = [&](int index) {
    char name[64];
    std::snprintf(name, sizeof name, "/snap_%03d", index);
    const auto [d, g] = to_snapshots(r, box, false);
    write_gas_snapshot(r.out + name, d, g, r.gp.box, r.format);
    analyse(r, box, index);
  };
  auto checkpoint = [&] {
    const auto [d, g] = to_snapshots(r, box, true);
    pik::io::write_checkpoint(r.out + "/checkpoint.gas.pbin", g);
    pik::io::write_checkpoint(r.out + "/checkpoint.pbin", d);  // last: the restart reads this one first
  };
  if (r.step == 0) snapshot(0);
  const double wall0 = pik::wall_time();
  const std::uint64_t first = r.step;
  std::uint64_t substeps = 0;
  while (r.step < r.n_steps && !(r.max_steps && r.step - first >= r.max_steps)) {
    substeps += std::uint64_t(box.step(r.a_of(r.step + 1), k, ks));
    ++r.step;
    const auto [p, s] = box.momentum();
    const double el = pik::wall_time() - wall0, per = el / double(r.step - first);
    std::printf("\rstep %" PRIu64 "/%" PRIu64 " (%" PRIu64 " substeps)  a %.4f  z %7.3f  T_gas %.3g K  |sum m p|/sum m|p| %.1e  %.2f s/step  eta %.0f s   ",
                r.step, r.n_steps, substeps, box.a, 1 / box.a - 1, box.mean_temperature(), pik::norm(p) / s, per,
                per * double(r.n_steps - r.step));
    std::fflush(stdout);
    while (next_out < r.outputs.size() && box.a >= r.outputs[next_out] * (1 - 1e-9)) snapshot(int(++next_out));
    const bool last = r.step == r.n_steps || (r.max_steps && r.step - first == r.max_steps);
    if ((r.checkpoint_every && r.step % r.checkpoint_every == 0) || (last && (r.checkpoint_every || r.max_steps))) checkpoint();
  }
  const auto [p, s] = box.momentum();
  if (r.step < r.n_steps) std::printf("\n\nstopped after --max-steps %" PRIu64 ": continue with --restart %s/checkpoint.pbin", r.max_steps, r.out.c_str());
  std::printf("\n\nsummary\n  particles         %zu dark matter + %zu gas\n  steps             %" PRIu64 " (%" PRIu64
              " substeps; a = %.4f, z = %.4f)\n", box.dm.size(), box.gas.size(), r.step - first, substeps, box.a, 1 / box.a - 1);
  std::printf("  wall time         %.2f s: gravity %.2f s, SPH %.2f s (%d density passes)\n", pik::wall_time() - wall0,
              box.seconds_gravity(), box.seconds_sph(), box.density_passes());
  std::printf("  momentum          |sum m p| / sum m|p| = %.2e\n", pik::norm(p) / s);
  std::printf("  output            %s/ (snapshots, pk_*.txt, gas.txt, checkpoint.pbin + checkpoint.gas.pbin)\n", r.out.c_str());
  return 0;
}

std::vector<double> parse_list(const pik::io::CommandLine& cli, const std::string& opt) {
  std::vector<double> v;
  std::stringstream ss(cli.str(opt));
  for (std::string item; std::getline(ss, item, ',');) {
    char* end = nullptr;
    const double x = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !(x > 0)) cli.fail(opt + ": '" + item + "' is not a positive number");
    v.push_back(x);
  }
  return v;
}

int run(const pik::io::CommandLine& cli) {
  Run r;
  auto format_option = [&](const std::string& name) {
    try {
      return pik::io::format_from_name(name);
    } catch (const std::invalid_argument& e) {
      cli.fail(e.what());
    }
  };
  if (cli.given("--restart")) {
    const std::string file = cli.str("--restart");
    std::string gas_file = file;
    if (gas_file.size() > 5 && gas_file.ends_with(".pbin")) gas_file.insert(gas_file.size() - 5, ".gas");
    const auto d = pik::io::read_checkpoint(file, {"Momentum"}, {"baryon_fraction", "box"});
    const auto g = pik::io::read_checkpoint(gas_file, {"Momentum", "Ut", "H"}, {"baryon_fraction", "box"});
    if (d.step != g.step || d.time != g.time) cli.fail(file + " and " + gas_file + " are of different steps");
    const auto& a = d.attr;
    r.bg.omega_m = a.get_double("omega_m"), r.pk.omega_m = r.bg.omega_m, r.pk.omega_b = a.get_double("omega_b");
    r.pk.h = a.get_double("h"), r.pk.n_s = a.get_double("n_s"), r.pk.sigma8 = a.get_double("sigma8");
    r.pk.fit = a.get_string("spectrum") == "bbks" ? PowerSpectrum::Fit::bbks : PowerSpectrum::Fit::eisenstein_hu;
    r.gp.box = a.get_double("box"), r.gp.n_mesh = int(a.get_int("mesh")), r.gp.theta = a.get_double("theta");
    r.gp.eps = a.get_double("eps"), r.n_side = int(a.get_int("n_side")), r.seed = std::uint64_t(a.get_int("seed"));
    r.order = int(a.get_int("lpt")), r.a_start = a.get_double("a_start"), r.a_end = a.get_double("a_end");
    r.n_steps = std::uint64_t(a.get_int("steps")), r.baryon_fraction = a.get_double("baryon_fraction");
    r.t_start = a.get_double("t_start"), r.gas.gamma = a.get_double("gamma"), r.gas.alpha = a.get_double("alpha");
    r.gas.nngb = a.get_double("nngb"), r.gas.cfl = a.get_double("cfl"), r.gas.balsara = a.get_int("balsara") != 0;
    r.max_steps = cli.count("--max-steps");
    r.checkpoint_every = cli.given("--checkpoint-every") ? cli.count("--checkpoint-every") : std::uint64_t(a.get_int("checkpoint_every"));
    r.format = format_option(cli.given("--format") ? cli.str("--format") : a.get_string("format"));
    r.out = cli.given("--out") ? cli.str("--out") : a.get_string("out");
    std::stringstream ss(a.get_string("outputs"));
    for (std::string item; std::getline(ss, item, ',');) r.outputs.push_back(std::stod(item));
    r.step = d.step;
    r.pk.normalise();
    Box box(r.bg, r.gp, r.gas);
    box.a = d.time;
    const double m = particle_mass(r.bg, r.gp.box, r.n_side);
    const auto* md = d.find("Momentum");
    for (std::size_t i = 0; i < d.size(); ++i) {
      Body b;
      b.id = d.id[i], b.mass = (1 - r.baryon_fraction) * m, b.pos = d.pos[i];
      b.mom = {md->data[3 * i], md->data[3 * i + 1], md->data[3 * i + 2]};
      box.dm.vector().push_back(b);
    }
    const auto *mg = g.find("Momentum"), *ut = g.find("Ut"), *hh = g.find("H");
    for (std::size_t i = 0; i < g.size(); ++i) {
      Gas p;
      p.id = g.id[i], p.mass = r.baryon_fraction * m, p.pos = g.pos[i];
      p.mom = {mg->data[3 * i], mg->data[3 * i + 1], mg->data[3 * i + 2]};
      p.ut = ut->data[i], p.h = hh->data[i], p.vel = p.mom / box.a;
      p.u = p.ut * std::pow(box.a, -3 * (r.gas.gamma - 1));
      box.gas.vector().push_back(p);
    }
    return simulate(r, box);
  }
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
  const std::string lpt = cli.str("--lpt");
  if (lpt != "1" && lpt != "2") cli.fail("--lpt must be 1 (Zel'dovich) or 2 (2LPT), got " + lpt);
  r.order = lpt == "2" ? 2 : 1;
  r.seed = cli.count("--seed"), r.a_start = cli.real("--a-start"), r.a_end = cli.real("--a-end");
  r.n_steps = cli.count("--steps"), r.checkpoint_every = cli.count("--checkpoint-every"), r.max_steps = cli.count("--max-steps");
  r.outputs = parse_list(cli, "--outputs");
  r.format = format_option(cli.str("--format"));
  r.out = cli.str("--out");
  r.baryon_fraction = cli.given("--baryon-fraction") ? cli.real("--baryon-fraction") : r.pk.omega_b / r.bg.omega_m;
  r.gas.gamma = cli.real("--gamma"), r.gas.alpha = cli.real("--alpha"), r.gas.cfl = cli.real("--cfl");
  r.gas.nngb = cli.real("--nngb"), r.gas.balsara = !cli.on("--no-balsara");
  if (r.n_side < 4) cli.fail("--n must be at least 4");
  if (!(r.bg.omega_m > 0 && r.bg.omega_m <= 1)) cli.fail("--omega-m must be in (0, 1]");
  if (!(r.pk.omega_b > 0 && r.pk.omega_b < r.bg.omega_m)) cli.fail("--omega-b must be in (0, omega_m)");
  if (!(r.baryon_fraction > 0 && r.baryon_fraction < 1)) cli.fail("--baryon-fraction must be in (0, 1)");
  if (!(r.a_start > 0 && r.a_start < r.a_end)) cli.fail("--a-start must be positive and below --a-end");
  if (r.n_steps < 1) cli.fail("--steps must be at least 1");
  if (!(r.gas.gamma > 1)) cli.fail("--gamma must be above 1");
  if (!(r.gas.alpha >= 0)) cli.fail("--alpha must be non-negative");
  if (!(r.gas.cfl > 0 && r.gas.cfl <= 1)) cli.fail("--cfl must be in (0, 1]");
  if (!(r.gas.nngb >= 8)) cli.fail("--nngb must be at least 8");
  if (!(r.gp.box > 0)) cli.fail("--box must be positive");
  if (r.gp.n_mesh < 4) cli.fail("--mesh must be at least 4");
  if (!(r.gp.theta >= 0 && r.gp.theta <= 1)) cli.fail("--theta must be in [0, 1]");
  r.gp.eps = cli.real("--eps") * r.gp.box / r.n_side;
  if (!(r.gp.eps > 0)) cli.fail("--eps must be positive");
  // Default start temperature: adiabatic cooling since thermal decoupling from the CMB
  // at z ~ 150, T = T_cmb (1 + z)^2 / (1 + 150) (e.g. Peebles 1993, sect. 6).
  r.t_start = cli.given("--t-start") ? cli.real("--t-start") : 2.7255 * std::pow(1 / r.a_start, 2) / 151;
  if (!(r.t_start > 0)) cli.fail("--t-start must be positive");
  r.pk.normalise();
  Box box(r.bg, r.gp, r.gas);
  box.a = r.a_start;
  const std::uint64_t n3 = std::uint64_t(r.n_side) * r.n_side * r.n_side;
  for (const Body& b : grid_particles(r.bg, r.pk, r.n_side, r.gp.box, r.a_start, r.seed,
                                      {.order = r.order, .offset = 0, .mass_fraction = 1 - r.baryon_fraction}))
    box.dm.vector().push_back(b);
  const double u0 = u_of_temperature(r.t_start, r.gas.gamma);
  for (const Body& b : grid_particles(r.bg, r.pk, r.n_side, r.gp.box, r.a_start, r.seed,
                                      {.order = r.order, .offset = 0.5, .mass_fraction = r.baryon_fraction, .id_base = n3})) {
    Gas g;
    g.id = b.id, g.mass = b.mass, g.pos = b.pos, g.mom = b.mom, g.vel = b.mom / r.a_start;
    g.u = u0, g.ut = u0 * std::pow(r.a_start, 3 * (r.gas.gamma - 1));
    box.gas.vector().push_back(g);
  }
  box.initial_smoothing_lengths();
  return simulate(r, box);
}

}  // namespace

int main(int argc, char** argv) {
  pik::io::CommandLine cli("cosmo_gas", "Dark matter and adiabatic gas in a periodic LCDM box: TreePM gravity on both "
                                        "species, SPH on the gas (lengths Mpc/h comoving, G = H0 = 1). One process.");
  cli.option("--n", "16", "particles per side of each species (n^3 dark matter + n^3 gas)", "N");
  cli.option("--box", "50", "box side in Mpc/h", "L");
  cli.option("--mesh", "", "PM mesh cells per side (default: --n)", "M");
  cli.option("--omega-m", "0.3", "matter density (flat: Omega_Lambda = 1 - Omega_m)", "X");
  cli.option("--omega-b", "0.045", "baryon density (spectrum shape; default baryon fraction Omega_b / Omega_m)", "X");
  cli.option("--baryon-fraction", "", "gas share of the mass (default Omega_b / Omega_m)", "F");
  cli.option("--h", "0.7", "Hubble constant / 100 km/s/Mpc", "X");
  cli.option("--ns", "0.96", "spectral index", "X");
  cli.option("--sigma8", "0.8", "normalisation of the linear spectrum at a = 1", "X");
  cli.option("--spectrum", "eh", "linear spectrum: eh (Eisenstein & Hu 1998 no-wiggle) or bbks", "S");
  cli.option("--lpt", "1", "initial displacements: 1 (Zel'dovich) or 2 (2LPT)", "ORDER");
  cli.option("--seed", "1", "random seed of the initial field", "S");
  cli.option("--a-start", "0.02", "initial scale factor (z = 49)", "A");
  cli.option("--a-end", "1", "final scale factor", "A");
  cli.option("--steps", "64", "steps uniform in ln a (each split further when the gas's Courant condition asks)", "N");
  cli.option("--t-start", "", "initial gas temperature in K (default 2.7255 (1+z)^2 / 151: decoupled at z = 150)", "T");
  cli.option("--gamma", "1.6666666666666667", "adiabatic index", "G");
  cli.option("--alpha", "1", "artificial viscosity (Monaghan 1997)", "A");
  cli.flag("--no-balsara", "switch the Balsara (1995) limiter of the viscosity off");
  cli.option("--nngb", "100", "SPH neighbour number (Wendland C2)", "N");
  cli.option("--cfl", "0.25", "Courant factor on the support radius", "C");
  cli.option("--theta", "0.3", "opening angle of the short-range gravity walk", "THETA");
  cli.option("--eps", "1/30", "Plummer softening in units of the mean spacing of one species", "EPS");
  cli.option("--outputs", "0.1,0.25,0.5,1", "scale factors of snapshots, P(k) and gas statistics (also at the start)", "A,A,...");
  cli.option("--checkpoint-every", "16", "write out/checkpoint.pbin (+ .gas.pbin) every N steps and at the end (0: never)", "N");
  cli.option("--max-steps", "0", "stop after N steps of this run, with a checkpoint (0: run to --a-end)", "N");
  cli.option("--format", pik::io::have_hdf5 ? "hdf5" : "binary",
             std::string("snapshot format: ascii, binary") + (pik::io::have_hdf5 ? ", hdf5 (PartType0 gas, PartType1 dark matter)" : ""), "F");
  cli.option("--out", "cosmo_gas_out", "output directory", "DIR");
  cli.option("--restart", "", "continue the run of this checkpoint (checkpoint.pbin; checkpoint.gas.pbin beside it)", "FILE");
  cli.parse(argc, argv);
  try {
    return run(cli);
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "cosmo_gas: error: out of memory (fewer particles with --n)\n");
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cosmo_gas: error: %s\n", e.what());
    return 1;
  }
}
