/// \file Stratified.hpp
/// \brief Convection in a stratified, compressible (polytropic) layer by explicit SPH with
///        the reduced speed of sound technique (RSST; Hotta, Rempel & Yokoyama 2012,
///        A&A 539, A30): the parameters, the reference state, the initial state and the
///        model the shared SPH driver (pik/sph/Driver.hpp) runs.
///
/// The layer 0 <= z <= d (d = 1; z the last dimension, gravity g along -z) is an ideal
/// gas (p = rho T with the gas constant R = 1, c_v = 1/(gamma - 1), c_p = gamma c_v)
/// about a hydrostatic, adiabatic reference state (the polytrope of index
/// m = 1/(gamma - 1)):
///
///   T0(z) = 1 + (chi^(1/m) - 1)(1 - z),  rho0 = T0^m,  p0 = T0^(m+1),  g = c_p (chi^(1/m) - 1)
///
/// (dp0/dz = -rho0 g; chi = rho0(0) / rho0(1) the density contrast, T = 1 at the top).
/// As in Hotta et al. (2012) the reference entropy has a small, prescribed superadiabatic
/// gradient ds0/dz = -delta c_p (delta = Delta s / c_p across the layer), which drives the
/// convection, and the perturbations (rho1, p1, s1, v) obey
///
///   d_t rho1   = -(1/xi^2) div(rho0 v)                               (RSST continuity)
///   rho0 dv/dt = -grad p1 - rho1 g e_z + div(mu grad v),  mu = rho0 nu
///              = -rho0 grad(p1 / rho0) + rho0 (s1 / c_p) g e_z + div(mu grad v)
///   rho0 T0 ds1/dt = -rho0 T0 v_z ds0/dz + div(rho0 T0 kappa grad s1)
///   p1 = (gamma p0 / rho0) rho1 + (p0 / c_v) s1                      (linearised EOS)
///
/// The particles move with v, so the continuity equation is integrated in its
/// Lagrangian form d rho1/dt = -(1/xi^2) div(rho0 v) + v . grad rho1 and the entropy
/// equation as ds1/dt = -v_z ds0/dz + div(k grad s1) / (rho0 T0). The second form of the
/// momentum equation is exact for an adiabatic reference (grad rho0 = -rho0 g / c_s^2 e_z,
/// p1 / c_s^2 - rho1 = rho0 s1 / c_p); it is the one discretised, because its pressure
/// sum is the adjoint of the SPH div(rho0 v), so the pair exchanges acoustic energy
/// exactly (with -grad p1 - rho1 g e_z summed separately the fully compressible run,
/// xi = 1, was unstable). The sums are in
/// kernels/sph_rsst.pik. xi >= 1 is the RSST factor: sound travels xi times slower
/// (c_s / xi), while the convection is unchanged as long as its Mach number against the
/// reduced sound speed stays small (Hotta et al. 2012: below about 0.7). xi may vary in
/// space (--rsst-law uniform: xi(z) = xi c_s(z) / c_s(top), one reduced sound speed
/// c_s(top) / xi everywhere).
///
/// Walls: free slip all round; s1 = 0 at the top and bottom (fixed entropy, images -s1),
/// insulating side walls; through mirror particles (pik/sph/Walls.hpp). The kinematic
/// viscosity nu and the thermal diffusivity kappa are uniform and follow from the Rayleigh
/// number Ra = g delta d^3 / (nu kappa) and the Prandtl number nu / kappa. Times are in
/// d / sqrt(R T_top); the report gives v_rms also in kappa / d.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <pik/io/Snapshot.hpp>
#include <pik/pik.hpp>
#include <pik/sph/Smoothing.hpp>
#include <pik/sph/TimeStep.hpp>
#include <pik/sph/Walls.hpp>

#include "StratifiedTypes.hpp"

