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
#include "plot_canvas.hpp"
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
         "                           samples, temperature and wind where the volume has them (the march's trilinear\n"
         "                           sampler); its cover, base, top and optical depth; with --camera, where along the view\n"
         "                           ray from there to the point's ground the light came from (the first cloud, and where\n"
         "                           the transmittance fell to 0.5: the CPU march kernel's own record of that ray);\n"
         "                           --time: one of the file's valid times or a step (default the first); the volume holds\n"
         "                           no pressure, so none is given\n";
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
      if (have_camera) {
        put(f, ",first_cloud_m=" + (ray.first_cloud_m >= 0 ? num(ray.first_cloud_m, "%.1f") : "") + ",half_transmittance_m=" +
                   (ray.half_transmittance_m >= 0 ? num(ray.half_transmittance_m, "%.1f") : "") + ",ray_transmittance=" +
                   num(ray.transmittance, "%.6g"));
      }
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
  core::SectionField field;
  try {
    field = core::section_field(vol, field_name);
  } catch (const std::invalid_argument& e) {
    throw UsageError{"cloudviewer section: --field: " + std::string(e.what()) + " (" + c.file + ")"};
  }
  check_point(vol.grid, "section", "--from", lat1, lon1, c.file);
  check_point(vol.grid, "section", "--to", lat2, lon2, c.file);
  {
    const double len = geo::great_circle_distance_m(lat1, lon1, lat2, lon2, vol.grid.earth_radius_m);
    const double cell = core::smallest_cell_m(vol.grid);
    if (!(len >= cell)) {
      throw UsageError{"cloudviewer section: --from/--to: the path is " + num(len, "%.4g") + " m long, expected at least one grid cell (" +
                       num(cell, "%.4g") + " m) of " + c.file};
    }
  }
  const std::size_t step = resolve_step(vol, c);
  const core::TimeStepData& data = vol.step(step);
  const core::GridMeanExtinction medium = core::grid_mean_extinction(vol.grid, data);
  const core::VolumeGrid& g = vol.grid;
  // The plot: altitude from the lowest of the grid and the ground (or 0) to the grid's top.
  const Area area{70, 34, width - 110, height - 44};
  const double z_top = g.alt_m.last(), z_bot = std::min(0.0, g.alt_m.start);
  std::vector<double> rows(static_cast<std::size_t>(area.h()));
  for (int y = 0; y < area.h(); ++y) rows[static_cast<std::size_t>(y)] = z_top - (y + 0.5) / area.h() * (z_top - z_bot);
  std::reverse(rows.begin(), rows.end());  // ascending: row k is pixel y = h - 1 - k
  const core::Section px = core::vertical_section(vol, data, medium, field, lat1, lon1, lat2, lon2, area.w(), rows);
  const core::Section grid_rows = core::vertical_section(vol, data, medium, field, lat1, lon1, lat2, lon2, columns,
                                                         [&] {
                                                           std::vector<double> z;
                                                           for (int k = 0; k < g.alt_m.count; ++k) z.push_back(g.alt_m.at(k));
                                                           return z;
                                                         }());
  if (!have_range) {
    lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (double v : px.value)
      if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
    if (!std::isfinite(lo)) lo = 0.0, hi = 1.0;
    if (!(hi > lo)) hi = lo + (lo == 0.0 ? 1.0 : std::abs(lo) * 1e-3);
  }
  Canvas cv(width, height, kPaper);
  const std::size_t nr = rows.size();
  for (int x = 0; x < area.w(); ++x) {
    const double ground = px.ground_m[static_cast<std::size_t>(x)];
    for (std::size_t k = 0; k < nr; ++k) {
      const int y = area.y1 - static_cast<int>(k);
      const double v = px.value[static_cast<std::size_t>(x) * nr + k];
      Rgb col = std::isfinite(v) ? sequential_colour((v - lo) / (hi - lo)) : kNoData;
      if (rows[k] < (std::isfinite(ground) ? ground : 0.0)) col = kGround;
      // The cloud's boundary: a cloudy point with a clear neighbour.
      const auto cloudy = [&](int xx, std::size_t kk) { return px.cloudy[static_cast<std::size_t>(xx) * nr + kk] != 0; };
      if (cloudy(x, k) && ((x > 0 && !cloudy(x - 1, k)) || (x + 1 < area.w() && !cloudy(x + 1, k)) || (k > 0 && !cloudy(x, k - 1)) ||
                           (k + 1 < nr && !cloudy(x, k + 1)))) {
        col = kInk;
      }
      cv.set(area.x0 + x, y, col);
    }
  }
  cv.box(area.x0 - 1, area.y0 - 1, area.x1 + 1, area.y1 + 1, kInk);
  // Axes: altitude in km at the left, distance in km below.
  for (int i = 0; i <= 4; ++i) {
    const double z = z_bot + i / 4.0 * (z_top - z_bot);
    const double y = area.y1 - (z - z_bot) / (z_top - z_bot) * (area.h() - 1);
    cv.line(area.x0 - 5, y, area.x0 - 1, y, kInk);
    cv.text(area.x0 - 8, y + 4, 9, tick_text(z / 1000.0), kInk, Canvas::Align::Right);
    const double d = i / 4.0 * px.length_m;
    const double x = area.x0 + i / 4.0 * (area.w() - 1);
    cv.line(x, area.y1 + 1, x, area.y1 + 5, kInk);
    cv.text(x, area.y1 + 18, 9, tick_text(d / 1000.0), kInk, Canvas::Align::Centre);
  }
  cv.text(area.x0 - 60, area.y0 - 8, 9, "alt km", kInk);
  cv.text(0.5 * (area.x0 + area.x1), height - 6, 9, "distance km", kInk, Canvas::Align::Centre);
  char title[200];
  std::snprintf(title, sizeof title, "%s %.4g %.4g to %.4g %.4g  %s", field.name().c_str(), lat1, lon1, lat2, lon2,
                vol.times[step].iso_utc.c_str());
  cv.text(area.x0, 16, 10, title, kInk);
  colour_bar(cv, width - 95, area.y0 + 14, width - 80, area.y1, lo, hi, field.units(), sequential_colour);
  core::OutputGroup group;
  group.write(out, [&](std::FILE* f) { render::encode_png(f, width, height, cv.rgb()); });
  if (!csv.empty()) {
    group.write(csv, [&](std::FILE* f) {
      put(f, "# section of " + c.file + " from " + num(lat1) + "," + num(lon1) + " to " + num(lat2) + "," + num(lon2) + ", " +
                 field.name() + " [" + field.units() + "], valid " + vol.times[step].iso_utc + "\n");
      put(f, "distance_m,lat_deg,lon_deg,alt_m,ground_m," + field.name() + ",cloudy\n");
      const std::size_t n = grid_rows.rows();
      for (std::size_t i = 0; i < grid_rows.path.size(); ++i) {
        const auto& p = grid_rows.path[i];
        for (std::size_t k = 0; k < n; ++k) {
          put(f, num(p.distance_m, "%.1f") + "," + num(p.lat_deg, "%.6f") + "," + num(p.lon_deg, "%.6f") + "," + num(grid_rows.alt_m[k], "%.1f") +
                     "," + num(grid_rows.ground_m[i], "%.1f") + "," + num(grid_rows.value[i * n + k]) + "," +
                     (grid_rows.cloudy[i * n + k] ? "1" : "0") + "\n");
        }
      }
    });
  }
  group.commit();
  std::printf("section of %s (%s) from %.6g,%.6g to %.6g,%.6g: %.4g km, step %zu (%s), colour %.4g..%.4g %s\nwrote %s%s%s\n",
              c.file.c_str(), field.name().c_str(), lat1, lon1, lat2, lon2, px.length_m / 1000.0, step, vol.times[step].iso_utc.c_str(), lo,
              hi, field.units().c_str(), out.c_str(), csv.empty() ? "" : " and ", csv.c_str());
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
  check_point(vol.grid, "series", "--at", lat, lon, c.file);
  std::vector<core::ColumnProbe> col;
  for (std::size_t t = 0; t < vol.times.size(); ++t) {
    const core::TimeStepData& d = vol.step(t);
    col.push_back(core::probe_column(vol, d, core::grid_mean_extinction(vol.grid, d), lat, lon));
  }
  const bool timed = core::times_known(vol.times);
  auto hours = [&](std::size_t t) {
    return timed ? (vol.times[t].unix_s - vol.times[0].unix_s) / 3600.0 : static_cast<double>(t);
  };
  // Three panels: cover (0..1), optical depth, base and top (km).
  Canvas cv(width, height, kPaper);
  const int left = 70, right = width - 20, top = 30, gap = 30, bottom = height - 40;
  const int ph = (bottom - top - 2 * gap) / 3;
  const double t_end = std::max(hours(vol.times.size() - 1), 1e-9);
  auto xat = [&](double h) { return left + h / t_end * (right - left); };
  double tau_max = 0.0, z_max = 0.0;
  for (const auto& p : col) {
    tau_max = std::max(tau_max, p.optical_depth);
    if (std::isfinite(p.top_m)) z_max = std::max(z_max, p.top_m);
  }
  if (!(tau_max > 0)) tau_max = 1.0;
  if (!(z_max > 0)) z_max = vol.grid.alt_m.last();
  struct Panel {
    const char* name;
    double hi;
  };
  const Panel panels[3] = {{"cover", 1.0}, {"optical depth", tau_max * 1.05}, {"base and top km", z_max * 1.05 / 1000.0}};
  for (int pi = 0; pi < 3; ++pi) {
    const int y0 = top + pi * (ph + gap), y1 = y0 + ph;
    cv.box(left, y0, right, y1, kInk);
    cv.text(left, y0 - 6, 9, panels[pi].name, kInk);
    for (int i = 0; i <= 2; ++i) {
      const double v = i / 2.0 * panels[pi].hi;
      const double y = y1 - i / 2.0 * ph;
      cv.line(left - 4, y, left, y, kInk);
      cv.text(left - 7, y + 4, 9, tick_text(v), kInk, Canvas::Align::Right);
    }
    auto yat = [&](double v) { return y1 - v / panels[pi].hi * ph; };
    auto series = [&](auto value, Rgb colour) {
      for (std::size_t t = 0; t < col.size(); ++t) {
        const double v = value(col[t]);
        if (!std::isfinite(v)) continue;
        const double x = xat(hours(t)), y = yat(v);
        cv.box(static_cast<int>(x) - 2, static_cast<int>(y) - 2, static_cast<int>(x) + 2, static_cast<int>(y) + 2, colour);
        if (t + 1 < col.size() && std::isfinite(value(col[t + 1]))) cv.line(x, y, xat(hours(t + 1)), yat(value(col[t + 1])), colour);
      }
    };
    const Rgb blue{30, 80, 190}, red{190, 40, 30};
    if (pi == 0) series([](const core::ColumnProbe& p) { return p.cover; }, blue);
    if (pi == 1) series([](const core::ColumnProbe& p) { return p.optical_depth; }, blue);
    if (pi == 2) {
      series([](const core::ColumnProbe& p) { return p.base_m / 1000.0; }, blue);
      series([](const core::ColumnProbe& p) { return p.top_m / 1000.0; }, red);
    }
  }
  for (int i = 0; i <= 4; ++i) {
    const double h = i / 4.0 * t_end;
    cv.line(xat(h), bottom - 4, xat(h), bottom, kInk);
    cv.text(xat(h), bottom + 14, 9, tick_text(h), kInk, Canvas::Align::Centre);
  }
  cv.text(0.5 * (left + right), height - 6, 9, std::string(timed ? "hours after " : "step from ") + vol.times[0].iso_utc, kInk,
          Canvas::Align::Centre);
  char title[160];
  std::snprintf(title, sizeof title, "lat %.4g lon %.4g", lat, lon);
  cv.text(right, 14, 10, title, kInk, Canvas::Align::Right);
  core::OutputGroup group;
  group.write(out, [&](std::FILE* f) { render::encode_png(f, width, height, cv.rgb()); });
  std::string table = "valid_utc,hours,cover,optical_depth,base_m,top_m\n";
  for (std::size_t t = 0; t < col.size(); ++t) {
    table += vol.times[t].iso_utc + "," + num(hours(t), "%.4f") + "," + num(col[t].cover, "%.6g") + "," + num(col[t].optical_depth, "%.6g") + "," +
             num(col[t].base_m, "%.1f") + "," + num(col[t].top_m, "%.1f") + "\n";
  }
  if (!csv.empty()) group.write(csv, [&](std::FILE* f) { put(f, table); });
  group.commit();
  std::printf("series of %s at lat %.6g, lon %.6g: %zu steps\n%swrote %s%s%s\n", c.file.c_str(), lat, lon, col.size(), table.c_str(),
              out.c_str(), csv.empty() ? "" : " and ", csv.c_str());
  return 0;
}

}  // namespace cv::cli
