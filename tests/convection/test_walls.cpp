// Mirror-particle walls (physics/include/pik/sph/Walls.hpp) and the convection program's
// parameter checks (examples/convection/Convection.hpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include <pik/sph/KernelResults.hpp>
#include <pik/sph/Walls.hpp>

#include "Convection.hpp"

namespace {

using pik::sph::WallFace;
using Kind = WallFace::Kind;

template <int D>
struct FP {
  std::uint32_t id = 0;
  pik::Vec3<double> pos{}, vel{}, vel_half{};
  double temp = 0;
  pik::Vec<double, D> getPos() const { return pik::sph::first_dims<D>(pos); }
  void setPos(const pik::Vec<double, D>& p) { pik::sph::set_first_dims<D>(pos, p); }
};

template <int D>
struct Img {
  pik::Vec3<double> pos{}, vel{};
  double temp = 0;
  int crossed = 0;
  pik::Vec<double, D> getPos() const { return pik::sph::first_dims<D>(pos); }
  void setPos(const pik::Vec<double, D>& p) { pik::sph::set_first_dims<D>(pos, p); }
  void copyFromFP(const FP<D>& p) { pos = p.pos, vel = p.vel, temp = p.temp; }
  void mirror(int, int, const WallFace& f) { temp = f.image_temperature(temp), ++crossed; }
};

pik::sph::Walls<2> box2() {
  pik::Box<double, 2> b;
  b.lo = {0, 0}, b.hi = {2, 1};
  pik::sph::Walls<2> w(b);
  w.set_axis(0, {Kind::free_slip, false, 0}, {Kind::free_slip, false, 0});
  w.set_axis(1, {Kind::no_slip, true, 1.0}, {Kind::free_slip, true, 0.0});
  return w;
}

// A particle near the lower-left corner: one image across each wall and one across both.
TEST(Walls, CornerImages2D) {
  auto w = box2();
  pik::ParticleSystem<FP<2>> ps;
  FP<2> p;
  p.pos = {0.1, 0.05, 0}, p.vel = {1, 2, 0}, p.temp = 0.9;
  ps.add(p);
  p.pos = {1.0, 0.5, 0};  // far from every wall
  ps.add(p);
  auto img = w.images<Img<2>>(ps, 0.2);
  ASSERT_EQ(img.size(), 3u);
  std::sort(img.begin(), img.end(), [](auto& a, auto& b) { return a.crossed < b.crossed || (a.crossed == b.crossed && a.pos.x < b.pos.x); });
  // across x = 0 (free slip, insulating): x mirrored, v_x reversed, T kept
  EXPECT_DOUBLE_EQ(img[0].pos.x, -0.1);
  EXPECT_DOUBLE_EQ(img[0].pos.y, 0.05);
  EXPECT_DOUBLE_EQ(img[0].vel.x, -1);
  EXPECT_DOUBLE_EQ(img[0].vel.y, 2);
  EXPECT_DOUBLE_EQ(img[0].temp, 0.9);
  // across y = 0 (no slip, T = 1): whole velocity reversed, T -> 2 - T
  EXPECT_DOUBLE_EQ(img[1].pos.x, 0.1);
  EXPECT_DOUBLE_EQ(img[1].pos.y, -0.05);
  EXPECT_DOUBLE_EQ(img[1].vel.x, -1);
  EXPECT_DOUBLE_EQ(img[1].vel.y, -2);
  EXPECT_NEAR(img[1].temp, 1.1, 1e-15);
  // across both
  EXPECT_EQ(img[2].crossed, 2);
  EXPECT_DOUBLE_EQ(img[2].pos.x, -0.1);
  EXPECT_DOUBLE_EQ(img[2].pos.y, -0.05);
}

// Near a corner of a 3D box: 7 images, each a reflection across a distinct set of walls.
TEST(Walls, CornerImages3D) {
  pik::Box<double, 3> b;
  b.lo = {0, 0, 0}, b.hi = {1, 1, 1};
  pik::sph::Walls<3> w(b);
  for (int d = 0; d < 3; ++d) w.set_axis(d, {Kind::free_slip, false, 0}, {Kind::free_slip, false, 0});
  pik::ParticleSystem<FP<3>> ps;
  FP<3> p;
  p.pos = {0.95, 0.95, 0.95};
  ps.add(p);
  const auto img = w.images<Img<3>>(ps, 0.1);
  ASSERT_EQ(img.size(), 7u);
  int by_count[4] = {};
  for (const auto& i : img) {
    ++by_count[i.crossed];
    for (int d = 0; d < 3; ++d) EXPECT_TRUE(i.pos[std::size_t(d)] == 0.95 || std::abs(i.pos[std::size_t(d)] - 1.05) < 1e-15);
  }
  EXPECT_EQ(by_count[1], 3);
  EXPECT_EQ(by_count[2], 3);
  EXPECT_EQ(by_count[3], 1);
}

// A box thinner than twice the reach: one image across each face, never both combined.
TEST(Walls, ThinBox) {
  pik::Box<double, 2> b;
  b.lo = {0, 0}, b.hi = {1, 0.1};
  pik::sph::Walls<2> w(b);
  w.set_axis(1, {Kind::free_slip, false, 0}, {Kind::free_slip, false, 0});
  pik::ParticleSystem<FP<2>> ps;
  FP<2> p;
  p.pos = {0.5, 0.05, 0};
  ps.add(p);
  EXPECT_EQ(w.images<Img<2>>(ps, 0.2).size(), 2u);
}

// Thin along every axis (convection --nz below 8: the reach spans the box): all 2D faces
// in reach, so every choice of none/low/high per axis but none-at-all, 3^D - 1 images,
// each within the reflected box. Overran a D-sized face list before the fix.
template <int D>
void thin_all_axes() {
  pik::Box<double, D> b;
  for (int d = 0; d < D; ++d) b.lo[d] = 0, b.hi[d] = 0.1;
  pik::sph::Walls<D> w(b);
  for (int d = 0; d < D; ++d) w.set_axis(d, {Kind::free_slip, false, 0}, {Kind::free_slip, false, 0});
  pik::ParticleSystem<FP<D>> ps;
  FP<D> p;
  p.pos = {0.04, 0.05, D == 3 ? 0.06 : 0.0};
  ps.add(p);
  const auto img = w.template images<Img<D>>(ps, 0.2);
  ASSERT_EQ(img.size(), std::size_t(D == 2 ? 8 : 26));
  for (const auto& e : img) {
    EXPECT_GE(e.crossed, 1);
    EXPECT_LE(e.crossed, D);
    for (int d = 0; d < D; ++d) {
      EXPECT_GT(e.getPos()[d], -0.1);
      EXPECT_LT(e.getPos()[d], 0.2);
    }
  }
}

TEST(Walls, ThinAlongEveryAxis) {
  thin_all_axes<2>();
  thin_all_axes<3>();
}

TEST(Walls, ReflectEscaped) {
  auto w = box2();
  pik::ParticleSystem<FP<2>> ps;
  FP<2> p;
  p.pos = {2.01, 0.5, 0}, p.vel = {3, 1, 0}, p.vel_half = {3, 1, 0};
  ps.add(p);
  EXPECT_EQ(w.reflect_escaped(ps), 1u);
  EXPECT_NEAR(ps[0].pos.x, 1.99, 1e-15);
  EXPECT_DOUBLE_EQ(ps[0].vel.x, -3);
  EXPECT_DOUBLE_EQ(ps[0].vel_half.x, -3);
  EXPECT_NO_THROW(w.check_inside(ps));
  ps[0].pos.y = -0.1;
  EXPECT_THROW(w.check_inside(ps), pik::Error);
}

TEST(Walls, EmptyBoxRefused) {
  pik::Box<double, 2> b;
  b.lo = {0, 0}, b.hi = {1, 0};
  EXPECT_THROW(pik::sph::Walls<2>{b}, pik::Error);
}

// Bad parameters are refused before a run, with the reason in the message.
TEST(ConvectionParams, Refused) {
  auto refused = [](auto edit, const char* why) {
    convection::Params p;
    p.xi = 2.5e23;
    edit(p);
    try {
      p.check();
    } catch (const pik::Error& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
      return;
    }
    ADD_FAILURE() << "accepted: " << why;
  };
  refused([](auto& p) { p.law = "exp", p.contrast = -10; }, "viscosity must be positive");
  refused([](auto& p) { p.xi = 0.5; }, "at least 1");
  refused([](auto& p) { p.c = 0.9; }, "at least 1");
  refused([](auto& p) { p.rsst = 0.5; }, "at least 1");
  refused([](auto& p) { p.nz = 0; }, "particles across the depth");
  refused([](auto& p) { p.aspect = 0.01; }, "box is empty");
  refused([](auto& p) { p.ra = -1; }, "Rayleigh");
  // modified Prandtl number 2.5e-4: four orders of magnitude below 10
  refused([](auto& p) { p.xi = 1e29; }, "orders of magnitude");
  convection::Params ok;
  ok.xi = 2.5e23;
  EXPECT_TRUE(ok.check().empty());
  ok.xi = 2.5e25;  // modified Prandtl number 1: a warning, not an error
  EXPECT_FALSE(ok.check().empty());
}

// The modified numbers: only xi c^2 enters the modified Prandtl number.
TEST(ConvectionParams, ModifiedNumbers) {
  convection::Params a, b;
  a.xi = 4e23, a.c = 1;
  b.xi = 1e23, b.c = 2;
  EXPECT_DOUBLE_EQ(a.modified_pr(1), b.modified_pr(1));
  EXPECT_NEAR(a.modified_pr(1), 2.5e25 / 4e23, 1e-9);
  a.rsst = 10;
  EXPECT_NEAR(a.sound_speed(1), std::sqrt(1.3e6 / (4e23 / 2.5e25)) / 10, 1e-9);
}

TEST(ConvectionLayerMean, LinearProfileIsExact) {
  std::vector<double> z, t;
  for (int i = 0; i < 400; ++i) z.push_back((i % 20 + 0.5) / 20 + 0.003 * (i % 7)), t.push_back(1 - z.back());
  convection::LayerMean m;
  m.fit(z, t, 20);
  for (double x : {0.1, 0.3, 0.55, 0.9}) EXPECT_NEAR(m(x), 1 - x, 0.01);
}

}  // namespace
