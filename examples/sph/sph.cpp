// sph: smoothed particle hydrodynamics on pik: standard (SSPH), density-independent
// (DISPH, Saitoh & Makino 2013) or with a smoothed pseudo-density (SPSPH, Yamamoto,
// Saitoh & Makino 2015), with the classic tests: Sod shock tube (3D), Kelvin-Helmholtz
// instability (2D, smoothed) and Evrard collapse (3D, self-gravity), and the contact-
// discontinuity problems that tell the schemes apart (Problems.hpp): hydrostatic strip
// and square at density contrasts 4 to 100, the sharp-interface Kelvin-Helmholtz
// instability and a stratified layer with a free surface under gravity.
//
// The pairwise work is done by generated kernels: kernels/sph_density.pik (gather,
// smoothing-length iteration), kernels/sph_force_ssph.pik / sph_force_disph.pik /
// sph_force_spsph.pik (symmetric, artificial viscosity, Balsara switch, signal
// velocity; SPSPH's also the pseudo-density rates) and kernels/gravity.pik
// (Barnes-Hut). The equations are in docs/sph.md. Run `sph --help`.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <span>
#include <sstream>
#include <string>
#include <vector>

#include <pik/eos/Eos.hpp>
#include <pik/io/CommandLine.hpp>
#include <pik/pik.hpp>
#include <pik/sph/Driver.hpp>
#include <pik/sph/Smoothing.hpp>
#include <pik/sph/SmoothingLength.hpp>

#include "Problems.hpp"
#include "Riemann.hpp"
#include "SphTypes.hpp"

// Generated kernels: one class per (dimension, smoothing function), see CMakeLists.txt.
#include "SphDensity2_0.hpp"
#include "SphDensity2_1.hpp"
#include "SphDensity2_2.hpp"
#include "SphDensity3_0.hpp"
#include "SphDensity3_1.hpp"
#include "SphDensity3_2.hpp"
#include "SphForceSsph2_0.hpp"
#include "SphForceSsph2_1.hpp"
#include "SphForceSsph2_2.hpp"
#include "SphForceSsph3_0.hpp"
#include "SphForceSsph3_1.hpp"
#include "SphForceSsph3_2.hpp"
#include "SphForceDisph2_0.hpp"
#include "SphForceDisph2_1.hpp"
#include "SphForceDisph2_2.hpp"
#include "SphForceDisph3_0.hpp"
#include "SphForceDisph3_1.hpp"
#include "SphForceDisph3_2.hpp"
#include "SphForceSpsph2_0.hpp"
#include "SphForceSpsph2_1.hpp"
#include "SphForceSpsph2_2.hpp"
#include "SphForceSpsph3_0.hpp"
#include "SphForceSpsph3_1.hpp"
#include "SphForceSpsph3_2.hpp"
#include "Gravity.hpp"
#include "GravityMonopole.hpp"

template <int D, int S>
struct Kernels;
#define SPH_KERNELS(D, S)                     \
  template <>                                 \
  struct Kernels<D, S> {                      \
    using Density = SphDensity##D##_##S;      \
    using Ssph = SphForceSsph##D##_##S;       \
    using Disph = SphForceDisph##D##_##S;     \
    using Spsph = SphForceSpsph##D##_##S;     \
  };
SPH_KERNELS(2, 0)
SPH_KERNELS(2, 1)
SPH_KERNELS(2, 2)
SPH_KERNELS(3, 0)
SPH_KERNELS(3, 1)
SPH_KERNELS(3, 2)
#undef SPH_KERNELS

// ---- configuration --------------------------------------------------------------------
struct Config {
  std::string problem, scheme, out;
  int shape = 0, n = 0, dim = 3;
  double gamma = 1.4, t_end = 0, cfl = 0.3, alpha = 1, nngb = 0, eps = 0, theta = 0.5;
  double h_tol = 1e-2, fixed_h = 0;
  double lists = 0;  // kept candidate lists: margin (< 0: a tree build and walk per pass)
  bool balsara = true, gravity = false;
  pik::sph::RunParams run;  // end time, outputs, checkpoints, restart (the shared driver's)
  // SPSPH: initial pseudo-density ("one": y = 1, "density": y = rho) and its diffusion
  std::string y_init = "one";
  double alpha_y = 0.1;
  std::string h_from = "n";  // h from the number density (n), the mass density (rho) or DISPH's volume m u / q (q)
  bool gradh = true;  // DISPH: grad-h terms (--no-gradh: without, the formulation before)
  int y_smooth = 16;  // y-init density: passes of volume-weighted kernel averaging of the initial y = rho
  double seed = 0.1;  // khsharp: amplitude of the seeded v_y mode
  double contrast = 4, scale = 1;  // contact/square/khsharp/layer: density contrast; layer: surface scale height
  bool disph() const { return scheme == "disph"; }
  bool ssph() const { return scheme == "ssph"; }
  bool spsph() const { return scheme == "spsph"; }
};

using pik::sph::shape_names;

// ---- initial conditions -----------------------------------------------------------------
template <int D>
struct Setup {
  std::vector<Particle<D>> p;
  pik::Boundary<D> boundary = pik::Boundary<D>::open();
  double gravity_y = 0;  // uniform external acceleration along y (the layer)
};

/// A 2D problem of Problems.hpp as the program's particles.
Setup<2> from_problem(const sph::problems::Setup& ps) {
  Setup<2> s;
  for (const auto& q : ps.p) {
    Particle<2> p;
    p.pos = q.pos, p.vel = q.vel, p.mass = q.mass, p.u = q.u, p.rho0 = q.rho, p.h = q.h, p.tag = q.tag;
    s.p.push_back(p);
  }
  const bool periodic[2] = {true, ps.periodic_y};
  s.boundary = pik::Boundary<2>::periodic_box({0, ps.lo_y}, {1, ps.hi_y}, periodic);
  s.gravity_y = ps.gravity_y;
  return s;
}

