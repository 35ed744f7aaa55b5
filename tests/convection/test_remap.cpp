// The remap of `convection --init` (examples/convection/Remap.hpp): interpolation of an
// analytic field that satisfies the box's boundary conditions from a coarse, jittered
// lattice (a run's particles after shifting) onto a finer one, in the interior and at the
// walls; what the wall images buy; and the checks on the file read_init makes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <pik/io/SnapshotIo.hpp>

#include "Remap.hpp"

namespace {

using convection::Remap;
using convection::Sample;
using convection::Vec3d;

// T = 1 - z + A cos(pi x) sin(pi z) (the benchmark's initial field) and the cellular flow
// of the stream function psi = sin(pi x) sin(pi z): v = (pi sin(pi x) cos(pi z),
// -pi cos(pi x) sin(pi z)), times cos(pi y) in 3D with the roll's axis along y. Both
// satisfy the box's conditions: T = 1 at z = 0, 0 at z = 1, dT/dx = 0 at the sides;
// normal velocity 0 and normal derivative of the tangential velocity 0 on every wall.
// (|v| <= pi; the gradients of T are O(1).)
constexpr double A = 0.1;

template <int D>
double t_exact(const Vec3d& p) {
  const double x = p.x, z = p[D - 1];
  const double y = D == 3 ? std::cos(M_PI * p.y) : 1.0;
  return 1 - z + A * std::cos(M_PI * x) * y * std::sin(M_PI * z);
}
template <int D>
Vec3d v_exact(const Vec3d& p) {
  const double x = p.x, z = p[D - 1];
  const double vx = M_PI * std::sin(M_PI * x) * std::cos(M_PI * z);
  const double vz = -M_PI * std::cos(M_PI * x) * std::sin(M_PI * z);
  if constexpr (D == 2) return {vx, vz, 0};
  else return {vx, 0, vz};
}

// A pressure perturbation even across every wall (zero normal derivative), as the images
// continue it: cos(pi x) cos(pi z) (times cos(pi y) in 3D).
template <int D>
double p_exact(const Vec3d& p) {
  return std::cos(M_PI * p.x) * std::cos(M_PI * p[D - 1]) * (D == 3 ? std::cos(M_PI * p.y) : 1.0);
}

// A lattice of n per unit length (cell centres) in the unit box, each point moved by up to
// `jitter` spacings in every direction (kept inside the box).
template <int D>
std::vector<Vec3d> lattice(int n, double jitter, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-jitter, jitter);
  std::vector<Vec3d> out;
  const double dx = 1.0 / n;
  for (int k = 0; k < (D == 3 ? n : 1); ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        Vec3d p{(i + 0.5) * dx, (j + 0.5) * dx, D == 3 ? (k + 0.5) * dx : 0.0};
        for (int d = 0; d < D; ++d) p[std::size_t(d)] = std::clamp(p[std::size_t(d)] + u(rng) * dx, 1e-9, 1 - 1e-9);
        out.push_back(p);
      }
  return out;
}

template <int D>
std::vector<Sample<D>> sample(const std::vector<Vec3d>& pts) {
  std::vector<Sample<D>> s;
  for (const auto& p : pts) {
    Sample<D> q;
    q.pos = p, q.temp = t_exact<D>(p), q.vel = v_exact<D>(p), q.pres = p_exact<D>(p);
    s.push_back(q);
  }
  return s;
}

struct Errors {
  double t_inner = 0, t_wall = 0, v_inner = 0, v_wall = 0;  // largest |error|; v relative to max |v| = pi
  double t_min = 1e300, t_max = -1e300;
  double p_all = 0;  // largest |error| of the pressure (its amplitude is 1)
};

