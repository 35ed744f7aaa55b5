// impact: the giant impact with SPH, self-gravity and the Tillotson EOS.
//
//   impact planet   build a differentiated body (hydrostatic profile, particles, relaxation)
//   impact evolve   let a saved body evolve alone (the hydrostatic check)
//   impact collide  two saved bodies on a collision orbit, run with snapshots and restart
//   impact analyse  planet / disk / escaping masses and the predicted moon, per snapshot
//
// Run `impact <command> --help`. Method and sources: docs/impact.md.
//
// planet, evolve and collide run unchanged under mpirun (domain decomposition, halos and
// local essential trees in Model.hpp; one gathered snapshot file, restart on any rank
// count); analyse reads the snapshots in one process.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <pik/comm/Environment.hpp>
#include <pik/eos/Registry.hpp>
#include <pik/io/CommandLine.hpp>
#include <pik/io/SnapshotIo.hpp>
#include <pik/pik.hpp>
#include <pik/sph/Driver.hpp>
#include <pik/sph/Smoothing.hpp>
#include <pik/detail/Threads.hpp>

#include "Analysis.hpp"
#include "Model.hpp"
#include "Orbit.hpp"
#include "Particles.hpp"
#include "Planet.hpp"
#include "Units.hpp"

// Generated kernels (CMakeLists.txt): one class per smoothing function.
#include "Gravity.hpp"
#include "GravityQuadrupole.hpp"
#include "ImpactDensity_0.hpp"
#include "ImpactDensity_1.hpp"
#include "ImpactDisph_0.hpp"
#include "ImpactDisph_1.hpp"
#include "ImpactSsph_0.hpp"
#include "ImpactSsph_1.hpp"

using namespace impact;

template <int S>
struct Kernels;
template <>
struct Kernels<0> {
  using Density = ImpactDensity_0;
  using Ssph = ImpactSsph_0;
  using Disph = ImpactDisph_0;
};
template <>
struct Kernels<1> {
  using Density = ImpactDensity_1;
  using Ssph = ImpactSsph_1;
  using Disph = ImpactDisph_1;
};

