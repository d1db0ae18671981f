// Playing a forecast in the viewer: the playhead (play/pause, loop, speed in forecast hours per
// second, step forward and back, scrubbing) on a grid of instants, and a prefetcher that prepares
// the instants playback will need on its own thread, from its own copy of the data, with a bound on
// how many stay resident.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "frame/camera.hpp"
#include "kernel/detail_drift.hpp"
#include "kernel/prepared_volume.hpp"
#include "kernel/volume_cache.hpp"
#include "scene/scene.hpp"
#include "volume/cloud_volume.hpp"
#include "volume/time_interpolation.hpp"

namespace cv::viewer {

// The playhead over a file's times [first_s, last_s]. Instants shown are on a grid of quantum_s
// (the file's first gap / frames_per_step), so prefetching knows them in advance.
struct Playhead {
  double first_s = 0.0, last_s = 0.0;
  double quantum_s = 3600.0;
  double t_s = 0.0;               // where the playhead is (continuous)
  bool playing = false, loop = true;
  double speed_h_per_s = 1.0;     // forecast hours per second of wall time
  int frames_per_step = 8;

  // Sets the span and the grid from the file's times (one step: a still, never playing).
  void reset(const std::vector<core::ValidTime>& times);
  // The instant shown: t_s on the grid.
  std::int64_t shown() const;
  // Moves on by `wall_s` of wall time (when playing): stops at the end, or goes back to the start on loop.
  void advance(double wall_s);
  // Moves on by one instant of the grid (the --frames mode: one per frame, independent of wall time).
  void advance_one();
  // To the previous / next step of the file (dir -1 / +1) from the playhead.
  void step(const std::vector<core::ValidTime>& times, int dir);
  // The next `n` instants after the shown one, as playback will need them (wrapping on loop).
  std::vector<std::int64_t> upcoming(int n) const;
  bool still() const { return last_s <= first_s; }
};

// The automatic exposure held while a forecast plays: the least of the frames' own exposures since
// play began, frames with no lit pixel left out (a sequence is exposed for its brightest frame, as
// `render --times` and `record` take it). Frame by frame, the exposure lifted a fading afternoon back
// to noon's brightness and a dawn's first light to white; held, the day's light is seen to change.
// The viewer starts a new hold when play starts and when anything but the time changes.
struct ExposureHold {
  std::optional<double> least;
  // The exposure to show, given this frame's own (nullopt: nothing lit) and `fallback` for when no
  // frame of the hold was lit yet.
  double update(std::optional<double> own, double fallback) {
    if (own && (!least || *own < *least)) least = own;
    return least.value_or(fallback);
  }
  void reset() { least.reset(); }
};

struct PrefetchStats {
  std::size_t resident = 0;        // prepared instants held
  std::size_t resident_bytes = 0;  // their memory
  std::size_t max_resident = 0;    // the bound in instants (lowered to fit the bound in bytes)
  std::size_t held_bytes = 0;      // what the worker holds besides them (decoded steps, their media), at the last instant
  std::size_t hits = 0, misses = 0;  // instants found ready / not ready when shown
  std::size_t prepared = 0;          // instants the worker prepared
  double last_prepare_ms = 0.0;      // the last instant's preparation, its source included
  std::size_t sources = 0;           // two-stream sources the worker built ahead
  double last_source_ms = 0.0;       // the last one's build
};

// The longitude where the camera's centre ray meets the sphere of radius r0_m (the camera's own
// longitude when it looks past the Earth), and the local apparent solar time there at unix_s, in
// hours 0..24 (12 + the hour angle from the subsolar point).
double view_centre_lon_deg(const core::Camera& cam, double r0_m);
double local_solar_time_h(double lon_deg, std::int64_t unix_s);

// Bytes a prepared instant holds (extinction, pyramid, column depths).
std::size_t prepared_bytes(const core::PreparedVolume& v);

class Prefetcher {
 public:
  // Opens its own copy of the scene's data (the viewer's CloudVolume stays on the render thread).
  // At most max_resident instants stay prepared, and fewer (never under 2) where that many would
  // hold more than max_bytes (0: a quarter of the machine's memory) less what the worker holds
  // besides them (its decoded steps and their media and winds), as measured when each instant is
  // prepared: a global 0.25-degree instant with its two-stream source holds about 0.8 GB, the two
  // steps and their media about 5 GB by their arrays' sizes.
  Prefetcher(const core::Scene& scene, std::size_t max_resident, std::size_t max_bytes = 0);
  ~Prefetcher();
  Prefetcher(const Prefetcher&) = delete;
  Prefetcher& operator=(const Prefetcher&) = delete;

  // The instants wanted, most urgent first; those beyond max_resident are ignored. Resident instants
  // not wanted are evicted as room is needed. `detail_drift`: the media carry the modelled cloud's
  // wind displacement (core::DetailDrift). `source_scene` (the scene shown; null: none): where its
  // march uses the two-stream source, each instant prepared from now on carries the source for the
  // sun at that instant and the scene's medium (PreparedVolume::ms_prebuilt), built on the worker's
  // thread, so the render thread does not build it while the forecast plays. A scene changed since
  // (another sun mode, droplet size or layer mask) only makes the render thread build its own.
  void want(const std::vector<std::int64_t>& instants, core::TimeInterpolation mode, bool detail_drift = false,
            const core::Scene* source_scene = nullptr);
  // The prepared instant if ready (counted as a hit), else nullptr (a miss). `wait`: block until ready.
  std::shared_ptr<const core::PreparedVolume> get(std::int64_t t, bool wait, core::TimeInterpolationReport* report = nullptr);
  PrefetchStats stats() const;
  std::string error() const;  // the worker's last error (a time outside the file), or empty

 private:
  struct Ready {
    std::shared_ptr<const core::PreparedVolume> volume;
    core::TimeInterpolationReport report;
  };
  void run();
  core::Scene scene_;
  core::CloudVolume volume_;
  std::size_t max_resident_;  // the bound in instants, lowered to fit max_bytes_ once an instant is measured
  std::size_t max_bytes_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<std::int64_t> wanted_;
  core::TimeInterpolation mode_ = core::TimeInterpolation::Auto;
  bool drift_ = false;
  std::shared_ptr<const core::Scene> source_scene_;  // the scene the sources are built for (null: none)
  core::DetailDrift detail_drift_;  // the worker's alone
  core::StepMediaCache media_;     // the worker's alone: the last two steps' media and winds
  std::map<std::int64_t, Ready> ready_;
  PrefetchStats stats_;
  std::string error_;
  bool stop_ = false;
  std::thread worker_;
};

}  // namespace cv::viewer
