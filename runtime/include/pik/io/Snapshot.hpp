/// \file Snapshot.hpp
/// \brief A set of particles as stored on disk: ids, masses, positions, velocities,
///        optional extra columns, the simulation time and step, and key/value
///        attributes (run parameters, provenance).
///
/// A Snapshot is the neutral exchange type between initial-condition generators,
/// files in every format (ASCII, pik binary, HDF5) and a program's own particle
/// type. It may hold one part of a larger snapshot: `first_index`/`n_total` place it
/// in the global particle sequence and `part`/`n_parts` name the file among the
/// per-rank files of one output (see part_path()).
#pragma once

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "pik/Vec.hpp"
#include "pik/io/IoError.hpp"

namespace pik::io {

/// An extra per-particle column of doubles with 1 (scalar) or 3 (vector) components,
/// e.g. {"Acceleration", 3} or {"Potential", 1}. `data` holds size()*components values.
struct Column {
  std::string name;
  int components = 1;
  std::vector<double> data;
};

/// Key/value text attributes. Doubles are stored with 17 significant digits, which
/// reads back to the identical double, so run parameters survive a restart exactly.
class Attributes {
 public:
  void set(const std::string& key, const std::string& value) {
    check_text(key, "attribute name");
    if (key.empty()) throw IoError("<attributes>", "empty attribute name");
    check_text(value, "value of attribute '" + key + "'");
    map_[key] = value;
  }
  void set(const std::string& key, const char* value) { set(key, std::string(value)); }
  void set(const std::string& key, double value) {
    set(key, fmt::format("{:.17g}", value));
  }
  void set(const std::string& key, std::int64_t value) { set(key, std::to_string(value)); }
  void set(const std::string& key, std::uint64_t value) { set(key, std::to_string(value)); }
  void set(const std::string& key, int value) { set(key, std::int64_t(value)); }
  void set(const std::string& key, bool value) { set(key, std::string(value ? "true" : "false")); }

  bool has(const std::string& key) const { return map_.count(key) != 0; }
  const std::map<std::string, std::string>& all() const { return map_; }
  bool operator==(const Attributes&) const = default;

  const std::string& get_string(const std::string& key) const {
    const auto it = map_.find(key);
    if (it == map_.end()) throw IoError("<attributes>", "missing attribute '" + key + "'");
    return it->second;
  }
  double get_double(const std::string& key) const {
    const std::string& s = get_string(key);
    char* end = nullptr;
    const double v = std::strtod(s.c_str(), &end);
    if (s.empty() || *end != '\0')
      throw IoError("<attributes>", "attribute '" + key + "' = '" + s + "' is not a number");
    return v;
  }
  std::int64_t get_int(const std::string& key) const {
    const std::string& s = get_string(key);
    char* end = nullptr;
    const long long v = std::strtoll(s.c_str(), &end, 10);
    if (s.empty() || *end != '\0')
      throw IoError("<attributes>", "attribute '" + key + "' = '" + s + "' is not an integer");
    return v;
  }
  bool get_bool(const std::string& key) const {
    const std::string& s = get_string(key);
    if (s == "true") return true;
    if (s == "false") return false;
    throw IoError("<attributes>", "attribute '" + key + "' = '" + s + "' is not true/false");
  }

 private:
  // Tabs and newlines separate entries in the text encodings of every format.
  static void check_text(const std::string& s, const std::string& what) {
    for (char c : s)
      if (c == '\n' || c == '\r' || c == '\t' || c == '\0')
        throw IoError("<attributes>", what + " contains a tab, newline or NUL");
  }
  std::map<std::string, std::string> map_;
};

// Readers and writers move positions and velocities as flat arrays of doubles.
static_assert(sizeof(Vec3<double>) == 3 * sizeof(double), "Vec3<double> must be packed");

struct Snapshot {
  double time = 0.0;
  std::uint64_t step = 0;
  /// Particles in the whole output (all parts); 0 means "this part is everything".
  std::uint64_t n_total = 0;
  /// Global index of this part's first particle.
  std::uint64_t first_index = 0;
  std::uint32_t part = 0;
  std::uint32_t n_parts = 1;

  std::vector<std::uint64_t> id;
  std::vector<double> mass;
  std::vector<Vec3<double>> pos;
  std::vector<Vec3<double>> vel;
  std::vector<Column> extra;
  Attributes attr;

  std::size_t size() const { return id.size(); }

