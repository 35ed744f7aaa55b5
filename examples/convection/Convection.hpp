/// \file Convection.hpp
/// \brief Thermal convection of a very viscous fluid in a box heated from below (the
///        Blankenbach et al. 1989 benchmark), by fully explicit SPH with the variable
///        inertia method (VIM) and the reduced speed of sound technique (RSST): the
///        parameters, the initial state and the model the shared SPH driver runs.
///
/// Units (Blankenbach et al. 1989, Geophys. J. Int. 98, 23): depth d = 1, thermal
/// diffusivity kappa = 1, temperature drop Delta T = 1, reference (surface) viscosity
/// eta_0 = 1, rho c_p = 1; times in d^2 / kappa, velocities in kappa / d, stresses in
/// eta_0 kappa / d^2. The Boussinesq equations then read
///
///   (xi / Pr) dv/dt = -grad p + (1/c) div(eta grad v) + Ra (T - Tbar(z)) e_z
///   dT/dt           = c lap T
///   d rho1/dt       = -(rho_0 / f^2) div v,   p = p_bg + K rho1 / rho_0
///
/// Pr = eta_0 / (rho_0 kappa) is the physical Prandtl number (~1e25 in the mantle; the
/// benchmark's infinite-Prandtl limit), xi >= 1 the VIM inertia factor and c >= 1 the VIM
/// viscosity/conduction factor (Takeyama, Saitoh & Makino 2017, New Astronomy:
/// xi rho dv/dt = -grad p + ... + (1/c) div Pi, rho c_p dT/dt = div(c k grad T); Ra is
/// unchanged and the evolution runs c times faster, so the code time t is t_phys / c and
/// velocities are c v_phys). f >= 1 is the RSST factor of the continuity equation (Hotta,
/// Rempel & Yokoyama 2012, A&A 539, A30: d rho1/dt = -(1/f^2) div(rho_0 v)): sound
/// moves f times slower. K is the bulk modulus (artificial compressibility of the
/// Boussinesq fluid). Tbar(z), the horizontal mean temperature at the particle's height,
/// is the hydrostatic reference state of RSST: a force that depends on z alone is a
/// gradient and changes nothing in an incompressible flow, but subtracting it keeps the
/// large hydrostatic pressure out of the compressible part.
///
/// The modified numbers (Takeyama et al. 2017): Pr' = eta / (c^2 rho_I) with the
/// inertia density rho_I = xi / Pr, Re = c rho_I |v| d / eta, Ma = |v| / c_s with the reduced
/// sound speed c_s = sqrt(K / (f^2 rho_I)). The results are those of the infinite-Prandtl
/// equations while Pr' > 10, Re < 1 and Ma < 1. Only xi c^2 enters Pr' and Re.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <pik/comm/Comm.hpp>
#include <pik/domain/DomainInfo.hpp>
#include <pik/domain/ParticleExchange.hpp>
#include <pik/domain/ShortRangeHalo.hpp>
#include <pik/io/Snapshot.hpp>
#include <pik/pik.hpp>
#include <pik/sph/Parallel.hpp>
#include <pik/sph/Smoothing.hpp>
#include <pik/sph/TimeStep.hpp>
#include <pik/sph/Walls.hpp>

#include "ConvectionTypes.hpp"

namespace convection {

/// Blankenbach et al. (1989) reference values (their best estimates, Table 9): Nusselt
/// number and rms velocity (kappa / d). 1a and 1c as quoted in issue 12; 1b and 2a (Ra = 1e4
/// with the viscosity at T = 0, eta = exp(-ln(1000) T)) as tabulated from Blankenbach's
/// Table 9 by Wilson & van Keken (2023, Prog. Earth Planet. Sci. 10, doi:10.1186/s40645-023-00588-6)
/// and in ASPECT's benchmarks/blankenbach/reference_statistics.txt (both read for this).
struct Reference {
  const char* name;
  double ra, contrast, nu, vrms;
};
inline constexpr Reference blankenbach[] = {
    {"1a", 1e4, 1, 4.884409, 42.864947},
    {"1b", 1e5, 1, 10.534095, 193.21454},
    {"1c", 1e6, 1, 21.972465, 833.98977},
    {"2a", 1e4, 1e3, 10.0660, 480.4334},
};

/// Run parameters (the command line's options).
struct Params {
  int dim = 2;
  double ra = 1e4;
  std::string law = "constant";  // viscosity law: constant, or exp (eta = exp(-b T), b = ln contrast)
  double contrast = 1;           // eta(T = 0) / eta(T = 1) for the exp law
  double aspect = 1;             // box width / depth (both horizontal directions in 3D)
  int nz = 32;                   // particles across the depth
  double xi = 2.5e24;            // VIM inertia factor (>= 1)
  std::string xi_law = "constant";  // constant, or viscosity: xi_i = xi eta_i / eta_0
  double c = 1;                  // VIM factor: viscosity / c, conductivity * c (>= 1)
  double rsst = 1;               // RSST factor f (>= 1)
  std::string rsst_law = "constant";  // constant, or viscosity: f_i = f sqrt(eta(0) / eta_i) (with --xi-law viscosity: uniform sound speed)
  double prandtl = 0;            // physical Prandtl number; 0: Blankenbach's mantle, 2.5e29 / Ra
  double bulk = 0;               // bulk modulus K; 0: 130 Ra (K = 1.3e11 Pa with the benchmark's parameters)
  std::string volume = "ssph";   // volume element: ssph (X = m) or disph (X = p V; needs p > 0)
  pik::sph::Shape shape = pik::sph::Shape::wendland2;
  double hfac = 4.0;             // support radius / particle spacing
  double cfl = 0.1, cdiff = 0.025, cacc = 0.25;
  double amplitude = 0.1;        // initial perturbation of T
  std::string mode = "cell";     // 3D initial mode: cell, cos(pi x / L) cos(pi y / L); roll, cos(pi x / L) (uniform in y)
  double p_bg = 0;               // background pressure; 0: Ra (DISPH, which needs p > 0) or Ra / 10
  std::string reference = "horizontal";  // buoyancy reference: horizontal (mean T at z) or constant (1/2)
  double t_end = 0.3;            // in diffusion times d^2 / kappa (c times the code time)
  std::optional<double> shift;  // particle shifting strength A (0: off; Skillen et al. 2013: 2);
                                // none (--shift auto): shift_strength() picks it from the viscosity law
  std::string pressure = "auto";  // pressure force: difference, -V_i sum_j V_j (p_j - p_i) grad W_ij(h_i)
                                  // (zero for a uniform p); symmetric, the conservative SPH pair form; auto (below)
  std::string drift = "auto";     // the volume-weighted mean of div v: remove (a closed box keeps its volume), keep, auto
  std::string stress = "auto";   // viscous term: full, div(eta (grad v + grad v^T)); morris, div(eta grad v) only;
                                 // symmetric, two passes: e_i per particle, then sum_j V_i V_j eta_ij (e_i + e_j) . grad W_ij;
                                 // split, Morris for div(eta grad v) and the two passes for the rest (e = G^T - 2/3 tr G);
                                 // local, Morris and (grad eta) . e at each particle from the force pass's corrected
                                 // gradients (no second pass, no pair viscosity);
                                 // auto (below)

