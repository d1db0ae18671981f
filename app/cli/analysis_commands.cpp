// `cloudviewer probe`, `section` and `series`: the column at a point, a vertical section and a
// time series, read through the march's sampler (core/analysis), printed and written as CSV and PNG.
#include "analysis_commands.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <limits>
#include <stdexcept>

#include "analysis/column_probe.hpp"
#include "analysis/section.hpp"
#include "cli_common.hpp"
#include "importer.hpp"
#include "io/output_file.hpp"
#include "kernel/prepared_volume.hpp"
#include "plots/analysis_plots.hpp"
#include "render/image_output.hpp"
#include "scene/framing.hpp"
#include "scene/instant.hpp"
#include "volume/volume_io.hpp"

#include "analysis_common.hpp"

namespace cv::cli {

using namespace analysis;

const char* probe_usage() {
  return "  probe FILE --at LAT,LON [--time ISO|N] [--csv OUT.csv] [--camera LAT,LON,ALT_M [--view-step M]]\n"
         "                           the column at a point, per grid level: altitude, height above the ground, cloud\n"
         "                           fraction, in-cloud liquid and ice extinction, the grid-mean extinction the march\n"
         "                           samples, temperature, wind and pressure where the volume has them (the march's trilinear\n"
         "                           sampler); its cover, base, top and optical depth; the weather textures at the nearest grid\n"
         "                           column (the modelled cloud's type and covers, docs/physics.md); with --camera, where along the view\n"
         "                           ray from there to the point's ground the light came from (the first cloud, and where\n"
         "                           the transmittance fell to 0.5: the CPU march kernel's own record of that ray);\n"
         "                           --time: one of the file's valid times or a step (default the first); pressure is\n"
         "                           given where the file has it (pressure or hybrid levels, WRF's P + PB)\n";
}

int cmd_probe(const std::vector<std::string>& args) {
  Common c{"probe", "", ""};
  std::string csv;
  bool have_at = false, have_camera = false;
  double lat = 0, lon = 0, view_step = 100.0;
  std::vector<double> camera;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (!a.empty() && a[0] == '-') {
      if (i + 1 >= args.size()) throw UsageError{"cloudviewer probe: " + a + ": expected a value after it"};
      const std::string& v = args[++i];
      if (a == "--at") {
        std::tie(lat, lon) = parse_lat_lon("probe", a, v);
        have_at = true;
      } else if (a == "--time") {
        c.time = v;
      } else if (a == "--csv") {
        csv = v;
      } else if (a == "--camera") {
        camera = parse_list(a, v, ',', 3, 3, "LAT,LON,ALT_M");
        if (!(camera[0] >= -90 && camera[0] <= 90 && camera[2] >= -1000.0 && camera[2] <= 1e9)) {
          throw UsageError{"cloudviewer probe: --camera: found '" + v + "', expected LAT within -90..90 and ALT_M within -1000..1e9"};
        }
        have_camera = true;
      } else if (a == "--view-step") {
        view_step = parse_number(a, v);
        if (!(view_step >= 1.0 && view_step <= 1e6)) throw UsageError{"cloudviewer probe: --view-step: found '" + v + "', expected metres 1..1e6"};
      } else {
        throw UsageError{"cloudviewer probe: unknown option '" + a + "'"};
      }
    } else if (c.file.empty()) {
      c.file = a;
    } else {
      throw UsageError{"cloudviewer probe: unexpected argument '" + a + "', expected one FILE"};
    }
  }
  if (c.file.empty() || !have_at) throw UsageError{"cloudviewer probe: expected FILE and --at LAT,LON"};
  check_outputs("probe", "", csv, c.file);
  core::CloudVolume vol = load(c.file);
  check_point(vol.grid, "probe", "--at", lat, lon, c.file);
  const std::size_t step = resolve_step(vol, c);
  const core::TimeStepData& data = vol.step(step);
  const core::PreparedVolume prepared = core::prepare_volume(vol.grid, data);
  const core::ColumnProbe p = core::probe_column(vol, data, prepared.extinction, lat, lon);
  core::ViewRayProbe ray;
  if (have_camera) {
    const double ground = std::isfinite(p.ground_m) ? p.ground_m : 0.0;
    try {
      ray = core::probe_view_ray(prepared, camera[0], camera[1], camera[2], lat, lon, ground, view_step);
    } catch (const std::invalid_argument& e) {
      throw UsageError{std::string("cloudviewer probe: --camera: ") + e.what()};
    }
  }
  std::printf("probe %s at lat %.6g, lon %.6g, step %zu (%s); ground %s\n", c.file.c_str(), lat, lon, step, vol.times[step].iso_utc.c_str(),
              std::isfinite(p.ground_m) ? (num(p.ground_m, "%.1f") + " m").c_str() : "unknown (heights above sea level)");
  const std::string table = core::probe_levels_csv(p, vol);
  std::printf("%s", table.c_str());
  std::string summary = "cover " + num(p.cover, "%.4f") + ", base " + (std::isfinite(p.base_m) ? num(p.base_m, "%.1f") + " m" : "none") +
                        ", top " + (std::isfinite(p.top_m) ? num(p.top_m, "%.1f") + " m" : "none") + ", optical depth " +
                        num(p.optical_depth, "%.6g");
  std::printf("column: %s\n", summary.c_str());
  const std::string weather = core::weather_at_text(vol.grid, prepared.weather, lat, lon);
  if (!weather.empty()) std::printf("%s\n", weather.c_str());
  if (have_camera) {
    std::printf("view ray from %.6g,%.6g,%.6g m to the point's ground (%.6g km): first cloud %s, transmittance 0.5 at %s, "
                "transmittance %.4g (view step %.4g m)\n",
                camera[0], camera[1], camera[2], ray.distance_to_target_m / 1000.0,
                ray.first_cloud_m >= 0 ? (num(ray.first_cloud_m / 1000.0, "%.4f") + " km").c_str() : "none",
                ray.half_transmittance_m >= 0 ? (num(ray.half_transmittance_m / 1000.0, "%.4f") + " km").c_str() : "never",
                ray.transmittance, ray.view_step_m);
  }
  if (!csv.empty()) {
    core::write_file_atomically(csv, [&](std::FILE* f) {
      put(f, "# probe of " + c.file + " at lat " + num(lat) + " lon " + num(lon) + ", valid " + vol.times[step].iso_utc + "\n");
      put(f, core::probe_summary_csv(p));
      if (have_camera) put(f, core::view_ray_csv(ray));
      put(f, "\n" + table);
    });
    std::printf("wrote %s\n", csv.c_str());
  }
  return 0;
}

