/// \file Driver.hpp
/// \brief The run loop every SPH program shares: time steps up to the end time, output
///        times, the diagnostics log, snapshots, checkpoints with bit-for-bit restart and
///        the progress line. The physics is the model's.
///
/// A Model provides
///   - `particles()`: the pik::ParticleSystem; a particle has `id`, `mass` and the
///     Vec3<double> `pos`, `vel` (plus what Leapfrog.hpp needs);
///   - `compute()`: every pass at the current state (density, EOS, forces);
///   - `limits() const -> StepLimits`: the time-step criteria at the current state;
///   - `diagnostic_names() const` and `diagnostics() const`: the log columns after
///     step, time and dt (energies, the benchmark's figures of merit);
///   - `fill_snapshot(io::Snapshot&, bool checkpoint) const`: extra columns and
///     attributes (id, mass, pos, vel, time and step are the driver's). A checkpoint must
///     hold everything the next step reads (accelerations, rates, h, ...), so that a
///     restart continues bit for bit;
///   - `restore(const io::Snapshot&)`: the state from a checkpoint (refusing one written
///     with other physical parameters);
///   - optionally `report(double t, std::FILE*) const`, printed at every output time.
///
/// Files in `out/`: log.txt (one row per step, or every RunParams::log_every steps), snap_NNNN.<ext> (RunParams::snapshots
/// outputs evenly in time plus the initial state; or snap_final.<ext> only),
/// checkpoint.pbin (every `checkpoint_every` steps and at the end).
///
/// Under MPI (a model that defines `const pik::Comm& comm() const`, see Parallel.hpp):
/// every rank runs the loop with the same global step (each criterion's minimum over
/// ranks); the model's diagnostics() and report() are called on every rank (they may
/// reduce) and must return global values; log, progress line and reports appear on
/// rank 0 only; snapshots and checkpoints are gathered into one file in id order (the
/// layout of a single-process run); a restart reads such a file (or a single-process
/// one) on any number of ranks, each rank getting the equal share
/// pik::sph::equal_share(N, rank, ranks) in file order: the model's particles() must
/// hold that share of its initial state, in id order, when run() starts. A model
/// without comm() runs exactly as before.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <pik/Error.hpp>
#include <pik/io/Checkpoint.hpp>
#include <pik/io/DiagnosticsLog.hpp>
#include <pik/io/ParallelCheckpoint.hpp>
#include <pik/io/Progress.hpp>
#include <pik/io/SnapshotIo.hpp>
#include <pik/sph/Leapfrog.hpp>
#include <pik/sph/Parallel.hpp>
#include <pik/sph/TimeStep.hpp>

namespace pik::sph {

struct RunParams {
  double t_end = 1;
  int snapshots = 0;           ///< outputs evenly in time (and the initial state); 0: only the final state
  std::string out = "out";     ///< output directory
  long max_steps = 0;          ///< stop after this many steps in all (0: no limit)
  long checkpoint_every = 0;   ///< steps between checkpoints (0: only at the end)
  /// a log row every this many steps (and at every output, checkpoint and the last step);
  /// 1: every step. For runs of millions of steps, whose every-step log would take GBs.
  long log_every = 1;
  io::Format format = io::Format::binary;
  std::string restart;         ///< checkpoint to resume from ("" : a new run)
  double progress_interval_s = 10;
};

template <class Model>
class Driver {
 public:
  Driver(Model& m, RunParams p) : m_(m), p_(std::move(p)) {
    if (!(p_.t_end > 0) || !std::isfinite(p_.t_end)) throw Error("the end time must be positive and finite");
    if (p_.snapshots < 0 || p_.max_steps < 0 || p_.checkpoint_every < 0)
      throw Error("snapshot count, step limit and checkpoint interval must not be negative");
    if (p_.log_every < 1) throw Error("the log interval must be at least one step");
  }