namespace stratified {

/// Run parameters (the command line's options) and the reference state they define.
struct Params {
  int dim = 2;
  double ra = 1e4;          // Rayleigh number g delta d^3 / (nu kappa)
  double prandtl = 1;       // nu / kappa
  double delta = 5e-4;      // superadiabatic entropy drop across the layer, Delta s / c_p
  double chi = 3;           // density contrast rho0(bottom) / rho0(top)
  double gamma = 5.0 / 3.0; // ratio of the specific heats
  double rsst = 1;          // RSST factor xi (>= 1)
  std::string rsst_law = "constant";  // constant, or uniform: xi(z) = xi c_s(z) / c_s(top)
  int nz = 16;              // particle rows across the depth
  double aspect = 2;        // box width / depth
  pik::sph::Shape shape = pik::sph::Shape::wendland2;
  double hfac = 4;          // support radius / local particle spacing
  double cfl = 0.1, cdiff = 0.025, cacc = 0.25;
  double shift = 2;         // particle shifting strength (0: off)
  double amplitude = 0.5;   // initial s1 = A Delta s cos(pi x / L) sin(pi z)
  double t_end = 400;       // in d / sqrt(R T_top)
  std::string gauge = "mean";  // the reduced pressure the pressure sum reads: mean (w less its volume mean) or absolute
  double filter = 0;        // acoustic filter strength alpha (0: off): rate alpha c_s / (xi h) towards the kernel average

  double cv() const { return 1 / (gamma - 1); }
  double cp() const { return gamma / (gamma - 1); }
  double poly() const { return 1 / (gamma - 1); }  // polytropic index of the adiabat
  double tbot() const { return std::pow(chi, gamma - 1); }
  double g() const { return cp() * (tbot() - 1); }
  double t0(double z) const { return 1 + (tbot() - 1) * (1 - z); }
  double rho0(double z) const { return std::pow(t0(z), poly()); }
  double p0(double z) const { return std::pow(t0(z), poly() + 1); }
  double sound(double z) const { return std::sqrt(gamma * t0(z)); }  // adiabatic c_s = sqrt(gamma p0 / rho0)
  double ds0dz() const { return -delta * cp(); }
  double kappa() const { return std::sqrt(g() * delta / (ra * prandtl)); }
  double nu() const { return prandtl * kappa(); }
  /// RSST factor at height z (Hotta et al. 2012 let it vary in space).
  double xi(double z) const { return rsst_law == "uniform" ? rsst * sound(z) / sound(1.0) : rsst; }
  /// Convective velocity estimate for the checks: v_rms ~ 0.113 Ra^0.645 kappa / d, the
  /// power law through Blankenbach et al.'s (1989) Boussinesq cases 1a and 1c.
  double v_estimate() const { return 0.113 * std::pow(ra, 0.645) * kappa(); }

