/// \file Problems.hpp
/// \brief Initial conditions and figures of merit of the contact-discontinuity problems
///        that tell SSPH, DISPH and SPSPH apart: hydrostatic contacts (a strip and the
///        square, density contrast 4 to 100), the sharp-interface Kelvin-Helmholtz
///        instability and a stratified layer with a free surface of small pressure
///        scale height under gravity.
///
/// Every problem is 2D (z = 0) in the unit box, periodic in x; the particles come as
/// `Initial` records (true density included: SPSPH starts its pseudo-density from it)
/// with a tag: 0 the light fluid, 1 the dense one, 2 fixed wall particles. The measures
/// take any particle range with `pos`, `vel`, `mass` and `tag`.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <pik/pik.hpp>

namespace sph::problems {

using Vec3d = pik::Vec3<double>;

enum Tag : int { light = 0, dense = 1, wall = 2 };

/// One particle of an initial condition. rho is the density of the fluid at pos (the
/// exact one, not an SPH estimate); h a first guess of the support radius.
struct Initial {
  Vec3d pos{}, vel{};
  double mass = 0, u = 0, rho = 0, h = 0;
  int tag = light;
};

struct Setup {
  std::vector<Initial> p;
  bool periodic_y = true;    ///< false: open in y, held by wall particles (the layer)
  double gravity_y = 0;      ///< uniform external acceleration along y (the layer: -g)
  double lo_y = 0, hi_y = 1;  ///< box extent in y (x is [0, 1))
};

/// Fills the rectangle [x0, x1) x [y0, y1) with a square lattice of about `spacing`
/// (rounded so that whole rows and columns fit), density rho, pressure pres, ideal gas
/// gamma; each particle's mass gives the density exactly: rho * area / count.
inline void fill(Setup& s, double x0, double x1, double y0, double y1, double spacing, double rho, double pres,
                 double gamma, int tag, bool stagger = false) {
  const int nx = std::max(1, int(std::lround((x1 - x0) / spacing)));
  const int ny = std::max(1, int(std::lround((y1 - y0) / spacing)));
  const double dx = (x1 - x0) / nx, dy = (y1 - y0) / ny, m = rho * dx * dy;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      Initial q;
      const double shift = stagger && (j % 2) ? 0.25 : 0.0;  // alternate rows a quarter cell over
      q.pos = {x0 + (i + 0.5 + shift) * dx, y0 + (j + 0.5) * dy, 0};
      q.mass = m, q.rho = rho, q.u = pres / ((gamma - 1) * rho), q.h = 2.5 * std::max(dx, dy), q.tag = tag;
      s.p.push_back(q);
    }
}

/// Lattice spacing of the dense fluid when the light one has 1/n: equal particle masses
/// up to a contrast of 4 (spacing ratio sqrt(contrast)), beyond that the spacing ratio
/// stays 2 and the masses differ (contrast / 4): a 2D run at contrast 100 with equal
/// masses would need 10 x 10 dense particles per light one.
inline double dense_spacing(int n, double contrast) { return 1.0 / (n * std::min(std::sqrt(contrast), 2.0)); }

/// Hydrostatic contact strip: density `contrast` for |y - 1/2| < 1/4, 1 elsewhere,
/// pressure 2.5, at rest, periodic unit box. Nothing must happen.
inline Setup contact_strip(int n, double contrast, double gamma) {
  Setup s;
  fill(s, 0, 1, 0, 0.25, 1.0 / n, 1.0, 2.5, gamma, light);
  fill(s, 0, 1, 0.75, 1, 1.0 / n, 1.0, 2.5, gamma, light);
  fill(s, 0, 1, 0.25, 0.75, dense_spacing(n, contrast), contrast, 2.5, gamma, dense);
  return s;
}

