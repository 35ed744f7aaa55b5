// convection: thermal convection of a very viscous fluid heated from below (mantle
// convection, the Blankenbach et al. 1989 benchmark) by fully explicit SPH: the variable
// inertia method (Takeyama, Saitoh & Makino 2017) and the reduced speed of sound
// technique (Hotta, Rempel & Yokoyama 2012) make the steps large without any Stokes or
// Poisson solve. Free-slip walls all round, fixed temperatures at the top (0) and bottom
// (1), insulating sides, through mirror particles (pik/sph/Walls.hpp).
//
// Pairwise work: kernels/sph_density.pik (volume element) and kernels/sph_viscous.pik
// (pressure, viscosity, conduction, div v). The run loop, output and restart are the
// shared SPH driver's (pik/sph/Driver.hpp). Equations and validation: docs/convection.md.
// Under mpirun the Boussinesq model runs on every rank (domain decomposition, halo
// exchange, global sums; docs/convection-mpi.md). Run `convection --help`.
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>

#include <pik/io/CommandLine.hpp>
#include <pik/pik.hpp>
#include <pik/sph/Driver.hpp>

#include "Convection.hpp"
#include "ConvectionKernels.hpp"
#include "Remap.hpp"  // --init: start from another run's snapshot at another resolution
#include "StratifiedMain.hpp"  // --setup stratified (the polytropic layer with RSST)

using namespace convection;

template <int D, class K>
int run(const Params& prm, const pik::sph::RunParams& rp, const pik::Comm& comm, const std::string& init,
        bool init_pressure, bool continuation) {
  // --init: read and check the old run's snapshot before the model is built (a wrong
  // file fails at once)
  std::optional<InitSource<D>> src;
  if (!init.empty()) src = read_init<D>(init, prm, continuation);
  Model<D, K> model(prm, comm);
  const std::size_t n_total = model.total_particles();
  const double cs = prm.sound_speed(prm.eta_min());
  std::printf("convection: %dD, Ra %g, viscosity %s%s, aspect %g, %zu particles (%d across the depth), kernel %s "
              "(%s), h = %.3g spacings, volume element %s, pressure force %s, volume drift %s, particle shifting %g\n",
              D, prm.ra, prm.law.c_str(),
              prm.law == "exp" ? (" (contrast " + std::to_string(prm.contrast) + ")").c_str() : "", prm.aspect,
              n_total, prm.nz, pik::sph::shape_name(prm.shape), K::Viscous::isa_name(), prm.hfac, prm.volume.c_str(),
              prm.pressure_force().c_str(), prm.volume_drift().c_str(), prm.shift_strength());
  std::printf("  VIM xi %g (%s), c %g; Pr %g -> modified Pr %.3g; RSST factor %g; K %g -> sound speed %.4g; "
              "t_end %g d^2/kappa (code time %g), %d threads%s\n",
              prm.xi, prm.xi_law.c_str(), prm.c, prm.pr(), prm.modified_pr(prm.eta_min()), prm.rsst, prm.k_bulk(), cs,
              prm.t_end, rp.t_end, pik::detail::max_threads(),
              comm.size() > 1 ? (" per rank, " + std::to_string(comm.size()) + " MPI ranks").c_str() : "");
  if (src) {
    int fewest = remap_onto<D>(model, *src, init_pressure);
    if (comm.size() > 1) fewest = comm.min(fewest);  // over every rank's particles
    std::printf("  --init %s: temperature, velocity%s of its %zu particles (%d across, t = %.5g d^2/kappa, step %llu) "
                "interpolated onto this lattice (quadratic-corrected Shepard, wall images, support %g old spacings; "
                "at least %d neighbours); positions and density this run's own; the clock starts at t = 0\n",
                src->path.c_str(), init_pressure ? " and pressure perturbation" : " (pressure perturbation 0)",
                src->samples.size(), src->nz, src->time, (unsigned long long)src->step, 2.0, fewest);
    if (src->other_problem)
      std::printf("  --init-problem continuation: the snapshot's problem is %s; its temperature and velocity are "
                  "this run's initial field\n", src->problem.c_str());
  }
  pik::sph::Driver<Model<D, K>> driver(model, rp);
  if (rp.restart.empty()) {
    model.compute();
    const auto lim = model.limits();
    std::printf("  time step %.4g limited by %s (", lim.dt(), lim.limiter().c_str());
    for (const auto& [n, v] : lim.all()) std::printf(" %s %.3g", n.c_str(), v);
    std::printf(" ); plain explicit SPH at the physical parameters (xi = c = f = 1): ");
    Params plain = prm;
    plain.xi = 1, plain.c = 1, plain.rsst = 1;
    Model<D, K> ref(plain, comm);
    ref.compute();
    const auto lp = ref.limits();
    std::printf("%.4g (%s), x%.3g\n", lp.dt(), lp.limiter().c_str(), lim.dt() * prm.c / lp.dt());
  }
  driver.run();
  const State s = model.state();
  std::printf("final: t = %.5g d^2/kappa after %ld steps (%.1f s, %.3g particle-steps/s; last step limited by %s)\n",
              driver.time() * prm.c, driver.steps(), driver.seconds(),
              double(n_total) * double(driver.steps()) / std::max(driver.seconds(), 1e-9), driver.limiter().c_str());
  std::printf("final: Nu top %.5f bottom %.5f volume %.5f  v_rms %.4f\n", s.nu_top, s.nu_bot, s.nu_vol, s.vrms);
  for (const auto& r : blankenbach)
    if (r.ra == prm.ra && r.contrast == (prm.law == "exp" ? prm.contrast : 1.0) && prm.aspect == 1 && (D == 2 || prm.mode == "roll"))
      std::printf("Blankenbach et al. (1989) case %s: Nu %.4f, v_rms %.3f -> error Nu(top) %+.2f %%, v_rms %+.2f %%\n",
                  r.name, r.nu, r.vrms, 100 * (s.nu_top / r.nu - 1), 100 * (s.vrms / r.vrms - 1));
  for (const auto& w : model.validity(s)) std::printf("warning: %s\n", w.c_str());
  return 0;
}

