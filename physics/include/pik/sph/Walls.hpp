/// \file Walls.hpp
/// \brief Plane walls of a box through mirror particles: each particle within reach of a
///        wall is reflected across it (and across two or three walls near an edge or
///        corner), and the images are handed to a short-range tree as imported
///        j-particles, so every neighbour pass sees them without a loop in the program.
///
/// Mirror particles (Libersky et al. 1993, J. Comput. Phys. 109, 67; Morris, Fox & Zhu
/// 1997, J. Comput. Phys. 136, 214, sec. 3) make the kernel sums near a wall those of a
/// flow continued by symmetry: a free-slip wall reflects the normal velocity (the
/// tangential one is kept, so the shear stress at the wall vanishes), a no-slip wall
/// reverses the whole velocity; a wall at fixed temperature T_w gives the image
/// 2 T_w - T (a linear profile through the wall, so the conduction sum sees the wall
/// temperature), an insulating wall the same T (no flux). Position, velocity and the
/// face of the image are the walls' business; every other field is copied (copyFromFP)
/// and the EPJ type may define
///
///     void mirror(int axis, int side, const pik::sph::WallFace& face);
///
/// to set what else a wall changes (a temperature, a flag that marks images of one
/// wall). An EPJ with a `vel` member gets its velocity reflected by the walls before
/// mirror() is called. Dimensions with `WallFace::kind == none` on both sides are left
/// alone (open or periodic there).
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include <pik/Box.hpp>
#include <pik/Error.hpp>
#include <pik/Vec.hpp>
#include <pik/particle/ParticleSystem.hpp>

namespace pik::sph {

/// What one face of the box does.
struct WallFace {
  enum class Kind { none, free_slip, no_slip };
  Kind kind = Kind::none;
  bool fixed_temperature = false;  ///< false: insulating (images carry the same temperature)
  double temperature = 0;          ///< T_w when fixed_temperature

  bool is_wall() const { return kind != Kind::none; }
  /// The image's temperature for a particle at temperature t.
  double image_temperature(double t) const { return fixed_temperature ? 2 * temperature - t : t; }
};

/// Walls on the faces of an axis-aligned box in D dimensions; face(axis, side) with side 0
/// the lower face (at box.lo[axis]) and 1 the upper one.
template <int D>
class Walls {
 public:
  Walls() = default;
  explicit Walls(const Box<double, D>& box) : box_(box) {
    for (int d = 0; d < D; ++d)
      if (!(box.hi[d] > box.lo[d]))
        throw Error("walls: the box is empty in dimension " + std::to_string(d) + " (hi must be above lo)");
  }

  const Box<double, D>& box() const { return box_; }
  WallFace& face(int axis, int side) { return faces_[std::size_t(axis)][std::size_t(side)]; }
  const WallFace& face(int axis, int side) const { return faces_[std::size_t(axis)][std::size_t(side)]; }
  /// Sets both faces of an axis.
  void set_axis(int axis, const WallFace& lo, const WallFace& hi) { face(axis, 0) = lo, face(axis, 1) = hi; }
  double plane(int axis, int side) const { return side ? box_.hi[axis] : box_.lo[axis]; }

  /// Throws unless every particle lies inside the box in every walled dimension.
  template <class FP>
  void check_inside(const ParticleSystem<FP>& ps) const {
    for (const auto& p : ps) {
      const auto x = p.getPos();
      for (int d = 0; d < D; ++d)
        for (int s = 0; s < 2; ++s)
          if (face(d, s).is_wall() && (s ? double(x[d]) > box_.hi[d] : double(x[d]) < box_.lo[d]))
            throw Error("walls: particle " + std::to_string(p.id) + " lies outside the box in dimension " +
                        std::to_string(d));
    }
  }

  /// A particle that has crossed a wall during a drift is put back by reflection (position
  /// mirrored, velocities of the members listed reflected as the face says). A step short
  /// enough for the Courant condition never needs it; it keeps a rare overshoot inside.
  template <class FP>
  std::size_t reflect_escaped(ParticleSystem<FP>& ps) const {
    std::size_t n = 0;
    for (auto& p : ps) {
      auto x = p.getPos();
      bool moved = false;
      for (int d = 0; d < D; ++d)
        for (int s = 0; s < 2; ++s) {
          const WallFace& f = face(d, s);
          if (!f.is_wall()) continue;
          const double w = plane(d, s);
          if (s ? double(x[d]) > w : double(x[d]) < w) {
            x[d] = std::remove_cvref_t<decltype(x[d])>(2 * w - double(x[d]));
            reflect_velocity(p.vel, d, f);
            if constexpr (requires { p.vel_half; }) reflect_velocity(p.vel_half, d, f);
            moved = true;
          }
        }
      if (moved) p.setPos(x), ++n;
    }
    return n;
  }

