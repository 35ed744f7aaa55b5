/// \file StratifiedMain.hpp
/// \brief `convection --setup stratified`: the command line and the run of the stratified
///        (polytropic) convection layer with the reduced speed of sound technique
///        (Stratified.hpp; docs/convection-stratified.md).
#pragma once

#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <pik/io/CommandLine.hpp>
#include <pik/pik.hpp>
#include <pik/sph/Driver.hpp>

#include "Stratified.hpp"
#include "StratifiedKernels.hpp"

namespace stratified {

/// True when the command line asks for the stratified layer (--setup stratified or
/// --setup=stratified).
inline bool requested(int argc, char** argv) {
  for (int a = 1; a < argc; ++a) {
    if (std::strcmp(argv[a], "--setup=stratified") == 0) return true;
    if (std::strcmp(argv[a], "--setup") == 0 && a + 1 < argc && std::strcmp(argv[a + 1], "stratified") == 0) return true;
  }
  return false;
}

template <int D, class K>
int run(const Params& prm, const pik::sph::RunParams& rp) {
  Model<D, K> model(prm);
  const auto& ps = model.particles();
  std::printf("convection --setup stratified: %dD polytropic layer, gamma %.4g, density contrast %g (g = %.4g), "
              "Ra %g, Pr %g, superadiabaticity %g; %zu particles (%d rows), kernel %s (%s), h = %g spacings, %d threads\n",
              D, prm.gamma, prm.chi, prm.g(), prm.ra, prm.prandtl, prm.delta, ps.size(), prm.nz,
              pik::sph::shape_name(prm.shape), K::Rsst::isa_name(), prm.hfac, pik::detail::max_threads());
  std::printf("  nu %.4g, kappa %.4g (diffusion time %.4g); sound speed %.4g (top) to %.4g (bottom); RSST factor %g (%s) "
              "-> reduced sound speed %.4g to %.4g; estimated v_rms %.3g (Mach %.3g reduced); t_end %g\n",
              prm.nu(), prm.kappa(), 1 / prm.kappa(), prm.sound(1), prm.sound(0), prm.rsst, prm.rsst_law.c_str(),
              prm.sound(1) / prm.xi(1), prm.sound(0) / prm.xi(0), prm.v_estimate(), prm.v_estimate() * prm.xi(1) / prm.sound(1),
              prm.t_end);
  if (prm.filter > 0) std::printf("  acoustic filter %g: p1 / c_s^2 relaxes to its kernel average at %g (c_s / xi) / h\n", prm.filter, prm.filter);
  pik::sph::Driver<Model<D, K>> driver(model, rp);
  if (rp.restart.empty()) {
    model.compute();
    const auto lim = model.limits();
    std::printf("  time step %.4g limited by %s (", lim.dt(), lim.limiter().c_str());
    for (const auto& [n, v] : lim.all()) std::printf(" %s %.3g", n.c_str(), v);
    std::printf(" )\n");
  }
  driver.run();
  const State s = model.state();
  std::printf("final: t = %.5g after %ld steps (%.1f s, %.3g particle-steps/s; last step %.4g limited by %s)\n",
              driver.time(), driver.steps(), driver.seconds(),
              double(ps.size()) * double(driver.steps()) / std::max(driver.seconds(), 1e-9), driver.last_dt(),
              driver.limiter().c_str());
  std::printf("final: Nu top %.5f bottom %.5f  v_rms %.6g (%.5g kappa/d)  Ma max %.3g\n", s.nu_top, s.nu_bot, s.vrms, s.pe, s.ma);
  for (const auto& w : model.validity(s)) std::printf("warning: %s\n", w.c_str());
  return 0;
}

template <int D>
int dispatch(const Params& prm, const pik::sph::RunParams& rp) {
  if (prm.shape == pik::sph::Shape::wendland2) return run<D, Kernels<D, 1>>(prm, rp);
  return run<D, Kernels<D, 2>>(prm, rp);
}

/// The program: options, checks, the run.
inline int program(int argc, char** argv) try {
  pik::io::CommandLine cli(
      "convection --setup stratified",
      "Convection in a stratified, compressible (polytropic) layer by explicit SPH with the reduced speed of sound "
      "technique (Hotta, Rempel & Yokoyama 2012): perturbations about an adiabatic hydrostatic reference state, "
      "continuity slowed by 1/xi^2. Units: depth 1, gas constant 1, T = 1 at the top; times in d / sqrt(R T_top).");
  cli.option("--setup", "stratified", "stratified (this), or boussinesq (the Blankenbach benchmark: convection --help)", "S");
  cli.option("--dim", "2", "2 (an x-z plane) or 3 (a box aspect x aspect x 1)", "D");
  cli.option("--ra", "1e4", "Rayleigh number g delta d^3 / (nu kappa)", "RA");
  cli.option("--prandtl", "1", "Prandtl number nu / kappa (> 0)", "PR");
  cli.option("--delta", "5e-4", "superadiabaticity: the entropy drop Delta s / c_p across the layer (sets the Mach number)", "D");
  cli.option("--chi", "3", "density contrast rho0(bottom) / rho0(top) of the adiabatic reference polytrope (> 1)", "X");
  cli.option("--gamma", "1.6666666666666667", "ratio of the specific heats (the polytropic index is 1 / (gamma - 1))", "G");
  cli.option("--rsst", "1", "RSST factor xi (>= 1): d rho1/dt = -(1/xi^2) div(rho0 v), sound xi times slower", "XI");
  cli.option("--rsst-law", "constant", "constant, or uniform (xi(z) = xi c_s(z) / c_s(top): one reduced sound speed)", "LAW");
  cli.option("--nz", "16", "resolution: particle rows across the depth (the spacing follows rho0^(-1/D))", "N");
  cli.option("--aspect", "2", "aspect ratio: box width / depth", "L");
  cli.option("--kernel", "wendland2", "smoothing function: wendland2 or wendland4", "K");
  cli.option("--hfac", "4", "support radius in local particle spacings", "H");
  cli.option("--amplitude", "0.5", "initial s1 = A Delta s cos(pi x / L) sin(pi z), in pressure balance", "A");
  cli.option("--cfl", "0.1", "Courant factor (reduced sound speed + |v|, on the support radius)", "C");
  cli.option("--cdiff", "0.025", "diffusion step factor (viscosity, conduction: C h^2 / D)", "C");
  cli.option("--shift", "2", "particle shifting strength A (Lind et al. 2012; 0: off)", "A");
  cli.option("--t-end", "400", "end time in d / sqrt(R T_top)", "T");
  cli.option("--snapshots", "10", "snapshots evenly in time (and the initial one); 0: only the final", "N");
  cli.option("--checkpoint-every", "0", "steps between checkpoints (0: at the end only)", "N");
  cli.option("--log-every", "1", "a row of out/log.txt every N steps (and at every output, checkpoint and the last step); 1: every step", "N");
  cli.option("--max-steps", "0", "stop after this many steps (0: no limit)", "N");
  cli.option("--format", "binary", "snapshot format: ascii, binary or hdf5", "F");
  cli.option("--restart", "", "continue from this checkpoint (same parameters)", "FILE");
  cli.option("--gauge", "mean", "reduced pressure w = p1 / rho0 in the pressure sum: mean (less its volume mean, the adjoint "
             "of the int rho1 dV correction) or absolute (as is; the scheme of session 3)", "G");
  cli.option("--filter", "0", "acoustic filter strength alpha in [0, 2]: p1 / c_s^2 relaxes to its kernel average at the rate "
             "alpha (c_s / xi) / h (particle-scale pressure noise; 0: off)", "A");
  cli.option("--out", "stratified_out", "output directory", "DIR");
  cli.parse(argc, argv);

  Params p;
  p.dim = int(cli.count("--dim")), p.ra = cli.real("--ra"), p.prandtl = cli.real("--prandtl");
  p.delta = cli.real("--delta"), p.chi = cli.real("--chi"), p.gamma = cli.real("--gamma");
  p.rsst = cli.real("--rsst"), p.rsst_law = cli.str("--rsst-law"), p.nz = int(cli.count("--nz"));
  p.aspect = cli.real("--aspect"), p.hfac = cli.real("--hfac"), p.amplitude = cli.real("--amplitude");
  p.cfl = cli.real("--cfl"), p.cdiff = cli.real("--cdiff"), p.shift = cli.real("--shift"), p.t_end = cli.real("--t-end");
  p.gauge = cli.str("--gauge"), p.filter = cli.real("--filter");
  std::vector<std::string> warnings;
  try {
    p.shape = pik::sph::shape_from_name(cli.str("--kernel"));
    if (p.shape != pik::sph::Shape::wendland2 && p.shape != pik::sph::Shape::wendland4)
      throw pik::Error("the stratified layer has the wendland2 and wendland4 smoothing functions, not '" +
                       cli.str("--kernel") + "'");
    warnings = p.check();
  } catch (const pik::Error& e) {
    cli.fail(e.what());
  }
  for (const auto& w : warnings) std::fprintf(stderr, "convection: warning: %s\n", w.c_str());

  pik::sph::RunParams rp;
  rp.t_end = p.t_end, rp.snapshots = int(cli.count("--snapshots")), rp.out = cli.str("--out");
  rp.max_steps = long(cli.count("--max-steps")), rp.checkpoint_every = long(cli.count("--checkpoint-every"));
  rp.log_every = long(cli.count("--log-every"));
  if (rp.log_every < 1) cli.fail("--log-every must be at least 1");
  rp.format = pik::io::format_from_name(cli.str("--format")), rp.restart = cli.str("--restart");
  return p.dim == 2 ? dispatch<2>(p, rp) : dispatch<3>(p, rp);
} catch (const std::exception& e) {
  std::fprintf(stderr, "convection: error: %s\n", e.what());
  return 1;
}

}  // namespace stratified
