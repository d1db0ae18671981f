// Prepared time steps kept resident: the last two used (a frame between two forecast steps needs
// both), each built once from its volume's data.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "kernel/detail_drift.hpp"
#include "kernel/prepared_volume.hpp"
#include "scene/instant.hpp"
#include "volume/cloud_volume.hpp"
#include "volume/time_interpolation.hpp"

namespace cv::core {

// The last two steps' grid-mean extinction and winds, for the instants between them (and the next
// pair, which shares one): derived once per step, not once per instant (a global 0.25-degree step's
// took 4-6 s).
struct StepMedium {
  std::size_t step = 0;
  GridMeanExtinction medium;
  StepWinds winds;  // empty unless asked for
  bool has_winds = false;
};
class StepMediaCache {
 public:
  // Step `step` of `volume` (named by `source`), with its winds where `winds`: from the cache or
  // derived now. Another volume or source empties the cache first.
  std::shared_ptr<const StepMedium> get(const std::string& source, CloudVolume& volume, std::size_t step, bool winds);
  // The memory of the media held.
  std::size_t bytes() const;

 private:
  std::string source_;
  const CloudVolume* volume_ = nullptr;
  std::vector<std::shared_ptr<const StepMedium>> media_;  // most recently used last
};

class PreparedVolumeCache {
 public:
  static constexpr std::size_t kResident = 2;
  // The prepared time step `step` of `volume`, whose data are named by `source` (a file path):
  // from the cache, or prepared now (evicting the least recently used beyond kResident). With
  // `detail_drift` (the modelled cloud), the volume has its weather textures and the medium carries
  // the detail's wind displacement at the step (DetailDrift: the winds of the steps before it are
  // read once).
  std::shared_ptr<const PreparedVolume> get(const std::string& source, CloudVolume& volume, std::size_t step,
                                            bool detail_drift = false);
  // The medium at an instant: the step itself at a step, else the two neighbouring steps'
  // extinction interpolated (interpolate_extinction) and prepared, once per instant and mode.
  // `report` receives what the interpolation did (its cost, or 0 when it came from the cache).
  // `volume` must keep at least two steps decoded (CloudVolume::set_loader's cache_steps).
  std::shared_ptr<const PreparedVolume> get(const std::string& source, CloudVolume& volume, const Instant& at,
                                            TimeInterpolation mode, TimeInterpolationReport* report = nullptr,
                                            bool detail_drift = false);
  // How many preparations get has run: a test of the cache, and what the viewer's overlay reports.
  std::size_t prepared() const { return prepared_; }

 private:
  struct Entry {
    std::string source;
    std::size_t step = 0;
    // Between steps: the later step, the fraction and the mode asked for (step1 == step: a step).
    std::size_t step1 = 0;
    double fraction = 0.0;
    TimeInterpolation mode = TimeInterpolation::Auto;
    bool drift = false;
    TimeInterpolationReport report;
    std::shared_ptr<const PreparedVolume> volume;
  };
  std::vector<Entry> entries_;  // most recently used last
  std::size_t prepared_ = 0;
  DetailDrift drift_;
  StepMediaCache media_;
};

}  // namespace cv::core
