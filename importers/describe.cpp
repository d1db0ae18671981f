// `cloudviewer info`: what the importer understands of a file, before importing anything.
#include <cstdio>

#include "cf_layout.hpp"
#include "importer.hpp"
#include "wrf_import.hpp"

namespace cv::importers {
namespace {
std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}
}  // namespace

// "importable: ..." from the import itself (setup only: time steps load lazily), so `info` and
// `import` always agree.
std::string importable(const std::string& path, const ImportOptions& options, bool cloud_missing, bool can_diagnose) {
  try {
    const core::CloudVolume v = import_file(path, options);
    char buf[200];
    std::snprintf(buf, sizeof buf, "importable: yes (grid %d x %d x %d, %zu time step(s))", v.grid.lon_deg.count,
                  v.grid.lat_deg.count, v.grid.alt_m.count, v.times.size());
    std::string s = buf;
    if (options.diagnose_cloud && cloud_missing) s += ", with a DIAGNOSED cloud (--diagnose-cloud)";
    return s + "\n";
  } catch (const ImportError& e) {
    std::string s = std::string("importable: no: ") + e.what() + "\n";
    if (cloud_missing && can_diagnose && !options.diagnose_cloud) {
      ImportOptions d = options;
      d.diagnose_cloud = true;
      try {
        import_file(path, d);
        s += "importable with --diagnose-cloud: yes (a cloud diagnosed from relative humidity)\n";
      } catch (const ImportError& e2) {
        s += std::string("importable with --diagnose-cloud: no: ") + e2.what() + "\n";
      }
    }
    return s;
  }
}

std::string describe_file(const std::string& path, const ImportOptions& options) {
  NcFile f(path);
  std::string out = "file: " + path + "\n";
  auto line = [&](const std::string& s) { out += s + "\n"; };
  if (is_wrf_file(f)) return out + describe_wrf(f) + importable(path, options, false, false);
  if (is_wrf_geogrid_file(f)) {
    return out + "format: WRF GEOGRID static file (" + f.global_text("TITLE") + ")\n" + "importable: no: " +
           wrf_geogrid_message(f) + "\n";
  }
  const CfLayout L = detect_cf_layout(f);
  line("format: CF-style gridded file (Conventions '" + f.global_text("Conventions") + "')");
  auto axis = [&](const char* what, const Axis& a) {
    if (!a.var) return;
    char buf[160];
    std::snprintf(buf, sizeof buf, "%s: '%s', %zu values from %.6g to %.6g", what, a.var->name.c_str(), a.values.size(),
                  a.values.empty() ? 0.0 : a.values.front(), a.values.empty() ? 0.0 : a.values.back());
    line(std::string(buf) + ", recognised " + a.how);
  };
  axis("longitude", L.lon);
  axis("latitude", L.lat);
  axis("vertical", L.vertical);
  if (L.vertical_kind == Vertical::Pressure) {
    line("  (pressure levels, " + L.vertical.var->text("units") + " -> Pa x " + fmt(L.pressure_scale_to_pa) + ")");
  } else if (L.vertical_kind == Vertical::Height) {
    line(std::string("  (height levels ") + (L.height_above_ground ? "above the ground" : "above sea level") + ", " +
         L.vertical.var->text("units") + ")");
  } else {
    line("  (hybrid sigma-pressure levels, formula_terms '" + L.vertical.var->text("formula_terms") + "')");
  }
  axis("time", L.time);
  if (!L.times.empty()) {
    line("times: " + std::to_string(L.times.size()) + ", " + L.times.front().iso_utc + " to " + L.times.back().iso_utc +
         (L.times_uneven ? " (unevenly spaced)" : ""));
  }
  line("variables used:");
  for (int r = 0; r < kRoleCount; ++r) {
    const NcVar* v = L.roles[r];
    std::string dims;
    if (v) {
      for (std::size_t d = 0; d < v->dims.size(); ++d) dims += (d ? ", " : "") + f.dim_name(*v, d);
    }
    line(std::string("  ") + role_name(static_cast<Role>(r)) + ": " +
         (v ? "'" + v->name + "' [" + v->text("units") + "] (" + dims + ")" +
                  (v->att("scale_factor") ? ", packed" : "")
            : std::string("absent")));
  }
  for (const auto& n : L.notes) line("note: " + n);
  for (const auto& p : L.precipitation) line("note: '" + p + "' is precipitation, not part of the cloud volume");
  const bool can_diagnose = L.roles[static_cast<int>(Role::Temperature)] &&
                            (L.roles[static_cast<int>(Role::RelativeHumidity)] || L.roles[static_cast<int>(Role::Humidity)]);
  return out + importable(path, options, !has_cloud(L), can_diagnose);
}

}  // namespace cv::importers