  double pr() const { return prandtl > 0 ? prandtl : 2.5e29 / ra; }
  /// `auto`: difference / remove for a constant viscosity (case 1: errors halved, docs/convection.md
  /// "2026-12-05"), symmetric / keep for a variable one (case 2a at 16 across blew up with the
  /// difference form and compressed by 24 % with the drift removed; the form it was run with before).
  std::string pressure_force() const { return pressure != "auto" ? pressure : law == "constant" ? "difference" : "symmetric"; }
  /// `auto`: local for a variable viscosity (case 2a: the closest to the converged solution at 16
  /// and 32 across, docs/convection.md, sixth 2026-12-05 session; full blows up), full (= morris)
  /// for a constant one.
  std::string stress_mode() const { return stress != "auto" ? stress : law == "constant" ? "full" : "local"; }
  /// --stress local with a variable viscosity: (grad eta) . e taken at each particle (for a
  /// constant one the term vanishes and is not computed).
  bool local_stress() const { return stress_mode() == "local" && law != "constant"; }
  /// `auto`: A = 2 for a constant viscosity (it halves case 1a's error), off for a variable
  /// one (case 2a: every shifting variant tried leaves v_rms 14-17 % low at 32 across, none
  /// 2 %; docs/convection.md, 2026-12-06, second session).
  double shift_strength() const { return shift ? *shift : law == "constant" ? 2.0 : 0.0; }
  std::string volume_drift() const { return drift != "auto" ? drift : law == "constant" ? "remove" : "keep"; }
  double k_bulk() const { return bulk > 0 ? bulk : 130 * ra; }
  /// A background pressure far above the buoyancy stresses (~ Ra) pins the particles in
  /// their lattice (a yield stress of order p_bg times the lattice error); DISPH needs
  /// p > 0 everywhere: with Ra (the default until 2026-12-06) and 10 Ra the convective
  /// pressure of case 1a goes negative, 100 Ra runs (docs/convection.md, volume element).
  double pbg() const { return p_bg > 0 ? p_bg : volume == "disph" ? 100 * ra : 0.1 * ra; }
  double b() const { return law == "exp" ? std::log(contrast) : 0.0; }
  double viscosity(double t) const { return law == "exp" ? std::exp(-b() * t) : 1.0; }
  double eta_min() const { return viscosity(1.0); }
  /// Inertia density rho_I = xi_i / Pr of a particle with viscosity eta.
  double inertia(double eta) const { return (xi_law == "viscosity" ? xi * eta : xi) / pr(); }
  double modified_pr(double eta) const { return eta / (c * c * inertia(eta)); }
  /// Reduced sound speed sqrt(K / (f^2 rho_I)) in code units.
  /// RSST factor of a particle with viscosity eta (Hotta et al. 2012: it may vary in space).
  double rsst_factor(double eta) const { return rsst_law == "viscosity" ? rsst / std::sqrt(eta) : rsst; }
  double sound_speed(double eta) const { return std::sqrt(k_bulk() / inertia(eta)) / rsst_factor(eta); }

