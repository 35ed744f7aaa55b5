/// \file TreePM.hpp
/// \brief pik::pm::TreePM: periodic gravity as a particle mesh plus a cut-off tree.
///
/// The force on each particle is the mesh's long-range part (pik::pm::ParticleMesh,
/// the Gaussian split at r_s) plus the short-range part summed through a Barnes-Hut
/// tree with the complementary kernel (kernels/gravity_treepm.pik), cut off at
/// r_cut = 5 r_s by default (GADGET-2 uses 4.5 r_s, Springel 2005 sect. 2.2). The
/// short-range sum takes the nearest periodic image of every pair: the j-particles
/// within r_cut of the faces of a rank's particles' bounding box enter the tree
/// again as shifted images (imported j-particles), and cells at least r_cut from an
/// i-group are skipped in the walk (TreeParams::r_cut). Since r_cut < L / 2, every
/// pair closer than r_cut under the minimum image is counted exactly once.
///
/// Under MPI the same images serve as the halo: rank r receives from every rank
/// (itself included) the particles, shifted by 0 or +-L per dimension, that lie
/// within r_cut of r's particles' bounding box, and the mesh is distributed in
/// slabs. One call per step, after the domain decomposition and exchange:
///
/// ```cpp
/// pik::pm::TreePM<Force, EPI, EPJ> gravity({.mesh = {.box = L, .n_mesh = 64}}, comm);
/// gravity.calcForceAllAndWriteBack(kernel, kernel_sp, ps);  // or pik::species(dm, gas)
/// ```
///
/// The full particle receives the short-range result through copyFromForce(FORCE)
/// and the long-range acceleration through copyFromForceParticleMesh(Vec3<double>)
/// (FDPS's name); its total acceleration is the sum. The mesh reads each particle's
/// mass as its EPJ's getCharge() (G = 1).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numbers>
#include <type_traits>
#include <vector>

#include "pik/Box.hpp"
#include "pik/Error.hpp"
#include "pik/domain/Position.hpp"
#include "pik/particle/Species.hpp"
#include "pik/pm/ParticleMesh.hpp"
#include "pik/walk/LongRangeTree.hpp"

namespace pik::pm {

struct TreePMParams {
  MeshParams mesh{};
  /// Opening angle and tree limits of the short-range walk. 0.3: at 0.5 the
  /// monopoles of cells inside r_cut double the rms error of a uniform set
  /// (docs/cosmo.md); the walk stops at r_cut, so a small theta costs little.
  double theta = 0.3;
  int n_leaf_limit = 8;
  int n_group_limit = 64;
  Opening opening = Opening::box;
  /// Cut-off of the short-range force in units of r_s. GADGET-2 uses 4.5, where the
  /// dropped factor g(4.5 r_s) = 0.0175 leaves rms errors near 3e-3; 5 (g = 0.0058)
  /// keeps them near 2e-3 (docs/cosmo.md).
  double r_cut_split = 5.0;

  double r_split() const { return mesh.r_split(); }
  double r_cut() const { return r_cut_split * mesh.r_split(); }
  void check() const {
    mesh.check();
    // kernels/gravity_treepm.pik evaluates exp(-r^2 / 4 r_s^2) for r <= 6 r_s only.
    if (!(r_cut_split > 0 && r_cut_split <= 6))
      throw Error("TreePM: r_cut_split must be in (0, 6], got " + std::to_string(r_cut_split));
    if (!(r_cut() < 0.5 * mesh.box))
      throw Error("TreePM: the cut-off " + std::to_string(r_cut()) + " must be below half the box " +
                  std::to_string(0.5 * mesh.box) + " (a finer mesh or a smaller r_split_cells)");
  }
};

template <class Force, class EPI, class EPJ, class SPJ = pik::detail::default_spj<EPJ>, class CommT = SerialComm>
class TreePM {
  static_assert(std::is_trivially_copyable_v<EPJ>, "TreePM: the EPJ type travels between ranks: trivially copyable");
  static_assert(HasWritablePosition<EPJ>, "TreePM: the EPJ type needs setPos(v) or a pos member (periodic images)");

 public:
  using tree_type = LongRangeTree<Force, EPI, EPJ, SPJ>;

  TreePM(TreePMParams p, CommT comm)
      : p_((p.check(), p)), comm_(comm), pm_(p.mesh, comm),
        tree_({.theta = p.theta, .n_leaf_limit = p.n_leaf_limit, .n_group_limit = p.n_group_limit,
               .opening = p.opening, .r_cut = p.r_cut()}) {}
  explicit TreePM(TreePMParams p) requires std::is_same_v<CommT, SerialComm> : TreePM(p, SerialComm::world()) {}

  const TreePMParams& params() const { return p_; }
  /// The kernel parameters of kernels/gravity_treepm.pik for this split: (eps2,
  /// rcut2, inv_2rs) = (eps^2, r_cut^2, 1 / (2 r_s)).
  double rcut2() const { return p_.r_cut() * p_.r_cut(); }
  double inv_2rs() const { return 0.5 / p_.r_split(); }

