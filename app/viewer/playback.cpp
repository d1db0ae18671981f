// The viewer's playhead and prefetcher.
#include "viewer/playback.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include <unistd.h>

#include "geo/geodesy.hpp"
#include "geo/solar.hpp"
#include "kernel/ms_source.hpp"
#include "render/albedo_map.hpp"
#include "render/frame_renderer.hpp"
#include "scene/frame_spec.hpp"
#include "scene/instant.hpp"
#include "scene_source.hpp"
#include "volume/grid_mean.hpp"

namespace cv::viewer {

void Playhead::reset(const std::vector<core::ValidTime>& times) {
  first_s = times.empty() ? 0.0 : double(times.front().unix_s);
  last_s = times.empty() ? 0.0 : double(times.back().unix_s);
  const double gap = times.size() > 1 ? double(times[1].unix_s - times[0].unix_s) : 3600.0;
  quantum_s = std::max(1.0, gap / std::max(1, frames_per_step));
  t_s = std::clamp(t_s, first_s, last_s);
  if (still()) playing = false;
}

std::int64_t Playhead::shown() const {
  const double k = std::round((t_s - first_s) / quantum_s);
  return static_cast<std::int64_t>(std::llround(std::min(last_s, first_s + k * quantum_s)));
}

void Playhead::advance(double wall_s) {
  if (!playing || still()) return;
  t_s += wall_s * speed_h_per_s * 3600.0;
  if (t_s > last_s) {
    if (loop) t_s = first_s + std::fmod(t_s - first_s, last_s - first_s + quantum_s);
    else t_s = last_s, playing = false;
  }
  if (t_s > last_s) t_s = last_s;
}

void Playhead::advance_one() {
  if (!playing || still()) return;
  const double next = double(shown()) + quantum_s;
  if (next > last_s + 0.5) {
    if (loop) t_s = first_s;
    else t_s = last_s, playing = false;
  } else {
    t_s = next;
  }
}

void Playhead::step(const std::vector<core::ValidTime>& times, int dir) {
  if (times.empty()) return;
  const double now = double(shown());
  if (dir > 0) {
    for (const auto& v : times)
      if (double(v.unix_s) > now + 0.5) {
        t_s = double(v.unix_s);
        return;
      }
    t_s = loop ? first_s : last_s;
  } else {
    for (auto it = times.rbegin(); it != times.rend(); ++it)
      if (double(it->unix_s) < now - 0.5) {
        t_s = double(it->unix_s);
        return;
      }
    t_s = loop ? last_s : first_s;
  }
}

std::vector<std::int64_t> Playhead::upcoming(int n) const {
  std::vector<std::int64_t> out;
  double t = double(shown());
  for (int i = 0; i < n && !still(); ++i) {
    t += quantum_s;
    if (t > last_s + 0.5) {
      if (!loop) break;
      t = first_s;
    }
    out.push_back(static_cast<std::int64_t>(std::llround(t)));
  }
  return out;
}

double view_centre_lon_deg(const core::Camera& cam, double r0_m) {
  const glm::dvec3 o = geo::sphere_to_ecef({cam.lat_deg, cam.lon_deg, cam.alt_m}, r0_m);
  const glm::dvec3 d = glm::normalize(core::camera_frame(cam).forward);
  const double b = glm::dot(o, d), c = glm::dot(o, o) - r0_m * r0_m;
  const double disc = b * b - c;
  if (disc < 0.0 || -b - std::sqrt(disc) < 0.0) return cam.lon_deg;
  return geo::ecef_to_sphere(o + (-b - std::sqrt(disc)) * d, r0_m).lon_deg;
}

double local_solar_time_h(double lon_deg, std::int64_t unix_s) {
  const double h = 12.0 + (lon_deg - geo::subsolar_point(unix_s).lon_deg) / 15.0;
  return h - 24.0 * std::floor(h / 24.0);
}

std::size_t prepared_bytes(const core::PreparedVolume& v) {
  const std::size_t source = v.ms_prebuilt ? v.ms_prebuilt->source.i0.size() + v.ms_prebuilt->source.i1.size() +
                                                  v.ms_prebuilt->source.i1e.size() + v.ms_prebuilt->source.i1n.size()
                                            : 0;
  return (v.extinction.liquid_per_m.size() + v.extinction.ice_per_m.size() + v.columns.tau.size() + source) * sizeof(float) +
         v.pyramid_packed.size() * sizeof(glm::vec2);
}

namespace {
std::size_t quarter_of_memory() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? static_cast<std::size_t>(pages) * static_cast<std::size_t>(page) / 4 : std::size_t(4) << 30;
}
}  // namespace

