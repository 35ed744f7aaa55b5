/// \file SphTypes.hpp
/// \brief The SPH example's particle types: the full particle, what the kernels read
///        (SphEP, single precision) and the kernel results (shared with bench/sph).
#pragma once

#include <cmath>
#include <cstdint>

#include <pik/pik.hpp>
#include <pik/sph/KernelResults.hpp>

using pik::Vec3;
using Vec3d = Vec3<double>;
using Vec3f = Vec3<float>;

// ---- particles ------------------------------------------------------------------------
// Kernel results (accumulated in single precision).
using pik::sph::DensityResult;  // kernels/sph_density.pik (pik/sph/KernelResults.hpp; bench/sph)
/// kernels/sph_density_gradh.pik: DensityResult's sums and dq/dh (DISPH's grad-h term).
struct DensityGradhResult {
  float rho, drhodh, q, dqdh, nd, dnddh, divv, nngb;  // nd, dnddh: number density sum W and its d/dh
  Vec3f rotv;
  void clear() { rho = drhodh = q = dqdh = nd = dnddh = divv = nngb = 0, rotv = {}; }
};
struct HydroResult {
  Vec3f acc;
  float dudt, vsig;
  float dydt, ydiff;  // SPSPH: pseudo-density continuity and diffusion terms (others leave them 0)
  void clear() { acc = {}, dudt = vsig = dydt = ydiff = 0; }
};
using pik::sph::GravityResult;

/// The full particle. Vectors have three components; 2D runs keep z = 0 and the
/// tree sees (x, y) only (getPos of dimension D).
template <int D>
struct Particle {
  std::uint32_t id = 0;
  int tag = 0;  // problem-specific label (1 the dense fluid of square/contact/kh, 2 a fixed wall particle)
  double mass = 0, u = 0, u_half = 0, dudt = 0;
  Vec3d pos{}, vel{}, vel_half{}, acc{}, grav{};
  double h = 0, rho = 0, q = 0, drhodh = 0, nngb = 0, divv = 0, curl = 0;
  double pres = 0, cs = 0, fgrad = 1, balsara = 1, vsig = 0, pot = 0;
  // DISPH's grad-h term: dq/dh from the density pass and C = h/(D rho) dq/dh / (1 + h/(D rho) drho/dh)
  // (or, with h from q, the factor f = (1 + h/(D q) dq/dh)^-1 as fq); rho_m, drho_m: the mass density kept aside
  // xt: the weight x~ of the density that sets h (m, or 1 for the number density nd)
  double dqdh = 0, gh = 0, fq = 1, xt = 0, rho_m = 0, drho_m = 0, nd = 0, dnddh = 0;
  double h_lo = 0, h_hi = 0;  // bracket of the smoothing-length iteration
  // SPSPH (Yamamoto, Saitoh & Makino 2015): pseudo-density y and the density rho_t, both
  // integrated in time, their rates and half-step values; rho0 the initial condition's
  // density (0: none given, the SPH estimate is used). rho_ep and pf: what the force
  // kernels read as the density and as the pressure term (P f / rho^2, or P / y^2).
  double y = 1, y_half = 1, dydt = 0, ydiff = 0, rho_t = 0, rho_t_half = 0, rho0 = 0;
  double rho_ep = 0, pf = 0;

  pik::Vec<double, D> getPos() const { return pik::sph::first_dims<D>(pos); }
  void setPos(const pik::Vec<double, D>& p) { pik::sph::set_first_dims<D>(pos, p); }
  void copyFromForce(const DensityResult& f) {
    rho = f.rho, drhodh = f.drhodh, q = f.q, divv = f.divv, nngb = f.nngb;
    curl = std::sqrt(double(f.rotv.x) * f.rotv.x + double(f.rotv.y) * f.rotv.y + double(f.rotv.z) * f.rotv.z);
  }
  void copyFromForce(const DensityGradhResult& f) {
    rho = f.rho, drhodh = f.drhodh, q = f.q, dqdh = f.dqdh, nd = f.nd, dnddh = f.dnddh, divv = f.divv, nngb = f.nngb;
    curl = std::sqrt(double(f.rotv.x) * f.rotv.x + double(f.rotv.y) * f.rotv.y + double(f.rotv.z) * f.rotv.z);
  }
  void copyFromForce(const HydroResult& f) {
    acc = pik::vec_cast<Vec3d>(f.acc), dudt = f.dudt, vsig = f.vsig, dydt = f.dydt, ydiff = f.ydiff;
  }
  void copyFromForce(const GravityResult& f) { grav = pik::vec_cast<Vec3d>(f.acc), pot = f.pot; }
};

/// What the kernels read of a particle, in single precision (i and j alike).
template <int D>
struct SphEP {
  Vec3f pos, vel;
  float h, mass, u, rho, q, pf, cs, balsara;
  float z, y;  // SPSPH pseudo-mass Z = m y / rho and pseudo-density
  float gh, fq, xt;  // DISPH grad-h terms: C (0: none), f (1: none), x~ (m or 1)
  pik::Vec<float, D> getPos() const { return pik::sph::first_dims<D>(pos); }
  void setPos(const pik::Vec<float, D>& p) { pik::sph::set_first_dims<D>(pos, p); }
  float getRSearch() const { return h; }
  void copyFromFP(const Particle<D>& p) {
    pos = pik::vec_cast<Vec3f>(p.pos), vel = pik::vec_cast<Vec3f>(p.vel);
    h = float(p.h), mass = float(p.mass), u = float(p.u), q = float(p.q);
    // before the first EOS call (the density pass) rho_ep and pf are not set yet: unused there
    rho = float(p.rho_ep > 0 ? p.rho_ep : p.rho), pf = float(p.pf), cs = float(p.cs), balsara = float(p.balsara);
    y = float(p.y), z = float(p.mass * p.y / (p.rho_ep > 0 ? p.rho_ep : 1.0));
    gh = float(p.gh), fq = float(p.fq), xt = float(p.xt);
  }
};
using SphEP2 = SphEP<2>;
using SphEP3 = SphEP<3>;

struct GravEPI {
  Vec3f pos;
  const Vec3f& getPos() const { return pos; }
  void copyFromFP(const Particle<3>& p) { pos = pik::vec_cast<Vec3f>(p.pos); }
};
struct GravEPJ {
  Vec3f pos;
  float mass;
  const Vec3f& getPos() const { return pos; }
  float getCharge() const { return mass; }
  void copyFromFP(const Particle<3>& p) { pos = pik::vec_cast<Vec3f>(p.pos), mass = float(p.mass); }
};
using GravSPJ = pik::SPJMonopole<float>;

