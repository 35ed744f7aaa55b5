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
///   4. self-gravity by the Barnes-Hut tree (kernels/gravity.pik, monopole, opening angle
///      theta), Plummer softening eps;
///   5. relaxation only: damping a -= v / tau, du/dt = 0.
/// DISPH needs P > 0 in Z: the pressure in Z and in the force is max(P, p_min_disph),
/// p_min_disph = 1e-6 A of the material (a few kPa to 0.1 MPa).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <pik/eos/Eos.hpp>
#include <pik/eos/Tillotson.hpp>
#include <pik/io/Snapshot.hpp>
#include <pik/pik.hpp>
#include <pik/sph/Leapfrog.hpp>
#include <pik/sph/SmoothingLength.hpp>
#include <pik/sph/TimeStep.hpp>

#include "Particles.hpp"

namespace impact {

struct ModelParams {
  bool disph = true;
  double disph_exponent = 0.1;  ///< a of Z = m P^a / rho
  double nngb = 50;
  double h_tol = 1e-2;
  double alpha = 1.0;           ///< artificial viscosity
  bool balsara = true;
  double cfl = 0.3;
  double theta = 0.5;           ///< gravity tree opening angle
  double eps = 0;               ///< gravitational softening (m)
  double damping = 0;           ///< relaxation: damping time tau (s); 0: none
  bool fixed_u = false;         ///< relaxation: keep u
  int sph_leaf = 8, sph_group = 32;  ///< short-range trees: leaf and i-group sizes
  int grav_leaf = 0, grav_group = 0;  ///< gravity tree: leaf and i-group sizes (0: the runtime's defaults)
  bool reuse_tree = true;       ///< one short-range tree build per evaluation (false: one per pass)
  bool predict_h = true;        ///< drift h with dh/dt = (h/3) div v before the h iteration
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
};

/// K: the kernel classes (Density, Ssph, Disph) for one smoothing function.
template <class K, class GravityKernel, class GravityMonopoleKernel>
class Model {
  using DensityTree = pik::ShortRangeTree<DensityResult, ImpactEP, ImpactEP, pik::SearchMode::gather>;
  using HydroTree = pik::ShortRangeTree<HydroResult, ImpactEP, ImpactEP, pik::SearchMode::symmetric>;
  using GravTree = pik::LongRangeTree<GravityResult, GravEPI, GravEPJ, GravSPJ>;

 public:
  Model(ModelParams prm, std::vector<Particle> p, const pik::eos::MaterialTable& mats)
      : prm_(std::move(prm)), ps_(std::move(p)), mats_(mats),
        density_tree_({.n_leaf_limit = prm_.sph_leaf, .n_group_limit = prm_.sph_group}, pik::Boundary<3>::open()),
        hydro_tree_({.n_leaf_limit = prm_.sph_leaf, .n_group_limit = prm_.sph_group}, pik::Boundary<3>::open()),
        gravity_tree_(grav_params(prm_)), density_(), ssph_(float(prm_.alpha)),
        disph_(float(prm_.alpha)) {
    if (!(prm_.eps > 0)) throw pik::Error("the gravitational softening must be positive");
    for (const auto& q : ps_) (void)mats_[q.material];  // every material id is defined
    h_params_ = {.nngb = prm_.nngb, .tol = prm_.h_tol, .max_passes = 50, .fixed_h = 0};
  }