  /// Long-range (mesh) and short-range (tree) forces of every particle of `ps` (a
  /// pik::ParticleSystem or pik::Species bundle), written back. Collective.
  template <class PS, class K, class KS>
    requires ParticleSource<PS>
  void calcForceAllAndWriteBack(K&& kernel, KS&& kernel_sp, PS&& ps) {
    const double t0 = wall_time();
    load(ps);
    pm_.accelerations(pos_, mass_, acc_);
    for (std::size_t i = 0; i < pos_.size(); ++i)
      pik::detail::visit_particle(ps, i, [&](auto& fp) { fp.copyFromForceParticleMesh(acc_[i]); });
    const double t1 = wall_time();
    tree_.setImportedParticles(images());
    const double t2 = wall_time();
    tree_.calcForceAllAndWriteBack(kernel, kernel_sp, ps);
    tree_.clearImported();
    const double t3 = wall_time();
    seconds_mesh_ = t1 - t0, seconds_images_ = t2 - t1, seconds_tree_ = t3 - t2;
  }

  tree_type& tree() { return tree_; }
  ParticleMesh<CommT>& mesh() { return pm_; }
  /// Seconds of the last call: mesh (assignment, FFTs, interpolation), periodic
  /// images and halo, short-range tree (build, walk, kernels; split in tree().profile()).
  double secondsMesh() const { return seconds_mesh_; }
  double secondsImages() const { return seconds_images_; }
  double secondsTree() const { return seconds_tree_; }
  /// Imported j-particles (images and halo) of the last call.
  std::size_t importedParticles() const { return n_images_; }

 private:
  template <class PS>
  void load(const PS& ps) {
    const std::size_t n = ps.size();
    pos_.resize(n), mass_.resize(n), acc_.resize(n), epj_.resize(n);
    for (std::size_t i = 0; i < n; ++i)
      pik::detail::visit_particle(ps, i, [&](const auto& fp) { epj_[i].copyFromFP(fp); });
    Box<double, 3> bb;
    for (std::size_t i = 0; i < n; ++i) {
      const auto x = epj_[i].getPos();
      pos_[i] = {double(x.x), double(x.y), double(x.z)};
      mass_[i] = double(epj_[i].getCharge());
      if (!std::isfinite(pos_[i].x) || !std::isfinite(pos_[i].y) || !std::isfinite(pos_[i].z))
        throw Error("TreePM: " + ps.describe_bad_position(i));
      bb.extend(pos_[i]);
    }
    bbox_ = bb;
  }

  /// The j-particles every rank needs from this one: each particle, shifted by 0 or
  /// +-L per dimension, that lies within r_cut of a rank's bounding box (its own
  /// unshifted self excepted), sent in one all-to-all.
  std::vector<EPJ> images() {
    const double L = p_.mesh.box, rc = p_.r_cut();
    const int nr = comm_.size(), me = comm_.rank();
    struct B {
      double lo[3], hi[3];
    };
    B mine{};
    for (int d = 0; d < 3; ++d) {
      mine.lo[d] = bbox_.empty() ? std::numeric_limits<double>::infinity() : bbox_.lo[d] - rc;
      mine.hi[d] = bbox_.empty() ? -std::numeric_limits<double>::infinity() : bbox_.hi[d] + rc;
    }
    const std::vector<B> boxes = comm_.allgather(mine);
    std::vector<std::vector<EPJ>> out(static_cast<std::size_t>(nr));
    for (std::size_t i = 0; i < epj_.size(); ++i) {
      const Vec3<double>& x = pos_[i];
      for (int q = 0; q < nr; ++q) {
        const B& b = boxes[std::size_t(q)];
        double sh[3][3];
        int ns[3];
        for (int d = 0; d < 3; ++d) {
          ns[d] = 0;
          for (double s : {0.0, -L, L})
            if (x[d] + s >= b.lo[d] && x[d] + s <= b.hi[d]) sh[d][ns[d]++] = s;
        }
        for (int a = 0; a < ns[0]; ++a)
          for (int c = 0; c < ns[1]; ++c)
            for (int e = 0; e < ns[2]; ++e) {
              if (q == me && sh[0][a] == 0 && sh[1][c] == 0 && sh[2][e] == 0) continue;
              EPJ img = epj_[i];
              auto y = domain_detail::position(img);
              domain_detail::set_coord(y, 0, x.x + sh[0][a]);
              domain_detail::set_coord(y, 1, x.y + sh[1][c]);
              domain_detail::set_coord(y, 2, x.z + sh[2][e]);
              domain_detail::set_position(img, y);
              out[std::size_t(q)].push_back(img);
            }
      }
    }
    std::vector<std::size_t> counts(static_cast<std::size_t>(nr));
    std::vector<EPJ> send;
    for (int q = 0; q < nr; ++q) {
      counts[std::size_t(q)] = out[std::size_t(q)].size();
      send.insert(send.end(), out[std::size_t(q)].begin(), out[std::size_t(q)].end());
    }
    std::vector<EPJ> got = comm_.alltoallv(std::span<const EPJ>(send), std::span<const std::size_t>(counts));
    n_images_ = got.size();
    return got;
  }

  TreePMParams p_;
  CommT comm_;
  ParticleMesh<CommT> pm_;
  tree_type tree_;
  std::vector<Vec3<double>> pos_, acc_;
  std::vector<double> mass_;
  std::vector<EPJ> epj_;
  Box<double, 3> bbox_;
  std::size_t n_images_ = 0;
  double seconds_mesh_ = 0, seconds_images_ = 0, seconds_tree_ = 0;
};

}  // namespace pik::pm
