// Prepared time steps kept resident: the last two used (a frame between two forecast steps needs
// both), each built once from its volume's data.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "kernel/prepared_volume.hpp"
#include "volume/cloud_volume.hpp"

namespace cv::core {

class PreparedVolumeCache {
 public:
  static constexpr std::size_t kResident = 2;
  // The prepared time step `step` of `volume`, whose data are named by `source` (a file path):
  // from the cache, or prepared now (evicting the least recently used beyond kResident).
  std::shared_ptr<const PreparedVolume> get(const std::string& source, CloudVolume& volume, std::size_t step);
  // How many preparations get has run: a test of the cache, and what the viewer's overlay reports.
  std::size_t prepared() const { return prepared_; }

 private:
  struct Entry {
    std::string source;
    std::size_t step = 0;
    std::shared_ptr<const PreparedVolume> volume;
  };
  std::vector<Entry> entries_;  // most recently used last
  std::size_t prepared_ = 0;
};

}  // namespace cv::core
