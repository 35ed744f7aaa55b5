/// \file ConvectionTypes.hpp
/// \brief Particle types of the convection program: the full particle (double
///        precision), the single-precision view the kernels read (i and j alike, wall
///        images included) and the kernel results.
#pragma once

#include <cmath>
#include <cstdint>

#include <pik/pik.hpp>
#include <pik/sph/KernelResults.hpp>
#include <pik/sph/Walls.hpp>

namespace convection {

using Vec3d = pik::Vec3<double>;
using Vec3f = pik::Vec3<float>;

/// Results of kernels/sph_density.pik (gather): rho = sum m W, q = sum X W (Y of the
/// volume element, the caller puts X / m in `u`).
using DensityResult = pik::sph::DensityResult;

/// Results of kernels/sph_viscous.pik (symmetric).
struct ViscousResult {
  Vec3f acc;
  float dtdt, divv, qtop, qbot;
  Vec3f gradc, gradt;
  Vec3f gvx, gvy, gvz, geta;  // gradients of the velocity components and of the viscosity
  void clear() { acc = {}, dtdt = divv = qtop = qbot = 0, gradc = gradt = gvx = gvy = gvz = geta = {}; }
};

/// Results of the stress pass of --stress symmetric (acceleration before VIM's 1/c).
struct StressResult {
  Vec3f acc;
  void clear() { acc = {}; }
};

/// The full particle. Vectors have three components; 2D runs keep z = 0 and gravity
/// points along -y (the last dimension), as in the benchmark's (x, z) plane.
template <int D>
struct Particle {
  std::uint32_t id = 0;
  double mass = 0, h = 0;
  Vec3d pos{}, vel{}, vel_half{}, acc{};
  double temp = 0, temp_half = 0, dtemp = 0;  // temperature and dT/dt
  double rho1 = 0, rho1_half = 0, drho1 = 0;  // density perturbation of the RSST continuity equation
  double rho = 1;                             // mass density m / V (the volume element's)
  double vol = 0, xw = 0, y = 0, pf = 0, pres = 0;
  double eta = 1, cond = 1, inertia = 1, divv = 0, qtop = 0, qbot = 0;
  Vec3d gradc{}, gradt{};  // particle-concentration and temperature gradients (shifting)
  Vec3d stress_acc{};      // the (grad eta).(grad v)^T part of the viscous acceleration
  double tau[6] = {};      // --stress symmetric: deviatoric stress xx yy zz xy xz yz (pass 1)
  Vec3d sym_acc{};         // --stress symmetric: ainv sum_j V_i V_j (tau_i + tau_j) . grad W_ij (pass 2)
  double eta_pair = 1;     // the viscosity the force pass's Morris pair term sees (--stress symmetric: ~0, off)
  double bvis = 0;         // b of the viscosity law eta = exp(-b T) (0: constant), for wall images

  pik::Vec<double, D> getPos() const { return pik::sph::first_dims<D>(pos); }
  void setPos(const pik::Vec<double, D>& p) { pik::sph::set_first_dims<D>(pos, p); }
  void copyFromForce(const DensityResult& f) { rho = f.rho, y = f.q; }
  void copyFromForce(const ViscousResult& f) {
    acc = pik::vec_cast<Vec3d>(f.acc), dtemp = f.dtdt, divv = f.divv, qtop = f.qtop, qbot = f.qbot;
    gradc = pik::vec_cast<Vec3d>(f.gradc), gradt = pik::vec_cast<Vec3d>(f.gradt);
    // div(eta (grad v + grad v^T)) - div(eta grad v) = sum_b (d eta / d x_b) grad v_b
    // (incompressible; a force density, the caller scales it to an acceleration)
    const Vec3d gx = pik::vec_cast<Vec3d>(f.gvx), gy = pik::vec_cast<Vec3d>(f.gvy), gz = pik::vec_cast<Vec3d>(f.gvz);
    stress_acc = gx * double(f.geta.x) + gy * double(f.geta.y) + gz * double(f.geta.z);
    set_stress(gx, gy, gz);
  }
  void copyFromForce(const StressResult& f) { sym_acc = pik::vec_cast<Vec3d>(f.acc); }
  /// Pass 1 of --stress symmetric: tau = eta (G + G^T - 2/3 tr G I) from the velocity
  /// gradient G_ab = d v_b / d x_a of the force pass (gvx, gvy, gvz: rows b).
  void set_stress(const Vec3d& gx, const Vec3d& gy, const Vec3d& gz) {
    const double g[3][3] = {{gx.x, gy.x, gz.x}, {gx.y, gy.y, gz.y}, {gx.z, gy.z, gz.z}};  // g[a][b] = d v_b / d x_a
    const double tr = g[0][0] + g[1][1] + g[2][2];
    tau[0] = eta * (2 * g[0][0] - 2.0 / 3.0 * tr), tau[1] = eta * (2 * g[1][1] - 2.0 / 3.0 * tr);
    tau[2] = D == 3 ? eta * (2 * g[2][2] - 2.0 / 3.0 * tr) : eta * (-2.0 / 3.0 * tr);
    tau[3] = eta * (g[0][1] + g[1][0]), tau[4] = eta * (g[0][2] + g[2][0]), tau[5] = eta * (g[1][2] + g[2][1]);
  }
};

/// What the stress pass (StressKernel, ConvectionKernels.hpp) reads of a particle or
/// wall image: the deviatoric stress of pass 1 in single precision.
template <int D>
struct SEP {
  Vec3f pos;
  float h, vol, ainv;
  float tau[6];  // xx yy zz xy xz yz

