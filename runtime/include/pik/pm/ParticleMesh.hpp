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
#include <type_traits>
#include <vector>

#include "pik/Error.hpp"
#include "pik/Profiler.hpp"
#include "pik/Vec.hpp"
#include "pik/comm/Comm.hpp"
#include "pik/detail/Threads.hpp"
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

template <class CommT = SerialComm>
class ParticleMesh {
 public:
  ParticleMesh(MeshParams p, CommT comm) : p_(p), comm_(std::move(comm)) {
    p_.check();
    inv_h_ = p_.n_mesh / p_.box;
    fft_ = std::make_unique<detail::SlabFft>(p_.n_mesh, comm_);
  }

  const MeshParams& params() const { return p_; }
  Profiler& profile() { return prof_; }

  /// Long-range accelerations at this rank's particles (positions anywhere: they are
  /// wrapped into the box), masses in units with G = 1. Collective.
  ///
  /// The particles are taken in the order of their mesh rows (a counting sort by
  /// the cell's x and y index), so that assignment and interpolation walk the mesh
  /// coherently. Assignment is threaded over fixed chunks of x-planes, at least three
  /// planes wide, in two passes (even chunks, then odd ones): chunks of one pass
  /// touch disjoint planes, and since the chunks depend only on the mesh size the
  /// sums, and so the results, do not depend on the number of threads.
  void accelerations(std::span<const Vec3<double>> pos, std::span<const double> mass,
                     std::span<Vec3<double>> acc) {
    if (pos.size() != mass.size() || pos.size() != acc.size())
      throw Error("particle mesh: positions, masses and accelerations differ in length");
    const int n = p_.n_mesh;
    const std::size_t plane = std::size_t(n) * n;
    const bool serial = comm_.size() == 1;
    {
      auto t = prof_.scope("pm sort");
      sort_by_row(pos, mass);
      // Planes this rank touches (the stencil reaches one plane either side of a
      // particle's cell, CIC and TSC alike), grouped by owner (owners hold
      // consecutive planes, so plane order is owner order).
      planes_.clear();
      slot_.assign(std::size_t(n), -1);
      std::vector<char> touched(std::size_t(n), 0);
      for (int x = 0; x < n; ++x)
        if (serial || row_start_[std::size_t(x + 1) * n] > row_start_[std::size_t(x) * n])
          for (int o = -1; o <= 1; ++o) touched[std::size_t((x + o + n) % n)] = 1;
      for (int x = 0; x < n; ++x)
        if (touched[std::size_t(x)]) slot_[std::size_t(x)] = int(planes_.size()), planes_.push_back(x);
    }
    {
      auto t = prof_.scope("pm assign");
      if (serial) {
        fft_->zero();
        assign(fft_->real_row(0, 0), std::size_t(n) * fft_->padded_row(), fft_->padded_row());
      } else {
        buf_.assign(planes_.size() * plane, 0.0);
        assign(buf_.data(), plane, std::size_t(n));
      }
    }
    if (!serial) {
      // Planes to their owners; each owner adds them into its slab.
      auto t = prof_.scope("pm communicate");
      route_planes();
      fft_->zero();
      for (std::size_t k = 0; k < in_planes_.size(); ++k) {
        const int x = in_planes_[k];
        const double* src = in_buf_.data() + k * plane;
        for (int iy = 0; iy < n; ++iy) {
          double* row = fft_->real_row(x, iy);
          for (int iz = 0; iz < n; ++iz) row[iz] += src[std::size_t(iy) * n + iz];
        }
      }
    }
    // Solve: rho(k) -> a_d(k) = -i k_d G(k) rho(k), each component back on the mesh.
    field_.resize(planes_.size() * plane * 3);
    {
      auto t = prof_.scope("pm fft");
      if (green_.empty()) make_green();
      fft_->forward();
      const std::size_t nc = std::size_t(fft_->nx()) * fft_->complex_plane();
      const double* c = reinterpret_cast<const double*>(fft_->complex_data());
      rhok_.resize(2 * nc);
      pik::detail::parallel_for_static(std::ptrdiff_t(fft_->nx()), [&](std::ptrdiff_t ix) {
        const std::size_t a = std::size_t(ix) * 2 * fft_->complex_plane();
        std::copy_n(c + a, 2 * fft_->complex_plane(), rhok_.data() + a);
      });
      std::array<std::vector<double>, 3> slab;
      for (int d = 0; d < 3; ++d) {
        gradient(d);
        fft_->backward();
        if (serial) {
          // The slab is the whole mesh: interleave the component into field_ directly.
          pik::detail::parallel_for_static(std::ptrdiff_t(n) * n, [&](std::ptrdiff_t r) {
            const int x = int(r / n), iy = int(r % n);
            const double* row = fft_->real_row(x, iy);
            double* f = field_.data() + (std::size_t(slot_[std::size_t(x)]) * plane + std::size_t(iy) * n) * 3 + d;
            for (int iz = 0; iz < n; ++iz) f[3 * iz] = row[iz];
          });
        } else {
          slab[std::size_t(d)] = slab_values();
        }
      }
      if (!serial) {
        // The planes each rank's particles read come back from their owners.
        auto tc = prof_.scope("pm communicate");
        for (int d = 0; d < 3; ++d) {
          const std::vector<double> local = return_planes(slab[std::size_t(d)]);
          for (std::size_t j = 0; j < local.size(); ++j) field_[3 * j + std::size_t(d)] = local[j];
        }
      }
    }
    {
      auto t = prof_.scope("pm interpolate");
      if (p_.assignment == Assignment::cic) interpolate<2>(acc);
      else interpolate<3>(acc);
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

  /// The mesh coordinate u = x / h of a coordinate x, wrapped into [0, n).
  double mesh_coord(double x) const {
    const double L = p_.box;
    if (!(x >= 0 && x < L)) x = wrap(x);
    const double u = x * inv_h_;
    return u >= p_.n_mesh ? u - p_.n_mesh : u;  // x just below L can round to u = n, the same point as 0
  }

  /// order_: the particles sorted (stably) by the row (x, y cell index) they lie in;
  /// row_start_[r]: the first position in order_ of row r = x n + y (n^2 + 1 entries);
  /// packed_: their mesh coordinates and masses in that order, so that assignment and
  /// interpolation stream through memory (written by a scatter in the sort's second
  /// pass: random stores cost less than random loads in both of them would).
  void sort_by_row(std::span<const Vec3<double>> pos, std::span<const double> mass) {
    const int n = p_.n_mesh;
    const std::size_t np = pos.size(), rows = std::size_t(n) * n;
    key_.resize(np);
    constexpr std::uint32_t bad = ~std::uint32_t(0);
    pik::detail::parallel_for_static(std::ptrdiff_t(np), [&](std::ptrdiff_t k) {
      const std::size_t i = std::size_t(k);
      if (!std::isfinite(pos[i].x) || !std::isfinite(pos[i].y) || !std::isfinite(pos[i].z)) {
        key_[i] = bad;
        return;
      }
      const int cx = std::min(n - 1, int(mesh_coord(pos[i].x))), cy = std::min(n - 1, int(mesh_coord(pos[i].y)));
      key_[i] = std::uint32_t(std::size_t(cx) * n + std::size_t(cy));
    });
    row_start_.assign(rows + 1, 0);
    for (std::size_t i = 0; i < np; ++i) {
      if (key_[i] == bad) throw Error("particle mesh: particle " + std::to_string(i) + " has a non-finite position");
      ++row_start_[key_[i] + 1];
    }
    for (std::size_t r = 0; r < rows; ++r) row_start_[r + 1] += row_start_[r];
    order_.resize(np);
    packed_.resize(np);
    std::vector<std::size_t> next(row_start_.begin(), row_start_.end() - 1);
    for (std::size_t i = 0; i < np; ++i) {
      const std::size_t k = next[key_[i]]++;
      order_[k] = i;
      packed_[k] = {{mesh_coord(pos[i].x), mesh_coord(pos[i].y), mesh_coord(pos[i].z)}, mass[i]};
    }
  }
  struct Packed {
    double u[3], m;
  };

  /// The P cells (wrapped) a particle at mesh coordinate u touches, and their weights.
  template <int P>
  static void window(double u, int n, int* idx, double* w) {
    if constexpr (P == 2) {
      const double v = u - 0.5, f = std::floor(v), d = v - f;
      int i0 = int(f);
      i0 = i0 < 0 ? i0 + n : i0;
      idx[0] = i0, idx[1] = i0 + 1 == n ? 0 : i0 + 1;
      w[0] = 1 - d, w[1] = d;
    } else {
      const double f = std::floor(u), d = u - (f + 0.5);
      const int c = int(f);
      idx[0] = c == 0 ? n - 1 : c - 1, idx[1] = c, idx[2] = c + 1 >= n ? c + 1 - n : c + 1;
      w[0] = 0.5 * (0.5 - d) * (0.5 - d), w[1] = 0.75 - d * d, w[2] = 0.5 * (0.5 + d) * (0.5 + d);
    }
  }

  /// Adds the particles' densities m / h^3 to the planes at `base` (plane x at base +
  /// slot(x) * plane_stride, rows row_stride apart), threaded as described at
  /// accelerations().
  void assign(double* base, std::size_t plane_stride, std::size_t row_stride) {
    const int n = p_.n_mesh;
    const double inv_h3 = 1.0 / (p_.spacing() * p_.spacing() * p_.spacing());
    // Chunks of planes: an even number, at least 3 planes each, at most 64 (n alone fixes them).
    int nchunk = std::min(64, n / 3);
    nchunk -= nchunk % 2;
    if (nchunk < 4) nchunk = 1;
    auto run = [&](auto P, int c) {
      constexpr int p = decltype(P)::value;
      const int x0 = int(std::int64_t(n) * c / nchunk), x1 = int(std::int64_t(n) * (c + 1) / nchunk);
      const std::size_t k0 = row_start_[std::size_t(x0) * n], k1 = row_start_[std::size_t(x1) * n];
      for (std::size_t k = k0; k < k1; ++k) {
        const Packed& q = packed_[k];
        int ix[p], iy[p], iz[p];
        double wx[p], wy[p], wz[p];
        window<p>(q.u[0], n, ix, wx);
        window<p>(q.u[1], n, iy, wy);
        window<p>(q.u[2], n, iz, wz);
        const double m = q.m * inv_h3;
        for (int a = 0; a < p; ++a) {
          double* pl = base + std::size_t(slot_[std::size_t(ix[a])]) * plane_stride;
          const double ma = m * wx[a];
          for (int b = 0; b < p; ++b) {
            double* row = pl + std::size_t(iy[b]) * row_stride;
            const double wab = ma * wy[b];
            for (int e = 0; e < p; ++e) row[iz[e]] += wab * wz[e];
          }
        }
      }
    };
    for (int pass = 0; pass < (nchunk == 1 ? 1 : 2); ++pass) {
      const int count = nchunk == 1 ? 1 : nchunk / 2;
      pik::detail::parallel_for(std::ptrdiff_t(count), [&](std::ptrdiff_t j, int) {
        const int c = nchunk == 1 ? 0 : int(2 * j) + pass;
        if (p_.assignment == Assignment::cic) run(std::integral_constant<int, 2>{}, c);
        else run(std::integral_constant<int, 3>{}, c);
      });
    }
  }

  /// acc[i] from field_ (the three components interleaved per cell, planes in slot order).
  template <int P>
  void interpolate(std::span<Vec3<double>> acc) const {
    const int n = p_.n_mesh;
    const std::size_t plane = std::size_t(n) * n;
    pik::detail::parallel_for_static(std::ptrdiff_t(order_.size()), [&](std::ptrdiff_t k) {
      const Packed& q = packed_[std::size_t(k)];
      int ix[P], iy[P], iz[P];
      double wx[P], wy[P], wz[P];
      window<P>(q.u[0], n, ix, wx);
      window<P>(q.u[1], n, iy, wy);
      window<P>(q.u[2], n, iz, wz);
      double a0 = 0, a1 = 0, a2 = 0;
      for (int u = 0; u < P; ++u) {
        const double* pl = field_.data() + std::size_t(slot_[std::size_t(ix[u])]) * plane * 3;
        for (int v = 0; v < P; ++v) {
          const double* row = pl + std::size_t(iy[v]) * n * 3;
          const double wuv = wx[u] * wy[v];
          for (int w = 0; w < P; ++w) {
            const double wt = wuv * wz[w];
            const double* f = row + 3 * std::size_t(iz[w]);
            a0 += wt * f[0], a1 += wt * f[1], a2 += wt * f[2];
          }
        }
      }
      acc[order_[std::size_t(k)]] = {a0, a1, a2};
    });
  }

  /// green_ = G(k) / N^3 on this rank's slab: the long-range potential per unit
  /// density mode, with the normalisation of the backward transform folded in.
  void make_green() {
    const int n = p_.n_mesh, nzc = fft_->nzc();
    const double L = p_.box, h = p_.spacing(), rs = p_.r_split(), twopi = 2 * std::numbers::pi;
    const double norm = 1.0 / (double(n) * n * n);
    const int pw = int(p_.assignment);
    std::vector<double> sinc(static_cast<std::size_t>(n)), kk(static_cast<std::size_t>(n));
    for (int m = 0; m < n; ++m) {
      const int mm = m <= n / 2 ? m : m - n;
      kk[std::size_t(m)] = twopi * mm / L;
      const double a = 0.5 * kk[std::size_t(m)] * h;
      sinc[std::size_t(m)] = mm == 0 ? 1.0 : std::sin(a) / a;
    }
    green_.assign(std::size_t(fft_->nx()) * fft_->complex_plane(), 0.0);
    pik::detail::parallel_for_static(std::ptrdiff_t(fft_->nx()) * n, [&](std::ptrdiff_t r) {
      const int ix = int(r / n), iy = int(r % n), gx = fft_->x0() + ix;
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
        green_[j] = g * norm;
      }
    });
  }

  /// Puts a_d(k) = -i k_d G(k) rho(k) / N^3 into the FFT buffer.
  void gradient(int d) {
    const int n = p_.n_mesh, nzc = fft_->nzc();
    const double twopi = 2 * std::numbers::pi;
    double* c = reinterpret_cast<double*>(fft_->complex_data());
    pik::detail::parallel_for_static(std::ptrdiff_t(fft_->nx()) * n, [&](std::ptrdiff_t r) {
      const int ix = int(r / n), iy = int(r % n), gx = fft_->x0() + ix;
      for (int iz = 0; iz < nzc; ++iz) {
        const int m = d == 0 ? gx : (d == 1 ? iy : iz);
        // The Nyquist mode's derivative is zero (its sine has no value on the mesh).
        const int mm = (2 * m == n) ? 0 : (m <= n / 2 ? m : m - n);
        const double k = twopi * mm / p_.box;
        const std::size_t j = (std::size_t(ix) * n + iy) * nzc + iz;
        const double g = k * green_[j], re = rhok_[2 * j], im = rhok_[2 * j + 1];
        // -i k g (re + i im) = k g im - i k g re
        c[2 * j] = g * im, c[2 * j + 1] = -g * re;
      }
    });
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
  double inv_h_ = 0;  // 1 / h
  CommT comm_;
  std::unique_ptr<detail::SlabFft> fft_;
  Profiler prof_;
  std::vector<std::uint32_t> key_;
  std::vector<std::size_t> order_, row_start_;
  std::vector<Packed> packed_;
  std::vector<int> planes_, slot_, in_planes_;
  std::vector<std::size_t> in_counts_, out_counts_;
  std::vector<double> buf_, in_buf_, rhok_, green_, field_;
  std::vector<Vec3<double>> pos_, acc_;
  std::vector<double> mass_;
};

}  // namespace pik::pm
