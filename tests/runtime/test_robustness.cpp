// Degenerate and hostile inputs: no particles, one, all at one point, positions over
// 1e-30 .. 1e30, NaN and Inf positions, bad parameters.
#include <gtest/gtest.h>

#include "support.hpp"

namespace {

using pt::Accel;
using pt::Body;
using Tree = pik::LongRangeTree<Accel<double>, Body<double>, Body<double>, pik::SPJQuadrupole<double>>;
constexpr double eps2 = 1e-4;
const pt::Gravity<double> mono{eps2};
const pt::GravityQuad<double> quad{eps2};

TEST(Robustness, NoParticles) {
  pik::ParticleSystem<Body<double>> ps;
  Tree tree;
  EXPECT_NO_THROW(tree.calcForceAllAndWriteBack(mono, quad, ps));
  pik::ShortRangeTree<Accel<double>, Body<double>, Body<double>, pik::SearchMode::gather> sr;
  EXPECT_NO_THROW(sr.calcForceAllAndWriteBack(mono, ps));
  std::vector<std::size_t> nb;
  sr.neighbourIndices(Body<double>{}, nb);
  EXPECT_TRUE(nb.empty());
}

TEST(Robustness, OneParticle) {
  auto ps = pt::make<double>(pt::Dist::uniform, 1);
  ps[0].acc = {1, 1, 1};
  Tree tree;
  tree.calcForceAllAndWriteBack(mono, quad, ps);
  EXPECT_EQ(ps[0].acc, (pik::Vec3<double>{0, 0, 0}));
  EXPECT_DOUBLE_EQ(ps[0].pot, -1 / std::sqrt(eps2));
}

TEST(Robustness, AllParticlesAtOnePoint) {
  auto ps = pt::make<double>(pt::Dist::uniform, 500);
  for (auto& b : ps) b.pos = {0.25, -3, 7}, b.r = 0.1;
  Tree tree({0.5, 8, 64});
  tree.calcForceAllAndWriteBack(mono, quad, ps);
  for (auto& b : ps) {
    EXPECT_EQ(b.acc, (pik::Vec3<double>{0, 0, 0}));
    EXPECT_NEAR(b.pot, -1 / std::sqrt(eps2), 1e-9);
  }
  pik::ShortRangeTree<Accel<double>, Body<double>, Body<double>, pik::SearchMode::scatter> sr;
  sr.calcForceAllAndWriteBack(pt::CountNeighbours<double, pik::SearchMode::scatter>{}, ps);
  for (auto& b : ps) EXPECT_EQ(b.pot, 500);
}

// Particles spread from 1e-30 to 1e30 from the origin: keys are re-based in deep
// cells, so the tree still separates the close pairs and forces stay accurate.
TEST(Robustness, PositionsSpreadOverSixtyDecades) {
  pik::ParticleSystem<Body<double>> ps;
  std::mt19937 g(9);
  std::uniform_real_distribution<double> u(-1, 1), ex(-30, 30);
  for (int i = 0; i < 400; ++i) {
    Body<double> b;
    const double s = std::pow(10.0, ex(g));
    b.pos = {s * u(g), s * u(g), s * u(g)};
    b.mass = 1;
    ps.add(b);
  }
  const double tiny = 0;  // no softening: forces span hundreds of decades
  pt::Gravity<double> k{tiny};
  pt::GravityQuad<double> kq{tiny};
  Tree tree({0.3, 4, 8});
  // The particle itself gives 0/0 without softening: skip i == j by distance 0.
  auto kernel = [&](const Body<double>* pi, int ni, const Body<double>* pj, int nj, Accel<double>* f) {
    for (int i = 0; i < ni; ++i)
      for (int j = 0; j < nj; ++j)
        if (!(pi[i].pos == pj[j].pos)) k(pi + i, 1, pj + j, 1, f + i);
  };
  tree.calcForceAllAndWriteBack(kernel, kq, ps);
  for (std::size_t i = 0; i < ps.size(); ++i) {
    pik::Vec3<double> a{};
    for (std::size_t j = 0; j < ps.size(); ++j) {
      if (i == j) continue;
      pik::Vec3<double> d = ps[i].pos - ps[j].pos;
      double r = pik::norm(d);
      a -= d * (1 / (r * r * r));
    }
    ASSERT_TRUE(pik::isfinite(ps[i].acc)) << i;
    EXPECT_LT(pik::norm(ps[i].acc - a), 1e-2 * pik::norm(a)) << "particle " << i;
  }
}

TEST(Robustness, NonFinitePositionIsNamed) {
  for (double bad : {std::nan(""), double(INFINITY), -double(INFINITY)}) {
    auto ps = pt::make<double>(pt::Dist::uniform, 100);
    ps[42].pos.y = bad;
    Tree tree;
    try {
      tree.calcForceAllAndWriteBack(mono, quad, ps);
      FAIL() << "no error for " << bad;
    } catch (const pik::Error& e) {
      EXPECT_NE(std::string(e.what()).find("particle 42 has a non-finite position"), std::string::npos)
          << e.what();
    }
  }
  auto ps = pt::make<float>(pt::Dist::uniform, 10);
  ps[3].pos.z = NAN;
  pik::ShortRangeTree<Accel<float>, Body<float>, Body<float>, pik::SearchMode::gather> sr;
  EXPECT_THROW(sr.build(ps), pik::Error);
}

TEST(Robustness, BadParametersAreErrors) {
  EXPECT_THROW(Tree({-0.1, 8, 64}), pik::Error);
  EXPECT_THROW(Tree({0.5, 0, 64}), pik::Error);
  EXPECT_THROW(Tree({0.5, 8, 0}), pik::Error);
  EXPECT_THROW(pik::Boundary<3>::periodic_box({0, 0, 0}, {1, 0, 1}), pik::Error);
}

// Large search radius with open boundaries: everyone is everyone's neighbour.
TEST(Robustness, SearchRadiusLargerThanEverything) {
  auto ps = pt::make<double>(pt::Dist::clustered, 300);
  for (auto& b : ps) b.r = 1e6;
  pik::ShortRangeTree<Accel<double>, Body<double>, Body<double>, pik::SearchMode::gather> sr;
  sr.calcForceAllAndWriteBack(pt::CountNeighbours<double, pik::SearchMode::gather>{}, ps);
  for (auto& b : ps) EXPECT_EQ(b.pot, 300);
}

}  // namespace
