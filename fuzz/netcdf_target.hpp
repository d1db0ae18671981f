// The NetCDF importers' fuzz body, shared by the byte-level target (fuzz_netcdf) and the semantic
// one (fuzz_netcdf_semantic): `info`'s description, the import and every time step (up to 4)
// loaded, as floats or (inputs of odd size) as half floats. Bad input must end in an InputError
// (exit 2 on the command line); anything else that escapes, a crash, a sanitizer report or a hang
// is a finding.
//
// fuzz_netcdf and fuzz_netcdf_semantic take netCDF classic inputs (CDF-1, -2 and -5); fuzz_netcdf4
// takes NetCDF-4 (HDF5) inputs, which NcFile reads in a child process because the HDF5 library
// crashes on some corrupt files: there a finding is a crash of this process, not of the reader.
#pragma once

#include <cstdint>
#include <cstring>

#include "fuzz_common.hpp"
#include "importer.hpp"

namespace cv::fuzz {

inline bool is_classic_netcdf(const std::uint8_t* data, std::size_t size) {
  return size >= 4 && std::memcmp(data, "CDF", 3) == 0 && (data[3] == 1 || data[3] == 2 || data[3] == 5);
}

inline bool is_hdf5(const std::uint8_t* data, std::size_t size) {
  return size >= 8 && std::memcmp(data, "\x89HDF\r\n\x1a\n", 8) == 0;
}

inline int run_netcdf_input(const std::uint8_t* data, std::size_t size, bool netcdf4 = false) {
  if (netcdf4 ? !is_hdf5(data, size) : !is_classic_netcdf(data, size)) return -1;
  limit_memory();
  const MemFile file(data, size, ".nc");
  if (file.path().empty()) return 0;
  try {
    (void)importers::describe_file(file.path());
  } catch (const core::InputError&) {
  }
  try {
    importers::ImportOptions o;
    o.cache_steps = 1;
    // Half the inputs take the path `cloudviewer import` takes to a float16 volume (steps held
    // as half floats), the other half the float steps a render loads.
    o.half_fields = (size & 1) != 0;
    core::CloudVolume v = importers::import_file(file.path(), o);
    for (std::size_t t = 0; t < v.times.size() && t < 4; ++t) (void)v.step(t);
  } catch (const core::InputError&) {
  }
  return 0;
}

}  // namespace cv::fuzz