/// Sod (1978) shock tube along x, as two mirrored Riemann problems in a box periodic
/// in every dimension: x in [-0.5, 0.5) left state (rho 1, P 1), [0.5, 1.5) right state
/// (rho 0.125, P 0.1), both at rest; equal-mass particles on cubic lattices of spacing
/// 1/n (left) and 2/n (right), cross-section (ny/n)^2. The interface at x = 0.5 is
/// measured; the one at x = 1.5 = -0.5 stays out of [0, 1] until t = 0.2.
Setup<3> sod(int n, int ny, double len_left, double len_right, double gamma) {
  Setup<3> s;
  const double d = 1.0 / n, side = ny * d, xl = 0.5 - len_left, xr = 0.5 + len_right;
  const double m = d * d * d;
  auto add = [&](double x0, double x1, double dx, double rho, double p, int tag) {
    const int nx = int(std::lround((x1 - x0) / dx)), nyz = int(std::lround(side / dx));
    for (int i = 0; i < nx; ++i)
      for (int j = 0; j < nyz; ++j)
        for (int k = 0; k < nyz; ++k) {
          Particle<3> q;
          q.pos = {x0 + (i + 0.5) * dx, (j + 0.5) * dx, (k + 0.5) * dx};
          q.mass = m, q.u = p / ((gamma - 1) * rho), q.h = 2.5 * dx, q.tag = tag, q.rho0 = rho;
          s.p.push_back(q);
        }
  };
  add(xl, 0.5, d, 1.0, 1.0, 0);
  add(0.5, xr, 2 * d, 0.125, 0.1, 1);
  s.boundary = pik::Boundary<3>::periodic_box({xl, 0, 0}, {xr, side, side});
  return s;
}

/// Smoothed Kelvin-Helmholtz profile of McNally, Lyra & Passy (2012), eqs. 1-4:
/// density 1 outside, 2 in the middle layer, velocities +-0.5, L = 0.025.
struct KhProfile {
  double rho1 = 1, rho2 = 2, u1 = 0.5, u2 = -0.5, L = 0.025;
  double ramp(double y, double a1, double a2) const {
    const double am = 0.5 * (a1 - a2);
    if (y < 0.25) return a1 - am * std::exp((y - 0.25) / L);
    if (y < 0.5) return a2 + am * std::exp((0.25 - y) / L);
    if (y < 0.75) return a2 + am * std::exp((y - 0.75) / L);
    return a1 - am * std::exp((0.75 - y) / L);
  }
  double rho(double y) const { return ramp(y, rho1, rho2); }
  double vx(double y) const { return ramp(y, u1, u2); }
};

/// Equal-mass rows: a row at height y has round(n sqrt(rho(y))) particles and the next
/// row follows at the spacing that gives density rho(y); alternate rows are shifted
/// by half a spacing. Pressure 2.5, v_y = 0.01 sin(4 pi x) (McNally et al. 2012).
Setup<2> kh(int n, double gamma) {
  Setup<2> s;
  const KhProfile k;
  const double m0 = 1.0 / (double(n) * n);
  std::vector<std::pair<double, int>> rows;
  double y = 0;
  while (y < 1) {
    const int nx = std::max(1, int(std::lround(n * std::sqrt(k.rho(y)))));
    rows.push_back({y, nx});
    y += nx * m0 / k.rho(y);
  }
  const double stretch = 1.0 / y;  // close the periodic box exactly
  std::size_t total = 0;
  for (auto& r : rows) total += std::size_t(r.second);
  const double mass = 1.5 / double(total);  // integral of rho over the box
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const double yr = rows[r].first * stretch;
    const int nx = rows[r].second;
    for (int i = 0; i < nx; ++i) {
      Particle<2> q;
      const double x = (i + (r % 2 ? 0.5 : 0.25)) / nx;
      q.pos = {x, yr, 0}, q.mass = mass;
      q.vel = {k.vx(yr), 0.01 * std::sin(4 * M_PI * x), 0};
      q.u = 2.5 / ((gamma - 1) * k.rho(yr)), q.h = 2.5 / (n * std::sqrt(k.rho(yr)));
      q.tag = std::abs(yr - 0.5) < 0.25, q.rho0 = k.rho(yr);
      s.p.push_back(q);
    }
  }
  s.boundary = pik::Boundary<2>::periodic_box({0, 0}, {1, 1});
  return s;
}

/// Evrard (1988) collapse: M = R = G = 1, rho = 1 / (2 pi r), u = 0.05, at rest.
/// A cubic lattice cut to the unit sphere, stretched radially (r -> r^(3/2)) so the
/// enclosed mass grows as r^2.
Setup<3> evrard(int n) {
  Setup<3> s;
  const double d = 2.0 / n;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        Vec3d x{-1 + (i + 0.5) * d, -1 + (j + 0.5) * d, -1 + (k + 0.5) * d};
        const double r = pik::norm(x);
        if (r >= 1) continue;
        Particle<3> q;
        q.pos = x * std::sqrt(r), q.u = 0.05;
        s.p.push_back(q);
      }
  for (auto& q : s.p) {
    q.mass = 1.0 / double(s.p.size());
    q.h = 0.1 * std::sqrt(std::max(pik::norm(q.pos), 0.05));
  }
  return s;
}

// ---- measurements -----------------------------------------------------------------------
// Sharp-interface KH: the growth rate is fitted to ln M from t = 0.1 (after the part of
// the seed that is no eigenmode has decayed, M ~ M(0) / 2) until M first reaches
// 2.5 M(0) (the linear phase, before the seeded mode saturates near 3.5 M(0)).
constexpr double kh_fit_from = 0.1, kh_fit_cap = 2.5, kh_window_end = 0.5;
constexpr double sod_t_end = 0.2;
const sph::GasState sod_left{1.0, 0.0, 1.0}, sod_right{0.125, 0.0, 0.1};

/// L1 errors (mean over particles with 0 <= x <= 1) of density, pressure and x-velocity
/// against the exact solution of the Riemann problem at x = 0.5.
std::array<double, 3> sod_l1(const pik::ParticleSystem<Particle<3>>& ps, double t, double gamma) {
  const sph::ExactRiemann ex(sod_left, sod_right, gamma);
  double e[3] = {0, 0, 0};
  long n = 0;
  for (const auto& p : ps) {
    if (p.pos.x < 0 || p.pos.x > 1) continue;
    const auto s = ex.sample((p.pos.x - 0.5) / t);
    e[0] += std::abs(p.rho - s.rho), e[1] += std::abs(p.pres - s.p), e[2] += std::abs(p.vel.x - s.u);
    ++n;
  }
  return {e[0] / double(n), e[1] / double(n), e[2] / double(n)};
}

// ---- the simulation ---------------------------------------------------------------------
/// The SPH model the shared driver (pik/sph/Driver.hpp) runs: the passes of one force
/// evaluation, the time-step criteria, diagnostics and the checkpoint contents.
template <int D, int S>
class Simulation {
  using K = Kernels<D, S>;
  using EP = SphEP<D>;
  using DensityTree = pik::ShortRangeTree<DensityGradhResult, EP, EP, pik::SearchMode::gather>;
  using HydroTree = pik::ShortRangeTree<HydroResult, EP, EP, pik::SearchMode::symmetric>;

