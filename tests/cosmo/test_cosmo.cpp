// The cosmological box of examples/cosmo: background and growth against published
// fits, the Zel'dovich pancake against its exact solution, linear growth of the
// large-scale power spectrum, momentum conservation (measured), friends-of-friends.
#include <gtest/gtest.h>

#include <complex>
#include <cstdio>
#include <numbers>

#include "Analysis.hpp"
#include "Cosmology.hpp"
#include "InitialConditions.hpp"
#include "Simulation.hpp"

#include "CosmoTreePM.hpp"
#include "CosmoTreePMSP.hpp"

namespace {

using namespace cosmo;

// Einstein-de Sitter: D = a and f = 1 exactly.
TEST(Cosmology, EinsteinDeSitterGrowth) {
  const Background eds{1.0};
  for (double a : {0.01, 0.1, 0.5, 1.0}) {
    EXPECT_NEAR(eds.growth(a), a, 1e-9 * a);
    EXPECT_NEAR(eds.growth_rate(a), 1.0, 1e-8);
  }
  // Drift and kick factors in EdS: ∫ a^{-3/2} da and ∫ a^{-1/2} da.
  EXPECT_NEAR(eds.drift(0.1, 0.5), 2 * (1 / std::sqrt(0.1) - 1 / std::sqrt(0.5)), 1e-9);
  EXPECT_NEAR(eds.kick(0.1, 0.5), 2 * (std::sqrt(0.5) - std::sqrt(0.1)), 1e-9);
}
// LCDM, Omega_m = 0.3: D(a = 0.5) = 0.6129 by the fit of Carroll, Press & Turner
// 1992 (ARA&A 30, 499, eq. 29; accurate to ~1 %), f(1) = Omega_m^0.55 = 0.5157
// (Linder 2005, PRD 72, 043529; ~0.5 %).
TEST(Cosmology, LambdaCdmGrowthAgainstFits) {
  const Background lcdm{0.3};
  EXPECT_NEAR(lcdm.growth(0.5), 0.6129, 0.01 * 0.6129);
  EXPECT_NEAR(lcdm.growth_rate(1.0), 0.5157, 0.01 * 0.5157);
  EXPECT_NEAR(lcdm.hubble(1.0), 1.0, 1e-15);
}
// sigma_8 normalisation; the EH98 no-wiggle shape and BBKS with Sugiyama's baryon
// correction agree within 20 % over 0.01-1 h/Mpc (both normalised to sigma_8 = 0.8;
// the transfer functions differ by < 5 %), and T -> 1 at large scales.
TEST(Cosmology, PowerSpectrumShapes) {
  PowerSpectrum eh, bbks;
  bbks.fit = PowerSpectrum::Fit::bbks;
  eh.normalise(), bbks.normalise();
  EXPECT_NEAR(std::sqrt(eh.sigma2(8.0)), 0.8, 1e-6);
  EXPECT_NEAR(eh.transfer(1e-5), 1.0, 1e-3);
  EXPECT_NEAR(bbks.transfer(1e-5), 1.0, 1e-3);
  for (double k : {0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0}) EXPECT_NEAR(eh(k) / bbks(k), 1.0, 0.20) << k;
}

// 2LPT (Scoccimarro 1998, MNRAS 299, 1097; Crocce, Pueblas & Scoccimarro 2006,
// MNRAS 373, 369) against its analytic solution for two crossed plane waves,
// phi1 = A cos(k1 x) + B cos(k2 y) (delta = lap phi1, psi1 = -grad phi1): the source
// sum_{i>j} (phi1_ii phi1_jj - phi1_ij^2) = A B k1^2 k2^2 cos(k1 x) cos(k2 y), so
// psi2 = grad phi2 = A B k1^2 k2^2 / (k1^2 + k2^2) (k1 sin(k1 x) cos(k2 y),
// k2 cos(k1 x) sin(k2 y), 0), sampled on the grid shifted by half a cell (the gas's).
// A single plane wave (the pancake) has no second order. And D2 = -3/7 D1^2 in
// Einstein-de Sitter (Bouchet et al. 1995, A&A 296, 575), f2 = 2.
TEST(Cosmology, SecondOrderLptOfTwoPlaneWaves) {
  const int n = 16;
  const double L = 10, k1 = 2 * std::numbers::pi / L, k2 = 2 * k1, A = 0.3, B = 0.2, dq = L / n;
  auto modes = [&](double a, double b) {
    pik::pm::detail::SlabFft fft(n, pik::SerialComm::world());
    for (int x = 0; x < n; ++x)
      for (int y = 0; y < n; ++y)
        for (int z = 0; z < n; ++z)
          fft.real(x, y, z) = -a * k1 * k1 * std::cos(k1 * x * dq) - b * k2 * k2 * std::cos(k2 * y * dq);
    fft.forward();
    const std::size_t nc = std::size_t(n) * n * (n / 2 + 1);
    const auto* c = reinterpret_cast<const std::complex<double>*>(fft.complex_data());
    std::vector<std::complex<double>> d(c, c + nc);
    for (auto& v : d) v /= double(n) * n * n;
    return d;
  };
  const Displacements two = lpt_displacements(modes(A, B), n, L, 0.5, true);
  const double c2 = A * B * k1 * k1 * k2 * k2 / (k1 * k1 + k2 * k2);
  double e1 = 0, e2 = 0, s2 = 0;
  for (int x = 0; x < n; ++x)
    for (int y = 0; y < n; ++y)
      for (int z = 0; z < n; ++z) {
        const std::size_t i = (std::size_t(x) * n + y) * n + z;
        const double qx = (x + 0.5) * dq, qy = (y + 0.5) * dq;
        const V p1{A * k1 * std::sin(k1 * qx), B * k2 * std::sin(k2 * qy), 0};
        const V p2{c2 * k1 * std::sin(k1 * qx) * std::cos(k2 * qy), c2 * k2 * std::cos(k1 * qx) * std::sin(k2 * qy), 0};
        e1 = std::max(e1, pik::norm(two.psi1[i] - p1)), e2 = std::max(e2, pik::norm(two.psi2[i] - p2));
        s2 = std::max(s2, pik::norm(p2));
      }
  EXPECT_LT(e1, 1e-12 * A * k1);
  EXPECT_LT(e2, 1e-10 * s2) << "largest psi2 " << s2;
  const Displacements one = lpt_displacements(modes(A, 0), n, L, 0.0, true);
  double p2max = 0;
  for (const V& v : one.psi2) p2max = std::max(p2max, pik::norm(v));
  EXPECT_LT(p2max, 1e-12 * A * k1);
  const Background eds{1.0}, lcdm{0.3};
  EXPECT_NEAR(lpt_d2(eds, 0.3), -3.0 / 7.0 * 0.09, 1e-9);
  EXPECT_NEAR(lpt_f2(eds, 0.3), 2.0, 1e-9);
  // LCDM today: Omega_m^(-1/143) moves D2 by 0.8 %, f2 = 2 Omega_m^(6/11) = 1.037.
  EXPECT_NEAR(lpt_d2(lcdm, 1.0), -3.0 / 7.0 * std::pow(0.3, -1.0 / 143), 1e-9);
  EXPECT_NEAR(lpt_f2(lcdm, 1.0), 2 * std::pow(0.3, 6.0 / 11.0), 1e-9);
}

// A 2LPT box and a Zel'dovich box of the same field: the same large-scale P(k) at the
// start (the second order adds ~ D1^2 power), different particles.
TEST(Cosmology, SecondOrderLptBoxKeepsLinearPower) {
  const Background bg{0.3};
  PowerSpectrum pk;
  pk.normalise();
  const int n = 16;
  const double L = 100, a = 0.02;
  const auto za = grid_particles(bg, pk, n, L, a, 3), lpt = grid_particles(bg, pk, n, L, a, 3, {.order = 2});
  double dmax = 0, d1 = 0;
  for (std::size_t i = 0; i < za.size(); ++i) {
    V d = lpt[i].pos - za[i].pos;
    for (int c = 0; c < 3; ++c) d[c] -= L * std::round(d[c] / L);
    dmax = std::max(dmax, pik::norm(d));
    V z = za[i].pos - V{double(i / (n * n)), double(i / n % n), double(i % n)} * (L / n);
    for (int c = 0; c < 3; ++c) z[c] -= L * std::round(z[c] / L);
    d1 = std::max(d1, pik::norm(z));
  }
  EXPECT_GT(dmax, 0);               // the second order moved the particles
  EXPECT_LT(dmax, 0.1 * d1);        // by much less than the first order at z = 49
  const auto pz = species_power(za, L, n, 0.0), pl = species_power(lpt, L, n, 0.0);
  for (std::size_t b = 0; b < 3; ++b) EXPECT_NEAR(pl[b].power / pz[b].power, 1.0, 0.01) << pz[b].k;
}

template <class Sim>
void run(Sim& sim, double a_end, int steps) {
  const auto k = sim.template kernel<CosmoTreePM>();
  const auto ks = sim.template kernel<CosmoTreePMSP>();
  sim.compute_forces(k, ks);
  const double a0 = sim.a, dl = std::log(a_end / a0) / steps;
  for (int s = 1; s <= steps; ++s) sim.step(a0 * std::exp(dl * s), k, ks);
}

// The Zel'dovich pancake (Zel'dovich 1970; the test of e.g. Efstathiou et al. 1985,
// ApJS 57, 241): one plane wave in Einstein-de Sitter, shell crossing at a = 1, run
// from a = 0.1 to half the crossing scale factor, a = 0.5 (density contrast 1 at the
// centre). Positions and momenta must follow the exact solution within 1 % of the
// wave's displacement and momentum amplitudes (issue 18).
TEST(Cosmology, ZeldovichPancake) {
  const int n = 32;
  const Pancake pan{Background{1.0}, 64.0, 1.0};
  GravityParams gp{.box = pan.L, .n_mesh = n, .theta = 0.3, .eps = 0.02 * pan.L / n};
  Simulation<pik::SerialComm> sim(pan.bg, gp, pik::SerialComm::world());
  sim.a = 0.1;
  sim.ps = pik::ParticleSystem<Body>(pan.particles(n, sim.a));
  const auto [p0, s0] = sim.momentum();
  run(sim, 0.5, 20);
  const double a = sim.a, dx_amp = pan.amplitude(a) / pan.k(), p_amp = std::abs(pan.p(pan.L / 4, a));
  double ex = 0, ep = 0, eyz = 0;
  for (const Body& b : sim.ps) {
    const std::uint64_t i = b.id / (n * n);
    const double q = (double(i) + 0.5) * pan.L / n;
    double d = b.pos.x - pan.x(q, a);
    d -= pan.L * std::round(d / pan.L);
    ex = std::max(ex, std::abs(d) / dx_amp);
    ep = std::max(ep, std::abs(b.mom.x - pan.p(q, a)) / p_amp);
    eyz = std::max(eyz, std::max(std::abs(b.mom.y), std::abs(b.mom.z)) / p_amp);
  }
  const auto [p1, s1] = sim.momentum();
  std::printf("pancake at a = %.2f: position error %.2e, momentum error %.2e (of the amplitudes), "
              "transverse %.2e; total momentum |sum m p| / sum m|p| = %.2e\n",
              a, ex, ep, eyz, pik::norm(p1) / s1);
  EXPECT_LT(ex, 0.01);
  EXPECT_LT(ep, 0.01);
  EXPECT_LT(eyz, 0.01);
  (void)p0, (void)s0;
}

// Linear growth (issue 18): a 32^3 LCDM box of side 256 Mpc/h from Zel'dovich initial
// conditions at a = 0.02 to a = 0.1; the power of the largest scales grows as D(a)^2
// within 3 %: the bins below a fifth of the particle Nyquist frequency (k < 0.08
// h/Mpc), since modes of a particle lattice grow more slowly than the fluid's as k
// nears the Nyquist frequency (Joyce, Marcos, Gabrielli & Baertschiger 2005, PRL 95,
// 011304; -2.7 % at k = k_Ny / 4 here). Also: total momentum stays small.
TEST(Cosmology, LinearGrowthOfLargeScalePower) {
  const int n = 32;
  const double L = 256;
  const Background bg{0.3};
  PowerSpectrum pk;
  pk.normalise();
  GravityParams gp{.box = L, .n_mesh = n, .theta = 0.3, .eps = 0.03 * L / n};
  Simulation<pik::SerialComm> sim(bg, gp, pik::SerialComm::world());
  sim.a = 0.02;
  sim.ps = pik::ParticleSystem<Body>(zeldovich(bg, pk, n, L, sim.a, 42));
  const double mass = bg.mean_density() * L * L * L;
  const auto k = sim.kernel<CosmoTreePM>();
  const auto ks = sim.kernel<CosmoTreePMSP>();
  sim.compute_forces(k, ks);
  const auto p0 = power_spectrum(sim.gravity().mesh(), mass, sim.comm());
  // The initial spectrum itself follows linear theory within its cosmic variance.
  for (std::size_t b = 0; b < 4; ++b) {
    const double lin = pk(p0[b].k) * std::pow(bg.growth(0.02), 2);
    EXPECT_NEAR(p0[b].power / lin, 1.0, 4 / std::sqrt(p0[b].modes)) << "bin " << b;
  }
  run(sim, 0.1, 16);
  const auto p1 = power_spectrum(sim.gravity().mesh(), mass, sim.comm());
  const double want = std::pow(bg.growth(0.1) / bg.growth(0.02), 2);
  const double k_nyquist = std::numbers::pi * n / L;
  for (std::size_t b = 0; p1[b].k < 0.2 * k_nyquist; ++b) {
    const double got = p1[b].power / p0[b].power;
    std::printf("k = %.4f h/Mpc: P(a=0.1)/P(a=0.02) = %.3f, D^2 ratio %.3f (%+.2f %%)\n", p1[b].k, got, want,
                100 * (got / want - 1));
    EXPECT_NEAR(got / want, 1.0, 0.03) << "bin " << b;
  }
  const auto [p, s] = sim.momentum();
  std::printf("total momentum |sum m p| / sum m|p| = %.2e\n", pik::norm(p) / s);
  EXPECT_LT(pik::norm(p) / s, 1e-3);
}

// Friends-of-friends: two compact clumps far apart in a sparse background, one of
// them across the periodic boundary.
TEST(Cosmology, FriendsOfFriendsFindsClumps) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<V> x;
  const double L = 100;
  for (int i = 0; i < 500; ++i) x.push_back({30 + u(rng), 30 + u(rng), 30 + u(rng)});           // 500 in 1^3
  for (int i = 0; i < 200; ++i) x.push_back({std::fmod(99.6 + u(rng), L), 50 + u(rng), 50 + u(rng)});  // wraps
  for (int i = 0; i < 300; ++i) x.push_back({L * u(rng), L * u(rng), L * u(rng)});  // mean spacing ~15
  const auto g = friends_of_friends(x, L, 0.5, 20);
  ASSERT_EQ(g.size(), 2u);
  EXPECT_GE(g[0], 500u);
  EXPECT_LE(g[0], 502u);
  EXPECT_GE(g[1], 200u);
  EXPECT_LE(g[1], 202u);
}

}  // namespace
