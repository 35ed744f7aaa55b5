/// \file Model.hpp
/// \brief The SPH model of the impact example for the shared driver (pik/sph/Driver.hpp):
///        several materials with their own EOS, self-gravity, DISPH (default) or SSPH,
///        optional damping and fixed u for relaxing a planet in isolation.
///
/// One force evaluation (compute()):
///   1. density by gather with the smoothing-length iteration (kernels/sph_density.pik,
///      pik/sph/SmoothingLength.hpp): rho = sum_j m_j W_ij(h_i), and y = sum_j Z_j W_ij;
///   2. the EOS of each particle's material at the density of the scheme: SSPH the
///      mass density rho; DISPH rho_i = m_i y_i / Z_i, the density of the volume element
///      Z_i / y_i (Saitoh & Makino 2013; Hosono et al. 2016), Z_i = m_i P_i^a / rho_i from
///      the previous evaluation (a: --disph-exponent, 0.1 by default: with a = 1 the
///      free surface, where P falls to the floor, blows up in our tests);
///   3. hydrodynamic forces (kernels/sph_force_disph_eos.pik or sph_force_ssph.pik),
///      Monaghan (1997) artificial viscosity with the Balsara (1995) switch;
///   4. self-gravity by the Barnes-Hut tree (kernels/gravity.pik between particles,
///      kernels/gravity_quadrupole.pik for quadrupole cells, opening angle theta with the
///      centre-of-mass offset criterion), Plummer softening eps;
///   5. relaxation only: damping a -= v / tau, du/dt = 0.
/// DISPH needs P > 0 in Z: the pressure in Z is max(P, p_min_disph), p_min_disph = 1e-6 A
/// of the material (a few kPa to 0.1 MPa). The force and du/dt use the EOS pressure P
/// itself (pf = P / y^2): the floor only keeps the volume element Z / y finite. (Until
/// session 5 the floored pressure entered the force too. Cold expanded material (u = 0,
/// rho << rho_0, Tillotson P = 0) then pushed with p_min_disph, an acceleration of about
/// p_min / (rho h), while the work it did could not be taken from u, which is held at
/// u >= 0: escaping debris at r ~ 5e9 m, rho ~ 1e-8 kg/m^3 reached 100-300 km/s and a
/// day-long run's total energy went from -1.97e32 to +0.19e32 J. Test: impact.cold_cloud.)
///
/// Under MPI (more than one rank in the communicator; docs/impact.md, "Under mpirun") each
/// rank starts with an equal share of the particles in id order (the driver's restart
/// layout); every compute() moves the particles to the owners of the last decomposition,
/// cuts new domains from them (pik::DomainInfo, equal particle counts: a rank's domain
/// follows the bodies as they merge and spread into a disk) and moves them again, each
/// time sorted by id, so the order on a rank depends only on which particles it holds.
/// Each density pass of the smoothing-length iteration imports the halo within the
/// particles' current h (pik::ShortRangeHalo, gather), the hydro pass the halo within
/// max(h_i, h_j) after the EOS (symmetric), and gravity exchanges local essential trees
/// (pik::DistributedLongRangeTree). Energies, momenta and the h iteration's count are
/// global; a checkpoint stores the decomposition (count and cuts), so a restart on the
/// same number of ranks continues bit for bit. Block time steps run in one process only.
/// One rank: exactly the single-process code path.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <span>
#include <string>
#include <vector>

#include <pik/comm/Comm.hpp>
#include <pik/domain/DistributedLongRangeTree.hpp>
#include <pik/domain/DomainInfo.hpp>
#include <pik/domain/ParticleExchange.hpp>
#include <pik/domain/ShortRangeHalo.hpp>
#include <pik/eos/Eos.hpp>
#include <pik/eos/Tillotson.hpp>
#include <pik/io/Snapshot.hpp>
#include <pik/pik.hpp>
#include <pik/sph/Leapfrog.hpp>
#include <pik/sph/Parallel.hpp>
#include <pik/sph/SmoothingLength.hpp>
#include <pik/sph/TimeStep.hpp>

#include <pik/detail/Threads.hpp>

#include "Particles.hpp"

namespace impact {

struct ModelParams {
  bool disph = true;
  double disph_exponent = 0.1;  ///< a of Z = m P^a / rho
  double nngb = 50;
  double h_tol = 1e-2;
  /// cap on the kernel support h (m); 0: none. A particle at the cap with fewer than
  /// N_ngb neighbours counts as converged (pik/sph/SmoothingLength.hpp): far debris keeps
  /// a bounded kernel instead of one reaching across the system (SWIFT's `SPH: h_max`).
  double h_max = 0;
  double alpha = 1.0;           ///< artificial viscosity
  bool balsara = true;
  double cfl = 0.3;
  double theta = 0.7;           ///< gravity tree opening angle (offset criterion, quadrupole cells)
  double eps = 0;               ///< gravitational softening (m)
  double damping = 0;           ///< relaxation: damping time tau (s); 0: none
  bool fixed_u = false;         ///< relaxation: keep u
  int sph_leaf = 16, sph_group = 64;  ///< short-range trees: leaf and i-group sizes (docs/impact.md, 2026-12-06 third session)
  int grav_leaf = 16, grav_group = 128;  ///< gravity tree: leaf and i-group sizes (0: the runtime's defaults; docs/impact.md, 2026-12-06 fourth session)
  bool reuse_tree = true;       ///< one short-range tree build per evaluation (false: one per pass)
  /// Candidate lists kept per evaluation and shared by the density passes and the hydro
  /// pass, with search radii grown by this fraction (ShortRangeTree::keepCandidates;
  /// one process with reuse_tree only); < 0: every pass walks the tree.
  double list_margin = 0;
  bool predict_h = true;        ///< drift h with dh/dt = (h/3) div v before the h iteration
  int max_rung = 0;             ///< block time steps: rungs 0..max_rung below the driver's step (0: one global step)
  /// Gravity on a step about this many times the SPH step (impulse splitting, advance());
  /// 1: gravity at every force evaluation.
  int gravity_every = 1;
  std::vector<std::string> materials;  ///< names, for checkpoints
};

/// CPU seconds of the process so far, all threads (under load the wall-clock time
/// measures the machine's other jobs too; the CPU time does not).
inline double cpu_time() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

/// Seconds per part of the force evaluation: wall clock, and CPU time of all threads.
struct Timings {
  double density = 0, eos = 0, hydro = 0, gravity = 0;
  double cpu_density = 0, cpu_eos = 0, cpu_hydro = 0, cpu_gravity = 0;
  long density_passes = 0, evaluations = 0;
  long density_group_walks = 0, density_group_slots = 0;  ///< groups walked / groups × passes
  double density_pairs = 0, hydro_pairs = 0;  ///< pairs the kernels evaluated (candidates, not only neighbours)
  double lists_collected = 0;  ///< kept candidate lists: groups collected (summed over evaluations)
  double list_groups = 0;      ///< groups of the trees (summed over evaluations)
  // block time steps (Model::advance)
  long blocks = 0, substeps = 0;        ///< driver steps done in blocks; force evaluations (fine steps)
  long active_evaluations = 0;          ///< particles evaluated, summed over the fine steps
  long wakes = 0, rung_overflows = 0;   ///< limiter wake-ups; particles whose step stayed above their criterion
  long neighbour_queries = 0;
  double cpu_limiter = 0;
  std::vector<long> rungs;              ///< particles per rung at the start of the last block
  long gravity_evaluations = 0;         ///< gravity passes (fewer than evaluations with --gravity-every)
  long split_steps = 0;                 ///< SPH steps inside gravity steps (--gravity-every)
  long gravity_steps = 0;               ///< gravity steps taken (--gravity-every)
};

/// K: the kernel classes (Density, Ssph, Disph) for one smoothing function.
template <class K, class GravityKernel, class GravityCellKernel>
class Model {
  using DensityTree = pik::ShortRangeTree<DensityResult, ImpactEP, ImpactEP, pik::SearchMode::gather>;
  using HydroTree = pik::ShortRangeTree<HydroResult, ImpactEP, ImpactEP, pik::SearchMode::symmetric>;
  using GravTree = pik::LongRangeTree<GravityResult, GravEPI, GravEPJ, GravSPJ>;

