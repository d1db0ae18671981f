// bench_reprojection: the viewer's temporal reprojection on a file at a size, the camera orbiting as
// `view --orbit PX` drags it: per frame the sparse march and the resolve (ms), against a full march
// of the same camera (ms), and the reprojected frames' error against the full marches (mean and
// 99th percentile of |dL| / the first frame's brightest), with the clamp, without it and without the
// history. With --play MIN, time advances MIN minutes a frame from the first step (the volumes
// as the viewer prepares them), and the history moved with the wind is measured against the history
// that stays where it is (the modelled cloud's detail drift, or in the data mode the advected
// medium's flow); --modelled draws the modelled cloud, whose detail the wind carries;
// --above M looks straight down on the grid's centre from M metres instead of the automatic camera.
// Not a test: docs/BENCHMARKS.md records what it prints.
//   bench_reprojection FILE [WxH] [FRAMES] [PX] [QUALITY] [--modelled] [--play MIN] [--above M]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "importer.hpp"
#include "kernel/volume_cache.hpp"
#include "render/context.hpp"
#include "render/frame_renderer.hpp"
#include "scene/quality.hpp"
#include "support/reprojection_sequence.hpp"
#include "viewer/camera_controller.hpp"

int main(int argc, char** argv) {
  using namespace cv;
  const char* usage = "usage: bench_reprojection FILE [WxH] [FRAMES] [PX] [QUALITY] [--modelled] [--play MIN] [--above M]\n";
  std::vector<std::string> pos;
  bool modelled = false;
  double play_min = 0.0, above_m = 0.0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::printf("%s", usage);
      return 0;
    } else if (a == "--modelled") {
      modelled = true;
    } else if (a == "--play" && i + 1 < argc) {
      play_min = std::atof(argv[++i]);
      if (!(play_min > 0.0)) {
        std::fprintf(stderr, "bench_reprojection: --play: found '%s', expected minutes > 0\n", argv[i]);
        return 2;
      }
    } else if (a == "--above" && i + 1 < argc) {
      above_m = std::atof(argv[++i]);
      if (!(above_m > 0.0)) {
        std::fprintf(stderr, "bench_reprojection: --above: found '%s', expected metres > 0\n", argv[i]);
        return 2;
      }
    } else {
      pos.push_back(a);
    }
  }
  if (pos.empty() || pos.size() > 5) {
    std::fprintf(stderr, "%s", usage);
    return 2;
  }
  int w = 640, h = 360;
  if (pos.size() > 1 && std::sscanf(pos[1].c_str(), "%dx%d", &w, &h) != 2) {
    std::fprintf(stderr, "bench_reprojection: size: found '%s', expected WxH\n", pos[1].c_str());
    return 2;
  }
  const int frames = pos.size() > 2 ? std::atoi(pos[2].c_str()) : 48;
  const double px = pos.size() > 3 ? std::atof(pos[3].c_str()) : 4.0;
  const std::string quality = pos.size() > 4 ? pos[4] : "default";
  const std::string path = pos[0];
  auto ctx = render::make_headless_context();
  core::CloudVolume vol = importers::import_file(path);
  core::Scene scene;
  scene.data.path = path;
  scene.width = render::Reprojector::whole_blocks(w), scene.height = render::Reprojector::whole_blocks(h);
  scene.sun.mode = core::SunMode::LocalNoon;
  core::apply_quality(quality, scene.render);
  scene.render.march.medium.modelled = modelled;
  const render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  render::FrameRenderer fr(loader);
  // Playing: the instants from the first step on, MIN minutes apart, prepared as the viewer does.
  core::PreparedVolumeCache cache;
  const std::size_t first = 0;
  const core::Instant start = core::instant_at_step(vol.times, first, path);
  auto volume_at = [&](int k) {
    if (play_min <= 0.0 || !start.time_known) return cache.get(path, vol, first, modelled);
    const std::int64_t t = start.unix_s + static_cast<std::int64_t>(k * play_min * 60.0);
    const core::Instant at = core::instant_at_time(vol.times, core::format_iso_utc(t), path);
    return cache.get(path, vol, at, scene.time.interpolation, nullptr, modelled);
  };
  if (play_min > 0.0 && !start.time_known) std::printf("  (the file has no UTC times: --play cannot advance time)\n");
  fr.use_volume(volume_at(0));
  if (play_min > 0.0) {  // the wind's motion between the first two frames, at the level that moves most
    const auto v0 = volume_at(0), v1 = volume_at(1);
    const std::vector<float> m = render::Reprojector::wind_motion_deg(v0->grid, v0->extinction.detail_drift_cells, v1->grid,
                                                                      v1->extinction.detail_drift_cells);
    double most = 0.0;
    for (std::size_t k = 0; k + 1 < m.size(); k += 2) most = std::max(most, std::hypot(double(m[k]), double(m[k + 1])));
    if (!m.empty()) {
      std::printf("  the wind's motion a frame: up to %.4f degrees (the detail's drift, %zu levels)\n", most, m.size() / 2);
    } else if (!v1->flow.empty()) {  // the data mode, advected: the flow times the time between the media
      const double dt = v1->time_s - v0->time_s;
      for (std::size_t k = 0; k + 1 < v1->flow.deg_per_s.size(); k += 2)
        most = std::max(most, std::hypot(double(v1->flow.deg_per_s[k]), double(v1->flow.deg_per_s[k + 1])) * std::abs(dt));
      std::printf("  the wind's motion a frame: up to %.4f degrees (the advected medium's flow, %d x %d x %d nodes)\n", most,
                  v1->flow.lon_deg.count, v1->flow.lat_deg.count, v1->flow.levels);
    } else {
      std::printf("  the wind's motion a frame: none (the media carry neither a drift nor an advected flow)\n");
    }
  }
  scene.time_step = static_cast<int>(first);
  core::FrameSpec base = render::resolve_frame(scene, vol);
  if (above_m > 0.0) {
    base.camera.lat_deg = vol.grid.lat_deg.at(vol.grid.lat_deg.count / 2);
    base.camera.lon_deg = vol.grid.lon_deg.at(vol.grid.lon_deg.count / 2);
    base.camera.alt_m = above_m;
    base.camera.heading_deg = 0.0, base.camera.pitch_deg = -90.0;
    base.march_camera = base.camera;
  }
  const double r0 = vol.grid.earth_radius_m;
  auto orbit = [&](core::Camera& c) { viewer::orbit(c, px, 0.0, r0); };
  render::Reprojector rp(loader);
  // The full march's time per frame, as the viewer without reprojection pays it.
  std::vector<double> full_ms;
  {
    core::FrameSpec f = base;
    f.march_camera = f.camera;
    f.accumulate = 1;
    GLuint target = 0;
    glCreateTextures(GL_TEXTURE_2D, 1, &target);
    glTextureStorage2D(target, 1, GL_RGBA32F, f.camera.width, f.camera.height);
    for (int k = 0; k < 4; ++k) {
      glFinish();
      const auto t0 = std::chrono::steady_clock::now();
      fr.march_into(target, f, 0);
      glFinish();
      if (k > 0) full_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    }
    glDeleteTextures(1, &target);
  }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
  };
  std::printf("%s at %dx%d, quality %s, cloud model %s, the camera orbiting %.1f px per frame, time %.1f min per frame from %s, %d "
              "frames (measured from frame 16):\n",
              path.c_str(), base.camera.width, base.camera.height, quality.c_str(), modelled ? "modelled" : "data", px, play_min,
              start.iso_utc.c_str(), frames);
  std::printf("  full march: %.1f ms per frame (median of 3)\n", median(full_ms));
  // Each frame's medium: the next instant when playing (a change of the medium, as the viewer says).
  auto before = [&](int k) {
    if (play_min <= 0.0) return false;
    fr.use_volume(volume_at(k));
    return k > 0;
  };
  std::vector<test_support::Mode> modes = {test_support::Mode::Reproject, test_support::Mode::NoClamp, test_support::Mode::SpatialOnly};
  if (play_min > 0.0) modes.insert(modes.begin() + 1, test_support::Mode::NoWind);
  for (test_support::Mode mode : modes) {
    std::vector<double> times;
    const test_support::Errors e = test_support::run_sequence(fr, rp, base, r0, frames, 16, orbit, mode, before, &times);
    std::vector<double> later(times.begin() + std::min<std::ptrdiff_t>(1, static_cast<std::ptrdiff_t>(times.size())), times.end());
    std::printf("  %-40s sparse march + resolve %.1f ms per frame (median), error mean %.4f, 99th percentile %.4f\n",
                mode == test_support::Mode::Reproject  ? "reprojected (clamp after a move):"
                : mode == test_support::Mode::NoClamp ? "reprojected without the clamp:"
                : mode == test_support::Mode::NoWind  ? "reprojected, history not moved by wind:"
                                                       : "the new samples' blend alone:",
                median(later), e.mean(), e.p99());
  }
  return 0;
}
