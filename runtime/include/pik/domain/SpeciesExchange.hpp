/// \file SpeciesExchange.hpp
/// \brief One domain decomposition and exchange for several species (pik::Species).
///
/// The domains are cut once, from samples of every species together (a rank's cost
/// is shared by all its particles), and each species' particles then move to the
/// rank owning their position under those same domains, so the ranks' domains hold
/// the dark matter and the gas of the same region, as one long-range tree over the
/// bundle needs.
///
/// ```cpp
/// pik::decompose(dinfo, pik::species(dm, gas), tree.cost());
/// pik::exchange_particles(pik::species(dm, gas), dinfo);
/// tree.calcForceAllAndWriteBack(kernel, kernel_sp, pik::species(dm, gas), comm);
/// ```
#pragma once

#include <vector>

#include "pik/Vec.hpp"
#include "pik/domain/DomainInfo.hpp"
#include "pik/domain/ParticleExchange.hpp"
#include "pik/particle/Species.hpp"

namespace pik {

namespace detail {
template <int D>
struct SamplePosition {
  Vec<double, D> pos;
};
}  // namespace detail

/// DomainInfo::decompose over the particles of every species in the bundle.
/// Collective.
template <class Real, int Dim, class CommT, class... FP>
void decompose(DomainInfo<Real, Dim, CommT>& domain, const Species<FP...>& sp, double cost = -1.0) {
  std::vector<detail::SamplePosition<Dim>> pos(sp.size());
  sp.for_each_species([&](auto& ps, std::size_t off) {
    for (std::size_t i = 0; i < ps.size(); ++i) {
      const auto x = ps[i].getPos();
      if constexpr (Dim == 2) {
        pos[off + i].pos = {double(x.x), double(x.y)};
      } else {
        pos[off + i].pos = {double(x.x), double(x.y), double(x.z)};
      }
    }
  });
  domain.decompose(pos, cost);
}

/// exchange_particles for every species in the bundle, under the same domains;
/// returns the summed statistics. Collective.
template <class Real, int Dim, class CommT, class... FP>
ExchangeStats exchange_particles(const Species<FP...>& sp, const DomainInfo<Real, Dim, CommT>& domain) {
  ExchangeStats total;
  sp.for_each_species([&](auto& ps, std::size_t) {
    const ExchangeStats s = exchange_particles(ps.vector(), domain);
    total.sent += s.sent, total.received += s.received, total.wrapped += s.wrapped;
  });
  return total;
}

}  // namespace pik
