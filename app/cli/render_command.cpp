// `cloudviewer render`: builds the effective scene (scene file or defaults, then the options on
// top), imports only the part of the data it needs, renders on the GPU with progress, and prints
// where the time went per pass.
#include "render_command.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

#include <unistd.h>

#include <glm/glm.hpp>

#include "cli_common.hpp"
#include "io/output_file.hpp"
#include "importer.hpp"
#include "noise/noise.hpp"
#include "quality_budget.hpp"
#include "render/albedo_map.hpp"
#include "render/context.hpp"
#include "render/exr_output.hpp"
#include "render/image_output.hpp"
#include "render/machine_id.hpp"
#include "render/raymarcher.hpp"
#include "render/shader_loader.hpp"
#include "geo/geodesy.hpp"
#include "reference/earth_shadow.hpp"
#include "scene/framing.hpp"
#include "scene/instant.hpp"
#include "scene/quality.hpp"
#include "scene/scene_json.hpp"
#include "kernel/detail_drift.hpp"
#include "kernel/volume_cache.hpp"
#include "overlays/overlays.hpp"
#include "render/frame_renderer.hpp"
#include "scene_source.hpp"
#include "volume/volume_io.hpp"

namespace cv::cli {
namespace {

namespace fs = std::filesystem;
using clock = std::chrono::steady_clock;

// A single frame larger than this is marched in tiles of rows of about this many pixels, each
// reported as it finishes (a 1920x1080 frame takes about 15 s on llvmpipe, see docs/BENCHMARKS.md).
constexpr double kTilePixels = 262144.0;

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}


// The most view steps one ray may take: beyond it a render runs for hours (a step of 1 m across a
// 20 km layer is a million steps per ray), so it is refused before it starts.
constexpr int kMaxViewStepsPerRay = 250000;

void check_view_steps(double view_step_m, double r0_m, double top_m) {
  const int steps = render::max_view_steps(r0_m, top_m, view_step_m);
  if (steps <= kMaxViewStepsPerRay) return;
  const double top = std::max(top_m, 0.0);
  const double chord = 2.0 * std::sqrt((r0_m + top) * (r0_m + top) - r0_m * r0_m);
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "cloudviewer render: view_step_m (--steps): found %g m, which takes up to %d steps per ray across this volume's "
                "cloud layer (top %.0f m); expected at most %d steps: a step of at least %.3g m (range 1..1e7 m)",
                view_step_m, steps, top_m, kMaxViewStepsPerRay, chord / (kMaxViewStepsPerRay - 4));
  throw UsageError{buf};
}

// Progress on one line that rewrites itself on a terminal; piped or written to a file, one line
// each, so the lines do not run together.
bool g_progress_open = false;
template <class... A>
void progress_line(const char* format, A... args) {
  const bool tty = ::isatty(::fileno(stdout)) != 0;
  if (tty) std::printf("\r");
  std::printf(format, args...);
  if (!tty) std::printf("\n");
  g_progress_open = tty;
  std::fflush(stdout);
}
void end_progress() {
  if (g_progress_open) std::printf("\n");
  g_progress_open = false;
}

// What the options ask for, applied on top of the scene file (or the defaults) in one place.
struct RenderArgs {
  std::string input, out, pfm, exr, save_scene;
  std::string front;              // --front FILE: the measured quality front for --budget-ms
  bool march_overridden = false;  // --steps, --sun-steps, --octaves or --accumulate: quality becomes custom
  bool quality_given = false, adaptive_given = false, budget_given = false;
  // --quality reference: the GPU path tracer, up to `spp` samples per pixel or until the image's
  // mean relative standard error falls to target_error (0: all spp).
  bool reference = false;
  int spp = 1024;
  double target_error = 0.0;
  bool spp_given = false;
  // --times START..END --every DURATION: a numbered PNG sequence into the folder -o names.
  std::string times_from, times_to;
  std::int64_t every_s = 0;
};

// "90s", "30m", "1h", "1.5h" (or a bare number of seconds) in whole seconds, or nothing.
std::optional<std::int64_t> parse_duration_s(const std::string& text) {
  if (text.empty()) return std::nullopt;
  double unit = 1.0;
  std::string num = text;
  const char last = text.back();
  if (last == 's' || last == 'm' || last == 'h') {
    unit = last == 'h' ? 3600.0 : last == 'm' ? 60.0 : 1.0;
    num = text.substr(0, text.size() - 1);
  }
  double v = 0.0;
  std::size_t used = 0;
  try {
    v = std::stod(num, &used);
  } catch (const std::exception&) {
    return std::nullopt;
  }
  if (used != num.size() || !(v > 0.0) || !(v * unit <= 1e9)) return std::nullopt;
  const double s = std::round(v * unit);
  if (s < 1.0) return std::nullopt;
  return static_cast<std::int64_t>(s);
}

int parse_int(const std::string& option, const std::string& text, int lo, int hi, const std::string& what) {
  const double v = parse_number(option, text);
  if (!(v >= lo && v <= hi) || v != std::floor(v)) {
    throw UsageError{"cloudviewer render: " + option + ": found '" + text + "', expected " + what};
  }
  return static_cast<int>(v);
}

// The table row whose flag this is (settings/march_settings.def), or nullptr.
const core::SettingRow* march_flag(const std::string& option) {
  for (const core::SettingRow& row : core::kMarchSettingRows) {
    if (row.flag && option == row.flag) return &row;
  }
  return nullptr;
}