 public:
  Simulation(const Config& c, Setup<D> s)
      : c_(c), gravity_y_(s.gravity_y), ps_(std::move(s.p)), density_tree_({.n_leaf_limit = 8, .n_group_limit = 32}, s.boundary),
        hydro_tree_({.n_leaf_limit = 8, .n_group_limit = 32}, s.boundary), boundary_(s.boundary), eos_(c.gamma),
        density_(), ssph_(float(c.alpha)), disph_(float(c.alpha), float(c.gamma)),
        spsph_(float(c.alpha), float(c.alpha_y)) {
    for (std::size_t i = 0; i < ps_.size(); ++i) ps_[i].id = std::uint32_t(i);
    if (boundary_.any_periodic()) ps_.wrapPositions(boundary_);
    h_params_ = {.nngb = c.nngb, .tol = c.h_tol, .max_passes = 50, .fixed_h = c.fixed_h};
    if (c.lists >= 0) density_tree_.keepCandidates(c.lists), hydro_tree_.keepCandidates(c.lists);
  }

  pik::ParticleSystem<Particle<D>>& particles() { return ps_; }
  const pik::ParticleSystem<Particle<D>>& particles() const { return ps_; }

  /// Every pass of one force evaluation, in order.
  void compute() {
    if (boundary_.any_periodic()) ps_.wrapPositions(boundary_);
    density();
    forces();
  }

  /// Density with the smoothing-length iteration (pik/sph/SmoothingLength.hpp), then the
  /// EOS, the grad-h factor and the Balsara switch. SPSPH takes its pressure from its own
  /// density rho_t (integrated in time, not summed) and starts it, at the first call,
  /// from the initial condition's density (the SPH estimate where it gives none), with
  /// the pseudo-density y = 1 or y = rho (--y-init).
  void density() {
    const double t0 = pik::wall_time();
    bool first = false;
    // DISPH with --h-from n or q: h_i^D n_i = const with the number density n = sum W, or
    // h_i^D q_i / (m_i u_i) = const (h from its own volume element m u / q); the iteration
    // then sees m n or q / u as its density, the mass density is kept aside
    const bool hq = c_.disph() && c_.h_from == "q", hn = !c_.ssph() && c_.h_from == "n";
    // After a pass: the iterated density of each particle the pass recomputed. A masked
    // pass leaves the others as they were (already turned into m n or q / u); they are
    // known by the number density, set to -1 before the pass (a recomputed one is > 0,
    // the particle's own W(0) at least) and restored after it.
    auto iterand = [&](bool masked) {
      if (!(hq || hn)) return;
      for (std::size_t i = 0; i < ps_.size(); ++i) {
        auto& p = ps_[i];
        if (masked && p.nd < 0) {
          p.nd = nd_before_[i];
          continue;
        }
        p.rho_m = p.rho, p.drho_m = p.drhodh;
        const double u = std::max(p.u, 1e-10);
        if (hq) p.rho = p.q / u, p.drhodh = p.dqdh / u;
        else p.rho = p.mass * p.nd, p.drhodh = p.mass * p.dnddh;
      }
    };
    if (c_.lists >= 0) {
      // One tree build per evaluation, refreshed with the new h between passes, and each
      // group's candidates collected once (kept lists, shared with the hydro pass). A pass
      // recomputes only the groups of the particles whose h changed.
      bool first_pass = true;
      density_passes_ += pik::sph::iterate_smoothing_length<D>(
          ps_,
          [&](std::span<const std::uint8_t> active) {
            if (first_pass) density_tree_.build(ps_);
            else density_tree_.refresh(ps_);
            const bool masked = !first_pass && (hq || hn);
            if (masked) {
              nd_before_.resize(ps_.size());
              for (std::size_t i = 0; i < ps_.size(); ++i) nd_before_[i] = ps_[i].nd, ps_[i].nd = -1;
            }
            density_tree_.calcForceOnTreeAndWriteBack(density_, ps_, first_pass ? std::span<const std::uint8_t>{} : active);
            first_pass = false;
            iterand(masked);
          },
          h_params_);
    } else {
      density_passes_ += pik::sph::iterate_smoothing_length<D>(
          ps_,
          [&] {
            density_tree_.calcForceAllAndWriteBack(density_, ps_);
            iterand(false);
          },
          h_params_);
    }
    for (auto& p : ps_) {
      if (hq || hn) p.rho = p.rho_m, p.drhodh = p.drho_m;
      p.u = std::max(p.u, 1e-10);
      if (c_.spsph() && !(p.rho_t > 0)) {
        // y = 1 or y = rho (the exact density, discontinuous at a contact; smoothed below);
        // the pseudo-mass Z = m y / rho_t then keeps the volume m / rho_t
        p.rho_t = p.rho0 > 0 ? p.rho0 : p.rho;
        p.y = c_.y_init == "one" ? 1.0 : p.rho_t;
        first = true;
      }
      p.rho_ep = c_.spsph() ? p.rho_t : p.rho;
      const auto st = eos_.state(p.rho_ep, p.u);
      p.pres = c_.disph() ? (c_.gamma - 1) * p.q : st.pressure;
      p.cs = st.sound_speed;
      // grad-h factor f = (1 + h/(D rho) drho/dh)^-1 (Springel & Hernquist 2002, eq. 8)
      const double om = 1 + p.h / (D * p.rho) * p.drhodh;
      p.fgrad = c_.fixed_h > 0 || c_.disph() || !(om > 0.2) ? 1.0 : 1.0 / om;
      // DISPH's grad-h term (h set by rho, volume by q; Hopkins 2013, eq. 10): C = h/(D rho) dq/dh / om
      // (--h-from q: f_ij = f_i = (1 + h/(D q) dq/dh)^-1 instead, SSPH's factor with q for rho)
      p.gh = 0, p.fq = 1, p.xt = hn ? 1.0 : p.mass;
      if (c_.disph() && c_.gradh && c_.fixed_h <= 0) {
        const double omq = 1 + p.h / (D * p.q) * p.dqdh, omn = 1 + p.h / (D * p.nd) * p.dnddh;
        if (hq && omq > 0.2) p.fq = 1 / omq;
        if (hn && omn > 0.2) p.gh = p.h / (D * p.nd) * p.dqdh / omn;
        if (!hq && !hn && om > 0.2) p.gh = p.h / (D * p.rho) * p.dqdh / om;
      }
      // Balsara (1995) switch with |div v| and |curl v| from the density pass
      const double div = std::abs(p.divv) / p.rho, curl = p.curl / p.rho;
      p.balsara = c_.balsara ? div / (div + curl + 1e-4 * p.cs / p.h) : 1.0;
      p.pf = c_.spsph() ? p.pres / (p.y * p.y) : p.fgrad * p.pres / (p.rho * p.rho);
    }
    if (first && c_.y_init == "density" && c_.y_smooth > 0) {
      smooth_pseudo_density(c_.y_smooth);
      for (auto& p : ps_) p.pf = p.pres / (p.y * p.y);
    }
    density_seconds_ += pik::wall_time() - t0;
  }