  double time() const { return t_; }
  long steps() const { return step_; }
  /// The criterion that limited the last step, and its dt.
  const std::string& limiter() const { return limiter_; }
  double last_dt() const { return dt_; }
  /// Seconds of wall-clock time in run().
  double seconds() const { return seconds_; }
  /// The simulated time run() started from (0, or the checkpoint's).
  double start_time() const { return t_start_; }

  /// Runs from the initial state (or the checkpoint) to t_end or max_steps.
  void run() {
    const auto wall0 = std::chrono::steady_clock::now();
    if (root()) std::filesystem::create_directories(p_.out);
    if constexpr (parallel) m_.comm().barrier();
    std::vector<std::string> cols = {"step", "time", "dt"};
    for (auto& n : m_.diagnostic_names()) cols.push_back(n);
    if (!p_.restart.empty()) {
      const io::Snapshot s = read_restart();
      load(s);
      m_.restore(s);
      t_ = s.time, step_ = long(s.step), next_out_ = int(s.attr.get_int("sph.next_output"));
      if (t_ >= p_.t_end) throw Error("the checkpoint's time " + std::to_string(t_) + " is not before --t-end");
      if (root()) log_ = io::DiagnosticsLog(p_.out + "/log.txt", cols, step_);
    } else {
      m_.compute();
      if (root()) log_ = io::DiagnosticsLog(p_.out + "/log.txt", cols);
      row(0);
      if (p_.snapshots > 0) output();
    }
    const double t_start = t_;
    t_start_ = t_;
    Clock::time_point progress_clock = Clock::now();
    while (t_ < p_.t_end * (1 - 1e-12)) {
      if (p_.max_steps && step_ >= p_.max_steps) break;
      StepLimits lim = m_.limits();
      if constexpr (parallel) lim = global_limits(lim, m_.comm());
      const double next = p_.snapshots > 0 ? p_.t_end * next_out_ / p_.snapshots : p_.t_end;
      double dt = lim.dt();
      if (!(dt > 0) || !std::isfinite(dt))
        throw Error("time step " + std::to_string(dt) + " from the '" + lim.limiter() + "' criterion at t = " +
                    std::to_string(t_) + " (the run has blown up)");
      limiter_ = lim.limiter();
      dt = std::min({dt, p_.t_end - t_, std::max(next - t_, 1e-12)});
      kdk_step(m_, dt);
      t_ += dt, ++step_, dt_ = dt;
      const bool out_now = p_.snapshots > 0 && t_ >= next * (1 - 1e-12);
      const bool check_now = p_.checkpoint_every && step_ % p_.checkpoint_every == 0;
      const bool last = t_ >= p_.t_end * (1 - 1e-12) || (p_.max_steps && step_ >= p_.max_steps);
      if (step_ % p_.log_every == 0 || out_now || check_now || last) row(dt);
      if (out_now) output();
      if (check_now) checkpoint();
      progress(progress_clock, t_start, wall0);
    }
    if (p_.snapshots == 0) write(p_.out + "/snap_final" + io::extension(p_.format), false);
    checkpoint();
    seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  }

 private:
  using Clock = std::chrono::steady_clock;
  static constexpr bool parallel = ParallelModel<Model>;

  /// Rank 0 (or the only process) writes the log, the files and the progress line.
  bool root() const {
    if constexpr (parallel) return m_.comm().rank() == 0;
    else return true;
  }

  void row(double dt) {
    std::vector<double> r = {double(step_), t_, dt};
    for (double v : m_.diagnostics()) r.push_back(v);
    if (root()) log_.row(r);
  }

  io::Snapshot read_restart() const {
    if constexpr (parallel) return io::read_checkpoint_parallel(p_.restart, m_.comm(), {}, {"sph.next_output"}).state;
    else return io::read_checkpoint(p_.restart, {}, {"sph.next_output"});
  }

