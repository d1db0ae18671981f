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

std::string describe_file(const std::string& path) {
  NcFile f(path);
  std::string out = "file: " + path + "\n";
  auto line = [&](const std::string& s) { out += s + "\n"; };
  if (is_wrf_file(f)) return out + describe_wrf(f);
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
  const bool cloud = L.roles[static_cast<int>(Role::CloudFraction)] || L.roles[static_cast<int>(Role::Liquid)] ||
                     L.roles[static_cast<int>(Role::Ice)];
  line(cloud ? "importable: yes" : "importable: no (no cloud fraction, liquid or ice water)");
  return out;
}

}  // namespace cv::importers