Prefetcher::Prefetcher(const core::Scene& scene, std::size_t max_resident, std::size_t max_bytes)
    : scene_(scene), volume_(importers::load_scene_volume(scene, 2)), max_resident_(std::max<std::size_t>(1, max_resident)),
      max_bytes_(max_bytes ? max_bytes : quarter_of_memory()) {
  stats_.max_resident = max_resident_;
  worker_ = std::thread([this] { run(); });
}

Prefetcher::~Prefetcher() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  worker_.join();
}

void Prefetcher::want(const std::vector<std::int64_t>& instants, core::TimeInterpolation mode, bool detail_drift,
                      const core::Scene* source_scene) {
  // The scene copied outside the lock (the worker copies the pointer only).
  std::shared_ptr<const core::Scene> scene =
      source_scene && source_scene->render.march.medium.ms_two_stream ? std::make_shared<const core::Scene>(*source_scene) : nullptr;
  std::lock_guard<std::mutex> lock(mutex_);
  source_scene_ = std::move(scene);
  if (mode != mode_ || detail_drift != drift_) ready_.clear();  // prepared for another mode: not what is shown now
  mode_ = mode;
  drift_ = detail_drift;
  wanted_.assign(instants.begin(), instants.begin() + static_cast<std::ptrdiff_t>(std::min(instants.size(), max_resident_)));
  changed_.notify_all();
}

std::shared_ptr<const core::PreparedVolume> Prefetcher::get(std::int64_t t, bool wait, core::TimeInterpolationReport* report) {
  std::unique_lock<std::mutex> lock(mutex_);
  if (wait) changed_.wait(lock, [&] { return ready_.count(t) || !error_.empty() || stop_; });
  const auto it = ready_.find(t);
  if (it == ready_.end()) {
    ++stats_.misses;
    return nullptr;
  }
  ++stats_.hits;
  if (report) *report = it->second.report;
  return it->second.volume;
}

PrefetchStats Prefetcher::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  PrefetchStats s = stats_;
  s.resident = ready_.size();
  s.resident_bytes = 0;
  for (const auto& [t, r] : ready_) s.resident_bytes += prepared_bytes(*r.volume);
  return s;
}

std::string Prefetcher::error() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return error_;
}

