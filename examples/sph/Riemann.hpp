/// \file Riemann.hpp
/// \brief Exact solution of the Riemann problem of an ideal gas (Toro 2009, ch. 4):
///        the reference the Sod shock tube is measured against.
#pragma once

#include <cmath>
#include <stdexcept>

namespace sph {

struct GasState {
  double rho, u, p;
};

class ExactRiemann {
 public:
  ExactRiemann(GasState l, GasState r, double gamma) : l_(l), r_(r), g_(gamma) {
    cl_ = std::sqrt(g_ * l_.p / l_.rho), cr_ = std::sqrt(g_ * r_.p / r_.rho);
    if (2 / (g_ - 1) * (cl_ + cr_) <= r_.u - l_.u) throw std::invalid_argument("Riemann problem creates a vacuum");
    // Newton iteration for p* (Toro eq. 4.5); start from the two-rarefaction guess.
    const double z = (g_ - 1) / (2 * g_);
    double p = std::pow((cl_ + cr_ - 0.5 * (g_ - 1) * (r_.u - l_.u)) /
                            (cl_ / std::pow(l_.p, z) + cr_ / std::pow(r_.p, z)), 1 / z);
    for (int it = 0; it < 100; ++it) {
      double fl, dfl, fr, dfr;
      f(p, l_, cl_, fl, dfl), f(p, r_, cr_, fr, dfr);
      const double dp = (fl + fr + r_.u - l_.u) / (dfl + dfr);
      p = std::max(p - dp, 1e-12 * p);
      if (std::abs(dp) < 1e-14 * p) break;
    }
    double fl, dfl, fr, dfr;
    f(p, l_, cl_, fl, dfl), f(p, r_, cr_, fr, dfr);
    ps_ = p, us_ = 0.5 * (l_.u + r_.u) + 0.5 * (fr - fl);
  }
  double pStar() const { return ps_; }
  double uStar() const { return us_; }

  /// The state at similarity coordinate s = (x - x0) / t (Toro section 4.5).
  GasState sample(double s) const {
    const double g = g_;
    if (s <= us_) {  // left of the contact
      if (ps_ > l_.p) {  // left shock
        const double sl = l_.u - cl_ * std::sqrt((g + 1) / (2 * g) * ps_ / l_.p + (g - 1) / (2 * g));
        if (s <= sl) return l_;
        const double q = ps_ / l_.p, gg = (g - 1) / (g + 1);
        return {l_.rho * (q + gg) / (gg * q + 1), us_, ps_};
      }
      const double shl = l_.u - cl_, csl = cl_ * std::pow(ps_ / l_.p, (g - 1) / (2 * g)), stl = us_ - csl;
      if (s <= shl) return l_;
      if (s >= stl) return {l_.rho * std::pow(ps_ / l_.p, 1 / g), us_, ps_};
      const double c = 2 / (g + 1) * (cl_ + (g - 1) / 2 * (l_.u - s));
      const double rho = l_.rho * std::pow(c / cl_, 2 / (g - 1));
      return {rho, 2 / (g + 1) * (cl_ + (g - 1) / 2 * l_.u + s), l_.p * std::pow(c / cl_, 2 * g / (g - 1))};
    }
    if (ps_ > r_.p) {  // right shock
      const double sr = r_.u + cr_ * std::sqrt((g + 1) / (2 * g) * ps_ / r_.p + (g - 1) / (2 * g));
      if (s >= sr) return r_;
      const double q = ps_ / r_.p, gg = (g - 1) / (g + 1);
      return {r_.rho * (q + gg) / (gg * q + 1), us_, ps_};
    }
    const double shr = r_.u + cr_, csr = cr_ * std::pow(ps_ / r_.p, (g - 1) / (2 * g)), str = us_ + csr;
    if (s >= shr) return r_;
    if (s <= str) return {r_.rho * std::pow(ps_ / r_.p, 1 / g), us_, ps_};
    const double c = 2 / (g + 1) * (cr_ - (g - 1) / 2 * (r_.u - s));
    const double rho = r_.rho * std::pow(c / cr_, 2 / (g - 1));
    return {rho, 2 / (g + 1) * (-cr_ + (g - 1) / 2 * r_.u + s), r_.p * std::pow(c / cr_, 2 * g / (g - 1))};
  }

 private:
  // Pressure function f_K(p) and its derivative (Toro eqs. 4.6, 4.7).
  void f(double p, const GasState& k, double c, double& val, double& der) const {
    const double g = g_;
    if (p > k.p) {
      const double a = 2 / ((g + 1) * k.rho), b = (g - 1) / (g + 1) * k.p, s = std::sqrt(a / (p + b));
      val = (p - k.p) * s;
      der = s * (1 - 0.5 * (p - k.p) / (b + p));
    } else {
      val = 2 * c / (g - 1) * (std::pow(p / k.p, (g - 1) / (2 * g)) - 1);
      der = 1 / (k.rho * c) * std::pow(p / k.p, -(g + 1) / (2 * g));
    }
  }
  GasState l_, r_;
  double g_, cl_, cr_, ps_, us_;
};

}  // namespace sph
