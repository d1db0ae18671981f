// The `cloudviewer` command: batch subcommands (more arrive with the importers and the renderer).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <regex>
#include <string>
#include <vector>

#include "geo/geodesy.hpp"
#include "geo/solar.hpp"
#include "importer.hpp"
#include <glm/glm.hpp>
#include "physics/physics.hpp"
#include "volume/volume_io.hpp"
#include "reference/raymarcher.hpp"
#include "render/context.hpp"
#include "render/image_output.hpp"
#include "render/raymarcher.hpp"
#include "render/shader_loader.hpp"

namespace {

namespace fs = std::filesystem;
constexpr int kExitBadInput = 2;

// Bad command-line input: one line naming the argument, what was found and what was expected.
struct UsageError {
  std::string message;
};

void print_usage() {
  std::printf(
      "usage: cloudviewer <command> [options]\n"
      "commands:\n"
      "  info FILE                what the importer understands of a NetCDF file (or a .cvvol volume)\n"
      "  import FILE -o OUT [--region W,E,S,N] [--times FIRST:LAST[:STRIDE] | --times START..END]\n"
      "         [--levels MIN_HPA:MAX_HPA]\n"
      "         [--stride N] [--dz M] [--reff-liquid UM] [--reff-ice UM] [--vti]\n"
      "                           import into OUT.cvvol (+ OUT.report.json, and OUT_tNNN.vti with --vti)\n"
      "  gpu-info                 open a headless OpenGL 4.5 context and compile every shader\n"
      "  phase --diameter D_UM    approximate Mie phase parameters for a droplet diameter\n"
      "  render INPUT -o OUT.png [--size WxH] [--time N] [--camera lat,lon,alt_m,heading,pitch,fov]\n"
      "         [--sun LAT,LON] [--steps M] [--sun-steps N] [--octaves N] [--accumulate N] [--exposure E]\n"
      "         [--pfm OUT.pfm] [--no-skip] [--adaptive TAU]\n"
      "                           (the sun stands where it stood at the valid time unless --sun is given;\n"
      "                           --no-skip marches empty bricks too, --adaptive divides view steps to\n"
      "                           at most TAU optical depth each)\n"
      "                           render a NetCDF file or .cvvol volume headlessly (EGL) to a PNG\n"
      "  --version                print the version\n");
}

double parse_number(const std::string& option, const std::string& text) {
  try {
    size_t used = 0;
    const double v = std::stod(text, &used);
    if (used == text.size() && std::isfinite(v)) return v;
  } catch (const std::exception&) {
  }
  throw UsageError{"cloudviewer: " + option + ": found '" + text + "', expected a finite number"};
}

std::vector<fs::path> all_shaders(const fs::path& dir) {
  std::vector<fs::path> out;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file() && e.path().extension() == ".comp") out.push_back(e.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Opens the headless context and compiles every compute shader; returns how many compiled.
int check_gpu(bool verbose) {
  auto ctx = cv::render::make_headless_context();
  std::printf("context: %s\n", ctx->info().summary().c_str());
  const fs::path dir = cv::render::ShaderLoader::default_shader_dir();
  cv::render::ShaderLoader loader({dir});
  int n = 0;
  for (const auto& file : all_shaders(dir)) {
    cv::render::load_compute(loader, file);
    if (verbose) std::printf("compiled %s\n", fs::relative(file, dir).c_str());
    ++n;
  }
  std::printf("%d compute shader(s) compiled from %s\n", n, dir.c_str());
  return n;
}

int cmd_phase(const std::vector<std::string>& args) {
  double d_um = -1.0;
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--diameter" && i + 1 < args.size()) {
      d_um = parse_number("--diameter", args[++i]);
    } else {
      throw UsageError{"cloudviewer phase: unexpected argument '" + args[i] + "', expected --diameter D_UM"};
    }
  }
  if (!(d_um >= 0.01 && d_um <= 50.0)) {
    throw UsageError{"cloudviewer phase: --diameter: expected a droplet diameter in [0.01, 50] um"};
  }
  const auto p = cv::physics::f64::mie_params(d_um);
  std::printf("droplet diameter %.4g um: g_HG %.4f  g_D %.4f  alpha %.4f  w_D %.4f  mean cosine %.4f\n", d_um,
              p.g_hg, p.g_d, p.alpha, p.w_d, cv::physics::f64::mie_mean_cosine(p));
  return 0;
}

