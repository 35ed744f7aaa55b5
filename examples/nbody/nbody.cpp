// nbody: a gravitational N-body simulation on pik.
//
// Leapfrog (kick-drift-kick, fixed step) with Barnes-Hut tree gravity; the pairwise
// kernels are kernels/gravity.pik (particles and monopole cells) and
// kernels/gravity_quadrupole.pik (quadrupole cells), compiled by pikg-gen for this CPU.
// Initial conditions: a Plummer sphere, a cold uniform sphere, or a snapshot.
// Writes snapshots, a checkpoint to restart from (bit for bit), and energy and
// momentum diagnostics (energy.txt, plotted by plot.py). Run `nbody --help`.
// The same program runs under `mpirun -np N`: pik decomposes the domain, moves the
// particles and exchanges the local essential trees; snapshots and checkpoints are
// written one part per rank (snap_000064.3.pbin), the log and progress by rank 0.
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <new>
#include <string>

#include <pik/ic/Plummer.hpp>
#include <pik/ic/UniformSphere.hpp>
#include <pik/io/Checkpoint.hpp>
#include <pik/io/ParallelCheckpoint.hpp>
#include <pik/io/CommandLine.hpp>
#include <pik/io/DiagnosticsLog.hpp>
#include <pik/io/Progress.hpp>
#include <pik/io/ParallelSnapshot.hpp>
#include <pik/io/SnapshotIo.hpp>
#include <pik/pik.hpp>

using pik::Vec3;

// ---- particles: what is stored, what the kernels read, what they return -------------
struct Force {  // kernel result, accumulated in single precision
  Vec3<float> acc;
  float pot;
  void clear() { acc = {}, pot = 0; }
};
struct Body {  // the full particle
  std::uint64_t id;
  double mass;
  Vec3<double> pos, vel, acc;
  double pot;
  const Vec3<double>& getPos() const { return pos; }
  void copyFromForce(const Force& f) { acc = pik::vec_cast<Vec3<double>>(f.acc), pot = f.pot; }
};
struct EPI {  // an i-particle: its position
  Vec3<float> pos;
  const Vec3<float>& getPos() const { return pos; }
  void copyFromFP(const Body& b) { pos = pik::vec_cast<Vec3<float>>(b.pos); }
};
struct EPJ {  // a j-particle: position and mass
  Vec3<float> pos;
  float mass;
  const Vec3<float>& getPos() const { return pos; }
  float getCharge() const { return mass; }
  void copyFromFP(const Body& b) { pos = pik::vec_cast<Vec3<float>>(b.pos), mass = float(b.mass); }
};
using SPJMonopole = pik::SPJMonopole<float>;
using SPJQuadrupole = pik::SPJQuadrupole<float>;

#include "Gravity.hpp"            // EPI x EPJ
#include "GravityMonopole.hpp"    // EPI x monopole cells
#include "GravityQuadrupole.hpp"  // EPI x quadrupole cells

// ---- the run ------------------------------------------------------------------------
struct Run {
  double theta, eps, dt, t_end, e0 = NAN;
  bool quadrupole;
  int leaf, group;
  std::uint64_t step = 0, n_steps, snapshot_every, checkpoint_every;
  std::string out;
  pik::io::Format format;
  pik::ParticleSystem<Body> ps;  // this rank's particles
  bool have_forces = false;
  // Domain decomposition: weighted by each rank's interactions of the last step, a
  // cost that, unlike measured seconds, is the same in a rerun; with the cuts and
  // count (DomainInfo::state) it is stored in the checkpoint, so a restart at the
  // same rank count decomposes exactly as the uninterrupted run would.
  double cost = -1;
  std::vector<double> domain_state;
  double time() const { return double(step) * dt; }
};

// Physical parameters: stored in every snapshot; a restart must not change them.
const char* const physics[] = {"theta", "eps", "dt", "quadrupole", "leaf", "group"};

pik::io::Snapshot to_snapshot(const Run& r, bool checkpoint) {
  pik::io::Snapshot s;
  if (checkpoint) s.column("Acceleration", 3), s.column("Potential", 1);
  s.resize(r.ps.size());
  for (std::size_t i = 0; i < r.ps.size(); ++i) {
    const Body& b = r.ps[i];
    s.id[i] = b.id, s.mass[i] = b.mass, s.pos[i] = b.pos, s.vel[i] = b.vel;
    if (checkpoint) {
      s.extra[0].data[3 * i] = b.acc.x, s.extra[0].data[3 * i + 1] = b.acc.y;
      s.extra[0].data[3 * i + 2] = b.acc.z, s.extra[1].data[i] = b.pot;
    }
  }
  s.time = r.time(), s.step = r.step;
  s.attr.set("theta", r.theta), s.attr.set("eps", r.eps), s.attr.set("dt", r.dt);
  s.attr.set("quadrupole", r.quadrupole), s.attr.set("leaf", r.leaf), s.attr.set("group", r.group);
  s.attr.set("t_end", r.t_end), s.attr.set("E0", r.e0);
  s.attr.set("snapshot_every", r.snapshot_every), s.attr.set("checkpoint_every", r.checkpoint_every);
  s.attr.set("format", pik::io::format_name(r.format)), s.attr.set("out", r.out);
  if (checkpoint) s.attr.set("domain_cost", r.cost), s.attr.set("domain_state", pik::io::encode_exact(r.domain_state));
  return s;
}