 public:
  /// `p`: every particle of the run (each rank passes the same set; under MPI a rank
  /// keeps its equal share in id order).
  Model(ModelParams prm, std::vector<Particle> p, const pik::eos::MaterialTable& mats, const pik::Comm& comm)
      : prm_(std::move(prm)), comm_(comm), dinfo_(comm), ps_(std::move(p)), mats_(mats),
        density_tree_({.n_leaf_limit = prm_.sph_leaf, .n_group_limit = prm_.sph_group}, pik::Boundary<3>::open()),
        hydro_tree_({.n_leaf_limit = prm_.sph_leaf, .n_group_limit = prm_.sph_group}, pik::Boundary<3>::open()),
        gravity_tree_(grav_params(prm_)), density_(), ssph_(float(prm_.alpha)),
        disph_(float(prm_.alpha)) {
    if (!(prm_.eps > 0)) throw pik::Error("the gravitational softening must be positive");
    for (const auto& q : ps_) (void)mats_[q.material];  // every material id is defined
    h_params_ = {.nngb = prm_.nngb, .tol = prm_.h_tol, .max_passes = 50, .fixed_h = 0, .h_max = prm_.h_max};
    n_total_ = ps_.size();
    if (comm_.size() > 1) {
      if (prm_.max_rung > 0)
        throw pik::Error("block time steps (--time-steps block) run in one process only; under mpirun use "
                         "--time-steps global");
      auto& v = ps_.vector();
      std::sort(v.begin(), v.end(), [](const Particle& a, const Particle& b) { return a.id < b.id; });
      const auto [a, b] = pik::sph::equal_share(v.size(), comm_.rank(), comm_.size());
      v.erase(v.begin() + std::ptrdiff_t(b), v.end());
      v.erase(v.begin(), v.begin() + std::ptrdiff_t(a));
      h_params_.global_sum = [c = comm_](long n) { return c.sum(n); };
      dgravity_.emplace(grav_params(prm_));
    } else if (prm_.reuse_tree && prm_.list_margin >= 0) {
      density_tree_.keepCandidates(prm_.list_margin);
      hydro_tree_.keepCandidates(prm_.list_margin);
    }
  }

  /// The communicator (pik/sph/Parallel.hpp: the driver runs the model on its ranks).
  const pik::Comm& comm() const { return comm_; }
  /// Particles on all ranks.
  std::size_t total_particles() const { return n_total_; }

  pik::ParticleSystem<Particle>& particles() { return ps_; }
  const pik::ParticleSystem<Particle>& particles() const { return ps_; }
  const ModelParams& params() const { return prm_; }
  const Timings& timings() const { return time_; }
  /// Particles whose h sits at the cap (prm_.h_max; 0 without one).
  /// Collective under MPI (the count over every rank).
  long particles_at_h_max() const {
    if (!(prm_.h_max > 0)) return 0;
    const long n = long(std::count_if(ps_.begin(), ps_.end(), [&](const Particle& p) { return p.h >= prm_.h_max; }));
    return mpi() ? comm_.sum(n) : n;
  }
  /// Tree-build seconds of the three trees (part of the density, hydro and gravity times).
  double tree_build_seconds() {
    return density_tree_.profile().seconds("tree build") + hydro_tree_.profile().seconds("tree build") +
           gravity_profile().seconds("tree build");
  }
  /// Seconds the short-range trees spent refreshing (new h, copied particles, cell boxes)
  /// and in the cell moments of their builds.
  double tree_refresh_seconds() {
    return density_tree_.profile().seconds("tree refresh") + hydro_tree_.profile().seconds("tree refresh") +
           density_tree_.profile().seconds("moments") + hydro_tree_.profile().seconds("moments");
  }
  /// Walk and kernel seconds of the density and hydro trees, and the gravity tree's profile.
  double density_walk_seconds() { return density_tree_.profile().seconds("walk+kernel"); }
  double hydro_walk_seconds() { return hydro_tree_.profile().seconds("walk+kernel"); }
  pik::Profiler& gravity_profile() { return mpi() ? dgravity_->tree().profile() : gravity_tree_.profile(); }

  void compute() {
    if (mpi()) distribute();
    density();
    bool first_z = false;
    if (prm_.disph) {
      std::atomic<bool> unset{false};  // a particle without Z (on the threads: every evaluation asks)
      pik::detail::parallel_for_static(std::ptrdiff_t(ps_.size()), [&](std::ptrdiff_t i) {
        if (!(ps_[std::size_t(i)].z > 0)) unset.store(true, std::memory_order_relaxed);
      });
      first_z = unset.load();
    }
    if (mpi()) first_z = comm_.max(int(first_z)) != 0;  // every rank makes the extra pass or none
    if (first_z) {
      // First evaluation: Z from the density the particle was set up with (dens, e.g. the
      // hydrostatic profile's), or else the mass density; then y from those Z (h is converged).
      for (auto& p : ps_) {
        const double d = p.dens > 0 ? p.dens : p.rho;
        p.z = (p.mass / Code::M) * std::pow(disph_pressure(mats_[p.material], d, p.u) / Code::P(),
                                            prm_.disph_exponent) / (d / Code::Rho());
      }
      const double t0 = pik::wall_time(), c0 = cpu_time();
      if (mpi()) {
        import_halo(density_tree_, density_halo_);  // the neighbours' new Z too
        density_tree_.build(ps_);
      } else {
        density_tree_.refresh(ps_);  // new Z, same positions and h: the tree of this step
      }
      density_tree_.calcForceOnTreeAndWriteBack(density_, ps_);
      ++time_.density_passes;
      time_.density += pik::wall_time() - t0, time_.cpu_density += cpu_time() - c0;
    }
    eos();
    forces();
    ++time_.evaluations;
  }