namespace {

const pik::eos::Registry registry = pik::eos::Registry::standard();

// ---- MPI: started after a command's options are read (so --help and option errors need
// none); every rank reads the same input, rank 0 prints and writes the files.
int main_argc = 0;
char** main_argv = nullptr;
std::optional<pik::Environment> environment;

pik::Comm start_comm() {
  if (!environment) environment.emplace(main_argc, main_argv);
  const pik::Comm comm = environment->world();
  if (!comm.is_root()) (void)std::freopen("/dev/null", "w", stdout);  // one header, progress line, summary
  return comm;
}

/// Every rank's particles on rank 0, in id order (the others get an empty vector).
/// Collective.
std::vector<Particle> gather_particles(const pik::ParticleSystem<Particle>& ps, const pik::Comm& comm) {
  std::vector<Particle> all = comm.gatherv(std::span<const Particle>(ps.vector()), 0);
  std::sort(all.begin(), all.end(), [](const Particle& a, const Particle& b) { return a.id < b.id; });
  return all;
}

/// The options every command that runs SPH shares.
void sph_options(pik::io::CommandLine& cli) {
  cli.option("--scheme", "disph", "disph (density-independent, Hosono et al. 2016) or ssph (standard)", "S");
  cli.option("--kernel", "cubic", "smoothing function: cubic or wendland2", "K");
  cli.option("--nngb", "0", "neighbour number; 0: 50 (cubic) or 100 (wendland2)", "N");
  cli.option("--alpha", "1", "artificial viscosity strength (Monaghan 1997)", "A");
  cli.option("--disph-exponent", "0.1", "DISPH: a of Z = m P^a / rho (1: the pressure itself, unstable at a free surface)", "A");
  cli.option("--cfl", "0.3", "Courant factor", "C");
  cli.option("--theta", "0.7", "opening angle of the gravity tree (quadrupole cells, opening by the centre-of-mass offset criterion: at 0.7 more accurate than monopoles at 0.5 with the box criterion, and cheaper before contact)", "THETA");
  cli.option("--snapshots", "0", "snapshots evenly in time (and the initial one); 0: the command's default", "N");
  cli.option("--format", pik::io::have_hdf5 ? "hdf5" : "binary", "snapshot format: binary, hdf5 or ascii", "F");
  cli.option("--max-steps", "0", "stop after this many steps (0: no limit)", "N");
  cli.option("--checkpoint-every", "100", "steps between checkpoints (and one at the end)", "N");
  cli.option("--log-every", "1", "a row of out/log.txt every N steps (and at every output, checkpoint and the last step); 1: every step", "N");
  cli.option("--out", "", "output directory", "DIR");
  cli.option("--tree-build", "step", "short-range tree: 'step' (built once per force evaluation, refreshed between "
             "smoothing-length passes) or 'pass' (rebuilt for every pass; slower, the results of 'step' with --sph-lists off "
             "bit for bit)", "W");
  cli.option("--sph-lists", "0", "short-range candidate lists: collected once per force evaluation with every h "
             "grown by this fraction and shared by the density passes and the hydro pass (collected again only "
             "where an h outgrows them); 'off': every pass walks the tree (one process, --tree-build step)", "M");
  cli.option("--sph-group", "64", "short-range trees: particles per i-group (and --sph-leaf per leaf, 16)", "N");
  cli.option("--sph-leaf", "16", "short-range trees: particles per leaf", "N");
  cli.option("--grav-group", "128", "gravity tree: particles per i-group (0: the runtime's default, 64)", "N");
  cli.option("--grav-leaf", "16", "gravity tree: particles per leaf (0: the runtime's default, 8; larger leaves "
             "mean more particles taken directly, so no less accurate)", "N");
  cli.option("--time-steps", "global", "'global' (one step for all, set by the smallest criterion) or 'block' "
             "(each particle on its own power-of-two fraction of the step, Saitoh & Makino 2009 limiter)", "W");
  cli.option("--max-rung", "5", "block time steps: the block is at most 2^N of the shortest particle step", "N");
  cli.option("--gravity-every", "auto", "gravity on a step of up to K SPH steps (impulse splitting: gravity "
             "kicks at the ends of its step, equal SPH steps between them; docs/impact.md, \"Gravity on a longer "
             "step\"); 1: gravity at every step; 'auto': 4 in collide with global steps, else 1", "K");
  cli.option("--h-max", "auto", "cap on the kernel support h (m; a particle at the cap with too few neighbours "
             "keeps it); 'auto': in collide twice the largest support in the target, at most its radius, no cap in planet and evolve; 0: no cap", "H");
  cli.option("--h-guess", "drift", "first h of the iteration: 'drift' (dh/dt = h div v / 3) or 'previous' (last h)",
             "G");
}

struct SphChoice {
  ModelParams prm;
  int shape = 0;
  bool h_max_auto = false;  ///< --h-max auto: the command chooses the cap
  bool gravity_every_auto = false;  ///< --gravity-every auto: the command chooses K
};

SphChoice sph_choice(const pik::io::CommandLine& cli) {
  SphChoice c;
  const std::string scheme = cli.str("--scheme");
  if (scheme != "disph" && scheme != "ssph") cli.fail("--scheme must be disph or ssph, not '" + scheme + "'");
  c.prm.disph = scheme == "disph";
  const std::string k = cli.str("--kernel");
  if (k != "cubic" && k != "wendland2") cli.fail("--kernel must be cubic or wendland2, not '" + k + "'");
  c.shape = k == "cubic" ? 0 : 1;
  c.prm.nngb = cli.real("--nngb") > 0 ? cli.real("--nngb") : pik::sph::default_nngb(3, pik::sph::Shape(c.shape));
  c.prm.alpha = cli.real("--alpha"), c.prm.cfl = cli.real("--cfl"), c.prm.theta = cli.real("--theta");
  c.prm.disph_exponent = cli.real("--disph-exponent");
  if (!(c.prm.nngb >= 8)) cli.fail("--nngb must be at least 8");
  if (!(c.prm.alpha >= 0)) cli.fail("--alpha must not be negative");
  if (!(c.prm.cfl > 0 && c.prm.cfl <= 1)) cli.fail("--cfl must be in (0, 1]");
  if (!(c.prm.theta >= 0 && c.prm.theta <= 1.5)) cli.fail("--theta must be in [0, 1.5]");
  if (!(c.prm.disph_exponent > 0 && c.prm.disph_exponent <= 1)) cli.fail("--disph-exponent must be in (0, 1]");
  const std::string tb = cli.str("--tree-build"), hg = cli.str("--h-guess");
  if (tb != "step" && tb != "pass") cli.fail("--tree-build must be step or pass, not '" + tb + "'");
  if (hg != "drift" && hg != "previous") cli.fail("--h-guess must be drift or previous, not '" + hg + "'");
  c.prm.reuse_tree = tb == "step", c.prm.predict_h = hg == "drift";
  if (cli.str("--sph-lists") == "off") {
    c.prm.list_margin = -1;
  } else {
    c.prm.list_margin = cli.real("--sph-lists");
    if (!(c.prm.list_margin >= 0 && c.prm.list_margin <= 0.5))
      cli.fail("--sph-lists must be 'off' or a margin in [0, 0.5], not '" + cli.str("--sph-lists") + "'");
  }
  c.h_max_auto = cli.str("--h-max") == "auto";
  if (!c.h_max_auto) {
    c.prm.h_max = cli.real("--h-max");
    if (!(c.prm.h_max >= 0) || !std::isfinite(c.prm.h_max))
      cli.fail("--h-max must be 'auto', 0 (no cap) or a positive length in metres, not '" + cli.str("--h-max") + "'");
  }
  c.prm.sph_group = int(cli.count("--sph-group")), c.prm.sph_leaf = int(cli.count("--sph-leaf"));
  c.prm.grav_group = int(cli.count("--grav-group")), c.prm.grav_leaf = int(cli.count("--grav-leaf"));
  if (c.prm.sph_group < 1 || c.prm.sph_leaf < 1) cli.fail("--sph-group and --sph-leaf must be at least 1");
  const std::string ts = cli.str("--time-steps");
  if (ts != "global" && ts != "block") cli.fail("--time-steps must be global or block, not '" + ts + "'");
  if (ts == "block") {
    const long r = long(cli.count("--max-rung"));
    if (r < 1 || r > 30) cli.fail("--max-rung must be between 1 and 30");
    if (!c.prm.reuse_tree) cli.fail("--time-steps block needs --tree-build step");
    c.prm.max_rung = int(r);
  }
  c.gravity_every_auto = cli.str("--gravity-every") == "auto";
  if (!c.gravity_every_auto) {
    const long ge = long(cli.count("--gravity-every"));
    if (ge < 1 || ge > 64) cli.fail("--gravity-every must be 'auto' or between 1 and 64");
    if (ge > 1 && ts == "block") cli.fail("--gravity-every needs --time-steps global (block steps are their own splitting)");
    c.prm.gravity_every = int(ge);
  }
  return c;
}

pik::sph::RunParams run_params(const pik::io::CommandLine& cli, double t_end, int default_snapshots) {
  pik::sph::RunParams r;
  r.t_end = t_end;
  r.snapshots = cli.count("--snapshots") ? int(cli.count("--snapshots")) : default_snapshots;
  r.out = cli.str("--out");
  r.max_steps = long(cli.count("--max-steps"));
  r.checkpoint_every = long(cli.count("--checkpoint-every"));
  r.log_every = long(cli.count("--log-every"));
  if (r.log_every < 1) cli.fail("--log-every must be at least 1");
  try {
    r.format = pik::io::format_from_name(cli.str("--format"));
  } catch (const std::exception& e) {
    cli.fail(std::string("--format: ") + e.what());
  }
  if (r.out.empty()) cli.fail("--out DIR is required");
  return r;
}

/// The material table of a run from the names ("iron,granite"); id = position.
pik::eos::MaterialTable material_table(const std::vector<std::string>& names) {
  pik::eos::MaterialTable t;
  for (const auto& n : names) t.add(registry.make(n));
  return t;
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::size_t a = 0;
  while (a <= s.size()) {
    const std::size_t b = std::min(s.find(',', a), s.size());
    out.push_back(s.substr(a, b - a));
    a = b + 1;
  }
  return out;
}

/// The hydrostatic check's figures, about the centre of mass: the radius R95 holding 95 %
/// of the mass (also R99: at low resolution the outermost per cent of the particles forms
/// the tenuous SPH "atmosphere" of a free surface, Reinhardt & Stadel 2017, and moves most),
/// and the density at half the radius: the median SPH density of the particles between
/// 0.45 and 0.55 R95, per material (for a core mass fraction of 0.3 the core boundary lies
/// at about R/2: one median over both would measure where the boundary is, not a density).
struct BodyShape {
  double r95 = 0, r99 = 0, rho_half_core = 0, rho_half_mantle = 0;
};
template <class PS>
BodyShape body_shape(const PS& ps) {
  double mt = 0;
  Vec3d c{};
  for (const auto& q : ps) mt += q.mass, c += q.pos * q.mass;
  c = c * (1 / mt);
  std::vector<std::pair<double, double>> rm;
  for (const auto& q : ps) rm.push_back({pik::norm(q.pos - c), q.mass});
  std::sort(rm.begin(), rm.end());
  BodyShape s;
  double acc = 0;
  for (auto& [r, mm] : rm) {
    acc += mm;
    if (s.r95 == 0 && acc >= 0.95 * mt) s.r95 = r;
    if (acc >= 0.99 * mt) {
      s.r99 = r;
      break;
    }
  }
  std::vector<double> d[2];
  for (const auto& q : ps) {
    const double r = pik::norm(q.pos - c);
    if (r >= 0.45 * s.r95 && r < 0.55 * s.r95) d[q.material == 0 ? 0 : 1].push_back(q.dens);
  }
  auto median = [](std::vector<double>& v) {
    if (v.empty()) return 0.0;
    std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  s.rho_half_core = median(d[0]), s.rho_half_mantle = median(d[1]);
  return s;
}

/// A body file: the particles, the material names, the radius and the softening.
struct Body {
  std::vector<Particle> p;
  std::vector<std::string> materials;
  double mass = 0, radius = 0, eps = 0;
};

Body read_body(const std::string& path) {
  if (!std::filesystem::exists(path)) throw pik::Error("body file '" + path + "' does not exist");
  pik::io::Snapshot s;
  try {
    s = pik::io::read_snapshot(path);
  } catch (const std::exception& e) {
    throw pik::Error("cannot read body file '" + path + "': " + e.what());
  }
  for (const char* c : {"Material", "InternalEnergy", "SmoothingLength"})
    if (!s.find(c)) throw pik::Error("'" + path + "' is not a body file (no column '" + c + "'; make one with `impact planet`)");
  for (const char* a : {"body.materials", "body.radius", "body.eps"})
    if (!s.attr.has(a)) throw pik::Error("'" + path + "' is not a body file (no attribute '" + a + "')");
  Body b;
  b.materials = split(s.attr.get_string("body.materials"));
  b.radius = s.attr.get_double("body.radius"), b.eps = s.attr.get_double("body.eps");
  if (!(b.radius > 0) || !(b.eps > 0) || s.size() == 0) throw pik::Error("'" + path + "': empty body or bad radius");
  b.p.resize(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    auto& q = b.p[i];
    q.id = std::uint32_t(s.id[i]), q.mass = s.mass[i], q.pos = s.pos[i], q.vel = s.vel[i];
    q.material = int(s.find("Material")->data[i]);
    q.u = s.find("InternalEnergy")->data[i], q.h = s.find("SmoothingLength")->data[i];
    if (const auto* d = s.find("Density")) q.dens = d->data[i];
    if (!(q.mass > 0) || !(q.u >= 0) || !(q.h > 0) || q.material < 0 || std::size_t(q.material) >= b.materials.size() ||
        !std::isfinite(pik::norm2(q.pos)) || !std::isfinite(pik::norm2(q.vel)))
      throw pik::Error("'" + path + "': particle " + std::to_string(i) + " has invalid values (corrupt body file?)");
    b.mass += q.mass;
  }
  return b;
}

/// `--h-max auto` of collide: twice the largest kernel support in the target (the body the
/// debris flies past), at most its radius.
double auto_h_max(const Body& target) {
  double h = 0;
  for (const Particle& q : target.p) h = std::max(h, q.h);
  return h > 0 ? std::min(2 * h, target.radius) : target.radius;
}

void write_body(const std::string& path, const std::vector<Particle>& ps, const std::vector<std::string>& mats,
                double radius, double eps, const std::map<std::string, double>& extra) {
  pik::io::Snapshot s;
  s.resize(ps.size());
  Vec3d c{}, v{};
  double mt = 0;
  for (const auto& q : ps) mt += q.mass, c += q.pos * q.mass, v += q.vel * q.mass;
  c = c * (1 / mt), v = v * (1 / mt);
  auto& mat = s.column("Material", 1);
  auto& u = s.column("InternalEnergy", 1);
  auto& h = s.column("SmoothingLength", 1);
  auto& rho = s.column("Density", 1);
  for (std::size_t i = 0; i < ps.size(); ++i) {
    const auto& q = ps[i];
    s.id[i] = q.id, s.mass[i] = q.mass, s.pos[i] = q.pos - c, s.vel[i] = {0, 0, 0};
    mat.data[i] = q.material, u.data[i] = q.u, h.data[i] = q.h, rho.data[i] = q.dens;
  }
  std::string m;
  for (const auto& n : mats) m += (m.empty() ? "" : ",") + n;
  s.attr.set("body.materials", m);
  s.attr.set("body.radius", radius);
  s.attr.set("body.mass", mt);
  s.attr.set("body.eps", eps);
  for (const auto& [k, x] : extra) s.attr.set(k, x);
  const std::string ext = std::filesystem::path(path).extension().string();
  const auto fmt = ext == ".hdf5" || ext == ".h5" ? pik::io::Format::hdf5 : ext == ".txt" ? pik::io::Format::ascii
                                                                                          : pik::io::Format::binary;
  pik::io::write_snapshot(path, s, fmt);
}

template <int S>
using ImpactModel = Model<Kernels<S>, Gravity, GravityQuadrupole>;

/// Runs the driver with the chosen kernel on the ranks of `comm`; `after(model, driver)`
/// sees the final state (on every rank: the model's particles are the rank's own).
template <class After>
void run_sph(const SphChoice& c, std::vector<Particle> p, const pik::eos::MaterialTable& mats,
             const pik::sph::RunParams& rp, const pik::Comm& comm, After&& after) {
  auto go = [&](auto tag) {
    constexpr int S = decltype(tag)::value;
    ImpactModel<S> model(c.prm, std::move(p), mats, comm);
    pik::sph::Driver driver(model, rp);
    driver.run();
    after(model, driver);
  };
  try {
    if (c.shape == 0) go(std::integral_constant<int, 0>{});
    else go(std::integral_constant<int, 1>{});
  } catch (const std::exception& e) {
    // an error on one rank must not leave the others waiting in a collective
    if (comm.size() > 1) comm.abort(std::string("impact: ") + e.what());
    throw;
  }
}

template <class M, class D>
void print_timing(M& model, const D& driver) {
  const auto& t = model.timings();
  // particle-steps: one particle's force evaluation (with block steps only active ones count)
  const double n = double(model.total_particles());
  const double ps = t.substeps > 0 ? double(t.active_evaluations) + n * double(t.evaluations - t.substeps)
                                   : n * double(t.evaluations);
  {
    // The summary of the benchmark: steps, CPU time per step split into SPH
    // (density + EOS + hydro), gravity and tree builds (the builds are part of the other
    // two), and particle-steps per second.
    const long fine = t.substeps > 0 ? t.substeps + (t.evaluations - t.substeps) : t.evaluations;
    const double per = 1.0 / double(std::max(1L, fine));
    std::printf("summary: %ld driver steps, %ld force evaluations (%s), %.4g particle-steps; CPU per evaluation: "
                "SPH %.4f s (density %.4f, eos %.4f, hydro %.4f), gravity %.4f s, tree builds %.4f s (wall, in the "
                "others); %.3g particle-steps per CPU second, %.3g per wall second; density passes per evaluation "
                "%.3f (groups walked per pass %.3f); %ld particles at h_max\n",
                driver.steps(), fine, t.substeps > 0 ? "block steps" : "global steps", ps,
                (t.cpu_density + t.cpu_eos + t.cpu_hydro) * per, t.cpu_density * per, t.cpu_eos * per,
                t.cpu_hydro * per, t.cpu_gravity * per, model.tree_build_seconds() * per, ps / std::max(cpu_time(), 1e-9),
                ps / std::max(driver.seconds(), 1e-9), double(t.density_passes) / double(std::max(1L, t.evaluations)),
                t.density_group_slots ? double(t.density_group_walks) / double(t.density_group_slots) : 1.0,
                model.particles_at_h_max());
    // what the short-range kernels evaluate: every candidate pair of a group (the group's
    // box grown by its largest h), of which about N_ngb per particle are neighbours
    const double dpairs = model.comm().sum(t.density_pairs), hpairs = model.comm().sum(t.hydro_pairs);
    std::printf("kernel pairs per particle and evaluation: density %.0f (all passes), hydro %.0f; N_ngb %.0f\n",
                dpairs / std::max(ps, 1.0), hpairs / std::max(ps, 1.0), model.params().nngb);
    if (t.list_groups > 0)
      std::printf("candidate lists (--sph-lists %g): collected %.3f times per group and evaluation, %.3f sets per "
                  "evaluation\n",
                  model.params().list_margin, t.lists_collected / t.list_groups,
                  double(model.list_sets()) / std::max(1.0, double(t.evaluations)));
    {
      // the projection of the figure: this run's simulated time per second, to 24 h
      const double sim = driver.time() - driver.start_time();
      if (sim > 0)
        std::printf("projection to 24 simulated hours at this run's rate (%.4g s simulated): %.1f min wall, %.1f min "
                    "of CPU time / %d threads\n",
                    sim, 86400 / sim * driver.seconds() / 60, 86400 / sim * cpu_time() / 60 / pik::detail::max_threads(),
                    pik::detail::max_threads());
    }
    if (t.split_steps > 0)
      std::printf("gravity every %d SPH steps (asked): %ld gravity steps, %ld SPH steps (%.2f per gravity step), "
                  "gravity CPU %.4f s per gravity evaluation\n",
                  model.params().gravity_every, t.gravity_steps, t.split_steps,
                  double(t.split_steps) / double(std::max(1L, t.gravity_steps)),
                  t.cpu_gravity / double(std::max(1L, t.gravity_evaluations)));
    if (t.substeps > 0) {
      std::string r;
      for (std::size_t k = 0; k < t.rungs.size(); ++k)
        if (t.rungs[k]) r += " " + std::to_string(k) + ":" + std::to_string(t.rungs[k]);
      std::printf("block steps: %ld blocks, %ld fine steps, mean active fraction %.3f, limiter %.2f s CPU (%ld "
                  "neighbour queries, %ld wake-ups), %ld steps above their criterion; rungs at the last block's start%s\n",
                  t.blocks, t.substeps, double(t.active_evaluations) / (n * double(std::max(1L, t.substeps))),
                  t.cpu_limiter, t.neighbour_queries, t.wakes, t.rung_overflows, r.c_str());
    }
  }
  std::printf("steps %ld, t = %.6g s, wall %.2f s: density %.2f s (%ld passes), eos %.2f s, hydro %.2f s, gravity "
              "%.2f s, tree builds %.2f s; %.3g particle-steps/s\n",
              driver.steps(), driver.time(), driver.seconds(), t.density, t.density_passes, t.eos, t.hydro, t.gravity,
              model.tree_build_seconds(), ps / std::max(driver.seconds(), 1e-9));
  auto& g = model.gravity_profile();
  std::printf("split: density walk %.2f s, hydro walk %.2f s, short-range tree refresh+moments %.2f s, gravity tree "
              "build+moments %.2f s, gravity walk %.2f s, density passes/evaluation %.3f, groups walked per pass %.3f\n",
              model.density_walk_seconds(), model.hydro_walk_seconds(), model.tree_refresh_seconds(),
              g.seconds("tree build") + g.seconds("moments"), g.seconds("walk") + g.seconds("kernel"), double(t.density_passes) / std::max(1L, t.evaluations),
              t.density_group_slots ? double(t.density_group_walks) / double(t.density_group_slots) : 1.0);
  std::printf("cpu: process %.2f s, density %.2f s, eos %.2f s, hydro %.2f s, gravity %.2f s (all threads; "
              "the wall-clock times above include the machine's other jobs)\n",
              cpu_time(), t.cpu_density, t.cpu_eos, t.cpu_hydro, t.cpu_gravity);
  if (model.comm().size() > 1)
    std::printf("(%d MPI ranks: the times and CPU figures above are rank 0's, the particle counts global)\n",
                model.comm().size());
}

// ---- impact planet ---------------------------------------------------------------------
int cmd_planet(int argc, char** argv) {
  pik::io::CommandLine cli("impact planet",
                           "Build a differentiated planet: hydrostatic profile for the EOS, particles placed to match "
                           "it, relaxed in isolation with damping; writes the body file.");
  cli.option("--mass", "0.9", "mass in Earth masses", "M");
  cli.option("--n", "10000", "number of particles (about)", "N");
  cli.option("--core", "iron", "core material", "NAME");
  cli.option("--mantle", "granite", "mantle material", "NAME");
  cli.option("--core-fraction", "0.3", "core mass fraction", "F");
  cli.option("--profile", "isentropic", "isentropic (u from the surface value, du = P/rho^2 drho) or constant-u", "P");
  cli.option("--u-core", "1e6", "specific internal energy of the core, at the core boundary (J/kg)", "U");
  cli.option("--u-mantle", "1e6", "specific internal energy of the mantle, at the surface (J/kg)", "U");
  cli.option("--relax-time", "0", "relaxation time (s); 0: 10 sound-crossing times", "T");
  cli.option("--damping", "0", "damping time tau of a -= v/tau (s); 0: half the dynamical time", "T");
  cli.option("--eps", "0.5", "gravitational softening in units of the mean particle spacing", "E");
  cli.option("--body", "", "the body file to write (.pbin, or .hdf5)", "FILE");
  sph_options(cli);
  cli.parse(argc, argv);
  const std::string body_path = cli.str("--body");
  if (body_path.empty()) cli.fail("--body FILE is required");
  const double mass = cli.real("--mass") * M_earth, fc = cli.real("--core-fraction");
  if (!(mass > 0)) cli.fail("--mass must be positive");
  if (!(fc >= 0 && fc < 1)) cli.fail("--core-fraction must be in [0, 1)");
  const std::size_t n = cli.count("--n");
  if (n < 100 || n > 20000000) cli.fail("--n must be between 100 and 2e7");
  if (!(cli.real("--u-core") >= 0) || !(cli.real("--u-mantle") >= 0)) cli.fail("--u-core and --u-mantle must not be negative");
  const std::vector<std::string> names = {cli.str("--core"), cli.str("--mantle")};
  for (const auto& nm : names)
    if (!registry.has(nm)) cli.fail("unknown material '" + nm + "'");
  const auto mats = material_table(names);
  SphChoice c = sph_choice(cli);
  const pik::Comm comm = start_comm();

  const Layer core{&mats[0], cli.real("--u-core"), 0}, mantle{&mats[1], cli.real("--u-mantle"), 1};
  const std::string kind = cli.str("--profile");
  if (kind != "isentropic" && kind != "constant-u") cli.fail("--profile must be isentropic or constant-u, not '" + kind + "'");
  const Profile pr = kind == "isentropic" ? isentropic_profile(core, mantle, mass, fc) : hydrostatic_profile(core, mantle, mass, fc);
  const auto placed = place_particles(pr, n, fc);
  std::vector<Particle> p(placed.size());
  const double vd = pik::sph::unit_ball(3);
  double cs_mean = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    auto& q = p[i];
    q.id = std::uint32_t(i), q.pos = placed[i].pos, q.mass = placed[i].mass, q.material = placed[i].layer;
    q.u = placed[i].u;
    q.h = std::cbrt(c.prm.nngb * q.mass / (vd * placed[i].rho));
    q.dens = placed[i].rho;
    cs_mean += mats[q.material].sound_speed(placed[i].rho, q.u) / double(p.size());
  }
  const double spacing = std::cbrt(4 * M_PI / 3 * pr.radius * pr.radius * pr.radius / double(p.size()));
  c.prm.eps = cli.real("--eps") * spacing;
  if (!(c.prm.eps > 0)) cli.fail("--eps must be positive");
  const double t_dyn = std::sqrt(pr.radius * pr.radius * pr.radius / (G * mass));
  const double t_sc = pr.radius / cs_mean;
  const double t_relax = cli.real("--relax-time") > 0 ? cli.real("--relax-time") : 10 * t_sc;
  c.prm.damping = cli.real("--damping") > 0 ? cli.real("--damping") : 0.5 * t_dyn;
  c.prm.fixed_u = true;
  c.prm.materials = names;
  std::printf("impact planet: %.4g M_E (%zu particles, core %s %.3g, mantle %s), %s profile, u %.3g / %.3g J/kg\n",
              mass / M_earth, p.size(), names[0].c_str(), fc, names[1].c_str(), kind.c_str(), core.u, mantle.u);
  std::printf("profile: R = %.1f km, core radius %.1f km, central density %.0f kg/m^3, central pressure %.4g GPa, "
              "surface density %.0f kg/m^3\n",
              pr.radius / 1e3, pr.r_core / 1e3, pr.rho.front(), pr.p.front() / 1e9, pr.rho.back());
  std::printf("dynamical time %.0f s, sound-crossing time %.0f s; relaxing %.0f s with damping time %.0f s, eps %.1f km\n",
              t_dyn, t_sc, t_relax, c.prm.damping, c.prm.eps / 1e3);
  auto rp = run_params(cli, t_relax, 5);
  std::FILE* f = nullptr;
  if (comm.is_root()) {  // the profile table beside the body, for the plots
    std::filesystem::create_directories(rp.out);
    f = std::fopen((rp.out + "/profile.txt").c_str(), "w");
  }
  if (f) {
    std::fprintf(f, "# hydrostatic profile: r (m) m (kg) rho (kg/m^3) P (Pa) u (J/kg) layer\n");
    for (std::size_t i = 0; i < pr.r.size(); i += std::max<std::size_t>(1, pr.r.size() / 500))
      std::fprintf(f, "%.6e %.6e %.6e %.6e %.6e %d\n", pr.r[i], pr.m[i], pr.rho[i], pr.p[i], pr.u[i], pr.layer[i]);
    std::fclose(f);
  }
  run_sph(c, std::move(p), mats, rp, comm, [&](auto& model, auto& driver) {
    print_timing(model, driver);
    // steadiness: R99 and rho(R/2) over the last two outputs
    const std::vector<Particle> ps = gather_particles(model.particles(), comm);
    if (!comm.is_root()) return;
    const auto now = body_shape(ps);
    std::printf("relaxed body: R95 %.1f km, R99 %.1f km, density at R95/2 %.0f (core) / %.0f (mantle) kg/m^3\n",
                now.r95 / 1e3, now.r99 / 1e3, now.rho_half_core, now.rho_half_mantle);
    write_body(body_path, ps, names, pr.radius, c.prm.eps,
               {{"body.u_core", core.u}, {"body.u_mantle", mantle.u}, {"body.core_fraction", fc},
                {"body.r95", now.r95}, {"body.r99", now.r99}, {"body.rho_half_core", now.rho_half_core}, {"body.rho_half_mantle", now.rho_half_mantle}, {"body.sound_crossing_time", t_sc},
                {"body.profile_central_density", pr.rho.front()}});
    std::printf("wrote %s\n", body_path.c_str());
  });
  return 0;
}

// ---- impact evolve ---------------------------------------------------------------------
int cmd_evolve(int argc, char** argv) {
  pik::io::CommandLine cli("impact evolve", "Let a saved body evolve alone (no damping, u evolves): the hydrostatic check.");
  cli.option("--body", "", "body file from `impact planet`", "FILE");
  cli.option("--t-end", "0", "end time (s); 0: 5 sound-crossing times of the body", "T");
  cli.option("--disperse", "1", "scale positions and h by S >= 1 about the centre of mass, set u = 0 and v = 0: "
             "a cold cloud far below rho_0 (Tillotson P = 0) that must fall in without gaining energy", "S");
  sph_options(cli);
  cli.parse(argc, argv);
  Body b = read_body(cli.str("--body"));
  const double disperse = cli.real("--disperse");
  if (!(disperse >= 1) || !std::isfinite(disperse)) throw pik::Error("--disperse must be a finite number >= 1");
  if (disperse > 1) {
    double mt = 0;
    Vec3d c{};
    for (const auto& q : b.p) mt += q.mass, c += q.pos * q.mass;
    c = c * (1 / mt);
    for (auto& q : b.p)
      q.pos = c + (q.pos - c) * disperse, q.h *= disperse, q.vel = {}, q.u = 0,
      q.dens /= disperse * disperse * disperse;
  }
  const auto s = pik::io::read_snapshot(cli.str("--body"));
  const double t_sc = s.attr.has("body.sound_crossing_time") ? s.attr.get_double("body.sound_crossing_time") : 1000;
  const double t_end = cli.real("--t-end") > 0 ? cli.real("--t-end") : 5 * t_sc;
  SphChoice c = sph_choice(cli);
  c.prm.eps = b.eps, c.prm.materials = b.materials;
  const auto mats = material_table(b.materials);
  const auto before = body_shape(b.p);
  const pik::Comm comm = start_comm();
  run_sph(c, b.p, mats, run_params(cli, t_end, 5), comm, [&](auto& model, auto& driver) {
    print_timing(model, driver);
    const std::vector<Particle> all = gather_particles(model.particles(), comm);
    if (!comm.is_root()) return;
    const auto after = body_shape(all);
    auto pct = [](double a, double b) { return 100 * (b / a - 1); };
    std::printf("hydrostatic check over %.0f s (%.2f sound-crossing times): R95 %.1f -> %.1f km (%+.2f %%), "
                "density at R95/2: core %.0f -> %.0f kg/m^3 (%+.2f %%), mantle %.0f -> %.0f kg/m^3 (%+.2f %%); "
                "R99 %.1f -> %.1f km (%+.2f %%)\n",
                driver.time(), driver.time() / t_sc, before.r95 / 1e3, after.r95 / 1e3, pct(before.r95, after.r95),
                before.rho_half_core, after.rho_half_core, pct(before.rho_half_core, after.rho_half_core),
                before.rho_half_mantle, after.rho_half_mantle, pct(before.rho_half_mantle, after.rho_half_mantle),
                before.r99 / 1e3, after.r99 / 1e3, pct(before.r99, after.r99));
  });
  return 0;
}

// ---- impact collide --------------------------------------------------------------------
AnalysisInput analysis_input(const pik::io::Snapshot& s, int iron, double ref_mass, double ref_radius) {
  AnalysisInput in;
  in.mass = s.mass, in.pos = s.pos, in.vel = s.vel;
  const auto* mat = s.find("Material");
  if (!mat) throw pik::Error("snapshot without a Material column");
  for (double v : mat->data) in.material.push_back(int(v));
  in.iron_material = iron, in.ref_mass = ref_mass, in.ref_radius = ref_radius;
  return in;
}

int cmd_collide(int argc, char** argv) {
  pik::io::CommandLine cli("impact collide",
                           "Two saved bodies on a collision orbit (impact angle, speed in units of the mutual escape "
                           "speed), run with snapshots, checkpoints and restart; `impact analyse` measures the disk.");
  cli.option("--target", "", "target body file", "FILE");
  cli.option("--impactor", "", "impactor body file", "FILE");
  cli.option("--angle", "45", "impact angle at contact (degrees; 0 head-on)", "DEG");
  cli.option("--speed", "1", "impact speed at contact in units of the mutual escape speed", "V");
  cli.option("--separation", "2", "start separation of the centres in units of R_target + R_impactor", "S");
  cli.option("--t-end", "86400", "end time (s)", "T");
  cli.option("--restart", "", "continue from this checkpoint (out/checkpoint.pbin)", "FILE");
  sph_options(cli);
  cli.parse(argc, argv);
  if (cli.str("--target").empty() || cli.str("--impactor").empty()) cli.fail("--target and --impactor are required");
  const double speed = cli.real("--speed");
  if (!(speed >= 0)) cli.fail("--speed must not be negative (it is v_imp / v_esc), not " + cli.str("--speed"));
  if (!(cli.real("--separation") > 1))
    cli.fail("--separation must exceed 1 (in units of R_target + R_impactor: the bodies would overlap)");
  const Body t = read_body(cli.str("--target")), im = read_body(cli.str("--impactor"));
  if (t.materials != im.materials) throw pik::Error("the target and the impactor must use the same materials in the same order");
  const Orbit o = collision_orbit(t.mass, im.mass, t.radius, im.radius, cli.real("--angle"), speed,
                                  cli.real("--separation") * (t.radius + im.radius));
  SphChoice c = sph_choice(cli);
  c.prm.eps = std::min(t.eps, im.eps), c.prm.materials = t.materials;
  // The default cap: twice the largest support in the relaxed target, at most its radius.
  // Only debris beyond the planet, whose kernel would otherwise grow until it holds N_ngb
  // masses across the system, reaches it. At 10^3 particles the target's outer kernels are
  // large (a few 10^6 m) and the cap is its radius; at 10^5 it is about 1.9e6 m, close to
  // SWIFT's demo impact (support 1.8e6 m for 10^5-10^6 particles). A cap of the target's
  // radius at every N let the debris next to the planet reach into it: at 10^5 particles,
  // 24 h, 4 % of the i-groups held half of the neighbour search's candidates (docs/impact.md).
  if (c.h_max_auto) c.prm.h_max = auto_h_max(t);
  // Gravity once per 4 SPH steps (fewer where its own criterion binds): the 10^5 day's
  // energy and disk as with gravity every step, at 22 % less CPU (docs/impact.md,
  // "Gravity on a longer step"); block steps are their own splitting.
  if (c.gravity_every_auto) c.prm.gravity_every = c.prm.max_rung > 0 ? 1 : 4;
  const auto mats = material_table(t.materials);
  const double M = t.mass + im.mass;
  std::vector<Particle> p;
  for (const auto& q0 : t.p) {
    Particle q = q0;
    q.pos = q0.pos - o.dx * (im.mass / M), q.vel = q0.vel - o.dv * (im.mass / M), q.body = 0;
    p.push_back(q);
  }
  for (const auto& q0 : im.p) {
    Particle q = q0;
    q.pos = q0.pos + o.dx * (t.mass / M), q.vel = q0.vel + o.dv * (t.mass / M), q.body = 1;
    p.push_back(q);
  }
  for (std::size_t i = 0; i < p.size(); ++i) p[i].id = std::uint32_t(i);
  int iron = 0;
  for (std::size_t k = 0; k < t.materials.size(); ++k)
    if (t.materials[k] == "iron") iron = int(k);
  auto rp = run_params(cli, cli.real("--t-end"), 24);
  rp.restart = cli.str("--restart");
  if (!rp.restart.empty() && !std::filesystem::exists(rp.restart)) cli.fail("--restart: no such file '" + rp.restart + "'");
  const pik::Comm comm = start_comm();
  std::printf("impact collide: target %.4g M_E (%zu particles, R %.0f km), impactor %.4g M_E (%zu, R %.0f km)\n",
              t.mass / M_earth, t.p.size(), t.radius / 1e3, im.mass / M_earth, im.p.size(), im.radius / 1e3);
  std::printf("v_esc %.3f km/s, v_imp %.3f km/s, angle %.1f deg, orbital L %.3f L_EM, contact after %.0f s, eps %.1f km, "
              "h_max %s\n",
              o.v_esc / 1e3, o.v_imp / 1e3, cli.real("--angle"), o.l_orbit / L_EM, o.t_contact, c.prm.eps / 1e3,
              c.prm.h_max > 0 ? (std::to_string(long(std::lround(c.prm.h_max / 1e3))) + " km").c_str() : "none");
  if (comm.is_root()) {
    std::filesystem::create_directories(rp.out);
    std::FILE* f = std::fopen((rp.out + "/run.txt").c_str(), "w");
    if (!f) throw pik::Error("cannot write " + rp.out + "/run.txt");
    std::fprintf(f, "target_mass %.17g\ntarget_radius %.17g\nimpactor_mass %.17g\nimpactor_radius %.17g\niron_material %d\n"
                 "v_esc %.17g\nv_imp %.17g\nangle %.17g\nl_orbit %.17g\nt_contact %.17g\n",
                 t.mass, t.radius, im.mass, im.radius, iron, o.v_esc, o.v_imp, cli.real("--angle"), o.l_orbit, o.t_contact);
    std::fclose(f);
  }
  if (comm.size() > 1) std::printf("%d MPI ranks\n", comm.size());
  run_sph(c, std::move(p), mats, rp, comm, [&](auto& model, auto& driver) { print_timing(model, driver); });
  return 0;
}

// ---- impact analyse --------------------------------------------------------------------
int cmd_analyse(int argc, char** argv) {
  pik::io::CommandLine cli("impact analyse",
                           "Per snapshot of a collide run: bound planet, disk and escaping masses, disk angular momentum "
                           "and iron fraction, predicted moon mass (Ida, Canup & Stewart 1997); writes RUN/analysis.txt.");
  cli.option("--run", "", "output directory of `impact collide`", "DIR");
  cli.flag("--circular", "disk criterion: equivalent circular orbit outside the planet (default: periapsis)");
  cli.parse(argc, argv);
  if (pik::launcher_ranks() > 1)
    throw pik::Error("impact analyse reads the snapshots in one process: run it without mpirun (or with -np 1)");
  const std::string run = cli.str("--run");
  if (run.empty()) cli.fail("--run DIR is required");
  std::map<std::string, double> info;
  {
    std::FILE* f = std::fopen((run + "/run.txt").c_str(), "r");
    if (!f) throw pik::Error("'" + run + "' is not a collide run (no run.txt)");
    char key[64];
    double v;
    while (std::fscanf(f, "%63s %lf", key, &v) == 2) info[key] = v;
    std::fclose(f);
  }
  std::vector<std::string> snaps;
  for (const auto& e : std::filesystem::directory_iterator(run)) {
    const std::string nm = e.path().filename().string();
    if (nm.rfind("snap_", 0) == 0) snaps.push_back(e.path().string());
  }
  std::sort(snaps.begin(), snaps.end());
  if (snaps.empty()) throw pik::Error("no snapshots in '" + run + "'");
  std::FILE* out = std::fopen((run + "/analysis.txt").c_str(), "w");
  if (!out) throw pik::Error("cannot write " + run + "/analysis.txt");
  const char* head = "# time_h M_planet/M_E R_planet_km M_disk/M_moon M_esc/M_moon L_disk/L_EM disk_iron M_pred/M_moon "
                     "L_total/L_EM\n";
  std::fputs(head, out), std::fputs(head, stdout);
  constexpr double M_moon = 7.342e22;  // kg
  for (const auto& sp : snaps) {
    const auto s = pik::io::read_snapshot(sp);
    auto in = analysis_input(s, int(info["iron_material"]), info["target_mass"], info["target_radius"]);
    in.equivalent_circular = cli.on("--circular");
    const auto r = analyse(in);
    char line[512];
    std::snprintf(line, sizeof line, "%8.3f %8.4f %8.1f %8.4f %8.4f %8.4f %7.4f %8.4f %8.4f\n", s.time / 3600,
                  r.planet_mass / M_earth, r.planet_radius / 1e3, r.disk_mass / M_moon, r.escape_mass / M_moon,
                  r.disk_lz / L_EM, r.disk_iron, r.moon_mass / M_moon, r.total_l / L_EM);
    std::fputs(line, out), std::fputs(line, stdout);
  }
  std::fclose(out);
  return 0;
}

void usage(std::FILE* f) {
  std::fprintf(f,
               "usage: impact <command> [options]   (impact <command> --help for the options)\n"
               "  planet    build and relax a differentiated body, write the body file\n"
               "  evolve    let a body evolve alone (hydrostatic check)\n"
               "  collide   two bodies on a collision orbit: snapshots, checkpoints, restart\n"
               "  analyse   planet / disk / escaping masses and predicted moon per snapshot\n");
}

}  // namespace

int main(int argc, char** argv) try {
  main_argc = argc, main_argv = argv;
  if (argc < 2) {
    usage(stderr);
    return 2;
  }
  const std::string cmd = argv[1];
  if (cmd == "--help" || cmd == "-h") {
    usage(stdout);
    return 0;
  }
  if (cmd == "planet") return cmd_planet(argc - 1, argv + 1);
  if (cmd == "evolve") return cmd_evolve(argc - 1, argv + 1);
  if (cmd == "collide") return cmd_collide(argc - 1, argv + 1);
  if (cmd == "analyse") return cmd_analyse(argc - 1, argv + 1);
  std::fprintf(stderr, "impact: error: unknown command '%s'\n", cmd.c_str());
  usage(stderr);
  return 2;
} catch (const std::exception& e) {
  std::fprintf(stderr, "impact: error: %s\n", e.what());
  return 1;
}
