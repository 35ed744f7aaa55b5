/// \file BinarySnapshot.hpp
/// \brief The pik binary snapshot format (".pbin"): compact, self-describing,
///        checksummed; written atomically. The layout is specified in docs/snapshots.md.
///
/// Layout (version 1; every integer in the byte order named by the endianness marker):
///   header (128 bytes)  magic, version, endianness marker, counts, time, step,
///                       offsets, CRC-32 of the field table, of the attributes and of
///                       the header itself
///   field table         64 bytes per field: name, type, components, offset, bytes, CRC-32
///   attributes          "key\tvalue\n" lines (UTF-8)
///   field data          each field 8-byte aligned
///   trailer (8 bytes)   end magic, so a truncated file is recognised at once
#pragma once

#include <sys/stat.h>

#include <array>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "pik/io/AtomicFile.hpp"
#include "pik/io/Crc32.hpp"
#include "pik/io/IoError.hpp"
#include "pik/io/Snapshot.hpp"

namespace pik::io {

namespace binary {

inline constexpr std::array<unsigned char, 8> magic = {0x89, 'P', 'I', 'K', '\r', '\n', 0x1A, '\n'};
inline constexpr std::array<unsigned char, 8> end_magic = {0x89, 'P', 'I', 'K', 'E', 'N', 'D', '\n'};
inline constexpr std::uint32_t version = 1;
inline constexpr std::uint32_t endian_marker = 0x0A0B0C0D;
inline constexpr std::size_t header_bytes = 128;
inline constexpr std::size_t field_entry_bytes = 64;
inline constexpr std::size_t max_name = 31;

/// Element types of a field.
enum class Type : std::uint8_t { f32 = 1, f64 = 2, u32 = 3, u64 = 4, i32 = 5, i64 = 6 };

inline std::size_t type_size(std::uint8_t t) {
  switch (Type(t)) {
    case Type::f32: case Type::u32: case Type::i32: return 4;
    case Type::f64: case Type::u64: case Type::i64: return 8;
  }
  return 0;
}

// Header field offsets (bytes).
enum Offset : std::size_t {
  o_magic = 0, o_version = 8, o_endian = 12, o_n_local = 16, o_n_total = 24,
  o_first_index = 32, o_part = 40, o_n_parts = 44, o_time = 48, o_step = 56,
  o_n_fields = 64, o_table_crc = 68, o_attr_offset = 72, o_attr_bytes = 80,
  o_attr_crc = 88, o_file_bytes = 96, o_header_crc = 124
};

template <class T>
void put(unsigned char* buf, std::size_t off, T v) { std::memcpy(buf + off, &v, sizeof v); }
template <class T>
T get(const unsigned char* buf, std::size_t off) {
  T v;
  std::memcpy(&v, buf + off, sizeof v);
  return v;
}

struct FieldEntry {
  std::string name;
  std::uint8_t type = 0;
  std::uint8_t components = 1;
  std::uint32_t crc = 0;
  std::uint64_t offset = 0;
  std::uint64_t bytes = 0;
  const void* data = nullptr;  // writer only
};

inline std::uint64_t align8(std::uint64_t x) { return (x + 7) & ~std::uint64_t(7); }

inline std::string encode_attributes(const Attributes& a) {
  std::string s;
  for (const auto& [k, v] : a.all()) s += k + "\t" + v + "\n";
  return s;
}

}  // namespace binary

/// Writes `snap` to `path` in the pik binary format, atomically.
inline void write_binary(const std::string& path, const Snapshot& snap) {
  using namespace binary;
  snap.validate(path);
  const std::uint64_t n = snap.size();

  std::vector<FieldEntry> fields;
  fields.push_back({"ParticleIDs", std::uint8_t(Type::u64), 1, 0, 0, n * 8, snap.id.data()});
  fields.push_back({"Masses", std::uint8_t(Type::f64), 1, 0, 0, n * 8, snap.mass.data()});
  fields.push_back({"Coordinates", std::uint8_t(Type::f64), 3, 0, 0, n * 24, snap.pos.data()});
  fields.push_back({"Velocities", std::uint8_t(Type::f64), 3, 0, 0, n * 24, snap.vel.data()});
  for (const auto& c : snap.extra)
    fields.push_back({c.name, std::uint8_t(Type::f64), std::uint8_t(c.components), 0, 0,
                      n * 8 * std::uint64_t(c.components), c.data.data()});

  const std::string attrs = encode_attributes(snap.attr);
  const std::uint64_t table_off = header_bytes;
  const std::uint64_t attr_off = table_off + fields.size() * field_entry_bytes;
  std::uint64_t off = align8(attr_off + attrs.size());
  for (auto& f : fields) {
    f.offset = off;
    f.crc = crc32(f.data, f.bytes);
    off = align8(off + f.bytes);
  }
  const std::uint64_t file_bytes = off + end_magic.size();

  std::vector<unsigned char> table(fields.size() * field_entry_bytes, 0);
  for (std::size_t i = 0; i < fields.size(); ++i) {
    unsigned char* e = table.data() + i * field_entry_bytes;
    std::memcpy(e, fields[i].name.data(), fields[i].name.size());
    e[32] = fields[i].type;
    e[33] = fields[i].components;
    put<std::uint32_t>(e, 36, fields[i].crc);
    put<std::uint64_t>(e, 40, fields[i].offset);
    put<std::uint64_t>(e, 48, fields[i].bytes);
  }

  std::array<unsigned char, header_bytes> h{};
  std::memcpy(h.data() + o_magic, magic.data(), magic.size());
  put<std::uint32_t>(h.data(), o_version, version);
  put<std::uint32_t>(h.data(), o_endian, endian_marker);
  put<std::uint64_t>(h.data(), o_n_local, n);
  put<std::uint64_t>(h.data(), o_n_total, snap.total());
  put<std::uint64_t>(h.data(), o_first_index, snap.first_index);
  put<std::uint32_t>(h.data(), o_part, snap.part);
  put<std::uint32_t>(h.data(), o_n_parts, snap.n_parts);
  put<double>(h.data(), o_time, snap.time);
  put<std::uint64_t>(h.data(), o_step, snap.step);
  put<std::uint32_t>(h.data(), o_n_fields, std::uint32_t(fields.size()));
  put<std::uint32_t>(h.data(), o_table_crc, crc32(table.data(), table.size()));
  put<std::uint64_t>(h.data(), o_attr_offset, attr_off);
  put<std::uint64_t>(h.data(), o_attr_bytes, attrs.size());
  put<std::uint32_t>(h.data(), o_attr_crc, crc32(attrs.data(), attrs.size()));
  put<std::uint64_t>(h.data(), o_file_bytes, file_bytes);
  put<std::uint32_t>(h.data(), o_header_crc, crc32(h.data(), o_header_crc));

  static constexpr unsigned char zeros[8] = {};
  AtomicFile out(path);
  out.write(h.data(), h.size());
  out.write(table.data(), table.size());
  out.write(attrs);
  out.write(zeros, align8(out.size()) - out.size());
  for (const auto& f : fields) {
    out.write(f.data, f.bytes);
    out.write(zeros, align8(out.size()) - out.size());
  }
  out.write(end_magic.data(), end_magic.size());
  if (out.size() != file_bytes) throw IoError(path, "internal error: layout size mismatch");
  out.commit();
}

/// Is `head` (the first bytes of a file) the start of a pik binary snapshot?
inline bool looks_binary(const unsigned char* head, std::size_t n) {
  return n >= binary::magic.size() && std::memcmp(head, binary::magic.data(), 8) == 0;
}

/// Reads a pik binary snapshot. Throws IoError naming the file and the problem for
/// a missing, truncated, corrupted (checksum), foreign or malformed file.
inline Snapshot read_binary(const std::string& path) {
  using namespace binary;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) throw IoError(path, "cannot open: " + detail::errno_text(errno));
  struct stat st {};
  if (::fstat(::fileno(f.get()), &st) != 0)
    throw IoError(path, "cannot stat: " + detail::errno_text(errno));
  const std::uint64_t size = std::uint64_t(st.st_size);
  auto read_at = [&](std::uint64_t off, void* dst, std::uint64_t bytes, const char* what) {
    if (off + bytes > size)
      throw IoError(path, std::string("truncated: ") + what + " ends at byte " +
                              std::to_string(off + bytes) + " but the file has " +
                              std::to_string(size) + " bytes");
    if (bytes == 0) return;
    if (std::fseek(f.get(), long(off), SEEK_SET) != 0 || std::fread(dst, 1, bytes, f.get()) != bytes)
      throw IoError(path, std::string("read error in ") + what + ": " + detail::errno_text(errno));
  };