// A table row's flag applied to `m`: its value read with the row's range and wording, as a scene
// file's key is; a Bool row's flag takes no value and sets the opposite of the default (--no-skip).
void apply_march_flag(const core::SettingRow& row, const std::string& text, core::MarchSettings& m) {
  static const core::MarchSettings defaults;
  core::for_each_march_setting_pair(m, defaults, [&](const core::SettingRow& r, auto& value, const auto& def) {
    using T = std::decay_t<decltype(value)>;
    if (&r != &row) return;
    if constexpr (std::is_same_v<T, bool>) {
      if (row.kind == core::SettingKind::Choice) {  // one of the two names, as in a scene file
        if (text != row.choices[0] && text != row.choices[1]) {
          throw UsageError{"cloudviewer render: " + std::string(row.flag) + ": found '" + text + "', expected " +
                           core::expected_text(row)};
        }
        value = text == row.choices[1];
      } else {
        value = !def;
      }
    } else if constexpr (std::is_same_v<T, int> || std::is_same_v<T, double>) {
      double v = 0.0;
      std::size_t used = 0;
      try {
        v = std::stod(text, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (text.empty() || used != text.size() || !core::in_range(row, v)) {
        throw UsageError{"cloudviewer render: " + std::string(row.flag) + ": found '" + text + "', expected " +
                         core::expected_text(row)};
      }
      value = static_cast<T>(v);
    }
  });
}

// Before any work: every output has a name the command can write, in a folder that exists and can
// be written, none is an input (the render's input, the scene's data, its ground image, the front)
// and no two are the same file; the scene's ground image is a regular file.
void check_outputs(const RenderArgs& r, const core::Scene& scene) {
  const std::string& ground = scene.render.march.medium.ground_texture;
  if (!ground.empty() && ground != "none") core::require_regular_file(ground, "render.march.ground_texture, the ground image");
  if (!r.front.empty()) core::require_regular_file(r.front, "the quality front");
  if (!r.times_from.empty()) {  // a folder of frames: it exists as a folder, or its parent does
    const fs::path dir(r.out);
    std::error_code ec;
    if (fs::exists(dir, ec) && !fs::is_directory(dir, ec)) {
      throw UsageError{"cloudviewer render: -o: found '" + r.out + "', which is not a folder, expected a folder for the frames of --times"};
    }
    const fs::path parent = fs::absolute(dir).lexically_normal().parent_path();
    if (!fs::exists(dir, ec) && !fs::is_directory(parent, ec)) {
      throw UsageError{"cloudviewer render: -o: found '" + r.out + "', whose folder " + parent.string() +
                       " does not exist, expected a folder for the frames of --times"};
    }
    return;
  }
  std::vector<std::pair<std::string, std::string>> outputs = {{r.out, "-o"}};
  core::check_output_extension(r.out, "-o", {".png"});
  if (!r.pfm.empty()) {
    core::check_output_extension(r.pfm, "--pfm", {".pfm"});
    outputs.push_back({r.pfm, "--pfm"});
    outputs.push_back({render::transmittance_pfm_path(r.pfm), "--pfm (its transmittance beside it)"});
  }
  if (!r.exr.empty()) {
    core::check_output_extension(r.exr, "--exr", {".exr"});
    outputs.push_back({r.exr, "--exr"});
  }
  if (!r.save_scene.empty()) {
    core::check_output_extension(r.save_scene, "--save-scene", {".json"});
    outputs.push_back({r.save_scene, "--save-scene"});
  }
  const std::pair<std::string, std::string> inputs[] = {{r.input, "the input"},
                                                        {scene.data.path, "the data (data.path)"},
                                                        {ground == "none" ? "" : ground, "the ground image"},
                                                        {r.front, "the quality front (--front)"}};
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const auto& [path, option] = outputs[i];
    core::check_output_path(path, option);
    for (const auto& [in, what] : inputs) core::check_output_not_input(path, option, in, what);
    for (std::size_t j = 0; j < i; ++j) core::check_output_not_input(path, option, outputs[j].first, "the output of " + outputs[j].second);
  }
}

// The options, applied to `scene` in the order given (later ones win).
RenderArgs parse_render_args(const std::vector<std::string>& args, core::Scene& scene) {
  RenderArgs r;
  // Every option but --no-sky, --diagnose-cloud and the table's Bool flags (--no-skip) takes a value; the one argument that is no
  // option's value is the input. It is read first so that a scene file's settings are the base the options override.
  std::vector<std::pair<std::string, std::string>> options;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    const core::SettingRow* row = march_flag(a);
    if (a == "--no-sky" || a == "--diagnose-cloud" || (row && row->kind == core::SettingKind::Bool)) {  // the flags without a value
      options.emplace_back(a, "");
    } else if (!a.empty() && a[0] == '-') {
      if (i + 1 >= args.size()) throw UsageError{"cloudviewer render: " + a + ": expected a value after it"};
      options.emplace_back(a, args[++i]);
    } else if (r.input.empty()) {
      r.input = a;
    } else {
      throw UsageError{"cloudviewer render: unexpected argument '" + a + "', expected one INPUT"};
    }
  }
  if (r.input.empty()) throw UsageError{"cloudviewer render: expected INPUT (.nc, .cvvol or a scene .json) and -o OUT.png"};
  if (ends_with(r.input, ".json")) {
    scene = core::load_scene(r.input);
  } else {
    scene = core::Scene{};
    core::apply_quality("default", scene.render);
    scene.data.path = r.input;
  }
  auto& m = scene.render.march;
  for (const auto& [a, v] : options) {
    if (a == "-o") r.out = v;
    else if (a == "--pfm") r.pfm = v;
    else if (a == "--exr") r.exr = v;
    else if (a == "--save-scene") r.save_scene = v;
    else if (a == "--size") {
      const auto size = parse_size(v, 1, 16384);
      if (!size) throw UsageError{"cloudviewer render: --size: found '" + v + "', expected WxH with 1..16384 each"};
      scene.width = size->first, scene.height = size->second;
    } else if (a == "--overlay") {
      try {
        scene.overlays.push_back(core::parse_overlay_flag(v));
      } catch (const std::invalid_argument& e) {
        throw UsageError{std::string("cloudviewer render: ") + e.what()};
      }
    } else if (a == "--time") {  // a UTC instant, or a step index (still accepted, and converted)
      if (core::parse_iso_utc(v)) {
        scene.time.valid_utc = v;
      } else {
        scene.time_step = parse_int(a, v, 0, 1 << 30, "a UTC date-time YYYY-MM-DDThh:mm:ssZ or a time-step index >= 0");
        scene.time.valid_utc.clear();
      }
    } else if (a == "--times") {
      const std::size_t dots = v.find("..");
      if (dots == std::string::npos || !core::parse_iso_utc(v.substr(0, dots)) || !core::parse_iso_utc(v.substr(dots + 2)) ||
          *core::parse_iso_utc(v.substr(dots + 2)) < *core::parse_iso_utc(v.substr(0, dots))) {
        throw UsageError{"cloudviewer render: --times: found '" + v +
                         "', expected START..END, two UTC date-times YYYY-MM-DDThh:mm:ssZ with START <= END"};
      }
      r.times_from = v.substr(0, dots), r.times_to = v.substr(dots + 2);
    } else if (a == "--every") {
      const auto d = parse_duration_s(v);
      if (!d) throw UsageError{"cloudviewer render: --every: found '" + v + "', expected a duration such as 30m, 1h or 90s (at least 1 s)"};
      r.every_s = *d;
    } else if (a == "--interpolation") {
      if (!core::parse_time_interpolation(v, scene.time.interpolation)) {
        throw UsageError{"cloudviewer render: --interpolation: found '" + v + "', expected auto, nearest, linear or advected"};
      }
    } else if (a == "--sun-mode") {
      if (v != "valid_time" && v != "local_noon") {
        throw UsageError{"cloudviewer render: --sun-mode: found '" + v + "', expected valid_time or local_noon"};
      }
      core::parse_sun_mode(v, scene.sun.mode);
    } else if (a == "--camera") {
      const auto c = parse_list(a, v, ',', 6, 6, "lat,lon,alt_m,heading,pitch,fov in degrees and metres");
      if (!(c[2] >= 0.0 && c[2] <= 4e8) || !(c[5] > 0.0 && c[5] < 180.0) || std::abs(c[0]) > 90.0 || std::abs(c[4]) > 90.0) {
        throw UsageError{"cloudviewer render: --camera: found '" + v +
                         "', expected |lat| <= 90, altitude 0..4e8 m, |pitch| <= 90 and fov in (0, 180) degrees"};
      }
      core::Camera cam;
      cam.lat_deg = c[0], cam.lon_deg = c[1], cam.alt_m = c[2], cam.heading_deg = c[3], cam.pitch_deg = c[4], cam.fov_deg = c[5];
      scene.camera = cam;
    } else if (a == "--sun") {
      const auto s = parse_list(a, v, ',', 2, 2, "the subsolar point lat,lon in degrees");
      if (std::abs(s[0]) > 90.0) throw UsageError{"cloudviewer render: --sun: found '" + v + "', expected |lat| <= 90"};
      scene.sun.mode = core::SunMode::Manual;
      scene.sun.subsolar_lat_deg = s[0], scene.sun.subsolar_lon_deg = s[1];
    } else if (a == "--sun-time") {
      if (!core::parse_iso_utc(v)) {
        throw UsageError{"cloudviewer render: --sun-time: found '" + v + "', expected a UTC date-time YYYY-MM-DDThh:mm:ssZ"};
      }
      scene.sun.mode = core::SunMode::DateTime;
      scene.sun.datetime_utc = v;
    } else if (a == "--quality") {
      if (v == "reference") {
        r.reference = true;
        r.quality_given = true;
      } else if (v == "custom") {
        scene.render.quality = v;
      } else if (core::find_quality(v)) {
        core::apply_quality(v, scene.render);
        r.quality_given = true;
      } else {
        throw UsageError{"cloudviewer render: --quality: found '" + v + "', expected one of " + core::quality_names() +
                         " or reference"};
      }
    } else if (const core::SettingRow* row = march_flag(a)) {
      apply_march_flag(*row, v, m);
      const std::string key = row->key;
      // What the quality presets set: given by hand, the quality becomes custom (and a budget,
      // which chooses them, contradicts them).
      if (key == "view_step_m" || key == "sun_steps" || key == "octaves") r.march_overridden = true;
      if (key == "max_step_optical_depth") {  // --adaptive TAU: the substep's optical depth, and adaptive steps on
        m.features.adaptive_steps = true;
        r.adaptive_given = true;
      }
    } else if (a == "--accumulate") {
      const core::SettingRow& acc = core::find_quality_knob("accumulate")->row;
      scene.render.accumulate = parse_int(a, v, static_cast<int>(acc.lo), static_cast<int>(acc.hi),
                                          core::range_text(acc) + " frames");
      r.march_overridden = true;
    } else if (a == "--spp") {
      r.spp = parse_int(a, v, 1, 1000000, "a number of samples per pixel 1..1e6");
      r.spp_given = true;
    } else if (a == "--target-error") {
      r.target_error = parse_number(a, v);
      if (!(r.target_error > 0.0 && r.target_error < 1.0)) {
        throw UsageError{"cloudviewer render: --target-error: found '" + v + "', expected a relative standard error between 0 and 1"};
      }
    } else if (a == "--budget-ms") {
      scene.render.budget_ms = parse_number(a, v);
      if (!(scene.render.budget_ms > 0 && scene.render.budget_ms <= 1e7)) {
        throw UsageError{"cloudviewer render: --budget-ms: found '" + v + "', expected a time budget in milliseconds, > 0 and <= 1e7"};
      }
      r.budget_given = true;
    } else if (a == "--front") {
      r.front = v;
    } else if (a == "--layer") {  // a named band of the layer mask (core::named_layer_band)
      core::LayerBand band;
      if (!core::named_layer_band(v, band)) {
        throw UsageError{"cloudviewer render: --layer: found '" + v + "', expected low, mid, high or all (heights above the ground)"};
      }
      m.medium.layer_bottom_m = band.bottom_m;
      m.medium.layer_top_m = band.top_m;
      m.medium.layer_sea_level = false;
    } else if (a == "--no-sky") {
      m.features.atmosphere = m.features.globe = false;
      m.medium.ambient = 0.0;
    } else if (a == "--exposure") {
      scene.render.auto_exposure = v == "auto";
      if (!scene.render.auto_exposure) {
        scene.render.exposure = parse_number(a, v);
        if (!(scene.render.exposure > 0))
          throw UsageError{"cloudviewer render: --exposure: found '" + v + "', expected a number > 0 or auto"};
      }
    } else if (a == "--region") {
      const auto g = parse_list(a, v, ',', 4, 4, "W,E,S,N in degrees");
      if (g[2] > g[3] || g[2] < -90 || g[3] > 90) {
        throw UsageError{"cloudviewer render: --region: found '" + v + "', expected S <= N within -90..90"};
      }
      scene.data.region_deg = std::array<double, 4>{g[0], g[1], g[2], g[3]};
    } else if (a == "--levels") {
      const auto l = parse_list(a, v, ':', 2, 2, "MIN_HPA:MAX_HPA");
      if (!(l[0] >= 0 && l[0] <= l[1])) throw UsageError{"cloudviewer render: --levels: found '" + v + "', expected 0 <= MIN <= MAX hPa"};
      scene.data.levels_hpa = std::array<double, 2>{l[0], l[1]};
    } else if (a == "--stride") {
      scene.data.horizontal_stride = parse_int(a, v, 1, 1000000, "an integer >= 1");
    } else if (a == "--diagnose-cloud") {
      scene.data.diagnose_cloud = true;
    } else if (a == "--rh-critical") {
      scene.data.rh_critical = parse_number(a, v);
      if (!(scene.data.rh_critical >= 0.5 && scene.data.rh_critical < 1.0)) {
        throw UsageError{"cloudviewer render: --rh-critical: found '" + v + "', expected a critical relative humidity 0.5 <= RH < 1"};
      }
    } else {
      throw UsageError{"cloudviewer render: unknown option '" + a + "'"};
    }
  }
  if (r.out.empty()) throw UsageError{"cloudviewer render: expected -o OUT.png"};
  if (!r.times_from.empty() || r.every_s > 0) {
    if (r.times_from.empty() || r.every_s <= 0) {
      throw UsageError{"cloudviewer render: --times and --every: found one without the other, expected both (--times START..END --every 30m)"};
    }
    if (!r.pfm.empty() || !r.exr.empty() || !r.save_scene.empty() || r.reference || scene.render.budget_ms > 0) {
      throw UsageError{"cloudviewer render: --times: found it with --pfm, --exr, --save-scene, --quality reference or a budget, "
                       "expected a sequence of PNGs alone"};
    }
    const std::int64_t count = (*core::parse_iso_utc(r.times_to) - *core::parse_iso_utc(r.times_from)) / r.every_s + 1;
    if (count > 100000) {
      throw UsageError{"cloudviewer render: --times and --every: found " + std::to_string(count) + " frames, expected at most 100000"};
    }
  }
  if (!r.reference && (r.spp_given || r.target_error > 0.0)) {
    throw UsageError{"cloudviewer render: --spp and --target-error: found them without a path tracer, expected --quality reference"};
  }
  if (r.reference && !r.pfm.empty()) {
    throw UsageError{"cloudviewer render: --pfm: found it with --quality reference, expected one or the other (the path tracer "
                     "estimates radiance, not the transmittance the PFM pair holds)"};
  }
  if (r.reference && r.budget_given) {
    throw UsageError{"cloudviewer render: --budget-ms: found it with --quality reference, expected one or the other"};
  }
  // The budget chooses the quality knobs: given together on the command line they contradict each
  // other; options override a scene file's budget as they override its other keys.
  if (r.budget_given && (r.march_overridden || r.quality_given || r.adaptive_given)) {
    throw UsageError{"cloudviewer render: --budget-ms: found it with --quality, --steps, --sun-steps, --octaves, --accumulate or "
                     "--adaptive, expected one or the other (the budget chooses those settings)"};
  }
  if (!r.budget_given && scene.render.budget_ms > 0 && (r.march_overridden || r.quality_given || r.adaptive_given)) {
    std::printf("the scene's render.budget_ms (%g ms) is off: quality options on the command line override it\n", scene.render.budget_ms);
    scene.render.budget_ms = 0.0;
  }
  if (!r.front.empty() && !(scene.render.budget_ms > 0)) {
    throw UsageError{"cloudviewer render: --front: found it without a budget, expected --budget-ms MS (or render.budget_ms in the scene)"};
  }
  if (scene.data.path.empty()) {
    throw UsageError{"cloudviewer render: " + r.input + ": data.path: found nothing, expected the NetCDF or .cvvol file to render"};
  }
  check_outputs(r, scene);
  return r;
}

}  // namespace

