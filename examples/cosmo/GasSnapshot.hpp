/// \file GasSnapshot.hpp
/// \brief Snapshots of the dark matter + gas box: one HDF5 file in the GADGET layout
///        with /PartType0 (gas) and /PartType1 (dark matter), or, in the other pik
///        formats, one file per species (`snap_NNN.gas.pbin`, `snap_NNN.dm.pbin`).
///
/// pik::io writes one particle type (PartType1); this writer builds the two-type file
/// from two pik::io::Snapshot with the same helpers (pik::io::hdf5), so each group
/// holds Coordinates, Velocities, Masses, ParticleIDs and the species' extra columns
/// (gas: InternalEnergy, Density, SmoothingLength), /Header holds NumPart_ThisFile /
/// NumPart_Total of both types, Time, Redshift and BoxSize, /Parameters the run's
/// attributes.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include <pik/io/SnapshotIo.hpp>

namespace cosmo {

#if defined(PIK_HAVE_HDF5) && PIK_HAVE_HDF5
/// One HDF5 file, /PartType0 = gas, /PartType1 = dark matter. Written atomically.
inline void write_gas_hdf5(const std::string& path, const pik::io::Snapshot& dm, const pik::io::Snapshot& gas,
                           double box) {
  using namespace pik::io::hdf5;
  dm.validate(path), gas.validate(path);
  quiet();
  pik::io::write_atomically_by_name(path, [&](const std::string& tmp) {
    Id file = check(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose, path,
                    "cannot create HDF5 file");
    {
      Id h = check(H5Gcreate2(file, "/Header", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, path,
                   "cannot create /Header");
      std::array<std::uint64_t, n_types> num{};
      std::array<double, n_types> mass_table{};
      num[0] = gas.size(), num[1] = dm.size();
      const double z = 1 / dm.time - 1;
      const std::int32_t files = 1;
      write_attr(h, "NumPart_ThisFile", H5T_NATIVE_UINT64, num.data(), n_types, path);
      write_attr(h, "NumPart_Total", H5T_NATIVE_UINT64, num.data(), n_types, path);
      write_attr(h, "MassTable", H5T_NATIVE_DOUBLE, mass_table.data(), n_types, path);
      write_attr(h, "Time", H5T_NATIVE_DOUBLE, &dm.time, 1, path);
      write_attr(h, "Redshift", H5T_NATIVE_DOUBLE, &z, 1, path);
      write_attr(h, "BoxSize", H5T_NATIVE_DOUBLE, &box, 1, path);
      write_attr(h, "NumFilesPerSnapshot", H5T_NATIVE_INT32, &files, 1, path);
      write_attr(h, "Step", H5T_NATIVE_UINT64, &dm.step, 1, path);
    }
    {
      Id p = check(H5Gcreate2(file, "/Parameters", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, path,
                   "cannot create /Parameters");
      for (const auto& [k, v] : dm.attr.all()) write_string_attr(p, k, v, path);
    }
    for (const auto& [name, s] : {std::pair<const char*, const pik::io::Snapshot*>{"/PartType0", &gas}, {"/PartType1", &dm}}) {
      Id gcpl = check(H5Pcreate(H5P_GROUP_CREATE), H5Pclose, path, "H5Pcreate failed");
      check(H5Pset_link_creation_order(gcpl, H5P_CRT_ORDER_TRACKED | H5P_CRT_ORDER_INDEXED), path,
            "H5Pset_link_creation_order failed");
      Id g = check(H5Gcreate2(file, name, H5P_DEFAULT, gcpl, H5P_DEFAULT), H5Gclose, path,
                   std::string("cannot create ") + name);
      const hsize_t n = s->size();
      write_dataset(g, "Coordinates", H5T_NATIVE_DOUBLE, s->pos.data(), n, 3, path);
      write_dataset(g, "Velocities", H5T_NATIVE_DOUBLE, s->vel.data(), n, 3, path);
      write_dataset(g, "Masses", H5T_NATIVE_DOUBLE, s->mass.data(), n, 1, path);
      write_dataset(g, "ParticleIDs", H5T_NATIVE_UINT64, s->id.data(), n, 1, path);
      for (const auto& c : s->extra) write_dataset(g, c.name, H5T_NATIVE_DOUBLE, c.data.data(), n, c.components, path);
    }
    check(H5Fflush(file, H5F_SCOPE_GLOBAL), path, "H5Fflush failed");
  });
}
#endif

/// `stem` + extension: one HDF5 file with both types, or stem.gas.EXT and stem.dm.EXT.
inline void write_gas_snapshot(const std::string& stem, const pik::io::Snapshot& dm, const pik::io::Snapshot& gas,
                               double box, pik::io::Format format) {
#if defined(PIK_HAVE_HDF5) && PIK_HAVE_HDF5
  if (format == pik::io::Format::hdf5) return write_gas_hdf5(stem + ".hdf5", dm, gas, box);
#endif
  pik::io::write_snapshot(stem + ".dm" + pik::io::extension(format), dm, format);
  pik::io::write_snapshot(stem + ".gas" + pik::io::extension(format), gas, format);
}

}  // namespace cosmo
