/// \file Leapfrog.hpp
/// \brief The kick-drift-kick leapfrog of the SPH programs, with hooks for the variables a
///        scheme integrates beside v and u (pseudo-density, density perturbation, walls).
///
/// One step of size dt (Springel 2005, sec. 4): v_{1/2} = v + a dt/2, u_{1/2} = u + du/dt dt/2,
/// x += v_{1/2} dt; v and u are predicted to the end of the drift (v_{1/2} + a dt/2) for the
/// force evaluation; then every pass runs (`model.compute()`) and the closing half kick
/// gives v = v_{1/2} + a' dt/2, u = u_{1/2} + du/dt' dt/2. u is kept above half its
/// half-step value, so a too-large cooling rate cannot make it negative.
#pragma once

#include <algorithm>
#include <concepts>
#include <cstddef>
#include <type_traits>

#include <pik/detail/Threads.hpp>

namespace pik::sph {

/// The opening half: half kick, drift, prediction to the end of the step.
template <class P>
void open_step(P& p, double dt) {
  p.vel_half = p.vel + p.acc * (0.5 * dt), p.u_half = p.u + 0.5 * dt * p.dudt;
  p.pos += p.vel_half * dt;
  p.vel = p.vel_half + p.acc * (0.5 * dt), p.u = std::max(p.u_half + 0.5 * dt * p.dudt, 0.5 * p.u_half);
}

/// The closing half kick with the new rates.
template <class P>
void close_step(P& p, double dt) {
  p.vel = p.vel_half + p.acc * (0.5 * dt);
  p.u = std::max(p.u_half + 0.5 * dt * p.dudt, 0.5 * p.u_half);
}

/// One kick-drift-kick step of the model. A model that integrates more than (x, v, u),
/// or holds some particles fixed, defines `open_step(P&, dt)` and/or `close_step(P&, dt)`
/// members (usually calling the free functions above, then its own updates); otherwise the
/// free functions are used. The per-particle halves run on the threads where they touch
/// only their particle: the free functions and `const` members (a non-const member runs
/// the particles in order on one thread); the result is the same on any number of threads.
///
/// A model that integrates the step itself (block time steps: each particle on its own
/// power-of-two fraction of dt, every particle synchronised again at the end of dt; or
/// a slow force on a longer step than the others) defines `bool advance(double dt)`: true
/// when it has done the step, false for this KDK. Its own steps may call kdk().
template <class Model>
void kdk(Model& m, double dt);

template <class Model>
void kdk_step(Model& m, double dt) {
  if constexpr (requires { { m.advance(dt) } -> std::convertible_to<bool>; }) {
    if (m.advance(dt)) return;
  }
  kdk(m, dt);
}

/// The kick-drift-kick of kdk_step without the `advance` hook.
template <class Model>
void kdk(Model& m, double dt) {
  auto& ps = m.particles();
  using P = std::remove_reference_t<decltype(*ps.begin())>;
  // (read again for each half: compute() may move particles between processes)
  auto each = [&](auto&& half, bool threads) {
    const std::ptrdiff_t n = std::ptrdiff_t(ps.size());
    auto it = ps.begin();
    if (threads) detail::parallel_for_throwing(n, [&](std::ptrdiff_t i) { half(it[i]); });
    else for (std::ptrdiff_t i = 0; i < n; ++i) half(it[i]);
  };
  constexpr bool open_member = requires(P& p) { m.open_step(p, dt); };
  constexpr bool open_const = requires(const Model& cm, P& p) { cm.open_step(p, dt); };
  each([&](P& p) {
    if constexpr (open_member) m.open_step(p, dt);
    else open_step(p, dt);
  }, !open_member || open_const);
  m.compute();
  constexpr bool close_member = requires(P& p) { m.close_step(p, dt); };
  constexpr bool close_const = requires(const Model& cm, P& p) { cm.close_step(p, dt); };
  each([&](P& p) {
    if constexpr (close_member) m.close_step(p, dt);
    else close_step(p, dt);
  }, !close_member || close_const);
}

}  // namespace pik::sph
