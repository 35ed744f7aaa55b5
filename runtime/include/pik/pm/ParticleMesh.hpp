/// \file ParticleMesh.hpp
/// \brief pik::pm::ParticleMesh: the long-range part of periodic gravity on an FFT mesh.
///
/// The TreePM split (Bagla 2002, J. Astrophys. Astron. 23, 185; Springel 2005, MNRAS
/// 364, 1105, eqs. 20-22): the potential of a point mass in Fourier space,
/// phi(k) = -4 pi G m / k^2, is split into a long-range part multiplied by
/// exp(-k^2 r_s^2), solved here on a mesh, and the complementary short-range part
/// whose pair force is the Newtonian one times
///
///     g(r) = erfc(r / 2 r_s) + r / (r_s sqrt(pi)) exp(-r^2 / 4 r_s^2),
///
/// summed through the tree (kernels/gravity_treepm.pik, pik::pm::TreePM).
///
/// The steps, for a periodic cube [0, L)^3 on an N^3 mesh of spacing h = L / N with
/// cell centres at (i + 1/2) h: the masses are assigned to the mesh by cloud-in-cell
/// (CIC, window order p = 2) or triangular-shaped cloud (TSC, p = 3) (Hockney &
/// Eastwood 1988, ch. 5); FFT; multiplied by the Green's function
///
///     G(k) = -4 pi G / k^2 exp(-k^2 r_s^2) / W(k)^2,  W(k) = prod_d sinc(k_d h / 2)^p,
///
/// the division by W^2 undoing the smoothing of the assignment and of the
/// interpolation (Hockney & Eastwood; Springel 2005, sect. 2.2); the acceleration
/// components a_d(k) = -i k_d phi(k) (exact spectral gradient, the Nyquist
/// component's derivative set to zero) transformed back; and interpolated to the
/// particles with the same window as the assignment (so that the self-force
/// vanishes and momentum is conserved to the accuracy of the symmetry of the
/// scheme). The k = 0 mode is dropped: the force is that of the density contrast,
/// a uniform background subtracted, as in Ewald summation.
///
/// Units: G = 1 (give masses as G m). Periodic boxes only.
///
/// Under MPI the mesh is decomposed in x-slabs (FFTW's MPI transforms): each rank
/// assigns its own particles to the planes they touch, sends each plane to the
/// rank owning it, and gets back the planes its particles read; particles may be
/// anywhere (any decomposition), the planes a rank touches are then more. Results
/// equal the single-process ones to rounding (the FFT's sums in another order).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include "pik/Error.hpp"
#include "pik/Profiler.hpp"
#include "pik/Vec.hpp"
#include "pik/comm/Comm.hpp"
#include "pik/pm/detail/SlabFft.hpp"

namespace pik::pm {

/// Mass assignment (and interpolation) scheme: the order p of its window.
enum class Assignment { cic = 2, tsc = 3 };

struct MeshParams {
  /// Box side L: the box is [0, L)^3 (positions are wrapped into it).
  double box = 1.0;
  /// Mesh cells per side N.
  int n_mesh = 64;
  /// Split scale r_s in units of the mesh spacing h (GADGET-2's default 1.25,
  /// Springel 2005 sect. 2.2).
  double r_split_cells = 1.25;
  /// TSC by default: at the same r_s its forces are 3-5 times closer to Ewald than
  /// CIC's (docs/cosmo.md).
  Assignment assignment = Assignment::tsc;

  double spacing() const { return box / n_mesh; }
  double r_split() const { return r_split_cells * spacing(); }
  void check() const {
    if (!(box > 0) || !std::isfinite(box)) throw Error("particle mesh: box side must be positive, got " + std::to_string(box));
    if (n_mesh < 4) throw Error("particle mesh: n_mesh must be at least 4, got " + std::to_string(n_mesh));
    if (!(r_split_cells > 0)) throw Error("particle mesh: r_split_cells must be positive");
  }
};

namespace detail {

/// The cells (in one dimension, periodic) that a particle at coordinate x (in units
/// of the mesh spacing) touches and their weights: CIC two cells, TSC three.
struct Stencil {
  int first = 0, n = 0;
  double w[3] = {0, 0, 0};
};
inline Stencil stencil(double u, Assignment a, int nmesh) {
  Stencil s;
  if (a == Assignment::cic) {
    const double v = u - 0.5, f = std::floor(v), d = v - f;
    s.first = int(f), s.n = 2, s.w[0] = 1 - d, s.w[1] = d;
  } else {
    const double f = std::floor(u), d = u - (f + 0.5);
    s.first = int(f) - 1, s.n = 3;
    s.w[0] = 0.5 * (0.5 - d) * (0.5 - d), s.w[1] = 0.75 - d * d, s.w[2] = 0.5 * (0.5 + d) * (0.5 + d);
  }
  s.first = ((s.first % nmesh) + nmesh) % nmesh;
  return s;
}

}  // namespace detail

template <class CommT = SerialComm>
class ParticleMesh {
 public:
  ParticleMesh(MeshParams p, CommT comm) : p_(p), comm_(std::move(comm)) {
    p_.check();
    fft_ = std::make_unique<detail::SlabFft>(p_.n_mesh, comm_);
  }

