/// \file ConvectionTypes.hpp
/// \brief Particle types of the convection program: the full particle (double
///        precision), the single-precision view the kernels read (i and j alike, wall
///        images included) and the kernel results.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <pik/pik.hpp>
#include <pik/sph/KernelResults.hpp>
#include <pik/sph/Smoothing.hpp>
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
  Vec3f mx, my, mz;            // the correction matrix by columns (as GradResult's)
  void clear() { acc = {}, dtdt = divv = qtop = qbot = 0, gradc = gradt = gvx = gvy = gvz = geta = mx = my = mz = {}; }
};

/// Results of the stress pass of --stress symmetric/split (acceleration before VIM's 1/c).
struct StressResult {
  Vec3f acc;
  void clear() { acc = {}; }
};

/// Results of the gradient pass of --stress symmetric/split/local (kernels/sph_gradient.pik):
/// the plain SPH velocity gradient g[a][b] = sum_j V_j (v_b,j - v_b,i) dW_ij/dx_a, one vector
/// per velocity component (gv_b[a] = g[a][b]), and the correction matrix m[a][c] = sum_j V_j
/// (x_c,j - x_c,i) dW_ij/dx_a, by columns (m_c[a] = m[a][c]) (Bonet & Lok 1999, Comput.
/// Methods Appl. Mech. Eng. 180, 97): m^-1 g is exact for a linear velocity field; gt[a] =
/// sum_j V_j (T_j - T_i) dW_ij/dx_a, the plain temperature gradient (m^-1 gt for --stress local).
struct GradResult {
  Vec3f gvx, gvy, gvz, mx, my, mz, gt;
  float g(int a, int b) const { return (b == 0 ? gvx : b == 1 ? gvy : gvz)[std::size_t(a)]; }
  float m(int a, int c) const { return (c == 0 ? mx : c == 1 ? my : mz)[std::size_t(a)]; }
  float t(int a) const { return gt[std::size_t(a)]; }
  void clear() { gvx = gvy = gvz = mx = my = mz = gt = {}; }
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
  double dtemp_shift = 0;  // the change of T that particle shifting made in the last step, / dt
  Vec3d stress_acc{};      // the (grad eta).(grad v)^T part of the viscous acceleration
  double gradv[3][3] = {};  // --stress symmetric/split/local: corrected velocity gradient d v_b / d x_a (pass 1)
  double strain[3][3] = {};  // --stress symmetric/split: e = tau_g G + G^T - 2/3 tr G I; pass 2 takes div(eta e)
  double tau_g = 1;          // weight of G in e: 1 symmetric (G + G^T), 0 split/local (G^T; Morris does div(eta G))
  Vec3d gradtc{};           // --stress symmetric/split/local: corrected temperature gradient (pass 1)
  Vec3d sym_acc{};          // --stress symmetric/split: ainv sum_j V_i V_j (tau_i + tau_j) . grad W_ij (pass 2);
                            // local: (grad eta) . e / inertia (local_transpose)
  double eta_pair = 1;      // the viscosity the force pass's Morris pair term sees (--stress symmetric: ~0, off)
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
    // the corrected gradients and the stress, as pass 1 gives them (the same sums over the
    // same neighbours): --stress local needs no pass of its own; symmetric and split
    // overwrite them with pass 1's
    copyFromForce(GradResult{f.gvx, f.gvy, f.gvz, f.mx, f.my, f.mz, f.gradt});
  }
  void copyFromForce(const StressResult& f) { sym_acc = pik::vec_cast<Vec3d>(f.acc); }
  /// Pass 1 of --stress symmetric/split: the corrected velocity gradient m^-1 g (the plain
  /// one where m is singular, e.g. a particle with too few neighbours), then the stress.
  void copyFromForce(const GradResult& f) {
    double m[D][D], inv[D][D], det;
    for (int a = 0; a < D; ++a)
      for (int c = 0; c < D; ++c) m[a][c] = f.m(a, c);
    if constexpr (D == 2) {
      det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
      inv[0][0] = m[1][1], inv[0][1] = -m[0][1], inv[1][0] = -m[1][0], inv[1][1] = m[0][0];
    } else {
      inv[0][0] = m[1][1] * m[2][2] - m[1][2] * m[2][1], inv[0][1] = m[0][2] * m[2][1] - m[0][1] * m[2][2];
      inv[0][2] = m[0][1] * m[1][2] - m[0][2] * m[1][1], inv[1][0] = m[1][2] * m[2][0] - m[1][0] * m[2][2];
      inv[1][1] = m[0][0] * m[2][2] - m[0][2] * m[2][0], inv[1][2] = m[0][2] * m[1][0] - m[0][0] * m[1][2];
      inv[2][0] = m[1][0] * m[2][1] - m[1][1] * m[2][0], inv[2][1] = m[0][1] * m[2][0] - m[0][0] * m[2][1];
      inv[2][2] = m[0][0] * m[1][1] - m[0][1] * m[1][0];
      det = m[0][0] * inv[0][0] + m[0][1] * inv[1][0] + m[0][2] * inv[2][0];
    }
    const bool ok = std::abs(det) > 1e-3;  // m ~ I on a full support
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        double s = 0;
        if (a < D && ok)
          for (int c = 0; c < D; ++c) s += inv[a][c] / det * double(f.g(c, b));
        else s = a < D ? double(f.g(a, b)) : 0.0;
        gradv[a][b] = s;
      }
    for (int a = 0; a < 3; ++a) {
      double s = 0;
      if (a < D && ok)
        for (int c = 0; c < D; ++c) s += inv[a][c] / det * double(f.t(c));
      else s = a < D ? double(f.t(a)) : 0.0;
      gradtc[a] = s;
    }
    set_stress();
  }
  /// e = tau_g G + G^T - 2/3 tr G I from gradv (G_ab = d v_b / d x_a): the stress is
  /// tau = eta e, and div tau is (tau_g = 1) div(eta (grad v + grad v^T)) - 2/3 grad(eta div v),
  /// or (tau_g = 0) the part the Morris pair term leaves out. tau_ab is the flux of momentum
  /// b through a face normal to a: (div tau)_b = d_a tau_ab.
  void set_stress() {
    const double tr = gradv[0][0] + gradv[1][1] + gradv[2][2];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) strain[a][b] = tau_g * gradv[a][b] + gradv[b][a] - (a == b ? 2.0 / 3.0 * tr : 0.0);
  }
  /// --stress local: the part of div(eta e) (e = G^T - 2/3 tr G I, tau_g = 0) that the Morris
  /// term leaves out, taken at the particle: (grad eta) . e, with grad eta = -b eta grad T of
  /// the law eta = exp(-b T) and the corrected gradients of pass 1 (a force density). It drops
  /// eta div e = eta grad(div v) / 3 (second order in the compression). Unlike a pair form it
  /// needs no pair viscosity: eta' is the particle's own, where a pair mean of eta across a
  /// boundary layer thinner than the support flattens it (docs/convection.md, case 2a).
  Vec3d local_transpose() const {
    Vec3d f{};
    for (int a = 0; a < D; ++a) {
      const double deta = -bvis * eta * gradtc[a];
      for (int c = 0; c < D; ++c) f[c] += deta * strain[a][c];
    }
    return f;
  }
};