  /// Refuses impossible parameters; returns warnings where the estimated flow breaks a
  /// validity condition, and throws where it breaks one by an order of magnitude.
  std::vector<std::string> check() const {
    auto need = [](bool ok, const std::string& what) {
      if (!ok) throw pik::Error(what);
    };
    need(dim == 2 || dim == 3, "the dimension must be 2 or 3");
    need(ra > 0 && std::isfinite(ra), "the Rayleigh number must be positive");
    need(prandtl > 0 && std::isfinite(prandtl), "the Prandtl number must be positive (a negative or zero viscosity is not a fluid)");
    need(delta > 0 && delta <= 0.1, "the superadiabaticity --delta must be in (0, 0.1] (the perturbation equations need s1 << c_p)");
    need(chi > 1 && chi <= 1000, "the density contrast --chi must be above 1 (a stratified layer) and at most 1000");
    need(gamma > 1 && gamma <= 3, "the ratio of specific heats must be in (1, 3]");
    need(rsst >= 1, "the RSST factor must be at least 1 (it reduces the sound speed)");
    need(rsst_law == "constant" || rsst_law == "uniform", "--rsst-law must be constant or uniform, not '" + rsst_law + "'");
    need(gauge == "mean" || gauge == "absolute", "--gauge must be mean or absolute, not '" + gauge + "'");
    need(nz >= 4, "at least 4 particle rows across the depth (an empty or one-row box has no convection)");
    need(aspect > 0 && std::isfinite(aspect), "the aspect ratio must be positive");
    need(aspect * nz / std::sqrt(chi) >= 1, "the box is empty: aspect ratio x resolution gives no particle column");
    need(nz <= 2048 && aspect * nz <= 4096 && (dim == 2 || std::pow(aspect * nz, 2) * nz <= 2e7), "too many particles for one machine");
    need(hfac >= 2 && hfac <= 6, "the support radius must be 2 to 6 particle spacings");
    need(cfl > 0 && cfl <= 1 && cdiff > 0 && cdiff <= 0.5 && cacc > 0 && cacc <= 1, "time-step factors out of range");
    need(shift >= 0 && shift <= 10, "the particle shifting strength must be in [0, 10]");
    need(amplitude >= 0 && amplitude <= 2, "the initial perturbation --amplitude must be in [0, 2] (units of Delta s)");
    need(t_end > 0 && std::isfinite(t_end), "the end time must be positive");
    need(filter >= 0 && filter <= 2, "the acoustic filter strength --filter must be in [0, 2] (0: off)");
    std::vector<std::string> warn;
    double ma = 0;
    for (double z = 0; z <= 1; z += 0.01) ma = std::max(ma, v_estimate() * xi(z) / sound(z));
    char b[256];
    std::snprintf(b, sizeof b, "estimated Mach number %.3g against the reduced sound speed (needs < 0.7; Hotta et al. 2012)", ma);
    if (ma > 7) throw pik::Error(std::string("validity condition broken by an order of magnitude: ") + b + ": lower --rsst");
    if (ma > 0.7) warn.push_back(std::string("validity condition broken: ") + b);
    if (delta > 0.02) warn.push_back("delta > 0.02: the linearised perturbation equations want Delta s << c_p");
    return warn;
  }
};

/// Diagnostics of the current state.
struct State {
  /// vrms in d sqrt(R T_top) / d; pe = vrms d / kappa; ma: largest |v| xi / c_s, ma_rms its
  /// rms; comp: largest |rho1| / rho0; s1top/s1bot: the heat through the walls as a Nusselt
  /// number (1 in the conductive state); ek: kinetic energy sum m v^2 / 2.
  double vrms = 0, pe = 0, ma = 0, ma_rms = 0, comp = 0, nu_top = 0, nu_bot = 0, ek = 0;
  /// rms of |sum_j V_j gradW_ij| h_i: the SPH gradient of a constant times the support radius
  /// (0 on a perfect lattice; the particle disorder the pressure sum sees)
  double disorder = 0;
};

/// The model the shared driver runs. K: the kernel classes of one dimension and smoothing
/// function (K::Density, K::Rsst).
template <int D, class K>
class Model {
  using P = Particle<D>;
  using E = EP<D>;
  using DensityTree = pik::ShortRangeTree<DensityResult, E, E, pik::SearchMode::gather>;
  using ForceTree = pik::ShortRangeTree<RsstResult, E, E, pik::SearchMode::symmetric>;

 public:
  explicit Model(const Params& prm)
      : p_(prm), density_tree_({.n_leaf_limit = 8, .n_group_limit = 32}),
        force_tree_({.n_leaf_limit = 8, .n_group_limit = 32}) {
    width_ = prm.aspect;
    pik::Box<double, D> box;
    for (int d = 0; d < D; ++d) box.lo[d] = 0, box.hi[d] = d == D - 1 ? 1.0 : width_;
    walls_ = pik::sph::Walls<D>(box);
    using Kind = pik::sph::WallFace::Kind;
    for (int d = 0; d < D - 1; ++d) walls_.set_axis(d, {Kind::free_slip, false, 0}, {Kind::free_slip, false, 0});
    walls_.set_axis(D - 1, {Kind::free_slip, true, 0.0}, {Kind::free_slip, true, 0.0});  // s1 = 0 at both
    area_ = std::pow(width_, D - 1);
    lattice();
    if (ps_.empty()) throw pik::Error("the box holds no particles");
  }

