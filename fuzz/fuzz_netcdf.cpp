// libFuzzer target: the NetCDF importers on one file, mutated byte by byte by libFuzzer (flips,
// insertions, erasures, truncations, copies across inputs). The body is netcdf_target.hpp.
#include "netcdf_target.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) { return cv::fuzz::run_netcdf_input(data, size); }