void Prefetcher::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stop_) {
    // The most urgent wanted instant not ready yet.
    std::int64_t todo = 0;
    bool found = false;
    for (std::int64_t t : wanted_)
      if (!ready_.count(t)) {
        todo = t, found = true;
        break;
      }
    if (!found) {
      changed_.wait(lock);
      continue;
    }
    const core::TimeInterpolation mode = mode_;
    const bool drift = drift_;
    const std::shared_ptr<const core::Scene> source_scene = source_scene_;
    lock.unlock();
    Ready r;
    std::string error;
    double source_ms = -1.0;
    const auto t0 = std::chrono::steady_clock::now();
    try {
      const core::Instant at = core::instant_at_time(volume_.times, core::format_iso_utc(todo), scene_.data.path);
      std::vector<double> d = drift ? detail_drift_.at(volume_, at) : std::vector<double>{};  // may load earlier steps: first
      core::GridMeanExtinction e0;
      if (at.between()) {
        const std::shared_ptr<const core::StepMedium> m0 = media_.get(scene_.data.path, volume_, at.step0, true);
        const std::shared_ptr<const core::StepMedium> m1 = media_.get(scene_.data.path, volume_, at.step1, true);
        e0 = core::interpolate_extinction(volume_.grid, m0->medium, m1->medium, m0->winds, m1->winds, at.gap_s, at.fraction, mode,
                                          &r.report);
      } else {
        e0 = media_.get(scene_.data.path, volume_, at.step0, false)->medium;
      }
      e0.detail_drift_cells = std::move(d);
      auto prepared = std::make_shared<core::PreparedVolume>(core::prepare_volume(volume_.grid, std::move(e0), drift));  // the weather textures for the modelled cloud only
      if (source_scene) {
        try {
          // The two-stream source for the sun at this instant, with the key the render thread's march
          // will ask for: the scene resolved at the instant as the viewer resolves it. A scene that
          // does not resolve (a sun being typed) leaves the source to the render thread.
          core::Scene at_instant = *source_scene;
          at_instant.time.valid_utc = core::format_iso_utc(todo);
          const core::FrameSpec spec = render::resolve_frame(at_instant, volume_);  // the ground texture resolved as the renderer has it
          auto pre = std::make_shared<core::PrebuiltMsSource>();
          // The ground map the renderer draws (shared: loaded once), so the key is the one it asks for.
          std::shared_ptr<const core::AlbedoMap> ground;
          if (spec.march.features.globe && !spec.march.medium.ground_texture.empty()) {
            try {
              ground = render::shared_albedo_map(spec.march.medium.ground_texture, spec.march.medium.ground_map_colours);
            } catch (const std::exception&) {  // the render thread says what is wrong with the image
            }
          }
          pre->key = core::ms_source_key(spec.march, core::march_params(*prepared, spec.march_camera, spec.sun, spec.march).u_to_sun,
                                         ground.get());
          pre->ground = ground;
          pre->source = core::build_ms_source(*prepared, pre->key);
          source_ms = pre->source.build_ms;
          prepared->ms_prebuilt = std::move(pre);
        } catch (const std::invalid_argument&) {
        }
      }
      r.volume = std::move(prepared);
    } catch (const std::exception& e) {
      error = e.what();
    }
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const std::size_t held = volume_.resident_bytes() + media_.bytes();  // the worker's alone: read unlocked
    lock.lock();
    if (!error.empty()) {
      error_ = error;
      wanted_.erase(std::remove(wanted_.begin(), wanted_.end(), todo), wanted_.end());
      changed_.notify_all();
      continue;
    }
    if (mode != mode_ || drift != drift_) continue;  // the mode changed meanwhile
    // Room: evict what is no longer wanted (oldest instants first), never beyond the bound.
    while (ready_.size() >= max_resident_) {
      auto victim = ready_.end();
      for (auto it = ready_.begin(); it != ready_.end(); ++it)
        if (std::find(wanted_.begin(), wanted_.end(), it->first) == wanted_.end()) {
          victim = it;
          break;
        }
      if (victim == ready_.end()) victim = ready_.begin();
      ready_.erase(victim);
    }
    // The bound in bytes, in instants of this size, after what the worker holds besides them (its
    // steps and media, which grow from one step's to two as playback goes between steps): measured
    // at every instant, so the bound only falls; never under 2, so the next instant can be prepared
    // while one is shown.
    if (r.volume) {
      stats_.held_bytes = held;
      const std::size_t room = max_bytes_ > held ? max_bytes_ - held : 0;
      const std::size_t fits = std::max<std::size_t>(2, room / std::max<std::size_t>(1, prepared_bytes(*r.volume)));
      if (fits < max_resident_) {
        max_resident_ = stats_.max_resident = fits;
        if (wanted_.size() > fits) wanted_.resize(fits);
      }
    }
    ready_[todo] = std::move(r);
    ++stats_.prepared;
    stats_.last_prepare_ms = ms;
    if (source_ms >= 0.0) ++stats_.sources, stats_.last_source_ms = source_ms;
    changed_.notify_all();
  }
}

}  // namespace cv::viewer