  std::array<unsigned char, header_bytes> h{};
  if (size < magic.size() || (read_at(0, h.data(), magic.size(), "magic"), !looks_binary(h.data(), 8)))
    throw IoError(path, "not a pik binary snapshot (bad magic number)");
  read_at(0, h.data(), header_bytes, "the 128-byte header");
  const auto marker = get<std::uint32_t>(h.data(), o_endian);
  if (marker != endian_marker) {
    if (marker == 0x0D0C0B0A)
      throw IoError(path, "written with the opposite byte order; byte-swapped reading is not supported");
    throw IoError(path, "corrupt header (bad endianness marker)");
  }
  if (get<std::uint32_t>(h.data(), o_header_crc) != crc32(h.data(), o_header_crc))
    throw IoError(path, "corrupt header (checksum mismatch)");
  const auto ver = get<std::uint32_t>(h.data(), o_version);
  if (ver != version)
    throw IoError(path, "format version " + std::to_string(ver) + ", this reader knows version " +
                            std::to_string(version));
  const auto file_bytes = get<std::uint64_t>(h.data(), o_file_bytes);
  if (size < file_bytes)
    throw IoError(path, "truncated: " + std::to_string(size) + " bytes, the header says " +
                            std::to_string(file_bytes));
  if (size > file_bytes)
    throw IoError(path, std::to_string(size - file_bytes) + " unexpected bytes after the end");
  std::array<unsigned char, 8> tail{};
  read_at(file_bytes - 8, tail.data(), 8, "the end marker");
  if (tail != end_magic) throw IoError(path, "corrupt end marker");

