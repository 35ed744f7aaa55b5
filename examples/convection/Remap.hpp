/// \file Remap.hpp
/// \brief `convection --init FILE`: a run started from another run's snapshot at another
///        resolution. The new model keeps its own fresh lattice (positions, masses, SPH
///        density); each new particle's temperature, velocity and (by default) pressure
///        perturbation K rho1 are interpolated from the old particles, mirrored across the
///        walls so that the interpolant near a wall sees the boundary conditions.
///
/// Interpolation (Shepard 1968, Proc. 23rd ACM National Conference, 517: the normalised
/// kernel-weighted mean f(x) = sum_j w_j f_j / sum_j w_j, w_j = W(|x - x_j| / R) with
/// the Wendland C2 shape, support radius R), corrected by the moving least-squares fit
/// (Lancaster & Salkauskas 1981, Math. Comp. 37, 141): f(x) = c_0 of the weighted fit
/// f_j ~ c_0 + c . u_j (+ the quadratic terms u_a u_b), u_j = (x_j - x) / R. `order` 0 is
/// the plain Shepard mean, off by O(R f') on an irregular set; 1 is exact for linear fields
/// (error O(R^2 f''); on case 1a's velocity at 10 across that is v_rms 3.5 % low); 2, the
/// default, exact for quadratic ones (measured in tests/convection/test_remap.cpp: 10-20
/// times smaller errors than order 1 at 24 across). Where the neighbours cannot determine
/// the fit it drops an order. The temperature is limited to the range of the values it was
/// formed from (no new extrema from an overshoot at a boundary layer) and to that of the
/// fixed wall temperatures (the images of a T = 0 wall carry -T, so next to it the first
/// limit alone would allow T < 0; conduction keeps T between the walls' values);
/// the velocity, smooth, is not (a limiter would clip its maxima at the walls).
///
/// The images are those of the running model (pik/sph/Walls.hpp): free-slip walls all
/// round (normal velocity odd, tangential even), fixed temperature at the bottom (1) and
/// top (0), where the image temperature is 2 T_w - T (odd about the wall value), and
/// insulating sides (T even); the pressure is even across every wall (the images copy it). Near a wall the mirrored set continues the field by the
/// symmetry the boundary condition implies, so the interpolant there is as accurate as in
/// the interior and takes the wall values (T = 1, 0; v_n = 0) at the wall.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <span>
#include <string>
#include <vector>

#include <pik/Box.hpp>
#include <pik/Error.hpp>
#include <pik/io/Snapshot.hpp>
#include <pik/io/SnapshotIo.hpp>
#include <pik/sph/Walls.hpp>

#include "Convection.hpp"

namespace convection {

/// One sample of the old run's fields (or of its wall image).
template <int D>
struct Sample {
  Vec3d pos{}, vel{};
  double temp = 0;
  double pres = 0;  ///< pressure perturbation K rho1 (even across every wall)
  pik::Vec<double, D> getPos() const { return pik::sph::first_dims<D>(pos); }
  void setPos(const pik::Vec<double, D>& p) { pik::sph::set_first_dims<D>(pos, p); }
  /// Walls.hpp reflects the velocity; the temperature as the face says.
  void mirror(int, int, const pik::sph::WallFace& f) { temp = f.image_temperature(temp); }
};

/// The walls of the convection box of width `width` (depth 1): free slip all round,
/// insulating sides, T = 1 at the bottom and 0 at the top (as Model's).
template <int D>
pik::sph::Walls<D> convection_walls(double width) {
  pik::Box<double, D> box;
  for (int d = 0; d < D; ++d) box.lo[d] = 0, box.hi[d] = d == D - 1 ? 1.0 : width;
  pik::sph::Walls<D> w(box);
  using Kind = pik::sph::WallFace::Kind;
  for (int d = 0; d < D - 1; ++d) w.set_axis(d, {Kind::free_slip, false, 0}, {Kind::free_slip, false, 0});
  w.set_axis(D - 1, {Kind::free_slip, true, 1.0}, {Kind::free_slip, true, 0.0});
  return w;
}

/// Interpolates temperature and velocity from scattered samples in a walled box.
template <int D>
class Remap {
 public:
  struct Value {
    Vec3d vel{};
    double temp = 0, pres = 0;
    int neighbours = 0;  ///< samples (images included) within the support radius
  };