/// Hydrostatic square (Saitoh & Makino 2013, sec. 4.2; their contrast 4): density
/// `contrast` in the central square of side 1/2, 1 outside, pressure 2.5, at rest.
inline Setup contact_square(int n, double contrast, double gamma) {
  Setup s;
  const double d = 1.0 / n;
  // the light fluid: the unit lattice minus the square (n even keeps the square's edges on cell edges)
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double x = (i + 0.5) * d, y = (j + 0.5) * d;
      if (std::abs(x - 0.5) < 0.25 && std::abs(y - 0.5) < 0.25) continue;
      Initial q;
      q.pos = {x, y, 0}, q.mass = d * d, q.rho = 1, q.u = 2.5 / (gamma - 1), q.h = 2.5 * d, q.tag = light;
      s.p.push_back(q);
    }
  fill(s, 0.25, 0.75, 0.25, 0.75, dense_spacing(n, contrast), contrast, 2.5, gamma, dense);
  return s;
}

/// Signed distance from the initial interface, positive outside the dense fluid's
/// initial region (strip or square), negative inside.
inline double strip_distance(const Vec3d& x) { return std::abs(x.y - 0.5) - 0.25; }
inline double square_distance(const Vec3d& x) { return std::max(std::abs(x.x - 0.5), std::abs(x.y - 0.5)) - 0.25; }

/// Spreading across an interface, unsigned: (dense particles more than `margin` outside
/// the initial region + light particles more than `margin` inside it) / dense
/// particles. 0 for a kept interface; the margin (one light-fluid spacing) ignores the
/// jitter of the particles next to it. Mixing and spreading (DISPH's failure in the
/// square without its grad-h terms) raise it; a rounding that stays inside the region does not.
template <class Particles, class Distance>
double spread(const Particles& ps, Distance&& distance, double margin) {
  long wrong = 0, ndense = 0;
  for (const auto& p : ps) {
    if (p.tag == wall) continue;
    const double d = distance(p.pos);
    if (p.tag == dense) ++ndense, wrong += d > margin;
    else wrong += d < -margin;
  }
  return double(wrong) / double(std::max(ndense, 1L));
}

/// Rounding of the square, unsigned: |1 - N / N0| with N the dense particles in the
/// four corner squares 0.15 < |x - 1/2|, |y - 1/2| < 1/4 now and N0 at t = 0 (the
/// lattice of contact_square). Standard SPH's spurious surface tension pulls the square
/// towards a disc (Saitoh & Makino 2013, fig. 6), emptying the corners: about 0.5 for a
/// disc of the same area, 0 for a kept square; a square that overfills its corners
/// counts as well.
template <class Particles>
double corner_loss(const Particles& ps, int n, double contrast) {
  auto corner = [](const Vec3d& x) {
    const double ax = std::abs(x.x - 0.5), ay = std::abs(x.y - 0.5);
    return ax > 0.15 && ay > 0.15 && ax < 0.25 && ay < 0.25;
  };
  const int m = std::max(1, int(std::lround(0.5 / dense_spacing(n, contrast))));
  long n0 = 0, now = 0;
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < m; ++i) n0 += corner({0.25 + (i + 0.5) * 0.5 / m, 0.25 + (j + 0.5) * 0.5 / m, 0});
  for (const auto& p : ps) now += p.tag == dense && corner(p.pos);
  return std::abs(1.0 - double(now) / double(std::max(n0, 1L)));
}

/// Displacement of an interface: rms over the particles that start within two light-
/// fluid spacings 2/n of it (|distance(x0)| < 2/n) of |x - x0| (nearest periodic image in
/// the unit box), in spacings 1/n; the caller keeps x0 by particle id. Standard SPH's
/// gap (its repulsion across a contact) and any mixing raise it; the jitter of a lattice
/// held at rest stays well below one spacing.
template <class Particles, class Distance>
double interface_displacement(const Particles& ps, const std::vector<Vec3d>& x0, Distance&& distance, int n) {
  double s2 = 0;
  long k = 0;
  for (const auto& p : ps) {
    if (p.tag == wall || !(std::abs(distance(x0[p.id])) < 2.0 / n)) continue;
    double dx = p.pos.x - x0[p.id].x, dy = p.pos.y - x0[p.id].y;
    dx -= std::round(dx), dy -= std::round(dy);
    s2 += (dx * dx + dy * dy) * n * n, ++k;
  }
  return std::sqrt(s2 / double(std::max(k, 1L)));
}