  pik::ParticleSystem<P>& particles() { return ps_; }
  const pik::ParticleSystem<P>& particles() const { return ps_; }
  const Params& params() const { return p_; }
  std::size_t images() const { return n_images_; }
  std::uint64_t interactions() const { return interactions_; }

  /// Every pass at the current state: the reference state at each particle's height, its
  /// smoothing length from the local reference density, the linearised EOS, the volume
  /// element (gather density pass with the wall images), the pair sums of sph_rsst.pik,
  /// then buoyancy, the background-entropy term and the RSST continuity equation per
  /// particle.
  void compute() {
    const double nu = p_.nu(), kappa = p_.kappa(), g = p_.g(), ds0 = p_.ds0dz();
    double hmax = 0;
    for (auto& q : ps_) {
      const double z = q.pos[D - 1];
      q.t0 = p_.t0(z), q.rho0 = p_.rho0(z), q.p0 = p_.p0(z), q.xi = p_.xi(z);
      q.h = p_.hfac * std::pow(q.mass / q.rho0, 1.0 / D);
      q.mu = q.rho0 * nu, q.cond = q.rho0 * q.t0 * kappa;
      q.p1 = p_.gamma * q.p0 / q.rho0 * q.rho1 + q.p0 / p_.cv() * q.s1;  // Hotta et al. 2012, linearised EOS
      q.pa = q.rho1 + q.rho0 * q.s1 / p_.cp();                           // p1 / c_s^2, the acoustic part of rho1
      hmax = std::max(hmax, q.h);
    }
    n_images_ = walls_.template attach<E>(density_tree_, ps_, hmax);
    density_tree_.calcForceAllAndWriteBack(density_, ps_);
    // The pressure sum -sum_j V_j (w_i + w_j) gradW_ij does not vanish for a uniform w: it
    // leaves -2 w_i sum_j V_j gradW_ij (the SPH gradient of a constant, 'bias', ~0.1 / h in a
    // disordered layer), a force on every particle proportional to the level of w, which the
    // continuum does not have (only grad w acts). The level is a gauge: the volume-weighted
    // mean of w is removed, which keeps the spurious force to the size of w's variation. It is
    // the adjoint of removing the mean of drho1/dt below (sum_i V_i (w_i - wbar) D_i =
    // sum_i V_i w_i (D_i - Dbar)), so the pair still exchanges acoustic energy exactly.
    double wv = 0, vt = 0;
    for (auto& q : ps_) q.vol = q.mass / q.rho, wv += q.vol * q.p1 / q.rho0, vt += q.vol;
    const double wbar = p_.gauge == "mean" ? wv / vt : 0.0;
    for (auto& q : ps_) q.pw = q.p1 / q.rho0 - wbar;
    walls_.template attach<E>(force_tree_, ps_, hmax);
    force_tree_.calcForceAllAndWriteBack(rsst_, ps_);
    interactions_ += density_tree_.interactions() + force_tree_.interactions();
    for (auto& q : ps_) {
      // -grad p1 - rho1 g e_z = -rho0 grad(p1 / rho0) + rho0 (s1 / c_p) g e_z (the adiabatic
      // reference; kernels/sph_rsst.pik): the buoyancy of the entropy perturbation
      q.acc[D - 1] += g * q.s1 / p_.cp();
      q.ds1 = q.ds1 / (q.rho0 * q.t0) - q.vel[D - 1] * ds0;         // background entropy gradient
      q.drho1 = -q.divm / (q.xi * q.xi) + pik::dot(q.vel, q.gradr);  // RSST, Lagrangian form
      // Acoustic filter (--filter alpha): p1 / c_s^2 relaxes towards its kernel (Shepard)
      // average at the rate alpha (c_s / xi) / h, a particle-scale diffusion
      // (<pa> - pa ~ (sigma^2 / 2) lap pa) of the pressure perturbation alone, in the spirit
      // of the delta-SPH term of Molteni & Colagrossi (2009, Comput. Phys. Commun. 180, 861)
      // with D ~ delta h c_s / xi. It leaves the entropy part of rho1 (-rho0 s1 / c_p, in
      // pressure balance) alone, and its effect on the flow is of order (k h) Ma.
      if (p_.filter > 0) q.drho1 += p_.filter * p_.sound(q.pos[D - 1]) / (q.xi * q.h) * (q.pa_mean - q.pa);
    }
    // Closed walls: d/dt int rho1 dV = -(1/xi^2) (the flux of rho0 v through the walls) = 0.
    // The SPH difference sums do not conserve it (particle disorder: sum_i V_i D_i =
    // -2 sum_i V_i rho0_i v_i . bias_i); the volume-weighted mean rate is removed, so the total
    // perturbation mass stays what it was.
    double rate = 0, vol = 0;
    for (const auto& q : ps_) rate += q.vol * q.drho1, vol += q.vol;
    for (auto& q : ps_) q.drho1 -= rate / vol;
  }