  /// The start of `--y-init density`: y = rho jumps by the full contrast at a contact,
  /// which SPSPH's force (a pair weighted by y_j / y_i) cannot take; `passes` volume-
  /// weighted kernel averages y_i <- sum_j dV_j y_j W_ij / sum_j dV_j W_ij (particles,
  /// h, rho and P fixed; the steady limit of the pseudo-density diffusion on the kernel
  /// scale) spread the jump over a few kernel radii (width ~ sqrt(passes)) before the first step.
  void smooth_pseudo_density(int passes) {
    pik::ParticleSystem<Particle<D>> tmp = ps_;
    for (int k = 0; k < passes; ++k) {
      for (std::size_t i = 0; i < ps_.size(); ++i) tmp[i].mass = ps_[i].mass / ps_[i].rho_t, tmp[i].u = ps_[i].y;
      density_tree_.calcForceAllAndWriteBack(density_, tmp);
      for (std::size_t i = 0; i < ps_.size(); ++i) ps_[i].y = tmp[i].q / tmp[i].rho;
    }
  }

  void forces() {
    const double t0 = pik::wall_time();
    auto pass = [&](auto& kernel) {
      if (c_.lists >= 0) {
        // the density pass's octree and candidate lists (same positions)
        hydro_tree_.buildLike(density_tree_, ps_);
        hydro_tree_.calcForceOnTreeAndWriteBack(kernel, ps_);
      } else {
        hydro_tree_.calcForceAllAndWriteBack(kernel, ps_);
      }
    };
    if (c_.spsph())
      pass(spsph_);
    else if (c_.disph())
      pass(disph_);
    else
      pass(ssph_);
    hydro_seconds_ += pik::wall_time() - t0;
    if (gravity_y_ != 0)
      for (auto& p : ps_) p.acc.y += gravity_y_;
    if constexpr (D == 3) {
      if (c_.gravity) {
        const double t1 = pik::wall_time();
        if (!gravity_tree_) gravity_tree_ = std::make_unique<GravTree>(pik::TreeParams{.theta = c_.theta});
        const float e2 = float(c_.eps * c_.eps);
        gravity_tree_->calcForceAllAndWriteBack(Gravity(e2), GravityMonopole(e2), ps_);
        for (auto& p : ps_) p.acc += p.grav;
        gravity_seconds_ += pik::wall_time() - t1;
      }
    }
  }

  /// SPSPH integrates its pseudo-density and density beside v and u (kick-drift-kick
  /// like u, kept above half their half-step values); wall particles stay where they are.
  void open_step(Particle<D>& p, double dt) const {
    if (p.tag == sph::problems::wall) return;
    pik::sph::open_step(p, dt);
    if (c_.spsph()) {
      const auto [ry, rr] = spsph_rates(p);
      p.y_half = p.y + 0.5 * dt * ry, p.rho_t_half = p.rho_t + 0.5 * dt * rr;
      p.y = std::max(p.y_half + 0.5 * dt * ry, 0.5 * p.y_half);
      p.rho_t = std::max(p.rho_t_half + 0.5 * dt * rr, 0.5 * p.rho_t_half);
    }
  }
  void close_step(Particle<D>& p, double dt) const {
    if (p.tag == sph::problems::wall) {
      p.vel = {}, p.acc = {}, p.dudt = 0;
      return;
    }
    pik::sph::close_step(p, dt);
    if (c_.spsph()) {
      const auto [ry, rr] = spsph_rates(p);
      p.y = std::max(p.y_half + 0.5 * dt * ry, 0.5 * p.y_half);
      p.rho_t = std::max(p.rho_t_half + 0.5 * dt * rr, 0.5 * p.rho_t_half);
    }
  }

  /// Global step: C_CFL h_i / vsig_i (Springel 2005, eq. 16), with gravity also
  /// 0.3 sqrt(eps / |a_i|), and for SPSPH the explicit-diffusion limit of the
  /// pseudo-density, C h^2 / D with D = alpha_y vsig h / 4 and C = 1/40.
  pik::sph::StepLimits limits() const {
    pik::sph::StepLimits lim;
    for (const auto& p : ps_) {
      lim.add("courant", pik::sph::courant(p.h, p.vsig, c_.cfl));
      if (c_.spsph() && c_.alpha_y > 0)
        lim.add("pseudo-density diffusion", pik::sph::diffusion(p.h, c_.alpha_y * p.vsig * p.h / 4, 1.0 / 40));
      if (c_.gravity) lim.add("gravity", pik::sph::acceleration(c_.eps, pik::norm(p.acc), 0.3));
    }
    return lim;
  }

  /// Kinetic, thermal and potential energy (the kernel's self term -m/eps removed).
  std::array<double, 3> energies() const {
    double k = 0, th = 0, w = 0;
    for (const auto& p : ps_) {
      if (p.tag == sph::problems::wall) continue;
      k += 0.5 * p.mass * pik::norm2(p.vel), th += p.mass * p.u;
      w -= p.mass * gravity_y_ * p.pos.y;
      if (c_.gravity) w += 0.5 * p.mass * (p.pot + p.mass / c_.eps);
    }
    return {k, th, w};
  }

  std::vector<std::string> diagnostic_names() const { return {"E", "K", "U", "W", "mode"}; }
  std::vector<double> diagnostics() const {
    const auto e = energies();
    double mode = 0;
    if constexpr (D == 2)
      if (c_.problem == "kh" || c_.problem == "khsharp")
        mode = sph::problems::kh_mode(ps_, 4 * M_PI, [](const auto& p) { return p.mass / p.rho_ep; });
    return {e[0] + e[1] + e[2], e[0], e[1], e[2], mode};
  }

