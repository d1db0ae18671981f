// The viewer's main loop: loading the input, the window and ImGui, mouse and keyboard navigation,
// the march -> accumulate -> tonemap path on the GPU with timer queries, and screenshots.
#include "viewer/viewer.hpp"

#include <imgui.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <climits>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <map>
#include <limits>
#include <memory>
#include <optional>

#include "importer.hpp"
#include "io/output_file.hpp"
#include "noise/noise.hpp"
#include "geo/geodesy.hpp"
#include "reference/earth_shadow.hpp"
#include "render/albedo_map.hpp"
#include "render/context.hpp"
#include "render/machine_id.hpp"
#include "render/image_output.hpp"
#include "render/presenter.hpp"
#include "render/reprojector.hpp"
#include "render/raymarcher.hpp"
#include "viewer/camera_controller.hpp"
#include "viewer/frame_budget.hpp"
#include "viewer/panels.hpp"
#include "scene/scene_json.hpp"
#include "scene_source.hpp"
#include "kernel/volume_cache.hpp"
#include "scene/instant.hpp"
#include "viewer/playback.hpp"
#include "viewer/probe_panel.hpp"
#include "viewer/view_compose.hpp"
#include "viewer/views.hpp"
#include "overlays/overlays.hpp"
#include "render/frame_renderer.hpp"
#include "scene/framing.hpp"
#include "scene/quality.hpp"
#include "scene/scene_json.hpp"
#include "volume/volume_io.hpp"

namespace cv::viewer {
namespace {
constexpr int kExitBadInput = 2;

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

int parse_int(const std::string& option, const std::string& text, int lo, int hi) {
  try {
    std::size_t used = 0;
    const long v = std::stol(text, &used);
    if (used == text.size() && v >= lo && v <= hi) return static_cast<int>(v);
  } catch (const std::exception&) {
  }
  throw ViewerInputError("cloudviewer view: " + option + ": found '" + text + "', expected an integer in " +
                         std::to_string(lo) + ".." + std::to_string(hi));
}

// GPU time of a pass, read a few frames later so the CPU never waits for the GPU.
class PassTimer {
 public:
  PassTimer() { glCreateQueries(GL_TIME_ELAPSED, kRing, ids_); }
  ~PassTimer() { glDeleteQueries(kRing, ids_); }
  PassTimer(const PassTimer&) = delete;
  PassTimer& operator=(const PassTimer&) = delete;
  void begin() { glBeginQuery(GL_TIME_ELAPSED, ids_[next_]); }
  void end() {
    glEndQuery(GL_TIME_ELAPSED);
    used_[next_] = true;
    next_ = (next_ + 1) % kRing;
    // The oldest query in the ring: read it if the GPU has finished it.
    const int old = next_;
    GLint ready = 0;
    if (used_[old]) glGetQueryObjectiv(ids_[old], GL_QUERY_RESULT_AVAILABLE, &ready);
    if (ready) {
      GLuint64 ns = 0;
      glGetQueryObjectui64v(ids_[old], GL_QUERY_RESULT, &ns);
      ms_ = static_cast<double>(ns) * 1e-6;
      used_[old] = false;
    }
  }
  // Waits for every pass still in flight and keeps the newest time (for the screenshot's report).
  void finish() {
    for (int k = 0; k < kRing; ++k) {
      const int q = (next_ + k) % kRing;  // oldest first
      if (!used_[q]) continue;
      GLuint64 ns = 0;
      glGetQueryObjectui64v(ids_[q], GL_QUERY_RESULT, &ns);
      ms_ = static_cast<double>(ns) * 1e-6;
      used_[q] = false;
    }
  }
  double ms() const { return ms_; }