  /// Resizes every per-particle array (extra columns included).
  void resize(std::size_t n) {
    id.resize(n);
    mass.resize(n);
    pos.resize(n);
    vel.resize(n);
    for (auto& c : extra) c.data.resize(n * std::size_t(c.components));
  }

  /// Adds (or returns the existing) extra column `name`, sized to the particles.
  Column& column(const std::string& name, int components) {
    for (auto& c : extra) {
      if (c.name == name) {
        if (c.components != components)
          throw IoError("<snapshot>", "column '" + name + "' exists with " +
                                          std::to_string(c.components) + " components, not " +
                                          std::to_string(components));
        return c;
      }
    }
    if (components != 1 && components != 3)
      throw IoError("<snapshot>", "column '" + name + "': components must be 1 or 3");
    extra.push_back({name, components, std::vector<double>(size() * std::size_t(components))});
    return extra.back();
  }
  /// The extra column `name`, or nullptr.
  const Column* find(const std::string& name) const {
    for (const auto& c : extra)
      if (c.name == name) return &c;
    return nullptr;
  }

  /// Particles in the whole output.
  std::uint64_t total() const { return n_total ? n_total : size(); }

  /// Throws (naming `where`) if the arrays disagree in length or the header is
  /// inconsistent; every writer calls it first, every reader last.
  void validate(const std::string& where) const {
    const std::size_t n = size();
    if (mass.size() != n || pos.size() != n || vel.size() != n)
      throw IoError(where, "particle arrays differ in length (id " + std::to_string(n) +
                               ", mass " + std::to_string(mass.size()) + ", pos " +
                               std::to_string(pos.size()) + ", vel " +
                               std::to_string(vel.size()) + ")");
    for (const auto& c : extra) {
      if (c.components != 1 && c.components != 3)
        throw IoError(where, "column '" + c.name + "' has " + std::to_string(c.components) +
                                 " components (1 or 3 allowed)");
      if (c.data.size() != n * std::size_t(c.components))
        throw IoError(where, "column '" + c.name + "' has " + std::to_string(c.data.size()) +
                                 " values for " + std::to_string(n) + " particles");
      if (c.name.empty() || c.name.size() > 31)
        throw IoError(where, "column name '" + c.name + "' must have 1 to 31 characters");
      for (char ch : c.name)
        if (ch <= ' ' || ch > '~')
          throw IoError(where, "column name '" + c.name + "' has a blank or non-ASCII character");
    }
    if (n_parts == 0 || part >= n_parts)
      throw IoError(where, "part " + std::to_string(part) + " of " + std::to_string(n_parts));
    if (n_total != 0 && first_index + n > n_total)
      throw IoError(where, "particles " + std::to_string(first_index) + ".." +
                               std::to_string(first_index + n) + " exceed the total " +
                               std::to_string(n_total));
  }
};

/// The file name of part `part` out of `n_parts` for an output named `path`: `path`
/// itself when there is one part, else `stem.<part>.ext` ("snap_0003.2.pbin"), the
/// convention of GADGET-style multi-file snapshots. Each MPI rank writes and reads
/// its own part.
inline std::string part_path(const std::string& path, std::uint32_t part, std::uint32_t n_parts) {
  if (n_parts <= 1) return path;
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  const std::string idx = std::to_string(part);
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash) || dot == slash + 1)
    return path + "." + idx;
  return path.substr(0, dot) + "." + idx + path.substr(dot);
}

/// Two snapshots hold the same particles and header bit for bit (NaNs compare by bits).
inline bool same_bits(const Snapshot& a, const Snapshot& b) {
  auto eq = [](const auto& x, const auto& y) {
    return x.size() == y.size() &&
           (x.empty() || std::memcmp(x.data(), y.data(), x.size() * sizeof(x[0])) == 0);
  };
  if (std::memcmp(&a.time, &b.time, sizeof(double)) != 0 || a.step != b.step ||
      a.total() != b.total() || a.first_index != b.first_index || a.part != b.part ||
      a.n_parts != b.n_parts || !(a.attr == b.attr))
    return false;
  if (!eq(a.id, b.id) || !eq(a.mass, b.mass) || !eq(a.pos, b.pos) || !eq(a.vel, b.vel))
    return false;
  if (a.extra.size() != b.extra.size()) return false;
  for (std::size_t i = 0; i < a.extra.size(); ++i)
    if (a.extra[i].name != b.extra[i].name || a.extra[i].components != b.extra[i].components ||
        !eq(a.extra[i].data, b.extra[i].data))
      return false;
  return true;
}

}  // namespace pik::io