// Remaps a coarse (nc across, jittered) field onto the fine lattice (nf across, regular);
// "wall" are the fine points within one coarse support radius of a wall.
template <int D>
Errors remap_errors(int nc, int nf, int order, bool mirror, double radius_spacings = 2.0) {
  const Remap<D> r(sample<D>(lattice<D>(nc, 0.25, 7)), convection::convection_walls<D>(1.0), radius_spacings / nc, order,
                   mirror);
  Errors e;
  for (const auto& p : lattice<D>(nf, 0.0, 0)) {
    double dist = 1;
    for (int d = 0; d < D; ++d) dist = std::min({dist, p[std::size_t(d)], 1 - p[std::size_t(d)]});
    const bool wall = dist < r.radius();
    const auto v = r.at(p);
    const double et = std::abs(v.temp - t_exact<D>(p)), ev = pik::norm(v.vel - v_exact<D>(p)) / M_PI;
    (wall ? e.t_wall : e.t_inner) = std::max(wall ? e.t_wall : e.t_inner, et);
    (wall ? e.v_wall : e.v_inner) = std::max(wall ? e.v_wall : e.v_inner, ev);
    e.t_min = std::min(e.t_min, v.temp), e.t_max = std::max(e.t_max, v.temp);
    e.p_all = std::max(e.p_all, std::abs(v.pres - p_exact<D>(p)));
  }
  std::printf("  %dD %d -> %d across, order %d, mirror %s: max |dT| interior %.2e wall %.2e; max |dv|/max|v| "
              "interior %.2e wall %.2e; T in [%.4f, %.4f]; max |dp| %.2e\n",
              D, nc, nf, order, mirror ? "on" : "off", e.t_inner, e.t_wall, e.v_inner, e.v_wall, e.t_min, e.t_max,
              e.p_all);
  return e;
}

// 2D, 24 across (jittered by a quarter spacing) -> 48 across, quadratic-corrected Shepard
// (order 2, what --init uses) with the wall images: T within 1e-4 of Delta T and v within
// 0.1 % of max |v| everywhere, the walls included (measured 3.1e-5 and 3.4e-4); no new
// extrema of T.
TEST(Remap, Coarse2DToFineIsAccurateAtTheWalls) {
  const Errors e = remap_errors<2>(24, 48, 2, true);
  EXPECT_LT(e.t_inner, 1e-4);
  EXPECT_LT(e.t_wall, 1e-4);
  EXPECT_LT(e.v_inner, 1e-3);
  EXPECT_LT(e.v_wall, 1e-3);
  EXPECT_LT(e.p_all, 1e-3);
  EXPECT_GE(e.t_min, 0.0);
  EXPECT_LE(e.t_max, 1.0);
}

// Without the images the points near a wall see a one-sided neighbourhood: the fit
// extrapolates there, several times worse than with the images (the wall values
// themselves: TakesTheWallValuesOnTheWalls below).
TEST(Remap, WithoutWallImagesTheWallsAreWrong) {
  // measured: T 1.4e-2 against 2.9e-5, v 4.0e-2 against 3.0e-4 (a linear fit, order 1,
  // extrapolates the smooth velocity about as well one-sided, but not the temperature)
  const Errors on = remap_errors<2>(24, 48, 2, true), off = remap_errors<2>(24, 48, 2, false);
  EXPECT_GT(off.t_wall, 30 * on.t_wall);
  EXPECT_GT(off.v_wall, 30 * on.v_wall);
  EXPECT_LT(off.t_inner, 2 * on.t_inner);  // the interior does not see the walls
  const Errors on1 = remap_errors<2>(24, 48, 1, true), off1 = remap_errors<2>(24, 48, 1, false);
  EXPECT_GT(off1.t_wall, 5 * on1.t_wall);
}

// Each order of correction buys an order of the error: the plain Shepard mean (order 0) is
// off by O(R f') on a jittered set, the linear fit by O(R^2 f''), the quadratic by O(R^3).
TEST(Remap, HigherOrderIsMoreAccurate) {
  const Errors e0 = remap_errors<2>(24, 48, 0, true), e1 = remap_errors<2>(24, 48, 1, true),
               e2 = remap_errors<2>(24, 48, 2, true);
  auto t = [](const Errors& e) { return std::max(e.t_inner, e.t_wall); };
  auto v = [](const Errors& e) { return std::max(e.v_inner, e.v_wall); };
  EXPECT_GT(t(e0), 5 * t(e1));
  EXPECT_GT(t(e1), 5 * t(e2));
  EXPECT_GT(v(e0), 3 * v(e1));
  EXPECT_GT(v(e1), 5 * v(e2));
}

