// `cloudviewer record SCENE.json -o OUT.mp4`: every input checked before the first frame (the path,
// its weather times against the data, the output folder, ffmpeg and its H.264 encoder), then the
// path's frames rendered through the one frame renderer into OUT_frames/frame_NNNNN.png (each
// written atomically; frames already whole are skipped), then assembled by the ffmpeg program.
#include "record_command.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include <glm/glm.hpp>

#include "cli_common.hpp"
#include "geo/geodesy.hpp"
#include "io/input_file.hpp"
#include "io/output_file.hpp"
#include "kernel/volume_cache.hpp"
#include "overlays/overlays.hpp"
#include "reference/earth_shadow.hpp"
#include "render/context.hpp"
#include "render/frame_renderer.hpp"
#include "render/exr_output.hpp"
#include "render/image_output.hpp"
#include "render/shader_loader.hpp"
#include "scene/camera_path.hpp"
#include "scene/framing.hpp"
#include "scene/instant.hpp"
#include "scene/quality.hpp"
#include "scene/scene_json.hpp"
#include "scene_source.hpp"
#include "vdb/vdb_export.hpp"

namespace cv::cli {
namespace {

namespace fs = std::filesystem;
using clock = std::chrono::steady_clock;

struct RecordArgs {
  std::string scene_path, out;
  double fps = 30.0;
  std::optional<std::pair<int, int>> frames;  // --frames A:B, inclusive
  bool assemble = false;
  bool count = false;  // --count: print the number of frames and stop
  // --quality reference: the GPU path tracer per frame, up to spp samples per pixel or until the
  // image's mean relative standard error is target_error (0: all spp); its seed from the frame number.
  bool reference = false;
  int spp = 64;
  double target_error = 0.0;
  bool spp_given = false;
  int crf = 18;
  bool vdb = false;  // --vdb: each frame's medium as OpenVDB grids beside its PNG
  bool exr = false;  // --exr: each frame's linear radiance (and coverage) as OpenEXR beside its PNG
};

int parse_whole(const std::string& option, const std::string& text, int lo, int hi, const std::string& expected) {
  const double v = parse_number(option, text);
  if (!(v >= lo && v <= hi) || v != std::floor(v)) throw UsageError{"cloudviewer record: " + option + ": found '" + text + "', expected " + expected};
  return static_cast<int>(v);
}

RecordArgs parse_record_args(const std::vector<std::string>& args, core::Scene& scene) {
  RecordArgs r;
  std::vector<std::pair<std::string, std::string>> options;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--vdb") {
      r.vdb = true;
    } else if (a == "--exr") {
      r.exr = true;
    } else if (a == "--assemble") {
      r.assemble = true;
    } else if (a == "--count") {
      r.count = true;
    } else if (!a.empty() && a[0] == '-') {
      if (i + 1 >= args.size()) throw UsageError{"cloudviewer record: " + a + ": expected a value after it"};
      options.emplace_back(a, args[++i]);
    } else if (r.scene_path.empty()) {
      r.scene_path = a;
    } else {
      throw UsageError{"cloudviewer record: unexpected argument '" + a + "', expected one SCENE.json"};
    }
  }
  if (r.scene_path.empty()) throw UsageError{"cloudviewer record: expected SCENE.json (a scene with a camera path) and -o OUT.mp4"};
  if (r.scene_path.size() < 5 || r.scene_path.compare(r.scene_path.size() - 5, 5, ".json") != 0) {
    throw UsageError{"cloudviewer record: found '" + r.scene_path + "', expected a scene file SCENE.json with a camera path (docs/scene.md)"};
  }
  scene = core::load_scene(r.scene_path);
  std::string frames_text;
  for (const auto& [a, v] : options) {
    if (a == "-o") {
      r.out = v;
    } else if (a == "--fps") {
      r.fps = parse_number(a, v);
      if (!(r.fps >= 1.0 && r.fps <= 240.0)) throw UsageError{"cloudviewer record: --fps: found '" + v + "', expected frames per second 1..240"};
    } else if (a == "--size") {
      const auto size = parse_size(v, 2, 16384);
      // yuv420p halves the chroma planes: H.264 in it needs even sides.
      if (!size || size->first % 2 != 0 || size->second % 2 != 0) {
        throw UsageError{"cloudviewer record: --size: found '" + v + "', expected WxH, even numbers 2..16384 each (H.264 in yuv420p)"};
      }
      scene.width = size->first, scene.height = size->second;
    } else if (a == "--quality") {
      if (v == "reference") {
        r.reference = true;
      } else if (!core::find_quality(v)) {
        throw UsageError{"cloudviewer record: --quality: found '" + v + "', expected one of " + core::quality_names() + " or reference"};
      } else {
        core::apply_quality(v, scene.render);
      }
    } else if (a == "--spp") {
      r.spp = parse_whole(a, v, 1, 1000000, "samples per pixel 1..1e6");
      r.spp_given = true;
    } else if (a == "--target-error") {
      r.target_error = parse_number(a, v);
      if (!(r.target_error > 0.0 && r.target_error < 1.0)) {
        throw UsageError{"cloudviewer record: --target-error: found '" + v + "', expected a relative standard error between 0 and 1"};
      }
    } else if (a == "--accumulate") {
      scene.render.accumulate = parse_whole(a, v, 1, 4096, "jittered frames per video frame 1..4096");
      scene.render.quality = "custom";
    } else if (a == "--exposure") {
      scene.render.auto_exposure = v == "auto";
      if (!scene.render.auto_exposure) {
        scene.render.exposure = parse_number(a, v);
        if (!(scene.render.exposure > 0)) throw UsageError{"cloudviewer record: --exposure: found '" + v + "', expected a number > 0 or auto"};
      }
    } else if (a == "--frames") {
      frames_text = v;
      const std::size_t colon = v.find(':');
      if (colon == std::string::npos) throw UsageError{"cloudviewer record: --frames: found '" + v + "', expected A:B, frame numbers from 0 with A <= B"};
      const int from = parse_whole(a, v.substr(0, colon), 0, 9999999, "A:B, frame numbers from 0 with A <= B");
      const int to = parse_whole(a, v.substr(colon + 1), 0, 9999999, "A:B, frame numbers from 0 with A <= B");
      if (from > to) throw UsageError{"cloudviewer record: --frames: found '" + v + "', expected A:B with A <= B"};
      r.frames = std::make_pair(from, to);
    } else if (a == "--crf") {
      r.crf = parse_whole(a, v, 0, 51, "an H.264 constant rate factor 0..51 (lower: better; 18 is near transparent)");
    } else {
      throw UsageError{"cloudviewer record: unknown option '" + a + "'"};
    }
  }
  if (r.out.empty()) throw UsageError{"cloudviewer record: expected -o OUT.mp4"};
  if (!r.reference && (r.spp_given || r.target_error > 0.0)) {
    throw UsageError{"cloudviewer record: --spp and --target-error: found them without a path tracer, expected --quality reference"};
  }
  if (r.assemble && r.frames) throw UsageError{"cloudviewer record: --assemble: found it with --frames, expected one or the other"};
  if (!scene.path) {
    throw UsageError{r.scene_path + ": path: found nothing, expected a camera path {\"keyframes\": [...]} (docs/scene.md, Camera paths)"};
  }
  if (scene.width % 2 != 0 || scene.height % 2 != 0) {
    throw UsageError{r.scene_path + ": width, height: found " + std::to_string(scene.width) + "x" + std::to_string(scene.height) +
                     ", expected even numbers (H.264 in yuv420p; --size WxH overrides)"};
  }
  if (scene.data.path.empty()) throw UsageError{r.scene_path + ": data.path: found nothing, expected the NetCDF or .cvvol file to render"};
  return r;
}