  /// The time-step criteria: sound at the reduced speed (Courant on the local support
  /// radius), viscous and thermal diffusion (C h^2 / D), acceleration.
  pik::sph::StepLimits limits() const {
    pik::sph::StepLimits l;
    double snd = 1e300, acc = 1e300, hmin = 1e300;
    for (const auto& q : ps_) {
      const double cs = p_.sound(q.pos[D - 1]) / q.xi;
      snd = std::min(snd, pik::sph::courant(q.h, cs + pik::norm(q.vel), p_.cfl));
      acc = std::min(acc, pik::sph::acceleration(q.h, pik::norm(q.acc), p_.cacc));
      hmin = std::min(hmin, q.h);
    }
    l.add("sound", snd);
    l.add("viscous", pik::sph::diffusion(hmin, p_.nu(), p_.cdiff));
    l.add("conduction", pik::sph::diffusion(hmin, p_.kappa(), p_.cdiff));
    l.add("acceleration", acc);
    return l;
  }

  /// Kick-drift-kick with s1 and rho1 beside v; a particle that overshoots a wall is
  /// reflected back.
  void open_step(P& q, double dt) const {
    q.vel_half = q.vel + q.acc * (0.5 * dt);
    q.s1_half = q.s1 + 0.5 * dt * q.ds1, q.rho1_half = q.rho1 + 0.5 * dt * q.drho1;
    q.pos += q.vel_half * dt;
    q.vel = q.vel_half + q.acc * (0.5 * dt);
    q.s1 = q.s1_half + 0.5 * dt * q.ds1, q.rho1 = q.rho1_half + 0.5 * dt * q.drho1;
    reflect(q);
  }
  /// The closing half kick, then particle shifting as in the Boussinesq model (Lind et al.
  /// 2012, J. Comput. Phys. 231, 1499; Skillen et al. 2013): dr = -A h |v| dt grad C, at
  /// most a tenth of the local spacing, with s1 and rho1 carried to the new position.
  void close_step(P& q, double dt) const {
    q.vel = q.vel_half + q.acc * (0.5 * dt);
    q.s1 = q.s1_half + 0.5 * dt * q.ds1, q.rho1 = q.rho1_half + 0.5 * dt * q.drho1;
    if (p_.shift > 0) {
      Vec3d dr = q.gradc * (-p_.shift * q.h * pik::norm(q.vel) * dt);
      const double len = pik::norm(dr), cap = 0.1 * q.h / p_.hfac;
      if (len > cap) dr = dr * (cap / len);
      q.pos += dr, q.s1 += pik::dot(q.grads, dr), q.rho1 += pik::dot(q.gradr, dr);
      reflect(q);
    }
  }