  /// Snapshots carry what the plots need; a checkpoint every field the next step reads.
  void fill_snapshot(pik::io::Snapshot& s, bool checkpoint) const {
    const std::size_t n = ps_.size();
    auto col = [&](const char* name, auto get) {
      auto& c = s.column(name, 1);
      for (std::size_t i = 0; i < n; ++i) c.data[i] = get(ps_[i]);
    };
    auto col3 = [&](const char* name, auto get) {
      auto& c = s.column(name, 3);
      for (std::size_t i = 0; i < n; ++i) {
        const Vec3d v = get(ps_[i]);
        c.data[3 * i] = v.x, c.data[3 * i + 1] = v.y, c.data[3 * i + 2] = v.z;
      }
    };
    col("Tag", [](const auto& p) { return double(p.tag); });
    col("Density", [](const auto& p) { return p.rho_ep; });  // SPSPH: its own density
    col("Pressure", [](const auto& p) { return p.pres; });
    col("InternalEnergy", [](const auto& p) { return p.u; });
    col("SmoothingLength", [](const auto& p) { return p.h; });
    if (checkpoint) {
      col("DuDt", [](const auto& p) { return p.dudt; });
      col("SignalVelocity", [](const auto& p) { return p.vsig; });
      col3("Acceleration", [](const auto& p) { return p.acc; });
      col("SphDensity", [](const auto& p) { return p.rho; });
    }
    if (c_.spsph()) {
      col("PseudoDensity", [](const auto& p) { return p.y; });
      if (checkpoint) {
        col("SpsphDensity", [](const auto& p) { return p.rho_t; });  // the state (Density: at the last force pass)
        col("PseudoDensityRate", [](const auto& p) { return p.dydt; });
        col("PseudoDensityDiffusion", [](const auto& p) { return p.ydiff; });
      }
    }
    s.attr.set("dim", D);
    for (const auto& [k, v] : physics()) s.attr.set(k, v);
  }

  /// Restores a checkpoint of the same problem and physics.
  void restore(const pik::io::Snapshot& s) {
    for (const auto& [k, v] : physics())
      if (!s.attr.has(k) || s.attr.get_string(k) != v)
        throw pik::Error("the checkpoint was written with " + k + " = " +
                         (s.attr.has(k) ? s.attr.get_string(k) : std::string("(none)")) + ", this run has " + v);
    std::vector<const char*> need = {"Tag",           "InternalEnergy", "SmoothingLength", "DuDt",
                                     "SignalVelocity", "Acceleration",   "SphDensity"};
    if (c_.spsph())
      need.insert(need.end(), {"SpsphDensity", "PseudoDensity", "PseudoDensityRate", "PseudoDensityDiffusion"});
    for (const char* c : need)
      if (!s.find(c)) throw pik::Error(std::string("the checkpoint lacks the column '") + c + "'");
    for (std::size_t i = 0; i < ps_.size(); ++i) {
      auto& p = ps_[i];
      p.tag = int(s.find("Tag")->data[i]), p.u = s.find("InternalEnergy")->data[i];
      p.h = s.find("SmoothingLength")->data[i], p.dudt = s.find("DuDt")->data[i];
      p.vsig = s.find("SignalVelocity")->data[i];
      const auto& a = s.find("Acceleration")->data;
      p.acc = {a[3 * i], a[3 * i + 1], a[3 * i + 2]};
      p.rho = s.find("SphDensity")->data[i], p.pres = s.find("Pressure")->data[i];
      if (c_.spsph()) {
        p.rho_ep = s.find("Density")->data[i], p.rho_t = s.find("SpsphDensity")->data[i];
        p.y = s.find("PseudoDensity")->data[i];
        p.dydt = s.find("PseudoDensityRate")->data[i], p.ydiff = s.find("PseudoDensityDiffusion")->data[i];
      }
    }
  }

  double densitySeconds() const { return density_seconds_; }
  double hydroSeconds() const { return hydro_seconds_; }
  double gravitySeconds() const { return gravity_seconds_; }
  long densityPasses() const { return density_passes_; }
  DensityTree& densityTree() { return density_tree_; }
  HydroTree& hydroTree() { return hydro_tree_; }

 private:
  /// The parameters a restart must not change, as text (exact doubles).
  std::vector<std::pair<std::string, std::string>> physics() const {
    auto x = [](double v) {
      char b[32];
      std::snprintf(b, sizeof b, "%.17g", v);
      return std::string(b);
    };
    return {{"problem", c_.problem}, {"scheme", c_.scheme}, {"kernel", shape_names[S]},
            {"gamma", x(c_.gamma)},  {"nngb", x(c_.nngb)},   {"alpha", x(c_.alpha)},
            {"cfl", x(c_.cfl)},      {"eps", x(c_.eps)},     {"theta", x(c_.theta)},
            {"balsara", c_.balsara ? "on" : "off"}, {"y_init", c_.spsph() ? c_.y_init : "-"},
            {"alpha_y", c_.spsph() ? x(c_.alpha_y) : "-"},
            {"y_smooth", c_.spsph() && c_.y_init == "density" ? std::to_string(c_.y_smooth) : "-"}, {"gradh", c_.disph() ? (c_.gradh ? "on" : "off") : "-"},
            {"h_from", c_.h_from}, {"contrast", x(c_.contrast)}, {"scale", x(c_.scale)}};
  }

  /// SPSPH's rates: dy/dt = continuity + diffusion; d rho/dt = (rho / y) x continuity
  /// (the same discrete -rho div v, without the diffusion: it moves pseudo-mass only).
  static std::pair<double, double> spsph_rates(const Particle<D>& p) {
    return {p.dydt + p.ydiff, p.rho_t / p.y * p.dydt};
  }

  using GravTree = pik::LongRangeTree<GravityResult, GravEPI, GravEPJ, GravSPJ>;
  Config c_;
  double gravity_y_ = 0;
  pik::ParticleSystem<Particle<D>> ps_;
  DensityTree density_tree_;
  HydroTree hydro_tree_;
  std::vector<double> nd_before_;  ///< density(): number densities before a masked pass
  std::unique_ptr<std::conditional_t<D == 3, GravTree, int>> gravity_tree_;
  pik::Boundary<D> boundary_;
  pik::eos::IdealGas eos_;
  pik::sph::SmoothingLengthParams h_params_;
  typename K::Density density_;
  typename K::Ssph ssph_;
  typename K::Disph disph_;
  typename K::Spsph spsph_;
  double density_seconds_ = 0, hydro_seconds_ = 0, gravity_seconds_ = 0;
  long density_passes_ = 0;
};