  Snapshot s;
  const auto n = get<std::uint64_t>(h.data(), o_n_local);
  s.n_total = get<std::uint64_t>(h.data(), o_n_total);
  s.first_index = get<std::uint64_t>(h.data(), o_first_index);
  s.part = get<std::uint32_t>(h.data(), o_part);
  s.n_parts = get<std::uint32_t>(h.data(), o_n_parts);
  s.time = get<double>(h.data(), o_time);
  s.step = get<std::uint64_t>(h.data(), o_step);
  if (n > file_bytes / 8) throw IoError(path, "corrupt header (particle count " + std::to_string(n) + ")");

  const auto n_fields = get<std::uint32_t>(h.data(), o_n_fields);
  if (n_fields > 1024) throw IoError(path, "corrupt header (" + std::to_string(n_fields) + " fields)");
  std::vector<unsigned char> table(std::size_t(n_fields) * field_entry_bytes);
  read_at(header_bytes, table.data(), table.size(), "the field table");
  if (crc32(table.data(), table.size()) != get<std::uint32_t>(h.data(), o_table_crc))
    throw IoError(path, "corrupt field table (checksum mismatch)");

  const auto attr_off = get<std::uint64_t>(h.data(), o_attr_offset);
  const auto attr_bytes = get<std::uint64_t>(h.data(), o_attr_bytes);
  std::string attrs(attr_bytes, '\0');
  read_at(attr_off, attrs.data(), attr_bytes, "the attributes");
  if (crc32(attrs.data(), attrs.size()) != get<std::uint32_t>(h.data(), o_attr_crc))
    throw IoError(path, "corrupt attributes (checksum mismatch)");
  for (std::size_t p = 0; p < attrs.size();) {
    const auto nl = attrs.find('\n', p);
    const auto tab = attrs.find('\t', p);
    if (nl == std::string::npos || tab == std::string::npos || tab > nl)
      throw IoError(path, "malformed attribute line at byte " + std::to_string(attr_off + p));
    s.attr.set(attrs.substr(p, tab - p), attrs.substr(tab + 1, nl - tab - 1));
    p = nl + 1;
  }