  /// The images of every particle closer than `reach` to a wall (reach: at least the
  /// largest search radius of the pass), as EPJ values: copyFromFP, position reflected,
  /// velocity reflected (if EPJ has `vel`), then EPJ::mirror for each wall crossed.
  /// Near an edge (corner) a particle has 3 (7) images.
  template <class EPJ, class FP>
  std::vector<EPJ> images(const ParticleSystem<FP>& ps, double reach) const {
    std::vector<EPJ> out;
    for (const auto& p : ps)
      push_images(out, p.getPos(), reach, [&] {
        EPJ e;
        e.copyFromFP(p);
        return e;
      });
    return out;
  }

  /// The images of j-particles that are already EPJ values (e.g. the halo a rank
  /// imported from its neighbours under MPI), by the same rules as images(): a rank that
  /// mirrors its own particles and its halo sees every image within reach of its
  /// particles, since a reflection never brings a particle closer to a point inside the
  /// box. The reach test uses the EPJ position (its precision).
  template <class EPJ>
  std::vector<EPJ> images_of(std::span<const EPJ> js, double reach) const {
    std::vector<EPJ> out;
    for (const EPJ& j : js) push_images(out, j.getPos(), reach, [&] { return j; });
    return out;
  }

  /// Hands the images to a tree as its imported particles for the next pass
  /// (tree.setImportedParticles); returns how many there are.
  template <class EPJ, class Tree, class FP>
  std::size_t attach(Tree& tree, const ParticleSystem<FP>& ps, double reach) const {
    std::vector<EPJ> img = images<EPJ>(ps, reach);
    const std::size_t n = img.size();
    tree.setImportedParticles(std::move(img));
    return n;
  }

 private:
  /// Appends the images of one particle at x (its EPJ value from make()) to out.
  template <class EPJ, class X, class Make>
  void push_images(std::vector<EPJ>& out, const X& x, double reach, Make&& make) const {
    std::array<int, 2 * D> axis{}, side{};  // up to two faces per axis (a thin box)
    int n = 0;
    for (int d = 0; d < D; ++d)
      for (int s = 0; s < 2; ++s) {
        if (!face(d, s).is_wall()) continue;
        const double dist = s ? box_.hi[d] - double(x[d]) : double(x[d]) - box_.lo[d];
        // both faces of one axis within reach (a box thinner than 2 reach): one image
        // across each, never the two combined
        if (dist < reach) axis[std::size_t(n)] = d, side[std::size_t(n)] = s, ++n;
      }
    if (n == 0) return;
    for (unsigned mask = 1; mask < (1u << n); ++mask) {
      bool valid = true;
      for (int a = 0; a < n && valid; ++a)
        for (int b = a + 1; b < n; ++b)
          if ((mask >> a & 1u) && (mask >> b & 1u) && axis[std::size_t(a)] == axis[std::size_t(b)]) valid = false;
      if (!valid) continue;
      EPJ e = make();
      auto y = e.getPos();
      for (int a = 0; a < n; ++a) {
        if (!(mask >> a & 1u)) continue;
        const int d = axis[std::size_t(a)], s = side[std::size_t(a)];
        const WallFace& f = face(d, s);
        y[d] = std::remove_cvref_t<decltype(y[d])>(2 * plane(d, s) - double(y[d]));
        if constexpr (requires { e.vel; }) reflect_velocity(e.vel, d, f);
        if constexpr (requires { e.mirror(d, s, f); }) e.mirror(d, s, f);
      }
      e.setPos(y);
      out.push_back(e);
    }
  }

  template <class V>
  static void reflect_velocity(V& v, int d, const WallFace& f) {
    if (f.kind == WallFace::Kind::free_slip) {
      v[d] = -v[d];
    } else if (f.kind == WallFace::Kind::no_slip) {
      for (int k = 0; k < 3; ++k) v[k] = -v[k];
    }
  }

  Box<double, D> box_{};
  std::array<std::array<WallFace, 2>, D> faces_{};
};

}  // namespace pik::sph