 private:
  static constexpr int kRing = 4;
  GLuint ids_[kRing] = {};
  bool used_[kRing] = {};
  int next_ = 0;
  double ms_ = 0.0;
};

void save_screenshot(const std::string& path, int w, int h) {
  std::vector<unsigned char> rgb(static_cast<std::size_t>(w) * h * 3), flipped(rgb.size());
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_BACK);
  glReadPixels(0, 0, w, h, GL_RGB, GL_UNSIGNED_BYTE, rgb.data());
  render::check_gl("reading the window's framebuffer for the screenshot");
  const std::size_t row = static_cast<std::size_t>(w) * 3;
  for (int y = 0; y < h; ++y) std::copy_n(rgb.data() + (h - 1 - y) * row, row, flipped.data() + y * row);  // GL rows are bottom up
  render::write_png(path, w, h, flipped);
}

// Keyboard and mouse navigation of `cam` (the view the mouse is over, or the last one), unless ImGui
// wants them; `mouse` false: this frame's mouse is not for a view (the swipe divider is dragged).
void navigate(GLFWwindow* win, core::Camera& cam, double r0, bool fly_mode, bool mouse, double dt_s) {
  const ImGuiIO& io = ImGui::GetIO();
  if (!io.WantCaptureMouse && mouse) {
    const double dx = io.MouseDelta.x, dy = io.MouseDelta.y;
    const bool moved = dx != 0.0 || dy != 0.0;
    if (moved && io.MouseDown[0] && !fly_mode) orbit(cam, dx, dy, r0);
    else if (moved && (io.MouseDown[1] || (io.MouseDown[0] && fly_mode))) look(cam, dx, dy);
    if (io.MouseWheel != 0.0f) zoom(cam, io.MouseWheel, r0);
  }
  if (!io.WantCaptureKeyboard && fly_mode) {
    auto key = [&](int k) { return glfwGetKey(win, k) == GLFW_PRESS ? 1.0 : 0.0; };
    const glm::dvec3 dir(key(GLFW_KEY_W) - key(GLFW_KEY_S), key(GLFW_KEY_D) - key(GLFW_KEY_A), key(GLFW_KEY_E) - key(GLFW_KEY_Q));
    const double boost = key(GLFW_KEY_LEFT_SHIFT) > 0.0 ? 5.0 : 1.0;
    if (dir != glm::dvec3(0.0)) fly(cam, dir * boost, dt_s, r0);
  }
}

// One view's GPU side: its renderer (the prepared instant it shows, uploaded), its march and mean
// textures, its overlays, its accumulation and exposure, and this frame's resolved frame.
struct ViewGpu {
  explicit ViewGpu(const render::ShaderLoader& loader) : renderer(loader), presenter(loader) {}
  render::FrameRenderer renderer;
  render::Presenter presenter;
  overlays::OverlayBuilder overlay_builder;
  int accumulated = 0;
  bool marching = false;
  core::Scene previous;
  // The progressive path tracer's sums (one sample per pixel per frame), and whether the mean
  // shown is theirs.
  core::MonteCarloImage paths;
  bool path_mode = false;
  double auto_exposure = render::kDefaultExposure;
  // While the forecast plays: the exposure held over the frames since play began, and the scene it
  // was taken with (a change of anything but the time starts a new hold).
  ExposureHold exposure_hold;
  core::Scene hold_scene;
  core::FrameSpec spec;
  // Temporal reprojection (ViewerState::reproject): made when first used; the sparse frame's index,
  // and whether the medium or the settings changed this frame (the camera's motion it finds itself).
  std::unique_ptr<render::Reprojector> reprojector;
  bool reprojecting = false, reproject_changed = false;
  int reproject_index = 0;
};

// One more path-traced sample per pixel of the view's march camera into its sums, and their mean
// (radiance; alpha 0: no background shows through, as `render --quality reference` writes it) into
// the presenter's frame texture. The seed is `render`'s default, so after N frames the mean is
// `render --quality reference --spp N`'s image at the march size.
void trace_into(ViewGpu& v) {
  render::PathTraceSettings pt;
  pt.samples_per_readback = 1;
  v.renderer.trace_paths(v.paths, v.spec, 1, pt);
  const int w = v.spec.march_camera.width, h = v.spec.march_camera.height;
  std::vector<glm::vec4> mean(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
  for (std::size_t i = 0; i < mean.size(); ++i) mean[i] = glm::vec4(glm::vec3(v.paths.mean(i)), 0.0f);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glTextureSubImage2D(v.presenter.frame_texture(), 0, 0, 0, w, h, GL_RGBA, GL_FLOAT, mean.data());
}

// A view besides view 0 (issue 17): its scene holds its data, camera and time, and takes view 0's
// settings each frame; its volume is shared by the views of one source (view 0's own when the file
// is view 0's), and so is the prepared instant where two views show the same one.
struct ExtraView {
  core::Scene scene;
  core::CloudVolume* volume = nullptr;
  double view_step_ratio = 1.0;  // its grid's vertical spacing over view 0's: the view step scales with it
  std::shared_ptr<const core::PreparedVolume> prepared;
  std::string prepared_key;
  std::unique_ptr<ViewGpu> gpu;
};

// What identifies a prepared instant: the source, the instant (or the step) and how it was made.
std::string prepared_key(const std::string& source, const core::Instant& at, core::TimeInterpolation mode, bool drift) {
  return source + (at.time_known ? "@" + std::to_string(at.unix_s) : "#" + std::to_string(at.step0)) + "/" +
         std::to_string(static_cast<int>(mode)) + (drift ? "/drift" : "");
}

// A view's camera and time for the link: UTC seconds where the file has UTC valid times, else the step.
ViewCursor cursor_of(const core::Scene& sc, const core::CloudVolume& vol) {
  ViewCursor c;
  c.camera = *sc.camera;
  c.utc = core::times_known(vol.times);
  const std::size_t step = static_cast<std::size_t>(std::clamp(sc.time_step, 0, static_cast<int>(vol.times.size()) - 1));
  if (c.utc) {
    const std::optional<std::int64_t> t = sc.time.valid_utc.empty() ? std::nullopt : core::parse_iso_utc(sc.time.valid_utc);
    c.t = double(t ? *t : vol.times[step].unix_s);
    c.t_first = double(vol.times.front().unix_s), c.t_last = double(vol.times.back().unix_s);
  } else {
    c.t = double(step);
    c.t_first = 0.0, c.t_last = double(vol.times.size() - 1);
  }
  return c;
}

void set_time(core::Scene& sc, const ViewCursor& c) {
  if (c.utc) {
    sc.time.valid_utc = core::format_iso_utc(static_cast<std::int64_t>(std::llround(c.t)));
  } else {
    sc.time_step = static_cast<int>(std::lround(c.t));
    sc.time.valid_utc.clear();
  }
}

// The previous (dir -1) or next (+1) step of the file from time t (in the cursor's unit).
double step_from(const core::CloudVolume& vol, const ViewCursor& c, int dir) {
  if (!c.utc) return std::clamp(c.t + dir, c.t_first, c.t_last);
  double best = c.t;
  for (const core::ValidTime& v : vol.times) {
    const double t = double(v.unix_s);
    if (dir > 0 && t > c.t) return t;
    if (dir < 0 && t < c.t) best = t;
  }
  return best;
}

// A view's label: its file and its valid time.
std::string view_label(const core::Scene& sc, const core::CloudVolume& vol) {
  const ViewCursor c = cursor_of(sc, vol);
  const std::string name = std::filesystem::path(sc.data.path).filename().string();
  if (c.utc) return name + "  " + core::format_iso_utc(static_cast<std::int64_t>(std::llround(c.t)));
  const std::size_t step = static_cast<std::size_t>(c.t);
  return name + "  step " + std::to_string(step) + " (" + vol.times[step].iso_utc + ")";
}

// FILE[@TIME] or @TIME (view 0's file at another time) as a file and a time ("" where not given).
core::ViewSource parse_view_spec(const std::string& spec) {
  const std::size_t at = spec.rfind('@');
  if (at == std::string::npos) return {spec, ""};
  core::ViewSource v{spec.substr(0, at), spec.substr(at + 1)};
  if (v.time.empty()) v.time = "@";  // '@' with nothing after it: refused by open_view
  return v;
}

// The --compare text of a view source, for messages.
std::string view_spec_text(const core::ViewSource& v) { return v.path + (v.time.empty() ? "" : "@" + (v.time == "@" ? "" : v.time)); }

// Opens a view of a file (empty: view 0's) at a time (a step or a UTC time; empty: view 0's
// instant, held within the file's span, or view 0's step), or throws ViewerInputError with one line
// naming `option`, what was found and what was expected.
ExtraView open_view(const core::ViewSource& source, const std::string& option, ViewerState& s,
                    std::map<std::string, std::unique_ptr<core::CloudVolume>>& sources) {
  const std::string spec = view_spec_text(source);
  std::string file = source.path.empty() ? s.scene.data.path : source.path;
  const std::string time = source.time == "@" ? "" : source.time;
  const bool at_given = !source.time.empty();
  const std::string bad = "cloudviewer view: " + option + ": found '" + spec + "'";
  // Another name of a file already open (./a.nc, a link) is that file: its volume and instants are shared.
  if (file != s.scene.data.path && core::same_file(file, s.scene.data.path)) file = s.scene.data.path;
  for (const auto& [path, volume] : sources) {
    if (file != path && core::same_file(file, path)) file = path;
  }
  if (at_given && time.empty()) throw ViewerInputError(bad + ", expected a time after '@' (a step index or a UTC time)");
  ExtraView v;
  v.scene = s.scene;
  v.scene.data.path = file;
  v.scene.path.reset();
  if (file == s.scene.data.path) {
    v.volume = &s.volume;
  } else if (auto it = sources.find(file); it != sources.end()) {
    v.volume = it->second.get();
  } else {
    if (!std::filesystem::exists(file)) throw ViewerInputError(bad + ": " + file + " does not exist, expected a NetCDF file or a .cvvol volume");
    auto vol = std::make_unique<core::CloudVolume>();
    try {
      *vol = importers::load_scene_volume(v.scene, 2);
    } catch (const std::exception& e) {
      throw ViewerInputError(bad + ": " + file + " does not import (" + e.what() + "), expected a NetCDF file or a .cvvol volume");
    }
    const core::VolumeGrid& g = vol->grid;
    if (g.lon_deg.count < 2 || g.lat_deg.count < 2 || g.alt_m.count < 2 || vol->times.empty()) {
      throw ViewerInputError(bad + ": " + file + " holds " + std::to_string(g.lon_deg.count) + " x " + std::to_string(g.lat_deg.count) +
                             " x " + std::to_string(g.alt_m.count) + " points, expected at least 2 along each axis");
    }
    v.volume = vol.get();
    sources.emplace(file, std::move(vol));
  }
  const core::CloudVolume& vol = *v.volume;
  v.scene.time.valid_utc.clear();
  v.scene.time_step = 0;
  if (!time.empty() && core::parse_iso_utc(time)) {
    try {
      core::instant_at_time(vol.times, time, file);
    } catch (const core::TimeError& e) {
      throw ViewerInputError(bad + ": " + e.what());
    }
    v.scene.time.valid_utc = time;
  } else if (!time.empty()) {
    const int n = static_cast<int>(vol.times.size());
    try {
      std::size_t used = 0;
      v.scene.time_step = std::stoi(time, &used);
      if (used != time.size()) v.scene.time_step = -1;
    } catch (const std::exception&) {
      v.scene.time_step = -1;
    }
    if (v.scene.time_step < 0 || v.scene.time_step >= n) {
      throw ViewerInputError(bad + ", expected a step 0.." + std::to_string(n - 1) + " of " + file + " or a UTC time YYYY-MM-DDThh:mm:ssZ");
    }
  } else if (core::times_known(vol.times) && core::times_known(s.volume.times)) {
    ViewCursor c = cursor_of(s.scene, s.volume);
    c.t = std::clamp(c.t, double(vol.times.front().unix_s), double(vol.times.back().unix_s));
    set_time(v.scene, c);
  } else {
    v.scene.time_step = std::min(s.scene.time_step, static_cast<int>(vol.times.size()) - 1);
  }
  v.view_step_ratio = vol.grid.alt_m.step / s.volume.grid.alt_m.step;
  return v;
}
// The whole of v as a number, or NaN (which fails every range check) where it is not one.
double number_or_nan(const std::string& v) {
  std::size_t used = 0;
  double x = 0.0;
  try {
    x = std::stod(v, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  return used == v.size() && used > 0 ? x : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

int cmd_view(const std::vector<std::string>& args) {
  ViewerOptions o;
  try {
    for (std::size_t i = 0; i < args.size(); ++i) {
      const std::string& a = args[i];
      auto next = [&]() -> const std::string& {
        if (i + 1 >= args.size()) throw ViewerInputError("cloudviewer view: " + a + ": expected a value after it");
        return args[++i];
      };
      if (a == "--size") {
        const std::string sz = next();
        if (std::sscanf(sz.c_str(), "%dx%d", &o.width, &o.height) != 2 || o.width < 16 || o.height < 16 || o.width > 16384 ||
            o.height > 16384) {
          throw ViewerInputError("cloudviewer view: --size: found '" + sz + "', expected WxH with 16..16384 each");
        }
      } else if (a == "--frames") {
        o.frames = parse_int("--frames", next(), 1, 100000);
      } else if (a == "--time") {
        const std::string v = next();
        if (core::parse_iso_utc(v)) o.time_utc = v;
        else o.time_step = parse_int("--time", v, 0, 1000000);
        o.time_given = true;
      } else if (a == "--play") {
        const std::string v = next();
        o.play_h_per_s = number_or_nan(v);
        if (!(o.play_h_per_s > 0.0 && o.play_h_per_s <= 1000.0)) {
          throw ViewerInputError("cloudviewer view: --play: found '" + v + "', expected forecast hours per second of wall time, > 0 and <= 1000");
        }
      } else if (a == "--screenshot") {
        o.screenshot = next();
      } else if (a == "--scale") {
        o.scale_given = true;
        const std::string v = next();
        o.scale = number_or_nan(v);
        if (!(o.scale >= 0.1 && o.scale <= 1.0)) {
          throw ViewerInputError("cloudviewer view: --scale: found '" + v + "', expected a resolution scale in 0.1..1");
        }
      } else if (a == "--frame-budget") {
        const std::string v = next();
        o.frame_budget_ms = number_or_nan(v);
        if (!(o.frame_budget_ms >= 0.0 && o.frame_budget_ms <= 1e7)) {
          throw ViewerInputError("cloudviewer view: --frame-budget: found '" + v + "', expected a frame time in ms 0..1e7 (0: off)");
        }
      } else if (a == "--compare") {
        o.compare.push_back(next());
        if (o.compare.size() > static_cast<std::size_t>(kMaxViews - 1)) {
          throw ViewerInputError("cloudviewer view: --compare: found " + std::to_string(o.compare.size()) + " of them, expected at most " +
                                 std::to_string(kMaxViews - 1) + " (" + std::to_string(kMaxViews) + " views)");
        }
      } else if (a == "--layout") {
        o.layout = next();
        o.layout_given = true;
        if (!parse_view_layout(o.layout)) throw ViewerInputError("cloudviewer view: --layout: found '" + o.layout + "', expected grid or swipe");
      } else if (a == "--unlinked") {
        o.unlinked = true;
      } else if (a == "--realtime") {
        o.realtime = true;
      } else if (a == "--hide-ui") {
        o.hide_ui = true;
      } else if (a == "--quality") {
        const std::string q = next();
        if (q != "reference") {
          throw ViewerInputError("cloudviewer view: --quality: found '" + q +
                                 "', expected reference (the progressive path tracer; the march's quality is the scene's)");
        }
        o.path_trace = true;
      } else if (a == "--spp") {
        o.path_spp = parse_int("--spp", next(), 1, 1000000);
      } else if (a == "--reproject") {
        o.reproject = true;
      } else if (a == "--diagnose-cloud") {
        o.diagnose_cloud = true;
      } else if (a == "--rh-critical") {
        const std::string v = next();
        o.rh_critical = number_or_nan(v);
        if (!(o.rh_critical >= 0.5 && o.rh_critical < 1.0)) {
          throw ViewerInputError("cloudviewer view: --rh-critical: found '" + v + "', expected a critical relative humidity 0.5 <= RH < 1");
        }
      } else if (a == "--orbit") {
        const std::string v = next();
        o.orbit_px = number_or_nan(v);
        if (!(std::abs(o.orbit_px) <= 1000.0)) {
          throw ViewerInputError("cloudviewer view: --orbit: found '" + v + "', expected pixels of drag per frame in -1000..1000");
        }
      } else if (a == "--section" || a == "--series") {
        (a == "--section" ? o.section : o.series) = next();
        SectionPanel sec;
        SeriesPanel ser;
        const std::string problem = a == "--section" ? section_from_option(sec, o.section) : series_from_option(ser, o.series);
        if (!problem.empty()) throw ViewerInputError(problem);
      } else if (!a.empty() && a[0] == '-') {
        throw ViewerInputError("cloudviewer view: unknown option '" + a + "'");
      } else if (o.input.empty()) {
        o.input = a;
      } else {
        throw ViewerInputError("cloudviewer view: unexpected argument '" + a + "', expected one INPUT");
      }
    }
    if (o.input.empty()) throw ViewerInputError("cloudviewer view: expected INPUT (.nc, .cvvol or a scene .json)");
    if (o.path_spp > 0 && !o.path_trace) {
      throw ViewerInputError("cloudviewer view: --spp: found it without the path tracer, expected --quality reference as well");
    }
    if (ends_with(o.input, ".json")) o.scene = core::load_scene(o.input);
    // The views: --compare, else the scene file's "views".
    const std::size_t more = !o.compare.empty() || !o.scene || !o.scene->views ? o.compare.size() : o.scene->views->compare.size();
    if (o.layout == "swipe" && more != 1) {
      throw ViewerInputError("cloudviewer view: --layout: found 'swipe' with " + std::to_string(more + 1) +
                             " view(s), expected exactly one --compare (a swipe divider splits two views)");
    }
    if (!o.screenshot.empty() && o.frames == 0) {
      throw ViewerInputError("cloudviewer view: --screenshot: expected --frames N as well (the frame to save is the Nth)");
    }
    if (!o.screenshot.empty()) {  // checked before the window opens, so a bad path costs no frames
      core::check_output_extension(o.screenshot, "--screenshot", {".png"});
      core::check_output_path(o.screenshot, "--screenshot");
      core::check_output_not_input(o.screenshot, "--screenshot", o.input, "the input");
    }
  } catch (const std::runtime_error& e) {  // ViewerInputError, core::InputError and core::SceneError
    std::fprintf(stderr, "%s\n", e.what());
    return kExitBadInput;
  }
  return run_viewer(o);
}

int run_viewer(const ViewerOptions& o) {
  ViewerState s;
  if (!o.section.empty()) section_from_option(s.section, o.section);  // checked by cmd_view; drawn on the first frame
  if (!o.series.empty()) series_from_option(s.series, o.series);
  if (o.scene) {
    s.scene = *o.scene;
  } else {
    s.scene.data.path = o.input;
  }
  if (o.diagnose_cloud) s.scene.data.diagnose_cloud = true;
  if (o.rh_critical > 0.0) s.scene.data.rh_critical = o.rh_critical;
  try {
    s.volume = importers::load_scene_volume(s.scene, 2);
    importers::print_diagnosed_cloud_note(s.volume, "cloudviewer view");
  } catch (const core::SceneError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return kExitBadInput;
  }
  const auto& g = s.volume.grid;
  if (g.lon_deg.count < 2 || g.lat_deg.count < 2 || g.alt_m.count < 2) {
    std::fprintf(stderr, "cloudviewer view: %s: the volume is %d x %d x %d points; rendering needs at least 2 along each axis\n",
                 o.input.c_str(), g.lon_deg.count, g.lat_deg.count, g.alt_m.count);
    return kExitBadInput;
  }
  if (static_cast<std::size_t>(o.time_step) >= s.volume.times.size()) {
    std::fprintf(stderr, "cloudviewer view: --time: found %d, %s has %zu time step(s)\n", o.time_step, o.input.c_str(),
                 s.volume.times.size());
    return kExitBadInput;
  }
  try {
    overlays::check_overlays(s.scene.overlays, s.volume);
  } catch (const overlays::OverlayError& e) {
    std::fprintf(stderr, "cloudviewer view: %s\n", e.what());
    return kExitBadInput;
  }
  s.import_report = s.volume.report.to_text();
  if (!o.scene || o.time_given) s.scene.time_step = o.time_step, s.scene.time.valid_utc = o.time_utc;
  // The timeline: from the scene's instant; a file with one step is a still (with a note).
  bool timeline = core::times_known(s.volume.times) && s.volume.times.size() > 1;
  if (timeline) {
    try {
      core::check_time_axis(s.volume.times, s.scene.data.path);
    } catch (const core::TimeError& e) {  // steps by index still work; instants between them do not
      std::fprintf(stderr, "%s; the timeline is off\n", e.what());
      timeline = false;
    }
  }
  if (s.volume.times.size() == 1) std::printf("%s has one time step (%s): it shows as a still\n", o.input.c_str(), s.volume.times[0].iso_utc.c_str());
  try {
    s.play.t_s = double(core::scene_instant(s.scene, s.volume, s.scene.data.path).unix_s);
  } catch (const core::TimeError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return kExitBadInput;
  }
  s.play.reset(s.volume.times);
  if (o.play_h_per_s > 0.0) {
    if (!timeline) {
      std::fprintf(stderr, "cloudviewer view: --play: %s has %s, expected at least two steps with UTC valid times\n", o.input.c_str(),
                   s.volume.times.size() == 1 ? "one time step" : "no UTC valid times");
      return kExitBadInput;
    }
    s.play.playing = true;
    s.play.speed_h_per_s = o.play_h_per_s;
    s.scene.time.valid_utc = core::format_iso_utc(s.play.shown());
  }
  // Instants are prepared off the render thread, from the prefetcher's own copy of the data.
  constexpr std::size_t kResidentInstants = 6;
  std::unique_ptr<Prefetcher> prefetch;
  if (timeline) prefetch = std::make_unique<Prefetcher>(s.scene, kResidentInstants);
  s.timeline = timeline;
  std::int64_t shown_instant = INT64_MIN;  // the instant whose medium is on the GPU
  bool shown_drift = false;                 // whether it carries the modelled cloud's wind displacement
  bool have_volume = false;
  std::string printed_sun_note;  // the sun note last printed to the terminal (printed when it changes)
  s.scene.width = o.width;
  s.scene.height = o.height;
  // As `render` does: the quality preset's settings, the view step from the grid's vertical spacing.
  if (!o.scene) {
    core::apply_quality("default", s.scene.render);
    s.scene.render.accumulate = 64;
  }
  s.scene.render.march.quality.view_step_m = core::resolve_view_step_m(s.scene.render, g);
  if (!(s.scene.render.march.medium.droplet_diameter_um > 0.0)) s.scene.render.march.medium.droplet_diameter_um = 2.0 * s.volume.liquid_r_eff_um;
  if (o.frames > 0) s.scene.render.accumulate = o.frames;
  if (!o.scene || o.scale_given) s.scene.render.resolution_scale = o.scale;
  if (o.frame_budget_ms >= 0.0) s.scene.render.budget_ms = o.frame_budget_ms;
  s.path_trace = o.path_trace;
  s.reproject = o.reproject;
  if (o.path_spp > 0) s.path_spp = o.path_spp;

  // More views (--compare, else the scene file's "views"): opened before the window, so bad input
  // costs no frames. The command line's --layout and --unlinked override the scene file's.
  std::map<std::string, std::unique_ptr<core::CloudVolume>> sources;  // the other files' volumes, one per file
  std::vector<ExtraView> extra;
  const bool scene_views = o.compare.empty() && s.scene.views.has_value();
  try {
    if (scene_views) {
      for (std::size_t i = 0; i < s.scene.views->compare.size(); ++i) {
        extra.push_back(open_view(s.scene.views->compare[i], o.input + ": views.compare[" + std::to_string(i) + "]", s, sources));
      }
    } else {
      for (const std::string& c : o.compare) extra.push_back(open_view(parse_view_spec(c), "--compare", s, sources));
    }
  } catch (const ViewerInputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return kExitBadInput;
  }
  s.views.layout = *parse_view_layout(scene_views && !o.layout_given ? s.scene.views->layout : o.layout);
  s.views.link_camera = s.views.link_time = !o.unlinked && (!scene_views || s.scene.views->linked);
  if (scene_views) s.views.divider = s.scene.views->divider;
  LinkedViews link;
  MouseRouter mouse;
  ClickDetector click;  // a click without a drag: the probe
  int active_view = 0;  // the view the keys fly: the last one the mouse acted on

  auto win = render::make_window_context(o.width, o.height, "cloudviewer - " + o.input);
  glfwSwapInterval(o.frames > 0 ? 0 : 1);
  const render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  ViewGpu main_view(loader);  // view 0: the scene the panels edit
  render::FrameRenderer& renderer = main_view.renderer;
  core::PreparedVolumeCache volumes;  // the time steps shown last, prepared once each (shared by every view)
  std::shared_ptr<const core::PreparedVolume> shown0;  // view 0's prepared instant, and its key: a view
  std::string shown0_key;                               // of the same source and instant shares it

  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini in whatever folder the viewer was started from
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForOpenGL(win->window(), true);
  ImGui_ImplOpenGL3_Init("#version 450 core");
  struct ImGuiGuard {  // shut ImGui down before the window goes, also when a frame throws
    ~ImGuiGuard() {
      ImGui_ImplOpenGL3_Shutdown();
      ImGui_ImplGlfw_Shutdown();
      ImGui::DestroyContext();
    }
  } imgui_guard;

  FrameBudget budget(render::machine_id(win->info()));
  if (!budget.warning().empty()) std::printf("frame budget: %s\n", budget.warning().c_str());
  bool marched_last = false;
  PanelContext ctx;
  struct PanelTextureGuard {  // the panels' figure textures go before the window's context
    PanelContext& ctx;
    ~PanelTextureGuard() { release_panel_textures(ctx); }
  } panel_texture_guard{ctx};
  FrameStats stats;
  stats.renderer = win->info().renderer;
  PassTimer march_timer, present_timer;
  bool show_ui = !o.hide_ui, f1_was_down = false;
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  auto last = start, fps_since = start;
  auto after_first = start;            // the end of frame 0: --frames reports the mean frame after it
  std::clock_t cpu_after_first = 0;    // the process's CPU time then (all threads: llvmpipe's too)
  int fps_frames = 0;
  for (int frame = 0; o.frames == 0 ? !win->should_close() : frame < o.frames; ++frame) {
    glfwPollEvents();
    const auto now = clock::now();
    const double dt = std::min(0.25, std::chrono::duration<double>(now - last).count());
    const double frame_ms = std::chrono::duration<double, std::milli>(now - last).count();  // the last frame, uncapped
    last = now;
    int fbw = 0, fbh = 0;
    glfwGetFramebufferSize(win->window(), &fbw, &fbh);
    if (fbw < 1 || fbh < 1) {  // minimised: nothing to draw into
      glfwWaitEvents();
      continue;
    }
    // The Views panel's requests from the last frame: a view to open or to close.
    if (s.views.add_requested) {
      s.views.add_requested = false;
      try {
        if (extra.size() + 1 >= static_cast<std::size_t>(kMaxViews)) throw ViewerInputError("at most " + std::to_string(kMaxViews) + " views");
        extra.push_back(open_view(parse_view_spec(s.views.add_source), "add view", s, sources));
        s.views.message = "opened " + s.views.add_source;
      } catch (const ViewerInputError& e) {
        s.views.message = e.what();
      }
    }
    if (s.views.remove_requested >= 1 && s.views.remove_requested <= static_cast<int>(extra.size())) {
      extra.erase(extra.begin() + (s.views.remove_requested - 1));
    }
    s.views.remove_requested = -1;
    const int n_views = 1 + static_cast<int>(extra.size());
    if (n_views != 2) s.views.layout = ViewLayout::Grid;  // a swipe divider splits two views
    const std::vector<ViewRect> rects = view_rects(s.views.layout, n_views, fbw, fbh);
    s.scene.width = rects[0].w;
    s.scene.height = rects[0].h;
    if (!s.scene.camera) {
      s.scene.camera = core::auto_camera(g, rects[0].w, rects[0].h);
      ctx.home = *s.scene.camera;
      ctx.goto_lat_deg = ctx.home.lat_deg, ctx.goto_lon_deg = ctx.home.lon_deg, ctx.goto_alt_m = ctx.home.alt_m;
    }
    // --orbit: a scripted drag of the globe every frame after the first (the reprojection's figures).
    if (o.orbit_px != 0.0 && frame > 0) orbit(*s.scene.camera, o.orbit_px, 0.0, g.earth_radius_m);
    for (ExtraView& v : extra) {
      if (!v.scene.camera) v.scene.camera = *s.scene.camera;  // a new view starts where view 0 looks
    }
    // The link (views.hpp): every view's camera and time before this frame's interactions; after
    // them (the mouse, the keys, the panels, playback), the one that changed moves the others.
    auto scene_of = [&](int i) -> core::Scene& { return i == 0 ? s.scene : extra[static_cast<std::size_t>(i - 1)].scene; };
    auto volume_of = [&](int i) -> core::CloudVolume& { return i == 0 ? s.volume : *extra[static_cast<std::size_t>(i - 1)].volume; };
    // A view's file's step nearest its instant (what the probe and the section read).
    auto nearest_step = [&](int vi) {
      std::size_t step = static_cast<std::size_t>(std::max(0, scene_of(vi).time_step));
      try {
        const core::Instant at = core::scene_instant(scene_of(vi), volume_of(vi), scene_of(vi).data.path);
        step = at.fraction < 0.5 ? at.step0 : at.step1;
      } catch (const core::TimeError&) {  // the step index stands
      }
      return std::min(step, volume_of(vi).times.size() - 1);
    };
    auto read_cursors = [&] {
      link.views.resize(static_cast<std::size_t>(n_views));
      for (int i = 0; i < n_views; ++i) link.views[static_cast<std::size_t>(i)] = cursor_of(scene_of(i), volume_of(i));
    };
    auto link_views = [&] {
      read_cursors();
      const std::vector<ViewCursor> before = link.views;
      const std::vector<bool> changed = link.sync();
      for (int i = 0; i < n_views; ++i) {
        const std::size_t k = static_cast<std::size_t>(i);
        if (!changed[k]) continue;
        core::Scene& sc = scene_of(i);
        if (!same_view_camera(before[k].camera, link.views[k].camera)) sc.camera = link.views[k].camera;
        if (before[k].t != link.views[k].t) {
          set_time(sc, link.views[k]);
          if (i == 0 && link.views[k].utc) s.play.t_s = link.views[k].t;
        }
      }
      link.begin();
    };
    link.link_camera = s.views.link_camera;
    link.link_time = s.views.link_time;
    read_cursors();
    link.begin();

    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    const bool f1 = glfwGetKey(win->window(), GLFW_KEY_F1) == GLFW_PRESS;
    if (f1 && !f1_was_down) show_ui = !show_ui;
    f1_was_down = f1;
    {  // the mouse goes to the view under it (a drag stays with its view; the swipe divider drags)
      const ImGuiIO& io = ImGui::GetIO();
      const double fx = io.DisplayFramebufferScale.x, fy = io.DisplayFramebufferScale.y;
      const bool pressed = !io.WantCaptureMouse && (io.MouseClicked[0] || io.MouseClicked[1]);
      const int target = n_views == 1 ? 0
                                       : mouse.route(s.views.layout, n_views, fbw, fbh, s.views.divider, io.MousePos.x * fx,
                                                     io.MousePos.y * fy, pressed, io.MouseDown[0] || io.MouseDown[1]);
      if (target >= 0) active_view = target;
      active_view = std::min(active_view, n_views - 1);
      navigate(win->window(), *scene_of(active_view).camera, volume_of(active_view).grid.earth_radius_m, s.fly_mode, target >= 0, dt);
      // A click (a press and release without a drag) on a view probes the column under it: the
      // file's step nearest the view's instant, read as `cloudviewer probe` reads it.
      if (click.update(io.MouseDown[0] && (click.down || !io.WantCaptureMouse), io.MousePos.x * fx, io.MousePos.y * fy)) {
        const int vi = view_at(s.views.layout, n_views, fbw, fbh, s.views.divider, click.x0, click.y0);
        if (vi >= 0) {
          const ViewRect r = view_rects(s.views.layout, n_views, fbw, fbh)[static_cast<std::size_t>(vi)];
          const core::Camera& cam = *scene_of(vi).camera;  // at its march size
          const std::optional<glm::dvec2> ll = pixel_ground(cam, (click.x0 - r.x) * cam.width / r.w, (click.y0 - r.y) * cam.height / r.h,
                                                            volume_of(vi).grid.earth_radius_m);
          s.probe.open = true;
          if (!ll) {
            s.probe.message = "the click is on the sky: no column there";
          } else {
            try {
              probe_into(s.probe, volume_of(vi), scene_of(vi).data.path, nearest_step(vi), ll->x, ll->y, &cam,
                         core::resolve_view_step_m(scene_of(vi).render, volume_of(vi).grid));
              s.probe.view = vi;
            } catch (const std::exception& e) {  // the step could not be read
              s.probe.message = e.what();
            }
          }
        }
      }
    }
    {  // view 0's time on the series' axis: hours after the file's first step, or the step index
      const ViewCursor c = cursor_of(s.scene, s.volume);
      s.series_now_hours = c.utc ? (c.t - c.t_first) / 3600.0 : c.t;
    }
    if (show_ui) draw_panels(s, ctx, stats);
    // The Section and Series panels' "draw": view 0's file (the section at its step nearest the time shown).
    if (s.section.requested) compute_section(s.section, volume_of(0), scene_of(0).data.path, nearest_step(0));
    if (s.series.requested) compute_series(s.series, volume_of(0), scene_of(0).data.path);
    if (s.views.step_view >= 0 && s.views.step_view < n_views) {  // a view's "<" or ">": its file's previous or next step
      ViewCursor c = cursor_of(scene_of(s.views.step_view), volume_of(s.views.step_view));
      c.t = step_from(volume_of(s.views.step_view), c, s.views.step_dir);
      set_time(scene_of(s.views.step_view), c);
      if (s.views.step_view == 0 && c.utc) s.play.t_s = c.t;
    }
    s.views.step_view = -1;
    // The camera path's preview: the camera and the weather time follow the path at wall time.
    if (s.keys.previewing) {
      if (const std::optional<core::Scene> at = preview_step(s.scene, s.keys, dt)) {
        s.scene.camera = at->camera;
        s.scene.time.valid_utc = at->time.valid_utc;
      }
    }

    // The frame budget steps along its candidates from the last frame's time (after the panels, so
    // that switching it on in the panel takes effect this frame).
    const bool budget_was_on = budget.on();
    if (!s.path_trace && budget.update(s.scene.render, g.alt_m.step, frame_ms, marched_last)) {  // the path tracer marches nothing
      if (!budget_was_on) std::printf("frame budget %g ms: candidates from %s\n", s.scene.render.budget_ms, budget.source().c_str());
      if (o.frames > 0) std::printf("frame budget %g ms: frame %d: %s\n", s.scene.render.budget_ms, frame, budget.status().c_str());
    }
    ctx.budget_text = budget.on() ? budget.status() + "; from " + budget.source() : "";
    // The march size follows the window and the resolution scale; the camera renders at it.
    int mw = 0, mh = 0;
    march_size(s.scene, rects[0].w, rects[0].h, mw, mh);
    s.scene.camera->width = mw;
    s.scene.camera->height = mh;
    s.scene.time_step = std::clamp(s.scene.time_step, 0, static_cast<int>(s.volume.times.size()) - 1);
    // Playback: the playhead moves (one grid instant per frame with --frames, else by wall time) and
    // the scene's instant follows it; the medium comes from the prefetcher, and while the next
    // instant is not ready the playhead waits on the one shown.
    const bool on_timeline = prefetch && !s.scene.time.valid_utc.empty();
    if (prefetch && s.play.playing) {
      if (s.scene.time.valid_utc.empty()) s.play.t_s = double(s.volume.times[static_cast<std::size_t>(s.scene.time_step)].unix_s);
      if (frame > 0 && have_volume) {
        if (o.frames > 0 && !o.realtime) s.play.advance_one();
        else s.play.advance(dt);
      }
      s.scene.time.valid_utc = core::format_iso_utc(s.play.shown());
    }
    link_views();  // the interactions and playback so far move the linked views
    if (prefetch && (on_timeline || s.play.playing)) {
      const std::int64_t want_t = *core::parse_iso_utc(s.scene.time.valid_utc);
      std::vector<std::int64_t> wanted = {want_t};
      if (s.play.playing) {
        const std::vector<std::int64_t> next = s.play.upcoming(static_cast<int>(kResidentInstants) - 1);
        wanted.insert(wanted.end(), next.begin(), next.end());
      }
      const bool drift = s.scene.render.march.medium.modelled;
      prefetch->want(wanted, s.scene.time.interpolation, drift, &s.scene);  // the two-stream sources built ahead too
      core::TimeInterpolationReport interp;
      const bool first_ask = want_t != shown_instant || drift != shown_drift;
      auto v = first_ask ? prefetch->get(want_t, (o.frames > 0 && !o.realtime) || !have_volume, &interp) : nullptr;
      if (v) {
        renderer.use_volume(v);
        core::Instant shown_at;
        shown_at.time_known = true, shown_at.unix_s = want_t;
        shown0 = v, shown0_key = prepared_key(s.scene.data.path, shown_at, s.scene.time.interpolation, drift);
        shown_instant = want_t;
        shown_drift = drift;
        // The step slider shows the step at or before the instant.
        s.scene.time_step = static_cast<int>(core::instant_at_time(s.volume.times, s.scene.time.valid_utc, s.scene.data.path).step0);
        have_volume = true;
        ctx.time_warning = interp.warning;
        if (o.frames > 0 && s.play.playing) std::printf("frame %d: instant %s\n", frame, s.scene.time.valid_utc.c_str());
      } else if (first_ask) {
        if (!prefetch->error().empty()) std::fprintf(stderr, "%s\n", prefetch->error().c_str());
        // Not ready: show the instant on the GPU, and hold the playhead there.
        if (have_volume) {
          s.scene.time.valid_utc = core::format_iso_utc(shown_instant);
          if (s.play.playing) s.play.t_s = double(shown_instant);
        }
      }
      const PrefetchStats ps = prefetch->stats();
      char text[240];
      std::snprintf(text, sizeof text,
                    "prefetch: %zu/%zu instants resident, %.1f MB (steps and media %.1f MB), hits %zu, misses %zu (%.0f %%), last %.0f ms%s",
                    ps.resident, ps.max_resident, double(ps.resident_bytes) / 1e6, double(ps.held_bytes) / 1e6, ps.hits, ps.misses,
                    ps.hits + ps.misses ? 100.0 * double(ps.hits) / double(ps.hits + ps.misses) : 0.0, ps.last_prepare_ms,
                    ps.sources ? (" (its two-stream source " + std::to_string(static_cast<int>(std::lround(ps.last_source_ms))) + " ms)").c_str() : "");
      stats.prefetch = text;
    } else {  // the scene's instant: between steps the medium is interpolated once per instant (core::PreparedVolumeCache)
      core::Instant at;
      try {
        at = core::scene_instant(s.scene, s.volume, s.scene.data.path);
      } catch (const core::TimeError& e) {
        std::fprintf(stderr, "%s; the time step is used instead\n", e.what());
        s.scene.time.valid_utc.clear();
        at = core::instant_at_step(s.volume.times, static_cast<std::size_t>(s.scene.time_step), s.scene.data.path);
      }
      core::TimeInterpolationReport interp;
      const bool drift = s.scene.render.march.medium.modelled;
      shown0 = volumes.get(s.scene.data.path, s.volume, at, s.scene.time.interpolation, &interp, drift);
      shown0_key = prepared_key(s.scene.data.path, at, s.scene.time.interpolation, drift);
      renderer.use_volume(shown0);
      ctx.time_warning = interp.warning;
      ctx.instant_text = at.iso_utc + (at.between() ? std::string(" (") + core::time_interpolation_name(interp.used) + " between steps)" : "");
      have_volume = true;
      shown_instant = INT64_MIN;
    }
    link_views();  // view 0's playhead held on the instant shown holds the linked views too
    if (core::times_known(s.volume.times)) {  // the valid time shown, and the local solar time at the view centre
      const std::int64_t t = shown_instant != INT64_MIN ? shown_instant
                             : !s.scene.time.valid_utc.empty() ? *core::parse_iso_utc(s.scene.time.valid_utc)
                                                               : s.volume.times[static_cast<std::size_t>(s.scene.time_step)].unix_s;
      const double lon = view_centre_lon_deg(*s.scene.camera, g.earth_radius_m);
      const double h = local_solar_time_h(lon, t);
      char text[160];
      std::snprintf(text, sizeof text, "%s; local solar time %02d:%02d at the view centre (%.1f E)%s", core::format_iso_utc(t).c_str(),
                    static_cast<int>(h), static_cast<int>(std::fmod(h * 60.0, 60.0)), lon,
                    s.scene.sun.mode == core::SunMode::LocalNoon ? "; sun: local noon (teaching)" : "");
      ctx.instant_text = text;
    }
    // The frame as `render` resolves it (camera at the march size, sun, settings); a date/time being
    // typed keeps the last good sun.
    auto resolve = [&](const core::Scene& sc, const core::CloudVolume& vol) {
      try {
        return render::resolve_frame(sc, vol);
      } catch (const std::invalid_argument&) {
        core::Scene held = sc;
        held.sun.mode = core::SunMode::Manual;
        held.sun.subsolar_lat_deg = ctx.sun.subsolar_lat_deg, held.sun.subsolar_lon_deg = ctx.sun.subsolar_lon_deg;
        return render::resolve_frame(held, vol);
      }
    };
    try {
      main_view.spec = render::resolve_frame(s.scene, s.volume);
      ctx.sun = main_view.spec.sun;
      ctx.sun_error.clear();
      // A domain at dawn, dusk or night shows a pale or dark frame: say why, and what lights it.
      ctx.sun_note.clear();
      if (s.scene.sun.mode != core::SunMode::LocalNoon) {
        const double highest = core::highest_sun_elevation_deg(
            g, glm::normalize(geo::sphere_to_ecef({ctx.sun.subsolar_lat_deg, ctx.sun.subsolar_lon_deg, 0.0}, g.earth_radius_m)));
        if (highest < core::kTwilightElevationDeg) ctx.sun_note = core::low_sun_words(highest) + ": 'local noon (teaching)' keeps the clouds lit";
      }
      if (ctx.sun_note != printed_sun_note && !ctx.sun_note.empty()) std::printf("note: %s\n", ctx.sun_note.c_str());
      printed_sun_note = ctx.sun_note;
    } catch (const std::invalid_argument& e) {
      ctx.sun_error = e.what();
      main_view.spec = resolve(s.scene, s.volume);
    }
    // The other views: view 0's settings, sun, overlays and interpolation on their own data, camera,
    // time and size; the prepared instant shared with any view of the same source and instant.
    std::vector<ViewGpu*> gpus = {&main_view};
    for (std::size_t k = 0; k < extra.size(); ++k) {
      ExtraView& v = extra[k];
      const ViewRect r = rects[k + 1];
      v.scene.render = s.scene.render;
      v.scene.render.march.quality.view_step_m *= v.view_step_ratio;  // as many steps per cell of its own grid
      v.scene.sun = s.scene.sun;
      v.scene.overlays = s.scene.overlays;
      v.scene.time.interpolation = s.scene.time.interpolation;
      v.scene.width = r.w, v.scene.height = r.h;
      march_size(v.scene, r.w, r.h, v.scene.camera->width, v.scene.camera->height);
      if (!v.gpu) v.gpu = std::make_unique<ViewGpu>(loader);
      core::Instant at;
      try {
        at = core::scene_instant(v.scene, *v.volume, v.scene.data.path);
      } catch (const core::TimeError& e) {
        std::fprintf(stderr, "%s; the time step is used instead\n", e.what());
        v.scene.time.valid_utc.clear();
        at = core::instant_at_step(v.volume->times, static_cast<std::size_t>(v.scene.time_step), v.scene.data.path);
      }
      v.scene.time_step = static_cast<int>(at.step0);
      const bool drift = v.scene.render.march.medium.modelled;
      const std::string key = prepared_key(v.scene.data.path, at, v.scene.time.interpolation, drift);
      if (key != v.prepared_key) {
        v.prepared = key == shown0_key ? shown0 : nullptr;
        for (const ExtraView& other : extra) {
          if (!v.prepared && &other != &v && other.prepared_key == key) v.prepared = other.prepared;
        }
        if (!v.prepared) v.prepared = volumes.get(v.scene.data.path, *v.volume, at, v.scene.time.interpolation, nullptr, drift);
        v.prepared_key = key;
      }
      v.gpu->renderer.use_volume(v.prepared);
      v.gpu->spec = resolve(v.scene, *v.volume);
      gpus.push_back(v.gpu.get());
    }

    // Each view: one more jittered frame into its mean until the target (a target of 1 marches at
    // step middles exactly as `render` does without --accumulate).
    bool any_march = false;
    for (std::size_t i = 0; i < gpus.size(); ++i) {
      ViewGpu& v = *gpus[i];
      const core::Scene& sc = scene_of(static_cast<int>(i));
      const bool tracing = s.path_trace;
      // Reprojection: not with the path tracer, overlays (their pass draws every pixel) or the
      // camera path's track. A still view goes on after its first 16 frames: each further pass of
      // 16 marches every pixel once more as the next accumulation frame, up to render.accumulate
      // passes (Reprojector::next_cycle), so it converges as the accumulation without it does.
      const bool reproject = s.reproject && !tracing && sc.overlays.empty() && !(i == 0 && s.keys.draw_path && s.scene.path);
      if (reproject) {  // the march size in whole 4 x 4 blocks
        v.spec.march_camera.width = render::Reprojector::whole_blocks(v.spec.march_camera.width);
        v.spec.march_camera.height = render::Reprojector::whole_blocks(v.spec.march_camera.height);
      }
      const bool same = frame > 0 && same_march(sc, v.previous);
      if (!same || v.path_mode != tracing || v.reprojecting != reproject) {
        v.accumulated = 0;
        v.paths = core::MonteCarloImage{};
      }
      if (reproject) {
        if (!v.reprojector) v.reprojector = std::make_unique<render::Reprojector>(loader);
        if (!v.reprojecting) v.reprojector->reset();
        // Anything but the camera changed (the reprojector finds the camera's motion itself).
        core::Scene camera_only = v.previous;
        camera_only.camera = sc.camera;
        v.reproject_changed = frame > 0 && v.reprojecting && !same_march(sc, camera_only);
      }
      v.path_mode = tracing;
      v.reprojecting = reproject;
      v.previous = sc;
      v.marching = reproject ? !same || v.reprojector->frames_since_change() <
                                            render::Reprojector::kFramesToComplete * std::max(1, sc.render.accumulate)
                             : v.accumulated < (tracing ? s.path_spp : sc.render.accumulate);
      any_march = any_march || v.marching;
      const int w = v.spec.march_camera.width, h = v.spec.march_camera.height;
      if (v.presenter.width() != w || v.presenter.height() != h) v.presenter.resize(w, h);
      if (!v.marching || v.accumulated != 0) continue;  // a new mean, marched or path-traced: both composite the overlays
      try {  // a new mean: the overlays for this view (VTK only when a scene has some)
        const auto built = v.overlay_builder.build(sc.overlays, volume_of(static_cast<int>(i)), static_cast<std::size_t>(sc.time_step),
                                                   v.spec.march_camera);
        std::vector<render::OverlayDraw> draws = overlays::OverlayBuilder::draws(built);
        if (i == 0) {
          stats.overlays.resize(built.size());
          for (std::size_t j = 0; j < built.size(); ++j) {
            if (built[j].rebuilt) stats.overlays[j].build_ms = built[j].build_ms;
          }
          if (s.keys.draw_path && s.scene.path) {  // the camera path on the globe, after the scene's overlays
            auto track = std::make_shared<const core::OverlayMesh>(path_mesh(s.scene, g.earth_radius_m));
            if (!track->empty()) draws.push_back({"camera path", track, nullptr, 2.0f});
          }
        }
        v.renderer.set_overlays(std::move(draws));
      } catch (const overlays::OverlayError& e) {
        ctx.scene_message = e.what();
        v.renderer.set_overlays({});
      }
    }
    marched_last = main_view.marching;
    if (any_march) march_timer.begin();
    for (ViewGpu* v : gpus) {
      if (!v->marching) continue;
      if (v->path_mode) {
        trace_into(*v);
      } else if (v->reprojecting) {  // 1/16 of the pixels, the rest reprojected into the frame texture
        core::FrameSpec sparse = v->spec;
        // Pass c of a still view is accumulation frame c (jittered steps and rays); a single frame
        // (accumulate 1) keeps the scene's own frame, as `render` does.
        if (v->spec.accumulate > 1) {
          sparse.march.per_frame.frame = v->reprojector->next_cycle(v->spec.march_camera, v->reproject_changed);
        }
        sparse.accumulate = 1;
        sparse.march_camera = render::Reprojector::sparse_camera(v->spec.march_camera, v->reproject_index);
        v->renderer.march_into(v->reprojector->sparse_target(v->spec.march_camera), sparse, 0);
        v->reprojector->resolve(v->renderer.raymarcher().cloud_depth_texture(), v->spec.march_camera, v->reproject_index,
                                v->reproject_changed, g.earth_radius_m, v->presenter.frame_texture(), v->renderer.volume());
        ++v->reproject_index;
      } else {
        v->renderer.march_into(v->presenter.frame_texture(), v->spec, v->accumulated);
      }
    }
    if (any_march) march_timer.end();
    present_timer.begin();
    std::vector<const render::Presenter*> presenters;
    std::vector<render::ToneSettings> tones;
    for (std::size_t i = 0; i < gpus.size(); ++i) {
      ViewGpu& v = *gpus[i];
      const core::Scene& sc = scene_of(static_cast<int>(i));
      if (v.marching) {
        // The path tracer's frame texture holds its mean, the reprojector's the whole image.
        v.presenter.accumulate(v.path_mode || v.reprojecting ? 0 : v.accumulated);
        ++v.accumulated;
        // The automatic exposure from the mean at the march size (as `render` takes it), when the mean
        // starts and when it is complete: not frame by frame, so the picture does not pulse.
        // (Reprojecting: again once 16 frames have marched every pixel, and once the last pass is
        // done, so a still view ends on the exposure `render --accumulate` takes from its mean.)
        const int pass = render::Reprojector::kFramesToComplete;
        const int target = v.path_mode ? s.path_spp : v.reprojecting ? pass * std::max(1, sc.render.accumulate) : sc.render.accumulate;
        if (v.spec.auto_exposure && (v.accumulated == 1 || v.accumulated == target || (v.reprojecting && v.accumulated == pass))) {
          std::vector<glm::vec4> mean(static_cast<std::size_t>(v.presenter.width()) * v.presenter.height());
          glGetTextureImage(v.presenter.mean_texture(), 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(mean.size() * sizeof(glm::vec4)),
                            mean.data());
          const std::optional<double> own = render::auto_exposure_if_lit(mean);
          if (s.play.playing && !s.play.still()) {
            // Held while playing: a new hold where play began or anything but the time changed.
            core::Scene untimed = sc;
            untimed.time = v.hold_scene.time;
            untimed.time_step = v.hold_scene.time_step;
            untimed.sun.datetime_utc = v.hold_scene.sun.datetime_utc;
            if (!v.exposure_hold.least || !same_march(untimed, v.hold_scene)) v.exposure_hold.reset();
            v.hold_scene = sc;
            v.auto_exposure = v.exposure_hold.update(own, render::kDefaultExposure);
            if (o.frames > 0 && i == 0) {
              std::printf("frame %d: exposure %.6g held while playing (this frame's own %s)\n", frame, v.auto_exposure,
                          own ? std::to_string(*own).c_str() : "none: nothing lit");
            }
          } else {
            v.exposure_hold.reset();
            v.auto_exposure = own.value_or(render::kDefaultExposure);
          }
        }
      }
      render::ToneSettings tone;
      tone.exposure = v.spec.auto_exposure ? v.auto_exposure : v.spec.exposure;
      if (sc.render.march.features.atmosphere || sc.render.march.features.globe) tone.background = glm::dvec3(0.0);
      presenters.push_back(&v.presenter);
      tones.push_back(tone);
    }
    ctx.auto_exposure = main_view.auto_exposure;
    ctx.exposure_held = s.play.playing && !s.play.still();
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    if (n_views > 1) {  // a grid of three leaves a cell empty
      glViewport(0, 0, fbw, fbh);
      glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
      glClear(GL_COLOR_BUFFER_BIT);
    }
    compose_views(presenters, tones, s.views.layout, s.views.divider, fbw, fbh);
    present_timer.end();
    stats.march_ms = march_timer.ms();
    stats.present_ms = present_timer.ms();
    for (std::size_t i = 0; i < stats.overlays.size(); ++i) {  // one per scene overlay, in order (0: off)
      stats.overlays[i].draw_ms = i < renderer.overlay_draw_ms().size() ? renderer.overlay_draw_ms()[i] : 0.0;
    }
    if (show_ui) stats.march = renderer.last_stats();  // read back only when shown (it waits for the march)
    stats.accumulated = main_view.accumulated;
    stats.path_trace = main_view.path_mode;
    stats.reprojecting = main_view.reprojecting;
    if (main_view.path_mode && main_view.paths.spp >= 2 && show_ui) stats.path_error = main_view.paths.mean_relative_standard_error();
    stats.march_w = mw;
    stats.march_h = mh;
    if (show_ui) draw_stats_overlay(stats, main_view.path_mode ? s.path_spp : s.scene.render.accumulate);  // built after the march: this frame's count
    // Each view's label (its file and valid time) at the bottom of the part that shows, and the
    // swipe divider; also with the panels hidden, when there are several views.
    s.views.labels.resize(static_cast<std::size_t>(n_views));
    for (int i = 0; i < n_views; ++i) s.views.labels[static_cast<std::size_t>(i)] = view_label(scene_of(i), volume_of(i));
    // What a saved scene keeps of views 1..: each file (empty: view 0's) at its own instant or step.
    s.views.sources.clear();
    for (const ExtraView& v : extra) {
      s.views.sources.push_back({v.scene.data.path == s.scene.data.path ? "" : v.scene.data.path,
                                 v.scene.time.valid_utc.empty() ? std::to_string(v.scene.time_step) : v.scene.time.valid_utc});
    }
    if (n_views > 1) {
      const ImGuiIO& io = ImGui::GetIO();
      const float fx = io.DisplayFramebufferScale.x > 0.0f ? io.DisplayFramebufferScale.x : 1.0f;
      const float fy = io.DisplayFramebufferScale.y > 0.0f ? io.DisplayFramebufferScale.y : 1.0f;
      ImDrawList* dl = ImGui::GetForegroundDrawList();
      for (int i = 0; i < n_views; ++i) {
        const ViewRect r = visible_rect(s.views.layout, n_views, i, fbw, fbh, s.views.divider);
        if (r.w <= 0 || r.h <= 0) continue;
        const char* text = s.views.labels[static_cast<std::size_t>(i)].c_str();
        const ImVec2 size = ImGui::CalcTextSize(text);
        const bool right = s.views.layout == ViewLayout::Swipe && i == 1;
        const ImVec2 p(right ? float(r.x + r.w) / fx - size.x - 8.0f : float(r.x) / fx + 8.0f, float(r.y + r.h) / fy - size.y - 8.0f);
        dl->PushClipRect(ImVec2(float(r.x) / fx, float(r.y) / fy), ImVec2(float(r.x + r.w) / fx, float(r.y + r.h) / fy), true);
        dl->AddRectFilled(ImVec2(p.x - 4.0f, p.y - 2.0f), ImVec2(p.x + size.x + 4.0f, p.y + size.y + 2.0f), IM_COL32(0, 0, 0, 170));
        dl->AddText(p, IM_COL32(255, 255, 255, 255), text);
        dl->PopClipRect();
      }
      if (s.views.layout == ViewLayout::Swipe) {
        const float x = float(swipe_column(fbw, s.views.divider)) / fx;
        dl->AddLine(ImVec2(x, 0.0f), ImVec2(x, float(fbh) / fy), IM_COL32(255, 255, 255, 220), 2.0f);
      }
    }

    ImGui::Render();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    if (o.frames > 0 && frame == o.frames - 1 && !o.screenshot.empty()) {
      save_screenshot(o.screenshot, fbw, fbh);
      march_timer.finish();
      stats.march_ms = march_timer.ms();
      std::printf("wrote %s (%d x %d window, %d %s in %.2f s wall, GPU %s %.1f ms per frame on %s)\n",
                  o.screenshot.c_str(), fbw, fbh, main_view.accumulated,
                  main_view.path_mode ? "path-traced sample(s) per pixel" : "frame(s) accumulated", std::chrono::duration<double>(clock::now() - start).count(),
                  main_view.path_mode ? "path trace" : "march", stats.march_ms, stats.renderer.c_str());
      if (main_view.path_mode) {
        std::printf("path tracer: %llu samples per pixel, mean relative standard error %.4f, %.2f scatterings per path\n",
                    static_cast<unsigned long long>(main_view.paths.spp),
                    main_view.paths.spp >= 2 ? main_view.paths.mean_relative_standard_error() : 1.0,
                    double(main_view.paths.stats.scatterings) / double(std::max<std::uint64_t>(main_view.paths.stats.paths, 1)));
      }
      if (o.frames > 1) {  // what a frame costs once the shaders are compiled and the data prepared
        std::printf("%d view(s), %s: frames 2..%d took %.1f ms wall, %.1f ms process CPU each\n", n_views, view_layout_name(s.views.layout),
                    o.frames, std::chrono::duration<double, std::milli>(clock::now() - after_first).count() / (o.frames - 1),
                    1e3 * double(std::clock() - cpu_after_first) / CLOCKS_PER_SEC / (o.frames - 1));
      }
      if (budget.on()) std::printf("frame budget %g ms: ended on %s\n", s.scene.render.budget_ms, budget.status().c_str());
      if (!stats.prefetch.empty()) std::printf("%s\n", stats.prefetch.c_str());
      if (prefetch && (main_view.renderer.raymarcher().ms_sources_built_here() || main_view.renderer.raymarcher().ms_sources_taken_prebuilt()))
        std::printf("two-stream sources of view 0: %zu taken as the prefetcher built them, %zu built on the render thread\n",
                    main_view.renderer.raymarcher().ms_sources_taken_prebuilt(), main_view.renderer.raymarcher().ms_sources_built_here());
    }
    win->swap_buffers();
    if (frame == 0) after_first = clock::now(), cpu_after_first = std::clock();
    ++fps_frames;
    const double since = std::chrono::duration<double>(clock::now() - fps_since).count();
    if (since >= 0.5) {
      stats.fps = fps_frames / since;
      fps_frames = 0;
      fps_since = clock::now();
    }
  }
  return 0;
}

}  // namespace cv::viewer
