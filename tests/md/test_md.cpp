// Tests of the Lennard-Jones example's pieces (examples/md): tail corrections,
// lattice, forces through the periodic tree against brute-force sums, Verlet-list
// reuse, energy conservation, the CSVR thermostat's distribution, block averages.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "BlockAverage.hpp"
#include "Lattice.hpp"
#include "System.hpp"
#include "TailCorrection.hpp"
#include "Thermostat.hpp"

namespace {

using md::Atom;
using pik::Vec3;

double lj(double r2) {
  const double s6 = 1.0 / (r2 * r2 * r2);
  return 4.0 * s6 * (s6 - 1.0);
}

// Tail corrections against a direct quadrature of the integrals they stand for:
// U_tail/N = 2 pi rho int_rc^inf r^2 u(r) dr, P_tail = -(2/3) pi rho^2 int r^3 u'(r) dr.
TEST(MdTail, MatchesQuadrature) {
  for (double rc : {2.5, 3.0, 4.0}) {
    const double rho = 0.86;
    double iu = 0, iw = 0;
    // Substitution r = rc / x, x in (0, 1]: integrand r^2 u dr = rc^3 x^-4 u dx; midpoint rule.
    const int n = 200000;
    for (int k = 0; k < n; ++k) {
      const double x = (k + 0.5) / n, r = rc / x, s6 = std::pow(r, -6.0);
      const double u = 4 * s6 * (s6 - 1), du = -24 * s6 * (2 * s6 - 1) / r;
      iu += r * r * u * rc / (x * x) / n;
      iw += r * r * r * du * rc / (x * x) / n;
    }
    EXPECT_NEAR(md::energy_tail(rho, rc), 2 * std::numbers::pi * rho * iu, 1e-8) << "rc " << rc;
    EXPECT_NEAR(md::pressure_tail(rho, rc), -2.0 / 3.0 * std::numbers::pi * rho * rho * iw, 1e-8) << "rc " << rc;
  }
  EXPECT_NEAR(md::energy_tail(0.86, 3.0), -0.266719, 1e-6);  // the value docs/md.md quotes
}

TEST(MdLattice, FccGeometryVelocitiesAndSeed) {
  const std::uint64_t m = 3;
  const double rho = 0.86, L = md::box_side(4 * m * m * m, rho), a = L / m;
  const auto atoms = md::fcc_lattice(m, rho, 0.85, 7);
  ASSERT_EQ(atoms.size(), 108u);
  Vec3<double> p{};
  double dmin = 1e300;
  for (std::size_t i = 0; i < atoms.size(); ++i) {
    for (int d = 0; d < 3; ++d) {
      EXPECT_GE(atoms[i].pos[d], 0.0);
      EXPECT_LT(atoms[i].pos[d], L);
    }
    p += atoms[i].vel;
    for (std::size_t j = 0; j < i; ++j) {
      Vec3<double> dx = atoms[i].pos - atoms[j].pos;
      for (int d = 0; d < 3; ++d) dx[d] -= L * std::round(dx[d] / L);
      dmin = std::min(dmin, pik::norm(dx));
    }
  }
  EXPECT_NEAR(dmin, a / std::sqrt(2.0), 1e-12);  // fcc nearest-neighbour distance
  EXPECT_LT(pik::norm(p), 1e-12);
  EXPECT_NEAR(md::kinetic_temperature(atoms), 0.85, 1e-12);
  const auto same = md::fcc_lattice(m, rho, 0.85, 7), other = md::fcc_lattice(m, rho, 0.85, 8);
  EXPECT_EQ(same[17].vel.x, atoms[17].vel.x);
  EXPECT_NE(other[17].vel.x, atoms[17].vel.x);
}

// Brute force over every periodic image within rc (valid for any box size).
struct Reference {
  std::vector<Vec3<double>> acc;
  std::vector<double> pot, vir;
};
Reference brute_force(const std::vector<Atom>& atoms, double L, double rc) {
  const std::size_t n = atoms.size();
  Reference r{std::vector<Vec3<double>>(n), std::vector<double>(n, 0.0), std::vector<double>(n, 0.0)};
  const int k = int(std::ceil(rc / L)) + 1;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j)
      for (int sx = -k; sx <= k; ++sx)
        for (int sy = -k; sy <= k; ++sy)
          for (int sz = -k; sz <= k; ++sz) {
            Vec3<double> xi = atoms[i].pos, xj = atoms[j].pos;
            for (int d = 0; d < 3; ++d) xi[d] -= L * std::floor(xi[d] / L), xj[d] -= L * std::floor(xj[d] / L);
            const Vec3<double> dx = xi - xj - Vec3<double>{sx * L, sy * L, sz * L};
            const double r2 = pik::norm2(dx);
            if (r2 == 0 || r2 >= rc * rc) continue;
            const double s6 = 1.0 / (r2 * r2 * r2), f = 24 * s6 * (2 * s6 - 1) / r2;
            r.acc[i] += dx * f;
            r.pot[i] += lj(r2);
            r.vir[i] += f * r2;
          }
  return r;
}