// The frames' folder beside the video: OUT_frames/ for OUT.mp4.
fs::path frames_folder(const std::string& out) {
  fs::path p(out);
  return p.parent_path() / (p.stem().string() + "_frames");
}

fs::path frame_file(const fs::path& folder, int k) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%05d.png", k);
  return folder / name;
}

// What decides the frames' pixels, written beside them as OUT_frames/record.json: a rerun (or
// another array task) with other settings would mix two videos' frames, so it is refused.
std::string frames_manifest(const RecordArgs& r, const core::Scene& scene) {
  core::Scene s = scene;
  s.data.path = fs::absolute(scene.data.path).lexically_normal().string();
  char extra[256];
  std::snprintf(extra, sizeof extra, "{\"fps\": %.17g, \"reference\": %s, \"spp\": %d, \"target_error\": %.17g}\n", r.fps,
                r.reference ? "true" : "false", r.spp, r.target_error);
  return std::string("{\"record\": ") + extra + ", \"scene\": " + core::scene_to_json(s) + "}\n";
}

void check_manifest(const fs::path& folder, const std::string& manifest) {
  const fs::path file = folder / "record.json";
  std::error_code ec;
  if (!fs::exists(file, ec)) return;
  std::string text;
  try {
    text = core::read_regular_file(file.string(), "the frames' record of their settings", 64u << 20);
  } catch (const core::InputError& e) {
    throw UsageError{std::string("cloudviewer record: ") + e.what()};
  }
  if (text != manifest) {
    throw UsageError{"cloudviewer record: " + file.string() + ": found frames rendered with other settings (scene, size, quality, fps or "
                     "data), expected this scene's: remove " + folder.string() + " or choose another -o"};
  }
}

