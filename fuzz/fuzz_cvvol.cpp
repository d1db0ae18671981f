// libFuzzer target: the .cvvol reader, header and every time step.
#include <cstdint>

#include "fuzz_common.hpp"
#include "volume/volume_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  cv::fuzz::limit_memory();
  const cv::fuzz::MemFile file(data, size, ".cvvol");
  if (file.path().empty()) return 0;
  try {
    cv::core::CloudVolume v = cv::core::read_cvvol(file.path(), 1);
    for (std::size_t t = 0; t < v.times.size() && t < 4; ++t) (void)v.step(t);
  } catch (const cv::core::InputError&) {
  }
  return 0;
}