void expect_matches(const md::System& sys, double rc, const char* what) {
  const auto ref = brute_force(sys.atoms(), sys.box(), rc);
  double u = 0;
  for (std::size_t i = 0; i < sys.size(); ++i) {
    const Atom& a = sys.atoms()[i];
    for (int d = 0; d < 3; ++d) ASSERT_NEAR(a.acc[d], ref.acc[i][d], 1e-9 * (1 + std::abs(ref.acc[i][d]))) << what << " atom " << i;
    ASSERT_NEAR(a.pot, ref.pot[i], 1e-10 * (1 + std::abs(ref.pot[i]))) << what << " atom " << i;
    ASSERT_NEAR(a.vir, ref.vir[i], 1e-9 * (1 + std::abs(ref.vir[i]))) << what << " atom " << i;
    u += ref.pot[i];
  }
  EXPECT_NEAR(sys.potential_per_atom(false), 0.5 * u / double(sys.size()), 1e-12);
}

// Lattice atoms displaced at random (seeded), so pairs sit at every distance.
std::vector<Atom> jittered(std::uint64_t m, double rho, double amp) {
  auto atoms = md::fcc_lattice(m, rho, 1.0, 3);
  for (Atom& a : atoms) {
    pik::ic::Stream s(99, a.id);
    a.pos += Vec3<double>{s.uniform(-amp, amp), s.uniform(-amp, amp), s.uniform(-amp, amp)};
  }
  return atoms;
}

TEST(MdForces, TreeMatchesBruteForce) {
  for (double skin : {0.0, 0.3}) {
    const double rho = 0.86, rc = 3.0, L = md::box_side(256, rho);
    md::System sys(jittered(4, rho, 0.15), L, rc, skin);
    sys.compute_forces();
    expect_matches(sys, rc, skin > 0 ? "skin 0.3" : "skin 0");
  }
}

// A box smaller than 2 rc (L = 3.37 for 32 atoms): every image within rc counts,
// several images of one atom included, so no pair may be dropped or doubled.
TEST(MdForces, SmallBoxAllImages) {
  const double rho = 0.86, rc = 3.0, L = md::box_side(32, rho);
  ASSERT_LT(L, 2 * rc);
  md::System sys(jittered(2, rho, 0.1), L, rc, 0.3);
  sys.compute_forces();
  expect_matches(sys, rc, "small box");
}

// After steps that reuse the lists (atoms drift outside the box in between), the
// forces are still those of a fresh brute-force sum.
TEST(MdForces, ListReuseStaysExact) {
  const double rho = 0.86, rc = 3.0, L = md::box_side(256, rho);
  md::System sys(md::fcc_lattice(4, rho, 2.0, 5), L, rc, 0.3);
  sys.compute_forces();
  for (int s = 0; s < 40; ++s) sys.step(0.005);
  EXPECT_GT(sys.stats().list_builds, 1u);
  EXPECT_LT(sys.stats().list_builds, sys.stats().force_calls);
  expect_matches(sys, rc, "after 40 steps");
}

// Pairs closer than rc (minimum image; the box is wider than 2 rc).
double pairs_within(const md::System& sys, double rc) {
  const auto& a = sys.atoms();
  const double L = sys.box();
  double n = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < i; ++j) {
      Vec3<double> dx = a[i].pos - a[j].pos;
      for (int d = 0; d < 3; ++d) dx[d] -= L * std::round(dx[d] / L);
      n += pik::norm2(dx) < rc * rc;
    }
  return n;
}