// The output folder and the frames' folder can be written, before anything is rendered.
void check_outputs(const RecordArgs& r, const core::Scene& scene) {
  core::check_output_extension(r.out, "-o", {".mp4"});
  core::check_output_path(r.out, "-o");
  core::check_output_not_input(r.out, "-o", r.scene_path, "the scene");
  core::check_output_not_input(r.out, "-o", scene.data.path, "the data (data.path)");
  const fs::path folder = frames_folder(r.out);
  std::error_code ec;
  if (fs::exists(folder, ec) && !fs::is_directory(folder, ec)) {
    throw UsageError{"cloudviewer record: -o: the frames' folder " + folder.string() + " exists and is not a folder, expected a folder (or nothing) there"};
  }
  if (fs::is_directory(folder, ec) && ::access(folder.c_str(), W_OK | X_OK) != 0) {
    throw UsageError{"cloudviewer record: -o: the frames' folder " + folder.string() + " cannot be written, expected a folder this user can write"};
  }
}

// The ffmpeg program and its H.264 encoder, found before any frame is rendered.
std::string find_ffmpeg() {
  const char* env = std::getenv("PATH");
  std::string found;
  std::string dirs = env ? env : "";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    const std::size_t end = std::min(dirs.find(':', start), dirs.size());
    const std::string dir = dirs.substr(start, end - start);
    const fs::path candidate = fs::path(dir.empty() ? "." : dir) / "ffmpeg";
    if (::access(candidate.c_str(), X_OK) == 0 && fs::is_regular_file(candidate)) {
      found = candidate.string();
      break;
    }
    start = end + 1;
  }
  if (found.empty()) {
    throw UsageError{"cloudviewer record: ffmpeg: found no 'ffmpeg' program on PATH, expected ffmpeg with the libx264 encoder to write "
                     "the MP4 (Debian package ffmpeg; scripts/setup installs it); --frames A:B renders frames without it"};
  }
  const std::string cmd = "'" + found + "' -hide_banner -loglevel error -encoders 2>/dev/null";
  std::FILE* p = ::popen(cmd.c_str(), "r");
  std::string text;
  if (p) {
    char buf[4096];
    std::size_t n = 0;
    while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) text.append(buf, n);
    ::pclose(p);
  }
  if (text.find(" libx264 ") == std::string::npos) {
    throw UsageError{"cloudviewer record: ffmpeg: found " + found + " without the libx264 encoder, expected an ffmpeg that encodes "
                     "H.264 (Debian's ffmpeg package has it)"};
  }
  return found;
}

