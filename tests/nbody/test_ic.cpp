// Initial conditions: the samples have the statistics of their models, sit in the
// centre-of-mass frame, and are reproducible from the seed.
#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include <pik/ic/Plummer.hpp>
#include <pik/ic/UniformSphere.hpp>

namespace {

struct Stats {
  double mass = 0, kinetic = 0, potential = 0, half_mass_radius = 0, max_radius = 0;
  pik::Vec3<double> com{}, momentum{};
};

// Exact O(N^2) potential energy, no softening.
Stats measure(const pik::io::Snapshot& s) {
  Stats st;
  std::vector<double> r(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    const auto& x = s.pos[i];
    const auto& v = s.vel[i];
    const double m = s.mass[i];
    st.mass += m;
    st.kinetic += 0.5 * m * (v.x * v.x + v.y * v.y + v.z * v.z);
    st.com = {st.com.x + m * x.x, st.com.y + m * x.y, st.com.z + m * x.z};
    st.momentum = {st.momentum.x + m * v.x, st.momentum.y + m * v.y, st.momentum.z + m * v.z};
    r[i] = std::sqrt(x.x * x.x + x.y * x.y + x.z * x.z);
    for (std::size_t j = 0; j < i; ++j) {
      const double dx = x.x - s.pos[j].x, dy = x.y - s.pos[j].y, dz = x.z - s.pos[j].z;
      st.potential -= m * s.mass[j] / std::sqrt(dx * dx + dy * dy + dz * dz);
    }
  }
  std::sort(r.begin(), r.end());
  st.half_mass_radius = 0.5 * (r[r.size() / 2 - 1] + r[r.size() / 2]);  // equal masses
  st.max_radius = r.back();
  return st;
}

double norm(pik::Vec3<double> v) { return std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }

}  // namespace

TEST(Plummer, HasTheModelsStatistics) {
  const auto s = pik::ic::plummer(8192, 42);
  ASSERT_EQ(s.size(), 8192u);
  const Stats st = measure(s);
  EXPECT_NEAR(st.mass, 1.0, 1e-12);
  EXPECT_LT(norm(st.com), 1e-15);
  EXPECT_LT(norm(st.momentum), 1e-15);
  // Virial equilibrium: 2K/|W| = 1, i.e. K/|W| = 0.5. Sampling noise for N = 8192 is
  // about 1%; the 0.1% mass truncation shifts it far less.
  EXPECT_NEAR(st.kinetic / -st.potential, 0.5, 0.02);
  // N-body units: E = -1/4.
  EXPECT_NEAR(st.kinetic + st.potential, -0.25, 0.01);
  // Half-mass radius a / sqrt(2^(2/3) - 1) with a = 3 pi / 16.
  const double rh = pik::ic::plummer_scale_radius / std::sqrt(std::cbrt(4.0) - 1.0);
  EXPECT_NEAR(rh, 0.76857, 1e-5);
  EXPECT_NEAR(st.half_mass_radius, rh, 0.03);
  // Truncated at the radius enclosing 99.9% of the mass: (0.999^(-2/3) - 1)^(-1/2) a.
  EXPECT_LT(st.max_radius, 1.01 * pik::ic::plummer_scale_radius / std::sqrt(std::pow(0.999, -2.0 / 3) - 1));
}

TEST(Plummer, IsReproducibleFromTheSeed) {
  const auto a = pik::ic::plummer(1000, 7), b = pik::ic::plummer(1000, 7),
             c = pik::ic::plummer(1000, 8);
  EXPECT_TRUE(pik::io::same_bits(a, b));
  EXPECT_FALSE(pik::io::same_bits(a, c));
  EXPECT_EQ(a.id.front(), 0u);
  EXPECT_EQ(a.id.back(), 999u);
  EXPECT_EQ(a.attr.get_string("ic"), "plummer");
  EXPECT_EQ(a.attr.get_int("ic.seed"), 7);
  // Particle i's draw depends only on (seed, i): the samples for N and 2N share their
  // first N particles up to the centre-of-mass shift and the particle mass.
  const auto big = pik::ic::plummer(2000, 7);
  const auto d0 = a.pos[0], d1 = a.pos[1];
  const auto e0 = big.pos[0], e1 = big.pos[1];
  EXPECT_NEAR((d1.x - d0.x) - (e1.x - e0.x), 0.0, 1e-12);
}

TEST(Plummer, EdgeCases) {
  EXPECT_EQ(pik::ic::plummer(0, 1).size(), 0u);
  const auto one = pik::ic::plummer(1, 1);
  EXPECT_EQ(one.mass[0], 1.0);
  EXPECT_EQ(norm(one.pos[0]), 0.0);  // its own centre of mass
  EXPECT_THROW(pik::ic::plummer(10, 1, 0.0), std::invalid_argument);
  EXPECT_THROW(pik::ic::plummer(10, 1, 1.5), std::invalid_argument);
}

TEST(UniformSphere, IsUniformAndCold) {
  const double R = 2.0;
  const auto s = pik::ic::uniform_sphere(8192, 3, R);
  const Stats st = measure(s);
  EXPECT_NEAR(st.mass, 1.0, 1e-12);
  EXPECT_LT(norm(st.com), 1e-15);
  EXPECT_EQ(st.kinetic, 0.0);
  // W = -3/(5R) for a uniform ball; the discrete sum is within a percent or two.
  EXPECT_NEAR(st.potential, -0.6 / R, 0.01 * 0.6 / R + 0.005);
  // Half the mass within R / 2^(1/3).
  EXPECT_NEAR(st.half_mass_radius, R / std::cbrt(2.0), 0.02 * R);
  // The centre-of-mass shift moves the ball by about R sqrt(3 / (5 N)) = 0.009 R.
  EXPECT_LT(st.max_radius, R * 1.04);
  EXPECT_GT(st.max_radius, R * 0.99);
  EXPECT_THROW(pik::ic::uniform_sphere(10, 1, -1.0), std::invalid_argument);
}