  /// The smoothing-length iteration. The positions do not move during it: the tree is
  /// built once (the first pass), the later passes refresh h in it and recompute only the
  /// groups holding a particle whose h changed (prm_.reuse_tree; false: a full build and
  /// pass every time, as before, for the equality test).
  void density() {
    const double t0 = pik::wall_time(), c0 = cpu_time();
    long groups = 0, all = 0;
    bool first = true;
    auto pass = [&](std::span<const std::uint8_t> active) {
      if (!mpi() && !prm_.reuse_tree) {
        density_tree_.calcForceAllAndWriteBack(density_, ps_);
        return;
      }
      if (mpi()) {
        // the halo within the particles' present h, then a tree over local and halo particles
        import_halo(density_tree_, density_halo_);
        density_tree_.build(ps_);
      } else if (first) {
        density_tree_.build(ps_);
      } else {
        density_tree_.refresh(ps_, active);  // same positions, new h for the particles of `active`
      }
      // after the first pass only the groups whose h changed are walked
      density_tree_.calcForceOnTreeAndWriteBack(density_, ps_, first ? std::span<const std::uint8_t>{} : active);
      groups += long(density_tree_.groupsWalked()), all += long(density_tree_.groups().size());
      time_.density_pairs += double(density_tree_.interactions());
      first = false;
    };
    time_.density_passes += pik::sph::iterate_smoothing_length<3>(ps_, pass, h_params_);
    time_.density_group_walks += groups, time_.density_group_slots += all;
    time_.density += pik::wall_time() - t0, time_.cpu_density += cpu_time() - c0;
  }

  /// EOS, the kernels' per-particle factors, the Balsara switch.
  void eos() {
    const double t0 = pik::wall_time(), c0 = cpu_time();
    pik::detail::parallel_for_throwing(std::ptrdiff_t(ps_.size()), [&](std::ptrdiff_t i) { eos_one(ps_[std::size_t(i)]); });
    time_.eos += pik::wall_time() - t0, time_.cpu_eos += cpu_time() - c0;
  }
  void eos_one(Particle& p) const {
    const double Pu = Code::P(), Ru = Code::Rho();
    {
      const auto& mat = mats_[p.material];
      const double mc = p.mass / Code::M;
      if (prm_.disph) {
        p.dens = mc * p.y / p.z * Ru;
      } else {
        p.dens = p.rho;
        p.z = mc;  // unused by SSPH
      }
      const auto st = mat.state(p.dens, p.u);
      p.pres = st.pressure, p.cs = st.sound_speed;
      if (prm_.disph) {
        // the EOS pressure, not the floored one of Z (see the file comment)
        p.pf = (p.pres / Pu) / (p.y * p.y);
      } else {
        // grad-h factor f = (1 + h/(3 rho) drho/dh)^-1 (Springel & Hernquist 2002, eq. 8)
        // At the cap h no longer follows the density, so the grad-h term is absent (f = 1).
        const double om = 1 + p.h / (3 * p.rho) * p.drhodh;
        p.fgrad = prm_.h_max > 0 && p.h >= prm_.h_max ? 1.0 : om > 0.2 ? 1.0 / om : 1.0;
        const double rc = p.dens / Ru;
        p.pf = p.fgrad * (p.pres / Pu) / (rc * rc);
      }
      const double div = std::abs(p.divv) / p.rho, curl = p.curl / p.rho;
      p.balsara = prm_.balsara ? div / (div + curl + 1e-4 * p.cs / p.h) : 1.0;
    }
  }

  void forces() {
    double t0 = pik::wall_time(), c0 = cpu_time();
    if (mpi() || prm_.reuse_tree) {
      if (mpi()) {
        // the halo within max(h_i, h_j), with the pressures, sound speeds and switches of
        // this evaluation's EOS pass
        import_halo(hydro_tree_, hydro_halo_);
        hydro_tree_.build(ps_);
      } else {
        // Same positions as the density passes: the density tree's octree, no new sort.
        hydro_tree_.buildLike(density_tree_, ps_);
      }
      if (prm_.disph) hydro_tree_.calcForceOnTreeAndWriteBack(disph_, ps_);
      else hydro_tree_.calcForceOnTreeAndWriteBack(ssph_, ps_);
      time_.hydro_pairs += double(hydro_tree_.interactions());
      count_lists();
    } else if (prm_.disph) {
      hydro_tree_.calcForceAllAndWriteBack(disph_, ps_);
    } else {
      hydro_tree_.calcForceAllAndWriteBack(ssph_, ps_);
    }
    time_.hydro += pik::wall_time() - t0, time_.cpu_hydro += cpu_time() - c0;
    if (!skip_gravity_) {
      t0 = pik::wall_time(), c0 = cpu_time();
      const double ec = prm_.eps / Code::L;
      if (mpi())
        dgravity_->calcForceAllAndWriteBack(GravityKernel(float(ec * ec)), GravityCellKernel(float(ec * ec)), ps_, comm_);
      else
        gravity_tree_.calcForceAllAndWriteBack(GravityKernel(float(ec * ec)), GravityCellKernel(float(ec * ec)), ps_);
      time_.gravity += pik::wall_time() - t0, time_.cpu_gravity += cpu_time() - c0;
      ++time_.gravity_evaluations;
    }
    pik::detail::parallel_for_throwing(std::ptrdiff_t(ps_.size()), [&](std::ptrdiff_t i) { finish_one(ps_[std::size_t(i)]); });
  }
  /// Kept candidate lists of this evaluation: the density tree's set, which the hydro
  /// pass borrowed (and let go) and may have added lists to.
  void count_lists() {
    if (prm_.list_margin < 0 || mpi() || !prm_.reuse_tree) return;
    time_.lists_collected += double(density_tree_.keptListsCollected() + hydro_tree_.keptListsCollected());
    time_.list_groups += double(hydro_tree_.groups().size());
  }
  /// List sets made (density and hydro trees together; one per evaluation when no h
  /// outgrows the margin of more than a twentieth of the particles).
  std::uint64_t list_sets() const { return density_tree_.keptListSets() + hydro_tree_.keptListSets(); }
  /// Gravity (unless split: advance() kicks with it) and damping into the acceleration;
  /// DISPH's Z for the next evaluation.
  void finish_one(Particle& p) const {
    if (!split()) p.acc += p.grav;
    if (prm_.damping > 0) p.acc -= p.vel * (1 / prm_.damping);
    if (prm_.fixed_u) p.dudt = 0;
    // DISPH: Z for the next evaluation, from this one's pressure and density
    if (prm_.disph)
      p.z = (p.mass / Code::M) *
            std::pow(disph_pressure(mats_[p.material], p.dens, p.u) / Code::P(), prm_.disph_exponent) /
            (p.dens / Code::Rho());
  }