  State state() const {
    State s;
    double vol = 0, v2 = 0, m2 = 0, qt = 0, qb = 0;
    for (const auto& q : ps_) {
      const double v = pik::norm(q.vel), ma = v * q.xi / p_.sound(q.pos[D - 1]);
      vol += q.vol, v2 += q.vol * v * v, m2 += q.vol * ma * ma;
      qt += q.vol * q.qtop, qb += q.vol * q.qbot;
      s.ma = std::max(s.ma, ma);
      s.comp = std::max(s.comp, std::abs(q.rho1) / q.rho0);
      s.ek += 0.5 * q.mass * v * v;
      s.disorder += q.vol * pik::norm2(q.bias) * q.h * q.h;
    }
    s.disorder = std::sqrt(s.disorder / vol);
    s.vrms = std::sqrt(v2 / vol), s.pe = s.vrms / p_.kappa(), s.ma_rms = std::sqrt(m2 / vol);
    const double ds = -p_.ds0dz();  // Delta s across the unit depth
    const double ktop = p_.rho0(1) * p_.t0(1) * p_.kappa(), kbot = p_.rho0(0) * p_.t0(0) * p_.kappa();
    s.nu_top = 1 - qt / (area_ * ktop * ds), s.nu_bot = 1 + qb / (area_ * kbot * ds);
    return s;
  }

  std::vector<std::string> diagnostic_names() const {
    return {"Nu_top", "Nu_bot", "v_rms", "Pe", "Ma_max", "Ma_rms", "compression", "E_kin", "disorder"};
  }
  std::vector<double> diagnostics() const {
    const State s = state();
    return {s.nu_top, s.nu_bot, s.vrms, s.pe, s.ma, s.ma_rms, s.comp, s.ek, s.disorder};
  }

  void report(double t, std::FILE* out) const {
    const State s = state();
    std::fprintf(out, "t = %.5g  Nu top %.4f bottom %.4f  v_rms %.5g (%.4g kappa/d)  Ma max %.3g rms %.3g  |rho1|/rho0 %.2g  disorder %.3g\n",
                 t, s.nu_top, s.nu_bot, s.vrms, s.pe, s.ma, s.ma_rms, s.comp, s.disorder);
    for (const auto& w : validity(s)) std::fprintf(out, "  warning: %s\n", w.c_str());
  }
  /// Hotta et al. (2012): the RSST result holds while the Mach number against the reduced
  /// sound speed stays below about 0.7; the linearisation wants |rho1| << rho0.
  std::vector<std::string> validity(const State& s) const {
    std::vector<std::string> w;
    char b[160];
    if (s.ma > 0.7) std::snprintf(b, sizeof b, "Mach number %.3g > 0.7 against the reduced sound speed (lower --rsst)", s.ma), w.push_back(b);
    if (s.comp > 0.05) std::snprintf(b, sizeof b, "density perturbation %.3g > 5 %% of rho0 (the equations are linearised)", s.comp), w.push_back(b);
    return w;
  }

  void fill_snapshot(pik::io::Snapshot& s, bool checkpoint) const {
    auto col = [&](const char* name, auto get) {
      auto& c = s.column(name, 1);
      for (std::size_t i = 0; i < ps_.size(); ++i) c.data[i] = get(ps_[i]);
    };
    auto col3 = [&](const char* name, auto get) {
      auto& c = s.column(name, 3);
      for (std::size_t i = 0; i < ps_.size(); ++i)
        for (int k = 0; k < 3; ++k) c.data[3 * i + std::size_t(k)] = get(ps_[i])[std::size_t(k)];
    };
    col("EntropyPerturbation", [](const P& q) { return q.s1; });
    col("DensityPerturbation", [](const P& q) { return q.rho1; });
    col("PressurePerturbation", [](const P& q) { return q.p1; });
    col("Density", [](const P& q) { return q.rho; });
    col("ReferenceDensity", [](const P& q) { return q.rho0; });
    if (checkpoint) {
      col3("Acceleration", [](const P& q) { return q.acc; });
      col("EntropyRate", [](const P& q) { return q.ds1; });
      col("PerturbationRate", [](const P& q) { return q.drho1; });
      col("HeatTop", [](const P& q) { return q.qtop; });
      col("HeatBottom", [](const P& q) { return q.qbot; });
      col("Volume", [](const P& q) { return q.vol; });
      // set by compute() at the position before the shift; the next step's limits read them
      col("SmoothingLength", [](const P& q) { return q.h; });
      col("RsstFactor", [](const P& q) { return q.xi; });
    }
    auto& at = s.attr;
    at.set("stratified.dim", D), at.set("stratified.ra", p_.ra), at.set("stratified.prandtl", p_.prandtl);
    at.set("stratified.delta", p_.delta), at.set("stratified.chi", p_.chi), at.set("stratified.gamma", p_.gamma);
    at.set("stratified.rsst", p_.rsst), at.set("stratified.rsst_law", p_.rsst_law), at.set("stratified.nz", p_.nz);
    at.set("stratified.aspect", p_.aspect), at.set("stratified.kernel", pik::sph::shape_name(p_.shape));
    at.set("stratified.hfac", p_.hfac), at.set("stratified.shift", p_.shift), at.set("stratified.gauge", p_.gauge);
    at.set("stratified.filter", p_.filter);
    at.set("stratified.interactions", std::uint64_t(interactions_));
  }

