// The viewer's camera-path editing (see keyframes.hpp).
#include "viewer/keyframes.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "geo/geodesy.hpp"

namespace cv::viewer {
namespace {

bool valid_index(const core::Scene& scene, int i) {
  return scene.path && i >= 0 && i < static_cast<int>(scene.path->keyframes.size());
}

}  // namespace

void add_keyframe(core::Scene& scene, KeyframeEditor& ed, const core::Camera& cam, const std::string& valid_utc, double spacing_s) {
  if (!scene.path) scene.path = core::CameraPath{};
  auto& keys = scene.path->keyframes;
  core::PathKeyframe k;
  k.t_s = keys.empty() ? 0.0 : keys.back().t_s + spacing_s;
  k.lat_deg = cam.lat_deg, k.lon_deg = cam.lon_deg, k.alt_m = cam.alt_m;
  k.heading_deg = cam.heading_deg, k.pitch_deg = cam.pitch_deg, k.fov_deg = cam.fov_deg;
  // With a rate rule only the first keyframe gives the weather time.
  k.valid_utc = scene.path->weather_hours_per_s != 0.0 && !keys.empty() ? "" : valid_utc;
  keys.push_back(k);
  ed.selected = static_cast<int>(keys.size()) - 1;
  ed.message.clear();
}

void delete_keyframe(core::Scene& scene, KeyframeEditor& ed) {
  if (!valid_index(scene, ed.selected)) return;
  auto& keys = scene.path->keyframes;
  keys.erase(keys.begin() + ed.selected);
  if (keys.empty()) {
    scene.path.reset();
    ed.selected = -1;
    ed.previewing = false;
  } else {
    ed.selected = std::min(ed.selected, static_cast<int>(keys.size()) - 1);
  }
  ed.message.clear();
}

void move_keyframe(core::Scene& scene, KeyframeEditor& ed, int delta) {
  const int j = ed.selected + delta;
  if (!valid_index(scene, ed.selected) || !valid_index(scene, j)) return;
  auto& keys = scene.path->keyframes;
  std::swap(keys[static_cast<std::size_t>(ed.selected)], keys[static_cast<std::size_t>(j)]);
  std::swap(keys[static_cast<std::size_t>(ed.selected)].t_s, keys[static_cast<std::size_t>(j)].t_s);  // the times stay in their slots
  ed.selected = j;
  ed.message.clear();
}

bool set_keyframe_time(core::Scene& scene, KeyframeEditor& ed, double t_s) {
  if (!valid_index(scene, ed.selected)) return false;
  auto& keys = scene.path->keyframes;
  const std::size_t i = static_cast<std::size_t>(ed.selected);
  const bool after = i == 0 || t_s > keys[i - 1].t_s;
  const bool before = i + 1 == keys.size() || t_s < keys[i + 1].t_s;
  if (!std::isfinite(t_s) || !after || !before) {
    char text[200];
    std::snprintf(text, sizeof text, "keyframe %zu: path time %g s refused, expected a time between its neighbours' (%s..%s)", i, t_s,
                  i == 0 ? "-inf" : std::to_string(keys[i - 1].t_s).c_str(),
                  i + 1 == keys.size() ? "+inf" : std::to_string(keys[i + 1].t_s).c_str());
    ed.message = text;
    return false;
  }
  keys[i].t_s = t_s;
  ed.message.clear();
  return true;
}

std::string path_problem(const core::Scene& scene) {
  if (!scene.path || scene.path->keyframes.size() < 2) {
    const std::size_t n = scene.path ? scene.path->keyframes.size() : 0;
    return "the path has " + std::to_string(n) + " keyframe" + (n == 1 ? "" : "s") + ", expected at least two";
  }
  try {
    core::PathEvaluator check(*scene.path);
  } catch (const core::PathError& e) {
    return std::string("path.") + e.what();
  }
  return "";
}

std::optional<core::Scene> preview_step(const core::Scene& scene, KeyframeEditor& ed, double dt_s) {
  if (!path_problem(scene).empty()) return std::nullopt;
  const core::PathEvaluator path(*scene.path);
  double t = ed.preview_t_s + dt_s;
  if (!(t >= path.start_s()) || t > path.end_s()) t = t > path.end_s() ? path.start_s() : std::clamp(t, path.start_s(), path.end_s());
  ed.preview_t_s = t;
  return core::scene_at_path_time(scene, path, t);
}

core::OverlayMesh path_mesh(const core::Scene& scene, double r0_m, double sample_s) {
  core::OverlayMesh m;
  if (!path_problem(scene).empty()) return m;
  const core::PathEvaluator path(*scene.path);
  const glm::vec4 track(1.0f, 0.55f, 0.1f, 1.0f), tick(1.0f, 1.0f, 1.0f, 1.0f);
  const int n = std::max(2, static_cast<int>(std::ceil(path.duration_s() / sample_s)) + 1);
  for (int k = 0; k < n; ++k) {
    const core::Camera c = path.at(path.start_s() + path.duration_s() * k / (n - 1)).camera;
    m.positions.push_back(core::camera_ecef(c, r0_m));
    m.colors.push_back(track);
    if (k > 0) m.lines.insert(m.lines.end(), {static_cast<std::uint32_t>(k - 1), static_cast<std::uint32_t>(k)});
  }
  for (const core::PathKeyframe& key : scene.path->keyframes) {
    const std::uint32_t base = static_cast<std::uint32_t>(m.positions.size());
    m.positions.push_back(geo::sphere_to_ecef({key.lat_deg, key.lon_deg, 0.0}, r0_m));
    m.positions.push_back(geo::sphere_to_ecef({key.lat_deg, key.lon_deg, key.alt_m}, r0_m));
    m.colors.insert(m.colors.end(), {tick, tick});
    m.lines.insert(m.lines.end(), {base, base + 1});
  }
  return m;
}

std::string record_command(const std::string& scene_path, const core::Scene& scene) {
  std::string video = scene_path;
  const std::size_t dot = video.rfind('.');
  const std::size_t slash = video.rfind('/');
  if (dot != std::string::npos && (slash == std::string::npos || dot > slash)) video.resize(dot);
  // record wants even sides (yuv420p).
  const int w = std::max(2, scene.width / 2 * 2), h = std::max(2, scene.height / 2 * 2);
  return "cloudviewer record " + scene_path + " -o " + video + ".mp4 --fps 30 --size " + std::to_string(w) + "x" + std::to_string(h);
}

}  // namespace cv::viewer