const char* render_usage() {
  // The march settings' flags come from their rows, with the range a scene file accepts.
  static const std::string text = [] {
    std::string t =
        "  render INPUT -o OUT.png   INPUT: NetCDF, .cvvol or a scene .json (docs/scene.md); options override it:\n"
        "         [--size WxH] [--time ISO|N] [--camera lat,lon,alt_m,heading,pitch,fov] [--sun LAT,LON | --sun-time ISO]\n"
        "         [--quality low|default|high|custom] [--accumulate N]\n"
        "         [--time YYYY-MM-DDThh:mm:ssZ]  any instant within the file's times (between steps the medium is\n"
        "                           interpolated); a step index N is still accepted\n"
        "         [--interpolation auto|nearest|linear|advected]  time.interpolation: between steps, the nearest step,\n"
        "                           a blend, or both neighbours carried along the winds then blended (auto: advected\n"
        "                           where the file has winds, else linear)\n"
        "         [--times START..END --every DURATION]  -o names a folder: frame_00000.png, ... at START, START +\n"
        "                           DURATION (30m, 1h, 90s), ... up to END, with progress; frames already written\n"
        "                           whole are skipped, so a stopped run resumes\n"
        "         [--sun-mode valid_time|local_noon]  sun.mode: the physical sun at the instant, or for teaching the\n"
        "                           sun at local noon over the camera (the instant's declination), so no frame is dark\n"
        "         [--quality reference [--spp N] [--target-error E]]  the GPU path tracer (full multiple scattering,\n"
        "                           clouds and the ground lit by the sun through the air and by the sky, seen through\n"
        "                           the haze in front of them): N samples per pixel at most (1024),\n"
        "                           fewer once the image's mean relative standard error is E\n"
        "         [--exposure E|auto] [--region W,E,S,N] [--levels MIN_HPA:MAX_HPA] [--stride N]\n"
        "         [--diagnose-cloud [--rh-critical RH]]  data.diagnose_cloud: a file with temperature and humidity but\n"
        "                           no cloud field gets a cloud diagnosed from relative humidity (Sundqvist, RH_c 0.8),\n"
        "                           said on stderr\n"
        "         [--no-sky]  clouds on black: no air, globe or ambient sky light\n"
        "         [--layer low|mid|high|all]  the layer mask's band: below 2 km, 2-6 km, from 6 km above the ground, or\n"
        "                           everything (sets layer_bottom_m and layer_top_m, below; docs/scene.md)\n"
        "         [--overlay NAME[:key=value,...]]  an overlay composited with the clouds by depth (repeatable):\n"
        "                           coastlines, borders, rivers, graticule, isosurface, wind or section, with the keys of docs/scene.md's Overlays\n"
        "                           table, e.g. --overlay graticule:step_deg=15,color=1,1,1\n";
    for (const core::SettingRow& row : core::kMarchSettingRows) {
      if (!row.flag) continue;
      std::string opt = std::string("[") + row.flag + (row.metavar ? std::string(" ") + row.metavar : "") + "]";
      opt.resize(std::max<std::size_t>(opt.size() + 1, 26), ' ');
      if (row.kind == core::SettingKind::Bool) {  // the flag sets the opposite of the default
        bool on = false;
        const core::MarchSettings defaults;
        core::for_each_march_setting(defaults, [&](const core::SettingRow& r, const auto& value) {
          if constexpr (std::is_same_v<std::decay_t<decltype(value)>, bool>) on = &r == &row ? value : on;
        });
        t += "         " + opt + row.key + " " + (on ? "false" : "true") + " (" + (on ? "true" : "false") + ": " + row.doc + ")";
      } else if (row.kind == core::SettingKind::Choice) {
        t += "         " + opt + row.key + ": " + row.doc + " (" + row.choices[0] + " or " + row.choices[1] + ")";
      } else {
        t += "         " + opt + row.key + ": " + row.doc + " (" + core::range_text(row) + ")";
      }
      if (std::string(row.key) == "max_step_optical_depth") t += ", and adaptive_steps on";
      t += "\n";
    }
    return t +
           "         [--pfm OUT.pfm]           linear radiance alone (no background, no exposure), and the\n"
           "                           transmittance beside it as OUT.transmittance.pfm (one channel)\n"
           "         [--exr OUT.exr]           OpenEXR for compositing: R, G, B the linear radiance as --pfm, and\n"
           "                           A = 1 - transmittance (premultiplied: over a plate, RGB + (1 - A) x plate);\n"
           "                           A is 1 where the globe shows and the air's light is in R, G, B: clouds alone\n"
           "                           over a plate with --no-sky; with --quality reference R, G, B alone (the path\n"
           "                           tracer estimates no transmittance)\n"
           "         [--save-scene OUT.json]  (the effective scene, camera and sun resolved, to reproduce the image)\n"
           "         [--budget-ms MS [--front quality_front.json]]  the most accurate settings of the measured front\n"
           "                           (from bench; else its cached copy, else the presets) that render within MS here\n"
           "                           the sun stands where it stood at the valid time unless --sun or --sun-time\n";
  }();
  return text.c_str();
}