/// What the two passes of --stress symmetric/split (kernels/sph_gradient.pik, StressKernel) read of a
/// particle or wall image, in single precision: position, velocity (the walls reflect it
/// in an image), viscosity and the strain rate of pass 1.
template <int D>
struct SEP {
  Vec3f pos, vel;
  float h, vol, ainv, temp, bvis, eta;
  float e[3][3];

  pik::Vec<float, D> getPos() const { return pik::sph::first_dims<D>(pos); }
  void setPos(const pik::Vec<float, D>& p) { pik::sph::set_first_dims<D>(pos, p); }
  float getRSearch() const { return h; }
  void copyFromFP(const Particle<D>& p) {
    pos = pik::vec_cast<Vec3f>(p.pos), vel = pik::vec_cast<Vec3f>(p.vel), h = float(p.h), vol = float(p.vol);
    ainv = float(1.0 / (p.inertia * p.vol)), temp = float(p.temp), bvis = float(p.bvis), eta = float(p.eta);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) e[a][b] = float(p.strain[a][b]);
  }
  /// The image's strain rate is that of the mirrored flow: across a free-slip wall normal
  /// to `axis` the velocity field is v'(x') = R v(R x) with R the reflection, so e' = R e R
  /// (the components with exactly one index along the axis change sign); across a no-slip
  /// wall v' = -R v(R x) and e' = -R e R. The viscosity continues as EP::mirror continues
  /// it, eta' = eta exp(-b (T' - T)) with the image temperature T' the face gives (a
  /// fixed-temperature wall: T' = 2 T_w - T): for a viscosity that varies across the wall
  /// d tau_nn / dn then keeps its value at the wall instead of vanishing there (as an even
  /// continuation of eta would make it).
  void mirror(int axis, int, const pik::sph::WallFace& f) {
    using Kind = pik::sph::WallFace::Kind;
    const float t_image = float(f.image_temperature(temp));
    if (bvis != 0) eta *= std::exp(-bvis * (t_image - temp));
    temp = t_image;
    if (f.kind != Kind::free_slip && f.kind != Kind::no_slip) return;
    const float all = f.kind == Kind::no_slip ? -1.0f : 1.0f;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) e[a][b] *= ((a == axis) != (b == axis)) ? -all : all;
  }
};

