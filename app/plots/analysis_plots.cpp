// The section and series figures shared by the commands and the viewer (analysis_plots.hpp).
#include "plots/analysis_plots.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <utility>

#include "geo/geodesy.hpp"
#include "scene/instant.hpp"
#include "volume/grid_mean.hpp"

namespace cv::plots {

std::string num(double v, const char* fmt) {
  if (!std::isfinite(v)) return "";
  char buf[48];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

std::string point_problem(const core::VolumeGrid& g, const std::string& option, double lat, double lon, const std::string& file) {
  if (core::grid_holds(g, lat, lon)) return "";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g,%.6g", lat, lon);
  return option + ": found " + buf + ", outside the data of " + file + ", expected a point within " + core::grid_extent_text(g);
}

std::string section_problem(const core::CloudVolume& vol, const std::string& file, const SectionInputs& in) {
  try {
    core::section_field(vol, in.field);
  } catch (const std::invalid_argument& e) {
    return "--field: " + std::string(e.what()) + " (" + file + ")";
  }
  if (std::string m = point_problem(vol.grid, "--from", in.lat1, in.lon1, file); !m.empty()) return m;
  if (std::string m = point_problem(vol.grid, "--to", in.lat2, in.lon2, file); !m.empty()) return m;
  const double len = geo::great_circle_distance_m(in.lat1, in.lon1, in.lat2, in.lon2, vol.grid.earth_radius_m);
  const double cell = core::smallest_cell_m(vol.grid);
  if (!(len >= cell)) {
    return "--from/--to: the path is " + num(len, "%.4g") + " m long, expected at least one grid cell (" + num(cell, "%.4g") + " m) of " + file;
  }
  return "";
}

SectionFigure section_figure(core::CloudVolume& vol, const std::string& file, std::size_t step, const SectionInputs& in) {
  SectionFigure fig;
  fig.field = core::section_field(vol, in.field);
  const double lat1 = in.lat1, lon1 = in.lon1, lat2 = in.lat2, lon2 = in.lon2;
  const int width = in.width, height = in.height;
  const core::TimeStepData& data = vol.step(step);
  const core::GridMeanExtinction medium = core::grid_mean_extinction(vol.grid, data);
  const core::VolumeGrid& g = vol.grid;
  // The plot: altitude from the lowest of the grid and the ground (or 0) to the grid's top.
  const Area area{70, 34, width - 110, height - 44};
  const double z_top = g.alt_m.last(), z_bot = std::min(0.0, g.alt_m.start);
  std::vector<double> rows(static_cast<std::size_t>(area.h()));
  for (int y = 0; y < area.h(); ++y) rows[static_cast<std::size_t>(y)] = z_top - (y + 0.5) / area.h() * (z_top - z_bot);
  std::reverse(rows.begin(), rows.end());  // ascending: row k is pixel y = h - 1 - k
  fig.pixels = core::vertical_section(vol, data, medium, fig.field, lat1, lon1, lat2, lon2, area.w(), rows);
  std::vector<double> levels;
  for (int k = 0; k < g.alt_m.count; ++k) levels.push_back(g.alt_m.at(k));
  fig.grid_rows = core::vertical_section(vol, data, medium, fig.field, lat1, lon1, lat2, lon2, in.columns, levels);
  const core::Section& px = fig.pixels;
  double lo = in.lo, hi = in.hi;
  if (!in.have_range) {
    lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (double v : px.value)
      if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
    if (!std::isfinite(lo)) lo = 0.0, hi = 1.0;
    if (!(hi > lo)) hi = lo + (lo == 0.0 ? 1.0 : std::abs(lo) * 1e-3);
  }
  fig.lo = lo, fig.hi = hi;
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
  std::snprintf(title, sizeof title, "%s %.4g %.4g to %.4g %.4g  %s", fig.field.name().c_str(), lat1, lon1, lat2, lon2,
                vol.times[step].iso_utc.c_str());
  cv.text(area.x0, 16, 10, title, kInk);
  colour_bar(cv, width - 95, area.y0 + 14, width - 80, area.y1, lo, hi, fig.field.units(), sequential_colour);
  fig.canvas = std::move(cv);

  const core::Section& gr = fig.grid_rows;
  std::string& t = fig.csv;
  t = "# section of " + file + " from " + num(lat1) + "," + num(lon1) + " to " + num(lat2) + "," + num(lon2) + ", " + fig.field.name() + " [" +
      fig.field.units() + "], valid " + vol.times[step].iso_utc + "\n";
  t += "distance_m,lat_deg,lon_deg,alt_m,ground_m," + fig.field.name() + ",cloudy\n";
  const std::size_t n = gr.rows();
  for (std::size_t i = 0; i < gr.path.size(); ++i) {
    const auto& p = gr.path[i];
    for (std::size_t k = 0; k < n; ++k) {
      t += num(p.distance_m, "%.1f") + "," + num(p.lat_deg, "%.6f") + "," + num(p.lon_deg, "%.6f") + "," + num(gr.alt_m[k], "%.1f") + "," +
           num(gr.ground_m[i], "%.1f") + "," + num(gr.value[i * n + k]) + "," + (gr.cloudy[i * n + k] ? "1" : "0") + "\n";
    }
  }
  return fig;
}

std::string series_problem(const core::CloudVolume& vol, const std::string& file, double lat, double lon) {
  return point_problem(vol.grid, "--at", lat, lon, file);
}

double series_x(const SeriesFigure& f, double h) { return f.left + h / f.t_end * (f.right - f.left); }

SeriesFigure series_figure(core::CloudVolume& vol, double lat, double lon, int width, int height) {
  SeriesFigure fig;
  std::vector<core::ColumnProbe>& col = fig.columns;
  for (std::size_t t = 0; t < vol.times.size(); ++t) {
    const core::TimeStepData& d = vol.step(t);
    col.push_back(core::probe_column(vol, d, core::grid_mean_extinction(vol.grid, d), lat, lon));
    fig.valid.push_back(vol.times[t].iso_utc);
  }
  fig.timed = core::times_known(vol.times);
  for (std::size_t t = 0; t < vol.times.size(); ++t) {
    fig.hours.push_back(fig.timed ? (vol.times[t].unix_s - vol.times[0].unix_s) / 3600.0 : static_cast<double>(t));
  }
  auto hours = [&](std::size_t t) { return fig.hours[t]; };
  // Three panels: cover (0..1), optical depth, base and top (km).
  Canvas cv(width, height, kPaper);
  const int left = 70, right = width - 20, top = 30, gap = 30, bottom = height - 40;
  const int ph = (bottom - top - 2 * gap) / 3;
  const double t_end = std::max(hours(vol.times.size() - 1), 1e-9);
  fig.left = left, fig.right = right, fig.top = top, fig.bottom = bottom, fig.t_end = t_end;
  auto xat = [&](double h) { return series_x(fig, h); };
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
  cv.text(0.5 * (left + right), height - 6, 9, std::string(fig.timed ? "hours after " : "step from ") + vol.times[0].iso_utc, kInk,
          Canvas::Align::Centre);
  char title[160];
  std::snprintf(title, sizeof title, "lat %.4g lon %.4g", lat, lon);
  cv.text(right, 14, 10, title, kInk, Canvas::Align::Right);
  fig.canvas = std::move(cv);
  std::string& table = fig.csv;
  table = "valid_utc,hours,cover,optical_depth,base_m,top_m\n";
  for (std::size_t t = 0; t < col.size(); ++t) {
    table += vol.times[t].iso_utc + "," + num(hours(t), "%.4f") + "," + num(col[t].cover, "%.6g") + "," + num(col[t].optical_depth, "%.6g") + "," +
             num(col[t].base_m, "%.1f") + "," + num(col[t].top_m, "%.1f") + "\n";
  }
  return fig;
}

}  // namespace cv::plots