  /// `samples` inside the box of `walls`; `radius` the support radius R of the weights
  /// (a few sample spacings); `mirror` false leaves the walls out (for tests: what the
  /// images buy); `order` 0 plain Shepard, 1 or 2 with the linear or quadratic correction.
  Remap(std::vector<Sample<D>> samples, const pik::sph::Walls<D>& walls, double radius, int order = 2,
        bool mirror = true)
      : r_(radius), order_(order), box_(walls.box()) {
    int fixed = 0;  // no internal heating: with two or more fixed-temperature walls T stays between them
    for (int d = 0; d < D; ++d)
      for (int side = 0; side < 2; ++side)
        if (const auto& f = walls.face(d, side); f.is_wall() && f.fixed_temperature)
          t_lo_ = std::min(t_lo_, f.temperature), t_hi_ = std::max(t_hi_, f.temperature), ++fixed;
    if (fixed < 2) t_lo_ = -1e300, t_hi_ = 1e300;
    if (!(radius > 0) || !std::isfinite(radius)) throw pik::Error("remap: the support radius must be positive");
    if (order < 0 || order > 2) throw pik::Error("remap: the order must be 0 (Shepard), 1 (linear) or 2 (quadratic)");
    if (samples.empty()) throw pik::Error("remap: no samples to interpolate from");
    if (mirror) {
      std::vector<Sample<D>> img = walls.template images_of<Sample<D>>(std::span<const Sample<D>>(samples), radius);
      n_images_ = img.size();
      samples.insert(samples.end(), img.begin(), img.end());
    }
    s_ = std::move(samples);
    // cells of side R over the box widened by R (every image within reach lies there)
    std::size_t ncell = 1;
    for (int d = 0; d < D; ++d) {
      lo_[d] = box_.lo[d] - r_;
      n_[d] = std::max(1, int(std::ceil((box_.hi[d] - box_.lo[d] + 2 * r_) / r_)));
      ncell *= std::size_t(n_[d]);
    }
    start_.assign(ncell + 1, 0);
    std::vector<std::size_t> cell(s_.size());
    for (std::size_t i = 0; i < s_.size(); ++i) cell[i] = cell_of(s_[i].pos), ++start_[cell[i] + 1];
    for (std::size_t c = 0; c < ncell; ++c) start_[c + 1] += start_[c];
    order_idx_.resize(s_.size());
    std::vector<std::size_t> fill(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < s_.size(); ++i) order_idx_[fill[cell[i]]++] = i;
  }

  std::size_t images() const { return n_images_; }
  double radius() const { return r_; }

