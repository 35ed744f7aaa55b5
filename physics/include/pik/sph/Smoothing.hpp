/// \file Smoothing.hpp
/// \brief The smoothing functions of pik's SPH kernels, seen from C++: their names, the
///        `--const shape=N` each kernel is compiled with, default neighbour numbers, and a
///        double-precision W(r, h) for initial conditions and analysis.
///
/// h is the support radius: W(r, h) = sigma_D h^-D f(r / h), zero for r >= h, with the
/// cubic B-spline M4 (Monaghan & Lattanzio 1985) and the Wendland (1995) C2 and C4
/// functions (normalisations from Dehnen & Aly 2012, table 1). The `.pik` kernels
/// (kernels/sph_*.pik) evaluate the same functions; tests compare the two.
#pragma once

#include <array>
#include <cmath>
#include <string>

#include <pik/Error.hpp>

namespace pik::sph {

/// The smoothing function; the value is the kernels' `shape` constant.
enum class Shape : int { cubic = 0, wendland2 = 1, wendland4 = 2 };

inline constexpr std::array<const char*, 3> shape_names = {"cubic", "wendland2", "wendland4"};

inline const char* shape_name(Shape s) { return shape_names[std::size_t(s)]; }

/// "cubic", "wendland2" or "wendland4"; anything else is an error naming the choices.
inline Shape shape_from_name(const std::string& name) {
  for (std::size_t i = 0; i < shape_names.size(); ++i)
    if (name == shape_names[i]) return Shape(int(i));
  throw Error("unknown smoothing function '" + name + "' (cubic, wendland2 or wendland4)");
}

/// Volume of the unit ball in D dimensions (2, pi, 4 pi / 3).
constexpr double unit_ball(int d) { return d == 3 ? 4.0 * M_PI / 3.0 : d == 2 ? M_PI : 2.0; }

/// Neighbour numbers (kernel mass in the support over m) for which each function is
/// stable against pairing: 3D 50 / 100 / 200, 2D 20 / 32 / 50 (Dehnen & Aly 2012, sec. 5).
inline double default_nngb(int dim, Shape s) {
  constexpr double n[2][3] = {{20, 32, 50}, {50, 100, 200}};
  return n[dim == 3 ? 1 : 0][int(s)];
}

/// f(q), f(0) = 1, zero for q >= 1.
inline double kernel_f(double q, Shape s) {
  const double a = std::max(1.0 - q, 0.0);
  switch (s) {
    case Shape::cubic: {
      const double b = std::max(0.5 - q, 0.0);
      return 2 * a * a * a - 8 * b * b * b;
    }
    case Shape::wendland2: return a * a * a * a * (1 + 4 * q);
    default: return a * a * a * a * a * a * (1 + 6 * q + 35.0 / 3.0 * q * q);
  }
}

/// sigma_D of W = sigma_D h^-D f(q): the integral of W over the plane or space is 1.
inline double kernel_sigma(int dim, Shape s) {
  constexpr double sig[2][3] = {{40.0 / 7.0, 7.0, 9.0}, {8.0, 21.0 / 2.0, 495.0 / 32.0}};
  return sig[dim == 3 ? 1 : 0][int(s)] / M_PI;
}

/// W(r, h) in D = 2 or 3 dimensions.
inline double kernel_w(double r, double h, int dim, Shape s) {
  return kernel_sigma(dim, s) / std::pow(h, dim) * kernel_f(r / h, s);
}

}  // namespace pik::sph