  pik::ParticleSystem<Particle>& particles() { return ps_; }
  const pik::ParticleSystem<Particle>& particles() const { return ps_; }
  const ModelParams& params() const { return prm_; }
  const Timings& timings() const { return time_; }
  /// Tree-build seconds of the three trees (part of the density, hydro and gravity times).
  double tree_build_seconds() {
    return density_tree_.profile().seconds("tree build") + hydro_tree_.profile().seconds("tree build") +
           gravity_tree_.profile().seconds("tree build");
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
  pik::Profiler& gravity_profile() { return gravity_tree_.profile(); }

  void compute() {
    density();
    if (prm_.disph && std::any_of(ps_.begin(), ps_.end(), [](const Particle& p) { return !(p.z > 0); })) {
      // First evaluation: Z from the density the particle was set up with (dens, e.g. the
      // hydrostatic profile's), or else the mass density; then y from those Z (h is converged).
      for (auto& p : ps_) {
        const double d = p.dens > 0 ? p.dens : p.rho;
        p.z = (p.mass / Code::M) * std::pow(disph_pressure(mats_[p.material], d, p.u) / Code::P(),
                                            prm_.disph_exponent) / (d / Code::Rho());
      }
      const double t0 = pik::wall_time(), c0 = cpu_time();
      density_tree_.refresh(ps_);  // new Z, same positions and h: the tree of this step
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
      if (!prm_.reuse_tree) {
        density_tree_.calcForceAllAndWriteBack(density_, ps_);
        return;
      }
      if (first) density_tree_.build(ps_);
      else density_tree_.refresh(ps_);
      density_tree_.calcForceOnTreeAndWriteBack(density_, ps_, first ? std::span<const std::uint8_t>{} : active);
      groups += long(density_tree_.groupsWalked()), all += long(density_tree_.groups().size());
      first = false;
    };
    time_.density_passes += pik::sph::iterate_smoothing_length<3>(ps_, pass, h_params_);
    time_.density_group_walks += groups, time_.density_group_slots += all;
    time_.density += pik::wall_time() - t0, time_.cpu_density += cpu_time() - c0;
  }

  /// EOS, the kernels' per-particle factors, the Balsara switch.
  void eos() {
    const double t0 = pik::wall_time(), c0 = cpu_time();
    const double Pu = Code::P(), Ru = Code::Rho();
    for (auto& p : ps_) {
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
        const double pc = disph_pressure(mat, p.dens, p.u) / Pu;
        p.pf = pc / (p.y * p.y);
      } else {
        // grad-h factor f = (1 + h/(3 rho) drho/dh)^-1 (Springel & Hernquist 2002, eq. 8)
        const double om = 1 + p.h / (3 * p.rho) * p.drhodh;
        p.fgrad = om > 0.2 ? 1.0 / om : 1.0;
        const double rc = p.dens / Ru;
        p.pf = p.fgrad * (p.pres / Pu) / (rc * rc);
      }
      const double div = std::abs(p.divv) / p.rho, curl = p.curl / p.rho;
      p.balsara = prm_.balsara ? div / (div + curl + 1e-4 * p.cs / p.h) : 1.0;
    }
    time_.eos += pik::wall_time() - t0, time_.cpu_eos += cpu_time() - c0;
  }

  void forces() {
    double t0 = pik::wall_time(), c0 = cpu_time();
    if (prm_.reuse_tree) {
      // Same positions as the density passes: the density tree's octree, no new sort.
      hydro_tree_.buildLike(density_tree_, ps_);
      if (prm_.disph) hydro_tree_.calcForceOnTreeAndWriteBack(disph_, ps_);
      else hydro_tree_.calcForceOnTreeAndWriteBack(ssph_, ps_);
    } else if (prm_.disph) {
      hydro_tree_.calcForceAllAndWriteBack(disph_, ps_);
    } else {
      hydro_tree_.calcForceAllAndWriteBack(ssph_, ps_);
    }
    time_.hydro += pik::wall_time() - t0, time_.cpu_hydro += cpu_time() - c0;
    t0 = pik::wall_time(), c0 = cpu_time();
    const double ec = prm_.eps / Code::L;
    gravity_tree_.calcForceAllAndWriteBack(GravityKernel(float(ec * ec)), GravityMonopoleKernel(float(ec * ec)), ps_);
    time_.gravity += pik::wall_time() - t0, time_.cpu_gravity += cpu_time() - c0;
    for (auto& p : ps_) {
      p.acc += p.grav;
      if (prm_.damping > 0) p.acc -= p.vel * (1 / prm_.damping);
      if (prm_.fixed_u) p.dudt = 0;
      // DISPH: Z for the next evaluation, from this one's pressure and density
      if (prm_.disph)
        p.z = (p.mass / Code::M) *
              std::pow(disph_pressure(mats_[p.material], p.dens, p.u) / Code::P(), prm_.disph_exponent) /
              (p.dens / Code::Rho());
    }
  }

  /// The leapfrog's opening half (pik/sph/Leapfrog.hpp), with u_half and the predicted u
  /// kept non-negative: a particle expanding to P = 0 may cool to u = 0 but not below
  /// (the EOS refuses u < 0).
  void open_step(Particle& p, double dt) const {
    pik::sph::open_step(p, dt);
    p.u_half = std::max(p.u_half, 0.0), p.u = std::max(p.u, 0.0);
    // The first guess of the h iteration: h ∝ rho^(-1/3) and drho/dt = -rho div v, so
    // dh/dt = (h/3) div v, div v = -divv / rho (kernels/sph_density.pik); at most 10 % a step.
    if (prm_.predict_h && p.rho > 0)
      p.h *= std::clamp(std::exp(-p.divv / (3 * p.rho) * dt), 1 / 1.1, 1.1);
  }