  /// The leapfrog's opening half (pik/sph/Leapfrog.hpp), with u_half and the predicted u
  /// kept non-negative: a particle expanding to P = 0 may cool to u = 0 but not below
  /// (the EOS refuses u < 0).
  void open_step(Particle& p, double dt) const {
    pik::sph::open_step(p, dt);
    p.u_half = std::max(p.u_half, 0.0), p.u = std::max(p.u, 0.0);
    // split gravity, the last SPH step of a gravity step: the velocity predicted for the
    // forces is the synchronised one (with the closing gravity kick, as the global step's
    // prediction has it): the rates then hold between the drifts before and after the
    // kicks. Without it du/dt misses the kicks' compression and a planet cools (0.5 % of
    // the total energy in 600 s of the 10^5 impact, at any K).
    p.vel += p.grav * predict_kick_;
    // The first guess of the h iteration: h ∝ rho^(-1/3) and drho/dt = -rho div v, so
    // dh/dt = (h/3) div v, div v = -divv / rho (kernels/sph_density.pik); at most 10 % a step.
    if (prm_.predict_h && p.rho > 0)
      p.h *= std::clamp(std::exp(-p.divv / (3 * p.rho) * dt), 1 / 1.1, 1.1);
  }

  pik::sph::StepLimits limits() const {
    pik::sph::StepLimits lim;
    if (prm_.max_rung > 0) {
      // Block time steps: the driver's step is the block, 2^m times the shortest particle
      // step, the smallest such that covers the longest one, m <= max_rung (advance()
      // puts each particle on its rung; the shortest one's step is then its criterion).
      double lo = std::numeric_limits<double>::infinity(), hi = 0;
      for (const auto& p : ps_) {
        const double d = particle_dt(p);
        lo = std::min(lo, d), hi = std::max(hi, d);
      }
      int m = 0;
      while (m < prm_.max_rung && std::ldexp(lo, m) < hi) ++m;
      lim.add("block", std::ldexp(lo, m));
      return lim;
    }
    if (split()) {
      // Split gravity: the driver's step is the gravity step, m equal SPH steps of 0.95
      // of the SPH criteria at the present state (room for them to shrink a little
      // within the step, which would otherwise cost an (m+1)th one; 0.98 took 1 % more
      // SPH steps through contact and 2.6 % fewer late in the day, but no whole day was
      // run with it: docs/impact.md), m = K or fewer where
      // the acceleration criterion of gravity alone is shorter (a whole number of SPH
      // steps: a gravity step of 4.2 SPH criteria would take 5 steps of 0.84); under
      // MPI every rank finds the same step (collective).
      const auto m3 = step_minima(true);
      pik::sph::StepLimits sph, grav;
      sph.add("courant", m3[0]), sph.add("acceleration", m3[1]), grav.add("gravity", m3[2]);
      if (mpi()) sph = pik::sph::global_limits(sph, comm_), grav = pik::sph::global_limits(grav, comm_);
      const double c = 0.95 * sph.dt(), m = std::min(double(prm_.gravity_every), std::floor(grav.dt() / c));
      if (m >= 1) lim.add(sph.limiter(), m * c);
      else lim.add("gravity", grav.dt());
      return lim;
    }
    // both names (infinite on a rank without particles): the driver reduces them by name
    const auto m2 = step_minima(false);
    lim.add("courant", m2[0]), lim.add("acceleration", m2[1]);
    return lim;
  }

  /// The smallest Courant step, acceleration step (of p.acc) and, with `gravity`, the
  /// acceleration step of gravity alone (p.grav) over this rank's particles (infinite
  /// without particles): each particle's on the threads, then the minima.
  std::array<double, 3> step_minima(bool gravity) const {
    const std::size_t n = ps_.size(), k = gravity ? 3 : 2;
    step_buf_.resize(k * n);
    pik::detail::parallel_for_static(std::ptrdiff_t(n), [&](std::ptrdiff_t i) {
      const Particle& p = ps_[std::size_t(i)];
      double* d = step_buf_.data() + std::size_t(i);
      d[0] = pik::sph::courant(p.h, p.vsig, prm_.cfl);
      d[n] = pik::sph::acceleration(std::min(p.h, prm_.eps), pik::norm(p.acc), 0.3);
      if (gravity) d[2 * n] = pik::sph::acceleration(std::min(p.h, prm_.eps), pik::norm(p.grav), 0.3);
    });
    std::array<double, 3> m;
    m.fill(std::numeric_limits<double>::infinity());
    for (std::size_t c = 0; c < k; ++c)
      for (std::size_t i = 0; i < n; ++i) m[c] = std::min(m[c], step_buf_[c * n + i]);
    return m;
  }

  // ---- gravity on a longer step (impulse splitting) ----------------------------------
  //
  // The impulse (r-RESPA) splitting of Tuckerman, Berne & Martyna (1992), as in Streett,
  // Tildesley & Saville (1978) for slow forces in molecular dynamics: the slow force,
  // gravity, kicks at the ends of the driver's step D (v += g D/2 with the gravity of the
  // step's start, then with that of its end), the fast one, SPH, drives up to K equal
  // kick-drift-kick steps in between (limits() sets D from the SPH criteria and gravity's
  // own; advance_split() takes more steps only where the criteria shrink below them).
  // Gravity is evaluated once per D. With one SPH step per D it is the global step's
  // leapfrog exactly. The impact's gravity changes on the orbital and free-fall times
  // (thousands of seconds) while the Courant step of its iron core is seconds
  // (docs/impact.md, "Gravity on a longer step").
  bool split() const { return prm_.gravity_every > 1 && prm_.max_rung == 0; }

  /// The SPH step from the present state: Courant and the acceleration criterion on the
  /// SPH acceleration (global under MPI).
  double sph_step() const {
    const auto m2 = step_minima(false);
    pik::sph::StepLimits lim;
    lim.add("courant", m2[0]), lim.add("acceleration", m2[1]);
    if (mpi()) lim = pik::sph::global_limits(lim, comm_);
    return lim.dt();
  }

  /// One gravity step of length dt: a half kick with gravity, SPH steps, gravity at the
  /// last one's end, the other half kick.
  void advance_split(double dt) {
    auto kick = [&](double h) {
      pik::detail::parallel_for_static(std::ptrdiff_t(ps_.size()),
                                       [&](std::ptrdiff_t i) { ps_[std::size_t(i)].vel += ps_[std::size_t(i)].grav * h; });
    };
    kick(0.5 * dt);
    ++time_.gravity_steps;
    // Equal SPH steps over dt, none above the criterion: their number is set at the start
    // and again only where the criterion falls below the step. Equal steps matter: the
    // rates of the last SPH step before the kicks also serve the first one after them
    // (open_step), and the velocity predicted with half the kicks (predict_kick_) fits
    // both halves only when those two steps are equally long (else du/dt has an error
    // in proportion to their difference: a planet cooled by 3e-5 of the total energy per
    // gravity step with steps of 7.0, 5.2, 5.2, 5.2, 5.2 s; docs/impact.md).
    double t = 0, step = 0;
    long left = 0;
    for (;;) {
      const double rest = dt - t, crit = sph_step();
      if (!(crit > 0) || !std::isfinite(crit))
        throw pik::Error("SPH step " + std::to_string(crit) + " inside a gravity step (the run has blown up)");
      if (left == 0 || crit < step) {
        left = long(std::max(1.0, std::ceil(rest / crit * (1 - 1e-12))));
        step = rest / double(left);
      }
      const bool last = left == 1;
      skip_gravity_ = !last, predict_kick_ = last ? 0.5 * dt : 0.0;
      try {
        pik::sph::kdk(*this, last ? rest : step);
      } catch (...) {
        skip_gravity_ = false, predict_kick_ = 0;
        throw;
      }
      skip_gravity_ = false, predict_kick_ = 0;
      ++time_.split_steps;
      if (last) break;
      t += step, --left;
    }
    kick(0.5 * dt);
  }