// The linear fit's error falls about as the square of the spacing from 12 to 24 to 48
// across, the quadratic's faster: a coarse field refines, it does not carry a fixed
// smoothing error.
TEST(Remap, ConvergesAtSecondOrder) {
  const double e12 = remap_errors<2>(12, 96, 1, true).t_wall, e24 = remap_errors<2>(24, 96, 1, true).t_wall,
               e48 = remap_errors<2>(48, 96, 1, true).t_wall;
  EXPECT_GT(e12 / e24, 2.5);
  EXPECT_GT(e24 / e48, 2.5);
  const double q12 = remap_errors<2>(12, 96, 2, true).t_wall, q24 = remap_errors<2>(24, 96, 2, true).t_wall;
  EXPECT_GT(q12 / q24, 5.0);
}

// 3D (edges and corners: 3 and 7 images), 8 -> 12 across: coarser, so looser bounds
// (measured 9.4e-4 and 9.4e-3).
TEST(Remap, Coarse3DToFine) {
  const Errors e = remap_errors<3>(8, 12, 2, true);
  EXPECT_LT(std::max(e.t_inner, e.t_wall), 2e-3);
  EXPECT_LT(std::max(e.v_inner, e.v_wall), 2e-2);
}

// On the walls themselves the mirrored set is symmetric about the wall and the field's
// deviation from the boundary value odd, so the interpolant takes the boundary values
// exactly: T = 1 at the bottom and 0 at the top, zero normal velocity on every face, at
// every point of the faces, corners and edges included. Without the images it does not.
template <int D>
void wall_values(bool mirror, double& t_err, double& vn_err) {
  const Remap<D> r(sample<D>(lattice<D>(D == 2 ? 16 : 8, 0.25, 11)), convection::convection_walls<D>(1.0),
                   2.0 / (D == 2 ? 16 : 8), 2, mirror);
  t_err = vn_err = 0;
  for (const auto& p0 : lattice<D>(D == 2 ? 20 : 10, 0.0, 0))
    for (int axis = 0; axis < D; ++axis)
      for (int side = 0; side < 2; ++side) {
        Vec3d p = p0;
        p[std::size_t(axis)] = side;  // onto the face
        const auto v = r.at(p);
        if (axis == D - 1) t_err = std::max(t_err, std::abs(v.temp - (side ? 0.0 : 1.0)));
        vn_err = std::max(vn_err, std::abs(v.vel[std::size_t(axis)]) / M_PI);
      }
  std::printf("  %dD on the faces, mirror %s: max |T - T_wall| %.2e, max |v_n| / max|v| %.2e\n", D,
              mirror ? "on" : "off", t_err, vn_err);
}

// Exact wall values with the mirror, clearly wrong ones without it.
template <int D>
void expect_wall_values() {
  double t, vn;
  wall_values<D>(true, t, vn);
  EXPECT_LT(t, 1e-12) << D << "D";
  EXPECT_LT(vn, 1e-12) << D << "D";
  wall_values<D>(false, t, vn);
  EXPECT_GT(t, 1e-3) << D << "D";
  EXPECT_GT(vn, 1e-2) << D << "D";
}

TEST(Remap, TakesTheWallValuesOnTheWalls) {
  expect_wall_values<2>();
  expect_wall_values<3>();
}

// A fine field onto a coarse lattice (--init may also go down in resolution).
TEST(Remap, FineToCoarse) {
  const Errors e = remap_errors<2>(48, 16, 2, true);
  EXPECT_LT(std::max(e.t_inner, e.t_wall), 1e-4);
  EXPECT_LT(std::max(e.v_inner, e.v_wall), 1e-3);
}

TEST(Remap, RefusesBadArguments) {
  const auto walls = convection::convection_walls<2>(1.0);
  EXPECT_THROW(Remap<2>(sample<2>(lattice<2>(4, 0, 0)), walls, 0.0), pik::Error);
  EXPECT_THROW(Remap<2>(sample<2>(lattice<2>(4, 0, 0)), walls, 0.5, 3), pik::Error);
  EXPECT_THROW(Remap<2>({}, walls, 0.5), pik::Error);
  // a point with no sample within reach is an error, not a silent 0
  std::vector<Sample<2>> one(1);
  one[0].pos = {0.9, 0.9, 0};
  const Remap<2> r(one, walls, 0.05, 1, false);
  EXPECT_THROW(r.at({0.1, 0.1, 0}), pik::Error);
}

