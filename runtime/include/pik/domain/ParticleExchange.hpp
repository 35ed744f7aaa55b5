/// \file ParticleExchange.hpp
/// \brief pik::exchange_particles: move every particle to the rank owning its position.
///
/// After a decomposition or a drift, each rank wraps its particles into the
/// periodic box, finds each particle's owner (DomainInfo::owner) and sends the
/// ones that left in one all-to-all exchange. Particles that stay keep their order
/// and come first; arrivals follow in rank order, so the result is deterministic
/// and no particle is lost or duplicated.
#pragma once

#include <cmath>
#include <cstddef>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "pik/domain/DomainInfo.hpp"
#include "pik/domain/Position.hpp"

namespace pik {

/// What one exchange moved on this rank.
struct ExchangeStats {
  std::size_t sent = 0;      ///< particles that left this rank
  std::size_t received = 0;  ///< particles that arrived
  std::size_t wrapped = 0;   ///< positions wrapped into the periodic box
};

/// Moves every particle of `particles` to its owner under `domain`. The particle
/// type must be trivially copyable (it travels as bytes) and expose its position
/// (getPos/setPos or a `pos` member). A non-finite position stops the program with
/// a message naming the rank, particle index and position. Collective.
template <class P, class Real, int Dim, class CommT>
ExchangeStats exchange_particles(std::vector<P>& particles, const DomainInfo<Real, Dim, CommT>& domain) {
  static_assert(std::is_trivially_copyable_v<P>,
                "exchange_particles: the particle type must be trivially copyable");
  static_assert(HasWritablePosition<P>,
                "exchange_particles: the particle type needs getPos()/setPos() or a pos member");
  const CommT& comm = domain.comm();
  const int me = comm.rank();
  const auto nranks = static_cast<std::size_t>(comm.size());
  ExchangeStats st;

  std::vector<int> dest(particles.size());
  std::vector<std::size_t> counts(nranks, 0);
  for (std::size_t i = 0; i < particles.size(); ++i) {
    auto pos = domain_detail::position(particles[i]);
    for (int d = 0; d < Dim; ++d) {
      if (!std::isfinite(static_cast<double>(domain_detail::coord(pos, d)))) {
        std::string where;
        for (int e = 0; e < Dim; ++e)
          where += (e ? ", " : "") + std::to_string(static_cast<double>(domain_detail::coord(pos, e)));
        comm.abort("exchange_particles: particle " + std::to_string(i) + " on rank " +
                   std::to_string(me) + " has a non-finite position (" + where + ")");
      }
    }
    if (domain.wrap(pos)) {
      domain_detail::set_position(particles[i], pos);
      ++st.wrapped;
    }
    dest[i] = domain.owner(pos);
    const auto to = static_cast<std::size_t>(dest[i]);
    if (to >= nranks) comm.abort("exchange_particles: owner " + std::to_string(dest[i]) + " out of range");
    if (dest[i] != me) ++counts[to];
  }

  // Pack leavers by destination (stable), compact stayers in place.
  std::vector<std::size_t> offset(nranks, 0);
  for (std::size_t r = 1; r < nranks; ++r) offset[r] = offset[r - 1] + counts[r - 1];
  std::vector<P> out(nranks ? offset[nranks - 1] + counts[nranks - 1] : 0);
  std::size_t keep = 0;
  for (std::size_t i = 0; i < particles.size(); ++i) {
    if (dest[i] == me) {
      if (keep != i) particles[keep] = particles[i];
      ++keep;
    } else {
      const auto to = static_cast<std::size_t>(dest[i]);
      if (to < nranks) out[offset[to]++] = particles[i];
    }
  }
  st.sent = out.size();
  particles.resize(keep);
  auto in = comm.alltoallv(std::span<const P>(out), std::span<const std::size_t>(counts));
  st.received = in.size();
  particles.insert(particles.end(), in.begin(), in.end());
  return st;
}

/// The same for a particle container that exposes its storage as `vector()`
/// (pik::ParticleSystem).
template <class Container, class Real, int Dim, class CommT>
  requires requires(Container& c) { c.vector(); }
ExchangeStats exchange_particles(Container& particles, const DomainInfo<Real, Dim, CommT>& domain) {
  return exchange_particles(particles.vector(), domain);
}

}  // namespace pik