  /// Refuses impossible parameters; returns warnings for validity conditions that an
  /// estimate of the flow speed (v_rms ~ 0.113 Ra^0.645, the power law through
  /// Blankenbach's cases 1a and 1c) says will be broken, and throws when one is broken
  /// by two orders of magnitude.
  std::vector<std::string> check() const;
};

inline std::vector<std::string> Params::check() const {
  auto need = [](bool ok, const std::string& what) {
    if (!ok) throw pik::Error(what);
  };
  need(dim == 2 || dim == 3, "the dimension must be 2 or 3");
  need(ra > 0 && std::isfinite(ra), "the Rayleigh number must be positive");
  need(law == "constant" || law == "exp", "the viscosity law must be constant or exp, not '" + law + "'");
  need(contrast > 0, "the viscosity must be positive: a viscosity contrast must be above 0");
  need(law == "exp" || contrast == 1, "a viscosity contrast needs --viscosity exp");
  need(aspect > 0 && std::isfinite(aspect), "the aspect ratio must be positive");
  need(nz >= 4, "at least 4 particles across the depth (an empty or one-row box has no convection)");
  const double ncol = std::round(aspect * nz);
  need(ncol >= 1, "the box is empty: aspect ratio x resolution gives no particle column");
  need(ncol <= 4096 && nz <= 4096 && (dim == 2 || ncol * ncol * nz <= 2e7), "too many particles for one machine");
  need(xi >= 1, "the VIM inertia factor xi must be at least 1 (it enlarges the inertia)");
  need(xi_law == "constant" || xi_law == "viscosity", "--xi-law must be constant or viscosity");
  need(c >= 1, "the VIM factor c must be at least 1");
  need(rsst >= 1, "the RSST factor must be at least 1 (it reduces the sound speed)");
  need(rsst_law == "constant" || rsst_law == "viscosity", "--rsst-law must be constant or viscosity");
  need(prandtl >= 0 && bulk >= 0 && p_bg >= 0, "Prandtl number, bulk modulus and background pressure must not be negative");
  need(volume == "disph" || volume == "ssph", "the volume element must be disph or ssph");
  need(hfac >= 1.5 && hfac <= 6, "the support radius must be 1.5 to 6 particle spacings");
  need(cfl > 0 && cfl <= 1 && cdiff > 0 && cdiff <= 0.5 && cacc > 0 && cacc <= 1, "time-step factors out of range");
  need(amplitude >= 0 && amplitude < 1, "the initial perturbation must be in [0, 1)");
  need(mode == "cell" || mode == "roll", "--mode must be cell or roll, not '" + mode + "'");
  need(reference == "horizontal" || reference == "constant", "--reference must be horizontal or constant");
  need(t_end > 0, "the end time must be positive");
  need(!shift || (*shift >= 0 && *shift <= 10), "the particle shifting strength must be auto or in [0, 10]");
  need(stress == "auto" || stress == "full" || stress == "morris" || stress == "symmetric" || stress == "split" ||
           stress == "local",
       "--stress must be auto, full, morris, symmetric, split or local");
  need(pressure == "auto" || pressure == "difference" || pressure == "symmetric",
       "--pressure-force must be auto, difference or symmetric");
  need(drift == "auto" || drift == "remove" || drift == "keep", "--volume-drift must be auto, remove or keep");

  std::vector<std::string> warn;
  const double v = 0.113 * std::pow(ra, 0.645) * std::sqrt(std::max(contrast, 1.0));  // kappa / d
  const double prm = modified_pr(eta_min()), re = v / prm;
  const double ma = c * v / sound_speed(eta_min());
  auto cond = [&](double value, double limit, bool above, const char* what) {
    const bool broken = above ? value < limit : value > limit;
    const double factor = above ? limit / value : value / limit;
    char buf[256];
    std::snprintf(buf, sizeof buf, "%s = %.3g (needs %s %g; Takeyama et al. 2017)", what, value, above ? ">" : "<", limit);
    if (broken && factor > 100) throw pik::Error(std::string("validity condition broken by orders of magnitude: ") + buf);
    if (broken) warn.push_back(std::string("validity condition broken: ") + buf);
  };
  cond(prm, 10, true, "modified Prandtl number");
  cond(re, 1, false, "estimated Reynolds number");
  cond(ma, 1, false, "estimated Mach number");
  return warn;
}

/// Diagnostics of the current state.
struct State {
  /// drho: the largest volume strain |int div v dt| = f^2 |rho1| (the compression the
  /// particles see; RSST slows the pressure's response, not the particles' motion)
  double nu_top = 0, nu_bot = 0, vrms = 0, pr = 0, re = 0, ma = 0, drho = 0, tmean = 0;
  /// Nusselt number from the volume average of the vertical heat flux: in a steady state
  /// the horizontally integrated flux w T - dT/dz is Nu at every height, so its mean over
  /// the depth is Nu = <w T> + Delta T / d = <w T> + 1 (equal to the wall values only
  /// once steady; a measure independent of the wall discretisation).
  double nu_vol = 0;
  /// The heat particle shifting added in the last step (its temperature correction T +=
  /// grad T . dr is not conservative), per unit wall area and time in the units of Nu: d<T>/dt
  /// = Nu_bot - Nu_top + Nu_shift (time in d^2 / kappa), so a steady state has Nu_bot - Nu_top
  /// = -Nu_shift.
  double nu_shift = 0;
};

/// Horizontal mean temperature at height z: particles are deposited on nbin layers with
/// linear (cloud-in-cell) weights and the mean is interpolated linearly, so it changes
/// smoothly as particles move between layers.
class LayerMean {
 public:
  /// `reduce` (optional) sums the per-layer sums over ranks in place (MPI: every rank
  /// holds a part of the particles).
  void fit(const std::vector<double>& z, const std::vector<double>& t, int nbin,
           const std::function<void(std::span<double>)>& reduce = {}) {
    n_ = nbin;
    std::vector<double> s(std::size_t(nbin), 0.0), w(std::size_t(nbin), 0.0);
    for (std::size_t i = 0; i < z.size(); ++i) {
      const double x = std::clamp(z[i] * nbin - 0.5, 0.0, double(nbin - 1));
      const int b = std::min(int(x), nbin - 1), b1 = std::min(b + 1, nbin - 1);
      const double f = x - b;
      s[std::size_t(b)] += (1 - f) * t[i], w[std::size_t(b)] += 1 - f;
      s[std::size_t(b1)] += f * t[i], w[std::size_t(b1)] += f;
    }
    if (reduce) {
      std::vector<double> sw(s);
      sw.insert(sw.end(), w.begin(), w.end());
      reduce(std::span<double>(sw));
      std::copy(sw.begin(), sw.begin() + nbin, s.begin());
      std::copy(sw.begin() + nbin, sw.end(), w.begin());
    }
    mean_.assign(std::size_t(nbin), 0.5);
    for (int b = 0; b < nbin; ++b)
      if (w[std::size_t(b)] > 0) mean_[std::size_t(b)] = s[std::size_t(b)] / w[std::size_t(b)];
  }
  double operator()(double z) const {
    const double x = std::clamp(z * n_ - 0.5, 0.0, double(n_ - 1));
    const int b = std::min(int(x), n_ - 1), b1 = std::min(b + 1, n_ - 1);
    const double f = x - b;
    return (1 - f) * mean_[std::size_t(b)] + f * mean_[std::size_t(b1)];
  }