std::vector<double> parse_list(const std::string& option, const std::string& text, char sep, std::size_t min_n,
                               std::size_t max_n, const char* expected) {
  std::vector<double> out;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const std::size_t end = text.find(sep, pos);
    const std::string item = text.substr(pos, end == std::string::npos ? std::string::npos : end - pos);
    try {
      out.push_back(parse_number(option, item));
    } catch (const UsageError&) {
      throw UsageError{"cloudviewer: " + option + ": found '" + text + "', expected " + expected};
    }
    if (end == std::string::npos) break;
    pos = end + 1;
  }
  if (out.size() < min_n || out.size() > max_n) {
    throw UsageError{"cloudviewer: " + option + ": found '" + text + "', expected " + expected};
  }
  return out;
}

int cmd_info(const std::vector<std::string>& args) {
  if (args.size() != 1) throw UsageError{"cloudviewer info: expected one FILE argument"};
  const std::string& path = args[0];
  if (path.size() > 6 && path.substr(path.size() - 6) == ".cvvol") {
    const cv::core::CloudVolume v = cv::core::read_cvvol(path);
    const auto& g = v.grid;
    std::printf("file: %s\nformat: cloud volume (.cvvol)\ngrid: %d x %d x %d, lon %.6g..%.6g step %.6g, lat %.6g..%.6g step "
                "%.6g, altitude %.6g..%.6g m step %.6g, Earth radius %.0f m\n",
                path.c_str(), g.lon_deg.count, g.lat_deg.count, g.alt_m.count, g.lon_deg.start, g.lon_deg.last(),
                g.lon_deg.step, g.lat_deg.start, g.lat_deg.last(), g.lat_deg.step, g.alt_m.start, g.alt_m.last(),
                g.alt_m.step, g.earth_radius_m);
    std::printf("times: %zu", v.times.size());
    if (!v.times.empty()) std::printf(", %s to %s", v.times.front().iso_utc.c_str(), v.times.back().iso_utc.c_str());
    std::printf("\nfields:");
    for (int i = 0; i < cv::core::kFieldCount; ++i) {
      if (v.has_field[static_cast<std::size_t>(i)]) {
        std::printf(" %s [%s]", cv::core::field_name(static_cast<cv::core::Field>(i)),
                    cv::core::field_units(static_cast<cv::core::Field>(i)));
      }
    }
    std::printf("\n");
    return 0;
  }
  std::printf("%s", cv::importers::describe_file(path).c_str());
  return 0;
}

