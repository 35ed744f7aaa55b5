/// \file Hdf5Snapshot.hpp
/// \brief HDF5 snapshots in the layout GADGET-4 and SWIFT users read:
///        /Header attributes, /Parameters attributes, /PartType1/{Coordinates,
///        Velocities, Masses, ParticleIDs, extra columns}. Written atomically.
///
/// Only available when the program is built with HDF5 (`PIK_HAVE_HDF5`, set by
/// pik's CMake when it finds the HDF5 C library). Every dataset is chunked with the
/// Fletcher-32 checksum filter, so corrupted data are detected when read; a
/// truncated or foreign file is refused when opened. Gravity-only particles go to
/// PartType1 (the dark-matter slot of the GADGET convention).
#pragma once

#if !defined(PIK_HAVE_HDF5) || !PIK_HAVE_HDF5
#error "pik/io/Hdf5Snapshot.hpp needs HDF5: link hdf5 and define PIK_HAVE_HDF5=1"
#endif

#include <hdf5.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "pik/io/AtomicFile.hpp"
#include "pik/io/IoError.hpp"
#include "pik/io/Snapshot.hpp"

namespace pik::io {

namespace hdf5 {

/// Owns an HDF5 identifier and closes it with the matching H5*close.
class Id {
 public:
  Id() = default;
  Id(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  Id(const Id&) = delete;
  Id& operator=(const Id&) = delete;
  Id(Id&& o) noexcept : id_(std::exchange(o.id_, H5I_INVALID_HID)), close_(o.close_) {}
  ~Id() {
    if (id_ >= 0 && close_) close_(id_);
  }
  operator hid_t() const { return id_; }
  bool ok() const { return id_ >= 0; }

 private:
  hid_t id_ = H5I_INVALID_HID;
  herr_t (*close_)(hid_t) = nullptr;
};

/// HDF5 prints its error stack to stderr by default; pik reports errors itself.
inline void quiet() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

inline Id check(hid_t id, herr_t (*close)(hid_t), const std::string& path, const std::string& what) {
  if (id < 0) throw IoError(path, what);
  return Id(id, close);
}
inline void check(herr_t rc, const std::string& path, const std::string& what) {
  if (rc < 0) throw IoError(path, what);
}

inline constexpr int n_types = 6;  // GADGET particle types 0..5
inline constexpr int part_type = 1;

template <class T>
void write_attr(hid_t loc, const char* name, hid_t type, const T* v, hsize_t n,
                const std::string& path) {
  Id space = n == 1 ? check(H5Screate(H5S_SCALAR), H5Sclose, path, "H5Screate failed")
                    : check(H5Screate_simple(1, &n, nullptr), H5Sclose, path, "H5Screate failed");
  Id attr = check(H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose, path,
                  std::string("cannot create attribute ") + name);
  check(H5Awrite(attr, type, v), path, std::string("cannot write attribute ") + name);
}

inline void write_string_attr(hid_t loc, const std::string& name, const std::string& value,
                              const std::string& path) {
  Id type = check(H5Tcopy(H5T_C_S1), H5Tclose, path, "H5Tcopy failed");
  H5Tset_size(type, value.empty() ? 1 : value.size());
  H5Tset_strpad(type, H5T_STR_NULLPAD);
  Id space = check(H5Screate(H5S_SCALAR), H5Sclose, path, "H5Screate failed");
  Id attr = check(H5Acreate2(loc, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose,
                  path, "cannot create attribute " + name);
  const std::string v = value.empty() ? std::string(1, '\0') : value;
  check(H5Awrite(attr, type, v.data()), path, "cannot write attribute " + name);
}

template <class T>
void read_attr(hid_t loc, const char* name, hid_t type, T* v, hsize_t n, const std::string& path) {
  if (H5Aexists(loc, name) <= 0) throw IoError(path, std::string("missing attribute ") + name);
  Id attr = check(H5Aopen(loc, name, H5P_DEFAULT), H5Aclose, path,
                  std::string("cannot open attribute ") + name);
  Id space = check(H5Aget_space(attr), H5Sclose, path, "H5Aget_space failed");
  if (hsize_t(H5Sget_simple_extent_npoints(space)) != n)
    throw IoError(path, std::string("attribute ") + name + " has the wrong length");
  check(H5Aread(attr, type, v), path, std::string("cannot read attribute ") + name);
}

/// Writes an n x comps dataset, chunked with the Fletcher-32 checksum filter.
inline void write_dataset(hid_t group, const std::string& name, hid_t type, const void* data,
                          hsize_t n, int comps, const std::string& path) {
  const int rank = comps == 1 ? 1 : 2;
  const hsize_t dims[2] = {n, hsize_t(comps)};
  Id space = check(H5Screate_simple(rank, dims, nullptr), H5Sclose, path, "H5Screate failed");
  Id plist = check(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, path, "H5Pcreate failed");
  if (n > 0) {
    const hsize_t chunk[2] = {std::min<hsize_t>(n, 1 << 16), hsize_t(comps)};
    check(H5Pset_chunk(plist, rank, chunk), path, "H5Pset_chunk failed");
    check(H5Pset_fletcher32(plist), path, "H5Pset_fletcher32 failed");
  }
  Id ds = check(H5Dcreate2(group, name.c_str(), type, space, H5P_DEFAULT, plist, H5P_DEFAULT),
                H5Dclose, path, "cannot create dataset " + name);
  if (n > 0)
    check(H5Dwrite(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), path,
          "cannot write dataset " + name);
}

/// Reads dataset `name` (n x comps) into `data` converted to `mem_type`.
inline void read_dataset(hid_t group, const std::string& name, hid_t mem_type, void* data,
                         hsize_t n, int comps, const std::string& path) {
  Id ds = check(H5Dopen2(group, name.c_str(), H5P_DEFAULT), H5Dclose, path,
                "cannot open dataset /PartType1/" + name);
  Id space = check(H5Dget_space(ds), H5Sclose, path, "H5Dget_space failed");
  hsize_t dims[2] = {0, 1};
  const int rank = H5Sget_simple_extent_ndims(space);
  if (rank < 1 || rank > 2) throw IoError(path, "dataset " + name + " has rank " + std::to_string(rank));
  H5Sget_simple_extent_dims(space, dims, nullptr);
  if (dims[0] != n || (rank == 2 ? dims[1] : 1) != hsize_t(comps))
    throw IoError(path, "dataset " + name + " has shape " + std::to_string(dims[0]) + "x" +
                            std::to_string(rank == 2 ? dims[1] : 1) + ", expected " +
                            std::to_string(n) + "x" + std::to_string(comps));
  if (n > 0 && H5Dread(ds, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0)
    throw IoError(path, "dataset /PartType1/" + name +
                            " cannot be read (corrupt data: checksum mismatch, or truncated file)");
}

}  // namespace hdf5

/// Writes `snap` to `path` as HDF5, atomically.
inline void write_hdf5(const std::string& path, const Snapshot& snap) {
  using namespace hdf5;
  snap.validate(path);
  quiet();
  write_atomically_by_name(path, [&](const std::string& tmp) {
    Id file = check(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose,
                    path, "cannot create HDF5 file");
    const hsize_t n = snap.size();
    {
      Id h = check(H5Gcreate2(file, "/Header", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose,
                   path, "cannot create /Header");
      std::array<std::uint64_t, n_types> this_file{}, total{};
      std::array<double, n_types> mass_table{};
      this_file[part_type] = n;
      total[part_type] = snap.total();
      const double zero = 0.0;
      const std::int32_t files = std::int32_t(snap.n_parts);
      write_attr(h, "NumPart_ThisFile", H5T_NATIVE_UINT64, this_file.data(), n_types, path);
      write_attr(h, "NumPart_Total", H5T_NATIVE_UINT64, total.data(), n_types, path);
      write_attr(h, "MassTable", H5T_NATIVE_DOUBLE, mass_table.data(), n_types, path);
      write_attr(h, "Time", H5T_NATIVE_DOUBLE, &snap.time, 1, path);
      write_attr(h, "Redshift", H5T_NATIVE_DOUBLE, &zero, 1, path);
      write_attr(h, "BoxSize", H5T_NATIVE_DOUBLE, &zero, 1, path);
      write_attr(h, "NumFilesPerSnapshot", H5T_NATIVE_INT32, &files, 1, path);
      write_attr(h, "Step", H5T_NATIVE_UINT64, &snap.step, 1, path);
      write_attr(h, "FirstIndex", H5T_NATIVE_UINT64, &snap.first_index, 1, path);
      write_attr(h, "ThisFile", H5T_NATIVE_UINT32, &snap.part, 1, path);
    }
    {
      Id p = check(H5Gcreate2(file, "/Parameters", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                   H5Gclose, path, "cannot create /Parameters");
      for (const auto& [k, v] : snap.attr.all()) write_string_attr(p, k, v, path);
    }
    // Track creation order so that extra columns read back in the order written.
    Id gcpl = check(H5Pcreate(H5P_GROUP_CREATE), H5Pclose, path, "H5Pcreate failed");
    check(H5Pset_link_creation_order(gcpl, H5P_CRT_ORDER_TRACKED | H5P_CRT_ORDER_INDEXED), path,
          "H5Pset_link_creation_order failed");
    Id g = check(H5Gcreate2(file, "/PartType1", H5P_DEFAULT, gcpl, H5P_DEFAULT), H5Gclose, path,
                 "cannot create /PartType1");
    write_dataset(g, "Coordinates", H5T_NATIVE_DOUBLE, snap.pos.data(), n, 3, path);
    write_dataset(g, "Velocities", H5T_NATIVE_DOUBLE, snap.vel.data(), n, 3, path);
    write_dataset(g, "Masses", H5T_NATIVE_DOUBLE, snap.mass.data(), n, 1, path);
    write_dataset(g, "ParticleIDs", H5T_NATIVE_UINT64, snap.id.data(), n, 1, path);
    for (const auto& c : snap.extra)
      write_dataset(g, c.name, H5T_NATIVE_DOUBLE, c.data.data(), n, c.components, path);
    check(H5Fflush(file, H5F_SCOPE_GLOBAL), path, "H5Fflush failed");
  });
}

/// Is the file at `head` an HDF5 file (its 8-byte signature at offset 0)?
inline bool looks_hdf5(const unsigned char* head, std::size_t n) {
  static constexpr unsigned char sig[8] = {0x89, 'H', 'D', 'F', '\r', '\n', 0x1A, '\n'};
  return n >= 8 && std::memcmp(head, sig, 8) == 0;
}

/// Reads an HDF5 snapshot written by write_hdf5 (or any file with the same layout:
/// other datasets in /PartType1 with 1 or 3 floating-point components become extra
/// columns).
inline Snapshot read_hdf5(const std::string& path) {
  using namespace hdf5;
  quiet();
  if (H5Fis_hdf5(path.c_str()) <= 0)
    throw IoError(path, "not a readable HDF5 file (missing, truncated or corrupt)");
  Id file = check(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose, path,
                  "cannot open as HDF5 (truncated or corrupt)");
  Snapshot s;
  hsize_t n = 0;
  {
    if (H5Lexists(file, "/Header", H5P_DEFAULT) <= 0) throw IoError(path, "no /Header group");
    Id h = check(H5Gopen2(file, "/Header", H5P_DEFAULT), H5Gclose, path, "cannot open /Header");
    std::array<std::uint64_t, n_types> this_file{}, total{};
    read_attr(h, "NumPart_ThisFile", H5T_NATIVE_UINT64, this_file.data(), n_types, path);
    read_attr(h, "NumPart_Total", H5T_NATIVE_UINT64, total.data(), n_types, path);
    read_attr(h, "Time", H5T_NATIVE_DOUBLE, &s.time, 1, path);
    for (int t = 0; t < n_types; ++t)
      if (t != part_type && this_file[t] != 0)
        throw IoError(path, "has PartType" + std::to_string(t) +
                                " particles; pik reads gravity-only PartType1");
    n = this_file[part_type];
    s.n_total = total[part_type];
    std::int32_t files = 1;
    if (H5Aexists(h, "NumFilesPerSnapshot") > 0)
      read_attr(h, "NumFilesPerSnapshot", H5T_NATIVE_INT32, &files, 1, path);
    s.n_parts = std::uint32_t(files);
    if (H5Aexists(h, "Step") > 0) read_attr(h, "Step", H5T_NATIVE_UINT64, &s.step, 1, path);
    if (H5Aexists(h, "FirstIndex") > 0)
      read_attr(h, "FirstIndex", H5T_NATIVE_UINT64, &s.first_index, 1, path);
    if (H5Aexists(h, "ThisFile") > 0) read_attr(h, "ThisFile", H5T_NATIVE_UINT32, &s.part, 1, path);
  }
  if (H5Lexists(file, "/Parameters", H5P_DEFAULT) > 0) {
    Id p = check(H5Gopen2(file, "/Parameters", H5P_DEFAULT), H5Gclose, path, "cannot open /Parameters");
    H5O_info_t info;
    check(H5Oget_info(p, &info), path, "H5Oget_info failed");
    for (hsize_t k = 0; k < info.num_attrs; ++k) {
      Id a = check(H5Aopen_by_idx(p, ".", H5_INDEX_NAME, H5_ITER_INC, k, H5P_DEFAULT, H5P_DEFAULT),
                   H5Aclose, path, "cannot open a /Parameters attribute");
      const ssize_t len = H5Aget_name(a, 0, nullptr);
      std::string name(std::size_t(len), '\0');
      H5Aget_name(a, std::size_t(len) + 1, name.data());
      Id type = check(H5Aget_type(a), H5Tclose, path, "H5Aget_type failed");
      if (H5Tget_class(type) != H5T_STRING || H5Tis_variable_str(type) > 0)
        throw IoError(path, "/Parameters/" + name + " is not a fixed-length string");
      std::string value(H5Tget_size(type), '\0');
      check(H5Aread(a, type, value.data()), path, "cannot read /Parameters/" + name);
      value.resize(strnlen(value.c_str(), value.size()));
      s.attr.set(name, value);
    }
  }
  s.resize(n);
  if (H5Lexists(file, "/PartType1", H5P_DEFAULT) <= 0) {
    if (n == 0) return s;
    throw IoError(path, "no /PartType1 group");
  }
  Id g = check(H5Gopen2(file, "/PartType1", H5P_DEFAULT), H5Gclose, path, "cannot open /PartType1");
  read_dataset(g, "Coordinates", H5T_NATIVE_DOUBLE, s.pos.data(), n, 3, path);
  read_dataset(g, "Velocities", H5T_NATIVE_DOUBLE, s.vel.data(), n, 3, path);
  read_dataset(g, "Masses", H5T_NATIVE_DOUBLE, s.mass.data(), n, 1, path);
  read_dataset(g, "ParticleIDs", H5T_NATIVE_UINT64, s.id.data(), n, 1, path);

  // Extra columns, in creation order when tracked, else by name.
  H5G_info_t ginfo;
  check(H5Gget_info(g, &ginfo), path, "H5Gget_info failed");
  H5_index_t order = H5_INDEX_NAME;
  {
    Id gcpl = check(H5Gget_create_plist(g), H5Pclose, path, "H5Gget_create_plist failed");
    unsigned flags = 0;
    if (H5Pget_link_creation_order(gcpl, &flags) >= 0 && (flags & H5P_CRT_ORDER_INDEXED))
      order = H5_INDEX_CRT_ORDER;
  }
  for (hsize_t k = 0; k < ginfo.nlinks; ++k) {
    const ssize_t len = H5Lget_name_by_idx(g, ".", order, H5_ITER_INC, k, nullptr, 0, H5P_DEFAULT);
    std::string name(std::size_t(len), '\0');
    H5Lget_name_by_idx(g, ".", order, H5_ITER_INC, k, name.data(), std::size_t(len) + 1,
                       H5P_DEFAULT);
    if (name == "Coordinates" || name == "Velocities" || name == "Masses" || name == "ParticleIDs")
      continue;
    Id ds = check(H5Dopen2(g, name.c_str(), H5P_DEFAULT), H5Dclose, path, "cannot open dataset " + name);
    Id space = check(H5Dget_space(ds), H5Sclose, path, "H5Dget_space failed");
    hsize_t dims[2] = {0, 1};
    const int rank = H5Sget_simple_extent_ndims(space);
    if (rank < 1 || rank > 2) continue;
    H5Sget_simple_extent_dims(space, dims, nullptr);
    const int comps = rank == 2 ? int(dims[1]) : 1;
    if (comps != 1 && comps != 3) continue;
    read_dataset(g, name, H5T_NATIVE_DOUBLE, s.column(name, comps).data.data(), n, comps, path);
  }
  s.validate(path);
  return s;
}

}  // namespace pik::io