// "3, 7-9, 12" for frame numbers in ascending order.
std::string ranges_text(const std::vector<int>& v) {
  std::string s;
  for (std::size_t i = 0; i < v.size();) {
    std::size_t j = i;
    while (j + 1 < v.size() && v[j + 1] == v[j] + 1) ++j;
    if (!s.empty()) s += ", ";
    s += std::to_string(v[i]) + (j > i ? "-" + std::to_string(v[j]) : "");
    if (s.size() > 200) return s + ", ...";
    i = j + 1;
  }
  return s;
}

// frames/min and the time left, for the progress line.
std::string eta_text(double seconds) {
  const long s = std::lround(std::max(0.0, seconds));
  char buf[32];
  std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
  return buf;
}

// The MP4 from the frames: written by ffmpeg to a temporary beside OUT, renamed into place only
// when it succeeded (a failed run leaves an existing OUT as it was). Bit-exact flags and no
// metadata, so the same frames give the same bytes.
void assemble_mp4(const std::string& ffmpeg, const fs::path& folder, const std::string& out, double fps, int crf) {
  const fs::path target(out);
  const fs::path temp = target.parent_path() / ("." + target.filename().string() + "." + std::to_string(::getpid()) + ".partial");
  char rate[32];
  std::snprintf(rate, sizeof rate, "%.10g", fps);
  const std::vector<std::string> argv_s = {ffmpeg, "-nostdin", "-hide_banner", "-loglevel", "error", "-y", "-framerate", rate,
                                           "-i", (folder / "frame_%05d.png").string(), "-c:v", "libx264", "-pix_fmt", "yuv420p",
                                           "-crf", std::to_string(crf), "-preset", "medium", "-threads", "1",
                                           "-fflags", "+bitexact", "-flags:v", "+bitexact", "-map_metadata", "-1",
                                           "-movflags", "+faststart", "-f", "mp4", temp.string()};
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error("cannot start ffmpeg (fork failed)");
  if (pid == 0) {
    std::vector<char*> argv;
    for (const std::string& a : argv_s) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(ffmpeg.c_str(), argv.data());
    ::_exit(127);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
  }
  std::error_code ec;
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    fs::remove(temp, ec);
    throw std::runtime_error("ffmpeg failed (exit status " + std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ") writing " +
                             out + "; an existing file there is left as it was");
  }
  fs::rename(temp, target, ec);
  if (ec) {
    fs::remove(temp, ec);
    throw std::runtime_error("cannot rename the video into place at " + out + " (" + ec.message() + ")");
  }
}

}  // namespace

const char* record_usage() {
  return "  record SCENE.json -o OUT.mp4  the scene's camera path (docs/scene.md, Camera paths) rendered headlessly\n"
         "         [--fps N] [--size WxH] [--quality low|default|high] [--accumulate N] [--exposure E|auto] [--crf N]\n"
         "                           frames into OUT_frames/frame_00000.png, ... (frame k at the path's start + k/fps,\n"
         "                           through its end), then an H.264 yuv420p MP4 through the ffmpeg program; frames\n"
         "                           already whole are skipped, so a stopped run resumes; the same scene and frame\n"
         "                           give the same bytes (each frame's jitter from its number); auto exposure is\n"
         "                           one for every frame, so the video does not flicker: the least of the automatic\n"
         "                           exposures of the first, the last and three frames between (the brightest sets it);\n"
         "                           OUT_frames/record.json holds the settings: frames of other ones are refused\n"
         "         [--quality reference [--spp N] [--target-error E]]  each frame by the GPU path tracer (clouds and\n"
         "                           the ground, lit by the sun and the sky): N samples per pixel at most (64), fewer once\n"
         "                           the image's mean relative standard error is E; the frame number seeds it\n"
         "         [--frames A:B]            render only frames A..B (inclusive, from 0), no video: for batch\n"
         "                           schedulers (scripts/slurm/record.sbatch)\n"
         "         [--assemble]              no rendering: the MP4 from the frames on disk, naming any missing\n"
         "         [--count]                 print the path's number of frames at --fps and stop\n"
         "         [--vdb]                   also each frame's medium at its weather instant (interpolated between\n"
         "                           forecast steps as the frame shows it) as OUT_frames/frame_00000.vdb, ...: OpenVDB\n"
         "                           grid-mean liquid and ice extinction (and cloud fraction at a forecast step) in\n"
         "                           metres in a tangent frame at the region's centre, as import --vdb writes them\n"
         "         [--exr]                   also each frame as OpenEXR for compositing, OUT_frames/frame_00000.exr, ...:\n"
         "                           R, G, B the linear radiance (no background, no exposure) and A = 1 - transmittance\n"
         "                           (premultiplied: over a plate, RGB + (1 - A) x plate; A is 1 where the globe shows:\n"
         "                           clouds alone with render.march.globe and .atmosphere false); R, G, B alone with\n"
         "                           --quality reference; a frame is whole when its PNG and its EXR both are (--assemble\n"
         "                           --exr names frames whose EXR is missing too)\n";
}