int cmd_import(const std::vector<std::string>& args) {
  cv::importers::ImportOptions o;
  std::string input, out;
  bool vti = false;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto next = [&]() -> const std::string& {
      if (i + 1 >= args.size()) throw UsageError{"cloudviewer import: " + a + ": expected a value after it"};
      return args[++i];
    };
    if (a == "-o") out = next();
    else if (a == "--vti") vti = true;
    else if (a == "--region") {
      const auto r = parse_list("--region", next(), ',', 4, 4, "W,E,S,N in degrees");
      if (r[2] > r[3] || r[2] < -90 || r[3] > 90) throw UsageError{"cloudviewer import: --region: expected S <= N within -90..90"};
      o.region = cv::importers::Region{r[0], r[1], r[2], r[3]};
    } else if (a == "--times" && i + 1 < args.size() && args[i + 1].find("..") != std::string::npos) {
      // A valid-time range: START..END in ISO 8601 UTC, either end may be empty.
      const std::string r = next();
      static const std::regex iso(R"(^(\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}Z)?$)");
      const std::string from = r.substr(0, r.find("..")), to = r.substr(r.find("..") + 2);
      if (!std::regex_match(from, iso) || !std::regex_match(to, iso)) {
        throw UsageError{"cloudviewer import: --times: found '" + r + "', expected START..END as YYYY-MM-DDThh:mm:ssZ"};
      }
      o.time_from_iso = from;
      o.time_to_iso = to;
    } else if (a == "--times") {
      const auto t = parse_list("--times", next(), ':', 2, 3, "FIRST:LAST[:STRIDE] as step indices, or START..END as ISO times");
      o.time_first = static_cast<int>(t[0]);
      o.time_last = static_cast<int>(t[1]);
      o.time_stride = t.size() > 2 ? static_cast<int>(t[2]) : 1;
      if (o.time_first < 0 || o.time_stride < 1) throw UsageError{"cloudviewer import: --times: expected FIRST >= 0 and STRIDE >= 1"};
    } else if (a == "--levels") {
      const auto l = parse_list("--levels", next(), ':', 2, 2, "MIN_HPA:MAX_HPA");
      o.level_min_hpa = l[0];
      o.level_max_hpa = l[1];
    } else if (a == "--stride") {
      o.horizontal_stride = static_cast<int>(parse_number("--stride", next()));
      if (o.horizontal_stride < 1) throw UsageError{"cloudviewer import: --stride: expected an integer >= 1"};
    } else if (a == "--dz") {
      o.dz_m = parse_number("--dz", next());
      if (!(o.dz_m > 0)) throw UsageError{"cloudviewer import: --dz: expected a spacing in metres > 0"};
    } else if (a == "--reff-liquid") {
      o.r_eff_liquid_um = parse_number("--reff-liquid", next());
      if (!(o.r_eff_liquid_um >= 1 && o.r_eff_liquid_um <= 50)) throw UsageError{"cloudviewer import: --reff-liquid: expected 1..50 um"};
    } else if (a == "--reff-ice") {
      o.r_eff_ice_um = parse_number("--reff-ice", next());
      if (!(o.r_eff_ice_um >= 5 && o.r_eff_ice_um <= 200)) throw UsageError{"cloudviewer import: --reff-ice: expected 5..200 um"};
    } else if (!a.empty() && a[0] == '-') {
      throw UsageError{"cloudviewer import: unknown option '" + a + "'"};
    } else if (input.empty()) {
      input = a;
    } else {
      throw UsageError{"cloudviewer import: unexpected argument '" + a + "', expected one FILE"};
    }
  }
  if (input.empty() || out.empty()) throw UsageError{"cloudviewer import: expected FILE and -o OUT"};
  if (out.size() > 6 && out.substr(out.size() - 6) == ".cvvol") out.resize(out.size() - 6);
  o.cache_steps = 1;  // steps are written one after another: keep only the current one
  cv::core::CloudVolume vol = cv::importers::import_file(input, o);
  std::printf("grid: %d x %d x %d (lon %.4g..%.4g, lat %.4g..%.4g, alt %.0f..%.0f m), %zu time step(s)\n",
              vol.grid.lon_deg.count, vol.grid.lat_deg.count, vol.grid.alt_m.count, vol.grid.lon_deg.start,
              vol.grid.lon_deg.last(), vol.grid.lat_deg.start, vol.grid.lat_deg.last(), vol.grid.alt_m.start,
              vol.grid.alt_m.last(), vol.times.size());
  cv::core::write_cvvol(out + ".cvvol", vol, [&](std::size_t t, std::size_t n) {
    std::printf("importing time step %zu/%zu (%s)\n", t + 1, n, vol.times[t].iso_utc.c_str());
    std::fflush(stdout);
    if (vti) {
      char name[32];
      std::snprintf(name, sizeof name, "_t%03zu.vti", t);
      cv::core::write_vti(out + name, vol.grid, vol.step(t), vol.has_field);
    }
  });
  cv::core::write_file_atomically(out + ".report.json", [&](std::FILE* f) {
    const std::string j = vol.report.to_json();
    std::fwrite(j.data(), 1, j.size(), f);
  });
  std::printf("%s", vol.report.to_text().c_str());
  std::printf("wrote %s.cvvol and %s.report.json%s\n", out.c_str(), out.c_str(), vti ? " and .vti files" : "");
  return 0;
}

