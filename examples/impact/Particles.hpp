/// \file Particles.hpp
/// \brief The impact example's particle (SI, double precision), the views the generated
///        kernels read (single precision, code units: Units.hpp) and the kernel results.
#pragma once

#include <cmath>
#include <cstdint>

#include <pik/pik.hpp>
#include <pik/sph/KernelResults.hpp>

#include "Units.hpp"

namespace impact {

using Vec3d = pik::Vec3<double>;
using Vec3f = pik::Vec3<float>;

// ---- kernel results (code units, single precision) --------------------------------------
using pik::sph::DensityResult;  // the SPH kernel library's results (pik/sph/KernelResults.hpp)
using pik::sph::GravityResult;
using pik::sph::HydroResult;

/// The full particle. Everything is SI except the two DISPH quantities z and y, which
/// stay in code units (they only ever meet the kernels).
struct Particle {
  std::uint32_t id = 0;
  int material = 0;  ///< index in the run's material table (0 core material, 1 mantle material, ...)
  int body = 0;      ///< 0 target, 1 impactor (for the pictures; the physics ignores it)
  double mass = 0, u = 0, u_half = 0, dudt = 0;
  Vec3d pos{}, vel{}, vel_half{}, acc{}, grav{};
  double h = 0;        ///< support radius of the kernel
  double rho = 0;      ///< SPH mass density sum_j m_j W_ij (drives the smoothing length)
  double drhodh = 0, nngb = 0, divv = 0, curl = 0;
  double dens = 0;     ///< density the EOS is evaluated at (rho in SSPH, m y / Z in DISPH)
  double pres = 0, cs = 0, fgrad = 1, balsara = 1, vsig = 0, pot = 0;
  double z = 0;        ///< DISPH: Z = m P^alpha / rho (code units)
  double y = 0;        ///< DISPH: y = sum_j Z_j W_ij (code units)
  double pf = 0;       ///< what the force kernel reads: SSPH f P / rho^2, DISPH P / y^2 (code units)
  double h_lo = 0, h_hi = 0;
  // block time steps (Model::advance): the particle's step runs from tick0 to tick1 (in
  // units of the block / 2^K), its rung k (step = block / 2^k) sets the limiter
  std::int64_t tick0 = 0, tick1 = 0;
  int rung = 0;

  const Vec3d& getPos() const { return pos; }
  void setPos(const Vec3d& p) { pos = p; }
  void copyFromForce(const DensityResult& f) {
    const double L = Code::L, M = Code::M, V = Code::V();
    rho = f.rho * (M / (L * L * L)), drhodh = f.drhodh * (M / (L * L * L * L));
    y = f.q, nngb = f.nngb;
    divv = f.divv * (M / (L * L * L)) * (V / L);
    curl = std::sqrt(double(f.rotv.x) * f.rotv.x + double(f.rotv.y) * f.rotv.y + double(f.rotv.z) * f.rotv.z) *
           (M / (L * L * L)) * (V / L);
  }
  void copyFromForce(const HydroResult& f) {
    acc = pik::vec_cast<Vec3d>(f.acc) * Code::A(), dudt = f.dudt * (Code::U() / Code::T()), vsig = f.vsig * Code::V();
  }
  void copyFromForce(const GravityResult& f) {
    grav = pik::vec_cast<Vec3d>(f.acc) * Code::A(), pot = f.pot * Code::U();
  }
};

/// What the SPH kernels read of a particle (i and j alike), in code units and F32. `u`
/// is Z / m: the density kernel's sum_j m_j u_j W_ij is then y = sum_j Z_j W_ij.
struct ImpactEP {
  Vec3f pos, vel;
  float h, mass, rho, pf, cs, balsara, u, z;
  const Vec3f& getPos() const { return pos; }
  void setPos(const Vec3f& p) { pos = p; }
  float getRSearch() const { return h; }
  void copyFromFP(const Particle& p) {
    const double L = Code::L, V = Code::V();
    pos = pik::vec_cast<Vec3f>(p.pos * (1 / L)), vel = pik::vec_cast<Vec3f>(p.vel * (1 / V));
    h = float(p.h / L), mass = float(p.mass / Code::M), rho = float(p.dens / Code::Rho());
    pf = float(p.pf), cs = float(p.cs / V), balsara = float(p.balsara);
    z = float(p.z), u = float(p.z / (p.mass / Code::M));
  }
};

/// What the gravity tree needs of an active particle (block time steps: the active ones
/// are the tree's local particles, the others enter as imported j-particles).
struct GravBody {
  std::uint32_t id = 0;
  double mass = 0;
  Vec3d pos{}, grav{};
  double pot = 0;
  const Vec3d& getPos() const { return pos; }
  void setPos(const Vec3d& p) { pos = p; }
  void copyFromForce(const GravityResult& f) {
    grav = pik::vec_cast<Vec3d>(f.acc) * Code::A(), pot = f.pot * Code::U();
  }
};

struct GravEPI {
  Vec3f pos;
  const Vec3f& getPos() const { return pos; }
  void copyFromFP(const Particle& p) { pos = pik::vec_cast<Vec3f>(p.pos * (1 / Code::L)); }
  void copyFromFP(const GravBody& p) { pos = pik::vec_cast<Vec3f>(p.pos * (1 / Code::L)); }
};
struct GravEPJ {
  Vec3f pos;
  float mass;
  const Vec3f& getPos() const { return pos; }
  float getCharge() const { return mass; }
  void copyFromFP(const Particle& p) {
    pos = pik::vec_cast<Vec3f>(p.pos * (1 / Code::L)), mass = float(p.mass / Code::M);
  }
  void copyFromFP(const GravBody& p) {
    pos = pik::vec_cast<Vec3f>(p.pos * (1 / Code::L)), mass = float(p.mass / Code::M);
  }
};
/// The gravity tree's cells: quadrupole super-particles. With the centre-of-mass offset
/// criterion at theta 0.7 their force error is below that of monopoles at theta 0.5 with
/// the box criterion, at fewer interactions (bench_tree; in the impact 29 % less gravity CPU
/// before contact, the same after it: docs/impact.md "quadrupole cells").
using GravSPJ = pik::SPJQuadrupole<float>;

}  // namespace impact