/// Mass-weighted rms velocity of the moving particles (tag `only`, or all when -1).
template <class Particles>
double rms_velocity(const Particles& ps, int only = -1) {
  double v2 = 0, m = 0;
  for (const auto& p : ps) {
    if (p.tag == wall || (only >= 0 && p.tag != only)) continue;
    v2 += p.mass * (p.vel.x * p.vel.x + p.vel.y * p.vel.y + p.vel.z * p.vel.z), m += p.mass;
  }
  return std::sqrt(v2 / std::max(m, 1e-300));
}

/// Sharp-interface Kelvin-Helmholtz instability (Agertz et al. 2007; Saitoh & Makino
/// 2013, sec. 4.4, with a sharp, unsmoothed interface): density `contrast` and v_x =
/// -1/2 for |y - 1/2| < 1/4, density 1 and v_x = +1/2 elsewhere, pressure 2.5, periodic
/// unit box; the mode of wavelength 1/2 seeded as v_y = A sin(4 pi x) times a Gaussian
/// exp(-(y - y_i)^2 / (2 sigma^2)) about each interface y_i, A = 0.1, sigma = 0.05 / sqrt 2
/// (the seed of Springel 2010, sec. 8.7).
struct KhSharp {
  double contrast = 2, du = 1, amplitude = 0.1, sigma = 0.05 / std::sqrt(2.0), wavenumber = 4 * M_PI;
  /// Linear growth rate of the incompressible vortex sheet (Chandrasekhar 1961, ch. XI):
  /// sigma = k dU sqrt(rho1 rho2) / (rho1 + rho2).
  double linear_rate() const { return wavenumber * du * std::sqrt(contrast) / (1 + contrast); }
};

inline Setup kh_sharp(int n, const KhSharp& k, double gamma) {
  Setup s;
  fill(s, 0, 1, 0, 0.25, 1.0 / n, 1.0, 2.5, gamma, light, true);
  fill(s, 0, 1, 0.75, 1, 1.0 / n, 1.0, 2.5, gamma, light, true);
  // equal masses at every contrast: sqrt(contrast) times the light fluid's particles per length
  fill(s, 0, 1, 0.25, 0.75, 1.0 / (n * std::sqrt(k.contrast)), k.contrast, 2.5, gamma, dense, true);
  for (auto& q : s.p) {
    const double y = q.pos.y;
    q.vel.x = q.tag == dense ? -0.5 * k.du : 0.5 * k.du;
    const double s2 = 2 * k.sigma * k.sigma;
    const double e = std::exp(-(y - 0.25) * (y - 0.25) / s2) + std::exp(-(y - 0.75) * (y - 0.75) / s2);
    q.vel.y = k.amplitude * std::sin(k.wavenumber * q.pos.x) * e;
  }
  return s;
}

/// Amplitude of the mode of wavenumber k in v_y near the interfaces y = 1/4 and 3/4
/// (McNally, Lyra & Passy 2012, eqs. 10-13: sine and cosine projections of v_y weighted
/// by exp(-k |y - y_interface|), over the particle volumes m/rho given by `volume`).
template <class Particles, class Volume>
double kh_mode(const Particles& ps, double k, Volume&& volume) {
  double s = 0, c = 0, d = 0;
  for (const auto& p : ps) {
    const double y = p.pos.y, vol = volume(p);
    const double e = y < 0.5 ? std::exp(-k * std::abs(y - 0.25)) : std::exp(-k * std::abs(y - 0.75));
    s += p.vel.y * std::sin(k * p.pos.x) * e * vol;
    c += p.vel.y * std::cos(k * p.pos.x) * e * vol;
    d += e * vol;
  }
  return 2 * std::sqrt((s / d) * (s / d) + (c / d) * (c / d));
}

