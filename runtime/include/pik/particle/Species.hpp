/// \file Species.hpp
/// \brief pik::Species: several particle systems of different types seen as one set.
///
/// A simulation of dark matter and gas (or stars, or sink particles) keeps each kind
/// in its own pik::ParticleSystem of its own type, but gravity must see them all in
/// one tree. `pik::species(dm, gas)` bundles references to the systems; a long-range
/// tree (pik::LongRangeTree, pik::DistributedLongRangeTree) takes the bundle where it
/// takes one particle system, loads every species into one tree, walks once, and
/// writes each result back into the particle it came from (FDPS lets several
/// particle systems feed one tree the same way). The user writes no loop over
/// species: the EPI / EPJ types only need one `copyFromFP` per full-particle type,
/// and each full-particle type its own `copyFromForce`.
///
/// Index i of the bundle is particle i - offset(s) of species s, offsets in the
/// order the systems were given: the bundle of (a, b) orders particles exactly as
/// one system holding a's particles followed by b's would.
///
/// ```cpp
/// pik::ParticleSystem<DarkMatter> dm;  pik::ParticleSystem<Gas> gas;
/// pik::LongRangeTree<Force, EPI, EPJ> tree;
/// tree.calcForceAllAndWriteBack(kernel, kernel_sp, pik::species(dm, gas));
/// ```
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>

#include "pik/Error.hpp"
#include "pik/particle/Concepts.hpp"
#include "pik/particle/ParticleSystem.hpp"

namespace pik {

/// References to N particle systems (not owning; the systems must outlive it). The
/// particle counts are read when the bundle is made: make a new one after particles
/// were added or removed (pik::species() is cheap).
template <class... FP>
class Species {
  static_assert(sizeof...(FP) >= 1, "pik::Species needs at least one particle system");

 public:
  static constexpr std::size_t count = sizeof...(FP);
  using first_type = std::tuple_element_t<0, std::tuple<FP...>>;
  static constexpr int dim = dim_of<first_type>;
  static_assert(((dim_of<FP> == dim) && ...), "pik::Species: every species needs the same dimension");
  template <std::size_t S>
  using type = std::tuple_element_t<S, std::tuple<FP...>>;

  explicit Species(ParticleSystem<FP>&... ps) : ps_(&ps...) {
    std::size_t s = 0, n = 0;
    offset_[0] = 0;
    ((n += ps.size(), offset_[++s] = n), ...);
  }

  /// Particles of all species together.
  std::size_t size() const { return offset_[count]; }
  bool empty() const { return size() == 0; }
  /// The particle system of species S.
  template <std::size_t S>
  ParticleSystem<type<S>>& get() const {
    return *std::get<S>(ps_);
  }
  /// Index of species s's first particle in the bundle; offset(count) = size().
  std::size_t offset(std::size_t s) const { return offset_.at(s); }
  /// The species that bundle index i belongs to.
  std::size_t species_of(std::size_t i) const {
    std::size_t s = 0;
    while (s + 1 < count && i >= offset_[s + 1]) ++s;
    return s;
  }

  /// Calls f(particle) with particle i of the bundle, as its own type (mutable: a
  /// bundle is a view, like std::span).
  template <class F>
  void visit(std::size_t i, F&& f) const {
    visit_from<0>(i, f);
  }
  /// Calls f(system, offset) for every species in order.
  template <class F>
  void for_each_species(F&& f) const {
    for_each_from<0>(f);
  }

  /// Throws pik::Error naming the species and particle of the first non-finite position.
  void checkPositions() const {
    for_each_species([&](auto& ps, std::size_t) {
      try {
        ps.checkPositions();
      } catch (const Error& e) {
        throw Error("species " + std::to_string(index_of(ps)) + ": " + e.what());
      }
    });
  }
  /// "species 1: particle 12 has a non-finite position (nan, 0, 1)".
  std::string describe_bad_position(std::size_t i) const {
    const std::size_t s = species_of(i);
    std::string out;
    for_each_species([&](auto& ps, std::size_t off) {
      if (index_of(ps) == s) out = "species " + std::to_string(s) + ": " + ps.describe_bad_position(i - off);
    });
    return out;
  }

 private:
  template <std::size_t S, class F>
  void visit_from(std::size_t i, F& f) const {
    if constexpr (S + 1 == count) {
      f((*std::get<S>(ps_))[i - offset_[S]]);
    } else {
      if (i < offset_[S + 1]) f((*std::get<S>(ps_))[i - offset_[S]]);
      else visit_from<S + 1>(i, f);
    }
  }
  template <std::size_t S, class F>
  void for_each_from(F& f) const {
    if constexpr (S < count) {
      f(*std::get<S>(ps_), offset_[S]);
      for_each_from<S + 1>(f);
    }
  }
  template <class PS>
  std::size_t index_of(const PS& ps) const {
    std::size_t k = 0, found = count;
    for_each_species([&](auto& other, std::size_t) {
      if constexpr (std::is_same_v<std::remove_cvref_t<decltype(other)>, PS>)
        if (&other == &ps && found == count) found = k;
      ++k;
    });
    return found;
  }

  std::tuple<ParticleSystem<FP>*...> ps_;
  std::array<std::size_t, count + 1> offset_{};
};

/// Bundles particle systems for one tree: `tree.calcForceAllAndWriteBack(k, ks,
/// pik::species(dm, gas))`.
template <class... FP>
Species<FP...> species(ParticleSystem<FP>&... ps) {
  return Species<FP...>(ps...);
}

namespace detail {

template <class T>
struct is_species : std::false_type {};
template <class... FP>
struct is_species<Species<FP...>> : std::true_type {};
template <class T>
struct is_particle_system : std::false_type {};
template <class FP>
struct is_particle_system<ParticleSystem<FP>> : std::true_type {};

/// f(particle i) for a ParticleSystem or a Species bundle.
template <class FP, class F>
void visit_particle(const ParticleSystem<FP>& ps, std::size_t i, F&& f) {
  f(ps[i]);
}
template <class FP, class F>
void visit_particle(ParticleSystem<FP>& ps, std::size_t i, F&& f) {
  f(ps[i]);
}
template <class... FP, class F>
void visit_particle(const Species<FP...>& sp, std::size_t i, F&& f) {
  sp.visit(i, f);
}

/// Whether every full-particle type of a source satisfies Check<FP>::value.
template <template <class> class Check, class PS>
struct all_particles;
template <template <class> class Check, class FP>
struct all_particles<Check, ParticleSystem<FP>> : std::bool_constant<Check<FP>::value> {};
template <template <class> class Check, class... FP>
struct all_particles<Check, Species<FP...>> : std::bool_constant<(Check<FP>::value && ...)> {};

}  // namespace detail

/// What a tree can load particles from: one pik::ParticleSystem or a pik::Species bundle.
template <class PS>
concept ParticleSource = detail::is_particle_system<std::remove_cvref_t<PS>>::value ||
                         detail::is_species<std::remove_cvref_t<PS>>::value;

}  // namespace pik