  const MeshParams& params() const { return p_; }
  Profiler& profile() { return prof_; }

  /// Long-range accelerations at this rank's particles (positions anywhere: they are
  /// wrapped into the box), masses in units with G = 1. Collective.
  void accelerations(std::span<const Vec3<double>> pos, std::span<const double> mass,
                     std::span<Vec3<double>> acc) {
    if (pos.size() != mass.size() || pos.size() != acc.size())
      throw Error("particle mesh: positions, masses and accelerations differ in length");
    const int n = p_.n_mesh;
    const double h = p_.spacing();
    // Which planes this rank touches, and where each lives in the local buffer.
    {
      auto t = prof_.scope("pm assign");
      stencils_.resize(pos.size());
      std::vector<char> touched(std::size_t(n), 0);
      for (std::size_t i = 0; i < pos.size(); ++i) {
        auto& st = stencils_[i];
        for (int d = 0; d < 3; ++d) {
          const double x = wrap(pos[i][d]);
          if (!std::isfinite(x)) throw Error("particle mesh: particle " + std::to_string(i) + " has a non-finite position");
          st[d] = detail::stencil(x / h, p_.assignment, n);
        }
        for (int k = 0; k < st[0].n; ++k) touched[std::size_t((st[0].first + k) % n)] = 1;
      }
      planes_.clear();
      slot_.assign(std::size_t(n), -1);
      // Grouped by owner (owners hold consecutive planes, so plane order is owner order).
      for (int x = 0; x < n; ++x)
        if (touched[std::size_t(x)]) slot_[std::size_t(x)] = int(planes_.size()), planes_.push_back(x);
      const std::size_t plane = std::size_t(n) * n;
      buf_.assign(planes_.size() * plane, 0.0);
      for (std::size_t i = 0; i < pos.size(); ++i) {
        const auto& st = stencils_[i];
        const double m = mass[i] / (h * h * h);
        for (int a = 0; a < st[0].n; ++a) {
          double* pl = buf_.data() + std::size_t(slot_[std::size_t((st[0].first + a) % n)]) * plane;
          for (int b = 0; b < st[1].n; ++b) {
            double* row = pl + std::size_t((st[1].first + b) % n) * n;
            const double wab = m * st[0].w[a] * st[1].w[b];
            for (int c = 0; c < st[2].n; ++c) row[(st[2].first + c) % n] += wab * st[2].w[c];
          }
        }
      }
    }
    // Planes to their owners; each owner adds them into its slab.
    {
      auto t = prof_.scope("pm communicate");
      route_planes();
      fft_->zero();
      const std::size_t plane = std::size_t(n) * n;
      for (std::size_t k = 0; k < in_planes_.size(); ++k) {
        const int x = in_planes_[k];
        const double* src = in_buf_.data() + k * plane;
        for (int iy = 0; iy < n; ++iy) {
          double* row = fft_->real_row(x, iy);
          for (int iz = 0; iz < n; ++iz) row[iz] += src[std::size_t(iy) * n + iz];
        }
      }
    }
    // Solve: rho(k) -> phi(k), and each acceleration component back on the mesh.
    std::array<std::vector<double>, 3> field;
    {
      auto t = prof_.scope("pm fft");
      fft_->forward();
      const std::size_t nc = std::size_t(fft_->nx()) * fft_->complex_plane();
      const double* c = reinterpret_cast<const double*>(fft_->complex_data());
      rhok_.assign(c, c + 2 * nc);
      phik_ = rhok_;
      apply_green();
      for (int d = 0; d < 3; ++d) {
        gradient(d);
        fft_->backward();
        field[std::size_t(d)] = slab_values();
      }
    }
    // The planes each rank's particles read come back from their owners.
    std::array<std::vector<double>, 3> local;
    {
      auto t = prof_.scope("pm communicate");
      for (int d = 0; d < 3; ++d) local[std::size_t(d)] = return_planes(field[std::size_t(d)]);
    }
    {
      auto t = prof_.scope("pm interpolate");
      const std::size_t plane = std::size_t(n) * n;
      for (std::size_t i = 0; i < pos.size(); ++i) {
        const auto& st = stencils_[i];
        double a[3] = {0, 0, 0};
        for (int u = 0; u < st[0].n; ++u) {
          const std::size_t off = std::size_t(slot_[std::size_t((st[0].first + u) % n)]) * plane;
          for (int v = 0; v < st[1].n; ++v) {
            const std::size_t row = off + std::size_t((st[1].first + v) % n) * n;
            const double wuv = st[0].w[u] * st[1].w[v];
            for (int w = 0; w < st[2].n; ++w) {
              const std::size_t j = row + std::size_t((st[2].first + w) % n);
              const double wt = wuv * st[2].w[w];
              for (int d = 0; d < 3; ++d) a[d] += wt * local[std::size_t(d)][j];
            }
          }
        }
        acc[i] = {a[0], a[1], a[2]};
      }
    }
  }