void load_particles(Run& r, const pik::io::Snapshot& s) {
  const auto* acc = s.find("Acceleration");
  const auto* pot = s.find("Potential");
  r.ps.resize(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    Body& b = r.ps[i];
    b = {s.id[i], s.mass[i], s.pos[i], s.vel[i], {}, 0.0};
    if (acc && pot) b.acc = {acc->data[3 * i], acc->data[3 * i + 1], acc->data[3 * i + 2]}, b.pot = pot->data[i];
  }
  r.have_forces = acc && pot;
}

// Energies (kinetic, potential without the kernel's self term -m/eps), momentum and
// angular momentum, summed in particle order, then over ranks (reproducible at a
// given rank count).
std::vector<double> diagnostics(const Run& r, const pik::Comm& comm) {
  double k = 0, w = 0;
  Vec3<double> p{}, l{};
  for (const Body& b : r.ps) {
    k += 0.5 * b.mass * pik::norm2(b.vel);
    w += 0.5 * b.mass * (b.pot + b.mass / r.eps);
    p += b.vel * b.mass;
    l += pik::cross(b.pos, b.vel) * b.mass;
  }
  k = comm.sum(k), w = comm.sum(w), p = comm.sum(p), l = comm.sum(l);
  // e == e0 also covers E0 = 0 (a lone particle at rest), which would give 0/0.
  const double e = k + w, de = std::isnan(r.e0) || e == r.e0 ? 0.0 : std::abs((e - r.e0) / r.e0);
  return {double(r.step), r.time(), e, k, w, de, p.x, p.y, p.z, l.x, l.y, l.z};
}