  /// The fields at x (a point of the box).
  Value at(const Vec3d& x) const {
    // weighted moments of the fit f_j ~ sum_k c_k p_k(x_j - x) with the basis
    // p = (1, u_1..u_D, u_a u_b for a <= b), u = (x_j - x) / R, for the 4 fields
    // (T, v_x, v_y, v_z, p1) at once; order 0 and 1 use the leading block
    double a[M2][M2] = {}, b[M2][NF] = {};
    double lo[1] = {1e300}, hi[1] = {-1e300};  // of the temperatures seen
    Value out;
    std::array<int, D> c0{};
    for (int d = 0; d < D; ++d) c0[d] = std::clamp(int(std::floor((x[d] - lo_[d]) / r_)), 0, n_[d] - 1);
    const int m = order_ == 0 ? 1 : order_ == 1 ? M1 : M2;
    visit(c0, [&](std::size_t j) {
      const Sample<D>& s = s_[j];
      double u[D], q2 = 0;
      for (int d = 0; d < D; ++d) u[d] = (s.pos[d] - x[d]) / r_, q2 += u[d] * u[d];
      if (q2 >= 1) return;
      const double q = std::sqrt(q2), w = std::pow(1 - q, 4) * (1 + 4 * q);  // Wendland C2
      double p[M2];
      p[0] = 1;
      int k = 1;
      for (int d = 0; d < D; ++d) p[k++] = u[d];
      for (int d = 0; d < D; ++d)
        for (int e = d; e < D; ++e) p[k++] = u[d] * u[e];
      const double f[NF] = {s.temp, s.vel.x, s.vel.y, s.vel.z, s.pres};
      for (int r = 0; r < m; ++r) {
        for (int l = 0; l < m; ++l) a[r][l] += w * p[r] * p[l];
        for (int c = 0; c < NF; ++c) b[r][c] += w * p[r] * f[c];
      }
      lo[0] = std::min(lo[0], f[0]), hi[0] = std::max(hi[0], f[0]);
      ++out.neighbours;
    });
    if (out.neighbours == 0)
      throw pik::Error("remap: no old particle within " + std::to_string(r_) + " of (" + std::to_string(x[0]) + ", " +
                       std::to_string(x[1]) + (D == 3 ? ", " + std::to_string(x[2]) : std::string()) + ")");
    double f[NF];
    for (int c = 0; c < NF; ++c) f[c] = b[0][c] / a[0][0];  // Shepard
    // the highest order the neighbours determine (too few, or all on a line: one lower)
    if (!(m == M2 && solve(a, b, M2, f)) && m >= M1) solve(a, b, M1, f);
    out.temp = std::clamp(std::clamp(f[0], lo[0], hi[0]), t_lo_, t_hi_), out.vel = {f[1], f[2], f[3]}, out.pres = f[4];
    return out;
  }

 private:
  static constexpr int M1 = D + 1, M2 = (D + 1) * (D + 2) / 2;  // unknowns of the linear, quadratic fit
  static constexpr int NF = 5;  // fields: T, v_x, v_y, v_z, p1

  /// c_0 of the weighted least-squares fit on the leading m x m block of the moments
  /// (Gaussian elimination with partial pivoting, on copies); false, f untouched, when the
  /// block is (nearly) singular.
  static bool solve(const double (&a0)[M2][M2], const double (&b0)[M2][NF], int m, double (&f)[NF]) {
    double a[M2][M2], b[M2][NF];
    for (int r = 0; r < m; ++r) {
      for (int l = 0; l < m; ++l) a[r][l] = a0[r][l];
      for (int c = 0; c < NF; ++c) b[r][c] = b0[r][c];
    }
    const double scale = a[0][0];
    for (int k = 0; k < m; ++k) {
      int piv = k;
      for (int r = k + 1; r < m; ++r)
        if (std::abs(a[r][k]) > std::abs(a[piv][k])) piv = r;
      if (std::abs(a[piv][k]) < 1e-9 * scale) return false;
      if (piv != k) {
        for (int l = 0; l < m; ++l) std::swap(a[k][l], a[piv][l]);
        for (int c = 0; c < NF; ++c) std::swap(b[k][c], b[piv][c]);
      }
      for (int r = k + 1; r < m; ++r) {
        const double g = a[r][k] / a[k][k];
        for (int l = k; l < m; ++l) a[r][l] -= g * a[k][l];
        for (int c = 0; c < NF; ++c) b[r][c] -= g * b[k][c];
      }
    }
    double sol[M2][NF];
    for (int k = m - 1; k >= 0; --k)
      for (int c = 0; c < NF; ++c) {
        double v = b[k][c];
        for (int l = k + 1; l < m; ++l) v -= a[k][l] * sol[l][c];
        sol[k][c] = v / a[k][k];
      }
    for (int c = 0; c < NF; ++c) f[c] = sol[0][c];
    return true;
  }

  std::size_t cell_of(const Vec3d& x) const {
    std::size_t c = 0;
    for (int d = D - 1; d >= 0; --d) {
      const int i = std::clamp(int(std::floor((x[d] - lo_[d]) / r_)), 0, n_[d] - 1);
      c = c * std::size_t(n_[d]) + std::size_t(i);
    }
    return c;
  }