// --quality reference: the GPU path tracer at the output size, in batches of samples with progress,
// until ra.spp samples per pixel or the mean relative standard error of the image (over pixels at
// least 5 % of the brightest) falls to ra.target_error. rgb = radiance; a = 0 (no transmittance is
// estimated: no background shows through).
std::vector<glm::vec4> path_trace(render::FrameRenderer& renderer, const core::FrameSpec& frame, const RenderArgs& ra, double& gpu_s) {
  const auto t0 = clock::now();
  core::MonteCarloImage img;
  render::PathTraceStats extra;
  render::PathTraceSettings pt;
  pt.samples_per_readback = 8;
  double error = 0.0;
  while (img.spp < static_cast<std::uint64_t>(ra.spp)) {
    const int batch = static_cast<int>(std::min<std::uint64_t>(static_cast<std::uint64_t>(ra.spp) - img.spp, 8));
    renderer.trace_paths(img, frame, batch, pt, &extra);  // the overlays drawn for the camera
    error = img.spp >= 2 ? img.mean_relative_standard_error() : 1.0;
    progress_line("path traced %llu/%d samples per pixel, mean relative standard error %.4f, %.1f s",
                  static_cast<unsigned long long>(img.spp), ra.spp, error, seconds_since(t0));
    if (ra.target_error > 0.0 && img.spp >= 8 && error <= ra.target_error) break;
  }
  end_progress();
  gpu_s = 0.0;
  std::printf("path tracer: %llu paths, %.2f scatterings per path, %llu null collisions, %llu sun-ray lookups, %llu cut at %d "
              "bounces, %llu ended by roulette, %llu directions drawn in the droplets' peak (branches, from a stack of %d per pixel; "
              "the one-sample technique at %llu vertices that found it full)%s\n",
              static_cast<unsigned long long>(img.stats.paths),
              double(img.stats.scatterings) / double(std::max<std::uint64_t>(img.stats.paths, 1)),
              static_cast<unsigned long long>(img.stats.null_collisions), static_cast<unsigned long long>(img.stats.shadow_lookups),
              static_cast<unsigned long long>(img.stats.truncated), pt.max_bounces,
              static_cast<unsigned long long>(img.stats.roulette_killed), static_cast<unsigned long long>(img.stats.peak_samples),
              extra.branch_slots, static_cast<unsigned long long>(extra.splits_without_room),
              ra.target_error > 0.0 && error > ra.target_error ? "; the target error was not reached within --spp" : "");
  if (img.stats.majorant_exceeded) {
    std::fprintf(stderr, "cloudviewer render: the medium exceeded its majorant at %llu lookups (a bug: the image is biased)\n",
                 static_cast<unsigned long long>(img.stats.majorant_exceeded));
  }
  if (extra.non_finite) std::fprintf(stderr, "cloudviewer render: %llu path samples were not finite and were left out\n",
                                      static_cast<unsigned long long>(extra.non_finite));
  if (extra.near_loop_budget) {
    std::fprintf(stderr, "cloudviewer render: %llu path samples came near the driver's loop budget (llvmpipe) and may be cut short\n",
                 static_cast<unsigned long long>(extra.near_loop_budget));
  }
  std::vector<glm::vec4> out(img.lum_sum.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = glm::vec4(glm::vec3(img.mean(i)), 0.0f);
  return out;
}

// Whether `path` holds a whole PNG (its signature first, its IEND chunk last): a frame a run
// that was stopped already wrote (frames are written atomically, so a partial one never has the name).
bool complete_png(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return false;
  const auto size = fs::file_size(path, ec);
  if (ec || size < 20) return false;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  unsigned char head[8], tail[8];
  const bool ok = std::fread(head, 1, 8, f) == 8 && std::fseek(f, -8, SEEK_END) == 0 && std::fread(tail, 1, 8, f) == 8;
  std::fclose(f);
  static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  return ok && std::equal(head, head + 8, sig) && std::equal(tail, tail + 4, reinterpret_cast<const unsigned char*>("IEND"));
}

// --times START..END --every D: frame_00000.png, ... at START, START + D, ... up to END, each at its
// instant (the medium interpolated, the sun at the instant), skipping frames already written whole.
int render_series(const RenderArgs& ra, core::Scene scene) {
  const auto t_start = clock::now();
  core::CloudVolume vol = importers::load_scene_volume(scene, 2);
  importers::print_diagnosed_cloud_note(vol, "cloudviewer render");
  const auto& g = vol.grid;
  if (g.lon_deg.count < 2 || g.lat_deg.count < 2 || g.alt_m.count < 2) {
    throw UsageError{"cloudviewer render: " + scene.data.path + ": the volume is too small to render (at least 2 points along each axis)"};
  }
  core::instant_at_time(vol.times, ra.times_from, scene.data.path);  // both ends within the file (TimeError otherwise)
  core::instant_at_time(vol.times, ra.times_to, scene.data.path);
  const std::int64_t from = *core::parse_iso_utc(ra.times_from), to = *core::parse_iso_utc(ra.times_to);
  std::vector<std::int64_t> instants;
  for (std::int64_t t = from; t <= to; t += ra.every_s) instants.push_back(t);
  std::error_code ec;
  fs::create_directories(ra.out, ec);
  if (!fs::is_directory(ra.out)) throw UsageError{"cloudviewer render: -o: cannot create the folder '" + ra.out + "' for the frames"};
  auto ctx = render::make_headless_context();
  const render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  render::FrameRenderer renderer(loader);
  core::PreparedVolumeCache volumes;
  std::printf("rendering %zu frames of %s from %s to %s every %lld s, %dx%d, quality %s, interpolation %s, sun %s, into %s\n",
              instants.size(), scene.data.path.c_str(), ra.times_from.c_str(), ra.times_to.c_str(), static_cast<long long>(ra.every_s),
              scene.width, scene.height, scene.render.quality.c_str(), core::time_interpolation_name(scene.time.interpolation),
              core::sun_mode_name(scene.sun.mode), ra.out.c_str());
  std::string warned;
  // Frame i's instant prepared on the GPU, its frame resolved (the sun at the instant), and whether
  // the whole cloud layer is then in the Earth's shadow.
  struct Prepared {
    core::Instant at;
    core::TimeInterpolationReport rep;
    core::FrameSpec frame;
    bool in_shadow = false;
    double probe_s = 0.0;  // the time a probed frame took before the loop (its preparation and march)
  };
  bool steps_checked = false;
  auto prepare = [&](std::size_t i) {
    Prepared p;
    scene.time.valid_utc = core::format_iso_utc(instants[i]);
    p.at = core::scene_instant(scene, vol, scene.data.path);
    const auto prepared = volumes.get(scene.data.path, vol, p.at, scene.time.interpolation, &p.rep, scene.render.march.medium.modelled);
    renderer.use_volume(prepared);
    if (!p.rep.warning.empty() && warned != p.rep.warning) std::printf("warning: %s\n", (warned = p.rep.warning).c_str());
    p.frame = render::resolve_frame(scene, vol);
    if (!steps_checked) check_view_steps(p.frame.march.quality.view_step_m, g.earth_radius_m, g.alt_m.last());
    steps_checked = true;
    p.in_shadow = scene.sun.mode != core::SunMode::LocalNoon &&
                  core::layer_in_earth_shadow(g, prepared->layer, glm::normalize(geo::sphere_to_ecef(
                      {p.frame.sun.subsolar_lat_deg, p.frame.sun.subsolar_lon_deg, 0.0}, g.earth_radius_m)));
    return p;
  };
  // One exposure for the whole sequence, so it does not flicker and a resumed run matches: given,
  // or the least automatic exposure of a few frames spread over it (render::sequence_exposure),
  // whose images are kept for the loop below.
  std::optional<double> exposure;
  std::map<std::size_t, std::pair<Prepared, std::vector<glm::vec4>>> probed;
  if (!scene.render.auto_exposure) {
    exposure = scene.render.exposure;
  } else {
    std::vector<std::optional<double>> probes;
    std::string which;
    for (const int k : render::exposure_probe_frames(static_cast<int>(instants.size()))) {
      const auto t_probe = clock::now();
      Prepared p = prepare(static_cast<std::size_t>(k));
      std::vector<glm::vec4> marched;
      std::vector<glm::vec4> pixels = renderer.render(p.frame, {}, {}, &marched);
      p.probe_s = seconds_since(t_probe);
      probes.push_back(render::auto_exposure_if_lit(marched));
      probed[static_cast<std::size_t>(k)] = {std::move(p), std::move(pixels)};
      which += (which.empty() ? "" : ", ") + std::to_string(k);
    }
    exposure = render::sequence_exposure(probes);
    std::printf("exposure %.4g (auto, for every frame: the least of the automatic exposures of frames %s, each putting the 99th "
                "percentile of its lit pixels' luminance at 0.8; --exposure E sets it)\n", *exposure, which.c_str());
  }
  int written = 0, skipped = 0, dark = 0;
  for (std::size_t i = 0; i < instants.size(); ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05zu.png", i);
    const fs::path path = fs::path(ra.out) / name;
    const std::string iso = core::format_iso_utc(instants[i]);
    if (complete_png(path)) {
      ++skipped;
      std::printf("frame %zu/%zu %s: %s already written, skipped\n", i + 1, instants.size(), iso.c_str(), path.c_str());
      continue;
    }
    const auto t0 = clock::now();
    Prepared p;
    std::vector<glm::vec4> pixels;
    if (auto kept = probed.find(i); kept != probed.end()) {
      p = std::move(kept->second.first);
      pixels = std::move(kept->second.second);
    } else {
      p = prepare(i);
      pixels = renderer.render(p.frame, {}, {}, nullptr);
    }
    const core::Instant& at = p.at;
    const core::TimeInterpolationReport& rep = p.rep;
    const core::FrameSpec& frame = p.frame;
    const bool in_shadow = p.in_shadow;
    dark += in_shadow ? 1 : 0;
    render::ToneSettings tone;
    tone.exposure = *exposure;
    if (frame.march.features.atmosphere || frame.march.features.globe) tone.background = glm::dvec3(0.0);
    const std::vector<unsigned char> rgb8 = render::tonemap_srgb8(pixels, tone);
    core::write_file_atomically(path.string(), [&](std::FILE* f) { render::encode_png(f, frame.camera.width, frame.camera.height, rgb8); });
    ++written;
    std::printf("frame %zu/%zu %s: %s, %s%s %.1f ms, %.2f s in all%s\n", i + 1, instants.size(), iso.c_str(), path.c_str(),
                at.between() ? "interpolated " : "at a step", at.between() ? core::time_interpolation_name(rep.used) : "",
                rep.cost_ms, seconds_since(t0) + p.probe_s, in_shadow ? " (dark: the cloud layer is in the Earth's shadow)" : "");
    std::fflush(stdout);
  }
  std::printf("wrote %d frame(s), skipped %d already written, in %.1f s; exposure %.4g\n", written, skipped, seconds_since(t_start), *exposure);
  if (dark > 0 && scene.sun.mode != core::SunMode::LocalNoon) {
    std::printf("hint: %d frame(s) are dark (the whole cloud layer in the Earth's shadow); --sun-mode local_noon keeps the clouds lit for teaching\n", dark);
  }
  return 0;
}

int cmd_render(const std::vector<std::string>& args) {
  core::Scene scene;
  const RenderArgs ra = parse_render_args(args, scene);
  if (!ra.times_from.empty()) return render_series(ra, scene);
  auto t0 = clock::now();
  core::CloudVolume vol = importers::load_scene_volume(scene, 2);  // an instant between steps needs both
  importers::print_diagnosed_cloud_note(vol, "cloudviewer render");
  if (scene.time.valid_utc.empty() && static_cast<std::size_t>(scene.time_step) >= vol.times.size()) {
    throw UsageError{"cloudviewer render: --time (time_step): found " + std::to_string(scene.time_step) + ", the input has " +
                     std::to_string(vol.times.size()) + " time step(s)"};
  }
  const core::Instant instant = core::scene_instant(scene, vol, scene.data.path);
  if (vol.times.size() == 1 && !scene.time.valid_utc.empty()) {
    std::printf("the input has one time step (%s): it renders as a still\n", vol.times[0].iso_utc.c_str());
  }
  const auto& g = vol.grid;
  if (g.lon_deg.count < 2 || g.lat_deg.count < 2 || g.alt_m.count < 2) {
    throw UsageError{"cloudviewer render: " + scene.data.path + ": the volume is " + std::to_string(g.lon_deg.count) + " x " +
                     std::to_string(g.lat_deg.count) + " x " + std::to_string(g.alt_m.count) +
                     " points; rendering needs at least 2 along each axis"};
  }
  core::PreparedVolumeCache volumes;
  core::TimeInterpolationReport interp;
  const auto prepared = volumes.get(scene.data.path, vol, instant, scene.time.interpolation, &interp, scene.render.march.medium.modelled);
  const double t_load = seconds_since(t0);
  if (instant.between()) {
    const core::ValidTime& a = vol.times[instant.step0];
    const core::ValidTime& b = vol.times[instant.step1];
    std::printf("time %s: between steps %zu (%s) and %zu (%s) at %.3f of the %.4g h gap, interpolation %s",
                instant.iso_utc.c_str(), instant.step0, a.iso_utc.c_str(), instant.step1, b.iso_utc.c_str(), instant.fraction,
                instant.gap_s / 3600.0, core::time_interpolation_name(interp.used));
    if (interp.used == core::TimeInterpolation::Advected) {
      std::printf(" (up to %d trajectory sub-step(s)", interp.substeps);
      if (interp.stride > 1) std::printf(", trajectories every %d nodes along longitude and latitude", interp.stride);
      std::printf(", winds up to %.3g cells over the gap%s)", interp.max_courant,
                  interp.vertical_wind ? ", vertical wind included" : ", no vertical wind in the file");
    }
    std::printf(": %.1f ms on the CPU, once per instant (each frame of an animation at a new instant pays it)\n", interp.cost_ms);
    if (!interp.warning.empty()) std::printf("warning: %s\n", interp.warning.c_str());
  }
  try {
    overlays::check_overlays(scene.overlays, vol);  // before any work: a field the volume lacks is bad input
  } catch (const overlays::OverlayError& e) {
    throw UsageError{std::string("cloudviewer render: ") + e.what()};
  }

  // Resolve everything the scene left automatic, so the saved scene reproduces this image exactly.
  core::FrameSpec frame = render::resolve_frame(scene, vol);
  check_view_steps(frame.march.quality.view_step_m, g.earth_radius_m, prepared->layer.empty ? g.alt_m.last() : prepared->layer.top_m);
  if (frame.march.medium.modelled) {
    if (prepared->weather.cover_from_water) {
      std::printf("note: %s has no cloud fraction: the modelled cloud takes the cover diagnosed from the water (in-cloud "
                  "extinction of a typical cloud, shaped by the layer's type; docs/physics.md \"Weather textures\")\n",
                  scene.data.path.c_str());
    }
    std::printf("%s\n", core::weather_textures_note(prepared->weather).c_str());
  }
  if (frame.march.medium.modelled) {
    if (!vol.has_field[static_cast<int>(core::Field::WindU)] || !vol.has_field[static_cast<int>(core::Field::WindV)]) {
      std::printf("note: %s has no horizontal winds: the modelled cloud's detail stands still\n", scene.data.path.c_str());
    } else if (!core::times_known(vol.times)) {
      std::printf("note: %s has no valid times: the modelled cloud's detail stands still\n", scene.data.path.c_str());
    } else {
      const std::string drift = core::detail_drift_note(*prepared, vol.times.front().iso_utc);
      if (!drift.empty()) std::printf("%s\n", drift.c_str());
    }
  }
  const core::Camera& cam = frame.camera;
  const core::Sun& sun = frame.sun;
  const core::ValidTime vt{instant.unix_s, instant.iso_utc};
  if (scene.sun.mode == core::SunMode::ValidTime && !frame.valid_time_known) {
    std::printf("the input has no valid times: the sun is put at noon over the camera (set it with --sun)\n");
  }
  std::printf("sun overhead at %.2f, %.2f (%s)\n", sun.subsolar_lat_deg, sun.subsolar_lon_deg,
              scene.sun.mode == core::SunMode::Manual      ? "set by hand"
              : scene.sun.mode == core::SunMode::DateTime  ? scene.sun.datetime_utc.c_str()
              : scene.sun.mode == core::SunMode::LocalNoon ? "sun mode local_noon: noon over the camera, for teaching"
              : frame.valid_time_known                    ? "from the valid time"
                                                          : "default");
  auto ctx = render::make_headless_context();
  const render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  render::FrameRenderer renderer(loader);
  render::GpuRaymarcher& gpu = renderer.raymarcher();
  t0 = clock::now();
  renderer.use_volume(prepared);
  if (scene.render.march.medium.noise_amount > 0.0 || scene.render.march.medium.modelled) {  // generated, compiled and bound only when used
    const auto t_noise = clock::now();
    const core::MediumSettings& md = scene.render.march.medium;
    core::ErosionNoise noise = core::make_erosion_noise();
    if (md.modelled) core::with_detail_table(noise);
    gpu.upload_noise(noise);
    if (md.modelled) {
      std::printf("noise tiles for the modelled cloud (detail %.2f, tile %.0f m) and erosion noise %.2f: generated and uploaded in %.2f s\n",
                  md.detail_amount, md.detail_scale_m, md.noise_amount, seconds_since(t_noise));
    } else {
      std::printf("erosion noise %.2f, tile %.0f m: generated and uploaded in %.2f s\n", md.noise_amount, md.noise_scale_m,
                  seconds_since(t_noise));
    }
  }
  glFinish();
  const double t_upload = seconds_since(t0);
  // The ground texture (the relief image and the shorelines rasterised into its water fraction):
  // loaded once per process, so it is timed here and not as frame time.
  t0 = clock::now();
  gpu.prepare_ground(frame.march);  // the path tracer's ground too
  const double t_ground = seconds_since(t0);
  scene.render.march.quality.view_step_m = frame.march.quality.view_step_m;
  if (ra.march_overridden) scene.render.quality = "custom";
  scene.camera = cam;
  const core::SunMode scene_sun_mode = scene.sun.mode;
  scene.sun.mode = core::SunMode::Manual;
  scene.sun.subsolar_lat_deg = sun.subsolar_lat_deg, scene.sun.subsolar_lon_deg = sun.subsolar_lon_deg;
  if (scene.render.budget_ms > 0.0) {  // the quality knobs chosen here, on this scene at this size
    choose_by_budget(gpu, cam, sun, frame.march, g.alt_m.step, scene.render.budget_ms, ra.front, render::machine_id(ctx->info()),
                     scene.render);
    scene.render.budget_ms = 0.0;  // a saved scene holds the chosen settings, so it renders this image again
    frame = render::resolve_frame(scene, vol);
  }
  core::OutputGroup outputs;  // the image, its PFMs and the saved scene: committed together or not at all
  if (!ra.save_scene.empty()) {
    core::Scene saved = scene;
    // Data beside or below the saved scene: a path relative to its folder (as load_scene resolves
    // it), so the two can move together; anywhere else an absolute path.
    const fs::path folder = fs::absolute(ra.save_scene).parent_path().lexically_normal();
    const fs::path data = fs::absolute(scene.data.path).lexically_normal();
    const fs::path rel = data.lexically_relative(folder);
    saved.data.path = (rel.empty() || *rel.begin() == "..") ? data.string() : rel.string();
    const std::string text = core::scene_to_json(saved);
    outputs.write(ra.save_scene, [&](std::FILE* f) { std::fwrite(text.data(), 1, text.size(), f); });
  }

  if (ra.reference) {  // the path tracer marches nothing: the output size
    frame.march_camera = frame.camera;
    if (frame.march.features.atmosphere) {
      std::printf("the path tracer's air: sunlight reddened through it, the sky's light where paths leave and the haze "
                  "between the camera and what it sees; not between later vertices\n");
    }
  }
  const core::RenderSettings& rs = scene.render;
  const core::MarchSettings& march = frame.march;
  const int mw = frame.march_camera.width, mh = frame.march_camera.height;
  const std::string model =
      march.medium.ms_two_stream
          ? std::string("two-stream multiple scattering, ") + (march.medium.ms_slab ? "slab-shaped" : "linear") + " diffuse light"
          : std::to_string(march.quality.octaves) + " octaves";
  // Between two steps the report names both (the medium is interpolated), else the step.
  const std::string when = instant.between() ? "between time steps " + std::to_string(instant.step0) + " and " + std::to_string(instant.step1)
                                             : "time step " + std::to_string(instant.step0);
  if (ra.reference) {
    std::printf("rendering %s, %s (%s), %dx%d, quality reference: the GPU path tracer, up to %d samples per pixel%s\n",
                scene.data.path.c_str(), when.c_str(), vt.iso_utc.c_str(), cam.width, cam.height, ra.spp,
                ra.target_error > 0.0 ? (", to a relative standard error of " + core::short_number(ra.target_error)).c_str() : "");
  } else std::printf("rendering %s, %s (%s), %dx%d%s, quality %s: view step %.0f m, %d sun steps, %s, %d frame(s)\n",
              scene.data.path.c_str(), when.c_str(), vt.iso_utc.c_str(), cam.width, cam.height,
              mw != cam.width || mh != cam.height ? (" marched at " + std::to_string(mw) + "x" + std::to_string(mh)).c_str() : "",
              rs.quality.c_str(), march.quality.view_step_m, march.quality.sun_steps, model.c_str(), frame.accumulate);

  // The overlays' geometry (VTK), built only when the scene has overlays; drawn before the march.
  std::vector<overlays::BuiltOverlay> built;
  if (!scene.overlays.empty()) {
    overlays::OverlayBuilder builder;
    try {
      built = builder.build(scene.overlays, vol, static_cast<std::size_t>(scene.time_step), frame.march_camera);
    } catch (const overlays::OverlayError& e) {
      throw UsageError{std::string("cloudviewer render: ") + e.what()};
    }
    renderer.set_overlays(overlays::OverlayBuilder::draws(built));
  }

  t0 = clock::now();
  double gpu_s = 0.0;
  render::DispatchOptions dispatch;
  dispatch.gpu_seconds = &gpu_s;
  const double pixels_per_frame = static_cast<double>(mw) * mh;
  if (frame.accumulate == 1 && pixels_per_frame > kTilePixels) {
    dispatch.rows_per_tile = std::max(8, static_cast<int>(kTilePixels / mw));
    dispatch.on_tile = [&](int done, int total) {
      progress_line("marched %d/%d rows (%.0f%%), %.1f s", done, total, 100.0 * done / total, seconds_since(t0));
    };
  }
  // One frame at step middles (or the scene's frame), or the mean of jittered frames, at the output
  // size in linear radiance.
  std::vector<glm::vec4> marched;  // at the march size, for the automatic exposure
  std::vector<glm::vec4> pixels;
  if (ra.reference) {
    pixels = path_trace(renderer, frame, ra, gpu_s);
    marched = pixels;
  } else {
    pixels = renderer.render(
        frame, dispatch,
        [&](int done, int total) {
          if (total > 1) progress_line("accumulated %d/%d frames, %.1f s", done, total, seconds_since(t0));
        },
        &marched);
    end_progress();
  }
  const double t_march = seconds_since(t0);
  if (march.medium.ms_two_stream && !ra.reference) {
    const int lateral = gpu.ms_source_lateral_iterations();
    const std::string between =
        lateral >= 0 ? "light between columns in " + std::to_string(lateral) + " iteration(s)"
                     : "columns on their own: " + gpu.ms_source_columns_alone();
    std::printf("two-stream source built in %.1f ms (once per time step and sun direction; %s)\n", gpu.ms_source_build_ms(),
                between.c_str());
  }
  const core::MarchStats& ms = ra.reference ? core::MarchStats{} : gpu.last_stats();
  if (!ra.reference) std::printf("march%s: %llu view samples, %llu skipped in %llu empty-brick jumps (view and sun), %llu sun samples, "
              "%llu skipped or cut off, %llu of %d rays missed the cloud shell%s\n",
              frame.accumulate > 1 ? " (last frame)" : "", static_cast<unsigned long long>(ms.view_samples),
              static_cast<unsigned long long>(ms.view_skipped), static_cast<unsigned long long>(ms.bricks_jumped),
              static_cast<unsigned long long>(ms.sun_samples), static_cast<unsigned long long>(ms.sun_skipped),
              static_cast<unsigned long long>(ms.rays_missed), mw * mh, march.features.skip_empty ? "" : " (skipping off)");
  if (ms.sun_down) std::printf("the sun is below the horizon for the whole cloud layer: sun marches and octave sums left out\n");
  if (scene_sun_mode != core::SunMode::LocalNoon && !prepared->layer.empty) {
    const glm::dvec3 to_sun =
        glm::normalize(geo::sphere_to_ecef({sun.subsolar_lat_deg, sun.subsolar_lon_deg, 0.0}, g.earth_radius_m));
    const double highest_deg = core::highest_sun_elevation_deg(g, to_sun);
    const bool in_shadow = core::layer_in_earth_shadow(g, prepared->layer, to_sun);
    if (in_shadow && !ra.reference) {
      std::printf("hint: at %s the whole cloud layer is in the Earth's shadow, so the image is dark; --sun-mode local_noon "
                  "(sun.mode \"local_noon\") keeps the clouds lit for teaching\n", vt.iso_utc.c_str());
    } else if (!in_shadow && highest_deg < core::kTwilightElevationDeg) {
      std::printf("hint: at %s %s, so the clouds are lit at a grazing angle through reddened air and the image is mostly "
                  "twilight; --sun-mode local_noon (sun.mode \"local_noon\") keeps the clouds lit for teaching\n",
                  vt.iso_utc.c_str(), core::low_sun_words(highest_deg).c_str());
    }
  }
  if (ms.octave_terms_full > ms.octave_terms) {
    std::printf("octave gate: %llu of %llu octave terms evaluated at sunlit samples (%.1f %% left out where the cloud is thin)\n",
                static_cast<unsigned long long>(ms.octave_terms), static_cast<unsigned long long>(ms.octave_terms_full),
                100.0 * static_cast<double>(ms.octave_terms_full - ms.octave_terms) / static_cast<double>(ms.octave_terms_full));
  }

  t0 = clock::now();
  render::check_finite_pixels(pixels, cam.width, scene.data.path);  // a wrong image is not written: what was there stays
  render::ToneSettings tone;
  tone.exposure = frame.auto_exposure ? render::auto_exposure(marched) : frame.exposure;
  if (frame.auto_exposure) std::printf("exposure %.4g (auto: the 99th percentile of lit pixels' luminance at 0.8; --exposure E sets it)\n", tone.exposure);
  if (march.features.atmosphere || march.features.globe) tone.background = glm::dvec3(0.0);  // the sky and space are in the image
  const std::vector<unsigned char> rgb8 = render::tonemap_srgb8(pixels, tone);
  const double t_tone = seconds_since(t0);
  t0 = clock::now();
  outputs.write(ra.out, [&](std::FILE* f) { render::encode_png(f, cam.width, cam.height, rgb8); });
  const std::string transmittance_pfm = ra.pfm.empty() ? "" : render::transmittance_pfm_path(ra.pfm);
  if (!ra.pfm.empty()) {  // radiance alone, and the transmittance as its own file
    outputs.write(ra.pfm, [&](std::FILE* f) { render::encode_pfm(f, cam.width, cam.height, pixels); });
    outputs.write(transmittance_pfm, [&](std::FILE* f) { render::encode_pfm_transmittance(f, cam.width, cam.height, pixels); });
  }
  if (!ra.exr.empty()) {  // radiance and coverage in one file; the path tracer's has no coverage
    outputs.write(ra.exr, [&](std::FILE* f) { render::encode_exr(f, cam.width, cam.height, pixels, !ra.reference); });
  }
  outputs.commit();
  if (!ra.save_scene.empty()) std::printf("wrote the scene %s\n", ra.save_scene.c_str());
  const double t_write = seconds_since(t0);
  char gpu_text[48];
  // GL_TIME_ELAPSED as the driver reports it (Mesa's llvmpipe runs compute on the CPU and reports
  // next to nothing; on a real GPU this is the march without queueing and read-back).
  if (gpu_s > 0.0) std::snprintf(gpu_text, sizeof gpu_text, "%.3f ms (GL timer query)", gpu_s * 1e3);
  else std::snprintf(gpu_text, sizeof gpu_text, "not reported by the driver");
  std::printf("timings (%s):\n  load/import %.3f s\n  upload      %.3f s\n  ground      %.3f s\n  march       %.3f s wall, GPU %s\n",
              ctx->info().renderer.c_str(), t_load, t_upload, t_ground, t_march, gpu_text);
  for (std::size_t i = 0; i < built.size(); ++i) {
    const std::size_t v = (built[i].mesh ? built[i].mesh->positions.size() : 0) + (built[i].view_mesh ? built[i].view_mesh->positions.size() : 0);
    const double draw = i < renderer.overlay_draw_ms().size() ? renderer.overlay_draw_ms()[i] : 0.0;
    const std::size_t instances = built[i].mesh ? built[i].mesh->instances.count() : 0;
    char inst[96] = "";
    if (instances > 0) {
      std::snprintf(inst, sizeof inst, ", %zu instances of a %zu-vertex glyph", instances, built[i].mesh->instances.glyph_positions.size());
    }
    std::printf("  overlay %-11s build %.3f s, draw %.3f s (%zu vertices%s; the draw is inside the march's wall time)\n",
                built[i].name.c_str(), built[i].build_ms * 1e-3, draw * 1e-3, v, inst);
  }
  std::printf("  composite/tonemap %.3f s\n  write       %.3f s\n", t_tone, t_write);
  std::printf("wrote %s%s%s\n", ra.out.c_str(),
              ra.pfm.empty() ? "" : (", " + ra.pfm + " (radiance) and " + transmittance_pfm + " (transmittance)").c_str(),
              ra.exr.empty() ? "" : (", " + ra.exr + (ra.reference ? " (radiance)" : " (radiance and coverage)")).c_str());
  return 0;
}

}  // namespace cv::cli
