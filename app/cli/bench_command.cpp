// `cloudviewer bench`: for each standard scene a cached Monte Carlo reference, then a sweep of quality
// settings and the seed documents' presets on the GPU, timed and held against the reference.
#include "bench_command.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>

#include "bench/metrics.hpp"
#include "bench/reference_cache.hpp"
#include "bench_report.hpp"
#include "cli_common.hpp"
#include "quality_budget.hpp"
#include "geo/geodesy.hpp"
#include "io/output_file.hpp"
#include "noise/noise.hpp"
#include "reference/monte_carlo.hpp"
#include "render/context.hpp"
#include "render/image_output.hpp"
#include "scene/scene.hpp"
#include "render/machine_id.hpp"
#include "render/frame_renderer.hpp"
#include "render/raymarcher.hpp"
#include "scene/quality.hpp"
#include "bench/standard_scenes.hpp"
#include "volume/volume_io.hpp"

#include <glm/geometric.hpp>

namespace cv::cli {

namespace {

namespace fs = std::filesystem;
using clock = std::chrono::steady_clock;

struct BenchArgs {
  std::vector<std::string> scenes;
  int spp = 64, width = 96, height = 54, repeats = 3;
  double ref_error = 0.0;  // stop a reference early at this mean relative standard error (0: at spp)
  std::string out = "bench_out";
  bool cache = true;  // copy quality_front.json to the per-user cache
  // The GPU path tracer's rows: one per count of samples per pixel (empty: none).
  std::vector<int> path_spp = {1, 4, 16};
  // Frame times only: no reference, no error, no front (scripts/bench-gpu at 1920x1080, where a
  // Monte Carlo reference on the CPU would take hours).
  bool timing_only = false;
  // The cloud models run on each scene (--cloud-model): the data mode, the modelled cloud, or both.
  // A modelled run is named "<scene>+modelled" throughout (rows, references, images, the front).
  std::vector<bool> modelled = {false};
};

// "1,4,16" (each in 1..65536, increasing) or "none".
std::vector<int> parse_spp_list(const std::string& text) {
  if (text == "none") return {};
  std::vector<int> out;
  std::size_t at = 0;
  while (at <= text.size()) {
    const std::size_t comma = std::min(text.find(',', at), text.size());
    const std::string item = text.substr(at, comma - at);
    char* end = nullptr;
    const long v = item.empty() ? 0 : std::strtol(item.c_str(), &end, 10);
    if (item.empty() || *end != '\0' || v < 1 || v > 65536 || (!out.empty() && v <= out.back())) {
      throw UsageError{"cloudviewer bench: --path-spp: found '" + text +
                       "', expected increasing samples per pixel in 1..65536 separated by commas (such as 1,4,16), or none"};
    }
    out.push_back(static_cast<int>(v));
    at = comma + 1;
  }
  return out;
}

int parse_int(const std::string& opt, const std::string& text, int lo, int hi, const char* expected) {
  const double v = parse_number(opt, text);
  if (v != std::floor(v) || v < lo || v > hi) {
    throw UsageError{"cloudviewer bench: " + opt + ": found '" + text + "', expected " + expected};
  }
  return static_cast<int>(v);
}

BenchArgs parse_args(const std::vector<std::string>& args) {
  BenchArgs a;
  const auto known = bench::standard_scene_names();
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& s = args[i];
    auto next = [&]() -> const std::string& {
      if (i + 1 >= args.size()) throw UsageError{"cloudviewer bench: " + s + ": expected a value after it"};
      return args[++i];
    };
    if (s == "--reference-spp") a.spp = parse_int(s, next(), 1, 1 << 20, "an integer in 1..1048576 samples per pixel");
    else if (s == "--reference-error") {
      const std::string v = next();
      a.ref_error = parse_number(s, v);
      if (!(a.ref_error > 0.0 && a.ref_error < 1.0)) {
        throw UsageError{"cloudviewer bench: --reference-error: found '" + v +
                         "', expected a mean relative standard error between 0 and 1 (such as 0.02)"};
      }
    } else if (s == "--repeats") a.repeats = parse_int(s, next(), 1, 100, "an integer in 1..100");
    else if (s == "--out") a.out = next();
    else if (s == "--no-cache") a.cache = false;
    else if (s == "--path-spp") a.path_spp = parse_spp_list(next());
    else if (s == "--timing-only") a.timing_only = true;
    else if (s == "--cloud-model") {
      const std::string v = next();
      if (v == "data") a.modelled = {false};
      else if (v == "modelled") a.modelled = {true};
      else if (v == "both") a.modelled = {false, true};
      else throw UsageError{"cloudviewer bench: --cloud-model: found '" + v + "', expected data, modelled or both"};
    }
    else if (s == "--size") {
      const std::string v = next();
      const auto x = v.find('x');
      if (x == std::string::npos) throw UsageError{"cloudviewer bench: --size: found '" + v + "', expected WxH such as 96x54"};
      a.width = parse_int("--size", v.substr(0, x), 8, 4096, "WxH with each in 8..4096");
      a.height = parse_int("--size", v.substr(x + 1), 8, 4096, "WxH with each in 8..4096");
    } else if (!s.empty() && s[0] == '-') {
      throw UsageError{"cloudviewer bench: unknown option '" + s +
                       "', expected --reference-spp, --reference-error, --size, --repeats, --path-spp, --timing-only, --cloud-model, --out "
                       "or --no-cache"};
    } else if (std::find(known.begin(), known.end(), s) == known.end()) {
      std::string names;
      for (const auto& n : known) names += (names.empty() ? "" : ", ") + n;
      throw UsageError{"cloudviewer bench: unknown scene '" + s + "', expected one of " + names};
    } else {
      a.scenes.push_back(s);
    }
  }
  if (a.scenes.empty()) a.scenes = known;
  return a;
}

struct Config {
  std::string name, description;
  ConfigKind kind = ConfigKind::Sweep;
  core::MarchSettings march;
  int accumulate = 1;
  double scale = 1.0;
};

// The length of the camera's central ray inside the cloud layer's shell (m), for Costa's fixed
// count of steps per ray: our march takes one step length for the whole image, so the central
// ray's chord stands for all. 0 when the central ray misses the shell.
double central_chord_m(const bench::StandardScene& sc, const core::CloudLayer& layer) {
  const double r0 = sc.grid.earth_radius_m;
  const glm::dvec3 o = geo::sphere_to_ecef({sc.camera.lat_deg, sc.camera.lon_deg, sc.camera.alt_m}, r0);
  const glm::dvec3 d = core::camera_ray(sc.camera, sc.camera.width / 2, sc.camera.height / 2);
  auto hits = [&](double r, double& t0, double& t1) {  // |o + t d| = r
    const double b = glm::dot(o, d), c = glm::dot(o, o) - r * r, disc = b * b - c;
    if (disc < 0) return false;
    t0 = -b - std::sqrt(disc), t1 = -b + std::sqrt(disc);
    return t1 > 0;
  };
  double a0, a1, b0, b1;
  if (!hits(r0 + layer.top_m, a0, a1)) return 0.0;
  a0 = std::max(a0, 0.0);
  double len = a1 - a0;
  if (hits(r0 + std::max(layer.bottom_m, 0.0), b0, b1)) {  // minus the part below the shell's bottom
    len -= std::max(0.0, std::min(b1, a1) - std::max(b0, a0));
    if (hits(r0, b0, b1) && b0 > a0) len = std::min(len, b0 - a0);  // a ray that meets the ground stops there
  }
  return std::max(len, 0.0);
}

std::vector<Config> make_configs(const bench::StandardScene& sc, const core::MarchSettings& base, const core::CloudLayer& layer) {
  std::vector<Config> out;
  auto from_preset = [&](const std::string& preset) {
    core::RenderSettings rs;
    rs.march = base;
    core::apply_quality(preset, rs);
    rs.march.quality.view_step_m = core::resolve_view_step_m(rs, sc.grid);
    Config c{preset, "", ConfigKind::Preset, rs.march, rs.accumulate, 1.0};
    return c;
  };
  for (const char* p : {"low", "default", "high"}) out.push_back(from_preset(p));
  const Config def = from_preset("default");
  const double dz = std::abs(sc.grid.alt_m.step);
  auto add = [&](const std::string& name, auto change) {
    Config c = def;
    c.name = name, c.kind = ConfigKind::Sweep;
    change(c);
    out.push_back(c);
  };
  for (double f : {4.0, 2.0, 0.5, 0.25}) {
    char n[32];
    std::snprintf(n, sizeof n, "step_%gdz", f);
    add(n, [&](Config& c) { c.march.quality.view_step_m = std::max(25.0, f * dz); });
  }
  for (int s : {4, 8, 32}) add("sun_" + std::to_string(s), [&](Config& c) { c.march.quality.sun_steps = s; });
  add("accumulate_4", [](Config& c) { c.accumulate = 4; });
  add("scale_0.5", [](Config& c) { c.scale = 0.5; });
  add("adaptive", [](Config& c) { c.march.features.adaptive_steps = true; });
  add("fast_2dz_sun8_scale0.5", [&](Config& c) {
    c.march.quality.view_step_m = std::max(25.0, 2.0 * dz), c.march.quality.sun_steps = 8, c.scale = 0.5;
  });
  // The seed documents' methods (../shared/seeds), as near as our march's settings come: the classic
  // octave sum (no gate by column optical depth) and a fixed count of sun steps (no fewer in thin
  // cloud), since those are ours; empty-space skipping stays on (it does not change the image).
  const double chord = central_chord_m(sc, layer);
  const auto seed = [](Config& c) {
    c.kind = ConfigKind::Seed;
    c.march.medium.ms_two_stream = false;  // the documents' own octave sum
    c.march.features.octave_gate = false;
    c.march.quality.max_sun_step_optical_depth = 0.0;
  };
  // The octave sum the seed documents use for multiple scattering, beside the two-stream default:
  // with our gate at the default preset, with 8 octaves, and the classic sum without the gate.
  add("octave_sum", [&](Config& c) {
    c.kind = ConfigKind::Seed;
    c.description = "the default preset with the octave sum (4 octaves, gate on) for multiple scattering";
    c.march.medium.ms_two_stream = false;
  });
  add("octave_sum_8", [&](Config& c) {
    c.kind = ConfigKind::Seed;
    c.description = "the default preset with the octave sum at 8 octaves, gate on";
    c.march.medium.ms_two_stream = false, c.march.quality.octaves = 8;
  });
  add("two_stream_linear", [&](Config& c) {
    c.kind = ConfigKind::Seed;
    c.description = "the default preset with the two-stream source's diffuse light linear in angle (diffuse_shape linear)";
    c.march.medium.ms_two_stream = true, c.march.medium.ms_slab = false;
  });
  add("octave_sum_classic", [&](Config& c) {
    c.kind = ConfigKind::Seed;
    c.description = "the default preset with the classic octave sum (4 octaves, no gate)";
    c.march.medium.ms_two_stream = false, c.march.features.octave_gate = false;
  });
  add("costa2023", [&](Config& c) {
    seed(c);
    c.description = "64 view steps over the central ray's chord of the cloud shell, 32 light steps, HG, single scattering";
    c.march.quality.view_step_m = chord > 0.0 ? chord / 64.0 : std::max(25.0, (layer.top_m - layer.bottom_m) / 64.0);
    c.march.quality.sun_steps = 32, c.march.quality.octaves = 1, c.march.medium.liquid_phase_hg = true;
  });
  add("haggstrom2018", [&](Config& c) {
    seed(c);
    c.description = "long steps of 2 dz split into short ones in dense cloud (adaptive), 4 sun steps, HG";
    c.march.quality.view_step_m = std::max(50.0, 2.0 * dz), c.march.features.adaptive_steps = true;
    c.march.quality.sun_steps = 4, c.march.quality.octaves = 1, c.march.medium.liquid_phase_hg = true;
  });
  add("fordsung2024", [&](Config& c) {
    seed(c);
    c.description = "100 m steps, 8 octaves, approximate Mie at 20 um, 8 accumulated frames";
    c.march.quality.view_step_m = 100.0, c.march.quality.octaves = 8, c.march.medium.droplet_diameter_um = 20.0, c.accumulate = 8;
  });
  return out;
}

// Error image: |L - L_ref| / max L_ref on a black-red-yellow-white ramp, full scale at 10 %.
std::vector<unsigned char> error_png(const std::vector<double>& e) {
  std::vector<unsigned char> out(e.size() * 3);
  for (std::size_t i = 0; i < e.size(); ++i) {
    const double v = std::clamp(e[i] / 0.1, 0.0, 1.0) * 3.0;
    out[i * 3 + 0] = static_cast<unsigned char>(255 * std::clamp(v, 0.0, 1.0));
    out[i * 3 + 1] = static_cast<unsigned char>(255 * std::clamp(v - 1.0, 0.0, 1.0));
    out[i * 3 + 2] = static_cast<unsigned char>(255 * std::clamp(v - 2.0, 0.0, 1.0));
  }
  return out;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

const char* bench_usage() {
  return "  bench [SCENE...] [--reference-spp N] [--reference-error E] [--size WxH] [--repeats R] [--path-spp LIST]\n"
         "        [--timing-only] [--cloud-model data|modelled|both] [--out DIR] [--no-cache]\n"
         "                           error against run time on the standard scenes (default all, 96x54, 64 spp,\n"
         "                           3 repeats, into bench_out): results.csv, summary.md, plots and error images,\n"
         "                           the march's quality sweep, presets and the seed documents' methods, and the\n"
         "                           GPU path tracer at each of --path-spp samples per pixel (default 1,4,16;\n"
         "                           none: left out; timed once; never a --budget-ms candidate),\n"
         "                           --timing-only: frame times (wall and GL timer) without references or errors,\n"
         "                           the path tracer with its own relative standard error; no front is written,\n"
         "                           quality_front.json (also cached per user for --budget-ms unless --no-cache).\n"
         "                           References are cached in DIR with their sums: a larger N extends them, an\n"
         "                           interrupted one resumes; --reference-error stops one early at that mean\n"
         "                           relative standard error. --cloud-model modelled (or both) runs each scene\n"
         "                           with the modelled cloud too, as <scene>+modelled, against the Monte Carlo of\n"
         "                           the same modelled density (default data)\n";
}

int cmd_bench(const std::vector<std::string>& args) {
  const BenchArgs a = parse_args(args);
  std::error_code ec;
  fs::create_directories(a.out, ec);
  if (ec || !fs::is_directory(a.out)) throw UsageError{"cloudviewer bench: --out: cannot create the folder '" + a.out + "'"};
  core::check_output_path((fs::path(a.out) / "results.csv").string(), "--out");  // the folder can be written
  auto ctx = render::make_headless_context();
  const std::string machine = ctx->info().summary();
  std::printf("bench: %zu scene(s) at %dx%d, references %d spp, %d repeat(s), into %s; %s\n", a.scenes.size(), a.width,
              a.height, a.spp, a.repeats, a.out.c_str(), machine.c_str());
  const render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  render::FrameRenderer renderer(loader);
  std::vector<BenchRow> rows;
  std::vector<SceneReference> refs;
  std::map<std::string, double> dz_by_scene;  // for the front file: view steps as multiples of dz
  std::set<std::string> variants_warm;  // program variants compiled already (compile time is not frame time)
  core::ErosionNoise noise;  // the modelled cloud's tiles and table, made once when a run needs them (as FrameRenderer's)
  std::vector<std::pair<std::string, bool>> runs;  // (scene, modelled)
  for (const auto& scene : a.scenes)
    for (bool m : a.modelled) runs.emplace_back(scene, m);
  for (const auto& run : runs) {
    const std::string& scene_name = run.first;
    const bool modelled = run.second;
    const bench::StandardScene sc = bench::standard_scene(scene_name, a.width, a.height);
    const std::string name = scene_name + (modelled ? "+modelled" : "");
    const core::GridMeanExtinction medium = core::grid_mean_extinction(sc.grid, sc.data);
    dz_by_scene[name] = std::abs(sc.grid.alt_m.step);
    if (modelled && noise.detail.empty()) {
      noise = core::make_erosion_noise();
      core::with_detail_table(noise);
    }
    // Clouds only, as the Monte Carlo reference models them.
    core::MarchSettings base = sc.march;
    base.medium.modelled = modelled;
    base.medium.ms_two_stream = core::scene_march_defaults().medium.ms_two_stream;  // the model the product renders with
    base.medium.ms_slab = core::scene_march_defaults().medium.ms_slab;
    base.features.atmosphere = base.features.globe = false;
    base.medium.ambient = 0.0, base.medium.noise_amount = 0.0;
    // The reference samples pixel centres: accumulated configurations march them too, so their
    // error is the transport's, not the difference between a filtered image and a point-sampled one.
    base.quality.anti_alias = false;
    if (!(base.medium.droplet_diameter_um > 0.0)) base.medium.droplet_diameter_um = 20.0;
    core::MonteCarloSettings mc;
    // The modelled cloud's one majorant is the densest shape anywhere (about 14x the in-cloud
    // extinction): its brick bounds are tighter (core::medium_pyramid), the expectation the same.
    mc.brick_majorants = modelled;
    std::vector<glm::dvec3> ref_rgb;  // the reference's mean and variance per pixel (none with --timing-only)
    std::vector<double> ref_var;
    // The reference: cached by scene, size and a hash of what decides it, with its running sums, so
    // a later run with more samples (or one resumed after an interruption) extends it.
    if (!a.timing_only) {
      const bench::ExtendedReference er = bench::extend_reference(a.out, name, sc, medium, base, mc, a.spp, a.ref_error,
                                                                  modelled ? &noise : nullptr, stdout);
      const core::MonteCarloImage& img = er.img;
      SceneReference ref{name, fs::path(er.path).filename().string(), a.spp, 0.0, false, er.seconds};
      const std::uint64_t cached_spp = er.cached_spp;
      ref.cached = cached_spp > 0;
      ref.cached_spp = static_cast<int>(cached_spp);
      ref.spp = static_cast<int>(img.spp);
      ref.mean_rel_stderr = img.mean_relative_standard_error();
      ref_rgb = img.radiance();
      ref_var = img.luminance_variance();
      refs.push_back(ref);
    }
    fs::create_directories(fs::path(a.out) / name);
    // The row's error against the reference and its error image; with --timing-only, none (NaN).
    auto set_error = [&](BenchRow& row, const std::string& image, const std::vector<glm::dvec3>& rgb) {
      if (a.timing_only) {
        const double nan = std::numeric_limits<double>::quiet_NaN();
        row.err.rel_rmse = row.err.rel_rmse_raw = row.err.rel_noise_floor = row.err.rel_rmse_resolution = nan;
        row.err.rel_bias = row.err.worst = row.err.psnr_db = nan;
        return;
      }
      row.err = bench::image_error(rgb, ref_rgb, ref_var);
      row.error_image = image;
      render::write_png((fs::path(a.out) / row.error_image).string(), a.width, a.height,
                        error_png(bench::pixel_error(rgb, ref_rgb)));
    };
    const auto prepared = std::make_shared<const core::PreparedVolume>(core::prepare_volume(sc.grid, medium));
    renderer.use_volume(prepared);
    const auto configs = make_configs(sc, base, prepared->layer);
    for (std::size_t ci = 0; ci < configs.size(); ++ci) {
      const Config& c = configs[ci];
      // The frame as `render` marches it: at the configuration's scale, accumulated, upscaled.
      core::FrameSpec frame;
      frame.camera = sc.camera;
      frame.camera.width = a.width, frame.camera.height = a.height;
      frame.march_camera = frame.camera;
      core::march_size(a.width, a.height, c.scale, frame.march_camera.width, frame.march_camera.height);
      frame.sun = sc.sun;
      frame.march = c.march;
      frame.accumulate = c.accumulate;
      std::vector<glm::vec4> pixels;
      auto render_image = [&](double& gpu_s) {
        render::DispatchOptions dispatch;
        dispatch.gpu_seconds = &gpu_s;
        return renderer.render(frame, dispatch);
      };
      const std::string variant = std::to_string(kernel::MarchVariant::of(c.march).key());
      if (variants_warm.insert(variant).second) {
        double ignored = 0.0;
        render_image(ignored);
      }
      std::vector<double> wall, gpu_t;
      for (int r = 0; r < a.repeats; ++r) {
        double gpu_s = 0.0;
        const auto t0 = clock::now();
        pixels = render_image(gpu_s);
        wall.push_back(seconds_since(t0) * 1e3);
        gpu_t.push_back(gpu_s * 1e3);
      }
      std::vector<glm::dvec3> rgb(pixels.size());
      for (std::size_t i = 0; i < pixels.size(); ++i) rgb[i] = glm::dvec3(pixels[i].x, pixels[i].y, pixels[i].z);
      BenchRow row;
      row.scene = name, row.config = c.name, row.description = c.description, row.kind = c.kind;
      row.view_step_m = c.march.quality.view_step_m;
      core::RenderSettings marched;
      marched.march = c.march, marched.accumulate = c.accumulate, marched.resolution_scale = c.scale;
      row.knobs = core::knobs_of(marched, c.march.quality.view_step_m, sc.grid.alt_m.step);
      row.phase_hg = c.march.medium.liquid_phase_hg;
      row.wall_ms = median(wall), row.gpu_ms = median(gpu_t);
      set_error(row, name + "/err_" + c.name + ".png", rgb);
      std::printf("%s [%zu/%zu] %-22s %8.2f ms  rel. RMSE %-9.3g (raw %-9.3g) bias %+-9.3g worst %-8.3g PSNR %.1f dB\n",
                  name.c_str(), ci + 1, configs.size(), c.name.c_str(), row.wall_ms, row.err.rel_rmse, row.err.rel_rmse_raw,
                  row.err.rel_bias, row.err.worst, row.err.psnr_db);
      std::fflush(stdout);
      rows.push_back(row);
    }
    // The GPU path tracer (`render --quality reference`) on the reference's transport problem (same
    // clouds, camera, sun, bounces and forward-peak technique), at each --path-spp count: it is
    // unbiased, so its error is its own noise, and it falls as 1/sqrt(spp). Its seed is not the
    // reference's, so the two estimates share no random numbers (with the same seed the float paths
    // would follow the double ones and the error would read as near zero).
    render::PathTraceSettings pt;
    pt.max_bounces = mc.max_bounces, pt.roulette_after = mc.roulette_after, pt.peak_mis = mc.peak_mis;
    pt.seed = static_cast<std::uint32_t>(mc.seed) ^ 0x9e3779b9u;
    if (!a.path_spp.empty()) {  // its program compiled (and its first dispatch made) outside the timing
      core::MonteCarloImage warm;
      renderer.raymarcher().trace_paths(warm, sc.camera, sc.sun, base, 1, pt);
    }
    for (std::size_t k = 0; k < a.path_spp.size(); ++k) {
      const int spp = a.path_spp[k];
      pt.samples_per_readback = std::min(spp, 16);
      core::MonteCarloImage img;
      const auto t0 = clock::now();
      renderer.raymarcher().trace_paths(img, sc.camera, sc.sun, base, spp, pt);
      BenchRow row;
      row.scene = name, row.config = "path_" + std::to_string(spp) + "spp", row.kind = ConfigKind::PathTracer;
      row.description = "the GPU path tracer at " + std::to_string(spp) + " samples per pixel";
      row.phase_hg = base.medium.liquid_phase_hg;
      row.spp = spp;
      row.wall_ms = seconds_since(t0) * 1e3;
      const std::vector<glm::dvec3> rgb = img.radiance();
      set_error(row, name + "/err_" + row.config + ".png", rgb);
      row.own_rel_stderr = img.mean_relative_standard_error();
      std::printf("%s [path %zu/%zu] %-17s %8.2f ms  rel. RMSE %-9.3g (raw %-9.3g) bias %+-9.3g worst %-8.3g PSNR %.1f dB, "
                  "own mean rel. s.e. %.3g\n",
                  name.c_str(), k + 1, a.path_spp.size(), row.config.c_str(), row.wall_ms, row.err.rel_rmse,
                  row.err.rel_rmse_raw, row.err.rel_bias, row.err.worst, row.err.psnr_db, row.own_rel_stderr);
      std::fflush(stdout);
      rows.push_back(row);
    }
  }
  if (!a.timing_only) mark_pareto(rows);
  std::string command = "cloudviewer bench";
  for (const auto& s : args) command += " " + s;
  write_results_csv((fs::path(a.out) / "results.csv").string(), rows, refs);
  write_summary_md((fs::path(a.out) / "summary.md").string(), rows, refs, command, machine);
  if (a.timing_only) {
    std::printf("wrote %s/results.csv (%zu rows) and %s/summary.md (frame times only: no reference, no error, no front)\n",
                a.out.c_str(), rows.size(), a.out.c_str());
    return 0;
  }
  const auto plots = write_plots(a.out, rows);
  write_quality_front(a.out, rows, dz_by_scene, render::machine_id(ctx->info()), a.width, a.height, command, a.cache);
  std::printf("wrote %s/results.csv (%zu rows), %s/summary.md and %zu plot(s)\n", a.out.c_str(), rows.size(), a.out.c_str(),
              plots.size());
  return 0;
}

}  // namespace cv::cli