 private:
  int n_ = 1;
  std::vector<double> mean_{0.5};
};

/// The model the shared driver (pik/sph/Driver.hpp) runs. K: the kernel classes of one
/// dimension and smoothing function (K::Density, K::Viscous).
///
/// Under MPI (more than one rank in `comm`) each rank starts with an equal share of the
/// lattice (in id order, as the driver's restart expects), the domains are cut once from
/// that lattice (pik::DomainInfo; a nearly incompressible flow keeps the particle count
/// of a fixed region, so the cut stays balanced, and every run of one rank count uses
/// the same cut, which makes a restart continue bit for bit), and every compute() moves
/// the particles to their owners (sorted by id, so the order on a rank depends only on
/// which particles it holds), imports the halo within the search radius
/// (pik::ShortRangeHalo) before each of the two passes and mirrors local and halo
/// particles across the walls. Sums (Nu, v_rms, the layer means) and extrema (the
/// validity numbers, the step limits) are global. One rank: exactly the single-process
/// code path.
template <int D, class K>
class Model {
  using P = Particle<D>;
  using E = EP<D>;
  using DensityTree = pik::ShortRangeTree<DensityResult, E, E, pik::SearchMode::gather>;
  using ForceTree = pik::ShortRangeTree<ViscousResult, E, E, pik::SearchMode::symmetric>;
  using SE = SEP<D>;
  using StressTree = pik::ShortRangeTree<StressResult, SE, SE, pik::SearchMode::symmetric>;
  using GradTree = pik::ShortRangeTree<GradResult, SE, SE, pik::SearchMode::symmetric>;

 public:
  Model(const Params& prm, const pik::Comm& comm)
      : p_(prm), comm_(comm), dinfo_(comm), density_tree_({.n_leaf_limit = 8, .n_group_limit = 32}),
        force_tree_({.n_leaf_limit = 8, .n_group_limit = 32}), stress_tree_({.n_leaf_limit = 8, .n_group_limit = 32}),
        grad_tree_({.n_leaf_limit = 8, .n_group_limit = 32}), density_(),
        viscous_(float(prm.c), prm.pressure_force() == "difference" ? 1.0f : 0.0f) {
    const int nz = prm.nz, nx = int(std::round(prm.aspect * nz)), ny = D == 3 ? nx : 1;
    dx_ = 1.0 / nz;
    width_ = nx * dx_;  // the box closes the lattice exactly
    pik::Box<double, D> box;
    for (int d = 0; d < D; ++d) box.lo[d] = 0, box.hi[d] = d == D - 1 ? 1.0 : width_;
    walls_ = pik::sph::Walls<D>(box);
    using Kind = pik::sph::WallFace::Kind;
    for (int d = 0; d < D - 1; ++d)  // reflecting, insulating side walls
      walls_.set_axis(d, {Kind::free_slip, false, 0}, {Kind::free_slip, false, 0});
    walls_.set_axis(D - 1, {Kind::free_slip, true, 1.0}, {Kind::free_slip, true, 0.0});  // hot bottom, cold top
    h_ = prm.hfac * dx_;
    const double m = std::pow(dx_, D);
    std::uint32_t id = 0;
    for (int k = 0; k < ny; ++k)
      for (int j = 0; j < nz; ++j)
        for (int i = 0; i < nx; ++i) {
          P q;
          const double x = (i + 0.5) * dx_, z = (j + 0.5) * dx_, y = (k + 0.5) * dx_;
          q.id = id++, q.mass = m, q.h = h_;
          if constexpr (D == 2) q.pos = {x, z, 0};
          else q.pos = {x, y, z};
          // Blankenbach et al. (1989), sec. 3: T = 1 - z + A cos(pi x / lambda) sin(pi z)
          // (3D: the product of the two horizontal cosines, or with --mode roll the 2D
          // roll, uniform in y: an exact solution of the 3D equations in a free-slip box)
          double mode = std::cos(M_PI * x / width_);
          if constexpr (D == 3) {
            if (prm.mode == "cell") mode *= std::cos(M_PI * y / width_);
          }
          q.temp = 1 - z + prm.amplitude * mode * std::sin(M_PI * z);
          q.rho = 1, q.vol = m;
          ps_.add(q);
        }
    if (ps_.empty()) throw pik::Error("the box holds no particles");
    area_ = std::pow(width_, D - 1);
    n_total_ = ps_.size();
    if (comm_.size() > 1) {
      const auto [a, b] = pik::sph::equal_share(ps_.size(), comm_.rank(), comm_.size());
      auto& v = ps_.vector();
      v.erase(v.begin() + std::ptrdiff_t(b), v.end());
      v.erase(v.begin(), v.begin() + std::ptrdiff_t(a));
      dinfo_.decompose(ps_.vector());
    }
  }

