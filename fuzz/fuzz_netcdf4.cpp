// libFuzzer target: the NetCDF importers on one NetCDF-4 (HDF5) file, mutated byte by byte by
// libFuzzer. The HDF5 library runs in NcFile's reader process, so libFuzzer sees no coverage of it;
// the mutations still reach it, and a crash there must come back as an ImportError. The body is
// netcdf_target.hpp.
#include <cstdlib>

#include "netcdf_target.hpp"

// HDF5 loops forever on some inputs (in the reader process): its waits well under libFuzzer's
// -timeout (10 s in scripts/fuzz), so such an input ends as the ImportError a user sees.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  ::setenv("CLOUDVIEWER_OPEN_TIMEOUT_S", "3", 1);
  ::setenv("CLOUDVIEWER_READ_TIMEOUT_S", "3", 1);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return cv::fuzz::run_netcdf_input(data, size, true);
}