  // ---- block time steps ------------------------------------------------------------
  //
  // Hierarchical power-of-two steps (e.g. Springel 2005, sec. 4; Saitoh & Makino 2009):
  // the driver's step dt (the block) holds 2^K ticks; a particle on rung k steps
  // 2^(K-k) ticks, kick-drift-kick on its own step, starting a step only at a tick that
  // the step divides. Every particle drifts at every fine step (x += v_1/2 dtau) and the
  // inactive ones' velocities are predicted to it (v_1/2 + a (t - t_mid)) for the active
  // ones' viscosity and div v; only the active particles get a new density (h iteration
  // on them alone), EOS, hydro force and gravity (the active particles are the gravity
  // tree's local particles, the others its imported j-particles; an inactive neighbour
  // keeps the pressure, Z and h of its last evaluation). At the block's end every
  // particle is synchronised, so outputs and checkpoints are those of the global step.
  //
  // Limiter (Saitoh & Makino 2009): neighbours' rungs differ by at most 2 (steps by at
  // most 4x). A particle whose step shrinks wakes its neighbours on longer steps: their
  // step is cut to end 4 of its steps from now, and the part of the opening kick (and
  // of the drift it moved them with) beyond the new end is taken back, so the woken
  // step is an exact KDK of the shorter length (Durier & Dalla Vecchia 2012 show the
  // wake-up is needed to conserve energy in strong shocks). A particle whose step grows
  // takes at most 4 times its neighbours' shortest step.

  /// The particle's step criterion: the global step's Courant and acceleration limits.
  double particle_dt(const Particle& p) const {
    return std::min(pik::sph::courant(p.h, p.vsig, prm_.cfl),
                    pik::sph::acceleration(std::min(p.h, prm_.eps), pik::norm(p.acc), 0.3));
  }

  /// One block of length dt, or one gravity step (Leapfrog.hpp calls it instead of its
  /// KDK); false in the global-step mode.
  bool advance(double dt) {
    if (split()) {
      advance_split(dt);
      return true;
    }
    if (prm_.max_rung <= 0) return false;
    const int kmax = std::min(prm_.max_rung + 6, 40);
    const std::int64_t T = std::int64_t(1) << kmax;
    const double tick = dt / double(T);
    const std::size_t n = ps_.size();
    active_.assign(n, 1);
    raised_.assign(n, 0);
    time_.rungs.assign(std::size_t(kmax) + 1, 0);
    for (auto& p : ps_) p.rung = rung_for(particle_dt(p), dt, kmax, 0), p.tick0 = 0;
    {  // the limiter over every particle: rungs that can raise a neighbour's
      const double c0 = cpu_time();
      // neighbours at the present positions and h (after a restart the tree of the last
      // evaluation does not exist; rebuilt here it is the same in both runs)
      hydro_tree_.build(ps_);
      std::vector<std::uint32_t> q;
      for (std::size_t i = 0; i < n; ++i)
        if (ps_[i].rung >= 3) q.push_back(std::uint32_t(i));
      limit_rungs(q, 0, tick, kmax);
      time_.cpu_limiter += cpu_time() - c0;
    }
    for (auto& p : ps_) ++time_.rungs[std::size_t(p.rung)], open_block(p, tick, kmax);
    std::int64_t t = 0;
    while (t < T) {
      std::int64_t tn = T;
      for (const auto& p : ps_) tn = std::min(tn, p.tick1);
      const double dtau = double(tn - t) * tick;
      long na = 0;
      for (std::size_t i = 0; i < n; ++i) {
        auto& p = ps_[i];
        p.pos += p.vel_half * dtau;
        const bool on = p.tick1 == tn;
        active_[i] = on, na += on;
        if (on) {  // predicted to the end of its step, as open_step does
          const double len = double(p.tick1 - p.tick0) * tick;
          p.vel = p.vel_half + p.acc * (0.5 * len);
          p.u = std::max(std::max(p.u_half + 0.5 * len * p.dudt, 0.5 * p.u_half), 0.0);
        } else {
          p.vel = p.vel_half + p.acc * ((double(tn) - 0.5 * double(p.tick0 + p.tick1)) * tick);
        }
      }
      t = tn;
      ++time_.substeps, time_.active_evaluations += na;
      if (na == long(n)) compute();  // every particle: the evaluation of the global step
      else compute_active();
      for (std::size_t i = 0; i < n; ++i)
        if (active_[i]) {
          auto& p = ps_[i];
          const double len = double(p.tick1 - p.tick0) * tick;
          p.vel = p.vel_half + p.acc * (0.5 * len);
          p.u = std::max(std::max(p.u_half + 0.5 * len * p.dudt, 0.5 * p.u_half), 0.0);
        }
      if (t == T) break;
      // the active particles' next step: rung from the criterion, aligned to t, limited
      const double c0 = cpu_time();
      std::vector<std::uint32_t> q;
      for (std::size_t i = 0; i < n; ++i)
        if (active_[i]) {
          auto& p = ps_[i];
          const int old = p.rung;
          p.rung = rung_for(particle_dt(p), dt, kmax, t), p.tick0 = t;
          if (p.rung != old) q.push_back(std::uint32_t(i));
        }
      limit_rungs(q, t, tick, kmax);
      time_.cpu_limiter += cpu_time() - c0;
      for (std::size_t i = 0; i < n; ++i)
        if (active_[i]) open_block(ps_[i], tick, kmax);
    }
    ++time_.blocks;
    return true;
  }

 private:
  /// The rung whose step (dt / 2^k) does not exceed the criterion dti, at least the
  /// one whose step divides the tick t (a step starts only where it fits the block).
  int rung_for(double dti, double dt, int kmax, std::int64_t t) {
    int k = 0;
    while (k < kmax && std::ldexp(dt, -k) > dti) ++k;
    if (std::ldexp(dt, -k) > dti * (1 + 1e-12)) ++time_.rung_overflows;
    while (k < kmax && t % (std::int64_t(1) << (kmax - k)) != 0) ++k;
    return k;
  }

