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
#include <memory>

#include "importer.hpp"
#include "io/output_file.hpp"
#include "noise/noise.hpp"
#include "render/albedo_map.hpp"
#include "render/context.hpp"
#include "render/machine_id.hpp"
#include "render/image_output.hpp"
#include "render/presenter.hpp"
#include "render/raymarcher.hpp"
#include "viewer/camera_controller.hpp"
#include "viewer/frame_budget.hpp"
#include "viewer/panels.hpp"
#include "scene/scene_json.hpp"
#include "scene_source.hpp"
#include "kernel/volume_cache.hpp"
#include "scene/instant.hpp"
#include "viewer/playback.hpp"
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

// Keyboard and mouse navigation, unless ImGui wants them.
void navigate(GLFWwindow* win, ViewerState& s, double dt_s) {
  const ImGuiIO& io = ImGui::GetIO();
  core::Camera& cam = *s.scene.camera;
  const double r0 = s.volume.grid.earth_radius_m;
  if (!io.WantCaptureMouse) {
    const double dx = io.MouseDelta.x, dy = io.MouseDelta.y;
    const bool moved = dx != 0.0 || dy != 0.0;
    if (moved && io.MouseDown[0] && !s.fly_mode) orbit(cam, dx, dy, r0);
    else if (moved && (io.MouseDown[1] || (io.MouseDown[0] && s.fly_mode))) look(cam, dx, dy);
    if (io.MouseWheel != 0.0f) zoom(cam, io.MouseWheel, r0);
  }
  if (!io.WantCaptureKeyboard && s.fly_mode) {
    auto key = [&](int k) { return glfwGetKey(win, k) == GLFW_PRESS ? 1.0 : 0.0; };
    const glm::dvec3 dir(key(GLFW_KEY_W) - key(GLFW_KEY_S), key(GLFW_KEY_D) - key(GLFW_KEY_A), key(GLFW_KEY_E) - key(GLFW_KEY_Q));
    const double boost = key(GLFW_KEY_LEFT_SHIFT) > 0.0 ? 5.0 : 1.0;
    if (dir != glm::dvec3(0.0)) fly(cam, dir * boost, dt_s, r0);
  }
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
        try {
          std::size_t used = 0;
          o.play_h_per_s = std::stod(v, &used);
          if (used != v.size()) o.play_h_per_s = -1.0;
        } catch (const std::exception&) {
          o.play_h_per_s = -1.0;
        }
        if (!(o.play_h_per_s > 0.0 && o.play_h_per_s <= 1000.0)) {
          throw ViewerInputError("cloudviewer view: --play: found '" + v + "', expected forecast hours per second of wall time, > 0 and <= 1000");
        }
      } else if (a == "--screenshot") {
        o.screenshot = next();
      } else if (a == "--scale") {
        o.scale_given = true;
        const std::string v = next();
        try {
          std::size_t used = 0;
          o.scale = std::stod(v, &used);
          if (used != v.size()) o.scale = -1.0;
        } catch (const std::exception&) {
          o.scale = -1.0;
        }
        if (!(o.scale >= 0.1 && o.scale <= 1.0)) {
          throw ViewerInputError("cloudviewer view: --scale: found '" + v + "', expected a resolution scale in 0.1..1");
        }
      } else if (a == "--frame-budget") {
        const std::string v = next();
        try {
          std::size_t used = 0;
          o.frame_budget_ms = std::stod(v, &used);
          if (used != v.size()) o.frame_budget_ms = -1.0;
        } catch (const std::exception&) {
          o.frame_budget_ms = -1.0;
        }
        if (!(o.frame_budget_ms >= 0.0 && o.frame_budget_ms <= 1e7)) {
          throw ViewerInputError("cloudviewer view: --frame-budget: found '" + v + "', expected a frame time in ms 0..1e7 (0: off)");
        }
      } else if (a == "--realtime") {
        o.realtime = true;
      } else if (a == "--hide-ui") {
        o.hide_ui = true;
      } else if (!a.empty() && a[0] == '-') {
        throw ViewerInputError("cloudviewer view: unknown option '" + a + "'");
      } else if (o.input.empty()) {
        o.input = a;
      } else {
        throw ViewerInputError("cloudviewer view: unexpected argument '" + a + "', expected one INPUT");
      }
    }
    if (o.input.empty()) throw ViewerInputError("cloudviewer view: expected INPUT (.nc, .cvvol or a scene .json)");
    if (!o.screenshot.empty() && o.frames == 0) {
      throw ViewerInputError("cloudviewer view: --screenshot: expected --frames N as well (the frame to save is the Nth)");
    }
    if (!o.screenshot.empty()) {  // checked before the window opens, so a bad path costs no frames
      core::check_output_extension(o.screenshot, "--screenshot", {".png"});
      core::check_output_path(o.screenshot, "--screenshot");
      core::check_output_not_input(o.screenshot, "--screenshot", o.input, "the input");
    }
    if (ends_with(o.input, ".json")) o.scene = core::load_scene(o.input);
  } catch (const std::runtime_error& e) {  // ViewerInputError, core::InputError and core::SceneError
    std::fprintf(stderr, "%s\n", e.what());
    return kExitBadInput;
  }
  return run_viewer(o);
}