const char* section_usage() {
  return "  section FILE --from LAT,LON --to LAT,LON --field NAME -o OUT.png [--csv OUT.csv] [--time ISO|N]\n"
         "          [--size WxH] [--columns N] [--range LO,HI]\n"
         "                           a vertical section: the field (a 3-D field the volume holds, or extinction: the\n"
         "                           grid-mean extinction the march samples) against distance along the great circle and\n"
         "                           altitude, the ground filled brown, the cloud's boundary drawn black, no data grey, with a\n"
         "                           colour bar (--range: its ends, default the section's own); --csv: the values at the\n"
         "                           grid's levels in N columns (default 64)\n";
}

int cmd_section(const std::vector<std::string>& args) {
  Common c{"section", "", ""};
  std::string out, csv, field_name;
  bool have_from = false, have_to = false, have_range = false;
  double lat1 = 0, lon1 = 0, lat2 = 0, lon2 = 0, lo = 0, hi = 0;
  int width = 800, height = 400, columns = 64;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (!a.empty() && a[0] == '-') {
      if (i + 1 >= args.size()) throw UsageError{"cloudviewer section: " + a + ": expected a value after it"};
      const std::string& v = args[++i];
      if (a == "--from") {
        std::tie(lat1, lon1) = parse_lat_lon("section", a, v);
        have_from = true;
      } else if (a == "--to") {
        std::tie(lat2, lon2) = parse_lat_lon("section", a, v);
        have_to = true;
      } else if (a == "--field") {
        field_name = v;
      } else if (a == "-o") {
        out = v;
      } else if (a == "--csv") {
        csv = v;
      } else if (a == "--time") {
        c.time = v;
      } else if (a == "--size") {
        const auto s = parse_size(v, 200, 4096);
        if (!s) throw UsageError{"cloudviewer section: --size: found '" + v + "', expected WxH with each 200..4096"};
        width = s->first, height = s->second;
      } else if (a == "--columns") {
        const double n = parse_number(a, v);
        if (!(n >= 2 && n <= 100000 && n == std::floor(n))) throw UsageError{"cloudviewer section: --columns: found '" + v + "', expected an integer 2..100000"};
        columns = static_cast<int>(n);
      } else if (a == "--range") {
        const auto r = parse_list(a, v, ',', 2, 2, "LO,HI");
        if (!(r[0] < r[1])) throw UsageError{"cloudviewer section: --range: found '" + v + "', expected LO,HI with LO < HI"};
        lo = r[0], hi = r[1], have_range = true;
      } else {
        throw UsageError{"cloudviewer section: unknown option '" + a + "'"};
      }
    } else if (c.file.empty()) {
      c.file = a;
    } else {
      throw UsageError{"cloudviewer section: unexpected argument '" + a + "', expected one FILE"};
    }
  }
  if (c.file.empty() || !have_from || !have_to || field_name.empty() || out.empty()) {
    throw UsageError{"cloudviewer section: expected FILE, --from LAT,LON, --to LAT,LON, --field NAME and -o OUT.png"};
  }
  check_outputs("section", out, csv, c.file);
  core::CloudVolume vol = load(c.file);
  plots::SectionInputs in;
  in.field = field_name;
  in.lat1 = lat1, in.lon1 = lon1, in.lat2 = lat2, in.lon2 = lon2;
  in.width = width, in.height = height, in.columns = columns;
  in.have_range = have_range, in.lo = lo, in.hi = hi;
  if (const std::string problem = plots::section_problem(vol, c.file, in); !problem.empty()) {
    throw UsageError{"cloudviewer section: " + problem};
  }
  const std::size_t step = resolve_step(vol, c);
  const plots::SectionFigure fig = plots::section_figure(vol, c.file, step, in);
  core::OutputGroup group;
  group.write(out, [&](std::FILE* f) { render::encode_png(f, width, height, fig.canvas.rgb()); });
  if (!csv.empty()) group.write(csv, [&](std::FILE* f) { put(f, fig.csv); });
  group.commit();
  std::printf("section of %s (%s) from %.6g,%.6g to %.6g,%.6g: %.4g km, step %zu (%s), colour %.4g..%.4g %s\nwrote %s%s%s\n",
              c.file.c_str(), fig.field.name().c_str(), lat1, lon1, lat2, lon2, fig.pixels.length_m / 1000.0, step, vol.times[step].iso_utc.c_str(),
              fig.lo, fig.hi, fig.field.units().c_str(), out.c_str(), csv.empty() ? "" : " and ", csv.c_str());
  return 0;
}