/// g(q) = f'(q)/q of the smoothing functions (0 cubic spline, 1 Wendland C2, 2 Wendland
/// C4; as kernels/sph_viscous.pik) and sigma / h^(D+2): grad_i W_ij(h) = norm(h) g(r/h) r_ij.
template <int D, int S>
struct KernelGrad {
  static float g(float q) {
    const float a = std::max(1.0f - q, 0.0f);
    if constexpr (S == 0) return q < 0.5f ? 18.0f * q - 12.0f : -6.0f * a * a / q;
    else if constexpr (S == 1) return -20.0f * a * a * a;
    else return -56.0f / 3.0f * a * a * a * a * a * (1.0f + 5.0f * q);
  }
  static float norm(float h) {
    static const float sig = float(pik::sph::kernel_sigma(D, pik::sph::Shape(S)));
    float hi = 1.0f / h, p = hi * hi * hi * hi;
    if constexpr (D == 3) p *= hi;
    return sig * p;
  }
};

/// Pass 2 of --stress symmetric/split, a symmetric pair kernel in C++: the force of the
/// stress of pass 1,
///
///   F_i = sum_j V_i V_j eta_ij (e_i + e_j) . grad W_ij,   acc_i = ainv_i F_i
///   ((F_i)_b = sum_j V_i V_j eta_ij (e_i + e_j)_ab (grad W_ij)_a),
///   eta_ij = 2 eta_i eta_j / (eta_i + eta_j)
///
/// with grad W_ij the mean of the two smoothing lengths' gradients, so F_ij = -F_ji: the
/// pair forces conserve linear momentum. It is the SPH form of div(eta e) (cf. the pressure
/// term, tau = -p I; for equal viscosities eta_ij (e_i + e_j) = tau_i + tau_j). The pair
/// viscosity is the harmonic mean (as Cleary 1998 takes it in the Morris term): with the
/// arithmetic form tau_i + tau_j a hot particle (eta_i small, and with --xi-law viscosity
/// a small inertia) is driven by its cold neighbours' eta_j, up to e^(b dT) times its own,
/// so the explicit step h^2 rho_I / eta_i that is stable for it is exceeded by that factor;
/// the harmonic mean is at most 2 min(eta_i, eta_j). No viscous heating (the Boussinesq
/// equations of Blankenbach et al. 1989 have none).
template <int D, int S>
class StressKernel {
 public:
  void operator()(const SEP<D>* epi, int ni, const SEP<D>* epj, int nj, StressResult* force) const {
    using G = KernelGrad<D, S>;
    for (int i = 0; i < ni; ++i) {
      const SEP<D>& a = epi[i];
      const float hinvi = 1.0f / a.h, ni_ = G::norm(a.h);
      float f[3] = {0, 0, 0};
      for (int j = 0; j < nj; ++j) {
        const SEP<D>& b = epj[j];
        const float r[3] = {a.pos.x - b.pos.x, a.pos.y - b.pos.y, a.pos.z - b.pos.z};
        const float r2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
        const float hmax = std::max(a.h, b.h);
        if (r2 >= hmax * hmax || r2 == 0) continue;
        const float rr = std::sqrt(r2);
        const float gi = ni_ * G::g(std::min(rr * hinvi, 1.0f)), gj = G::norm(b.h) * G::g(std::min(rr / b.h, 1.0f));
        const float etaij = 2.0f * a.eta * b.eta / (a.eta + b.eta);
        const float w = a.vol * b.vol * 0.5f * (gi + gj) * etaij;  // V_i V_j eta_ij grad W_ij = w r_ij
        for (int x = 0; x < D; ++x)
          for (int c = 0; c < 3; ++c) f[c] += w * (a.e[x][c] + b.e[x][c]) * r[x];
      }
      force[i].acc.x += a.ainv * f[0], force[i].acc.y += a.ainv * f[1], force[i].acc.z += a.ainv * f[2];
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
using SEP2 = SEP<2>;
using SEP3 = SEP<3>;

}  // namespace convection
