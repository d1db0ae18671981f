// libFuzzer target: the scene-file reader (the JSON parser, every key's checks, the writer of what
// was read, and reading that back).
#include <cstdint>
#include <string>

#include "scene/scene_json.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const cv::core::Scene s = cv::core::scene_from_json(text, "fuzz.json");
    const cv::core::Scene again = cv::core::scene_from_json(cv::core::scene_to_json(s), "fuzz.json");
    (void)again;
  } catch (const cv::core::InputError&) {
  }
  return 0;
}