// Velocity Verlet conserves the energy of the potential the forces derive from:
// the truncated potential shifted by u(rc) (the unshifted one jumps when a pair
// crosses rc). Its error is second order in dt; momentum stays zero.
double energy_spread(double dt, double t_end) {
  const double rho = 0.86, rc = 3.0;
  md::System sys(md::fcc_lattice(4, rho, 0.85, 11), md::box_side(256, rho), rc, 0.3);
  sys.compute_forces();
  for (int s = 0; s < 300; ++s) sys.step(0.004);  // melt the lattice first
  const auto energy = [&] {
    return sys.kinetic() / double(sys.size()) + sys.potential_per_atom(false) -
           lj(rc * rc) * pairs_within(sys, rc) / double(sys.size());
  };
  const double e0 = energy();
  double spread = 0;
  const int steps = int(std::lround(t_end / dt));
  for (int s = 1; s <= steps; ++s) {
    sys.step(dt);
    if (s % int(std::lround(0.04 / dt)) == 0) spread = std::max(spread, std::abs(energy() - e0));
  }
  EXPECT_LT(pik::norm(sys.momentum()), 1e-10);
  return spread;
}
TEST(MdIntegrator, EnergyConservation) {
  const double coarse = energy_spread(0.008, 2.0), fine = energy_spread(0.002, 2.0);
  EXPECT_LT(coarse, 3e-3);
  EXPECT_LT(fine, 2e-4);
  EXPECT_LT(fine, 0.15 * coarse);  // 1/16 for a second-order integrator
  std::printf("max |E/N - E0/N| over t = 2: %.3e (dt 0.008), %.3e (dt 0.002)\n", coarse, fine);
}

// Overlapping atoms (rho* = 100) fly apart in the first step: the run stops with the
// reason instead of integrating nonsense (it once ended in a tree error about the box).
TEST(MdIntegrator, BlowUpIsReported) {
  md::System sys(md::fcc_lattice(2, 100.0, 0.85, 1), md::box_side(32, 100.0), 3.0, 0.3);
  sys.compute_forces();
  try {
    for (int s = 0; s < 10; ++s) sys.step(0.005);
    ADD_FAILURE() << "ten steps at rho* = 100 ran without an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("unstable run"), std::string::npos) << e.what();
  }
}

TEST(MdThermostat, GammaDeviates) {
  pik::ic::Stream s(1, 2);
  for (double shape : {0.5, 3.0, 150.0}) {
    const int n = 200000;
    double m = 0, m2 = 0;
    for (int i = 0; i < n; ++i) {
      const double g = md::gamma_deviate(s, shape);
      m += g, m2 += g * g;
    }
    m /= n, m2 = m2 / n - m * m;
    EXPECT_NEAR(m, shape, 5 * std::sqrt(shape / n)) << "shape " << shape;
    EXPECT_NEAR(m2, shape, 0.03 * shape) << "shape " << shape;
  }
}

// With no forces the CSVR kinetic energy alone must follow the canonical
// distribution: <K> = N_f T / 2, var K = N_f T^2 / 2.
TEST(MdThermostat, CsvrSamplesCanonicalKineticEnergy) {
  const double nf = 30, t = 0.85, dt = 0.005, tau = 0.05;
  md::Csvr th(t, tau, nf, 4);
  double k = 3.0 * nf * t;  // far from equilibrium
  for (int i = 0; i < 2000; ++i) k *= std::pow(th.factor(k, dt), 2);
  md::BlockAverage ks, k2;
  for (int i = 0; i < 400000; ++i) {
    k *= std::pow(th.factor(k, dt), 2);
    ks.add(k);
    k2.add(k * k);
  }
  const double mean = ks.mean(), var = k2.mean() - mean * mean;
  EXPECT_NEAR(mean, 0.5 * nf * t, 4 * ks.error(50));
  EXPECT_NEAR(var, 0.5 * nf * t * t, 0.05 * 0.5 * nf * t * t);
}

// An AR(1) series x_k = phi x_{k-1} + e_k has var(mean) -> (s^2 / n)(1 + phi)/(1 - phi),
// s^2 = var(e) / (1 - phi^2): blocks long against 1/(1 - phi) recover it; treating the
// samples as independent underestimates it by sqrt((1 + phi)/(1 - phi)).
TEST(MdBlockAverage, CorrelatedSeries) {
  const double phi = 0.9;
  const int n = 1 << 20;
  pik::ic::Stream s(5, 6);
  md::BlockAverage b;
  double x = 0;
  for (int i = 0; i < n; ++i) b.add(x = phi * x + md::normal(s));
  const double s2 = 1.0 / (1.0 - phi * phi);
  const double exact = std::sqrt(s2 / n * (1 + phi) / (1 - phi));
  EXPECT_NEAR(b.error(32), exact, 0.35 * exact);
  const auto curve = b.blocking_curve();
  EXPECT_NEAR(curve[0], std::sqrt(s2 / n), 0.05 * std::sqrt(s2 / n));
  EXPECT_NEAR(curve[10], exact, 0.25 * exact);  // blocks of 1024 samples
  EXPECT_NEAR(b.mean(), 0.0, 5 * exact);
  EXPECT_TRUE(std::isnan(md::BlockAverage{}.error()));
}

}  // namespace