  /// The opening half of the particle's step from tick0 on its rung.
  void open_block(Particle& p, double tick, int kmax) const {
    const std::int64_t len = std::int64_t(1) << (kmax - p.rung);
    p.tick1 = p.tick0 + len;
    const double d = double(len) * tick;
    p.vel_half = p.vel + p.acc * (0.5 * d);
    p.u_half = std::max(p.u + 0.5 * d * p.dudt, 0.0);
    if (prm_.predict_h && p.rho > 0) p.h *= std::clamp(std::exp(-p.divv / (3 * p.rho) * d), 1 / 1.1, 1.1);
  }

  /// The limiter at tick t for the particles in q (active ones whose rung changed;
  /// every particle on rung >= 3 at a block's start): neighbours (the hydro tree's,
  /// r < max(h_i, h_j)) must be on rung >= k_i - 2. An active neighbour is raised; an
  /// inactive one is woken (its step cut to end at t + 4 steps of i). A particle whose
  /// rung fell is raised to 2 below its highest neighbour. Raised and woken particles
  /// are checked in turn (a few rounds).
  void limit_rungs(std::vector<std::uint32_t> q, std::int64_t t, double tick, int kmax) {
    const int nt = pik::detail::max_threads();
    std::vector<std::vector<std::size_t>> nb(std::size_t(std::max(nt, 1)));
    std::vector<std::vector<std::pair<std::uint32_t, int>>> req(nb.size());
    std::vector<int> top(q.size());
    for (int round = 0; round < 8 && !q.empty(); ++round) {
      for (auto& r : req) r.clear();
      top.assign(q.size(), 0);
      pik::detail::parallel_for(std::ptrdiff_t(q.size()), [&](std::ptrdiff_t a, int th) {
        const Particle& p = ps_[q[std::size_t(a)]];
        ImpactEP e;
        e.copyFromFP(p);
        hydro_tree_.neighbourIndices(e, nb[std::size_t(th)]);
        int m = 0;
        for (std::size_t j : nb[std::size_t(th)]) {
          if (j >= ps_.size()) continue;
          m = std::max(m, ps_[j].rung);
          if (ps_[j].rung < p.rung - 2) req[std::size_t(th)].push_back({std::uint32_t(j), p.rung - 2});
        }
        top[std::size_t(a)] = m;
      }, 64);
      time_.neighbour_queries += long(q.size());
      std::vector<std::uint32_t> next;
      // a particle whose rung fell takes at most 4x its neighbours' shortest step
      for (std::size_t a = 0; a < q.size(); ++a) {
        Particle& p = ps_[q[a]];
        if (active_[q[a]] && top[a] - 2 > p.rung) p.rung = top[a] - 2;
      }
      // the highest request per particle, applied once (the same for any thread count)
      std::vector<std::pair<std::uint32_t, int>> all;
      for (const auto& r : req) all.insert(all.end(), r.begin(), r.end());
      std::sort(all.begin(), all.end(), [](const auto& x, const auto& y) {
        return x.first != y.first ? x.first < y.first : x.second > y.second;
      });
      for (std::size_t a = 0; a < all.size(); ++a) {
        const auto [j, k] = all[a];
        if (a > 0 && all[a - 1].first == j) continue;
        {
          Particle& p = ps_[j];
          if (p.rung >= k) continue;
          if (active_[j]) {
            p.rung = k;  // it starts its next step now: a shorter step still fits t
          } else {
            wake(p, k, t, tick, kmax);
          }
          if (!raised_[j]) raised_[j] = 1, next.push_back(j);
        }
      }
      for (std::uint32_t j : next) raised_[j] = 0;
      q = std::move(next);
    }
  }

  /// Cuts an inactive particle's step to end at t + 2^(K-k) ticks (if earlier): the
  /// opening kick beyond the new end, and the drift made with it since tick0, are
  /// taken back, so the step is a KDK of the new length.
  void wake(Particle& p, int k, std::int64_t t, double tick, int kmax) {
    const std::int64_t e = t + (std::int64_t(1) << (kmax - k));
    p.rung = k;
    if (e >= p.tick1) return;
    const double cut = double(p.tick1 - e) * tick, since = double(t - p.tick0) * tick;
    p.vel_half -= p.acc * (0.5 * cut);
    p.pos -= p.acc * (0.5 * cut * since);
    p.u_half = std::max(p.u_half - 0.5 * cut * p.dudt, 0.0);
    p.vel = p.vel_half + p.acc * ((double(t) - 0.5 * double(p.tick0 + e)) * tick);
    p.tick1 = e;
    ++time_.wakes;
  }

  /// One fine step's evaluation for the active particles (active_[i] != 0).
  void compute_active() {
    const std::size_t n = ps_.size();
    {
      const double t0 = pik::wall_time(), c0 = cpu_time();
      long groups = 0, all = 0;
      bool first = true;
      auto pass = [&](std::span<const std::uint8_t> act) {
        if (first) density_tree_.build(ps_);
        else density_tree_.refresh(ps_, act);  // new h for the particles of `act` only
        density_tree_.calcForceOnTreeAndWriteBack(density_, ps_, act);
        groups += long(density_tree_.groupsWalked()), all += long(density_tree_.groups().size());
        first = false;
      };
      time_.density_passes += pik::sph::iterate_smoothing_length<3>(ps_, pass, h_params_, active_);
      time_.density_group_walks += groups, time_.density_group_slots += all;
      time_.density += pik::wall_time() - t0, time_.cpu_density += cpu_time() - c0;
    }
    {
      const double t0 = pik::wall_time(), c0 = cpu_time();
      for (std::size_t i = 0; i < n; ++i)
        if (active_[i]) eos_one(ps_[i]);
      time_.eos += pik::wall_time() - t0, time_.cpu_eos += cpu_time() - c0;
    }
    double t0 = pik::wall_time(), c0 = cpu_time();
    // The hydro walk writes back to whole groups: the inactive members keep their results.
    saved_.clear();
    for (std::size_t i = 0; i < n; ++i)
      if (!active_[i]) saved_.push_back({ps_[i].acc, ps_[i].dudt, ps_[i].vsig});
    hydro_tree_.buildLike(density_tree_, ps_);
    if (prm_.disph) hydro_tree_.calcForceOnTreeAndWriteBack(disph_, ps_, active_);
    else hydro_tree_.calcForceOnTreeAndWriteBack(ssph_, ps_, active_);
    count_lists();
    {
      std::size_t k = 0;
      for (std::size_t i = 0; i < n; ++i)
        if (!active_[i]) ps_[i].acc = saved_[k].acc, ps_[i].dudt = saved_[k].dudt, ps_[i].vsig = saved_[k].vsig, ++k;
    }
    time_.hydro += pik::wall_time() - t0, time_.cpu_hydro += cpu_time() - c0;
    t0 = pik::wall_time(), c0 = cpu_time();
    gbodies_.clear();
    std::vector<GravEPJ> imports;
    imports.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
      const auto& p = ps_[i];
      if (active_[i]) {
        gbodies_.add(GravBody{p.id, p.mass, p.pos, {}, 0});
      } else {
        GravEPJ e;
        e.copyFromFP(p);
        imports.push_back(e);
      }
    }
    const double ec = prm_.eps / Code::L;
    gravity_tree_.setImportedParticles(std::move(imports));
    gravity_tree_.calcForceAllAndWriteBack(GravityKernel(float(ec * ec)), GravityCellKernel(float(ec * ec)),
                                           gbodies_);
    gravity_tree_.clearImported();
    {
      std::size_t k = 0;
      for (std::size_t i = 0; i < n; ++i)
        if (active_[i]) ps_[i].grav = gbodies_[k].grav, ps_[i].pot = gbodies_[k].pot, ++k;
    }
    time_.gravity += pik::wall_time() - t0, time_.cpu_gravity += cpu_time() - c0;
    for (std::size_t i = 0; i < n; ++i)
      if (active_[i]) finish_one(ps_[i]);
    ++time_.evaluations;
  }

