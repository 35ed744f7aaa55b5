/// \file StratifiedTypes.hpp
/// \brief Particle types of the stratified (polytropic) convection layer with the reduced
///        speed of sound technique: the full particle (double precision), the
///        single-precision view the kernels read (wall images included) and the result
///        of kernels/sph_rsst.pik.
#pragma once

#include <cstdint>

#include <pik/pik.hpp>
#include <pik/sph/KernelResults.hpp>
#include <pik/sph/Walls.hpp>

namespace stratified {

using Vec3d = pik::Vec3<double>;
using Vec3f = pik::Vec3<float>;

/// Results of kernels/sph_density.pik (gather): rho = sum m W.
using DensityResult = pik::sph::DensityResult;

/// Results of kernels/sph_rsst.pik (symmetric).
struct RsstResult {
  Vec3f acc;
  float dsdt, divm, qtop, qbot;
  Vec3f gradr, gradc, grads, bias;
  void clear() { acc = {}, dsdt = divm = qtop = qbot = 0, gradr = gradc = grads = bias = {}; }
};

/// The full particle. Vectors have three components; 2D runs keep z = 0 and gravity
/// points along -y (the last dimension).
template <int D>
struct Particle {
  std::uint32_t id = 0;
  double mass = 0, h = 0;
  Vec3d pos{}, vel{}, vel_half{}, acc{};
  double s1 = 0, s1_half = 0, ds1 = 0;        // entropy perturbation and ds1/dt
  double rho1 = 0, rho1_half = 0, drho1 = 0;  // density perturbation and drho1/dt (RSST)
  double rho = 1, vol = 0;                    // SPH density (sum m W) and volume m / rho
  double rho0 = 1, p0 = 1, t0 = 1, p1 = 0;    // reference state at the particle, pressure perturbation
  double pw = 0;                              // the reduced pressure the pressure sum reads (p1 / rho0, less its mean)
  double pa = 0, pa_mean = 0;                 // acoustic density p1 / c_s^2 = rho1 + rho0 s1 / c_p, and its kernel average
  double xi = 1;                              // the particle's RSST factor
  double mu = 0, cond = 0;                    // dynamic viscosity rho0 nu, entropy conductivity rho0 T0 kappa
  double divm = 0, qtop = 0, qbot = 0;
  Vec3d gradr{}, gradc{}, grads{};
  Vec3d bias{};  // sum_j V_j gradW_ij: the SPH gradient of a constant (zero in the continuum)

  pik::Vec<double, D> getPos() const { return pik::sph::first_dims<D>(pos); }
  void setPos(const pik::Vec<double, D>& p) { pik::sph::set_first_dims<D>(pos, p); }
  /// q = sum_j m_j u_j W_ij with u = pa (the acoustic density): its Shepard average is q / rho
  void copyFromForce(const DensityResult& f) { rho = f.rho, pa_mean = f.q / f.rho; }
  void copyFromForce(const RsstResult& f) {
    acc = pik::vec_cast<Vec3d>(f.acc), ds1 = f.dsdt, divm = f.divm, qtop = f.qtop, qbot = f.qbot;
    gradr = pik::vec_cast<Vec3d>(f.gradr), gradc = pik::vec_cast<Vec3d>(f.gradc), grads = pik::vec_cast<Vec3d>(f.grads);
    bias = pik::vec_cast<Vec3d>(f.bias);
  }
};

/// What the kernels read of a particle (or of a wall image), in single precision.
/// `u` is read by sph_density.pik: the acoustic density p1 / c_s^2 (its kernel average is the
/// acoustic filter's target; the wall images keep it: zero normal gradient); pw is the reduced pressure p1 / rho0;
/// mu and cond are the dynamic viscosity
/// rho0 nu and the entropy conductivity rho0 T0 kappa.
template <int D>
struct EP {
  Vec3f pos, vel;
  float h, mass, u, vol, vol0, pw, mu, cond, rho0, rho1, s1, ainv, wtop, wbot;

  pik::Vec<float, D> getPos() const { return pik::sph::first_dims<D>(pos); }
  void setPos(const pik::Vec<float, D>& p) { pik::sph::set_first_dims<D>(pos, p); }
  float getRSearch() const { return h; }
  void copyFromFP(const Particle<D>& p) {
    pos = pik::vec_cast<Vec3f>(p.pos), vel = pik::vec_cast<Vec3f>(p.vel);
    h = float(p.h), mass = float(p.mass), u = float(p.pa), vol = float(p.vol), vol0 = float(p.mass / p.rho0), pw = float(p.pw);
    mu = float(p.mu), cond = float(p.cond), rho0 = float(p.rho0), rho1 = float(p.rho1);
    s1 = float(p.s1), ainv = float(1.0 / (p.rho0 * p.vol));
    wtop = wbot = 0;
  }
  /// A wall image: across the top or bottom (the last dimension) the entropy
  /// perturbation is held at 0 (image -s1) and the image is marked, so that the kernel
  /// sums the heat through each wall; the side walls are insulating (same s1).
  void mirror(int axis, int side, const pik::sph::WallFace& f) {
    if (f.fixed_temperature) s1 = float(f.image_temperature(s1));
    if (axis == D - 1) (side ? wtop : wbot) = 1;
  }
};

using EP2 = EP<2>;
using EP3 = EP<3>;

}  // namespace stratified