template <class SPJ, class KernelSP>
int simulate(Run& r, const pik::Comm& comm, const KernelSP& kernel_sp) {
  pik::DomainInfo<double, 3> domain(comm);
  if (!r.domain_state.empty()) domain.restore_state(r.domain_state);
  pik::DistributedLongRangeTree<Force, EPI, EPJ, SPJ> tree(
      {.theta = r.theta, .n_leaf_limit = r.leaf, .n_group_limit = r.group});
  const Gravity kernel(float(r.eps * r.eps));
  double force_seconds = 0, interactions = 0, max_de = 0, wall0 = pik::wall_time();
  std::uint64_t steps_run = 0;
  const std::uint64_t n_total = comm.sum(std::uint64_t(r.ps.size()));
  auto compute_forces = [&] {
    const double t0 = pik::wall_time();
    domain.decompose(r.ps.vector(), r.cost);
    pik::exchange_particles(r.ps, domain);
    tree.calcForceAllAndWriteBack(kernel, kernel_sp, r.ps, comm);
    force_seconds += pik::wall_time() - t0;
    r.cost = double(tree.tree().interactionsEP() + tree.tree().interactionsSP());
    r.domain_state = domain.state();
    interactions += comm.sum(r.cost);
  };
  auto snapshot = [&] {
    char name[64];
    std::snprintf(name, sizeof name, "/snap_%06" PRIu64 "%s", r.step, pik::io::extension(r.format));
    pik::io::write_snapshot_parallel(r.out + name, to_snapshot(r, false), r.format, comm);
  };

  if (comm.is_root()) std::filesystem::create_directories(r.out);
  comm.barrier();
  const std::string log_path = r.out + "/energy.txt";
  const bool resume = r.step > 0 && comm.broadcast(int(std::filesystem::exists(log_path)), 0);
  pik::io::DiagnosticsLog log;  // written by rank 0
  if (comm.is_root())
    log = pik::io::DiagnosticsLog(log_path, {"step", "time", "E", "K", "W", "dE/E", "Px", "Py", "Pz",
                                             "Lx", "Ly", "Lz"}, resume ? (long long)r.step : -1);
  auto log_row = [&](const std::vector<double>& d) { if (comm.is_root()) log.row(d); };
  if (!r.have_forces) compute_forces();
  if (std::isnan(r.e0)) r.e0 = diagnostics(r, comm)[2];
  if (!resume) log_row(diagnostics(r, comm));
  if (r.step == 0 && r.snapshot_every) snapshot();

  std::printf("nbody: %" PRIu64 " particles, theta %g%s, eps %g, dt %g, steps %" PRIu64 " to %" PRIu64
              " (t = %g), kernel %s, %d ranks x %d threads\n",
              n_total, r.theta, r.quadrupole ? " (quadrupole)" : "", r.eps, r.dt, r.step,
              r.n_steps, r.t_end, Gravity::isa_name(), comm.size(), pik::detail::max_threads());
  pik::io::Progress progress(r.step, r.n_steps);
  while (r.step < r.n_steps) {
    for (Body& b : r.ps) b.vel += b.acc * (0.5 * r.dt), b.pos += b.vel * r.dt;  // kick, drift
    compute_forces();
    for (Body& b : r.ps) b.vel += b.acc * (0.5 * r.dt);                          // kick
    ++r.step, ++steps_run;
    const auto d = diagnostics(r, comm);
    log_row(d);
    max_de = std::max(max_de, d[5]);
    progress.update(r.step, r.time(), d[5], interactions / force_seconds);
    if (r.snapshot_every && (r.step % r.snapshot_every == 0 || r.step == r.n_steps)) snapshot();
    if (r.checkpoint_every && (r.step % r.checkpoint_every == 0 || r.step == r.n_steps))
      pik::io::write_checkpoint_parallel(r.out + "/checkpoint.pbin", to_snapshot(r, true), comm);
  }
  const auto d = diagnostics(r, comm);
  const double wall = pik::wall_time() - wall0;
  std::printf("\nsummary\n  particles         %" PRIu64 "\n  steps             %" PRIu64 " (t = %g)\n",
              n_total, steps_run, r.time());
  std::printf("  wall time         %.2f s (forces %.2f s)\n", wall, force_seconds);
  std::printf("  interactions/s    %.3g (%.0f per particle per step)\n",
              interactions / force_seconds,
              interactions / double(std::max<std::uint64_t>(1, steps_run + !r.have_forces)) /
                  double(std::max<std::uint64_t>(1, n_total)));
  std::printf("  |dE/E|            %.3e final, %.3e max over the run\n", d[5], max_de);
  std::printf("  momentum |P|      %.3e\n", std::hypot(d[6], d[7], d[8]));
  std::printf("  output            %s/ (energy.txt, snapshots, checkpoint.pbin)\n", r.out.c_str());
  return 0;
}

pik::io::Format format_option(const pik::io::CommandLine& cli, const std::string& name) {
  try {
    return pik::io::format_from_name(name);
  } catch (const std::invalid_argument& e) {
    cli.fail(e.what());
  }
}

