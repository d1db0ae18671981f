// The cache of prepared time steps.
#include "kernel/volume_cache.hpp"

#include <algorithm>

namespace cv::core {

std::shared_ptr<const PreparedVolume> PreparedVolumeCache::get(const std::string& source, CloudVolume& volume, std::size_t step) {
  const auto it = std::find_if(entries_.begin(), entries_.end(), [&](const Entry& e) { return e.source == source && e.step == step; });
  if (it != entries_.end()) {
    Entry e = *it;
    entries_.erase(it);
    entries_.push_back(e);
    return e.volume;
  }
  auto v = std::make_shared<const PreparedVolume>(prepare_volume(volume.grid, volume.step(step)));
  ++prepared_;
  entries_.push_back({source, step, v});
  if (entries_.size() > kResident) entries_.erase(entries_.begin());
  return v;
}

}  // namespace cv::core
