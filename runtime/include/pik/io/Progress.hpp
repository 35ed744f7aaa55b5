/// \file Progress.hpp
/// \brief A live progress line for long runs: step, time, |dE/E|, interactions/s, ETA.
///
/// On a terminal the line is redrawn in place with '\r' at most ten times a second;
/// into a file or pipe (a batch job's log) it prints plain lines at a fixed interval
/// instead, so logs stay readable and small.
#pragma once

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>

#include <fmt/format.h>

namespace pik::io {

/// "1:02:03", "4:05" or "--:--" (unknown).
inline std::string format_duration(double seconds) {
  if (!(seconds >= 0) || !std::isfinite(seconds)) return "--:--";
  const auto s = static_cast<long long>(std::llround(seconds));
  if (s >= 3600) return fmt::format("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60);
  return fmt::format("{}:{:02}", s / 60, s % 60);
}

class Progress {
 public:
  using clock = std::chrono::steady_clock;

  /// Steps run from `first_step` (exclusive; where the run starts or resumes) to
  /// `last_step`. `log_interval_s` is the spacing of plain lines when `out` is not a
  /// terminal; `interactive` forces the terminal (1) or log (0) style, -1 detects it.
  Progress(std::uint64_t first_step, std::uint64_t last_step, std::FILE* out = stdout,
           double log_interval_s = 10.0, int interactive = -1)
      : first_(first_step),
        last_(last_step),
        out_(out),
        tty_(interactive < 0 ? ::isatty(::fileno(out)) != 0 : interactive != 0),
        log_interval_(log_interval_s),
        start_(clock::now()),
        last_draw_(start_) {}

  bool interactive() const { return tty_; }

  /// Reports that `step` is done at simulation `time`. `rel_energy_error` is |dE/E|
  /// (NaN if not known this step), `interactions_per_s` the measured force rate.
  void update(std::uint64_t step, double time, double rel_energy_error, double interactions_per_s) {
    const auto now = clock::now();
    if (std::isfinite(rel_energy_error)) de_ = rel_energy_error;
    const bool final = step >= last_;
    const double since = std::chrono::duration<double>(now - last_draw_).count();
    if (tty_) {
      if (!final && since < 0.1 && drawn_) return;
    } else if (!final && drawn_ && since < log_interval_) {
      return;
    }
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    const double done = double(step - first_);
    const double eta = done > 0 ? elapsed / done * double(last_ - step) : NAN;
    const int digits = int(std::to_string(last_).size());
    const std::string line =
        fmt::format("step {:>{}}/{}  t {:<10.5g}  |dE/E| {:<9.2e}  {:8.3g} int/s  elapsed {}  ETA {}", step,
                    digits, last_, time, de_, interactions_per_s, format_duration(elapsed),
                    format_duration(final ? 0.0 : eta));
    if (tty_) {
      // Pad with blanks so a shorter line fully covers the previous one.
      width_ = std::max(width_, line.size());
      fmt::print(out_, "\r{:<{}}", line, width_);
    } else {
      fmt::print(out_, "{}\n", line);
    }
    drawn_ = true;
    last_draw_ = now;
    if (final) finish();
    std::fflush(out_);
  }

  /// Ends the terminal line if the run stopped before `last_step` (Ctrl-C, error).
  void finish() {
    if (tty_ && drawn_) {
      std::fputc('\n', out_);
      std::fflush(out_);
      drawn_ = false;
    }
  }

 private:
  std::uint64_t first_, last_;
  std::FILE* out_;
  bool tty_;
  double log_interval_;
  clock::time_point start_, last_draw_;
  double de_ = NAN;
  bool drawn_ = false;
  std::size_t width_ = 0;
};

}  // namespace pik::io
