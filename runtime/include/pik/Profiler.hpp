/// \file Profiler.hpp
/// \brief Wall-clock timers with named regions, accumulated over calls (FDPS's TimeProfile).
#pragma once

#include <chrono>
#include <cstddef>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

namespace pik {

/// Seconds since an arbitrary epoch, from a monotonic clock.
inline double wall_time() {
  using clock = std::chrono::steady_clock;
  return std::chrono::duration<double>(clock::now().time_since_epoch()).count();
}

/// Accumulates seconds per named region, in first-use order. Regions are few (a
/// dozen), so a linear search by name is cheaper than a map and keeps the order.
class Profiler {
 public:
  struct Region {
    std::string name;
    double seconds = 0;
    long calls = 0;
  };

  /// RAII guard: adds the time from construction to destruction to a region.
  class Scope {
   public:
    Scope(Profiler& p, std::string_view name) : p_(p), name_(name), t0_(wall_time()) {}
    ~Scope() { p_.add(name_, wall_time() - t0_); }
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;

   private:
    Profiler& p_;
    std::string_view name_;
    double t0_;
  };

  Scope scope(std::string_view name) { return Scope(*this, name); }

  void add(std::string_view name, double seconds) {
    Region& r = region(name);
    r.seconds += seconds;
    ++r.calls;
  }
  /// Seconds accumulated in a region (0 if it never ran).
  double seconds(std::string_view name) const {
    for (const Region& r : regions_)
      if (r.name == name) return r.seconds;
    return 0;
  }
  double total() const {
    double s = 0;
    for (const Region& r : regions_) s += r.seconds;
    return s;
  }
  const std::vector<Region>& regions() const { return regions_; }
  void clear() { regions_.clear(); }

  friend std::ostream& operator<<(std::ostream& os, const Profiler& p) {
    for (const Region& r : p.regions_)
      os << r.name << ": " << r.seconds << " s in " << r.calls << " calls\n";
    return os;
  }

 private:
  Region& region(std::string_view name) {
    for (Region& r : regions_)
      if (r.name == name) return r;
    regions_.push_back({std::string(name), 0, 0});
    return regions_.back();
  }
  std::vector<Region> regions_;
};

}  // namespace pik