int cmd_record(const std::vector<std::string>& args) {
  const auto t_start = clock::now();
  core::Scene scene;
  RecordArgs r = parse_record_args(args, scene);
  const core::PathEvaluator path(*scene.path);  // checked when the scene was read
  const int count = core::path_frame_count(path, r.fps);
  if (r.count) {  // for batch scripts that split the frames (scripts/slurm/record.sbatch)
    std::printf("%d\n", count);
    return 0;
  }
  if (r.frames && r.frames->second >= count) {
    throw UsageError{"cloudviewer record: --frames: found " + std::to_string(r.frames->first) + ":" + std::to_string(r.frames->second) +
                     ", expected frames within 0:" + std::to_string(count - 1) + " (the path has " + std::to_string(count) + " frames at " +
                     core::short_number(r.fps) + " fps)"};
  }
  check_outputs(r, scene);
  const bool encode = !r.frames;
  const std::string ffmpeg = encode ? find_ffmpeg() : "";
  const fs::path folder = frames_folder(r.out);
  const std::string manifest = frames_manifest(r, scene);
  check_manifest(folder, manifest);

  if (r.assemble) {
    std::vector<int> missing;
    for (int k = 0; k < count; ++k) {
      const fs::path file = frame_file(folder, k);
      fs::path exr_file = file;
      exr_file.replace_extension(".exr");
      // With --exr (as a cluster's assemble step passes the frames' options on) a frame needs its EXR too.
      if (!render::png_decodes_at_size(file.string(), scene.width, scene.height) ||
          (r.exr && !render::exr_decodes_at_size(exr_file.string(), scene.width, scene.height, !r.reference))) {
        missing.push_back(k);
      }
    }
    if (!missing.empty()) {
      throw UsageError{"cloudviewer record --assemble: " + folder.string() + ": frames " + ranges_text(missing) + " of 0.." +
                       std::to_string(count - 1) + " are missing or not whole " + std::to_string(scene.width) + "x" +
                       std::to_string(scene.height) + (r.exr ? " PNGs with their EXRs" : " PNGs") + ", expected all " +
                       std::to_string(count) + " (render them with --frames A:B)"};
    }
    const auto t0 = clock::now();
    assemble_mp4(ffmpeg, folder, r.out, r.fps, r.crf);
    std::printf("wrote %s from %d frames in %s (encoded in %.2f s)\n", r.out.c_str(), count, folder.c_str(), seconds_since(t0));
    return 0;
  }

  // The data, and every weather time the path asks for, before any frame.
  core::CloudVolume vol = importers::load_scene_volume(scene, 2);
  importers::print_diagnosed_cloud_note(vol, "cloudviewer record");
  const auto& g = vol.grid;
  if (g.lon_deg.count < 2 || g.lat_deg.count < 2 || g.alt_m.count < 2) {
    throw UsageError{"cloudviewer record: " + scene.data.path + ": the volume is too small to render (at least 2 points along each axis)"};
  }
  const auto& keys = scene.path->keyframes;
  auto check_time = [&](const std::string& iso, const std::string& key, const std::string& what) {
    try {
      core::instant_at_time(vol.times, iso, scene.data.path);
    } catch (const core::TimeError&) {
      throw UsageError{r.scene_path + ": " + key + ": found \"" + iso + "\"" + what + ", expected a valid time within the data's " +
                       core::time_range_text(vol.times) + " (" + scene.data.path + ")"};
    }
  };
  for (std::size_t i = 0; i < keys.size(); ++i) {
    if (!keys[i].valid_utc.empty()) check_time(keys[i].valid_utc, "path.keyframes[" + std::to_string(i) + "].valid_utc", "");
  }
  if (scene.path->weather_hours_per_s != 0.0) {
    check_time(core::format_iso_utc(*path.at(path.end_s()).weather_unix_s), "path.weather_hours_per_s",
               " at the path's end (" + core::short_number(scene.path->weather_hours_per_s) + " h per second)");
  }
  core::scene_instant(core::scene_at_path_time(scene, path, path.start_s()), vol, scene.data.path);  // the scene's own time, when the path gives none
  try {
    overlays::check_overlays(scene.overlays, vol);
  } catch (const overlays::OverlayError& e) {
    throw UsageError{std::string("cloudviewer record: ") + e.what()};
  }
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (!fs::is_directory(folder)) throw UsageError{"cloudviewer record: -o: cannot create the frames' folder " + folder.string()};
  if (!fs::exists(folder / "record.json", ec)) {
    core::write_file_atomically((folder / "record.json").string(), [&](std::FILE* f) { std::fwrite(manifest.data(), 1, manifest.size(), f); });
  }

  const int first = r.frames ? r.frames->first : 0, last = r.frames ? r.frames->second : count - 1;
  auto ctx = render::make_headless_context();
  const render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  render::FrameRenderer renderer(loader);
  core::PreparedVolumeCache volumes;
  overlays::OverlayBuilder builder;
  std::string warned;
  bool sun_was_low = false;  // the last frame rendered had the sun low over all the data

  // Frame k's linear image, through the one frame renderer: the scene at the path's time for k,
  // its jitter indices k * accumulate onwards.
  auto render_frame = [&](int k, std::vector<glm::vec4>* marched, core::FrameSpec& frame) {
    core::Scene at;
    frame = render::resolve_path_frame(scene, path, vol, k, r.fps, &at);
    if (r.reference) frame.march_camera = frame.camera;  // the path tracer and its overlays at the output size
    const core::Instant& instant = frame.instant;
    core::TimeInterpolationReport rep;
    renderer.use_volume(volumes.get(scene.data.path, vol, instant, at.time.interpolation, &rep, at.render.march.medium.modelled));
    if (!rep.warning.empty() && rep.warning != warned) std::printf("warning: %s\n", (warned = rep.warning).c_str());
    // Frames whose whole domain has the sun low (dawn, dusk or night there) come out pale or dark:
    // said once where such a run of frames begins.
    const bool low_sun = at.sun.mode != core::SunMode::LocalNoon &&
                         core::highest_sun_elevation_deg(vol.grid, glm::normalize(geo::sphere_to_ecef(
                             {frame.sun.subsolar_lat_deg, frame.sun.subsolar_lon_deg, 0.0}, vol.grid.earth_radius_m))) <
                             core::kTwilightElevationDeg;
    if (low_sun && !sun_was_low) {
      std::printf("hint: from frame %d (%s) the sun stands under %g degrees above the horizon over all the data (dawn, dusk or "
                  "night there), so those frames are twilight or dark; sun.mode \"local_noon\" keeps the clouds lit for teaching\n",
                  k, instant.iso_utc.c_str(), core::kTwilightElevationDeg);
    }
    sun_was_low = low_sun;
    if (!at.overlays.empty()) {
      try {
        renderer.set_overlays(overlays::OverlayBuilder::draws(builder.build(at.overlays, vol, instant.step0, frame.march_camera)));
      } catch (const overlays::OverlayError& e) {
        throw UsageError{std::string("cloudviewer record: ") + e.what()};
      }
    }
    if (!r.reference) return renderer.render(frame, {}, {}, marched);
    // The path tracer at the output size (sunlight through the air, the sky as an environment
    // light), in batches of 8 samples until spp or the target error; the same frame number gives
    // the same samples.
    core::MonteCarloImage img;
    render::PathTraceSettings pt;
    pt.samples_per_readback = 8;
    pt.seed = static_cast<std::uint32_t>(k) + 1u;
    while (img.spp < static_cast<std::uint64_t>(r.spp)) {
      const int batch = static_cast<int>(std::min<std::uint64_t>(static_cast<std::uint64_t>(r.spp) - img.spp, 8));
      renderer.trace_paths(img, frame, batch, pt);
      if (r.target_error > 0.0 && img.spp >= 8 && img.mean_relative_standard_error() <= r.target_error) break;
    }
    std::vector<glm::vec4> out(img.lum_sum.size());
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = glm::vec4(glm::vec3(img.mean(i)), 0.0f);
    if (marched) *marched = out;
    return out;
  };

  std::optional<double> exposure;
  if (!scene.render.auto_exposure) exposure = scene.render.exposure;
  // The probed frames of this range, kept for the loop (their images are the loop's to the bit).
  std::map<int, std::pair<core::FrameSpec, std::vector<glm::vec4>>> probed;
  if (!exposure) {  // from the same frames of the whole path for every range, so ranges rendered apart match
    std::vector<std::optional<double>> probes;
    std::string which;
    for (const int k : render::exposure_probe_frames(count)) {
      std::vector<glm::vec4> marched;
      core::FrameSpec fk;
      std::vector<glm::vec4> pixels = render_frame(k, &marched, fk);
      if (k >= first && k <= last) probed[k] = {fk, std::move(pixels)};
      probes.push_back(render::auto_exposure_if_lit(marched));
      which += (which.empty() ? "" : ", ") + std::to_string(k);
    }
    exposure = render::sequence_exposure(probes);
    std::printf("exposure %.6g (auto, for every frame: the least of the automatic exposures of frames %s)\n", *exposure, which.c_str());
  }
  if (r.reference) {
    std::printf("recording %s: %d frames (%.3g s at %.6g fps), %d..%d here, %dx%d, quality reference: the GPU path tracer, up to %d "
                "samples per pixel%s (clouds and the ground, lit by the sun and the sky), into %s\n",
                r.scene_path.c_str(), count, path.duration_s(), r.fps, first, last, scene.width, scene.height, r.spp,
                r.target_error > 0.0 ? (" or a relative standard error of " + core::short_number(r.target_error)).c_str() : "",
                folder.c_str());
  } else {
    std::printf("recording %s: %d frames (%.3g s at %.6g fps), %d..%d here, %dx%d, quality %s, %d jittered frame(s) each, into %s\n",
                r.scene_path.c_str(), count, path.duration_s(), r.fps, first, last, scene.width, scene.height, scene.render.quality.c_str(),
                std::max(1, scene.render.accumulate), folder.c_str());
  }
  std::fflush(stdout);
  const bool tty = ::isatty(::fileno(stdout)) != 0;
  int rendered = 0, skipped = 0;
  double verify_s = 0.0, render_s = 0.0;
  const auto t_loop = clock::now();
  double vdb_s = 0.0;
  int vdb_written = 0, exr_written = 0;
  for (int k = first; k <= last; ++k) {
    const fs::path file = frame_file(folder, k);
    const auto t_verify = clock::now();
    fs::path exr_file = file;
    exr_file.replace_extension(".exr");
    const bool whole = render::png_decodes_at_size(file.string(), scene.width, scene.height) &&
                       (!r.exr || render::exr_decodes_at_size(exr_file.string(), scene.width, scene.height, !r.reference));
    verify_s += seconds_since(t_verify);
    if (r.vdb) {
      // The medium the frame shows, at its instant, written atomically (a rerun writes the missing).
      fs::path vdb_file = file;
      vdb_file.replace_extension(".vdb");
      std::error_code vec;
      if (!fs::exists(vdb_file, vec)) {
        const auto t_vdb = clock::now();
        core::Scene at;
        const core::FrameSpec f = render::resolve_path_frame(scene, path, vol, k, r.fps, &at);
        const auto prepared = volumes.get(scene.data.path, vol, f.instant, at.time.interpolation, nullptr, at.render.march.medium.modelled);
        const bool fraction = !f.instant.between() && vol.has_field[static_cast<int>(core::Field::CloudFraction)];
        core::OutputGroup group;
        vdb::write_vdb(group, vdb_file.string(), prepared->grid, prepared->extinction,
                       fraction ? &vol.step(f.instant.step0)[core::Field::CloudFraction] : nullptr, f.instant.iso_utc);
        group.commit();
        vdb_s += seconds_since(t_vdb);
        ++vdb_written;
      }
    }
    if (whole) {
      ++skipped;
      continue;
    }
    const auto t0 = clock::now();
    core::FrameSpec frame;
    std::vector<glm::vec4> pixels;
    if (auto kept = probed.find(k); kept != probed.end()) {
      frame = kept->second.first;
      pixels = std::move(kept->second.second);
    } else {
      pixels = render_frame(k, nullptr, frame);
    }
    render::check_finite_pixels(pixels, frame.camera.width, file.string());
    render::ToneSettings tone;
    tone.exposure = *exposure;
    if (frame.march.features.atmosphere || frame.march.features.globe) tone.background = glm::dvec3(0.0);
    const std::vector<unsigned char> rgb8 = render::tonemap_srgb8(pixels, tone);
    // The EXR before the PNG: a whole PNG is what marks the frame done.
    if (r.exr) {
      core::write_file_atomically(exr_file.string(),
                                  [&](std::FILE* f) { render::encode_exr(f, frame.camera.width, frame.camera.height, pixels, !r.reference); });
      ++exr_written;
    }
    core::write_file_atomically(file.string(), [&](std::FILE* f) { render::encode_png(f, frame.camera.width, frame.camera.height, rgb8); });
    render_s += seconds_since(t0);
    ++rendered;
    const int done = k - first + 1, total = last - first + 1;
    const double per_min = 60.0 * rendered / std::max(1e-9, render_s);
    std::printf("%sframe %d of %d (%s), %.1f frames/min, ETA %s%s", tty ? "\r" : "", done, total, file.filename().c_str(), per_min,
                eta_text((total - done) * 60.0 / per_min).c_str(), tty ? "   " : "\n");
    std::fflush(stdout);
  }
  if (tty && rendered > 0) std::printf("\n");
  const double loop_s = seconds_since(t_loop);
  std::printf("rendered %d frame(s), skipped %d already whole, in %.1f s (%.1f frames/min; checking frames on disk %.3f s)\n", rendered,
              skipped, loop_s, rendered > 0 ? 60.0 * rendered / std::max(1e-9, render_s) : 0.0, verify_s);
  if (r.vdb) std::printf("wrote %d OpenVDB file(s) beside the frames in %.2f s\n", vdb_written, vdb_s);
  if (r.exr) std::printf("wrote %d OpenEXR frame(s) beside the PNGs\n", exr_written);
  if (!encode) {
    std::printf("frames %d..%d of %d in %s; build the video with: cloudviewer record %s -o %s --assemble\n", first, last, count, folder.c_str(),
                r.scene_path.c_str(), r.out.c_str());
    return 0;
  }
  const auto t_enc = clock::now();
  assemble_mp4(ffmpeg, folder, r.out, r.fps, r.crf);
  const double enc_s = seconds_since(t_enc), all_s = seconds_since(t_start);
  std::printf("wrote %s: %d frames, encoded in %.2f s (%.1f %% of the run's %.1f s)\n", r.out.c_str(), count, enc_s, 100.0 * enc_s / all_s, all_s);
  return 0;
}

}  // namespace cv::cli