  /// The communicator (pik/sph/Parallel.hpp: the driver runs this model on its ranks).
  const pik::Comm& comm() const { return comm_; }
  /// Particles on all ranks.
  std::size_t total_particles() const { return n_total_; }

  pik::ParticleSystem<P>& particles() { return ps_; }
  const pik::ParticleSystem<P>& particles() const { return ps_; }
  const Params& params() const { return p_; }
  double spacing() const { return dx_; }
  double support() const { return h_; }
  std::size_t images() const { return n_images_; }
  /// Pair interactions so far, over all ranks (collective under MPI).
  std::uint64_t interactions() const { return comm_.size() > 1 ? comm_.sum(interactions_) : interactions_; }

  /// Every pass at the current state: equation of state, volume element (gather density
  /// pass with wall images), the force pass (pressure, viscosity, conduction, div v with
  /// wall images), then buoyancy and the RSST continuity equation per particle.
  void compute() {
    if (comm_.size() > 1) {
      pik::exchange_particles(ps_, dinfo_);
      auto& v = ps_.vector();
      std::sort(v.begin(), v.end(), [](const P& a, const P& b) { return a.id < b.id; });
    }
    const double cs2 = p_.k_bulk(), pbg = p_.pbg();  // rho_0 = 1
    const bool disph = p_.volume == "disph";
    const std::string stress = p_.stress_mode();
    const bool symmetric = stress == "symmetric" || stress == "split";
    const bool local = p_.local_stress();
    for (auto& q : ps_) {
      q.eta = p_.viscosity(q.temp), q.inertia = p_.inertia(q.eta), q.bvis = p_.b();
      // --stress symmetric: the Morris pair term off (its harmonic mean of ~0 underflows to 0);
      // split: Morris takes div(eta grad v), the two passes the rest (e = G^T - 2/3 tr G)
      q.eta_pair = stress == "symmetric" ? 1e-30 : q.eta;
      q.tau_g = stress == "symmetric" ? 1.0 : 0.0;
      q.pres = pbg + cs2 * q.rho1;
      if (q.pres <= 0 && disph)
        throw pik::Error("pressure of particle " + std::to_string(q.id) +
                         " is not positive (DISPH needs p > 0): raise --p-background or the bulk modulus");
      q.xw = disph ? q.pres * q.mass / q.rho : q.mass;  // X of the volume element
    }
    // volume element: Y_i = sum_j X_j W_ij (Hopkins 2013)
    n_images_ = import_j(density_tree_, density_halo_);
    density_tree_.calcForceAllAndWriteBack(density_, ps_);
    for (auto& q : ps_) {
      q.vol = q.xw / q.y;
      if (disph) q.pf = 1.0 / q.y;  // P_i = Y_i: the smoothed pressure
      else q.pf = q.pres / (q.y * q.y);
      q.rho = q.mass / q.vol;
    }
    import_j(force_tree_, force_halo_);
    if (comm_.size() == 1) {
      // Same positions and the same wall images as the density pass: its octree, no new
      // sort (the images carry this pass's volumes and pressures; the result is a build's).
      force_tree_.buildLike(density_tree_, ps_);
      force_tree_.calcForceOnTreeAndWriteBack(viscous_, ps_);
    } else {
      force_tree_.calcForceAllAndWriteBack(viscous_, ps_);
    }
    interactions_ += density_tree_.interactions() + force_tree_.interactions();
    // pass 1: the corrected velocity gradient -> e_i (copyFromForce); --stress local takes
    // it from the force pass, which sums the same terms (ViscousResult)
    if (symmetric) {
      import_j<SE>(grad_tree_, grad_halo_);
      grad_tree_.calcForceAllAndWriteBack(grad_, ps_);
      interactions_ += grad_tree_.interactions();
    }
    if (symmetric) {  // pass 2: div(eta e) in pair form
      import_j<SE>(stress_tree_, stress_halo_);
      stress_tree_.calcForceAllAndWriteBack(stress_, ps_);
      interactions_ += stress_tree_.interactions();
    }
    if (local)
      for (auto& q : ps_) q.sym_acc = q.local_transpose() * (1.0 / q.inertia);
    // buoyancy against the reference state, in the last dimension
    if (p_.reference == "horizontal") {
      std::vector<double> z, t;
      z.reserve(ps_.size()), t.reserve(ps_.size());
      for (const auto& q : ps_) z.push_back(q.pos[D - 1]), t.push_back(q.temp);
      if (comm_.size() > 1) tbar_.fit(z, t, p_.nz, [this](std::span<double> v) { pik::sph::global_sum(v, comm_); });
      else tbar_.fit(z, t, p_.nz);
    }
    // The box is closed, so the volume integral of div v vanishes; the SPH estimate's volume
    // mean does not (its zeroth-order error near the walls and in a disordered lattice), and
    // integrated by the continuity equation it becomes a uniform compression that grows
    // without bound (6 % by t = 0.04 in case 1c at 32 across, 32 % with the difference form).
    // A uniform p gives no force in the difference form but does in the symmetric one.
    if (p_.volume_drift() == "remove") {
      double sum[2] = {0, 0};
      for (const auto& q : ps_) sum[0] += q.vol * q.divv, sum[1] += q.vol;
      if (comm_.size() > 1) pik::sph::global_sum(std::span<double>(sum), comm_);
      const double mean = sum[0] / sum[1];
      for (auto& q : ps_) q.divv -= mean;
    }
    const bool full_stress = stress == "full" && p_.law != "constant";
    for (auto& q : ps_) {
      const double tref = p_.reference == "horizontal" ? tbar_(q.pos[D - 1]) : 0.5;
      q.acc[D - 1] += p_.ra * (q.temp - tref) / q.inertia;
      // the (grad eta).(grad v)^T part of div(eta (grad v + grad v^T)), with VIM's 1/c
      if (full_stress) q.acc += q.stress_acc * (1.0 / (p_.c * q.inertia));
      if (symmetric || local) q.acc += q.sym_acc * (1.0 / p_.c);
      const double f = p_.rsst_factor(q.eta);
      q.drho1 = -q.divv / (f * f);
    }
  }