template <int D>
int dispatch(const Params& prm, const pik::sph::RunParams& rp, const pik::Comm& comm, const std::string& init,
             bool init_pressure, bool continuation) {
  switch (prm.shape) {
    case pik::sph::Shape::cubic: return run<D, Kernels<D, 0>>(prm, rp, comm, init, init_pressure, continuation);
    case pik::sph::Shape::wendland2: return run<D, Kernels<D, 1>>(prm, rp, comm, init, init_pressure, continuation);
    default: return run<D, Kernels<D, 2>>(prm, rp, comm, init, init_pressure, continuation);
  }
}

static std::optional<pik::Environment> environment;  // MPI, initialised after the options

int main(int argc, char** argv) try {
  // --setup stratified: the stratified layer with RSST has its own options (StratifiedMain.hpp)
  if (stratified::requested(argc, argv)) {
    if (pik::launcher_ranks() > 1) {
      std::fprintf(stderr, "convection: error: --setup stratified runs in one process only (run it without mpirun, "
                           "or with -np 1); the Boussinesq setup runs under mpirun\n");
      return 1;
    }
    return stratified::program(argc, argv);
  }
  pik::io::CommandLine cli("convection",
                           "Mantle convection (Blankenbach et al. 1989 benchmark) by explicit SPH with the variable "
                           "inertia method and the reduced speed of sound technique. Units: d = kappa = Delta T = 1.");
  cli.option("--setup", "boussinesq", "boussinesq (this benchmark), or stratified: a polytropic layer with RSST (convection --setup stratified --help)", "S");
  cli.option("--ra", "1e4", "Rayleigh number (with the viscosity at T = 0)", "RA");
  cli.option("--viscosity", "constant", "viscosity law: constant, or exp (eta = exp(-b T), b = ln contrast)", "LAW");
  cli.option("--contrast", "1", "viscosity contrast eta(0) / eta(1) of the exp law (Blankenbach case 2a: 1000)", "R");
  cli.option("--aspect", "1", "aspect ratio: box width / depth", "L");
  cli.option("--dim", "2", "2 (the benchmark's plane) or 3 (a box aspect x aspect x 1)", "D");
  cli.option("--nz", "32", "resolution: particles across the depth", "N");
  cli.option("--xi", "2.5e24", "VIM inertia factor xi (>= 1); the modified Prandtl number is Pr / (xi c^2)", "XI");
  cli.option("--xi-law", "constant", "constant, or viscosity (xi_i = xi eta_i / eta(0): uniform modified Pr)", "LAW");
  cli.option("--c", "1", "VIM factor c (>= 1): viscosity / c, conductivity x c (the run goes c times faster)", "C");
  cli.option("--rsst", "1", "RSST factor (>= 1): sound speed / factor in the continuity equation", "F");
  cli.option("--rsst-law", "constant", "constant, or viscosity (f_i = f sqrt(eta(0) / eta_i): uniform sound speed with --xi-law viscosity)", "LAW");
  cli.option("--prandtl", "0", "physical Prandtl number eta/(rho kappa); 0: 2.5e29 / Ra (Blankenbach's mantle)", "PR");
  cli.option("--bulk", "0", "bulk modulus K in eta kappa / d^2; 0: 130 Ra (1.3e11 Pa with the benchmark's parameters)", "K");
  cli.option("--p-background", "0", "background pressure (DISPH needs p > 0); 0: 100 Ra for disph, Ra / 10 for ssph", "P");
  cli.option("--volume", "ssph", "SPH volume element: ssph (standard, X = m) or disph (density independent, X = p V: needs p > 0)", "V");
  cli.option("--kernel", "wendland2", "smoothing function: cubic, wendland2 or wendland4", "K");
  cli.option("--hfac", "4", "support radius in particle spacings", "H");
  cli.option("--reference", "horizontal", "buoyancy reference state: horizontal (mean T at each height) or constant (1/2)", "R");
  cli.option("--amplitude", "0.1", "initial perturbation A of T = 1 - z + A cos(pi x / L) sin(pi z)", "A");
  cli.option("--mode", "cell", "3D initial mode: cell (cos(pi x / L) cos(pi y / L)) or roll (cos(pi x / L), uniform in y)", "M");
  cli.option("--cfl", "0.1", "Courant factor (sound, on the support radius)", "C");
  cli.option("--cdiff", "0.025", "diffusion step factor (viscosity, conduction: C h^2 / D, h the support radius)", "C");
  cli.option("--stress", "auto", "viscous term: auto (local for a variable viscosity, full for a constant one); full, div(eta (grad v + grad v^T)); morris, div(eta grad v) only (the same for a constant viscosity); symmetric, two passes (corrected velocity gradient, then the divergence of eta_ij (e_i + e_j), e = G + G^T - 2/3 tr G); split, morris for div(eta grad v) and the two passes for the rest (e = G^T - 2/3 tr G); local, morris and (grad eta) . e taken at each particle from the first pass (grad eta = -b eta grad T) (case 2a, see docs/convection.md)", "S");
  cli.option("--pressure-force", "auto", "pressure force: difference, -V_i sum_j V_j (p_j - p_i) grad W_ij (zero for a uniform pressure; Lind et al. 2012), or symmetric, the conservative pair form (its error grows with the pressure itself); auto: difference for a constant viscosity, symmetric for a variable one", "F");
  cli.option("--volume-drift", "auto", "remove the volume mean of div v each step (the box is closed: the mean is a discretisation error that builds up a uniform compression), or keep it; auto: remove for a constant viscosity, keep for a variable one", "R");
  cli.option("--shift", "auto", "particle shifting strength A (Lind et al. 2012; Skillen et al. 2013: 2; 0: off); auto: 2 for a constant viscosity, 0 for a variable one", "A");
  cli.option("--t-end", "0.3", "end time in diffusion times d^2 / kappa", "T");
  cli.option("--snapshots", "10", "snapshots evenly in time (and the initial one); 0: only the final", "N");
  cli.option("--checkpoint-every", "0", "steps between checkpoints (0: at the end only)", "N");
  cli.option("--log-every", "1", "a row of out/log.txt every N steps (and at every output, checkpoint and the last step); 1: every step", "N");
  cli.option("--max-steps", "0", "stop after this many steps (0: no limit)", "N");
  cli.option("--format", "binary", "snapshot format: ascii, binary or hdf5", "F");
  cli.option("--restart", "", "continue from this checkpoint (same parameters)", "FILE");
  cli.option("--init", "", "start from this snapshot or checkpoint of a run of the same problem (dimension, Ra, viscosity law, contrast, aspect; another Ra, law or contrast with --init-problem continuation) at any resolution: T and v interpolated onto the new lattice, the clock from 0", "FILE");
  cli.option("--init-problem", "same", "with --init: same (the snapshot must be of this Ra, viscosity law and contrast), or "
             "continuation (another Ra, viscosity law or contrast: a parameter continuation, e.g. case 2a from case 1a's "
             "steady cell; dimension and aspect must agree)", "P");
  cli.option("--init-pressure", "auto", "with --init: carry the pressure perturbation K rho1 too (yes), or start it at 0 "
             "(no); auto: yes for the same problem, no for a continuation (another problem's pressure)", "Y");
  cli.option("--out", "convection_out", "output directory", "DIR");
  cli.parse(argc, argv);
  environment.emplace(argc, argv);
  const pik::Comm comm = environment->world();
  if (!comm.is_root()) (void)std::freopen("/dev/null", "w", stdout);  // one header, progress line, report
  if (cli.str("--setup") != "boussinesq") cli.fail("--setup must be boussinesq or stratified, not '" + cli.str("--setup") + "'");

  Params p;
  p.ra = cli.real("--ra"), p.law = cli.str("--viscosity"), p.contrast = cli.real("--contrast");
  p.aspect = cli.real("--aspect"), p.dim = int(cli.count("--dim")), p.nz = int(cli.count("--nz"));
  p.xi = cli.real("--xi"), p.xi_law = cli.str("--xi-law"), p.c = cli.real("--c"), p.rsst = cli.real("--rsst");
  p.rsst_law = cli.str("--rsst-law");
  p.prandtl = cli.real("--prandtl"), p.bulk = cli.real("--bulk"), p.p_bg = cli.real("--p-background");
  p.volume = cli.str("--volume"), p.hfac = cli.real("--hfac"), p.reference = cli.str("--reference");
  p.mode = cli.str("--mode");
  p.amplitude = cli.real("--amplitude"), p.cfl = cli.real("--cfl"), p.cdiff = cli.real("--cdiff");
  p.t_end = cli.real("--t-end"), p.stress = cli.str("--stress");
  if (cli.str("--shift") != "auto") p.shift = cli.real("--shift");
  p.pressure = cli.str("--pressure-force"), p.drift = cli.str("--volume-drift");
  try {
    p.shape = pik::sph::shape_from_name(cli.str("--kernel"));
  } catch (const pik::Error& e) {
    cli.fail(e.what());
  }
  std::vector<std::string> warnings;
  try {
    warnings = p.check();
  } catch (const pik::Error& e) {
    cli.fail(e.what());
  }
  if (comm.is_root())
    for (const auto& w : warnings) std::fprintf(stderr, "convection: warning: %s\n", w.c_str());

  pik::sph::RunParams rp;
  rp.t_end = p.t_end / p.c;
  rp.snapshots = int(cli.count("--snapshots")), rp.out = cli.str("--out");
  rp.max_steps = long(cli.count("--max-steps")), rp.checkpoint_every = long(cli.count("--checkpoint-every"));
  rp.log_every = long(cli.count("--log-every"));
  if (rp.log_every < 1) cli.fail("--log-every must be at least 1");
  rp.format = pik::io::format_from_name(cli.str("--format")), rp.restart = cli.str("--restart");
  const std::string init = cli.str("--init");
  const std::string init_problem = cli.str("--init-problem"), init_p = cli.str("--init-pressure");
  if (init_problem != "same" && init_problem != "continuation")
    cli.fail("--init-problem must be same or continuation, not '" + init_problem + "'");
  if (init_p != "auto" && init_p != "yes" && init_p != "no")
    cli.fail("--init-pressure must be auto, yes or no, not '" + init_p + "'");
  const bool continuation = init_problem == "continuation";
  if (continuation && init_p == "yes")
    cli.fail("--init-pressure yes needs --init-problem same (a continuation starts from another problem, whose pressure "
             "perturbation is not this one's)");
  const bool init_pressure = init_p == "yes" || (init_p == "auto" && !continuation);
  if (!init.empty() && !rp.restart.empty())
    cli.fail("--init and --restart exclude each other (--restart continues a run bit for bit, --init starts a new one "
             "from another run's fields)");
  try {
    return p.dim == 2 ? dispatch<2>(p, rp, comm, init, init_pressure, continuation) : dispatch<3>(p, rp, comm, init, init_pressure, continuation);
  } catch (const std::exception& e) {
    // an error on one rank must not leave the others waiting in a collective
    if (comm.size() > 1) comm.abort(std::string("convection: ") + e.what());
    throw;
  }
} catch (const std::exception& e) {
  std::fprintf(stderr, "convection: error: %s\n", e.what());
  return 1;
}