const char* series_usage() {
  return "  series FILE --at LAT,LON -o OUT.png [--csv OUT.csv] [--size WxH]\n"
         "                           a time series at a point: the column's cover, optical depth, cloud base and top\n"
         "                           (as probe gives them) at each of the file's valid times, plotted and as CSV\n";
}

int cmd_series(const std::vector<std::string>& args) {
  Common c{"series", "", ""};
  std::string out, csv;
  bool have_at = false;
  double lat = 0, lon = 0;
  int width = 800, height = 480;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (!a.empty() && a[0] == '-') {
      if (i + 1 >= args.size()) throw UsageError{"cloudviewer series: " + a + ": expected a value after it"};
      const std::string& v = args[++i];
      if (a == "--at") {
        std::tie(lat, lon) = parse_lat_lon("series", a, v);
        have_at = true;
      } else if (a == "-o") {
        out = v;
      } else if (a == "--csv") {
        csv = v;
      } else if (a == "--size") {
        const auto s = parse_size(v, 200, 4096);
        if (!s) throw UsageError{"cloudviewer series: --size: found '" + v + "', expected WxH with each 200..4096"};
        width = s->first, height = s->second;
      } else {
        throw UsageError{"cloudviewer series: unknown option '" + a + "'"};
      }
    } else if (c.file.empty()) {
      c.file = a;
    } else {
      throw UsageError{"cloudviewer series: unexpected argument '" + a + "', expected one FILE"};
    }
  }
  if (c.file.empty() || !have_at || out.empty()) throw UsageError{"cloudviewer series: expected FILE, --at LAT,LON and -o OUT.png"};
  check_outputs("series", out, csv, c.file);
  core::CloudVolume vol = load(c.file);
  if (const std::string problem = plots::series_problem(vol, c.file, lat, lon); !problem.empty()) {
    throw UsageError{"cloudviewer series: " + problem};
  }
  const plots::SeriesFigure fig = plots::series_figure(vol, lat, lon, width, height);
  const std::string& table = fig.csv;
  core::OutputGroup group;
  group.write(out, [&](std::FILE* f) { render::encode_png(f, width, height, fig.canvas.rgb()); });
  if (!csv.empty()) group.write(csv, [&](std::FILE* f) { put(f, table); });
  group.commit();
  std::printf("series of %s at lat %.6g, lon %.6g: %zu steps\n%swrote %s%s%s\n", c.file.c_str(), lat, lon, fig.columns.size(), table.c_str(),
              out.c_str(), csv.empty() ? "" : " and ", csv.c_str());
  return 0;
}

}  // namespace cv::cli
