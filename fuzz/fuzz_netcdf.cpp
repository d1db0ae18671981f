// libFuzzer target: the NetCDF importers (CF and WRF) on one file, every time step loaded, and
// `info`'s description. Bad input must end in an InputError (exit 2 on the command line); anything
// else that escapes, a crash, a sanitizer report or a hang is a finding.
//
// Only netCDF classic inputs (CDF-1, -2 and -5) are taken: NetCDF-4 files are HDF5, whose own
// readers HDF5 fuzzes; our code sees the same values from either (the seeds are CDF-5 copies of
// the real files).
#include <cstdint>
#include <cstring>

#include "fuzz_common.hpp"
#include "importer.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 4 || std::memcmp(data, "CDF", 3) != 0 || (data[3] != 1 && data[3] != 2 && data[3] != 5)) return -1;
  cv::fuzz::limit_memory();
  const cv::fuzz::MemFile file(data, size, ".nc");
  if (file.path().empty()) return 0;
  try {
    (void)cv::importers::describe_file(file.path());
  } catch (const cv::core::InputError&) {
  }
  try {
    cv::importers::ImportOptions o;
    o.cache_steps = 1;
    cv::core::CloudVolume v = cv::importers::import_file(file.path(), o);
    for (std::size_t t = 0; t < v.times.size() && t < 4; ++t) (void)v.step(t);
  } catch (const cv::core::InputError&) {
  }
  return 0;
}
