// Tillotson (1962) EOS in the form of Melosh (1989, appendix II), parameters for granite
// and iron as listed in Melosh (1989, table AII.3). Reference values below were worked
// out from the formulas (written out in each comment) with a calculator, not by the
// code under test.
#include <cmath>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include <pik/eos/Registry.hpp>
#include <pik/eos/Tillotson.hpp>

using pik::eos::Tillotson;
using pik::eos::TillotsonParams;

namespace {

const Tillotson granite(TillotsonParams::granite());
const Tillotson iron(TillotsonParams::iron());

// Relative comparison.
void expect_rel(double got, double want, double tol, const std::string& what) {
  EXPECT_NEAR(got / want, 1.0, tol) << what << ": got " << got << ", want " << want;
}

}  // namespace

TEST(Tillotson, ParameterSetsAreTheStandardOnes) {
  const auto g = TillotsonParams::granite(), i = TillotsonParams::iron();
  EXPECT_EQ(g.rho0, 2680.0);
  EXPECT_EQ(g.A, 18e9);
  EXPECT_EQ(g.u_cv, 18e6);
  EXPECT_EQ(i.rho0, 7800.0);
  EXPECT_EQ(i.B, 105e9);
  EXPECT_EQ(i.u_cv, 8.67e6);
}

TEST(Tillotson, CompressedGranite) {
  // rho 3000, u 1 MJ/kg: eta = 1.1194030, mu = 0.1194030, omega = 1e6/(16e6 eta^2) + 1 = 1.0498776,
  // P = (0.5 + 1.3/omega) rho u + A mu + B mu^2
  //   = 1.7382378 * 3e9 + 2.1492537e9 + 0.25662731e9 = 7.6205992e9 Pa.
  EXPECT_EQ(granite.region(3000, 1e6), Tillotson::Region::compressed);
  expect_rel(granite.pressure(3000, 1e6), 7.6205992e9, 1e-7, "P");
  expect_rel(granite.sound_speed(3000, 1e6), 3800.299, 1e-5, "c");
}

TEST(Tillotson, CompressedIron) {
  // rho 9000, u 2 MJ/kg: eta = 1.1538462, mu = 0.15384615, omega = 2e6/(9.5e6 eta^2) + 1 = 1.1581287,
  // P = (0.5 + 1.5/omega) * 1.8e10 + 128e9 mu + 105e9 mu^2 = 5.4490987e10 Pa.
  expect_rel(iron.pressure(9000, 2e6), 5.4490987e10, 1e-7, "P");
  expect_rel(iron.sound_speed(9000, 2e6), 5886.290, 1e-5, "c");
  // rho 12000, u 5 MJ/kg (deep compression, as in a planet's core)
  expect_rel(iron.pressure(12000, 5e6), 2.0299442e11, 1e-7, "P");
  expect_rel(iron.sound_speed(12000, 5e6), 8198.500, 1e-5, "c");
}

TEST(Tillotson, HotExpandedGranite) {
  // rho 2000, u 20 MJ/kg (> u_cv): eta = 0.74626866, mu = -0.25373134, z = 1/eta - 1 = 0.34,
  // omega = 20e6/(16e6 eta^2) + 1 = 3.2445,
  // P = a rho u + (b rho u / omega + A mu e^(-beta z)) e^(-alpha z^2) = 2.8523441e10 Pa.
  EXPECT_EQ(granite.region(2000, 20e6), Tillotson::Region::hot_expanded);
  expect_rel(granite.pressure(2000, 20e6), 2.8523441e10, 1e-7, "P");
  expect_rel(granite.sound_speed(2000, 20e6), 6882.703, 1e-5, "c");
}

TEST(Tillotson, HybridGranite) {
  // rho 2000, u 10 MJ/kg (between u_iv and u_cv): P = ((u - u_iv) P_e + (u_cv - u) P_c) / (u_cv - u_iv)
  // = 1.7750023e10 Pa.
  EXPECT_EQ(granite.region(2000, 10e6), Tillotson::Region::hybrid);
  expect_rel(granite.pressure(2000, 10e6), 1.7750023e10, 1e-7, "P");
  expect_rel(granite.sound_speed(2000, 10e6), 5370.680, 1e-5, "c");
}

TEST(Tillotson, ColdExpandedAndTheFloor) {
  // rho 7000, u 1 MJ/kg, iron: the compressed formula (u < u_iv): P = 7.6262919e8 Pa.
  EXPECT_EQ(iron.region(7000, 1e6), Tillotson::Region::cold_expanded);
  expect_rel(iron.pressure(7000, 1e6), 7.6262919e8, 1e-7, "P");
  // rho 2000, u 0, granite: omega = 1, P = A mu + B mu^2 = 18e9 (-0.25373134 + 0.064379594) = -3.4083315e9:
  // tension. The raw value keeps it, state() floors it at 0 by default.
  expect_rel(granite.raw_pressure(2000, 0), -3.4083315e9, 1e-7, "raw P");
  EXPECT_EQ(granite.pressure(2000, 0), 0.0);
  EXPECT_GT(granite.sound_speed(2000, 0), 0.01 * std::sqrt(18e9 / 2680) * 0.999);
  // A negative floor lets limited tension through.
  const Tillotson t(TillotsonParams::granite(), -1e9);
  EXPECT_EQ(t.pressure(2000, 0), -1e9);
  EXPECT_THROW(Tillotson(TillotsonParams::granite(), 1e5), pik::Error);
}