// read_init: the file's problem must be this run's; a missing attribute, a missing column
// or a NaN are refused with a message that names the file and the cause.
class ReadInit : public ::testing::Test {
 protected:
  std::filesystem::path dir = std::filesystem::temp_directory_path() / ("pik_test_remap_" + std::to_string(::getpid()));
  void SetUp() override { std::filesystem::create_directories(dir); }
  void TearDown() override { std::filesystem::remove_all(dir); }

  pik::io::Snapshot snapshot(int n) const {
    pik::io::Snapshot s;
    const auto pts = lattice<2>(n, 0.1, 3);
    s.resize(pts.size());
    auto& t = s.column("Temperature", 1);
    for (std::size_t i = 0; i < pts.size(); ++i)
      s.id[i] = i, s.mass[i] = 1.0 / (n * n), s.pos[i] = pts[i], s.vel[i] = v_exact<2>(pts[i]) * 3.0,
      t.data[i] = t_exact<2>(pts[i]);
    s.time = 0.01, s.step = 77;
    s.attr.set("convection.dim", 2), s.attr.set("convection.ra", 1e4), s.attr.set("convection.law", "constant");
    s.attr.set("convection.contrast", 1.0), s.attr.set("convection.aspect", 1.0), s.attr.set("convection.nz", n);
    s.attr.set("convection.c", 3.0);
    return s;
  }
  std::string write(const pik::io::Snapshot& s, const char* name) const {
    const std::string p = (dir / name).string();
    pik::io::write_snapshot(p, s, pik::io::Format::binary);
    return p;
  }
  static std::string error_of(const std::string& path, const convection::Params& p) {
    try {
      (void)convection::read_init<2>(path, p);
    } catch (const pik::Error& e) {
      return e.what();
    }
    return "";
  }
};

TEST_F(ReadInit, ReadsAndRemapsAMatchingSnapshot) {
  const std::string path = write(snapshot(16), "good.pbin");
  convection::Params p;  // Ra 1e4, constant viscosity, aspect 1 (c 1)
  const auto src = convection::read_init<2>(path, p);
  EXPECT_EQ(src.samples.size(), 256u);
  EXPECT_EQ(src.nz, 16);
  EXPECT_DOUBLE_EQ(src.c, 3.0);
  EXPECT_DOUBLE_EQ(src.time, 0.03);  // code time x c
  EXPECT_EQ(src.step, 77u);
}

TEST_F(ReadInit, RefusesAnotherProblemOrABadFile) {
  const std::string good = write(snapshot(8), "good.pbin");
  auto expect = [&](const std::string& path, const convection::Params& p, const std::string& want) {
    const std::string e = error_of(path, p);
    EXPECT_NE(e.find(want), std::string::npos) << "wanted '" << want << "', got '" << e << "'";
    EXPECT_NE(e.find(path), std::string::npos) << e;
  };
  convection::Params p;
  p.ra = 1e5;
  expect(good, p, "Rayleigh number 10000, this run 100000 (--ra)");
  p = {}, p.aspect = 2;
  expect(good, p, "aspect ratio 1, this run 2 (--aspect)");
  p = {}, p.law = "exp", p.contrast = 1000;
  expect(good, p, "viscosity law constant, this run exp (--viscosity)");
  // another resolution, xi, c or RSST factor is what --init is for
  p = {}, p.nz = 64, p.xi = 1e20, p.c = 10, p.rsst = 7;
  EXPECT_EQ(error_of(good, p), "");
  p = {};
  auto s = snapshot(8);
  s.attr = {};
  s.attr.set("convection.dim", 2);
  expect(write(s, "noattr.pbin"), p, "not a snapshot of the convection program (no attribute convection.ra)");
  s = snapshot(8);
  s.extra.clear();
  expect(write(s, "nocol.pbin"), p, "no Temperature column");
  s = snapshot(8);
  s.column("Temperature", 1).data[5] = std::nan("");
  expect(write(s, "nan.pbin"), p, "particle 5 has a non-finite temperature");
  s = snapshot(8);
  s.pos[3].y = 1.5;
  expect(write(s, "outside.pbin"), p, "lies outside the box");
  const std::string corrupt = (dir / "corrupt.pbin").string();
  std::FILE* f = std::fopen(corrupt.c_str(), "wb");
  std::fputs("not a snapshot at all", f);
  std::fclose(f);
  expect(corrupt, p, "cannot read the snapshot");
  expect((dir / "missing.pbin").string(), p, "cannot read the snapshot");
}

}  // namespace
