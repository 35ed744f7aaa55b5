/// \file SnapshotIo.hpp
/// \brief One entry point for every snapshot format: choose a format by name, write,
///        read with the format detected from the file's first bytes, and gather the
///        per-rank parts of one output.
#pragma once

#include <sys/stat.h>

#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <memory>
#include <string>

#include "pik/io/AsciiSnapshot.hpp"
#include "pik/io/BinarySnapshot.hpp"
#include "pik/io/IoError.hpp"
#include "pik/io/Snapshot.hpp"
#if defined(PIK_HAVE_HDF5) && PIK_HAVE_HDF5
#include "pik/io/Hdf5Snapshot.hpp"
#endif

namespace pik::io {

enum class Format { ascii, binary, hdf5 };

/// Is HDF5 compiled into this program?
inline constexpr bool have_hdf5 =
#if defined(PIK_HAVE_HDF5) && PIK_HAVE_HDF5
    true;
#else
    false;
#endif

/// "ascii" | "binary" | "hdf5" -> Format; throws std::invalid_argument otherwise
/// (also for "hdf5" when the program was built without HDF5).
inline Format format_from_name(const std::string& name) {
  if (name == "ascii") return Format::ascii;
  if (name == "binary") return Format::binary;
  if (name == "hdf5") {
    if (!have_hdf5)
      throw std::invalid_argument("format 'hdf5' is not available: built without HDF5 "
                                  "(install libhdf5-dev and reconfigure)");
    return Format::hdf5;
  }
  throw std::invalid_argument("unknown snapshot format '" + name + "' (ascii, binary" +
                              std::string(have_hdf5 ? ", hdf5" : "") + ")");
}

inline const char* format_name(Format f) {
  switch (f) {
    case Format::ascii: return "ascii";
    case Format::binary: return "binary";
    case Format::hdf5: return "hdf5";
  }
  return "?";
}

/// The usual file extension of a format, with the dot.
inline const char* extension(Format f) {
  switch (f) {
    case Format::ascii: return ".txt";
    case Format::binary: return ".pbin";
    case Format::hdf5: return ".hdf5";
  }
  return "";
}

/// Writes `snap` to `path` in `format`, atomically.
inline void write_snapshot(const std::string& path, const Snapshot& snap, Format format) {
  switch (format) {
    case Format::ascii: write_ascii(path, snap); return;
    case Format::binary: write_binary(path, snap); return;
    case Format::hdf5:
#if defined(PIK_HAVE_HDF5) && PIK_HAVE_HDF5
      write_hdf5(path, snap);
      return;
#else
      throw IoError(path, "cannot write HDF5: built without HDF5");
#endif
  }
}

/// The format of the file at `path`, from its first bytes.
inline Format detect_format(const std::string& path) {
  // fopen succeeds on a directory and fread then fails: say what it is instead.
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode))
    throw IoError(path, "is a directory, not a snapshot file");
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) throw IoError(path, "cannot open: " + detail::errno_text(errno));
  unsigned char head[24] = {};
  const std::size_t n = std::fread(head, 1, sizeof head, f.get());
  if (looks_binary(head, n)) return Format::binary;
  if (n >= 8 && std::memcmp(head, "\x89HDF\r\n\x1a\n", 8) == 0) return Format::hdf5;
  // Text starting with '#': read_ascii checks the rest of the first line.
  if (n > 0 && head[0] == '#') return Format::ascii;
  if (n == 0) throw IoError(path, "empty file, not a snapshot");
  throw IoError(path, "not a pik snapshot (unknown magic number: neither pik binary, HDF5 nor pik ASCII)");
}

/// Reads one snapshot file of any format.
inline Snapshot read_snapshot(const std::string& path) {
  switch (detect_format(path)) {
    case Format::ascii: return read_ascii(path);
    case Format::binary: return read_binary(path);
    case Format::hdf5:
#if defined(PIK_HAVE_HDF5) && PIK_HAVE_HDF5
      return read_hdf5(path);
#else
      throw IoError(path, "is an HDF5 file, but this program was built without HDF5");
#endif
  }
  throw IoError(path, "unknown format");
}

/// Writes this rank's part of an output: `snap.part`/`snap.n_parts` choose the file
/// name (see part_path()); `snap.first_index` and `snap.n_total` place the particles.
inline void write_snapshot_part(const std::string& path, const Snapshot& snap, Format format) {
  write_snapshot(part_path(path, snap.part, snap.n_parts), snap, format);
}

/// The file that holds part 0 of the output `path`: `path` itself when it exists,
/// else its first per-rank part; when neither exists, an error naming both.
inline std::string first_part_file(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) return path;
  const std::string part0 = part_path(path, 0, 2);
  if (::stat(part0.c_str(), &st) == 0) return part0;
  throw IoError(path, "cannot open: no such file (nor a per-rank part " + part0 + ")");
}

/// Reads every part of an output written by write_snapshot_part (or a single file)
/// and concatenates them in global index order. Checks that the parts agree on the
/// header and cover 0..n_total exactly once.
inline Snapshot read_snapshot_parts(const std::string& path) {
  const std::string file0 = first_part_file(path);
  const bool single = file0 == path;
  Snapshot all = read_snapshot(file0);
  if (single && all.n_parts == 1) return all;
  const std::uint32_t n_parts = all.n_parts;
  if (all.part != 0 || all.first_index != 0)
    throw IoError(part_path(path, 0, n_parts), "expected part 0 starting at particle 0");
  for (std::uint32_t p = 1; p < n_parts; ++p) {
    const std::string file = part_path(path, p, n_parts);
    Snapshot s = read_snapshot(file);
    if (s.part != p || s.n_parts != n_parts || s.n_total != all.n_total || s.step != all.step ||
        std::memcmp(&s.time, &all.time, sizeof(double)) != 0)
      throw IoError(file, "header does not match part 0 (part, count, step or time)");
    if (s.first_index != all.size())
      throw IoError(file, "starts at particle " + std::to_string(s.first_index) + ", expected " +
                              std::to_string(all.size()));
    if (s.extra.size() != all.extra.size())
      throw IoError(file, "has different extra columns than part 0");
    all.id.insert(all.id.end(), s.id.begin(), s.id.end());
    all.mass.insert(all.mass.end(), s.mass.begin(), s.mass.end());
    all.pos.insert(all.pos.end(), s.pos.begin(), s.pos.end());
    all.vel.insert(all.vel.end(), s.vel.begin(), s.vel.end());
    for (std::size_t c = 0; c < s.extra.size(); ++c) {
      if (s.extra[c].name != all.extra[c].name || s.extra[c].components != all.extra[c].components)
        throw IoError(file, "has different extra columns than part 0");
      all.extra[c].data.insert(all.extra[c].data.end(), s.extra[c].data.begin(), s.extra[c].data.end());
    }
  }
  if (all.size() != all.total())
    throw IoError(path, "parts hold " + std::to_string(all.size()) + " particles, the header says " +
                            std::to_string(all.total()));
  all.part = 0;
  all.n_parts = 1;
  all.validate(path);
  return all;
}

}  // namespace pik::io