TEST(Tillotson, ContinuousAcrossRegionBoundaries) {
  for (const Tillotson* m : {&granite, &iron}) {
    const auto& p = m->params();
    const double d = 1e-9;
    // rho = rho0 at several u (compressed | cold expanded, hybrid, hot expanded).
    for (double u : {0.5 * p.u_iv, 0.5 * (p.u_iv + p.u_cv), 2 * p.u_cv}) {
      const double above = m->raw_pressure(p.rho0 * (1 + d), u), below = m->raw_pressure(p.rho0 * (1 - d), u);
      EXPECT_NEAR(above, below, 1e-6 * std::abs(above) + 1e-6 * p.A) << p.name << " at rho0, u " << u;
    }
    // u = u_iv and u = u_cv at several expanded densities.
    for (double rho : {0.3 * p.rho0, 0.7 * p.rho0, 0.95 * p.rho0})
      for (double u : {p.u_iv, p.u_cv}) {
        const double lo = m->raw_pressure(rho, u * (1 - d)), hi = m->raw_pressure(rho, u * (1 + d));
        EXPECT_NEAR(lo, hi, 1e-6 * std::abs(hi) + 1e-6 * p.A) << p.name << " at rho " << rho << ", u " << u;
      }
  }
}

TEST(Tillotson, DerivativesMatchFiniteDifferences) {
  for (const Tillotson* m : {&granite, &iron}) {
    const auto& p = m->params();
    for (double eta : {0.4, 0.8, 1.0001, 1.3, 1.8})
      for (double uf : {0.3, 1.5, 3.0}) {  // in units of u_iv, u between u_iv and u_cv, above u_cv
        const double rho = eta * p.rho0, u = uf < 1 ? uf * p.u_iv : uf < 2 ? 0.5 * (p.u_iv + p.u_cv) : 1.5 * p.u_cv;
        const auto d = m->raw(rho, u);
        const double h = 1e-6;
        const double dr = (m->raw_pressure(rho * (1 + h), u) - m->raw_pressure(rho * (1 - h), u)) / (2 * h * rho);
        const double du = (m->raw_pressure(rho, u * (1 + h)) - m->raw_pressure(rho, u * (1 - h))) / (2 * h * u);
        EXPECT_NEAR(d.dp_drho, dr, 1e-5 * std::abs(dr) + 1e-3) << p.name << " eta " << eta << " u " << u;
        EXPECT_NEAR(d.dp_du, du, 1e-5 * std::abs(du) + 1e-9) << p.name << " eta " << eta << " u " << u;
      }
  }
}

TEST(Tillotson, RefusesNonPhysicalInput) {
  try {
    granite.pressure(-1.0, 1e6);
    FAIL() << "negative density accepted";
  } catch (const pik::Error& e) {
    EXPECT_NE(std::string(e.what()).find("density must be positive"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("granite"), std::string::npos) << e.what();
  }
  EXPECT_THROW(iron.state(0.0, 1e6), pik::Error);
  EXPECT_THROW(iron.state(7800, -1.0), pik::Error);
  EXPECT_THROW(iron.state(std::numeric_limits<double>::quiet_NaN(), 1e6), pik::Error);
  auto bad = TillotsonParams::iron();
  bad.u_cv = bad.u_iv / 2;
  EXPECT_THROW(Tillotson{bad}, pik::Error);
}

TEST(Registry, MaterialsByName) {
  const auto r = pik::eos::Registry::standard();
  EXPECT_EQ(r.make("iron")->name(), "iron");
  EXPECT_EQ(r.make("granite")->name(), "granite");
  EXPECT_NEAR(r.make("ideal-gas-5/3")->pressure(2.0, 3.0), 4.0, 1e-12);
  try {
    r.make("basalt");
    FAIL() << "unknown material accepted";
  } catch (const pik::Error& e) {
    EXPECT_NE(std::string(e.what()).find("granite"), std::string::npos) << e.what();
  }
  // A user's own material, without touching any kernel.
  auto r2 = r;
  r2.add("soft-granite", [] {
    auto p = TillotsonParams::granite();
    p.name = "soft-granite", p.A = 9e9;
    return std::make_unique<Tillotson>(p);
  });
  EXPECT_LT(r2.make("soft-granite")->pressure(3000, 1e6), r.make("granite")->pressure(3000, 1e6));
}