  void restore(const pik::io::Snapshot& s) {
    const auto& at = s.attr;
    auto same = [&](const char* key, double v) {
      if (at.get_double(key) != v)
        throw pik::Error(std::string("the checkpoint was written with another ") + key + " (" + at.get_string(key) + ")");
    };
    auto same_s = [&](const char* key, const std::string& v) {
      if (at.get_string(key) != v)
        throw pik::Error(std::string("the checkpoint was written with another ") + key + " (" + at.get_string(key) + ")");
    };
    same("stratified.dim", D), same("stratified.ra", p_.ra), same("stratified.prandtl", p_.prandtl);
    same("stratified.delta", p_.delta), same("stratified.chi", p_.chi), same("stratified.gamma", p_.gamma);
    same("stratified.rsst", p_.rsst), same_s("stratified.rsst_law", p_.rsst_law), same("stratified.nz", p_.nz);
    same("stratified.aspect", p_.aspect), same_s("stratified.kernel", pik::sph::shape_name(p_.shape));
    same("stratified.hfac", p_.hfac), same("stratified.shift", p_.shift);
    if (at.has("stratified.gauge")) same_s("stratified.gauge", p_.gauge);
    else if (p_.gauge != "absolute") throw pik::Error("the checkpoint predates --gauge (it ran with --gauge absolute)");
    if (at.has("stratified.filter")) same("stratified.filter", p_.filter);
    else if (p_.filter != 0) throw pik::Error("the checkpoint predates --filter (it ran with --filter 0)");
    auto get = [&](const char* name, int comps) {
      const pik::io::Column* c = s.find(name);
      if (!c || c->components != comps) throw pik::Error(std::string("the checkpoint has no column ") + name);
      return c;
    };
    const auto *s1 = get("EntropyPerturbation", 1), *r1 = get("DensityPerturbation", 1), *rho = get("Density", 1);
    const auto *a = get("Acceleration", 3), *ds = get("EntropyRate", 1), *dr = get("PerturbationRate", 1);
    const auto *qt = get("HeatTop", 1), *qb = get("HeatBottom", 1), *vol = get("Volume", 1);
    const auto *h = get("SmoothingLength", 1), *xi = get("RsstFactor", 1), *r0 = get("ReferenceDensity", 1);
    for (std::size_t i = 0; i < ps_.size(); ++i) {
      auto& q = ps_[i];
      q.s1 = s1->data[i], q.rho1 = r1->data[i], q.rho = rho->data[i];
      q.acc = {a->data[3 * i], a->data[3 * i + 1], a->data[3 * i + 2]};
      q.ds1 = ds->data[i], q.drho1 = dr->data[i], q.qtop = qt->data[i], q.qbot = qb->data[i], q.vol = vol->data[i];
      q.h = h->data[i], q.xi = xi->data[i], q.rho0 = r0->data[i];
    }
    interactions_ = std::uint64_t(at.get_int("stratified.interactions"));
  }