  io::Snapshot snapshot(bool checkpoint) const {
    io::Snapshot s;
    const auto& ps = m_.particles();
    s.time = t_, s.step = std::uint64_t(step_);
    s.resize(ps.size());
    for (std::size_t i = 0; i < ps.size(); ++i) {
      const auto& q = ps[i];
      s.id[i] = q.id, s.mass[i] = q.mass, s.pos[i] = q.pos, s.vel[i] = q.vel;
    }
    m_.fill_snapshot(s, checkpoint);
    s.attr.set("sph.next_output", std::int64_t(next_out_));
    return s;
  }

  void write(const std::string& path, bool checkpoint) const {
    if constexpr (parallel) {
      const io::Snapshot all = gather_snapshot(snapshot(checkpoint), m_.comm());
      io::parallel_detail::collectively(m_.comm(), path, [&] {
        if (!root()) return;
        if (checkpoint) io::write_checkpoint(path, all);
        else io::write_snapshot(path, all, p_.format);
      });
    } else {
      if (checkpoint) io::write_checkpoint(path, snapshot(true));
      else io::write_snapshot(path, snapshot(false), p_.format);
    }
  }

  /// Where the reports of ranks other than 0 go.
  static std::FILE* null_file() {
    static std::FILE* f = std::fopen("/dev/null", "w");
    return f;
  }

  void output() {
    char name[32];
    std::snprintf(name, sizeof name, "/snap_%04d", next_out_++);
    write(p_.out + name + io::extension(p_.format), false);
    if constexpr (requires(const Model& c) { c.report(0.0, stdout); }) {
      m_.report(t_, root() ? stdout : null_file());
    }
  }

  void checkpoint() const { write(p_.out + "/checkpoint.pbin", true); }

  /// Restores ids, masses, positions and velocities in the checkpoint's order.
  void load(const io::Snapshot& s) {
    auto& ps = m_.particles();
    bool mismatch = s.size() != ps.size();
    std::size_t n_file = s.size(), n_run = ps.size();
    if constexpr (parallel) {
      mismatch = m_.comm().max(int(mismatch)) != 0;
      n_file = m_.comm().sum(n_file), n_run = m_.comm().sum(n_run);
    }
    if (mismatch)
      throw Error(p_.restart + ": the checkpoint has " + std::to_string(n_file) +
                  " particles, this run's setup " + std::to_string(n_run) + " (other problem or resolution?)");
    for (std::size_t i = 0; i < ps.size(); ++i) {
      auto& q = ps[i];
      q.id = decltype(q.id)(s.id[i]), q.mass = s.mass[i], q.pos = s.pos[i], q.vel = s.vel[i];
    }
  }

  /// One line every progress_interval_s: step, time, dt and its limiter, ETA from the
  /// simulated time done so far.
  void progress(Clock::time_point& last, double t_start, Clock::time_point wall0) {
    if (!root()) return;
    const auto now = Clock::now();
    const bool final = t_ >= p_.t_end * (1 - 1e-12);
    if (!final && std::chrono::duration<double>(now - last).count() < p_.progress_interval_s) return;
    last = now;
    const double elapsed = std::chrono::duration<double>(now - wall0).count();
    const double frac = (t_ - t_start) / (p_.t_end - t_start);
    const double eta = frac > 0 ? elapsed * (1 - frac) / frac : NAN;
    std::printf("step %ld  t %-10.5g (%5.1f %%)  dt %-9.3g (%s)  elapsed %s  ETA %s\n", step_, t_,
                100 * t_ / p_.t_end, dt_, limiter_.c_str(), io::format_duration(elapsed).c_str(),
                io::format_duration(final ? 0.0 : eta).c_str());
    std::fflush(stdout);
  }

  Model& m_;
  RunParams p_;
  io::DiagnosticsLog log_;
  double t_ = 0, dt_ = 0, seconds_ = 0, t_start_ = 0;
  long step_ = 0;
  int next_out_ = 0;
  std::string limiter_ = "none";
};

}  // namespace pik::sph