  /// The same for a particle system (or pik::Species bundle) whose full particles
  /// have getPos(), getChargeParticleMesh() (the mass, G = 1) and
  /// copyFromForceParticleMesh(const Vec3<double>&) (FDPS's names). Collective.
  template <class PS>
  void calcForceAllAndWriteBack(PS&& ps) {
    const std::size_t np = ps.size();
    pos_.resize(np), mass_.resize(np), acc_.resize(np);
    for (std::size_t i = 0; i < np; ++i)
      visit(ps, i, [&](const auto& p) {
        const auto x = p.getPos();
        pos_[i] = {double(x.x), double(x.y), double(x.z)};
        mass_[i] = double(p.getChargeParticleMesh());
      });
    accelerations(pos_, mass_, acc_);
    for (std::size_t i = 0; i < np; ++i) visit(ps, i, [&](auto& p) { p.copyFromForceParticleMesh(acc_[i]); });
  }

  /// The mesh density's Fourier modes of the last call (this rank's slab, FFTW's
  /// r2c layout, unnormalised, the assignment window not undone; for power spectra).
  std::span<const double> densityModes() const { return rhok_; }
  const detail::SlabFft& fft() const { return *fft_; }

 private:
  template <class PS, class F>
  static void visit(PS& ps, std::size_t i, F&& f) {
    if constexpr (requires { ps.visit(i, f); }) ps.visit(i, f);
    else f(ps[i]);
  }

  double wrap(double x) const {
    const double L = p_.box;
    double y = x - L * std::floor(x / L);
    return y >= L ? 0.0 : y;
  }

  /// Sends this rank's touched planes (buf_, planes_) to their owners: in_planes_
  /// and in_buf_ get what arrived; the request lists are kept for return_planes.
  void route_planes() {
    const int nr = comm_.size(), n = p_.n_mesh;
    const std::size_t plane = std::size_t(n) * n;
    std::vector<std::size_t> counts(std::size_t(nr), 0), dcounts(std::size_t(nr), 0);
    for (int x : planes_) ++counts[std::size_t(fft_->owner(x))];
    for (int r = 0; r < nr; ++r) dcounts[std::size_t(r)] = counts[std::size_t(r)] * plane;
    std::vector<std::size_t> got;
    in_planes_ = comm_.alltoallv(std::span<const int>(planes_), std::span<const std::size_t>(counts), &got);
    in_counts_ = got;
    in_buf_ = comm_.alltoallv(std::span<const double>(buf_), std::span<const std::size_t>(dcounts));
    out_counts_ = counts;
  }

  /// The planes other ranks asked for (in_planes_) sent back from the local slab
  /// values `slab` (nx planes of n * n); returns this rank's planes in planes_ order.
  std::vector<double> return_planes(const std::vector<double>& slab) const {
    const int nr = comm_.size(), n = p_.n_mesh;
    const std::size_t plane = std::size_t(n) * n;
    std::vector<double> send(in_planes_.size() * plane);
    for (std::size_t k = 0; k < in_planes_.size(); ++k)
      std::copy_n(slab.begin() + std::ptrdiff_t(std::size_t(in_planes_[k] - fft_->x0()) * plane), plane,
                  send.begin() + std::ptrdiff_t(k * plane));
    std::vector<std::size_t> counts(static_cast<std::size_t>(nr));
    for (int r = 0; r < nr; ++r) counts[std::size_t(r)] = in_counts_[std::size_t(r)] * plane;
    return comm_.alltoallv(std::span<const double>(send), std::span<const std::size_t>(counts));
  }