 public:
  /// Kinetic, internal and gravitational energy (J), the softened potential's self term
  /// removed. These three and the momenta are sums over every rank (collective).
  std::array<double, 3> energies() const {
    std::array<double, 3> e{};
    for (const auto& p : ps_) {
      e[0] += 0.5 * p.mass * pik::norm2(p.vel), e[1] += p.mass * p.u;
      e[2] += 0.5 * p.mass * (p.pot + G * p.mass / prm_.eps);
    }
    if (mpi()) pik::sph::global_sum(std::span<double>(e), comm_);
    return e;
  }
  Vec3d angular_momentum() const {
    Vec3d l{};
    for (const auto& p : ps_) l += pik::cross(p.pos, p.vel) * p.mass;
    return global(l);
  }
  Vec3d momentum() const {
    Vec3d m{};
    for (const auto& p : ps_) m += p.vel * p.mass;
    return global(m);
  }

  std::vector<std::string> diagnostic_names() const { return {"E", "K", "U", "W", "Lx", "Ly", "Lz", "Px", "Py", "Pz"}; }
  std::vector<double> diagnostics() const {
    const auto e = energies();
    const Vec3d l = angular_momentum(), m = momentum();
    return {e[0] + e[1] + e[2], e[0], e[1], e[2], l.x, l.y, l.z, m.x, m.y, m.z};
  }

  void fill_snapshot(pik::io::Snapshot& s, bool checkpoint) const {
    const std::size_t n = ps_.size();
    auto col = [&](const char* name, auto get) {
      auto& c = s.column(name, 1);
      for (std::size_t i = 0; i < n; ++i) c.data[i] = get(ps_[i]);
    };
    col("Material", [](const Particle& p) { return double(p.material); });
    col("Body", [](const Particle& p) { return double(p.body); });
    col("InternalEnergy", [](const Particle& p) { return p.u; });
    col("Density", [](const Particle& p) { return p.dens; });
    col("Pressure", [](const Particle& p) { return p.pres; });
    col("SmoothingLength", [](const Particle& p) { return p.h; });
    col("Potential", [](const Particle& p) { return p.pot; });
    if (checkpoint) {
      col("DuDt", [](const Particle& p) { return p.dudt; });
      col("SignalVelocity", [](const Particle& p) { return p.vsig; });
      col("DisphZ", [](const Particle& p) { return p.z; });
      // the h guess of the next step (open_step) reads the last density pass's rho and div v
      col("SphDensity", [](const Particle& p) { return p.rho; });
      col("VelocityDivergence", [](const Particle& p) { return p.divv; });
      auto& a = s.column("Acceleration", 3);
      for (std::size_t i = 0; i < n; ++i)
        a.data[3 * i] = ps_[i].acc.x, a.data[3 * i + 1] = ps_[i].acc.y, a.data[3 * i + 2] = ps_[i].acc.z;
      if (split()) {
        auto& g = s.column("Gravity", 3);
        for (std::size_t i = 0; i < n; ++i)
          g.data[3 * i] = ps_[i].grav.x, g.data[3 * i + 1] = ps_[i].grav.y, g.data[3 * i + 2] = ps_[i].grav.z;
      }
      if (prm_.max_rung > 0) {
        // block steps: a particle inactive at the first fine step lends its neighbours
        // what the EOS pass of its last evaluation gave
        col("ForceFactor", [](const Particle& p) { return p.pf; });
        col("SoundSpeed", [](const Particle& p) { return p.cs; });
        col("Balsara", [](const Particle& p) { return p.balsara; });
        col("DisphY", [](const Particle& p) { return p.y; });
      }
    }
    for (const auto& [k, v] : physics()) s.attr.set(k, v);
    if (checkpoint && mpi()) {
      // the decomposition a restart on as many ranks continues from (not physics: a
      // restart on another rank count starts a new one)
      std::ostringstream st;
      st.precision(17);
      for (double x : dinfo_.state()) st << (st.tellp() > 0 ? "," : "") << x;
      s.attr.set("impact.domain_ranks", std::int64_t(comm_.size()));
      s.attr.set("impact.domain_state", st.str());
    }
  }

  void restore(const pik::io::Snapshot& s) {
    if (s.attr.has("impact.h_max") && !(prm_.h_max > 0))
      throw pik::Error("the checkpoint was written with impact.h_max = " + s.attr.get_string("impact.h_max") +
                       ", this run has no cap (--h-max)");
    // parameters a run adds only when set: a checkpoint with one needs a run with it
    const auto phys = physics();
    for (const char* k : {"impact.max_rung", "impact.gravity_every"})
      if (s.attr.has(k) && std::none_of(phys.begin(), phys.end(), [&](const auto& kv) { return kv.first == k; }))
        throw pik::Error(std::string("the checkpoint was written with ") + k + " = " + s.attr.get_string(k) +
                         ", this run has (none)");
    for (const auto& [k, v] : phys)
      if (!s.attr.has(k) || s.attr.get_string(k) != v)
        throw pik::Error("the checkpoint was written with " + k + " = " +
                         (s.attr.has(k) ? s.attr.get_string(k) : std::string("(none)")) + ", this run has " + v);
    for (const char* c : {"Material", "Body", "InternalEnergy", "SmoothingLength", "DuDt", "SignalVelocity", "DisphZ",
                          "Acceleration", "Density", "Pressure", "Potential"})
      if (!s.find(c)) throw pik::Error(std::string("the checkpoint lacks the column '") + c + "'");
    if (prm_.max_rung > 0)
      for (const char* c : {"ForceFactor", "SoundSpeed", "Balsara", "DisphY"})
        if (!s.find(c)) throw pik::Error(std::string("the checkpoint lacks the block-step column '") + c + "'");
    if (split() && !s.find("Gravity")) throw pik::Error("the checkpoint lacks the column 'Gravity' (--gravity-every)");
    if (mpi() && s.attr.has("impact.domain_ranks") && s.attr.get_int("impact.domain_ranks") == comm_.size() &&
        s.attr.has("impact.domain_state")) {
      std::vector<double> st;
      std::stringstream in(s.attr.get_string("impact.domain_state"));
      for (std::string x; std::getline(in, x, ',');) st.push_back(std::stod(x));
      dinfo_.restore_state(st);
    }
    auto get = [&](const char* c, std::size_t i) { return s.find(c)->data[i]; };
    for (std::size_t i = 0; i < ps_.size(); ++i) {
      auto& p = ps_[i];
      p.material = int(get("Material", i)), p.body = int(get("Body", i)), p.u = get("InternalEnergy", i);
      p.h = get("SmoothingLength", i), p.dudt = get("DuDt", i), p.vsig = get("SignalVelocity", i);
      p.z = get("DisphZ", i), p.dens = get("Density", i), p.pres = get("Pressure", i), p.pot = get("Potential", i);
      const auto& a = s.find("Acceleration")->data;
      p.acc = {a[3 * i], a[3 * i + 1], a[3 * i + 2]};
      if (split()) {
        const auto& g = s.find("Gravity")->data;
        p.grav = {g[3 * i], g[3 * i + 1], g[3 * i + 2]};
      }
      // Checkpoints before the h guess lack these: the first step then starts from the last h.
      if (s.find("SphDensity") && s.find("VelocityDivergence"))
        p.rho = get("SphDensity", i), p.divv = get("VelocityDivergence", i);
      if (prm_.max_rung > 0)
        p.pf = get("ForceFactor", i), p.cs = get("SoundSpeed", i), p.balsara = get("Balsara", i), p.y = get("DisphY", i);
      (void)mats_[p.material];
    }
  }