// ---- driver -----------------------------------------------------------------------------
/// Time and mode columns of the run's log (a restarted run's log holds the whole run).
std::vector<std::array<double, 4>> read_log(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw pik::Error("cannot read " + path);
  std::vector<std::array<double, 4>> rows;  // time, E, mode, K
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ss(line);
    double step, t, dt, e, k, u, w, mode;
    if (ss >> step >> t >> dt >> e >> k >> u >> w >> mode) rows.push_back({t, e, mode, k});
  }
  return rows;
}

template <int D, int S>
int run(const Config& c, Setup<D> setup) {
  Simulation<D, S> sim(c, std::move(setup));
  auto& ps = sim.particles();
  std::printf("sph: problem %s, scheme %s, %dD, %zu particles, kernel %s (%s), N_ngb %g, gamma %g, t_end %g, "
              "%d threads\n",
              c.problem.c_str(), c.scheme.c_str(), D, ps.size(), shape_names[S], Kernels<D, S>::Density::isa_name(),
              c.nngb, c.gamma, c.t_end, pik::detail::max_threads());
  std::fflush(stdout);
  std::vector<double> y0(ps.size());  // initial heights (the layer's surface); a restart rebuilds them
  std::vector<Vec3d> x0(ps.size());   // initial positions (the contacts' interface displacement), likewise
  for (const auto& p : ps) y0[p.id] = p.pos.y, x0[p.id] = p.pos;
  pik::sph::Driver driver(sim, c.run);
  driver.run();

  std::printf("steps %ld, t = %.4g, wall %.2f s (density %.2f s in %ld passes, hydro %.2f s, gravity %.2f s)\n",
              driver.steps(), driver.time(), driver.seconds(), sim.densitySeconds(), sim.densityPasses(),
              sim.hydroSeconds(), sim.gravitySeconds());
  double nmin = 1e30, nmax = 0;
  for (const auto& p : ps) nmin = std::min(nmin, p.nngb), nmax = std::max(nmax, p.nngb);
  std::printf("neighbours per particle: %.0f to %.0f\n", nmin, nmax);
  const auto log = read_log(c.out + "/log.txt");
  if constexpr (D == 3) {
    if (c.problem == "sod") {
      const auto e = sod_l1(ps, driver.time(), c.gamma);
      const sph::ExactRiemann ex(sod_left, sod_right, c.gamma);
      std::printf("sod exact star state: p* = %.5f u* = %.5f\n", ex.pStar(), ex.uStar());
      std::printf("sod L1 error (0 <= x <= 1, t = %.3g): rho %.5f  p %.5f  vx %.5f\n", driver.time(), e[0], e[1],
                  e[2]);
      std::FILE* f = std::fopen((c.out + "/exact.txt").c_str(), "w");
      if (!f) throw pik::Error("cannot write " + c.out + "/exact.txt");
      std::fprintf(f, "# exact Sod solution at t = %.9g: x rho p vx\n", driver.time());
      for (int i = 0; i <= 2000; ++i) {
        const double x = -0.5 + 2.0 * i / 2000;
        const auto s = ex.sample((x - 0.5) / driver.time());
        std::fprintf(f, "%.6f %.9g %.9g %.9g\n", x, s.rho, s.p, s.u);
      }
      std::fclose(f);
    }
    if (c.problem == "evrard") {
      const auto e = sim.energies();
      const double e0 = log.front()[1];
      double max_de = 0;
      for (const auto& r : log) max_de = std::max(max_de, std::abs(r[1] - e0) / std::abs(e0));
      std::printf("evrard energy: E0 %.6f  E %.6f (K %.4f U %.4f W %.4f)  |dE/E0| final %.4f max %.4f\n", e0,
                  e[0] + e[1] + e[2], e[0], e[1], e[2], std::abs(e[0] + e[1] + e[2] - e0) / std::abs(e0), max_de);
    }
  } else {
    namespace pr = sph::problems;
    if (c.problem == "square" || c.problem == "contact") {
      const bool sq = c.problem == "square";
      const double spread = sq ? pr::spread(ps, pr::square_distance, 1.0 / c.n) : pr::spread(ps, pr::strip_distance, 1.0 / c.n);
      const double corners = sq ? pr::corner_loss(ps, c.n, c.contrast) : 0.0;
      const double shift = sq ? pr::interface_displacement(ps, x0, pr::square_distance, c.n)
                              : pr::interface_displacement(ps, x0, pr::strip_distance, c.n);
      double kmax = 0, mass = 0;
      for (const auto& r : log) kmax = std::max(kmax, r[3]);
      for (const auto& p : ps) mass += p.mass;
      std::printf("%s contrast %g (t = %.3g): deformation %.4f (corner loss %.4f + spread %.4f)  rms velocity %.5f "
                  "(dense %.5f, light %.5f)  max rms velocity %.5f  interface displacement %.4f spacings\n",
                  c.problem.c_str(), c.contrast, driver.time(), corners + spread, corners, spread, pr::rms_velocity(ps),
                  pr::rms_velocity(ps, pr::dense), pr::rms_velocity(ps, pr::light), std::sqrt(2 * kmax / mass), shift);
    }
    if (c.problem == "layer")
      std::printf("layer contrast %g scale %g (t = %.3g): rms velocity dense %.5f light %.5f  surface displacement %.4f "
                  "spacings\n",
                  c.contrast, c.scale, driver.time(), pr::rms_velocity(ps, pr::dense), pr::rms_velocity(ps, pr::light),
                  pr::surface_displacement(ps, y0, c.n));
    if (c.problem == "khsharp") {
      const pr::KhSharp k{.contrast = c.contrast};
      std::vector<std::pair<double, double>> modes;
      double mmax = 0;
      for (const auto& [t, e, mode, k] : log) modes.push_back({t, mode}), mmax = std::max(mmax, mode);
      // and over a fixed early window, the same for every scheme (the linear phase at contrasts 2 to 10)
      std::vector<std::pair<double, double>> early;
      for (const auto& [t, m] : modes)
        if (t <= kh_window_end + 1e-9) early.push_back({t, m});
      std::printf("khsharp contrast %g: M(0) = %.4f  M(%.3g) = %.4f  max %.4f  growth rate %.3f  linear rate %.3f  "
                  "rate (%.2g <= t <= %.2g) %.3f\n",
                  c.contrast, log.front()[2], log.back()[0], log.back()[2], mmax,
                  pr::growth_rate(modes, kh_fit_from, kh_fit_cap * log.front()[2]), k.linear_rate(), kh_fit_from,
                  kh_window_end, pr::growth_rate(early, kh_fit_from, 1e300));
    }
    if (c.problem == "kh") {
      // Growth rate from a least-squares fit of ln M over the linear phase 0.25 <= t <= 1.
      double sx = 0, sy = 0, sxx = 0, sxy = 0, n = 0;
      for (const auto& [t, e, mode, k] : log)
        if (t >= 0.25 && t <= 1.0 && mode > 0) {
          const double y = std::log(mode);
          sx += t, sy += y, sxx += t * t, sxy += t * y, ++n;
        }
      const double rate = n > 2 ? (n * sxy - sx * sy) / (n * sxx - sx * sx) : NAN;
      double m1 = NAN;
      for (const auto& [t, e, mode, k] : log)
        if (t <= 1.0 + 1e-9) m1 = mode;
      std::printf("kh mode amplitude: M(0) = %.4f  M(1) = %.4f  M(%.3g) = %.4f  growth rate (0.25 <= t <= 1) %.3f\n",
                  log.front()[2], m1, log.back()[0], log.back()[2], rate);
    }
  }
  return 0;
}

