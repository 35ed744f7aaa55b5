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
    vol = float(p.vol), temp = float(p.temp), eta = float(p.eta), cond = float(p.cond);
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