  /// Calls fn(j) for every sample in the 3^D cells around c0.
  template <class Fn>
  void visit(const std::array<int, D>& c0, Fn&& fn) const {
    std::array<int, D> c{}, k{};
    k.fill(-1);
    while (true) {
      bool ok = true;
      for (int e = 0; e < D; ++e) {
        c[e] = c0[e] + k[e];
        if (c[e] < 0 || c[e] >= n_[e]) ok = false;
      }
      if (ok) {
        std::size_t id = 0;
        for (int e = D - 1; e >= 0; --e) id = id * std::size_t(n_[e]) + std::size_t(c[e]);
        for (std::size_t m = start_[id]; m < start_[id + 1]; ++m) fn(order_idx_[m]);
      }
      int e = 0;
      while (e < D && ++k[e] > 1) k[e] = -1, ++e;
      if (e == D) break;
    }
  }

  double r_;
  double t_lo_ = 1e300, t_hi_ = -1e300;  ///< the fixed wall temperatures' range (the limit on T)
  int order_;
  pik::Box<double, D> box_;
  std::vector<Sample<D>> s_;
  std::size_t n_images_ = 0;
  std::array<double, D> lo_{};
  std::array<int, D> n_{};
  std::vector<std::size_t> start_, order_idx_;
};

/// What --init read from the old run's snapshot.
template <int D>
struct InitSource {
  std::string path;
  std::vector<Sample<D>> samples;
  double time = 0;       ///< the snapshot's time, d^2 / kappa (code time x its c)
  std::uint64_t step = 0;
  int nz = 0;            ///< its resolution (particles across the depth)
  double c = 1;          ///< its VIM factor c (velocities in the file are c v)
  double width = 1;      ///< its box width
  bool has_pressure = false;  ///< the file has DensityPerturbation (and the bulk modulus K)
  std::string problem;        ///< its Rayleigh number and viscosity law, for the header line
  bool other_problem = false; ///< they differ from this run's (a continuation)
};

/// Reads the snapshot `path` (any format the driver writes, a checkpoint included) of a
/// convection run and checks that it is the same problem as `p`: dimension, Rayleigh
/// number, viscosity law and contrast, aspect ratio. With `continuation` only the
/// geometry (dimension, aspect ratio) must agree: the Rayleigh number and the viscosity
/// law and contrast may differ (a parameter continuation: e.g. the variable-viscosity case
/// 2a started from the steady cell of the isoviscous case 1a). Throws pik::Error naming
/// the file and what differs or is missing.
template <int D>
InitSource<D> read_init(const std::string& path, const Params& p, bool continuation = false) {
  const std::string where = "--init " + path + ": ";
  pik::io::Snapshot s;
  try {
    s = pik::io::read_snapshot(path);
  } catch (const std::exception& e) {
    throw pik::Error(where + "cannot read the snapshot (" + e.what() + ")");
  }
  const auto& at = s.attr;
  for (const char* k : {"convection.dim", "convection.ra", "convection.law", "convection.contrast", "convection.aspect",
                        "convection.nz", "convection.c"})
    if (!at.has(k)) throw pik::Error(where + "not a snapshot of the convection program (no attribute " + k + ")");
  auto num = [&](const char* k) {
    try {
      return at.get_double(k);
    } catch (const std::exception& e) {
      throw pik::Error(where + e.what());
    }
  };
  auto differs = [](double a, double b) { return !(std::abs(a - b) <= 1e-12 * std::max(std::abs(a), std::abs(b))); };
  // `physics`: a difference that --init-problem continuation accepts (not the geometry)
  auto refuse = [&](const std::string& what, const std::string& old, const std::string& now, const char* opt,
                    bool physics = false) {
    throw pik::Error(where + "the snapshot has " + what + " " + old + ", this run " + now + " (" + opt +
                     "): --init remaps another resolution of the same problem only" +
                     (physics ? " (--init-problem continuation: from another Ra, viscosity law or contrast)" : ""));
  };
  auto str = [](double v) {
    char b[40];
    std::snprintf(b, sizeof b, "%.10g", v);
    return std::string(b);
  };
  if (differs(num("convection.dim"), D)) refuse("dimension", str(num("convection.dim")), str(D), "--dim");
  const std::string law = at.get_string("convection.law");
  const bool ra_differs = differs(num("convection.ra"), p.ra), law_differs = law != p.law;
  const bool contrast_differs = p.law == "exp" && differs(num("convection.contrast"), p.contrast);
  if (!continuation) {
    if (ra_differs) refuse("Rayleigh number", str(num("convection.ra")), str(p.ra), "--ra", true);
    if (law_differs) refuse("viscosity law", law, p.law, "--viscosity", true);
    if (contrast_differs)
      refuse("viscosity contrast", str(num("convection.contrast")), str(p.contrast), "--contrast", true);
  }
  if (differs(num("convection.aspect"), p.aspect))
    refuse("aspect ratio", str(num("convection.aspect")), str(p.aspect), "--aspect");
  InitSource<D> src;
  src.path = path, src.step = s.step, src.c = num("convection.c");
  src.problem = "Ra " + str(num("convection.ra")) + ", viscosity " + law +
                (law == "exp" ? " (contrast " + str(num("convection.contrast")) + ")" : "");
  src.other_problem = ra_differs || law_differs || contrast_differs;
  src.nz = int(num("convection.nz"));
  if (src.nz < 1 || !(src.c >= 1)) throw pik::Error(where + "corrupt attributes (convection.nz, convection.c)");
  src.time = s.time * src.c;
  src.width = std::round(p.aspect * src.nz) / src.nz;
  const pik::io::Column* t = s.find("Temperature");
  if (!t || t->components != 1) throw pik::Error(where + "the snapshot has no Temperature column");
  if (s.size() == 0) throw pik::Error(where + "the snapshot holds no particles");
  // the pressure perturbation K rho1 (the RSST continuity equation's variable), if present
  const pik::io::Column* r1 = s.find("DensityPerturbation");
  if (r1 && r1->components != 1) r1 = nullptr;
  const double k_old = at.has("convection.bulk") ? num("convection.bulk") : 0;
  src.has_pressure = r1 && k_old > 0;
  const double tol = 1e-6;
  src.samples.resize(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    Sample<D>& q = src.samples[i];
    q.pos = s.pos[i], q.vel = s.vel[i], q.temp = t->data[i];
    q.pres = src.has_pressure ? k_old * r1->data[i] : 0.0;
    bool ok = std::isfinite(q.temp) && std::isfinite(pik::norm2(q.vel)) && std::isfinite(q.pres);
    for (int d = 0; d < D; ++d)
      ok = ok && q.pos[d] >= -tol && q.pos[d] <= (d == D - 1 ? 1.0 : src.width) + tol;
    if (!ok)
      throw pik::Error(where + "particle " + std::to_string(s.id[i]) +
                       " has a non-finite temperature, velocity or pressure, or lies outside the box (a run that blew up?)");
  }
  return src;
}

/// Sets the temperature and velocity of every particle of `model` (a freshly constructed
/// Model: lattice positions, its own density and pressure) from `src`. The support radius
/// is `radius_spacings` old spacings. Velocities are rescaled from the old run's VIM c to
/// this run's (the files hold code velocities c v). With `pressure`, the dynamic pressure
/// perturbation K rho1 is carried too (rho1 = p1 / K of this run), so that the new run does
/// not start from a fluid at rest in pressure; without, rho1 = 0. Returns the fewest
/// neighbours any particle had.
template <int D, class ModelT>
int remap_onto(ModelT& model, const InitSource<D>& src, bool pressure = true, double radius_spacings = 2.0,
               int order = 2) {
  if (pressure && !src.has_pressure)
    throw pik::Error("--init " + src.path + ": the snapshot has no DensityPerturbation column to carry the pressure from");
  const Remap<D> r(src.samples, convection_walls<D>(src.width), radius_spacings / src.nz, order);
  const double scale = model.params().c / src.c;
  int fewest = 1 << 30;
  for (auto& q : model.particles()) {
    const auto v = r.at(q.pos);
    q.temp = v.temp, q.vel = v.vel * scale;
    if (pressure) q.rho1 = q.rho1_half = v.pres / model.params().k_bulk();
    if constexpr (D == 2) q.vel.z = 0;
    q.vel_half = q.vel;
    fewest = std::min(fewest, v.neighbours);
  }
  return fewest;
}

}  // namespace convection