template <int D>
int dispatch_shape(const Config& c, Setup<D> s) {
  switch (c.shape) {
    case 0: return run<D, 0>(c, std::move(s));
    case 1: return run<D, 1>(c, std::move(s));
    default: return run<D, 2>(c, std::move(s));
  }
}

int main(int argc, char** argv) try {
  pik::io::CommandLine cli("sph", "SPH (standard, density-independent or with a smoothed pseudo-density) with the "
                                  "classic tests and contact-discontinuity problems.");
  cli.option("--problem", "sod", "sod (3D), evrard (3D, self-gravity), kh (2D, smoothed), and the 2D contact "
                                 "problems: square, contact (a strip), khsharp (sharp-interface KH), layer "
                                 "(stratified, gravity, free surface)", "P");
  cli.option("--scheme", "disph", "ssph (standard SPH), disph (density-independent SPH) or spsph (smoothed "
                                  "pseudo-density SPH)", "S");
  cli.option("--y-init", "one", "spsph: initial pseudo-density, one (y = 1) or density (y = rho)", "Y");
  cli.option("--y-smooth", "16", "spsph --y-init density: passes of kernel averaging of the initial y = rho "
                                "(0: none, the exact discontinuous density)", "N");
  cli.option("--alpha-y", "0.1", "spsph: strength of the pseudo-density diffusion", "A");
  cli.option("--contrast", "0", "density contrast; 0: the problem's (square, contact 4; khsharp 2; layer 1000)", "X");
  cli.option("--seed", "0.1", "khsharp: amplitude of the seeded v_y mode (Springel 2010: 0.1)", "A");
  cli.option("--scale", "1", "layer: pressure scale height at the free surface, in lattice spacings", "S");
  cli.option("--kernel", "cubic", "smoothing function: cubic, wendland2 or wendland4", "K");
  cli.option("--n", "0", "resolution: particles per unit length (sod: left state; evrard: lattice "
                         "across the sphere); 0: the problem's default", "N");
  cli.option("--ny", "0", "sod: particles across the tube (left state; even); 0: n / 4", "N");
  cli.option("--gamma", "0", "adiabatic index; 0: the problem's (sod 1.4, others 5/3)", "G");
  cli.option("--t-end", "0", "end time; 0: the problem's (sod 0.2, evrard 3, khsharp 1, others 2)", "T");
  cli.option("--nngb", "0", "neighbour number (kernel mass in the support / m); 0: by kernel and dimension", "N");
  cli.option("--cfl", "0.3", "Courant factor of the time step", "C");
  cli.option("--alpha", "1", "artificial viscosity strength", "A");
  cli.flag("--no-balsara", "switch the Balsara (1995) limiter off");
  cli.flag("--no-gradh", "disph: leave out the grad-h terms");
  cli.option("--h-from", "", "the smoothing length from the number density (n; disph's default), the mass density "
                             "(rho; the default of ssph and spsph, the only choice of ssph) or, disph only, its "
                             "volume element m u / q (q)", "X");
  cli.option("--eps", "0.01", "gravitational softening (evrard)", "EPS");
  cli.option("--theta", "0.5", "opening angle of the gravity tree (evrard)", "THETA");
  cli.option("--lists", "0", "neighbour candidates: one tree build and one candidate walk per force evaluation, "
                             "shared by the smoothing-length passes and the hydro pass, with every h grown by this "
                             "fraction (collected again only where an h outgrows it); 'off': a tree build and walk per pass", "M");
  cli.option("--snapshots", "0", "write this many snapshots evenly in time (and the initial one); 0: only the final", "N");
  cli.option("--format", "binary", "snapshot format: binary, ascii or hdf5", "F");
  cli.option("--checkpoint-every", "0", "write out/checkpoint.pbin every N steps (and always at the end)", "N");
  cli.option("--log-every", "1", "a row of out/log.txt every N steps (and at every output, checkpoint and the last step); 1: every step", "N");
  cli.option("--restart", "", "continue the run of this checkpoint (same problem and options; --t-end may grow)", "FILE");
  cli.option("--max-steps", "0", "stop after this many steps in all (0: no limit)", "N");
  cli.option("--out", "sph_out", "output directory", "DIR");
  cli.parse(argc, argv);

  Config c;
  c.problem = cli.str("--problem"), c.scheme = cli.str("--scheme"), c.out = cli.str("--out");
  const std::vector<std::string> problems = {"sod", "evrard", "kh", "square", "contact", "khsharp", "layer"};
  if (std::find(problems.begin(), problems.end(), c.problem) == problems.end())
    cli.fail("--problem must be sod, evrard, kh, square, contact, khsharp or layer, not '" + c.problem + "'");
  if (c.scheme != "ssph" && c.scheme != "disph" && c.scheme != "spsph")
    cli.fail("--scheme must be ssph, disph or spsph, not '" + c.scheme + "'");
  c.y_init = cli.str("--y-init"), c.alpha_y = cli.real("--alpha-y"), c.scale = cli.real("--scale");
  if (c.y_init != "one" && c.y_init != "density") cli.fail("--y-init must be one or density, not '" + c.y_init + "'");
  if (!(c.alpha_y >= 0)) cli.fail("--alpha-y must be non-negative");
  if (cli.count("--y-smooth") > 1000) cli.fail("--y-smooth must be at most 1000");
  c.y_smooth = int(cli.count("--y-smooth"));
  if (!(c.scale > 0)) cli.fail("--scale must be positive");
  c.seed = cli.real("--seed");
  if (!(c.seed > 0 && c.seed < 1)) cli.fail("--seed must be in (0, 1)");
  if (cli.real("--contrast") < 0 || (cli.real("--contrast") > 0 && !(cli.real("--contrast") >= 1)))
    cli.fail("--contrast must be at least 1 (or 0 for the problem's value)");
  c.contrast = cli.real("--contrast") > 0 ? cli.real("--contrast")
               : c.problem == "khsharp"   ? 2.0
               : c.problem == "layer"     ? 1000.0
                                          : 4.0;
  const std::string kname = cli.str("--kernel");
  c.shape = kname == "cubic" ? 0 : kname == "wendland2" ? 1 : kname == "wendland4" ? 2 : -1;
  if (c.shape < 0) cli.fail("--kernel must be cubic, wendland2 or wendland4, not '" + kname + "'");
  c.dim = c.problem == "sod" || c.problem == "evrard" ? 3 : 2;
  c.gravity = c.problem == "evrard";
  // 0 asks for the problem's value; a negative one is a mistake, not a request for it.
  for (const char* opt : {"--gamma", "--t-end", "--nngb"})
    if (cli.real(opt) < 0) cli.fail(std::string(opt) + " must be positive (or 0 for the problem's value)");
  c.gamma = cli.real("--gamma") > 0 ? cli.real("--gamma") : (c.problem == "sod" ? 1.4 : 5.0 / 3.0);
  c.t_end = cli.real("--t-end") > 0 ? cli.real("--t-end")
            : c.problem == "sod"    ? sod_t_end
            : c.problem == "evrard" ? 3.0
            : c.problem == "khsharp" ? 1.0
                                    : 2.0;
  const double nngb_default[2][3] = {{20, 32, 50}, {50, 100, 200}};
  c.nngb = cli.real("--nngb") > 0 ? cli.real("--nngb") : nngb_default[c.dim - 2][c.shape];
  c.cfl = cli.real("--cfl"), c.alpha = cli.real("--alpha"), c.balsara = !cli.on("--no-balsara");
  c.gradh = !cli.on("--no-gradh"), c.h_from = cli.str("--h-from");
  if (c.h_from.empty()) c.h_from = c.scheme == "disph" ? "n" : "rho";
  if (c.h_from != "rho" && c.h_from != "n" && c.h_from != "q")
    cli.fail("--h-from must be rho, n or q, not '" + c.h_from + "'");
  if (c.h_from != "rho" && c.scheme == "ssph") cli.fail("--h-from " + c.h_from + " is for disph and spsph (ssph: rho)");
  if (c.h_from == "q" && c.scheme != "disph") cli.fail("--h-from q is for disph only");
  c.eps = cli.real("--eps"), c.theta = cli.real("--theta");
  if (cli.str("--lists") == "off") {
    c.lists = -1;
  } else {
    c.lists = cli.real("--lists");
    if (!(c.lists >= 0 && c.lists <= 0.5)) cli.fail("--lists must be 'off' or a margin in [0, 0.5], not '" + cli.str("--lists") + "'");
  }
  c.run.snapshots = int(cli.count("--snapshots")), c.run.max_steps = long(cli.count("--max-steps"));
  c.run.checkpoint_every = long(cli.count("--checkpoint-every"));
  c.run.log_every = long(cli.count("--log-every"));
  if (c.run.log_every < 1) cli.fail("--log-every must be at least 1");
  c.run.restart = cli.str("--restart"), c.run.out = c.out, c.run.t_end = c.t_end;
  try {
    c.run.format = pik::io::format_from_name(cli.str("--format"));
  } catch (const std::invalid_argument& e) {
    cli.fail(std::string("--format: ") + e.what());
  }
  if (!(c.gamma > 1)) cli.fail("--gamma must be above 1");
  if (!(c.cfl > 0 && c.cfl <= 1)) cli.fail("--cfl must be in (0, 1]");
  if (!(c.alpha >= 0)) cli.fail("--alpha must be non-negative");
  if (!(c.eps > 0)) cli.fail("--eps must be positive");
  if (!(c.nngb >= 4)) cli.fail("--nngb must be at least 4");
  if (!(c.theta >= 0 && c.theta <= 2)) cli.fail("--theta must be in [0, 2]");
  // Particles grow as n^dim (sod: n x ny^2); past this the lattice alone exhausts memory.
  const std::uint64_t n_max = c.dim == 2 ? 20000 : 1000;
  if (cli.count("--n") > n_max || cli.count("--ny") > n_max)
    cli.fail("--n and --ny must be at most " + std::to_string(n_max) + " for a " + std::to_string(c.dim) +
             "D problem (particles grow as n^" + std::to_string(c.dim) + ")");
  int n = int(cli.count("--n"));

  if (c.problem == "sod") {
    if (!n) n = 64;
    int ny = int(cli.count("--ny"));
    if (!ny) ny = std::max(2, (n / 4) & ~1);
    if (ny % 2 || n < 8) cli.fail("sod needs --n >= 8 and an even --ny");
    return dispatch_shape<3>(c, sod(n, ny, 1.0, 1.0, c.gamma));
  }
  namespace pr = sph::problems;
  if (c.problem == "kh") return dispatch_shape<2>(c, kh(n ? n : 64, c.gamma));
  if (c.problem != "evrard") {
    c.n = n ? n : 32;
    if (c.n < 8 || c.n % 4) cli.fail("--n must be a multiple of 4, at least 8, for " + c.problem);
  }
  if (c.problem == "square") return dispatch_shape<2>(c, from_problem(pr::contact_square(c.n, c.contrast, c.gamma)));
  if (c.problem == "contact") return dispatch_shape<2>(c, from_problem(pr::contact_strip(c.n, c.contrast, c.gamma)));
  if (c.problem == "khsharp")
    return dispatch_shape<2>(c, from_problem(pr::kh_sharp(c.n, pr::KhSharp{.contrast = c.contrast, .amplitude = c.seed}, c.gamma)));
  if (c.problem == "layer")
    return dispatch_shape<2>(c, from_problem(pr::layer(c.n, pr::Layer{.contrast = c.contrast, .scale = c.scale}, c.gamma)));
  return dispatch_shape<3>(c, evrard(n ? n : 20));
} catch (const std::exception& e) {
  std::fprintf(stderr, "sph: error: %s\n", e.what());
  return 1;
}