  /// The time-step criteria (code time): sound (reduced speed, Courant), viscous and
  /// thermal diffusion (explicit stability, C h^2 / D) and the acceleration.
  pik::sph::StepLimits limits() const {
    pik::sph::StepLimits l;
    double vs = 0, nu = 0, amax = 0, fmin = 1e300, vt = 0;
    const bool local = p_.local_stress();
    // a particle feels its neighbours' stiffness K / f_j^2: with a variable RSST factor the
    // light (low-inertia) particles next to stiff ones set the step
    for (const auto& q : ps_) fmin = std::min(fmin, p_.rsst_factor(p_.viscosity(q.temp)));
    if (comm_.size() > 1) fmin = comm_.min(fmin);
    for (const auto& q : ps_) {
      const double eta = p_.viscosity(q.temp), rho_i = p_.inertia(eta);
      vs = std::max(vs, std::sqrt(p_.k_bulk() / rho_i) / fmin + pik::norm(q.vel));
      nu = std::max(nu, eta / (p_.c * rho_i));
      amax = std::max(amax, pik::norm(q.acc));
      // --stress local: (grad eta) . e is a first derivative of v with the coefficient
      // |grad eta| / (c rho_I), a speed: a Courant limit like the sound one
      if (local) vt = std::max(vt, p_.b() * eta * pik::norm(q.gradtc) / (p_.c * rho_i));
    }
    if (comm_.size() > 1) {
      double m[4] = {vs, nu, amax, vt};
      pik::sph::global_max(std::span<double>(m), comm_);
      vs = m[0], nu = m[1], amax = m[2], vt = m[3];
    }
    l.add("sound", pik::sph::courant(h_, vs, p_.cfl));
    l.add("viscous", pik::sph::diffusion(h_, nu, p_.cdiff));
    l.add("conduction", pik::sph::diffusion(h_, p_.c, p_.cdiff));
    l.add("acceleration", pik::sph::acceleration(h_, amax, p_.cacc));
    if (vt > 0) l.add("transpose", pik::sph::courant(h_, vt, p_.cfl));
    return l;
  }

  /// Kick-drift-kick with the temperature and the density perturbation beside v; a
  /// particle that overshoots a wall is reflected back.
  void open_step(P& q, double dt) const {
    q.vel_half = q.vel + q.acc * (0.5 * dt);
    q.temp_half = q.temp + 0.5 * dt * q.dtemp, q.rho1_half = q.rho1 + 0.5 * dt * q.drho1;
    q.pos += q.vel_half * dt;
    q.vel = q.vel_half + q.acc * (0.5 * dt);
    q.temp = q.temp_half + 0.5 * dt * q.dtemp, q.rho1 = q.rho1_half + 0.5 * dt * q.drho1;
    reflect(q);
  }
  /// The closing half kick, then (with --shift) particle shifting (Lind et al. 2012, J.
  /// Comput. Phys. 231, 1499; the step length of Skillen et al. 2013, Comput. Methods Appl.
  /// Mech. Eng. 265, 163): dr = -D grad C with D = A h |v| dt, at most a tenth of a
  /// spacing, and the temperature carried to the new position, T += grad T . dr. It keeps
  /// the particles evenly spread, where the SPH operators are accurate.
  void close_step(P& q, double dt) const {
    q.vel = q.vel_half + q.acc * (0.5 * dt);
    q.temp = q.temp_half + 0.5 * dt * q.dtemp, q.rho1 = q.rho1_half + 0.5 * dt * q.drho1;
    if (const double a = p_.shift_strength(); a > 0) {
      Vec3d dr = q.gradc * (-a * h_ * pik::norm(q.vel) * dt);
      const double len = pik::norm(dr), cap = 0.1 * dx_;
      if (len > cap) dr = dr * (cap / len);
      const double dtemp = pik::dot(q.gradt, dr);
      q.pos += dr, q.temp += dtemp, q.dtemp_shift = dtemp / dt;
      reflect(q);
    }
  }

