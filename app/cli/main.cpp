// The `cloudviewer` command: batch subcommands (more arrive with the importers and the renderer).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <regex>
#include <string>
#include <utility>
#include <vector>

#include "importer.hpp"
#include "scene_source.hpp"
#include "io/input_file.hpp"
#include "io/output_file.hpp"
#include "scene/framing.hpp"
#include "scene/instant.hpp"
#include "physics/physics.hpp"
#include "volume/volume_io.hpp"
#include "render/albedo_map.hpp"
#include "render/context.hpp"
#include "render/shader_loader.hpp"
#include "cli_common.hpp"
#include "record_command.hpp"
#include "render_command.hpp"
#include "vdb/vdb_export.hpp"
#include "bench_command.hpp"
#include "time_error_command.hpp"
#include "analysis_commands.hpp"
#include "scene/scene_json.hpp"
#include "viewer/viewer.hpp"

namespace {

namespace fs = std::filesystem;
using cv::cli::kExitBadInput;
using cv::cli::parse_list;
using cv::cli::parse_number;
using cv::cli::UsageError;

// Each command's lines of the usage text, in the order `cloudviewer --help` lists them.
std::vector<std::pair<std::string, std::string>> command_usages() {
  return {
      {"info", "  info FILE [--diagnose-cloud]\n"
               "                           what the importer understands of a NetCDF file (or a .cvvol volume)\n"},
      {"import",
       "  import FILE -o OUT [--region W,E,S,N] [--times FIRST:LAST[:STRIDE] | --times START..END]\n"
       "         [--levels MIN_HPA:MAX_HPA]\n"
       "         [--stride N] [--dz M] [--reff-liquid UM] [--reff-ice UM] [--vti] [--vdb]\n"
       "         [--diagnose-cloud [--rh-critical RH]] [--float32] [--all-levels]\n"
       "                           import into OUT.cvvol (+ OUT.report.json, and OUT_tNNN.vti with --vti);\n"
       "                           --vdb: OUT_tNNN.vdb, OpenVDB fog volumes of grid-mean liquid and ice extinction\n"
       "                           (1/m) and cloud fraction in metres in a tangent frame at the region's centre\n"
       "                           fields are stored as half floats (--float32: full floats); levels above\n"
       "                           the highest cloud are left out (--all-levels keeps them);\n"
       "                           --diagnose-cloud: a file with temperature and humidity but no cloud field\n"
       "                           gets a cloud diagnosed from relative humidity (Sundqvist, RH_c 0.8 by default)\n"},
      {"gpu-info", "  gpu-info                 open a headless OpenGL 4.5 context and compile every shader\n"},
      {"phase", "  phase --diameter D_UM    approximate Mie phase parameters for a droplet diameter\n"},
      {"render", cv::cli::render_usage()},
      {"record", cv::cli::record_usage()},
      {"bench", cv::cli::bench_usage()},
      {"time-error", cv::cli::time_error_usage()},
      {"probe", cv::cli::probe_usage()},
      {"section", cv::cli::section_usage()},
      {"series", cv::cli::series_usage()},
      {"compare", cv::cli::compare_usage()},
      {"view",
       "  view INPUT [--size WxH] [--time ISO|N] [--play H] [--scale S] [--hide-ui] [--frame-budget MS]\n"
       "             [--compare FILE[@T] | @T ...] [--layout grid|swipe] [--unlinked] [--frames N --screenshot OUT.png]\n"
       "             [--section LAT,LON,LAT,LON[,FIELD]] [--series LAT,LON] [--quality reference [--spp N]]\n"
       "             [--reproject] [--orbit PX] [--diagnose-cloud [--rh-critical RH]]\n"
       "                           --diagnose-cloud: a file with temperature and humidity but no cloud field gets\n"
       "                           a cloud diagnosed from relative humidity (as import's), said on stderr\n"
       "                           --time: an instant (UTC) or a step; --play H: start playing at H forecast\n"
       "                           hours per second (the timeline is in the data panel); with --frames it moves\n"
       "                           one instant per frame and waits for each, unless --realtime (wall time, no wait)\n"
       "                           the interactive viewer (GLFW window); with --frames it renders N frames,\n"
       "                           saves the window to OUT.png and exits; --frame-budget: the quality panel's\n"
       "                           frame budget (0 off)\n"
       "                           --compare: one more view (up to 3) of FILE, of FILE at T (a step or a UTC time),\n"
       "                           or of INPUT at T (@T), each on its own grid, labelled with its file and valid time;\n"
       "                           --layout: a grid of the views (default) or a swipe divider between two (drag it);\n"
       "                           cameras and time are linked (a change in one view moves all) unless --unlinked;\n"
       "                           without --compare, a scene file's \"views\" open (its layout and link unless\n"
       "                           --layout or --unlinked is given); the Scene file panel saves the open views\n"
       "                           --section, --series: open the Section (default field extinction) or Series panel\n"
       "                           with that path or point, drawn as the section and series commands draw them\n"
       "                           --quality reference: the progressive path tracer (the Quality panel's switch):\n"
       "                           one sample per pixel per frame up to N (256), restarted by any change; clouds,\n"
       "                           ground, sunlight through the air and the sky's light, the haze and the overlays\n"
       "                           --reproject: temporal reprojection (the Quality panel's switch): 1/16 of the\n"
       "                           pixels marched per frame, the rest carried from the last image along the\n"
       "                           camera's motion (and the wind's while a forecast plays) and clamped to the\n"
       "                           new samples after a move; a still view has marched every pixel after 16\n"
       "                           frames, then refines 16 frames per accumulated frame, as --frames sets (not\n"
       "                           with overlays)\n"
       "                           --orbit PX: drag the globe PX pixels to the right every frame (scripted orbit)\n"},
  };
}

void print_usage() {
  std::printf("usage: cloudviewer <command> [options]\ncommands:\n");
  for (const auto& [name, text] : command_usages()) std::printf("%s", text.c_str());
  std::printf("  help COMMAND             that command's usage (as COMMAND --help)\n");
  std::printf("  --version                print the version\n");
  std::printf("environment: CLOUDVIEWER_MEMORY_LIMIT  the most memory one input may ask for (bytes, or 512M, 4G, ...;\n"
              "                           default half the machine's memory); larger declared sizes are refused\n"
              "             CLOUDVIEWER_THREADS       worker threads per parallel pass (default one per core)\n"
              "             CLOUDVIEWER_CPU=baseline  no AVX paths (the same output, more slowly; for checks)\n"
              "             CLOUDVIEWER_OPEN_TIMEOUT_S, CLOUDVIEWER_READ_TIMEOUT_S  the longest wait for a NetCDF-4\n"
              "                           file's header (30 s) and for its reads (300 s) before the file is named as hung\n");
}

// `cloudviewer COMMAND --help`: that command's usage, exit 0. False for an unknown command.
bool print_command_usage(const std::string& cmd) {
  for (const auto& [name, text] : command_usages()) {
    if (name == cmd) {
      std::printf("usage: cloudviewer %s [options]\n%s", name.c_str(), text.c_str());
      return true;
    }
  }
  return false;
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

int cmd_info(const std::vector<std::string>& args) {
  cv::importers::ImportOptions options;
  std::vector<std::string> files;
  for (const auto& a : args) {
    if (a == "--diagnose-cloud") options.diagnose_cloud = true;
    else if (!a.empty() && a[0] == '-') throw UsageError{"cloudviewer info: unknown option '" + a + "'"};
    else files.push_back(a);
  }
  if (files.size() != 1) throw UsageError{"cloudviewer info: expected one FILE argument"};
  const std::string& path = files[0];
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
    for (const auto& note : v.report.notes) std::printf("%s\n", note.c_str());
    return 0;
  }
  std::printf("%s", cv::importers::describe_file(path, options).c_str());
  return 0;
}

int cmd_import(const std::vector<std::string>& args) {
  cv::importers::ImportOptions o;
  std::string input, out;
  bool vti = false;
  bool vdb = false;  // OpenVDB grids per step (app/vdb), for graphics teams
  // Fields as half floats unless asked (docs/importers.md states the error bound).
  cv::core::CvvolEncoding encoding = cv::core::CvvolEncoding::Float16;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto next = [&]() -> const std::string& {
      if (i + 1 >= args.size()) throw UsageError{"cloudviewer import: " + a + ": expected a value after it"};
      return args[++i];
    };
    if (a == "-o") out = next();
    else if (a == "--vti") vti = true;
    else if (a == "--vdb") vdb = true;
    else if (a == "--region") {
      const auto r = parse_list("--region", next(), ',', 4, 4, "W,E,S,N in degrees");
      if (r[2] > r[3] || r[2] < -90 || r[3] > 90) throw UsageError{"cloudviewer import: --region: expected S <= N within -90..90"};
      o.region = cv::importers::Region{r[0], r[1], r[2], r[3]};
    } else if (a == "--times" && i + 1 < args.size() && args[i + 1].find("..") != std::string::npos) {
      // A valid-time range: START..END in ISO 8601 UTC, either end may be empty.
      const std::string r = next();
      static const std::regex iso(R"(^(\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}Z)?$)");
      const std::string from = r.substr(0, r.find("..")), to = r.substr(r.find("..") + 2);
      // The form, then the date itself (2020-02-30 has the form of a date and is none).
      if (!std::regex_match(from, iso) || !std::regex_match(to, iso) || (!from.empty() && !cv::core::parse_iso_utc(from)) ||
          (!to.empty() && !cv::core::parse_iso_utc(to))) {
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
      const std::string v = next();
      o.dz_m = parse_number("--dz", v);
      if (!(o.dz_m >= 1.0 && o.dz_m <= 1e5)) {  // the range a scene's data.dz_m takes (0 there: the default)
        throw UsageError{"cloudviewer import: --dz: found '" + v + "', expected a spacing in metres 1..100000"};
      }
    } else if (a == "--reff-liquid") {
      o.r_eff_liquid_um = parse_number("--reff-liquid", next());
      if (!(o.r_eff_liquid_um >= 1 && o.r_eff_liquid_um <= 50)) throw UsageError{"cloudviewer import: --reff-liquid: expected 1..50 um"};
    } else if (a == "--reff-ice") {
      o.r_eff_ice_um = parse_number("--reff-ice", next());
      if (!(o.r_eff_ice_um >= 5 && o.r_eff_ice_um <= 200)) throw UsageError{"cloudviewer import: --reff-ice: expected 5..200 um"};
    } else if (a == "--all-levels") {
      o.keep_cloudless_levels = true;
    } else if (a == "--float32") {
      encoding = cv::core::CvvolEncoding::Float32;
    } else if (a == "--diagnose-cloud") {
      o.diagnose_cloud = true;
    } else if (a == "--rh-critical") {
      o.rh_critical = parse_number("--rh-critical", next());
      if (!(o.rh_critical >= 0.5 && o.rh_critical < 1.0)) throw UsageError{"cloudviewer import: --rh-critical: expected 0.5 <= RH < 1"};
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
  {  // OUT names a volume: an extension of another format is a mistake, not part of the name
    std::string ext = fs::path(out).extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    for (const char* other : {".nc", ".nc4", ".cdf", ".h5", ".png", ".pfm", ".jpg", ".json", ".vti", ".mp4", ".exr", ".tif", ".tiff"}) {
      if (ext == other) {
        throw UsageError{"cloudviewer import: -o: found '" + out + "', expected OUT or OUT.cvvol (it writes a .cvvol volume, "
                         "its .report.json and .vti files, not " + ext + ")"};
      }
    }
  }
  // Every output checked before the import starts: its folder, and none of them the input.
  std::vector<std::string> outputs = {out + ".cvvol", out + ".report.json"};
  if (vti) outputs.push_back(out + "_t000.vti");
  if (vdb) outputs.push_back(out + "_t000.vdb");
  for (const std::string& p : outputs) {
    cv::core::check_output_path(p, "-o");
    cv::core::check_output_not_input(p, "-o", input, "the input");
  }
  o.cache_steps = 1;  // steps are written one after another: keep only the current one
  // A float16 volume alone needs nothing of a step but its half floats: the reader makes them.
  o.half_fields = encoding == cv::core::CvvolEncoding::Float16 && !vti && !vdb;
  cv::core::CloudVolume vol = cv::importers::import_file(input, o);
  cv::importers::print_diagnosed_cloud_note(vol, "cloudviewer import");
  for (std::size_t t = 0; t < vol.times.size(); ++t) {
    for (const char* ext : {".vti", ".vdb"}) {
      if ((std::string(ext) == ".vti" && !vti) || (std::string(ext) == ".vdb" && !vdb)) continue;
      char name[32];
      std::snprintf(name, sizeof name, "_t%03zu%s", t, ext);
      cv::core::check_output_not_input(out + name, "-o", input, "the input");
    }
  }
  std::printf("grid: %d x %d x %d (lon %.4g..%.4g, lat %.4g..%.4g, alt %.0f..%.0f m), %zu time step(s)\n",
              vol.grid.lon_deg.count, vol.grid.lat_deg.count, vol.grid.alt_m.count, vol.grid.lon_deg.start,
              vol.grid.lon_deg.last(), vol.grid.lat_deg.start, vol.grid.lat_deg.last(), vol.grid.alt_m.start,
              vol.grid.alt_m.last(), vol.times.size());
  // The volume, its report and its VTI files belong together: committed together or not at all.
  cv::core::OutputGroup group;
  cv::core::write_cvvol(group, out + ".cvvol", vol, [&](std::size_t t, std::size_t n) {
    std::printf("importing time step %zu/%zu (%s)\n", t + 1, n, vol.times[t].iso_utc.c_str());
    std::fflush(stdout);
    if (vti) {
      char name[32];
      std::snprintf(name, sizeof name, "_t%03zu.vti", t);
      cv::core::write_vti(group, out + name, vol.grid, vol.step(t), vol.has_field);
    }
    if (vdb) {
      char name[32];
      std::snprintf(name, sizeof name, "_t%03zu.vdb", t);
      const cv::vdb::VdbSummary v = cv::vdb::write_vdb(group, out + name, vol.grid, vol.step(t), vol.has_field, vol.times[t].iso_utc);
      std::printf("  %s%s: %zu, %zu and %zu active voxels (liquid, ice extinction, cloud fraction) in %.2f s\n", out.c_str(), name,
                  v.active_voxels[0], v.active_voxels[1], v.active_voxels[2], v.seconds);
    }
  }, encoding);
  group.write(out + ".report.json", [&](std::FILE* f) {
    const std::string j = vol.report.to_json();
    std::fwrite(j.data(), 1, j.size(), f);
  });
  group.commit();
  std::printf("%s", vol.report.to_text().c_str());
  std::printf("wrote %s.cvvol and %s.report.json%s%s\n", out.c_str(), out.c_str(), vti ? " and .vti files" : "", vdb ? " and .vdb files" : "");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // A SIGTERM or SIGINT during a write removes the temporary it was writing.
  cv::core::install_output_cleanup();
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty() || args[0] == "-h" || args[0] == "--help") {
    print_usage();
    return args.empty() ? kExitBadInput : 0;
  }
  if (const char* limit = std::getenv("CLOUDVIEWER_MEMORY_LIMIT"); limit && *limit && !cv::core::parse_byte_size(limit)) {
    std::fprintf(stderr, "cloudviewer: CLOUDVIEWER_MEMORY_LIMIT: found '%s', expected a size in bytes such as 512M or 4G\n", limit);
    return kExitBadInput;
  }
  if (const char* cpu = std::getenv("CLOUDVIEWER_CPU"); cpu && *cpu && std::string(cpu) != "baseline") {
    std::fprintf(stderr, "cloudviewer: CLOUDVIEWER_CPU: found '%s', expected baseline (or unset)\n", cpu);
    return kExitBadInput;
  }
  if (const char* threads = std::getenv("CLOUDVIEWER_THREADS"); threads && *threads) {
    char* end = nullptr;
    const long n = std::strtol(threads, &end, 10);
    if (*end != '\0' || n < 1 || n > 4096) {
      std::fprintf(stderr, "cloudviewer: CLOUDVIEWER_THREADS: found '%s', expected a whole number of threads 1..4096\n", threads);
      return kExitBadInput;
    }
  }
  if (args[0] == "help") {  // `cloudviewer help COMMAND`: as `cloudviewer COMMAND --help`
    if (args.size() == 1 || (args.size() == 2 && (args[1] == "--help" || args[1] == "-h"))) {  // help on help: the usage
      print_usage();
      return 0;
    }
    if (args.size() == 2 && print_command_usage(args[1])) return 0;
    std::fprintf(stderr, "cloudviewer help: found '%s', expected one command: info, import, gpu-info, phase, render, record, bench, time-error, probe, section, series, compare or view\n",
                 args.size() == 2 ? args[1].c_str() : "several arguments");
    return kExitBadInput;
  }
  const std::string cmd = args[0];
  args.erase(args.begin());
  // Every command answers --help (or -h) anywhere among its arguments, before it reads any of them.
  if (std::find_if(args.begin(), args.end(), [](const std::string& x) { return x == "--help" || x == "-h"; }) != args.end() &&
      print_command_usage(cmd)) {
    return 0;
  }
  try {
    if (cmd == "--version") {
      std::printf("cloudviewer %s\n", CV_VERSION);
      return 0;
    }
    if (cmd == "gpu-info") return check_gpu(true) > 0 ? 0 : 1;
    if (cmd == "info") return cmd_info(args);
    if (cmd == "import") return cmd_import(args);
    if (cmd == "phase") return cmd_phase(args);
    if (cmd == "render") return cv::cli::cmd_render(args);
    if (cmd == "record") return cv::cli::cmd_record(args);
    if (cmd == "bench") return cv::cli::cmd_bench(args);
    if (cmd == "time-error") return cv::cli::cmd_time_error(args);
    if (cmd == "probe") return cv::cli::cmd_probe(args);
    if (cmd == "section") return cv::cli::cmd_section(args);
    if (cmd == "series") return cv::cli::cmd_series(args);
    if (cmd == "compare") return cv::cli::cmd_compare(args);
    if (cmd == "view") return cv::viewer::cmd_view(args);
    throw UsageError{"cloudviewer: unknown command '" + cmd + "', expected info, import, gpu-info, phase, render, record, bench, time-error, probe, section, series, compare or view"};
  } catch (const UsageError& e) {
    std::fprintf(stderr, "%s\n", e.message.c_str());
    return kExitBadInput;
  } catch (const cv::core::SceneError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return kExitBadInput;
  } catch (const cv::core::TimeError& e) {  // a time outside the file, a time axis that does not ascend
    std::fprintf(stderr, "%s\n", e.what());
    return kExitBadInput;
  } catch (const cv::core::VolumeFileError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return kExitBadInput;
  } catch (const cv::render::GroundImageError& e) {
    // A ground texture that is no usable image: bad input, one line naming the file.
    std::fprintf(stderr, "%s\n", e.what());
    return kExitBadInput;
  } catch (const cv::importers::ImportError& e) {
    // Bad input files: one line naming the file and variable, exit code 2.
    std::fprintf(stderr, "%s\n", e.what());
    return kExitBadInput;
  } catch (const cv::core::InputError& e) {
    // Every other reader's bad input (a FIFO given as a file, a size beyond the memory limit, an output path that cannot be).
    std::fprintf(stderr, "%s\n", e.what());
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cloudviewer %s: %s\n", cmd.c_str(), e.what());
    return 1;
  }
}