  pik::sph::StepLimits limits() const {
    pik::sph::StepLimits lim;
    for (const auto& p : ps_) {
      lim.add("courant", pik::sph::courant(p.h, p.vsig, prm_.cfl));
      lim.add("acceleration", pik::sph::acceleration(std::min(p.h, prm_.eps), pik::norm(p.acc), 0.3));
    }
    return lim;
  }

  /// Kinetic, internal and gravitational energy (J), the softened potential's self term removed.
  std::array<double, 3> energies() const {
    double k = 0, th = 0, w = 0;
    for (const auto& p : ps_) {
      k += 0.5 * p.mass * pik::norm2(p.vel), th += p.mass * p.u;
      w += 0.5 * p.mass * (p.pot + G * p.mass / prm_.eps);
    }
    return {k, th, w};
  }
  Vec3d angular_momentum() const {
    Vec3d l{};
    for (const auto& p : ps_) l += pik::cross(p.pos, p.vel) * p.mass;
    return l;
  }
  Vec3d momentum() const {
    Vec3d m{};
    for (const auto& p : ps_) m += p.vel * p.mass;
    return m;
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
    }
    for (const auto& [k, v] : physics()) s.attr.set(k, v);
  }

  void restore(const pik::io::Snapshot& s) {
    for (const auto& [k, v] : physics())
      if (!s.attr.has(k) || s.attr.get_string(k) != v)
        throw pik::Error("the checkpoint was written with " + k + " = " +
                         (s.attr.has(k) ? s.attr.get_string(k) : std::string("(none)")) + ", this run has " + v);
    for (const char* c : {"Material", "Body", "InternalEnergy", "SmoothingLength", "DuDt", "SignalVelocity", "DisphZ",
                          "Acceleration", "Density", "Pressure", "Potential"})
      if (!s.find(c)) throw pik::Error(std::string("the checkpoint lacks the column '") + c + "'");
    auto get = [&](const char* c, std::size_t i) { return s.find(c)->data[i]; };
    for (std::size_t i = 0; i < ps_.size(); ++i) {
      auto& p = ps_[i];
      p.material = int(get("Material", i)), p.body = int(get("Body", i)), p.u = get("InternalEnergy", i);
      p.h = get("SmoothingLength", i), p.dudt = get("DuDt", i), p.vsig = get("SignalVelocity", i);
      p.z = get("DisphZ", i), p.dens = get("Density", i), p.pres = get("Pressure", i), p.pot = get("Potential", i);
      const auto& a = s.find("Acceleration")->data;
      p.acc = {a[3 * i], a[3 * i + 1], a[3 * i + 2]};
      // Checkpoints before the h guess lack these: the first step then starts from the last h.
      if (s.find("SphDensity") && s.find("VelocityDivergence"))
        p.rho = get("SphDensity", i), p.divv = get("VelocityDivergence", i);
      (void)mats_[p.material];
    }
  }

 private:
  static pik::TreeParams grav_params(const ModelParams& m) {
    pik::TreeParams t{.theta = m.theta};
    if (m.grav_leaf > 0) t.n_leaf_limit = m.grav_leaf;
    if (m.grav_group > 0) t.n_group_limit = m.grav_group;
    return t;
  }

  /// Pressure entering DISPH's Z and force: the EOS pressure, at least 1e-6 A (Tillotson)
  /// or 1e-12 of the unit pressure otherwise, so that Z > 0.
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
    return {{"impact.scheme", prm_.disph ? "disph" : "ssph"},
            {"impact.disph_exponent", x(prm_.disph_exponent)},
            {"impact.nngb", x(prm_.nngb)},
            {"impact.alpha", x(prm_.alpha)},
            {"impact.balsara", prm_.balsara ? "true" : "false"},
            {"impact.cfl", x(prm_.cfl)},
            {"impact.theta", x(prm_.theta)},
            {"impact.eps", x(prm_.eps)},
            {"impact.damping", x(prm_.damping)},
            {"impact.materials", mats}};
  }

  ModelParams prm_;
  pik::ParticleSystem<Particle> ps_;
  const pik::eos::MaterialTable& mats_;
  DensityTree density_tree_;
  HydroTree hydro_tree_;
  GravTree gravity_tree_;
  typename K::Density density_;
  typename K::Ssph ssph_;
  typename K::Disph disph_;
  pik::sph::SmoothingLengthParams h_params_;
  Timings time_;
};

}  // namespace impact