  State state() const {
    State s;
    double vol = 0, v2 = 0, t = 0, qt = 0, qb = 0, wt = 0, qs = 0;
    s.pr = 1e300;
    for (const auto& q : ps_) {
      vol += q.vol, v2 += q.vol * pik::norm2(q.vel), t += q.vol * q.temp;
      qt += q.vol * q.qtop, qb += q.vol * q.qbot, wt += q.vol * q.vel[D - 1] * q.temp;
      qs += q.vol * q.dtemp_shift;
      const double eta = p_.viscosity(q.temp), v = pik::norm(q.vel);
      s.pr = std::min(s.pr, p_.modified_pr(eta));
      s.re = std::max(s.re, p_.c * p_.inertia(eta) * v / eta);
      s.ma = std::max(s.ma, v / p_.sound_speed(eta));
      const double f = p_.rsst_factor(eta);
      s.drho = std::max(s.drho, f * f * std::abs(q.rho1));  // volume strain: f^2 rho1
    }
    if (comm_.size() > 1) {
      double sum[7] = {vol, v2, t, qt, qb, wt, qs}, mx[4] = {-s.pr, s.re, s.ma, s.drho};
      pik::sph::global_sum(std::span<double>(sum), comm_);
      pik::sph::global_max(std::span<double>(mx), comm_);
      vol = sum[0], v2 = sum[1], t = sum[2], qt = sum[3], qb = sum[4], wt = sum[5], qs = sum[6];
      s.pr = -mx[0], s.re = mx[1], s.ma = mx[2], s.drho = mx[3];
    }
    s.vrms = std::sqrt(v2 / vol) / p_.c;  // kappa / d of the physical evolution
    s.tmean = t / vol;
    s.nu_top = -qt / (p_.c * area_), s.nu_bot = qb / (p_.c * area_);
    s.nu_vol = wt / (p_.c * vol) + 1;
    s.nu_shift = qs / (p_.c * area_);
    return s;
  }

  std::vector<std::string> diagnostic_names() const {
    return {"Nu_top", "Nu_bot", "v_rms", "T_mean", "Pr_mod", "Re", "Ma", "compression", "Nu_vol", "Nu_shift"};
  }
  /// The log's columns after step, time (code time: c times it is the time in d^2 / kappa)
  /// and dt.
  std::vector<double> diagnostics() const {
    const State s = state();
    return {s.nu_top, s.nu_bot, s.vrms, s.tmean, s.pr, s.re, s.ma, s.drho, s.nu_vol, s.nu_shift};
  }

  void report(double t, std::FILE* out) const {
    const State s = state();
    std::fprintf(out, "t = %.5g d^2/kappa  Nu top %.5f bottom %.5f volume %.5f  v_rms %.4f kappa/d  <T> %.4f  Pr' %.3g  Re %.3g  Ma %.3g  compression %.2g\n",
                 t * p_.c, s.nu_top, s.nu_bot, s.nu_vol, s.vrms, s.tmean, s.pr, s.re, s.ma, s.drho);
    for (const auto& w : validity(s)) std::fprintf(out, "  warning: %s\n", w.c_str());
  }
  /// The validity conditions of VIM and RSST at a state (Takeyama et al. 2017;
  /// Hotta et al. 2012: Ma < 0.7 against the reduced sound speed), and the density
  /// perturbation (the artificial compressibility must stay small).
  std::vector<std::string> validity(const State& s) const {
    std::vector<std::string> w;
    char b[160];
    if (s.pr < 10) std::snprintf(b, sizeof b, "modified Prandtl number %.3g < 10", s.pr), w.push_back(b);
    if (s.re > 1) std::snprintf(b, sizeof b, "Reynolds number %.3g > 1", s.re), w.push_back(b);
    if (s.ma > 0.7) std::snprintf(b, sizeof b, "Mach number %.3g > 0.7 (reduced sound speed)", s.ma), w.push_back(b);
    if (s.drho > 0.05) std::snprintf(b, sizeof b, "compression %.3g > 5 %% (raise --bulk or lower --rsst)", s.drho), w.push_back(b);
    return w;
  }

