/// \file SphTypes.hpp
/// \brief The SPH example's particle types: the full particle, what the kernels read
///        (SphEP, single precision) and the kernel results (shared with bench/sph).
#pragma once

#include <cmath>
#include <cstdint>

#include <pik/pik.hpp>

using pik::Vec3;
using Vec3d = Vec3<double>;
using Vec3f = Vec3<float>;

// ---- particles ------------------------------------------------------------------------
// Kernel results (accumulated in single precision).
struct DensityResult {
  float rho, drhodh, q, divv, nngb;
  Vec3f rotv;
  void clear() { rho = drhodh = q = divv = nngb = 0, rotv = {}; }
};
struct HydroResult {
  Vec3f acc;
  float dudt, vsig;
  void clear() { acc = {}, dudt = vsig = 0; }
};
struct GravityResult {
  Vec3f acc;
  float pot;
  void clear() { acc = {}, pot = 0; }
};

/// The full particle. Vectors have three components; 2D runs keep z = 0 and the
/// tree sees (x, y) only (getPos of dimension D).
template <int D>
struct Particle {
  std::uint32_t id = 0;
  int tag = 0;  // problem-specific label (square: 1 inside; kh: 1 in the dense layer)
  double mass = 0, u = 0, u_half = 0, dudt = 0;
  Vec3d pos{}, vel{}, vel_half{}, acc{}, grav{};
  double h = 0, rho = 0, q = 0, drhodh = 0, nngb = 0, divv = 0, curl = 0;
  double pres = 0, cs = 0, fgrad = 1, balsara = 1, vsig = 0, pot = 0;
  double h_lo = 0, h_hi = 0;  // bracket of the smoothing-length iteration

  pik::Vec<double, D> getPos() const {
    if constexpr (D == 2) return {pos.x, pos.y};
    else return pos;
  }
  void setPos(const pik::Vec<double, D>& p) {
    pos.x = p.x, pos.y = p.y;
    if constexpr (D == 3) pos.z = p.z;
  }
  void copyFromForce(const DensityResult& f) {
    rho = f.rho, drhodh = f.drhodh, q = f.q, divv = f.divv, nngb = f.nngb;
    curl = std::sqrt(double(f.rotv.x) * f.rotv.x + double(f.rotv.y) * f.rotv.y + double(f.rotv.z) * f.rotv.z);
  }
  void copyFromForce(const HydroResult& f) { acc = pik::vec_cast<Vec3d>(f.acc), dudt = f.dudt, vsig = f.vsig; }
  void copyFromForce(const GravityResult& f) { grav = pik::vec_cast<Vec3d>(f.acc), pot = f.pot; }
};

/// What the kernels read of a particle, in single precision (i and j alike).
template <int D>
struct SphEP {
  Vec3f pos, vel;
  float h, mass, u, rho, q, pf, cs, balsara;
  pik::Vec<float, D> getPos() const {
    if constexpr (D == 2) return {pos.x, pos.y};
    else return pos;
  }
  void setPos(const pik::Vec<float, D>& p) {
    pos.x = p.x, pos.y = p.y;
    if constexpr (D == 3) pos.z = p.z;
  }
  float getRSearch() const { return h; }
  void copyFromFP(const Particle<D>& p) {
    pos = pik::vec_cast<Vec3f>(p.pos), vel = pik::vec_cast<Vec3f>(p.vel);
    h = float(p.h), mass = float(p.mass), u = float(p.u), rho = float(p.rho), q = float(p.q);
    pf = float(p.fgrad * p.pres / (p.rho * p.rho)), cs = float(p.cs), balsara = float(p.balsara);
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