 private:
  /// Rows of particles whose spacing follows the reference density, a(z) = (m /
  /// rho0(z))^(1/D): the row edges are where int_0^z rho0^(1/D) reaches k/nz of its
  /// total; a row of thickness a holds round(L / a) particles per horizontal direction,
  /// each with the exact mass of its cell of the reference state.
  void lattice() {
    const int nt = 4096;
    std::vector<double> cum(std::size_t(nt) + 1, 0.0);
    for (int i = 0; i < nt; ++i) {  // midpoint rule on a fine grid
      const double z = (i + 0.5) / nt;
      cum[std::size_t(i) + 1] = cum[std::size_t(i)] + std::pow(p_.rho0(z), 1.0 / D) / nt;
    }
    auto inverse = [&](double f) {  // z with cum(z) = f cum(1)
      const double target = f * cum.back();
      const auto it = std::lower_bound(cum.begin(), cum.end(), target);
      const std::size_t k = std::size_t(std::max<std::ptrdiff_t>(it - cum.begin(), 1));
      const double w = (target - cum[k - 1]) / (cum[k] - cum[k - 1]);
      return (double(k - 1) + w) / nt;
    };
    auto mass_between = [&](double a, double b) {  // int_a^b rho0 dz, Simpson
      const int n = 64;
      double s = 0;
      for (int i = 0; i <= n; ++i) {
        const double z = a + (b - a) * i / n, w = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
        s += w * p_.rho0(z);
      }
      return s * (b - a) / (3 * n);
    };
    std::uint32_t id = 0;
    for (int k = 0; k < p_.nz; ++k) {
      const double z0 = k == 0 ? 0.0 : inverse(double(k) / p_.nz), z1 = k + 1 == p_.nz ? 1.0 : inverse(double(k + 1) / p_.nz);
      const double a = z1 - z0, zc = 0.5 * (z0 + z1);
      const int nx = std::max(1, int(std::lround(width_ / a)));
      const int ny = D == 3 ? nx : 1;
      const double dxh = width_ / nx, m = mass_between(z0, z1) * std::pow(dxh, D - 1);
      for (int jy = 0; jy < ny; ++jy)
        for (int ix = 0; ix < nx; ++ix) {
          P q;
          const double x = (ix + 0.5) * dxh, y = (jy + 0.5) * dxh;
          q.id = id++, q.mass = m;
          if constexpr (D == 2) q.pos = {x, zc, 0};
          else q.pos = {x, y, zc};
          // the initial perturbation, in pressure balance (p1 = 0): rho1 = -rho0 s1 / c_p
          double mode = std::cos(M_PI * x / width_);
          if constexpr (D == 3) mode *= std::cos(M_PI * y / width_);
          q.s1 = p_.amplitude * p_.delta * p_.cp() * mode * std::sin(M_PI * zc);
          q.rho0 = p_.rho0(zc), q.t0 = p_.t0(zc), q.p0 = p_.p0(zc);
          q.rho1 = -q.rho0 * q.s1 / p_.cp();
          q.rho = q.rho0, q.vol = m / q.rho0;
          q.h = p_.hfac * std::pow(q.vol, 1.0 / D);
          ps_.add(q);
        }
    }
  }

  void reflect(P& q) const {
    auto x = q.getPos();
    for (int d = 0; d < D; ++d) {
      const double lo = walls_.box().lo[d], hi = walls_.box().hi[d];
      if (x[d] < lo) x[d] = 2 * lo - x[d], q.vel[d] = -q.vel[d], q.vel_half[d] = -q.vel_half[d];
      if (x[d] > hi) x[d] = 2 * hi - x[d], q.vel[d] = -q.vel[d], q.vel_half[d] = -q.vel_half[d];
    }
    q.setPos(x);
  }

  Params p_;
  pik::ParticleSystem<P> ps_;
  pik::sph::Walls<D> walls_;
  DensityTree density_tree_;
  ForceTree force_tree_;
  typename K::Density density_;
  typename K::Rsst rsst_;
  double width_ = 1, area_ = 1;
  std::size_t n_images_ = 0;
  std::uint64_t interactions_ = 0;
};

}  // namespace stratified