  void fill_snapshot(pik::io::Snapshot& s, bool checkpoint) const {
    auto col = [&](const char* name, auto get) {
      auto& c = s.column(name, 1);
      for (std::size_t i = 0; i < ps_.size(); ++i) c.data[i] = get(ps_[i]);
    };
    col("Temperature", [](const P& q) { return q.temp; });
    col("DensityPerturbation", [](const P& q) { return q.rho1; });
    col("Density", [](const P& q) { return q.rho; });
    col("Viscosity", [](const P& q) { return q.eta; });
    col("Pressure", [](const P& q) { return q.pres; });
    if (checkpoint) {
      auto& a = s.column("Acceleration", 3);
      for (std::size_t i = 0; i < ps_.size(); ++i)
        for (int k = 0; k < 3; ++k) a.data[3 * i + std::size_t(k)] = ps_[i].acc[std::size_t(k)];
      col("TemperatureRate", [](const P& q) { return q.dtemp; });
      col("PerturbationRate", [](const P& q) { return q.drho1; });
      col("HeatTop", [](const P& q) { return q.qtop; });
      col("HeatBottom", [](const P& q) { return q.qbot; });
      col("Volume", [](const P& q) { return q.vol; });
    }
    auto& at = s.attr;
    at.set("convection.dim", D), at.set("convection.ra", p_.ra), at.set("convection.law", p_.law);
    at.set("convection.contrast", p_.contrast), at.set("convection.aspect", p_.aspect), at.set("convection.nz", p_.nz);
    at.set("convection.xi", p_.xi), at.set("convection.xi_law", p_.xi_law), at.set("convection.c", p_.c);
    at.set("convection.rsst", p_.rsst), at.set("convection.rsst_law", p_.rsst_law), at.set("convection.prandtl", p_.pr()), at.set("convection.bulk", p_.k_bulk());
    at.set("convection.volume", p_.volume), at.set("convection.kernel", pik::sph::shape_name(p_.shape));
    at.set("convection.hfac", p_.hfac), at.set("convection.p_bg", p_.pbg()), at.set("convection.reference", p_.reference);
    at.set("convection.stress", p_.stress_mode());
    at.set("convection.pressure_force", p_.pressure_force()), at.set("convection.volume_drift", p_.volume_drift());
    at.set("convection.shift", p_.shift_strength()), at.set("convection.interactions", interactions());
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
    same("convection.dim", D), same("convection.ra", p_.ra), same_s("convection.law", p_.law);
    same("convection.contrast", p_.contrast), same("convection.aspect", p_.aspect), same("convection.nz", p_.nz);
    same("convection.xi", p_.xi), same_s("convection.xi_law", p_.xi_law), same("convection.c", p_.c);
    same("convection.rsst", p_.rsst), same_s("convection.rsst_law", p_.rsst_law), same("convection.prandtl", p_.pr()), same("convection.bulk", p_.k_bulk());
    same_s("convection.volume", p_.volume), same_s("convection.kernel", pik::sph::shape_name(p_.shape));
    same("convection.hfac", p_.hfac), same("convection.p_bg", p_.pbg()), same_s("convection.reference", p_.reference);
    same("convection.shift", p_.shift_strength());
    if (at.has("convection.stress")) same_s("convection.stress", p_.stress_mode());
    // checkpoints written before these options existed ran with the symmetric form and the drift
    auto same_or = [&](const char* key, const std::string& v, const char* old) {
      const std::string was = at.has(key) ? at.get_string(key) : std::string(old);
      if (was != v) throw pik::Error(std::string("the checkpoint was written with another ") + key + " (" + was + ")");
    };
    same_or("convection.pressure_force", p_.pressure_force(), "symmetric");
    same_or("convection.volume_drift", p_.volume_drift(), "keep");
    auto get = [&](const char* name, int comps) {
      const pik::io::Column* c = s.find(name);
      if (!c || c->components != comps) throw pik::Error(std::string("the checkpoint has no column ") + name);
      return c;
    };
    const auto *t = get("Temperature", 1), *r1 = get("DensityPerturbation", 1), *rho = get("Density", 1);
    const auto *a = get("Acceleration", 3), *dt = get("TemperatureRate", 1), *dr = get("PerturbationRate", 1);
    const auto *qt = get("HeatTop", 1), *qb = get("HeatBottom", 1), *vol = get("Volume", 1);
    for (std::size_t i = 0; i < ps_.size(); ++i) {
      auto& q = ps_[i];
      q.temp = t->data[i], q.rho1 = r1->data[i], q.rho = rho->data[i];
      q.acc = {a->data[3 * i], a->data[3 * i + 1], a->data[3 * i + 2]};
      q.dtemp = dt->data[i], q.drho1 = dr->data[i], q.qtop = qt->data[i], q.qbot = qb->data[i], q.vol = vol->data[i];
      q.eta = p_.viscosity(q.temp), q.inertia = p_.inertia(q.eta), q.h = h_;
    }
    // the run's total: kept on rank 0, so that the sum over ranks stays the total
    interactions_ = comm_.rank() == 0 ? std::uint64_t(at.get_int("convection.interactions")) : 0;
  }

 private:
  /// The imported j-particles of a pass: the wall images of the local particles (one
  /// rank: exactly as in a single process); under MPI first the halo within the search
  /// radius from the other ranks, then the images of local and halo particles (every
  /// image within reach of a local particle is an image of one of them). Returns the
  /// number of images. Collective.
  template <class J = E, class Tree, class Halo>
  std::size_t import_j(Tree& tree, Halo& halo) {
    if (comm_.size() == 1) return walls_.template attach<J>(tree, ps_, h_);
    halo.exchange(ps_, comm_, tree.boundary());
    std::vector<J> js = std::move(halo.importedParticles());
    std::vector<J> img = walls_.template images<J>(ps_, h_);
    // the halo's reach test runs on single-precision positions: a little wider
    std::vector<J> himg = walls_.template images_of<J>(std::span<const J>(js), h_ * (1 + 1e-5));
    const std::size_t n = img.size() + himg.size();
    js.insert(js.end(), img.begin(), img.end());
    js.insert(js.end(), himg.begin(), himg.end());
    tree.setImportedParticles(std::move(js));
    return n;
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
  pik::Comm comm_;
  pik::DomainInfo<double, D> dinfo_;
  pik::ShortRangeHalo<E, E, pik::SearchMode::gather> density_halo_;
  pik::ShortRangeHalo<E, E, pik::SearchMode::symmetric> force_halo_;
  pik::ShortRangeHalo<SE, SE, pik::SearchMode::symmetric> stress_halo_;
  pik::ShortRangeHalo<SE, SE, pik::SearchMode::symmetric> grad_halo_;
  std::size_t n_total_ = 0;
  pik::ParticleSystem<P> ps_;
  pik::sph::Walls<D> walls_;
  DensityTree density_tree_;
  ForceTree force_tree_;
  StressTree stress_tree_;
  GradTree grad_tree_;
  typename K::Stress stress_;
  typename K::Grad grad_;
  typename K::Density density_;
  typename K::Viscous viscous_;
  LayerMean tbar_;
  double dx_ = 0, h_ = 0, width_ = 1, area_ = 1;
  std::size_t n_images_ = 0;
  std::uint64_t interactions_ = 0;
};

}  // namespace convection