  pik::Vec<float, D> getPos() const { return pik::sph::first_dims<D>(pos); }
  void setPos(const pik::Vec<float, D>& p) { pik::sph::set_first_dims<D>(pos, p); }
  float getRSearch() const { return h; }
  void copyFromFP(const Particle<D>& p) {
    pos = pik::vec_cast<Vec3f>(p.pos), h = float(p.h), vol = float(p.vol);
    ainv = float(1.0 / (p.inertia * p.vol));
    for (int k = 0; k < 6; ++k) tau[k] = float(p.tau[k]);
  }
  /// The image's stress is that of the mirrored flow: across a free-slip wall normal to
  /// `axis` the velocity field is v'(x') = R v(R x) with R the reflection, so
  /// tau' = R tau R (the components with exactly one index along the axis change sign);
  /// across a no-slip wall v' = -R v(R x) and tau' = -R tau R.
  void mirror(int axis, int, const pik::sph::WallFace& f) {
    using Kind = pik::sph::WallFace::Kind;
    if (f.kind != Kind::free_slip && f.kind != Kind::no_slip) return;
    static constexpr int ia[6] = {0, 1, 2, 0, 0, 1}, ib[6] = {0, 1, 2, 1, 2, 2};
    const float all = f.kind == Kind::no_slip ? -1.0f : 1.0f;
    for (int k = 0; k < 6; ++k) {
      const bool one = (ia[k] == axis) != (ib[k] == axis);
      tau[k] *= one ? -all : all;
    }
  }
};

/// What the kernels read of a particle (or of a wall image), in single precision.
template <int D>
struct EP {
  Vec3f pos, vel;
  float h, mass, u, xw, pf, vol, temp, eta, cond, ainv, wtop, wbot, bvis;

  pik::Vec<float, D> getPos() const { return pik::sph::first_dims<D>(pos); }
  void setPos(const pik::Vec<float, D>& p) { pik::sph::set_first_dims<D>(pos, p); }
  float getRSearch() const { return h; }
  void copyFromFP(const Particle<D>& p) {
    pos = pik::vec_cast<Vec3f>(p.pos), vel = pik::vec_cast<Vec3f>(p.vel);
    h = float(p.h), mass = float(p.mass), u = float(p.xw / p.mass), xw = float(p.xw), pf = float(p.pf);
    vol = float(p.vol), temp = float(p.temp), eta = float(p.eta_pair), cond = float(p.cond);
    ainv = float(1.0 / (p.inertia * p.vol));
    wtop = wbot = 0, bvis = float(p.bvis);
  }
  /// A wall image: the temperature as the face says, and the viscosity of that
  /// temperature (eta = exp(-b T), so the viscosity gradient continues across a
  /// fixed-temperature wall); images across the bottom or top (the last dimension) are
  /// marked, so the kernel sums the heat through each wall.
  void mirror(int axis, int side, const pik::sph::WallFace& f) {
    const float t_image = float(f.image_temperature(temp));
    if (bvis != 0) eta *= std::exp(-bvis * (t_image - temp));
    temp = t_image;
    if (axis == D - 1) (side ? wtop : wbot) = 1;
  }
};

// pikg-gen takes (qualified) names, not template-ids, for --epi/--epj
using EP2 = EP<2>;
using EP3 = EP<3>;

}  // namespace convection