 private:
  bool mpi() const { return comm_.size() > 1; }
  Vec3d global(Vec3d v) const {
    if (mpi()) pik::sph::global_sum(std::span<double>(&v.x, 3), comm_);
    return v;
  }

  /// Under MPI: every particle to the owner of the last decomposition's domains, new
  /// domains of equal particle count cut from them, every particle to its new owner;
  /// after each move a rank's particles are sorted by id. The first move (skipped before
  /// the first decomposition) makes the particles each rank samples, and so the cuts,
  /// independent of how they were spread before (a restart's equal shares, or the last
  /// step's domains): with the checkpoint's decomposition a restart continues bit for bit.
  void distribute() {
    auto& v = ps_.vector();
    auto by_id = [](const Particle& a, const Particle& b) { return a.id < b.id; };
    if (dinfo_.decompositions() > 0) {
      pik::exchange_particles(v, dinfo_);
      std::sort(v.begin(), v.end(), by_id);
    }
    dinfo_.decompose(v);
    pik::exchange_particles(v, dinfo_);
    std::sort(v.begin(), v.end(), by_id);
  }

  /// Under MPI: the j-particles other ranks hold within the halo's reach of this rank's
  /// particles, as the tree's imported particles (collective).
  template <class Tree, class Halo>
  void import_halo(Tree& tree, Halo& halo) {
    halo.exchange(ps_, comm_, tree.boundary());
    tree.setImportedParticles(std::move(halo.importedParticles()));
  }

  static pik::TreeParams grav_params(const ModelParams& m) {
    pik::TreeParams t{.theta = m.theta, .opening = pik::Opening::centre_of_mass_offset};
    if (m.grav_leaf > 0) t.n_leaf_limit = m.grav_leaf;
    if (m.grav_group > 0) t.n_group_limit = m.grav_group;
    return t;
  }

  /// Pressure entering DISPH's Z (not its force): the EOS pressure, at least 1e-6 A
  /// (Tillotson) or 1e-12 of the unit pressure otherwise, so that Z > 0.
  double disph_pressure(const pik::eos::Material& m, double rho, double u) const {
    double floor = 1e-12 * Code::P();
    if (const auto* t = dynamic_cast<const pik::eos::Tillotson*>(&m)) floor = 1e-6 * t->params().A;
    return std::max(m.pressure(rho, u), floor);
  }

  /// Parameters a restart must not change, as exact text.
  std::vector<std::pair<std::string, std::string>> physics() const {
    auto x = [](double v) {
      char b[32];
      std::snprintf(b, sizeof b, "%.17g", v);
      return std::string(b);
    };
    std::string mats;
    for (const auto& m : prm_.materials) mats += (mats.empty() ? "" : ",") + m;
    std::vector<std::pair<std::string, std::string>> v = {{"impact.scheme", prm_.disph ? "disph" : "ssph"},
            {"impact.disph_exponent", x(prm_.disph_exponent)},
            {"impact.nngb", x(prm_.nngb)},
            {"impact.alpha", x(prm_.alpha)},
            {"impact.balsara", prm_.balsara ? "true" : "false"},
            {"impact.cfl", x(prm_.cfl)},
            {"impact.theta", x(prm_.theta)},
            {"impact.gravity_cells", "quadrupole, offset criterion"},  // (monopole, box before 2026-12-05)
            {"impact.eps", x(prm_.eps)},
            {"impact.damping", x(prm_.damping)},
            {"impact.materials", mats}};
    // block time steps (absent in global-step checkpoints, which stay as they were)
    if (prm_.max_rung > 0) v.push_back({"impact.max_rung", std::to_string(prm_.max_rung)});
    // split gravity: the checkpoint's Acceleration is the SPH part alone, Gravity beside it
    if (split()) v.push_back({"impact.gravity_every", std::to_string(prm_.gravity_every)});
    // the h cap (absent without one: checkpoints of uncapped runs stay as they were)
    if (prm_.h_max > 0) v.push_back({"impact.h_max", x(prm_.h_max)});
    return v;
  }

  ModelParams prm_;
  pik::Comm comm_;
  pik::DomainInfo<double, 3> dinfo_;
  std::size_t n_total_ = 0;
  pik::ParticleSystem<Particle> ps_;
  const pik::eos::MaterialTable& mats_;
  DensityTree density_tree_;
  HydroTree hydro_tree_;
  GravTree gravity_tree_;
  // under MPI: the halos of the two short-range passes and the distributed gravity tree
  pik::ShortRangeHalo<ImpactEP, ImpactEP, pik::SearchMode::gather> density_halo_;
  pik::ShortRangeHalo<ImpactEP, ImpactEP, pik::SearchMode::symmetric> hydro_halo_;
  /// gravity under MPI (one process: gravity_tree_)
  std::optional<pik::DistributedLongRangeTree<GravityResult, GravEPI, GravEPJ, GravSPJ>> dgravity_;
  typename K::Density density_;
  typename K::Ssph ssph_;
  typename K::Disph disph_;
  pik::sph::SmoothingLengthParams h_params_;
  Timings time_;
  bool skip_gravity_ = false;  ///< split gravity: an SPH step inside a gravity step
  double predict_kick_ = 0;    ///< split gravity: the closing kick's length in the predicted velocity (open_step)
  mutable std::vector<double> step_buf_;  ///< step_minima: each particle's steps
  // block time steps
  struct HydroSaved {
    Vec3d acc;
    double dudt, vsig;
  };
  std::vector<std::uint8_t> active_, raised_;
  std::vector<HydroSaved> saved_;
  pik::ParticleSystem<GravBody> gbodies_;
};

}  // namespace impact
