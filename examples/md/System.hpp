/// \file System.hpp
/// \brief A periodic Lennard-Jones system: forces through pik's short-range tree and
///        the generated kernel (kernels/lj.pik), velocity-Verlet steps, observables.
///
/// Neighbour search: pik::ShortRangeTree in gather mode over a fully periodic cube;
/// the tree hands the kernel the periodic images of the j-atoms itself. The search
/// radius is r_c + skin and the candidate lists are kept (ListMode::make_for_reuse)
/// until some atom has moved more than skin / 2 since they were made, so no pair
/// within r_c can be missed (the Verlet-list argument; Verlet 1967). Between list
/// builds the atoms are not wrapped back into the box, so the kept image shifts stay
/// valid; they are wrapped when the lists are rebuilt.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "Particles.hpp"

namespace md {

struct ForceStats {
  std::uint64_t force_calls = 0;   ///< force evaluations
  std::uint64_t list_builds = 0;   ///< of which built the tree and candidate lists
  std::uint64_t pair_evals = 0;    ///< (i, j) candidates handed to the kernel, summed
  double seconds_total = 0;        ///< wall time in compute_forces
  double seconds_build = 0;        ///< tree build / reload and cell boxes ("neighbour search")
  double seconds_walk = 0;         ///< walk + kernel
  double seconds_kernel = 0;       ///< inside the kernel, summed over threads / threads
};

class System {
 public:
  /// atoms in [0, box)^3 (wrapped here if not), cutoff rc, Verlet skin (0: build the
  /// tree and lists at every force call).
  System(std::vector<Atom> atoms, double box, double rc, double skin);
  ~System();
  System(const System&) = delete;
  System& operator=(const System&) = delete;

  /// Recomputes acc, pot, vir of every atom (rebuilding the lists when needed).
  void compute_forces();
  /// One velocity-Verlet step: half kick, drift, forces, half kick.
  void step(double dt);
  /// Multiplies every velocity by s.
  void scale_velocities(double s);

  std::size_t size() const;
  double box() const { return box_; }
  double rc() const { return rc_; }
  double density() const;
  double kinetic() const;      ///< sum m v^2 / 2
  double temperature() const;  ///< 2 K / N_f, N_f = 3N - 3
  /// Potential energy per atom of the truncated (unshifted) potential, plus the tail
  /// correction when `tail`.
  double potential_per_atom(bool tail) const;
  /// Pressure rho T + W / (3V), W = sum_{i<j} r_ij . F_ij, plus the tail correction
  /// when `tail`; T is the kinetic temperature.
  double pressure(bool tail) const;
  /// Total momentum (zero up to rounding: pair forces are antisymmetric).
  Vec3<double> momentum() const;

  const std::vector<Atom>& atoms() const;
  const ForceStats& stats() const { return stats_; }
  void reset_stats() { stats_ = {}; }
  /// Name of the kernel variant the CPU runs (e.g. "avx512").
  static const char* kernel_isa();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  double box_, rc_, skin_;
  ForceStats stats_;
};

}  // namespace md