  /// phik_ = G(k) rho(k) (the long-range potential).
  void apply_green() {
    const int n = p_.n_mesh, nzc = fft_->nzc();
    const double L = p_.box, h = p_.spacing(), rs = p_.r_split(), twopi = 2 * std::numbers::pi;
    const int pw = int(p_.assignment);
    std::vector<double> sinc(static_cast<std::size_t>(n)), kk(static_cast<std::size_t>(n));
    for (int m = 0; m < n; ++m) {
      const int mm = m <= n / 2 ? m : m - n;
      kk[std::size_t(m)] = twopi * mm / L;
      const double a = 0.5 * kk[std::size_t(m)] * h;
      sinc[std::size_t(m)] = mm == 0 ? 1.0 : std::sin(a) / a;
    }
    for (int ix = 0; ix < fft_->nx(); ++ix) {
      const int gx = fft_->x0() + ix;
      for (int iy = 0; iy < n; ++iy)
        for (int iz = 0; iz < nzc; ++iz) {
          const std::size_t j = (std::size_t(ix) * n + iy) * nzc + iz;
          const double kx = kk[std::size_t(gx)], ky = kk[std::size_t(iy)], kz = kk[std::size_t(iz)];
          const double k2 = kx * kx + ky * ky + kz * kz;
          double g = 0;
          if (k2 > 0) {
            const double w = sinc[std::size_t(gx)] * sinc[std::size_t(iy)] * sinc[std::size_t(iz)];
            const double w2p = std::pow(w, 2 * pw);
            g = -4 * std::numbers::pi / k2 * std::exp(-k2 * rs * rs) / w2p;
          }
          phik_[2 * j] *= g, phik_[2 * j + 1] *= g;
        }
    }
  }

  /// Puts a_d(k) = -i k_d phi(k) into the FFT buffer (normalised by 1/N^3).
  void gradient(int d) {
    const int n = p_.n_mesh, nzc = fft_->nzc();
    const double twopi = 2 * std::numbers::pi, norm = 1.0 / (double(n) * n * n);
    double* c = reinterpret_cast<double*>(fft_->complex_data());
    for (int ix = 0; ix < fft_->nx(); ++ix) {
      const int gx = fft_->x0() + ix;
      for (int iy = 0; iy < n; ++iy)
        for (int iz = 0; iz < nzc; ++iz) {
          const int m = d == 0 ? gx : (d == 1 ? iy : iz);
          // The Nyquist mode's derivative is zero (its sine has no value on the mesh).
          const int mm = (2 * m == n) ? 0 : (m <= n / 2 ? m : m - n);
          const double k = twopi * mm / p_.box * norm;
          const std::size_t j = (std::size_t(ix) * n + iy) * nzc + iz;
          const double re = phik_[2 * j], im = phik_[2 * j + 1];
          // -i k (re + i im) = k im - i k re
          c[2 * j] = k * im, c[2 * j + 1] = -k * re;
        }
    }
  }

  /// The local slab's real values as nx planes of n * n (padding dropped).
  std::vector<double> slab_values() {
    const int n = p_.n_mesh;
    std::vector<double> v(std::size_t(fft_->nx()) * n * n);
    for (int ix = 0; ix < fft_->nx(); ++ix)
      for (int iy = 0; iy < n; ++iy) {
        const double* row = fft_->real_row(fft_->x0() + ix, iy);
        std::copy_n(row, n, v.begin() + std::ptrdiff_t((std::size_t(ix) * n + iy) * n));
      }
    return v;
  }

  MeshParams p_;
  CommT comm_;
  std::unique_ptr<detail::SlabFft> fft_;
  Profiler prof_;
  std::vector<std::array<detail::Stencil, 3>> stencils_;
  std::vector<int> planes_, slot_, in_planes_;
  std::vector<std::size_t> in_counts_, out_counts_;
  std::vector<double> buf_, in_buf_, rhok_, phik_;
  std::vector<Vec3<double>> pos_, acc_;
  std::vector<double> mass_;
};

}  // namespace pik::pm