  s.resize(n);
  bool seen[4] = {false, false, false, false};
  std::vector<unsigned char> buf;
  for (std::uint32_t i = 0; i < n_fields; ++i) {
    const unsigned char* e = table.data() + std::size_t(i) * field_entry_bytes;
    FieldEntry fe;
    fe.name.assign(reinterpret_cast<const char*>(e), strnlen(reinterpret_cast<const char*>(e), 32));
    fe.type = e[32];
    fe.components = e[33];
    fe.crc = get<std::uint32_t>(e, 36);
    fe.offset = get<std::uint64_t>(e, 40);
    fe.bytes = get<std::uint64_t>(e, 48);
    const std::string what = "field '" + fe.name + "'";
    const std::size_t ts = type_size(fe.type);
    if (ts == 0) throw IoError(path, what + " has unknown type code " + std::to_string(fe.type));
    if (fe.components != 1 && fe.components != 3)
      throw IoError(path, what + " has " + std::to_string(fe.components) + " components");
    if (fe.bytes != n * ts * fe.components)
      throw IoError(path, what + " has " + std::to_string(fe.bytes) + " bytes, expected " +
                              std::to_string(n * ts * fe.components));
    if (fe.offset + fe.bytes > file_bytes - 8)
      throw IoError(path, what + " runs past the end of the data");
    buf.resize(fe.bytes);
    read_at(fe.offset, buf.data(), fe.bytes, what.c_str());
    if (crc32(buf.data(), buf.size()) != fe.crc)
      throw IoError(path, what + " is corrupt (checksum mismatch)");

    // Core fields are stored as u64 ids and f64 values; extra columns may be f32 or f64.
    auto as_doubles = [&](double* dst) {
      if (Type(fe.type) == Type::f64) {
        std::memcpy(dst, buf.data(), buf.size());
      } else if (Type(fe.type) == Type::f32) {
        for (std::size_t k = 0; k < buf.size() / 4; ++k) dst[k] = get<float>(buf.data(), 4 * k);
      } else {
        throw IoError(path, what + " must be floating point");
      }
    };
    auto expect = [&](int comps) {
      if (fe.components != comps)
        throw IoError(path, what + " must have " + std::to_string(comps) + " components");
    };
    if (fe.name == "ParticleIDs") {
      expect(1);
      if (Type(fe.type) != Type::u64) throw IoError(path, what + " must be u64");
      std::memcpy(s.id.data(), buf.data(), buf.size());
      seen[0] = true;
    } else if (fe.name == "Masses") {
      expect(1);
      as_doubles(s.mass.data());
      seen[1] = true;
    } else if (fe.name == "Coordinates") {
      expect(3);
      as_doubles(&s.pos.data()->x);
      seen[2] = true;
    } else if (fe.name == "Velocities") {
      expect(3);
      as_doubles(&s.vel.data()->x);
      seen[3] = true;
    } else {
      if (s.find(fe.name)) throw IoError(path, what + " appears twice");
      as_doubles(s.column(fe.name, fe.components).data.data());
    }
  }
  static const char* const required[4] = {"ParticleIDs", "Masses", "Coordinates", "Velocities"};
  for (int k = 0; k < 4; ++k)
    if (!seen[k]) throw IoError(path, std::string("required field '") + required[k] + "' is missing");
  s.validate(path);
  return s;
}

}  // namespace pik::io
