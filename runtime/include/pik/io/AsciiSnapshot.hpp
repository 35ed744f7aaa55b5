/// \file AsciiSnapshot.hpp
/// \brief The ASCII snapshot format (".txt"): one particle per line, readable by
///        numpy.loadtxt, gnuplot and people; written atomically.
///
/// ```
/// # pik ascii snapshot 1
/// # time 0.125
/// # step 32
/// # particles 4096 total 4096 first 0 part 0 of 1
/// # attr KEY VALUE            (zero or more; VALUE runs to the end of the line)
/// # columns id mass x y z vx vy vz [NAME or NAME.x NAME.y NAME.z ...]
/// 0 2.44140625e-04 ...        (one line per particle, 17 significant digits)
/// # end
/// ```
/// Doubles carry 17 significant digits, so a round trip is exact. A file without its
/// `# end` line, with the wrong number of lines or columns, or with a token that is not
/// a number is refused with the line number.
#pragma once

#include <cerrno>
#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <iterator>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "pik/io/AtomicFile.hpp"
#include "pik/io/IoError.hpp"
#include "pik/io/Snapshot.hpp"

namespace pik::io {

inline constexpr const char* ascii_magic_line = "# pik ascii snapshot 1";

/// Writes `snap` to `path` as text, atomically.
inline void write_ascii(const std::string& path, const Snapshot& snap) {
  snap.validate(path);
  std::string out;
  out.reserve(256 + snap.size() * 200);
  auto num = [&](double v) { fmt::format_to(std::back_inserter(out), " {:.17g}", v); };
  out += ascii_magic_line;
  out += "\n# time";
  num(snap.time);
  out += "\n# step " + std::to_string(snap.step) + "\n";
  out += "# particles " + std::to_string(snap.size()) + " total " + std::to_string(snap.total()) +
         " first " + std::to_string(snap.first_index) + " part " + std::to_string(snap.part) +
         " of " + std::to_string(snap.n_parts) + "\n";
  for (const auto& [k, v] : snap.attr.all()) {
    if (k.find(' ') != std::string::npos)
      throw IoError(path, "attribute name '" + k + "' contains a blank (not allowed in ASCII)");
    out += "# attr " + k + " " + v + "\n";
  }
  out += "# columns id mass x y z vx vy vz";
  for (const auto& c : snap.extra) {
    if (c.components == 1) out += " " + c.name;
    else out += " " + c.name + ".x " + c.name + ".y " + c.name + ".z";
  }
  out += "\n";
  AtomicFile file(path);
  for (std::size_t i = 0; i < snap.size(); ++i) {
    out += std::to_string(snap.id[i]);
    num(snap.mass[i]);
    num(snap.pos[i].x), num(snap.pos[i].y), num(snap.pos[i].z);
    num(snap.vel[i].x), num(snap.vel[i].y), num(snap.vel[i].z);
    for (const auto& c : snap.extra)
      for (int k = 0; k < c.components; ++k) num(c.data[i * c.components + k]);
    out += "\n";
    if (out.size() > (1u << 22)) {
      file.write(out);
      out.clear();
    }
  }
  out += "# end\n";
  file.write(out);
  file.commit();
}

/// Reads an ASCII snapshot; throws IoError with "file:line: problem" on bad input.
inline Snapshot read_ascii(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw IoError(path, "cannot open: " + detail::errno_text(errno));
  std::string line;
  std::size_t lineno = 0;
  auto fail = [&](const std::string& what) -> IoError {
    return IoError(path + ":" + std::to_string(lineno), what);
  };
  auto next = [&](const char* what) {
    ++lineno;
    if (!std::getline(in, line)) throw fail(std::string("truncated: expected ") + what);
  };
  auto starts = [&](const char* prefix) { return line.rfind(prefix, 0) == 0; };
  auto to_double = [&](const std::string& tok) {
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(tok.c_str(), &end);
    if (tok.empty() || *end != '\0') throw fail("'" + tok + "' is not a number");
    return v;
  };
  auto to_u64 = [&](const std::string& tok) {
    char* end = nullptr;
    errno = 0;
    const unsigned long long v = std::strtoull(tok.c_str(), &end, 10);
    if (tok.empty() || *end != '\0' || tok[0] == '-' || errno == ERANGE)
      throw fail("'" + tok + "' is not an unsigned integer");
    return std::uint64_t(v);
  };

  Snapshot s;
  next("the header line");
  if (line != ascii_magic_line) throw fail("not a pik ASCII snapshot (first line is not '" +
                                           std::string(ascii_magic_line) + "')");
  next("'# time'");
  if (!starts("# time ")) throw fail("expected '# time T'");
  s.time = to_double(line.substr(7));
  next("'# step'");
  if (!starts("# step ")) throw fail("expected '# step S'");
  s.step = to_u64(line.substr(7));
  next("'# particles'");
  {
    std::istringstream ss(line);
    std::string hash, w1, n, w2, total, w3, first, w4, part, w5, nparts, rest;
    ss >> hash >> w1 >> n >> w2 >> total >> w3 >> first >> w4 >> part >> w5 >> nparts;
    if (hash != "#" || w1 != "particles" || w2 != "total" || w3 != "first" || w4 != "part" ||
        w5 != "of" || (ss >> rest))
      throw fail("expected '# particles N total T first F part P of Q'");
    const std::uint64_t count = to_u64(n);
    s.n_total = to_u64(total);
    s.first_index = to_u64(first);
    s.part = std::uint32_t(to_u64(part));
    s.n_parts = std::uint32_t(to_u64(nparts));
    if (count > (std::uint64_t(1) << 40)) throw fail("implausible particle count " + n);
    s.resize(count);
  }
  next("'# columns'");
  while (starts("# attr ")) {
    const auto sp = line.find(' ', 7);
    if (sp == std::string::npos) throw fail("expected '# attr NAME VALUE'");
    s.attr.set(line.substr(7, sp - 7), line.substr(sp + 1));
    next("'# columns'");
  }
  if (!starts("# columns ")) throw fail("expected '# columns ...'");
  std::vector<std::string> cols;
  {
    std::istringstream ss(line.substr(10));
    for (std::string c; ss >> c;) cols.push_back(c);
  }
  static const char* const core[8] = {"id", "mass", "x", "y", "z", "vx", "vy", "vz"};
  if (cols.size() < 8) throw fail("the first 8 columns must be: id mass x y z vx vy vz");
  for (int k = 0; k < 8; ++k)
    if (cols[k] != core[k]) throw fail("the first 8 columns must be: id mass x y z vx vy vz");
  for (std::size_t k = 8; k < cols.size();) {
    const std::string& c = cols[k];
    if (c.size() > 2 && c.compare(c.size() - 2, 2, ".x") == 0) {
      const std::string base = c.substr(0, c.size() - 2);
      if (k + 2 >= cols.size() || cols[k + 1] != base + ".y" || cols[k + 2] != base + ".z")
        throw fail("column '" + c + "' must be followed by " + base + ".y " + base + ".z");
      if (s.find(base)) throw fail("column '" + base + "' appears twice");
      s.column(base, 3);
      k += 3;
    } else {
      if (s.find(c)) throw fail("column '" + c + "' appears twice");
      s.column(c, 1);
      k += 1;
    }
  }

  std::vector<std::string> tok;
  tok.reserve(cols.size() + 1);
  for (std::size_t i = 0; i < s.size(); ++i) {
    next(("particle line " + std::to_string(i + 1) + " of " + std::to_string(s.size())).c_str());
    if (starts("#"))
      throw fail("truncated: found '" + line + "' after " + std::to_string(i) + " of " +
                 std::to_string(s.size()) + " particles");
    tok.clear();
    std::istringstream ss(line);
    for (std::string t; ss >> t;) tok.push_back(std::move(t));
    if (tok.size() != cols.size())
      throw fail("expected " + std::to_string(cols.size()) + " columns, found " +
                 std::to_string(tok.size()));
    s.id[i] = to_u64(tok[0]);
    s.mass[i] = to_double(tok[1]);
    s.pos[i] = {to_double(tok[2]), to_double(tok[3]), to_double(tok[4])};
    s.vel[i] = {to_double(tok[5]), to_double(tok[6]), to_double(tok[7])};
    std::size_t k = 8;
    for (auto& c : s.extra)
      for (int d = 0; d < c.components; ++d) c.data[i * c.components + d] = to_double(tok[k++]);
  }
  next("'# end'");
  if (line != "# end") throw fail("expected '# end' after " + std::to_string(s.size()) + " particles");
  while (std::getline(in, line)) {
    ++lineno;
    if (!line.empty()) throw fail("unexpected text after '# end'");
  }
  s.validate(path);
  return s;
}

}  // namespace pik::io