int cmd_render(const std::vector<std::string>& args) {
  using clock = std::chrono::steady_clock;
  auto seconds = [](clock::time_point a) { return std::chrono::duration<double>(clock::now() - a).count(); };
  std::string input, out, pfm;
  int w = 960, h = 540, step = 0, accumulate = 1;
  std::optional<std::vector<double>> camera, sun;
  cv::core::MarchSettings march;
  march.view_step_m = 0.0;  // from the grid unless set
  march.sun_steps = 16;
  march.octaves = 4;
  cv::render::ToneSettings tone;
  tone.exposure = 4.0;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto next = [&]() -> const std::string& {
      if (i + 1 >= args.size()) throw UsageError{"cloudviewer render: " + a + ": expected a value after it"};
      return args[++i];
    };
    if (a == "-o") out = next();
    else if (a == "--pfm") pfm = next();
    else if (a == "--size") {
      const std::string sz = next();
      if (std::sscanf(sz.c_str(), "%dx%d", &w, &h) != 2 || w < 1 || h < 1 || w > 16384 || h > 16384) {
        throw UsageError{"cloudviewer render: --size: found '" + sz + "', expected WxH with 1..16384 each"};
      }
    } else if (a == "--time") {
      step = static_cast<int>(parse_number("--time", next()));
      if (step < 0) throw UsageError{"cloudviewer render: --time: expected a time-step index >= 0"};
    } else if (a == "--camera") {
      camera = parse_list("--camera", next(), ',', 6, 6, "lat,lon,alt_m,heading,pitch,fov in degrees and metres");
    } else if (a == "--sun") {
      sun = parse_list("--sun", next(), ',', 2, 2, "the subsolar point lat,lon in degrees");
    } else if (a == "--steps") {
      march.view_step_m = parse_number("--steps", next());
      if (!(march.view_step_m > 0)) throw UsageError{"cloudviewer render: --steps: expected a view step in metres > 0"};
    } else if (a == "--sun-steps") {
      march.sun_steps = static_cast<int>(parse_number("--sun-steps", next()));
      if (march.sun_steps < 1 || march.sun_steps > 1024) throw UsageError{"cloudviewer render: --sun-steps: expected 1..1024"};
    } else if (a == "--octaves") {
      march.octaves = static_cast<int>(parse_number("--octaves", next()));
      if (march.octaves < 1 || march.octaves > 16) throw UsageError{"cloudviewer render: --octaves: expected 1..16"};
    } else if (a == "--accumulate") {
      accumulate = static_cast<int>(parse_number("--accumulate", next()));
      if (accumulate < 1 || accumulate > 4096) throw UsageError{"cloudviewer render: --accumulate: expected 1..4096 frames"};
    } else if (a == "--exposure") {
      tone.exposure = parse_number("--exposure", next());
      if (!(tone.exposure > 0)) throw UsageError{"cloudviewer render: --exposure: expected a number > 0"};
    } else if (a == "--no-skip") {
      march.skip_empty = false;
    } else if (a == "--adaptive") {
      march.adaptive_steps = true;
      march.max_step_optical_depth = parse_number("--adaptive", next());
      if (!(march.max_step_optical_depth > 0)) {
        throw UsageError{"cloudviewer render: --adaptive: expected the optical depth per substep, a number > 0"};
      }
    } else if (!a.empty() && a[0] == '-') {
      throw UsageError{"cloudviewer render: unknown option '" + a + "'"};
    } else if (input.empty()) {
      input = a;
    } else {
      throw UsageError{"cloudviewer render: unexpected argument '" + a + "', expected one INPUT"};
    }
  }
  if (input.empty() || out.empty()) throw UsageError{"cloudviewer render: expected INPUT (.nc or .cvvol) and -o OUT.png"};
  auto t0 = clock::now();
  cv::core::CloudVolume vol = input.size() > 6 && input.substr(input.size() - 6) == ".cvvol"
                                  ? cv::core::read_cvvol(input, 1)
                                  : cv::importers::import_file(input, cv::importers::ImportOptions{});
  if (static_cast<std::size_t>(step) >= vol.times.size()) {
    throw UsageError{"cloudviewer render: --time: found " + std::to_string(step) + ", the input has " +
                     std::to_string(vol.times.size()) + " time step(s)"};
  }
  const cv::core::TimeStepData& data = vol.step(static_cast<std::size_t>(step));
  const cv::core::GridMeanExtinction medium = cv::core::grid_mean_extinction(vol.grid, data);
  const double t_load = seconds(t0);
  const auto& g = vol.grid;
  if (g.lon_deg.count < 2 || g.lat_deg.count < 2 || g.alt_m.count < 2) {
    throw UsageError{"cloudviewer render: " + input + ": the volume is " + std::to_string(g.lon_deg.count) + " x " +
                     std::to_string(g.lat_deg.count) + " x " + std::to_string(g.alt_m.count) +
                     " points; rendering needs at least 2 along each axis"};
  }
  cv::core::Camera cam;
  cam.width = w;
  cam.height = h;
  if (camera) {
    const auto& c = *camera;
    cam.lat_deg = c[0], cam.lon_deg = c[1], cam.alt_m = c[2], cam.heading_deg = c[3], cam.pitch_deg = c[4], cam.fov_deg = c[5];
    if (!(cam.alt_m >= 0.0 && cam.alt_m <= 4e8) || !(cam.fov_deg > 0.0 && cam.fov_deg < 180.0) || std::abs(cam.lat_deg) > 90.0) {
      throw UsageError{"cloudviewer render: --camera: expected |lat| <= 90, altitude 0..4e8 m and fov in (0, 180) degrees"};
    }
  } else {
    // South of the volume and high up, aimed at its centre.
    const double span = g.lat_deg.last() - g.lat_deg.start;
    const double lat_c = g.lat_deg.start + 0.5 * span, lon_c = g.lon_deg.start + 0.5 * (g.lon_deg.last() - g.lon_deg.start);
    cam.lat_deg = std::max(-89.0, g.lat_deg.start - 0.1 * span);
    cam.lon_deg = lon_c;
    cam.alt_m = 90000.0 * span;
    const glm::dvec3 eye = cv::geo::sphere_to_ecef({cam.lat_deg, cam.lon_deg, cam.alt_m}, g.earth_radius_m);
    const glm::dvec3 target = cv::geo::sphere_to_ecef({lat_c, lon_c, g.alt_m.start}, g.earth_radius_m);
    const glm::dvec3 dir = glm::normalize(target - eye);
    const cv::geo::EnuFrame f = cv::geo::sphere_enu(cam.lat_deg, cam.lon_deg);
    cam.pitch_deg = std::asin(glm::dot(dir, f.up)) * 180.0 / 3.14159265358979323846;
    cam.heading_deg = std::atan2(glm::dot(dir, f.east), glm::dot(dir, f.north)) * 180.0 / 3.14159265358979323846;
    cam.fov_deg = 60.0;
  }
  // The sun where it stood at the valid time, unless set by hand or the time is unknown.
  cv::core::Sun s;
  const cv::core::ValidTime& vt = vol.times[static_cast<std::size_t>(step)];
  const bool known_time = vt.iso_utc.find('T') != std::string::npos;
  if (sun) {
    s.subsolar_lat_deg = (*sun)[0];
    s.subsolar_lon_deg = (*sun)[1];
  } else if (known_time) {
    const cv::geo::SubsolarPoint sp = cv::geo::subsolar_point(vt.unix_s);
    s.subsolar_lat_deg = sp.lat_deg;
    s.subsolar_lon_deg = sp.lon_deg;
  } else {
    s.subsolar_lon_deg = cam.lon_deg;  // noon over the camera
    std::printf("the input has no valid times: the sun is put at noon over the camera (set it with --sun)\n");
  }
  std::printf("sun overhead at %.2f, %.2f (%s)\n", s.subsolar_lat_deg, s.subsolar_lon_deg,
              sun ? "--sun" : known_time ? "from the valid time" : "default");
  if (march.view_step_m <= 0.0) march.view_step_m = std::max(50.0, g.alt_m.step);
  std::printf("rendering %s, time step %d (%s), %dx%d, view step %.0f m, %d sun steps, %d octaves, %d frame(s)\n",
              input.c_str(), step, vol.times[static_cast<std::size_t>(step)].iso_utc.c_str(), w, h, march.view_step_m,
              march.sun_steps, march.octaves, accumulate);
  auto ctx = cv::render::make_headless_context();
  const cv::render::ShaderLoader loader({cv::render::ShaderLoader::default_shader_dir()});
  cv::render::GpuRaymarcher gpu(loader);
  t0 = clock::now();
  gpu.upload(g, medium);
  glFinish();
  const double t_upload = seconds(t0);
  t0 = clock::now();
  // One frame at step middles, or the mean of jittered frames (banding averages away).
  std::vector<glm::vec4> pixels;
  if (accumulate == 1) {
    pixels = gpu.render(cam, s, march);
  } else {
    pixels.assign(static_cast<std::size_t>(w) * h, glm::vec4(0.0f));
    for (int f = 0; f < accumulate; ++f) {
      march.frame = f;
      const std::vector<glm::vec4> frame = gpu.render(cam, s, march);
      for (std::size_t i = 0; i < pixels.size(); ++i) pixels[i] += (frame[i] - pixels[i]) / static_cast<float>(f + 1);
      std::printf("\raccumulated %d/%d frames", f + 1, accumulate);
      std::fflush(stdout);
    }
    std::printf("\n");
  }
  const double t_march = seconds(t0);
  t0 = clock::now();
  std::size_t bad = 0;
  for (const auto& p : pixels) bad += !(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && std::isfinite(p.w));
  cv::render::write_png(out, w, h, cv::render::tonemap_srgb8(pixels, tone));
  if (!pfm.empty()) cv::render::write_pfm(pfm, w, h, pixels, tone);
  const double t_write = seconds(t0);
  std::printf("timings: load %.2f s, upload %.3f s, march %.2f s, tonemap and write %.3f s (%s)\n", t_load, t_upload,
              t_march, t_write, ctx->info().renderer.c_str());
  const cv::core::MarchStats& ms = gpu.last_stats();
  std::printf("march%s: %llu view samples, %llu skipped in %llu empty-brick jumps (view and sun), %llu sun samples, "
              "%llu skipped or cut off, %llu of %d rays missed the cloud shell%s\n",
              accumulate > 1 ? " (last frame)" : "", static_cast<unsigned long long>(ms.view_samples),
              static_cast<unsigned long long>(ms.view_skipped), static_cast<unsigned long long>(ms.bricks_jumped),
              static_cast<unsigned long long>(ms.sun_samples), static_cast<unsigned long long>(ms.sun_skipped),
              static_cast<unsigned long long>(ms.rays_missed), w * h, march.skip_empty ? "" : " (skipping off)");
  if (bad) std::fprintf(stderr, "cloudviewer render: %zu pixels were not finite (drawn white)\n", bad);
  std::printf("wrote %s%s\n", out.c_str(), pfm.empty() ? "" : (" and " + pfm).c_str());
  return bad ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty() || args[0] == "-h" || args[0] == "--help") {
    print_usage();
    return args.empty() ? kExitBadInput : 0;
  }
  const std::string cmd = args[0];
  args.erase(args.begin());
  try {
    if (cmd == "--version") {
      std::printf("cloudviewer %s\n", CV_VERSION);
      return 0;
    }
    if (cmd == "gpu-info") return check_gpu(true) > 0 ? 0 : 1;
    if (cmd == "info") return cmd_info(args);
    if (cmd == "import") return cmd_import(args);
    if (cmd == "phase") return cmd_phase(args);
    if (cmd == "render") return cmd_render(args);
    throw UsageError{"cloudviewer: unknown command '" + cmd + "', expected info, import, gpu-info, phase or render"};
  } catch (const UsageError& e) {
    std::fprintf(stderr, "%s\n", e.message.c_str());
    return kExitBadInput;
  } catch (const cv::core::VolumeFileError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return kExitBadInput;
  } catch (const cv::importers::ImportError& e) {
    // Bad input files: one line naming the file and variable, exit code 2.
    std::fprintf(stderr, "%s\n", e.what());
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cloudviewer %s: %s\n", cmd.c_str(), e.what());
    return 1;
  }
}