int run_viewer(const ViewerOptions& o) {
  ViewerState s;
  if (o.scene) {
    s.scene = *o.scene;
  } else {
    s.scene.data.path = o.input;
  }
  try {
    s.volume = importers::load_scene_volume(s.scene, 2);
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
  bool have_volume = false;
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

  auto win = render::make_window_context(o.width, o.height, "cloudviewer - " + o.input);
  glfwSwapInterval(o.frames > 0 ? 0 : 1);
  const render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  render::FrameRenderer renderer(loader);
  render::Presenter presenter(loader);
  core::PreparedVolumeCache volumes;  // the time steps shown last, prepared once each
  overlays::OverlayBuilder overlay_builder;  // the overlays' geometry, rebuilt only when its inputs change

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
  FrameStats stats;
  stats.renderer = win->info().renderer;
  PassTimer march_timer, present_timer;
  int accumulated = 0;
  double auto_exposure = render::kDefaultExposure;  // the last automatic exposure (render::auto_exposure)
  bool show_ui = !o.hide_ui, f1_was_down = false;
  core::Scene previous;
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  auto last = start, fps_since = start;
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
    s.scene.width = fbw;
    s.scene.height = fbh;
    if (!s.scene.camera) {
      s.scene.camera = core::auto_camera(g, fbw, fbh);
      ctx.home = *s.scene.camera;
      ctx.goto_lat_deg = ctx.home.lat_deg, ctx.goto_lon_deg = ctx.home.lon_deg, ctx.goto_alt_m = ctx.home.alt_m;
    }

    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    const bool f1 = glfwGetKey(win->window(), GLFW_KEY_F1) == GLFW_PRESS;
    if (f1 && !f1_was_down) show_ui = !show_ui;
    f1_was_down = f1;
    navigate(win->window(), s, dt);
    if (show_ui) draw_panels(s, ctx, stats);
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
    if (budget.update(s.scene.render, g.alt_m.step, frame_ms, marched_last)) {
      if (!budget_was_on) std::printf("frame budget %g ms: candidates from %s\n", s.scene.render.budget_ms, budget.source().c_str());
      if (o.frames > 0) std::printf("frame budget %g ms: frame %d: %s\n", s.scene.render.budget_ms, frame, budget.status().c_str());
    }
    ctx.budget_text = budget.on() ? budget.status() + "; from " + budget.source() : "";
    // The march size follows the window and the resolution scale; the camera renders at it.
    int mw = 0, mh = 0;
    march_size(s.scene, fbw, fbh, mw, mh);
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
    if (prefetch && (on_timeline || s.play.playing)) {
      const std::int64_t want_t = *core::parse_iso_utc(s.scene.time.valid_utc);
      std::vector<std::int64_t> wanted = {want_t};
      if (s.play.playing) {
        const std::vector<std::int64_t> next = s.play.upcoming(static_cast<int>(kResidentInstants) - 1);
        wanted.insert(wanted.end(), next.begin(), next.end());
      }
      prefetch->want(wanted, s.scene.time.interpolation);
      core::TimeInterpolationReport interp;
      const bool first_ask = want_t != shown_instant;
      auto v = first_ask ? prefetch->get(want_t, (o.frames > 0 && !o.realtime) || !have_volume, &interp) : nullptr;
      if (v) {
        renderer.use_volume(v);
        shown_instant = want_t;
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
      char text[200];
      std::snprintf(text, sizeof text, "prefetch: %zu/%zu instants resident, %.1f MB, hits %zu, misses %zu (%.0f %%), last %.0f ms",
                    ps.resident, ps.max_resident, double(ps.resident_bytes) / 1e6, ps.hits, ps.misses,
                    ps.hits + ps.misses ? 100.0 * double(ps.hits) / double(ps.hits + ps.misses) : 0.0, ps.last_prepare_ms);
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
      renderer.use_volume(volumes.get(s.scene.data.path, s.volume, at, s.scene.time.interpolation, &interp));
      ctx.time_warning = interp.warning;
      ctx.instant_text = at.iso_utc + (at.between() ? std::string(" (") + core::time_interpolation_name(interp.used) + " between steps)" : "");
      have_volume = true;
      shown_instant = INT64_MIN;
    }
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
    if (presenter.width() != mw || presenter.height() != mh) presenter.resize(mw, mh);
    // The frame as `render` resolves it (camera at the march size, sun, settings).
    core::FrameSpec spec;
    try {
      spec = render::resolve_frame(s.scene, s.volume);
      ctx.sun = spec.sun;
      ctx.sun_error.clear();
    } catch (const std::invalid_argument& e) {
      ctx.sun_error = e.what();  // keep the last good sun while the date/time is being typed
      core::Scene held = s.scene;
      held.sun.mode = core::SunMode::Manual;
      held.sun.subsolar_lat_deg = ctx.sun.subsolar_lat_deg, held.sun.subsolar_lon_deg = ctx.sun.subsolar_lon_deg;
      spec = render::resolve_frame(held, s.volume);
    }
    if (frame == 0 || !same_march(s.scene, previous)) accumulated = 0;
    previous = s.scene;

    // One more jittered frame into the mean until the target; a target of 1 marches at step middles
    // exactly as `render` does without --accumulate.
    marched_last = accumulated < s.scene.render.accumulate;
    if (marched_last) {
      if (accumulated == 0) {  // a new mean: the overlays for this view (VTK only when a scene has some)
        try {
          const auto built = overlay_builder.build(s.scene.overlays, s.volume, static_cast<std::size_t>(s.scene.time_step), spec.march_camera);
          stats.overlays.resize(built.size());
          for (std::size_t i = 0; i < built.size(); ++i) {
            if (built[i].rebuilt) stats.overlays[i].build_ms = built[i].build_ms;
          }
          std::vector<render::OverlayDraw> draws = overlays::OverlayBuilder::draws(built);
          if (s.keys.draw_path && s.scene.path) {  // the camera path on the globe, after the scene's overlays
            auto track = std::make_shared<const core::OverlayMesh>(path_mesh(s.scene, g.earth_radius_m));
            if (!track->empty()) draws.push_back({"camera path", track, nullptr, 2.0f});
          }
          renderer.set_overlays(std::move(draws));
        } catch (const overlays::OverlayError& e) {
          ctx.scene_message = e.what();
          renderer.set_overlays({});
        }
      }
      march_timer.begin();
      renderer.march_into(presenter.frame_texture(), spec, accumulated);
      march_timer.end();
      present_timer.begin();
      presenter.accumulate(accumulated);
      ++accumulated;
      // The automatic exposure from the mean at the march size (as `render` takes it), when the mean
      // starts and when it is complete: not frame by frame, so the picture does not pulse.
      if (spec.auto_exposure && (accumulated == 1 || accumulated == s.scene.render.accumulate)) {
        std::vector<glm::vec4> mean(static_cast<std::size_t>(mw) * mh);
        glGetTextureImage(presenter.mean_texture(), 0, GL_RGBA, GL_FLOAT,
                          static_cast<GLsizei>(mean.size() * sizeof(glm::vec4)), mean.data());
        auto_exposure = render::auto_exposure(mean);
      }
    } else {
      present_timer.begin();
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    render::ToneSettings tone;
    tone.exposure = spec.auto_exposure ? auto_exposure : spec.exposure;
    ctx.auto_exposure = auto_exposure;
    if (s.scene.render.march.features.atmosphere || s.scene.render.march.features.globe) tone.background = glm::dvec3(0.0);
    presenter.draw(tone, 0, 0, fbw, fbh);
    present_timer.end();
    stats.march_ms = march_timer.ms();
    stats.present_ms = present_timer.ms();
    for (std::size_t i = 0; i < stats.overlays.size(); ++i) {  // one per scene overlay, in order (0: off)
      stats.overlays[i].draw_ms = i < renderer.overlay_draw_ms().size() ? renderer.overlay_draw_ms()[i] : 0.0;
    }
    if (show_ui) stats.march = renderer.last_stats();  // read back only when shown (it waits for the march)
    stats.accumulated = accumulated;
    stats.march_w = mw;
    stats.march_h = mh;
    if (show_ui) draw_stats_overlay(stats, s.scene.render.accumulate);  // built after the march: this frame's count

    ImGui::Render();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    if (o.frames > 0 && frame == o.frames - 1 && !o.screenshot.empty()) {
      save_screenshot(o.screenshot, fbw, fbh);
      march_timer.finish();
      stats.march_ms = march_timer.ms();
      std::printf("wrote %s (%d x %d window, %d frame(s) accumulated in %.2f s wall, GPU march %.1f ms per frame on %s)\n",
                  o.screenshot.c_str(), fbw, fbh, accumulated, std::chrono::duration<double>(clock::now() - start).count(),
                  stats.march_ms, stats.renderer.c_str());
      if (budget.on()) std::printf("frame budget %g ms: ended on %s\n", s.scene.render.budget_ms, budget.status().c_str());
      if (!stats.prefetch.empty()) std::printf("%s\n", stats.prefetch.c_str());
    }
    win->swap_buffers();
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
