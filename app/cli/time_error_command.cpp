// `cloudviewer time-error FILE`: holds back the middle steps of a file with regular output, rebuilds
// them from their neighbours at gaps of 2, 3 and 6 hours by each interpolation, and prints the
// errors against the held-back truth and each measure's ranking.
#include "time_error_command.hpp"

#include <algorithm>
#include <cstdio>
#include <stdexcept>

#include "bench/time_error.hpp"
#include "cli_common.hpp"
#include "importer.hpp"

namespace cv::cli {

const char* time_error_usage() {
  return "  time-error FILE [--gaps H,H,...] [--levels MIN_HPA:MAX_HPA] [--stride N]\n"
         "                           hold back the steps between steps k and k+gap of a NetCDF file with evenly\n"
         "                           spaced output, rebuild them by nearest, linear and advected interpolation, and\n"
         "                           print the RMSE of extinction, column optical depth and cover, and the fraction\n"
         "                           skill score at 1, 3 and 5 cells, per gap (hours; default 2,3,6)\n";
}

int cmd_time_error(const std::vector<std::string>& args) {
  std::string file;
  importers::ImportOptions opt;
  bench::TimeErrorOptions topt;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (!a.empty() && a[0] == '-') {
      if (i + 1 >= args.size()) throw UsageError{"cloudviewer time-error: " + a + ": expected a value after it"};
      const std::string& v = args[++i];
      if (a == "--gaps") {
        const auto g = parse_list(a, v, ',', 1, 16, "gaps in hours, e.g. 2,3,6");
        for (double h : g)
          if (!(h > 0.0)) throw UsageError{"cloudviewer time-error: --gaps: found '" + v + "', expected gaps in hours > 0"};
        topt.gaps_h = g;
      } else if (a == "--levels") {
        const auto l = parse_list(a, v, ':', 2, 2, "MIN_HPA:MAX_HPA");
        if (!(l[0] >= 0 && l[0] <= l[1])) throw UsageError{"cloudviewer time-error: --levels: found '" + v + "', expected 0 <= MIN <= MAX hPa"};
        opt.level_min_hpa = l[0], opt.level_max_hpa = l[1];
      } else if (a == "--stride") {
        const double s = parse_number(a, v);
        if (!(s >= 1 && s <= 1e6) || s != static_cast<int>(s)) throw UsageError{"cloudviewer time-error: --stride: found '" + v + "', expected an integer >= 1"};
        opt.horizontal_stride = static_cast<int>(s);
      } else {
        throw UsageError{"cloudviewer time-error: unknown option '" + a + "'"};
      }
    } else if (file.empty()) {
      file = a;
    } else {
      throw UsageError{"cloudviewer time-error: unexpected argument '" + a + "', expected one FILE"};
    }
  }
  if (file.empty()) throw UsageError{"cloudviewer time-error: expected FILE (NetCDF with evenly spaced output)"};
  opt.cache_steps = 1;  // measure_time_error takes what it needs from each step in turn
  core::CloudVolume vol = importers::import_file(file, opt);
  std::printf("%s: %d x %d x %d nodes, %zu steps %s .. %s, winds: %s%s\n", file.c_str(), vol.grid.lon_deg.count, vol.grid.lat_deg.count,
              vol.grid.alt_m.count, vol.times.size(), vol.times.empty() ? "" : vol.times.front().iso_utc.c_str(),
              vol.times.empty() ? "" : vol.times.back().iso_utc.c_str(),
              vol.has_field[static_cast<int>(core::Field::WindU)] && vol.has_field[static_cast<int>(core::Field::WindV)] ? "horizontal" : "none",
              vol.has_field[static_cast<int>(core::Field::WindW)] ? " and vertical" : "");
  std::vector<bench::TimeErrorRow> rows;
  try {
    rows = bench::measure_time_error(vol, file, topt);
  } catch (const std::invalid_argument& e) {
    throw UsageError{std::string("cloudviewer time-error: ") + e.what()};
  }
  if (rows.empty()) throw UsageError{"cloudviewer time-error: " + file + ": no gap of --gaps is a whole number of at least 2 of its steps within the file"};
  std::printf("%s", bench::time_error_table(rows).c_str());
  // Per gap and measure, the methods from best to worst (lower RMSE, higher FSS is better).
  for (double gap : topt.gaps_h) {
    std::vector<const bench::TimeErrorRow*> at;
    for (const auto& r : rows)
      if (r.gap_h == gap) at.push_back(&r);
    if (at.empty()) continue;
    const auto rank = [&](const char* what, auto key) {
      std::vector<const bench::TimeErrorRow*> s = at;
      std::stable_sort(s.begin(), s.end(), [&](auto* x, auto* y) { return key(*x) < key(*y); });
      std::printf("ranking at %g h by %s:", gap, what);
      for (std::size_t i = 0; i < s.size(); ++i) std::printf("%s %s", i ? " <" : "", core::time_interpolation_name(s[i]->method));
      std::printf("\n");
    };
    rank("extinction RMSE", [](const bench::TimeErrorRow& r) { return r.rmse_extinction_per_km; });
    rank("column tau RMSE", [](const bench::TimeErrorRow& r) { return r.rmse_column_tau; });
    rank("cover RMSE", [](const bench::TimeErrorRow& r) { return r.rmse_cover; });
    rank("1 - FSS at 3 cells", [](const bench::TimeErrorRow& r) { return 1.0 - r.fss[1]; });
  }
  return 0;
}

}  // namespace cv::cli
