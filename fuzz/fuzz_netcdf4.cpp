// libFuzzer target: the NetCDF importers on one NetCDF-4 (HDF5) file, mutated byte by byte by
// libFuzzer. The HDF5 library runs in NcFile's reader process, so libFuzzer sees no coverage of it;
// the mutations still reach it, and a crash there must come back as an ImportError. The body is
// netcdf_target.hpp.
#include "netcdf_target.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return cv::fuzz::run_netcdf_input(data, size, true);
}