/// Exponential growth rate of a mode amplitude series (t, M): least-squares slope of
/// ln M over the samples from t0 up to the first time M reaches `cap` or its maximum,
/// whichever comes first (the linear phase, before the mode saturates).
inline double growth_rate(const std::vector<std::pair<double, double>>& series, double t0, double cap) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0, n = 0;
  std::size_t peak = 0;
  for (std::size_t i = 0; i < series.size(); ++i)
    if (series[i].second > series[peak].second) peak = i;
  for (std::size_t i = 0; i <= peak && i < series.size(); ++i) {
    const auto [t, m] = series[i];
    if (m >= cap) break;
    if (t < t0 || !(m > 0)) continue;
    const double y = std::log(m);
    sx += t, sy += y, sxx += t * t, sxy += t * y, ++n;
  }
  return n > 2 ? (n * sxy - sx * sy) / (n * sxx - sx * sx) : NAN;
}

/// Stratified layer with a free surface of small pressure scale height: a dense fluid
/// (density 1, 0 <= y < 1/2) under uniform gravity g = 1 towards -y, with a light
/// fluid above (density 1/contrast, 1/2 <= y < 1). Pressure is hydrostatic: linear in
/// the dense fluid, P = P_s + g (1/2 - y), and isothermal in the light one, P = P_s
/// exp(-(y - 1/2) / H), H = P_s contrast / g. The surface pressure P_s = g h_s sets the
/// dense fluid's pressure scale height at the surface, P / |dP/dy| = h_s: `scale`
/// light-fluid lattice spacings. Equal spacing 1/n in both fluids (masses differ by the
/// contrast); three fixed rows of each fluid continue the layers below y = 0 and above
/// y = 1 as walls (open y boundary). The dense fluid is held at uniform density by its
/// temperature (u grows with depth), like a liquid.
struct Layer {
  double contrast = 1000, scale = 1, g = 1;
};

inline Setup layer(int n, const Layer& l, double gamma) {
  Setup s;
  s.periodic_y = false, s.gravity_y = -l.g;
  const double d = 1.0 / n, ps = l.g * l.scale * d, rho_l = 1.0 / l.contrast, H = ps / (l.g * rho_l);
  const int walls = 3;
  s.lo_y = -walls * d, s.hi_y = 1 + walls * d;
  for (int j = -walls; j < n + walls; ++j)
    for (int i = 0; i < n; ++i) {
      Initial q;
      const double x = (i + 0.5) * d, y = (j + 0.5) * d;
      const bool heavy = y < 0.5;
      q.pos = {x, y, 0};
      q.rho = heavy ? 1.0 : rho_l;
      const double pres = heavy ? ps + l.g * (0.5 - y) : ps * std::exp(-(y - 0.5) / H);
      q.mass = q.rho * d * d, q.u = pres / ((gamma - 1) * q.rho), q.h = 2.5 * d;
      q.tag = (j < 0 || j >= n) ? wall : heavy ? dense : light;
      s.p.push_back(q);
    }
  return s;
}

/// Displacement of the free surface: rms over the dense particles of the top two initial
/// rows (1/2 - 2/n < y0) of y - y0, in lattice spacings; the caller keeps y0.
template <class Particles>
double surface_displacement(const Particles& ps, const std::vector<double>& y0, int n) {
  double s2 = 0;
  long k = 0;
  for (const auto& p : ps) {
    if (p.tag != dense || y0[p.id] < 0.5 - 2.0 / n) continue;
    const double dy = (p.pos.y - y0[p.id]) * n;
    s2 += dy * dy, ++k;
  }
  return std::sqrt(s2 / double(std::max(k, 1L)));
}

}  // namespace sph::problems