int run(const pik::io::CommandLine& cli, const pik::Comm& comm) {
  Run r;
  if (cli.given("--restart")) {
    const std::string file = cli.str("--restart");
    auto [s, exact] = pik::io::read_checkpoint_parallel(file, comm, {"Acceleration", "Potential"}, {"theta", "E0"});
    const auto& a = s.attr;
    for (const std::string key : physics) {  // the same run, or it would not continue bit for bit
      const std::string opt = "--" + key, was = a.get_string(key);
      if (cli.given(opt) && cli.str(opt) != was && (key == "quadrupole" || cli.real(opt) != a.get_double(key)))
        cli.fail(opt + " differs from the checkpoint's " + key + " = " + was);
    }
    r.theta = a.get_double("theta"), r.eps = a.get_double("eps"), r.dt = a.get_double("dt");
    r.quadrupole = a.get_bool("quadrupole"), r.e0 = a.get_double("E0");
    r.leaf = int(a.get_int("leaf")), r.group = int(a.get_int("group"));
    r.t_end = cli.given("--t-end") ? cli.real("--t-end") : a.get_double("t_end");
    r.snapshot_every = cli.given("--snapshot-every") ? cli.count("--snapshot-every") : a.get_int("snapshot_every");
    r.checkpoint_every = cli.given("--checkpoint-every") ? cli.count("--checkpoint-every") : a.get_int("checkpoint_every");
    r.format = format_option(cli, cli.given("--format") ? cli.str("--format") : a.get_string("format"));
    r.out = cli.given("--out") ? cli.str("--out") : a.get_string("out");
    r.step = s.step;
    load_particles(r, s);
    if (exact) r.cost = a.get_double("domain_cost"), r.domain_state = pik::io::decode_exact(a.get_string("domain_state"), file);
  } else {
    r.theta = cli.real("--theta"), r.eps = cli.real("--eps"), r.dt = cli.real("--dt");
    r.t_end = cli.real("--t-end"), r.quadrupole = cli.on("--quadrupole");
    r.leaf = int(cli.count("--leaf")), r.group = int(cli.count("--group"));
    r.snapshot_every = cli.count("--snapshot-every"), r.checkpoint_every = cli.count("--checkpoint-every");
    r.format = format_option(cli, cli.str("--format"));
    r.out = cli.str("--out");
    const std::string ic = cli.str("--ic");
    const auto n = cli.count("--n");
    const auto seed = cli.count("--seed");
    if (ic != "plummer" && ic != "uniform" && cli.given("--n"))
      cli.fail("--n applies to generated initial conditions, not to the file " + ic);
    // Generated particles start on rank 0; the first decomposition spreads them.
    load_particles(r, ic != "plummer" && ic != "uniform" ? pik::io::read_snapshot_parallel(ic, comm)
                      : !comm.is_root()                  ? pik::io::Snapshot{}
                      : ic == "plummer"                  ? pik::ic::plummer(n, seed)
                                                         : pik::ic::uniform_sphere(n, seed));
    r.have_forces = false;
  }
  if (!(r.eps > 0)) cli.fail("--eps must be positive (the kernel divides by r^2 + eps^2)");
  if (!(r.dt > 0)) cli.fail("--dt must be positive");
  if (!(r.theta >= 0 && r.theta <= 2)) cli.fail("--theta must be in [0, 2]");
  if (r.leaf < 1 || r.group < 1) cli.fail("--leaf and --group must be at least 1");
  if (comm.sum(std::uint64_t(r.ps.size())) == 0) cli.fail("no particles");
  // Checked before the conversion: a negative or huge step count would wrap around.
  if (!(r.t_end >= 0)) cli.fail("--t-end must be non-negative");
  if (!(r.t_end / r.dt < 1e15)) cli.fail("--t-end / --dt is more than 1e15 steps");
  r.n_steps = std::uint64_t(std::llround(r.t_end / r.dt));
  if (r.n_steps < r.step) cli.fail("--t-end is before the checkpoint's time");

  if (r.quadrupole) return simulate<SPJQuadrupole>(r, comm, GravityQuadrupole(float(r.eps * r.eps)));
  return simulate<SPJMonopole>(r, comm, GravityMonopole(float(r.eps * r.eps)));
}

int main(int argc, char** argv) {
  pik::io::CommandLine cli("nbody", "Barnes-Hut N-body simulation (leapfrog, N-body units G = 1).");
  cli.option("--n", "32768", "number of particles (with --ic plummer|uniform)", "N");
  cli.option("--ic", "plummer", "initial conditions: plummer, uniform or a snapshot file", "IC");
  cli.option("--seed", "1", "random seed of the initial conditions", "S");
  cli.option("--theta", "0.5", "opening angle (0: direct summation)", "THETA");
  cli.flag("--quadrupole", "use quadrupole moments of tree cells");
  cli.option("--eps", "1/64", "Plummer softening length", "EPS");
  cli.option("--dt", "1/256", "time step", "DT");
  cli.option("--t-end", "1", "end time", "T");
  cli.option("--leaf", "8", "tree leaf limit", "N");
  cli.option("--group", "64", "i-group limit of the tree walk", "N");
  cli.option("--snapshot-every", "0", "write a snapshot every N steps and at the end (0: never)", "N");
  cli.option("--checkpoint-every", "64", "write out/checkpoint.pbin every N steps and at the end", "N");
  cli.option("--format", "binary", std::string("snapshot format: ascii, binary") +
                                       (pik::io::have_hdf5 ? ", hdf5" : ""), "F");
  cli.option("--out", "nbody_out", "output directory", "DIR");
  cli.option("--restart", "", "continue the run of this checkpoint", "FILE");
  cli.parse(argc, argv);  // before MPI starts: --help and usage errors end every rank cleanly
  pik::Environment env(argc, argv);
  const pik::Comm comm = env.world();
  if (!comm.is_root()) (void)std::freopen("/dev/null", "w", stdout);  // one progress line, one summary
  try {
    return run(cli, comm);
  } catch (const std::bad_alloc&) {
    const std::string what = "out of memory (fewer particles with --n, or more ranks under mpirun)";
    if (comm.size() > 1) comm.abort("nbody: " + what);
    std::fprintf(stderr, "nbody: error: %s\n", what.c_str());
    return 1;
  } catch (const std::exception& e) {  // pik::io::IoError, pik::Error: already say what and where
    if (comm.size() > 1) comm.abort(std::string("nbody: ") + e.what());  // no rank left waiting
    std::fprintf(stderr, "nbody: error: %s\n", e.what());
    return 1;
  }
}
