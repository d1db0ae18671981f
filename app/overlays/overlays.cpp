// The overlays' geometry, built by VTK filters.
#include "overlays/overlays.hpp"

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>

#include <glm/glm.hpp>

#include <vtkArrowSource.h>
#include <vtkCellArray.h>
#include <vtkCleanPolyData.h>
#include <vtkFloatArray.h>
#include <vtkFlyingEdges3D.h>
#include <vtkFlyingEdgesPlaneCutter.h>
#include <vtkPlane.h>
#include <vtkProbeFilter.h>
#include <vtkCharArray.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkRungeKutta45.h>
#include <vtkStreamTracer.h>
#include <vtkTriangleFilter.h>
#include <vtkSmartPointer.h>

#include "geo/geodesy.hpp"

namespace cv::overlays {
namespace {

std::atomic<std::uint64_t> g_vtk_runs{0};

glm::vec4 rgba(const glm::dvec3& c, double alpha = 1.0) {
  return {static_cast<float>(c.x), static_cast<float>(c.y), static_cast<float>(c.z), static_cast<float>(alpha)};
}

// Appends the polyline a -> b on the sphere (a, b unit vectors) at radius r as segments no longer
// than max_m, along the great circle.
void add_arc(core::OverlayMesh& m, const glm::dvec3& a, const glm::dvec3& b, double r, double max_m, const glm::vec4& color,
             bool first_shared) {
  const double angle = std::acos(std::clamp(glm::dot(a, b), -1.0, 1.0));
  const int n = std::max(1, static_cast<int>(std::ceil(angle * r / max_m)));
  const double s = std::sin(angle);
  // Vertices lifted so that each chord's middle is on the sphere, never under it (where the
  // sphere would hide it): r / cos(half a piece's angle), 8 cm for 2 km pieces.
  r /= std::cos(0.5 * angle / n);
  auto base = static_cast<std::uint32_t>(m.positions.size());
  if (!first_shared) {
    m.positions.push_back(r * a);
    m.colors.push_back(color);
  } else {
    base -= 1;  // the previous arc's end is this one's start
  }
  for (int k = 1; k <= n; ++k) {
    const double f = static_cast<double>(k) / n;
    const glm::dvec3 p = s > 1e-12 ? (std::sin((1.0 - f) * angle) * a + std::sin(f * angle) * b) / s : glm::normalize((1.0 - f) * a + f * b);
    m.positions.push_back(r * p);
    m.colors.push_back(color);
    m.lines.push_back(base + static_cast<std::uint32_t>(k - 1));
    m.lines.push_back(base + static_cast<std::uint32_t>(k));
  }
}

glm::dvec3 unit(double lat_deg, double lon_deg) { return geo::sphere_to_ecef({lat_deg, lon_deg, 0.0}, 1.0); }

// The polylines of a vtkPolyData whose points hold (lon, lat, 0) in degrees, on the sphere.
void polylines_to_sphere(vtkPolyData* pd, double r0_m, double max_m, const glm::vec4& color, core::OverlayMesh& out) {
  vtkCellArray* lines = pd->GetLines();
  vtkPoints* pts = pd->GetPoints();
  if (!lines || !pts) return;
  vtkIdType npts = 0;
  const vtkIdType* ids = nullptr;
  for (lines->InitTraversal(); lines->GetNextCell(npts, ids);) {
    for (vtkIdType k = 0; k + 1 < npts; ++k) {
      double p0[3], p1[3];
      pts->GetPoint(ids[k], p0);
      pts->GetPoint(ids[k + 1], p1);
      add_arc(out, unit(p0[1], p0[0]), unit(p1[1], p1[0]), r0_m, max_m, color, k > 0);
    }
  }
}

std::string hold_list(const core::CloudVolume& v) {
  std::string list;
  for (int f = 0; f < core::kFieldCount; ++f) {
    if (v.has_field[static_cast<std::size_t>(f)]) list += (list.empty() ? "" : ", ") + std::string(core::field_name(static_cast<core::Field>(f)));
  }
  return list.empty() ? "(none)" : list;
}

}  // namespace

std::uint64_t vtk_pipeline_runs() { return g_vtk_runs.load(); }

core::Field volume_field(const core::CloudVolume& volume, const std::string& name, const std::string& where) {
  for (int f = 0; f < core::kFieldCount; ++f) {
    if (name == core::field_name(static_cast<core::Field>(f)) && volume.has_field[static_cast<std::size_t>(f)]) {
      return static_cast<core::Field>(f);
    }
  }
  throw OverlayError(where + ": found \"" + name + "\", expected a 3-D field the volume holds: " + hold_list(volume));
}

void check_overlays(const std::vector<core::OverlaySpec>& specs, const core::CloudVolume& volume) {
  for (std::size_t i = 0; i < specs.size(); ++i) {
    const std::string at = "overlays[" + std::to_string(i) + "]";
    if (specs[i].type == "isosurface") {
      volume_field(volume, specs[i].text("field"), at + ".field");
      if (specs[i].text("color_field") != "none") volume_field(volume, specs[i].text("color_field"), at + ".color_field");
    }
    if (specs[i].type == "section") {
      const core::OverlaySpec& o = specs[i];
      volume_field(volume, o.text("field"), at + ".field");
      const std::string& kind = o.text("kind");
      if (kind != "horizontal" && kind != "isobaric" && kind != "vertical") {
        throw OverlayError(at + ".kind: found \"" + kind + "\", expected horizontal, isobaric or vertical");
      }
      if (kind == "isobaric" && !volume.has_field[static_cast<std::size_t>(core::Field::Pressure)]) {
        throw OverlayError(at + ".kind: found \"isobaric\" for a volume without pressure (its file is on height levels, or gives none), "
                           "expected a volume that holds pressure (it holds " + hold_list(volume) + ")");
      }
      const core::RegularAxis& z = volume.grid.alt_m;
      if (kind == "horizontal" && !(o.number("altitude_m") >= z.start && o.number("altitude_m") <= z.last())) {
        char buf[160];
        std::snprintf(buf, sizeof buf, ".altitude_m: found %g, expected an altitude within the grid's levels, %g..%g m", o.number("altitude_m"),
                      z.start, z.last());
        throw OverlayError(at + buf);
      }
      if (kind == "vertical" && glm::dot(unit(o.number("from_lat"), o.number("from_lon")), unit(o.number("to_lat"), o.number("to_lon"))) > 1.0 - 1e-15) {
        throw OverlayError(at + ".to_lat: found the path's two ends at one point, expected a vertical section's path of non-zero length");
      }
    }
    if (specs[i].type == "wind" || specs[i].type == "arrows") {
      if (!volume.has_field[static_cast<std::size_t>(core::Field::WindU)] || !volume.has_field[static_cast<std::size_t>(core::Field::WindV)]) {
        throw OverlayError(at + ": found a volume without wind_u and wind_v, expected both for wind " +
                           (specs[i].type == "wind" ? "streamlines" : "arrows") + " (it holds " + hold_list(volume) + ")");
      }
      if (specs[i].type == "arrows" && specs[i].number("pressure_hpa") > 0.0 && !volume.has_field[static_cast<std::size_t>(core::Field::Pressure)]) {
        char buf[160];
        std::snprintf(buf, sizeof buf, ".pressure_hpa: found %g for a volume without pressure (its file is on height levels, or gives none), ",
                      specs[i].number("pressure_hpa"));
        throw OverlayError(at + buf + "expected 0 (the level at altitude_m) or a volume that holds pressure (it holds " + hold_list(volume) + ")");
      }
      if (specs[i].type == "arrows" && !(specs[i].number("speed_min_m_s") < specs[i].number("speed_max_m_s"))) {
        char buf[160];
        std::snprintf(buf, sizeof buf, ".speed_max_m_s: found %g, expected more than speed_min_m_s (%g)", specs[i].number("speed_max_m_s"),
                      specs[i].number("speed_min_m_s"));
        throw OverlayError(at + buf);
      }
      const double a = specs[i].number("altitude_m");
      const core::RegularAxis& z = volume.grid.alt_m;
      const bool by_pressure = specs[i].type == "arrows" && specs[i].number("pressure_hpa") > 0.0;
      if (!by_pressure && !(a >= z.start && a <= z.last())) {
        char buf[160];
        std::snprintf(buf, sizeof buf, ".altitude_m: found %g, expected an altitude within the grid's levels, %g..%g m", a, z.start, z.last());
        throw OverlayError(at + buf);
      }
    }
    if (specs[i].type == "borders" || specs[i].type == "rivers") {
      const std::string& c = specs[i].text("class");
      const bool borders = specs[i].type == "borders";
      if (borders ? (c != "national" && c != "states" && c != "marine" && c != "all") : (c != "major" && c != "permanent" && c != "all")) {
        throw OverlayError(at + ".class: found \"" + c + "\", expected " + (borders ? "national, states, marine or all" : "major, permanent or all"));
      }
    }
    if (specs[i].type == "coastlines" || specs[i].type == "borders" || specs[i].type == "rivers") {
      const std::string& r = specs[i].text("resolution");
      if (r != "auto" && (r.size() != 1 || std::string("clihf").find(r[0]) == std::string::npos)) {
        throw OverlayError(at + ".resolution: found \"" + r + "\", expected auto, c, l, i, h or f");
      }
    }
  }
}

char coastline_resolution(const std::string& setting, double alt_m) {
  if (setting.size() == 1) return setting[0];
  if (alt_m > 2.0e6) return 'c';
  if (alt_m > 3.0e5) return 'l';
  if (alt_m > 3.0e4) return 'i';
  if (alt_m > 3.0e3) return 'h';
  return 'f';
}

core::OverlayMesh build_coastlines(const std::string& dir, char res, double r0_m, const glm::vec4& color, double max_segment_m,
                                   const GeoBox& box) {
  return build_gshhg(GshhgFeature::Shore, res, "", box, r0_m, color, dir, max_segment_m);
}

core::OverlayMesh build_gshhg(GshhgFeature feature, char res, const std::string& select, const GeoBox& box, double r0_m,
                              const glm::vec4& color, const std::string& dir, double max_segment_m) {
  const std::vector<std::vector<glm::dvec2>> lines = read_gshhg_lines(feature, res, select, box, dir);
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();  // degrees in float would move a vertex by up to half a metre
  vtkNew<vtkCellArray> cells;
  // GSHHG's lines are straight in longitude and latitude (the border along 49 N is the parallel):
  // each piece is divided every 0.05 degrees there, so the great-circle chords that follow stay
  // within a metre of it (a 4 degree piece along 49 N drawn as one great circle bulges 4 km north).
  constexpr double kStepDeg = 0.05;
  for (const auto& line : lines) {
    std::vector<glm::dvec2> dense{line.front()};
    for (std::size_t k = 1; k < line.size(); ++k) {
      const glm::dvec2 a = line[k - 1], b = line[k];
      const int n = std::max(1, static_cast<int>(std::ceil(std::max(std::abs(b.x - a.x), std::abs(b.y - a.y)) / kStepDeg)));
      for (int j = 1; j <= n; ++j) dense.push_back(a + (b - a) * (static_cast<double>(j) / n));
    }
    cells->InsertNextCell(static_cast<vtkIdType>(dense.size()));
    for (const glm::dvec2& p : dense) cells->InsertCellPoint(points->InsertNextPoint(p.x, p.y, 0.0));
  }
  core::OverlayMesh out;
  if (lines.empty()) return out;  // nothing of the feature in the box
  vtkNew<vtkPolyData> pd;
  pd->SetPoints(points);
  pd->SetLines(cells);
  // GMT cuts the lines at its bins' edges: the repeated points there are merged.
  vtkNew<vtkCleanPolyData> clean;
  clean->SetInputData(pd);
  clean->PointMergingOn();
  clean->SetTolerance(0.0);
  clean->Update();
  ++g_vtk_runs;
  polylines_to_sphere(clean->GetOutput(), r0_m, max_segment_m, color, out);
  return out;
}

GeoBox overlay_box(const core::VolumeGrid& grid, char res, const core::Camera& cam) {
  GeoBox box;
  if (res != 'h' && res != 'f') return box;
  // Around the camera, on a lattice so a moving camera rebuilds only when it crosses a cell.
  const double half = res == 'h' ? 15.0 : 4.0, step = res == 'h' ? 5.0 : 1.0;
  const double clat = std::clamp(std::round(cam.lat_deg / step) * step, -90.0, 90.0), clon = std::round(cam.lon_deg / step) * step;
  const double lon_half = std::min(180.0, half / std::max(std::cos(clat * 3.14159265358979323846 / 180.0), 0.1));
  box.global = false;
  box.lat_min = std::max(-90.0, clat - half), box.lat_max = std::min(90.0, clat + half);
  box.lon_min = clon - lon_half, box.lon_max = clon + lon_half;
  // A regional volume: no further than its own extent and a margin of 2 degrees.
  if (grid.lon_deg.step * grid.lon_deg.count < 359.0) {
    const double lon0 = std::min(grid.lon_deg.start, grid.lon_deg.last()) - 2.0, lon1 = std::max(grid.lon_deg.start, grid.lon_deg.last()) + 2.0;
    const double lat0 = std::min(grid.lat_deg.start, grid.lat_deg.last()) - 2.0, lat1 = std::max(grid.lat_deg.start, grid.lat_deg.last()) + 2.0;
    const double shift = std::round(((lon0 + lon1) / 2.0 - clon) / 360.0) * 360.0;  // the grid's longitudes near the camera's
    const GeoBox cut{false, std::max(box.lon_min, lon0 - shift), std::min(box.lon_max, lon1 - shift), std::max(box.lat_min, lat0),
                     std::min(box.lat_max, lat1)};
    if (cut.lon_min < cut.lon_max && cut.lat_min < cut.lat_max) return cut;
    return GeoBox{false, lon0, lon1, std::max(-90.0, lat0), std::min(90.0, lat1)};
  }
  if (lon_half >= 180.0) box.global = true;
  return box;
}

core::OverlayMesh build_graticule(double step_deg, double r0_m, const glm::vec4& color) {
  // Meridians from pole to pole (stopping at 89.9: they meet there) and parallels, as polylines
  // in (lon, lat) through VTK, then onto the sphere.
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();  // degrees in float would move a vertex by up to half a metre
  vtkNew<vtkCellArray> cells;
  const double fine = std::min(1.0, step_deg);  // polyline vertices every degree at most
  const int nm = static_cast<int>(std::floor(360.0 / step_deg + 1e-9));
  for (int i = 0; i < nm; ++i) {
    const double lon = -180.0 + i * step_deg;
    const int n = static_cast<int>(std::ceil(2 * 89.9 / fine));
    cells->InsertNextCell(n + 1);
    for (int k = 0; k <= n; ++k) cells->InsertCellPoint(points->InsertNextPoint(lon, -89.9 + k * (2 * 89.9 / n), 0.0));
  }
  for (double lat = -90.0 + step_deg; lat < 90.0 - 1e-9; lat += step_deg) {
    const int n = static_cast<int>(std::ceil(360.0 / fine));
    cells->InsertNextCell(n + 1);
    for (int k = 0; k <= n; ++k) cells->InsertCellPoint(points->InsertNextPoint(-180.0 + k * (360.0 / n), lat, 0.0));
  }
  vtkNew<vtkPolyData> pd;
  pd->SetPoints(points);
  pd->SetLines(cells);
  vtkNew<vtkCleanPolyData> clean;
  clean->SetInputData(pd);
  clean->Update();
  ++g_vtk_runs;
  core::OverlayMesh out;
  polylines_to_sphere(clean->GetOutput(), r0_m, 10000.0, color, out);  // 10 km pieces: 2 m of lift
  return out;
}

std::vector<std::array<double, 4>> label_strokes(const std::string& text) {
  // Seven segments for the digits (a top, b upper right, c lower right, d bottom, e lower left,
  // f upper left, g middle); polylines of their own for the letters (either case draws the
  // capital) and a few signs. A glyph is 4 wide and 6 high.
  static const double seg[7][4] = {{0, 6, 4, 6}, {4, 6, 4, 3}, {4, 3, 4, 0}, {0, 0, 4, 0}, {0, 0, 0, 3}, {0, 3, 0, 6}, {0, 3, 4, 3}};
  static const char* digits[10] = {"abcdef", "bc", "abged", "abgcd", "fgbc", "afgcd", "afgedc", "abc", "abcdefg", "abcdfg"};
  // Each glyph: polylines separated by '|', points "x,y" separated by ' '.
  static const char* letters[26] = {
      "0,0 2,6 4,0|1,3 3,3",                               // A
      "0,0 0,6 3,6 4,5 3,3 0,3|3,3 4,1.5 3,0 0,0",        // B
      "4,6 0,6 0,0 4,0",                                   // C
      "0,0 0,6 2.5,6 4,4 4,2 2.5,0 0,0",                   // D
      "4,6 0,6 0,0 4,0|0,3 3,3",                           // E
      "4,6 0,6 0,0|0,3 3,3",                               // F
      "4,6 0,6 0,0 4,0 4,3 2,3",                           // G
      "0,0 0,6|4,0 4,6|0,3 4,3",                           // H
      "2,0 2,6|1,6 3,6|1,0 3,0",                           // I
      "4,6 4,0 0,0 0,2",                                   // J
      "0,0 0,6|4,6 0,3 4,0",                               // K
      "0,6 0,0 4,0",                                       // L
      "0,0 0,6 2,3 4,6 4,0",                               // M
      "0,0 0,6 4,0 4,6",                                   // N
      "0,0 0,6 4,6 4,0 0,0",                               // O
      "0,0 0,6 4,6 4,3 0,3",                               // P
      "0,0 0,6 4,6 4,0 0,0|2,2 4,0",                       // Q
      "0,0 0,6 4,6 4,3 0,3|1.5,3 4,0",                     // R
      "4,6 0,6 0,3 4,3 4,0 0,0",                           // S
      "0,6 4,6|2,6 2,0",                                   // T
      "0,6 0,0 4,0 4,6",                                   // U
      "0,6 2,0 4,6",                                       // V
      "0,6 1,0 2,4 3,0 4,6",                               // W
      "0,0 4,6|0,6 4,0",                                   // X
      "0,6 2,3 4,6|2,3 2,0",                               // Y
      "0,6 4,6 0,0 4,0",                                   // Z
  };
  std::vector<std::array<double, 4>> out;
  double x = 0.0;
  auto add = [&](double x0, double y0, double x1, double y1) { out.push_back({x + x0, y0, x + x1, y1}); };
  auto polylines = [&](const char* spec) {
    double px = 0.0, py = 0.0;
    bool have = false;
    for (const char* p = spec; *p;) {
      if (*p == '|') {
        have = false;
        ++p;
        continue;
      }
      if (*p == ' ') {
        ++p;
        continue;
      }
      char* end = nullptr;
      const double qx = std::strtod(p, &end);
      const double qy = std::strtod(end + 1, &end);
      p = end;
      if (have) add(px, py, qx, qy);
      px = qx, py = qy, have = true;
    }
  };
  for (char ch : text) {
    if (ch >= '0' && ch <= '9') {
      for (const char* p = digits[ch - '0']; *p; ++p) {
        const double* q = seg[*p - 'a'];
        add(q[0], q[1], q[2], q[3]);
      }
    } else if ((ch >= 'A' && ch <= 'Z') || (ch >= 'a' && ch <= 'z')) {
      polylines(letters[(ch >= 'a' ? ch - 'a' : ch - 'A')]);
    } else if (ch == '-') {
      add(0, 3, 4, 3);
    } else if (ch == '+') {
      add(0, 3, 4, 3), add(2, 1, 2, 5);
    } else if (ch == '.') {
      polylines("1.5,0 2.5,0 2.5,1 1.5,1 1.5,0");
    } else if (ch == '/') {
      add(0, 0, 4, 6);
    } else if (ch == '_') {
      add(0, 0, 4, 0);
    } else if (ch != ' ') {
      continue;
    }
    x += 6.0;
  }
  return out;
}

namespace {

std::string degrees_text(double v, char pos, char neg) {
  const double a = std::abs(v);
  char buf[32];
  if (std::abs(a - std::round(a)) < 1e-9) std::snprintf(buf, sizeof buf, "%.0f", a);
  else std::snprintf(buf, sizeof buf, "%.1f", a);
  std::string t = buf;
  if (a > 1e-9 && a < 180.0 - 1e-9) t += (v > 0 ? pos : neg);
  return t;
}

}  // namespace

core::OverlayMesh graticule_labels(double step_deg, const core::Camera& cam, double r0_m, const glm::vec4& color, double label_px) {
  core::OverlayMesh out;
  if (!(label_px > 0.0)) return out;
  const glm::dvec3 c = core::camera_ecef(cam, r0_m);
  const core::CameraFrame f = core::camera_frame(cam);
  // Where the view's centre meets the ground (else the point under the camera).
  geo::Geodetic centre{cam.lat_deg, cam.lon_deg, 0.0};
  {
    const double b = glm::dot(f.forward, c), cq = glm::dot(c, c) - r0_m * r0_m, disc = b * b - cq;
    if (disc >= 0.0 && b < 0.0) centre = geo::ecef_to_sphere(c + (cq / (-b + std::sqrt(disc))) * f.forward, r0_m);
  }
  const double lat_line = std::clamp(std::round(centre.lat_deg / step_deg) * step_deg, -90.0 + step_deg, 90.0 - step_deg);
  const double lon_line = std::round(centre.lon_deg / step_deg) * step_deg;
  std::vector<std::pair<geo::Geodetic, std::string>> labels;
  for (double lon = -180.0; lon < 180.0 - 1e-9; lon += step_deg) {
    labels.push_back({{lat_line, lon, 0.0}, degrees_text(geo::wrap_lon_deg(lon), 'E', 'W')});
  }
  for (double lat = -90.0 + step_deg; lat < 90.0 - 1e-9; lat += step_deg) {
    if (std::abs(lat - lat_line) < 1e-9) continue;  // that crossing holds the meridian's label
    labels.push_back({{lat, lon_line, 0.0}, degrees_text(lat, 'N', 'S')});
  }
  std::vector<std::array<double, 4>> placed;  // pixel boxes of the labels kept: no label over another
  for (const auto& [where, text] : labels) {
    const glm::dvec3 p = geo::sphere_to_ecef(where, r0_m);
    const core::Projected q = core::project_point(cam, p - c);
    if (!q.in_front || q.x < 0 || q.y < 0 || q.x >= cam.width || q.y >= cam.height || core::hidden_by_sphere(c, p - c, r0_m)) continue;
    const double w_px = (6.0 * static_cast<double>(text.size()) - 2.0) * label_px / 6.0;
    const std::array<double, 4> box = {q.x + 3.0 - 2.0, q.y - 3.0 - label_px - 2.0, q.x + 3.0 + w_px + 2.0, q.y - 3.0 + 2.0};
    bool overlaps = false;
    for (const auto& o : placed) overlaps = overlaps || (box[0] < o[2] && o[0] < box[2] && box[1] < o[3] && o[1] < box[3]);
    if (overlaps) continue;
    placed.push_back(box);
    // One glyph unit in metres at the crossing's depth along the view axis, in the camera's plane
    // there; the label starts 3 px right of and above the crossing.
    const double depth = glm::dot(p - c, f.forward);
    const double px_m = depth * 2.0 * f.tan_half / cam.width;
    const double unit = px_m * label_px / 6.0;
    const glm::dvec3 origin = p + 3.0 * px_m * (f.right + f.up);
    for (const auto& s : label_strokes(text)) {
      const auto base = static_cast<std::uint32_t>(out.positions.size());
      out.positions.push_back(origin + unit * (s[0] * f.right + s[1] * f.up));
      out.positions.push_back(origin + unit * (s[2] * f.right + s[3] * f.up));
      out.colors.insert(out.colors.end(), 2, color);
      out.lines.push_back(base);
      out.lines.push_back(base + 1);
    }
  }
  return out;
}

glm::vec4 colormap(double t, double brightness) {
  static const double stops[5][3] = {{0.05, 0.05, 0.45}, {0.0, 0.6, 0.85}, {0.2, 0.8, 0.2}, {0.95, 0.85, 0.1}, {0.85, 0.1, 0.05}};
  const double x = std::clamp(std::isfinite(t) ? t : 0.0, 0.0, 1.0) * 4.0;
  const int k = std::min(3, static_cast<int>(x));
  const double f = x - k;
  glm::vec4 c(1.0f);
  for (int i = 0; i < 3; ++i) c[i] = static_cast<float>(brightness * ((1.0 - f) * stops[k][i] + f * stops[k + 1][i]));
  return c;
}

namespace {

// A field at fractional grid indices, trilinear (as the march's fetch between grid points).
double trilinear(const core::VolumeGrid& g, const std::vector<float>& f, double x, double y, double z) {
  const int nx = g.lon_deg.count, ny = g.lat_deg.count, nz = g.alt_m.count;
  x = std::clamp(x, 0.0, nx - 1.0), y = std::clamp(y, 0.0, ny - 1.0), z = std::clamp(z, 0.0, nz - 1.0);
  const int i = std::min(static_cast<int>(x), nx - 2 < 0 ? 0 : nx - 2), j = std::min(static_cast<int>(y), ny - 2 < 0 ? 0 : ny - 2),
            k = std::min(static_cast<int>(z), nz - 2 < 0 ? 0 : nz - 2);
  const double fx = x - i, fy = y - j, fz = z - k;
  double sum = 0.0;
  for (int c = 0; c < 8; ++c) {
    const int di = c & 1, dj = (c >> 1) & 1, dk = (c >> 2) & 1;
    const int ii = std::min(i + di, nx - 1), jj = std::min(j + dj, ny - 1), kk = std::min(k + dk, nz - 1);
    const double wgt = (di ? fx : 1.0 - fx) * (dj ? fy : 1.0 - fy) * (dk ? fz : 1.0 - fz);
    if (wgt == 0.0) continue;
    sum += wgt * f[g.index(ii, jj, kk)];
  }
  return sum;
}

glm::dvec3 index_to_ecef(const core::VolumeGrid& g, double x, double y, double z) {
  return geo::sphere_to_ecef({g.lat_deg.start + y * g.lat_deg.step, g.lon_deg.start + x * g.lon_deg.step, g.alt_m.start + z * g.alt_m.step},
                             g.earth_radius_m);
}

}  // namespace

core::OverlayMesh build_isosurface(const core::VolumeGrid& grid, const std::vector<float>& field, double value, const glm::vec4& color,
                                   const FieldColor& by) {
  core::OverlayMesh out;
  if (field.size() != grid.points() || grid.points() == 0) return out;
  vtkNew<vtkImageData> image;
  image->SetDimensions(grid.lon_deg.count, grid.lat_deg.count, grid.alt_m.count);
  image->SetOrigin(0.0, 0.0, 0.0);
  image->SetSpacing(1.0, 1.0, 1.0);  // grid indices: mapped to the sphere below
  vtkNew<vtkFloatArray> scalars;
  scalars->SetNumberOfValues(static_cast<vtkIdType>(field.size()));
  // No data (NaN) as far below the value: the surface closes against it instead of vanishing.
  const float below = static_cast<float>(value) - 1e30f;
  for (std::size_t i = 0; i < field.size(); ++i) scalars->SetValue(static_cast<vtkIdType>(i), std::isnan(field[i]) ? below : field[i]);
  scalars->SetName("field");
  image->GetPointData()->SetScalars(scalars);  // longitude fastest, then latitude, then altitude: VTK's x, y, z
  vtkNew<vtkFlyingEdges3D> contour;
  contour->SetInputData(image);
  contour->SetValue(0, value);
  contour->ComputeNormalsOff();
  contour->ComputeGradientsOff();
  contour->ComputeScalarsOff();
  contour->Update();
  ++g_vtk_runs;
  vtkPolyData* pd = contour->GetOutput();
  vtkPoints* pts = pd->GetPoints();
  if (!pts) return out;
  out.positions.reserve(static_cast<std::size_t>(pts->GetNumberOfPoints()));
  for (vtkIdType i = 0; i < pts->GetNumberOfPoints(); ++i) {
    double p[3];
    pts->GetPoint(i, p);
    const double lon = grid.lon_deg.start + p[0] * grid.lon_deg.step;
    const double lat = grid.lat_deg.start + p[1] * grid.lat_deg.step;
    const double alt = grid.alt_m.start + p[2] * grid.alt_m.step;
    out.positions.push_back(geo::sphere_to_ecef({lat, lon, alt}, grid.earth_radius_m));
    if (by.field && by.field->size() == grid.points()) {
      const double fv = trilinear(grid, *by.field, p[0], p[1], p[2]);
      out.colors.push_back(colormap((fv - by.lo) / (by.hi - by.lo != 0.0 ? by.hi - by.lo : 1.0), by.brightness));
    } else {
      out.colors.push_back(color);
    }
  }
  vtkCellArray* polys = pd->GetPolys();
  vtkIdType npts = 0;
  const vtkIdType* ids = nullptr;
  for (polys->InitTraversal(); polys->GetNextCell(npts, ids);) {
    for (vtkIdType k = 1; k + 1 < npts; ++k) {  // a fan, should a polygon have more than three corners
      out.triangles.push_back(static_cast<std::uint32_t>(ids[0]));
      out.triangles.push_back(static_cast<std::uint32_t>(ids[k]));
      out.triangles.push_back(static_cast<std::uint32_t>(ids[k + 1]));
    }
  }
  return out;
}

namespace {

// The field as a VTK image in grid indices (longitude fastest: VTK's x, y, z).
vtkSmartPointer<vtkImageData> field_image(const core::VolumeGrid& g, const std::vector<float>& field) {
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(g.lon_deg.count, g.lat_deg.count, g.alt_m.count);
  image->SetOrigin(0.0, 0.0, 0.0);
  image->SetSpacing(1.0, 1.0, 1.0);
  vtkNew<vtkFloatArray> scalars;
  scalars->SetNumberOfValues(static_cast<vtkIdType>(field.size()));
  for (std::size_t i = 0; i < field.size(); ++i) scalars->SetValue(static_cast<vtkIdType>(i), field[i]);
  scalars->SetName("field");
  image->GetPointData()->SetScalars(scalars);
  return image;
}

glm::vec4 mapped(const FieldColor& by, double v) {
  return colormap((v - by.lo) / (by.hi - by.lo != 0.0 ? by.hi - by.lo : 1.0), by.brightness);
}

}  // namespace

core::OverlayMesh build_horizontal_section(const core::VolumeGrid& g, const std::vector<float>& field, double altitude_m, const FieldColor& by) {
  core::OverlayMesh out;
  if (field.size() != g.points() || g.points() == 0) return out;
  const auto image = field_image(g, field);
  vtkNew<vtkPlane> plane;
  plane->SetOrigin(0.0, 0.0, (altitude_m - g.alt_m.start) / g.alt_m.step);
  plane->SetNormal(0.0, 0.0, 1.0);
  vtkNew<vtkFlyingEdgesPlaneCutter> cut;
  cut->SetInputData(image);
  cut->SetPlane(plane);
  cut->ComputeNormalsOff();
  cut->InterpolateAttributesOn();
  cut->Update();
  ++g_vtk_runs;
  vtkPolyData* pd = cut->GetOutput();
  vtkPoints* pts = pd->GetPoints();
  vtkDataArray* values = pd->GetPointData()->GetArray("field");
  if (!pts || !values) return out;
  for (vtkIdType i = 0; i < pts->GetNumberOfPoints(); ++i) {
    double p[3];
    pts->GetPoint(i, p);
    out.positions.push_back(index_to_ecef(g, p[0], p[1], p[2]));
    out.colors.push_back(mapped(by, values->GetTuple1(i)));
  }
  vtkIdType npts = 0;
  const vtkIdType* ids = nullptr;
  vtkCellArray* polys = pd->GetPolys();
  for (polys->InitTraversal(); polys->GetNextCell(npts, ids);) {
    for (vtkIdType k = 1; k + 1 < npts; ++k) {
      out.triangles.insert(out.triangles.end(), {static_cast<std::uint32_t>(ids[0]), static_cast<std::uint32_t>(ids[k]), static_cast<std::uint32_t>(ids[k + 1])});
    }
  }
  return out;
}

namespace {

// The lowest fractional level of column (i, j) where the pressure falls through exp(target_ln),
// ln p linear between the two nodes around it; negative where the column does not cross it.
double isobaric_level(const core::VolumeGrid& g, const std::vector<float>& pressure, int i, int j, double target_ln) {
  for (int k = 0; k + 1 < g.alt_m.count; ++k) {
    const double p0 = pressure[g.index(i, j, k)], p1 = pressure[g.index(i, j, k + 1)];
    if (!(p0 > 0.0) || !(p1 > 0.0)) continue;  // no data (NaN) or nonsense
    const double l0 = std::log(p0), l1 = std::log(p1);
    if (!((l0 >= target_ln && target_ln >= l1) || (l0 <= target_ln && target_ln <= l1)) || l0 == l1) continue;
    return k + (target_ln - l0) / (l1 - l0);
  }
  return -1.0;
}

}  // namespace

core::OverlayMesh build_isobaric_section(const core::VolumeGrid& g, const std::vector<float>& pressure, const std::vector<float>& field,
                                         double pressure_pa, const FieldColor& by) {
  core::OverlayMesh out;
  const std::size_t n = g.points();
  if (pressure.size() != n || field.size() != n || n == 0 || !(pressure_pa > 0.0)) return out;
  const int nx = g.lon_deg.count, ny = g.lat_deg.count;
  const double target = std::log(pressure_pa);
  std::vector<std::uint32_t> vertex(g.columns(), std::numeric_limits<std::uint32_t>::max());
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const double z = isobaric_level(g, pressure, i, j, target);
      if (z < 0.0) continue;
      vertex[g.column(i, j)] = static_cast<std::uint32_t>(out.positions.size());
      out.positions.push_back(index_to_ecef(g, i, j, z));
      out.colors.push_back(mapped(by, trilinear(g, field, i, j, z)));  // linear between the two nodes
    }
  }
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  for (int j = 0; j + 1 < ny; ++j) {
    for (int i = 0; i + 1 < nx; ++i) {
      const std::uint32_t a = vertex[g.column(i, j)], b = vertex[g.column(i + 1, j)], c = vertex[g.column(i + 1, j + 1)],
                          d = vertex[g.column(i, j + 1)];
      if (a != kNone && b != kNone && c != kNone) out.triangles.insert(out.triangles.end(), {a, b, c});
      if (a != kNone && c != kNone && d != kNone) out.triangles.insert(out.triangles.end(), {a, c, d});
    }
  }
  return out;
}

core::OverlayMesh build_vertical_section(const core::VolumeGrid& g, const std::vector<float>& field, double from_lat, double from_lon,
                                         double to_lat, double to_lon, const FieldColor& by, int columns) {
  core::OverlayMesh out;
  if (field.size() != g.points() || g.points() == 0 || columns < 2) return out;
  const glm::dvec3 a = unit(from_lat, from_lon), b = unit(to_lat, to_lon);
  const double angle = std::acos(std::clamp(glm::dot(a, b), -1.0, 1.0));
  const double sn = std::sin(angle);
  const int levels = g.alt_m.count;
  // The curtain's points in grid indices: `columns` along the path, every level.
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  for (int c = 0; c < columns; ++c) {
    const double f = static_cast<double>(c) / (columns - 1);
    const glm::dvec3 p = sn > 1e-12 ? (std::sin((1.0 - f) * angle) * a + std::sin(f * angle) * b) / sn : a;
    const geo::Geodetic ll = geo::ecef_to_sphere(p, 1.0);
    double lon = ll.lon_deg;
    while (lon < g.lon_deg.start) lon += 360.0;  // the grid's own longitudes (it may run past 180)
    while (lon - 360.0 >= g.lon_deg.start) lon -= 360.0;
    for (int k = 0; k < levels; ++k) {
      points->InsertNextPoint((lon - g.lon_deg.start) / g.lon_deg.step, (ll.lat_deg - g.lat_deg.start) / g.lat_deg.step, k);
    }
  }
  vtkNew<vtkPolyData> curtain;
  curtain->SetPoints(points);
  vtkNew<vtkProbeFilter> probe;
  probe->SetInputData(curtain);
  probe->SetSourceData(field_image(g, field));
  probe->Update();
  ++g_vtk_runs;
  vtkDataSet* sampled = probe->GetOutput();
  vtkDataArray* values = sampled->GetPointData()->GetArray("field");
  vtkDataArray* valid = sampled->GetPointData()->GetArray(probe->GetValidPointMaskArrayName());
  if (!values) return out;
  for (vtkIdType i = 0; i < sampled->GetNumberOfPoints(); ++i) {
    double p[3];
    points->GetPoint(i, p);
    out.positions.push_back(index_to_ecef(g, p[0], p[1], p[2]));
    out.colors.push_back(mapped(by, values->GetTuple1(i)));
  }
  auto ok = [&](int c, int k) { return !valid || valid->GetTuple1(static_cast<vtkIdType>(c * levels + k)) != 0.0; };
  for (int c = 0; c + 1 < columns; ++c) {
    for (int k = 0; k + 1 < levels; ++k) {
      if (!ok(c, k) || !ok(c + 1, k) || !ok(c, k + 1) || !ok(c + 1, k + 1)) continue;
      const auto i00 = static_cast<std::uint32_t>(c * levels + k), i10 = static_cast<std::uint32_t>((c + 1) * levels + k);
      out.triangles.insert(out.triangles.end(), {i00, i10, i10 + 1, i00, i10 + 1, i00 + 1});
    }
  }
  return out;
}

core::OverlayMesh colour_bar(const core::Camera& cam, double r0_m, const std::string& title, double lo, double hi, double brightness,
                             double text_px) {
  core::OverlayMesh out;
  if (!(text_px > 0.0)) return out;
  const glm::dvec3 c = core::camera_ecef(cam, r0_m);
  const core::CameraFrame f = core::camera_frame(cam);
  const double w = cam.width, h = cam.height, aspect = h / w;
  // A pixel position (x right, y down) 1 m in front of the camera, on that pixel's ray's plane.
  auto at = [&](double x, double y) {
    const double xn = (2.0 * x / w - 1.0) * f.tan_half, yn = (1.0 - 2.0 * y / h) * f.tan_half * aspect;
    return c + 1.0 * (f.forward + xn * f.right + yn * f.up);
  };
  const glm::vec4 white(static_cast<float>(brightness));
  auto text = [&](const std::string& t, double x, double y_base, double px) {  // left end, baseline (pixels), height
    const double u = px / 6.0;
    for (const auto& s : label_strokes(t)) {
      const auto base = static_cast<std::uint32_t>(out.positions.size());
      out.positions.push_back(at(x + s[0] * u, y_base - s[1] * u));
      out.positions.push_back(at(x + s[2] * u, y_base - s[3] * u));
      out.colors.insert(out.colors.end(), 2, white);
      out.lines.insert(out.lines.end(), {base, base + 1});
    }
  };
  auto text_w = [&](const std::string& t) { return (6.0 * static_cast<double>(t.size()) - 2.0) * text_px / 6.0; };
  char buf[5][32];
  double widest = 0.0;
  for (int k = 0; k < 5; ++k) {
    std::snprintf(buf[k], sizeof buf[k], "%.3g", lo + (hi - lo) * k / 4.0);
    widest = std::max(widest, text_w(buf[k]));
  }
  const double bar_w = std::max(4.0, text_px), x1 = w - 6.0 - widest - 4.0, x0 = x1 - bar_w;
  const double y0 = h * 0.85, y1 = std::max(h * 0.30, 2.0 * text_px + 8.0);  // bottom (lo) and top (hi)
  const int steps = 16;
  for (int k = 0; k <= steps; ++k) {
    const double y = y0 + (y1 - y0) * k / steps;
    out.positions.push_back(at(x0, y));
    out.positions.push_back(at(x1, y));
    out.colors.insert(out.colors.end(), 2, colormap(static_cast<double>(k) / steps, brightness));
    if (k > 0) {
      const auto b = static_cast<std::uint32_t>(out.positions.size() - 4);
      out.triangles.insert(out.triangles.end(), {b, b + 1, b + 3, b, b + 3, b + 2});
    }
  }
  for (int k = 0; k < 5; ++k) {
    const double y = y0 + (y1 - y0) * k / 4.0;
    const auto b = static_cast<std::uint32_t>(out.positions.size());
    out.positions.push_back(at(x1, y));
    out.positions.push_back(at(x1 + 3.0, y));
    out.colors.insert(out.colors.end(), 2, white);
    out.lines.insert(out.lines.end(), {b, b + 1});
    text(buf[k], x1 + 5.0, y + 0.5 * text_px, text_px);
  }
  // The title above the bar, right-aligned; smaller where it would not fit the image's width.
  const double title_px = std::min(text_px, text_px * (w - 6.0) / std::max(1.0, text_w(title)));
  text(title, w - 4.0 - text_w(title) * title_px / text_px, y1 - 6.0, title_px);
  return out;
}

core::OverlayMesh build_streamlines_from(const core::VolumeGrid& g, const std::vector<float>& u, const std::vector<float>& v,
                                         const std::vector<float>& w, const std::vector<glm::dvec3>& seeds_ijk, double length_cells,
                                         double speed_max_m_s, double brightness, std::vector<std::vector<glm::dvec3>>* lines_ijk) {
  core::OverlayMesh out;
  const std::size_t n = g.points();
  if (u.size() != n || v.size() != n || n == 0 || seeds_ijk.empty()) return out;
  vtkNew<vtkImageData> image;
  image->SetDimensions(g.lon_deg.count, g.lat_deg.count, g.alt_m.count);
  image->SetOrigin(0.0, 0.0, 0.0);
  image->SetSpacing(1.0, 1.0, 1.0);
  // Velocity in grid cells per second: east over the cell's width at its latitude, north over its
  // height, up over its depth. No data (NaN) is calm.
  constexpr double kDeg = 3.14159265358979323846 / 180.0;
  vtkNew<vtkFloatArray> vel;
  vel->SetNumberOfComponents(3);
  vel->SetNumberOfTuples(static_cast<vtkIdType>(n));
  vel->SetName("velocity");
  for (int k = 0; k < g.alt_m.count; ++k) {
    const double r = g.earth_radius_m + g.alt_m.at(k);
    for (int j = 0; j < g.lat_deg.count; ++j) {
      const double dx = r * std::cos(g.lat_deg.at(j) * kDeg) * g.lon_deg.step * kDeg, dy = r * g.lat_deg.step * kDeg;
      for (int i = 0; i < g.lon_deg.count; ++i) {
        const std::size_t idx = g.index(i, j, k);
        auto calm = [](float x) { return std::isfinite(x) ? static_cast<double>(x) : 0.0; };
        const double c[3] = {calm(u[idx]) / dx, calm(v[idx]) / dy, w.size() == n ? calm(w[idx]) / g.alt_m.step : 0.0};
        vel->SetTuple(static_cast<vtkIdType>(idx), c);
      }
    }
  }
  image->GetPointData()->SetVectors(vel);
  vtkNew<vtkPoints> seed_points;
  seed_points->SetDataTypeToDouble();
  for (const glm::dvec3& s : seeds_ijk) seed_points->InsertNextPoint(s.x, s.y, s.z);
  vtkNew<vtkPolyData> seeds;
  seeds->SetPoints(seed_points);
  vtkNew<vtkRungeKutta45> rk;
  vtkNew<vtkStreamTracer> tracer;
  tracer->SetInputData(image);
  tracer->SetSourceData(seeds);
  tracer->SetIntegrator(rk);
  tracer->SetIntegrationDirectionToForward();
  tracer->SetMaximumPropagation(length_cells);
  tracer->SetIntegrationStepUnit(vtkStreamTracer::CELL_LENGTH_UNIT);
  tracer->SetInitialIntegrationStep(0.05);
  tracer->SetMinimumIntegrationStep(0.001);
  tracer->SetMaximumIntegrationStep(0.2);
  tracer->SetMaximumError(1e-8);
  tracer->SetMaximumNumberOfSteps(200000);
  tracer->SetTerminalSpeed(1e-12);
  tracer->Update();
  ++g_vtk_runs;
  vtkPolyData* pd = tracer->GetOutput();
  vtkPoints* pts = pd->GetPoints();
  vtkCellArray* lines = pd->GetLines();
  if (!pts || !lines) return out;
  vtkIdType npts = 0;
  const vtkIdType* ids = nullptr;
  for (lines->InitTraversal(); lines->GetNextCell(npts, ids);) {
    std::vector<glm::dvec3> ijk;
    for (vtkIdType k = 0; k < npts; ++k) {
      double p[3];
      pts->GetPoint(ids[k], p);
      ijk.emplace_back(p[0], p[1], p[2]);
      const double su = trilinear(g, u, p[0], p[1], p[2]), sv = trilinear(g, v, p[0], p[1], p[2]);
      const double sw = w.size() == n ? trilinear(g, w, p[0], p[1], p[2]) : 0.0;
      const auto base = static_cast<std::uint32_t>(out.positions.size());
      out.positions.push_back(index_to_ecef(g, p[0], p[1], p[2]));
      out.colors.push_back(colormap(std::sqrt(su * su + sv * sv + sw * sw) / speed_max_m_s, brightness));
      if (k > 0) out.lines.push_back(base - 1), out.lines.push_back(base);
    }
    if (lines_ijk) lines_ijk->push_back(std::move(ijk));
  }
  return out;
}

core::OverlayMesh build_streamlines(const core::VolumeGrid& g, const std::vector<float>& u, const std::vector<float>& v,
                                    const std::vector<float>& w, double altitude_m, int seeds, double length_cells,
                                    double speed_max_m_s, double brightness) {
  const double z = (altitude_m - g.alt_m.start) / g.alt_m.step;
  std::vector<glm::dvec3> lattice;
  for (int b = 0; b < seeds; ++b) {
    for (int a = 0; a < seeds; ++a) {
      lattice.emplace_back((a + 0.5) / seeds * (g.lon_deg.count - 1), (b + 0.5) / seeds * (g.lat_deg.count - 1), z);
    }
  }
  return build_streamlines_from(g, u, v, w, lattice, length_cells, speed_max_m_s, brightness);
}

core::OverlayInstances arrow_glyph() {
  vtkNew<vtkArrowSource> arrow;
  arrow->SetTipLength(0.35);
  arrow->SetTipRadius(0.12);
  arrow->SetShaftRadius(0.04);
  arrow->SetTipResolution(8);
  arrow->SetShaftResolution(8);
  vtkNew<vtkTriangleFilter> triangles;  // the shaft's and the tip's caps are polygons
  triangles->SetInputConnection(arrow->GetOutputPort());
  triangles->PassVertsOff();
  triangles->PassLinesOff();
  triangles->Update();
  ++g_vtk_runs;
  core::OverlayInstances g;
  vtkPolyData* pd = triangles->GetOutput();
  vtkPoints* pts = pd->GetPoints();
  if (!pts) return g;
  for (vtkIdType i = 0; i < pts->GetNumberOfPoints(); ++i) {
    double p[3];
    pts->GetPoint(i, p);
    g.glyph_positions.emplace_back(static_cast<float>(p[0] - 0.5), static_cast<float>(p[1]), static_cast<float>(p[2]));  // middle at 0
  }
  vtkIdType npts = 0;
  const vtkIdType* ids = nullptr;
  vtkCellArray* polys = pd->GetPolys();
  for (polys->InitTraversal(); polys->GetNextCell(npts, ids);) {
    if (npts != 3) continue;
    for (int k = 0; k < 3; ++k) g.glyph_triangles.push_back(static_cast<std::uint32_t>(ids[k]));
  }
  return g;
}

core::OverlayMesh build_arrows(const core::VolumeGrid& g, const std::vector<float>& u, const std::vector<float>& v, double altitude_m,
                               const ArrowStyle& style, const std::vector<float>* pressure) {
  core::OverlayMesh out;
  const std::size_t n = g.points();
  if (u.size() != n || v.size() != n || n == 0 || style.spacing_cells < 1 || !(style.speed_max_m_s > 0.0)) return out;
  const bool isobaric = style.pressure_pa > 0.0;
  if (isobaric && (!pressure || pressure->size() != n)) return out;
  out.instances = arrow_glyph();
  core::OverlayInstances& in = out.instances;
  constexpr double kDeg = 3.14159265358979323846 / 180.0;
  const double target_ln = isobaric ? std::log(style.pressure_pa) : 0.0;
  const double range = style.speed_max_m_s - style.speed_min_m_s;
  const int s = style.spacing_cells;
  // The lattice centred on the grid: as many whole spacings as fit, the rest split at both sides.
  const int i0 = ((g.lon_deg.count - 1) % s) / 2, j0 = ((g.lat_deg.count - 1) % s) / 2;
  for (int j = j0; j < g.lat_deg.count; j += s) {
    for (int i = i0; i < g.lon_deg.count; i += s) {
      const double z = isobaric ? isobaric_level(g, *pressure, i, j, target_ln) : (altitude_m - g.alt_m.start) / g.alt_m.step;
      if (z < 0.0) continue;  // the pressure surface does not cross this column
      const double alt = isobaric ? g.alt_m.start + z * g.alt_m.step : altitude_m;
      const double wu = trilinear(g, u, i, j, z), wv = trilinear(g, v, i, j, z);
      const double speed = std::hypot(wu, wv);
      if (!std::isfinite(speed) || speed == 0.0) continue;
      const double lat = g.lat_deg.at(j), lon = g.lon_deg.at(i);
      const geo::EnuFrame f = geo::sphere_enu(lat, lon);
      const glm::dvec3 along = (wu * f.east + wv * f.north) / speed, left = glm::cross(f.up, along);
      // The spacing north-south in metres at the arrow; metres of arrow per m/s from it.
      const double spacing_m = style.spacing_cells * (g.earth_radius_m + alt) * std::abs(g.lat_deg.step) * kDeg;
      const double length = style.scale * spacing_m / style.speed_max_m_s * speed;
      in.origins.push_back(geo::sphere_to_ecef({lat, lon, alt}, g.earth_radius_m));
      in.axis_x.emplace_back(length * along);
      in.axis_y.emplace_back(length * left);
      in.axis_z.emplace_back(length * f.up);
      in.colors.push_back(colormap((speed - style.speed_min_m_s) / range, style.brightness));
    }
  }
  if (in.origins.empty()) in = {};
  return out;
}

namespace {

// A pressure level must lie among the time step's pressures (known only once the step is read).
void check_pressure_level(const std::vector<float>& p, double hpa, std::size_t i) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (float x : p) {
    if (x > 0.0f) lo = std::min(lo, static_cast<double>(x)), hi = std::max(hi, static_cast<double>(x));
  }
  if (!(100.0 * hpa >= lo && 100.0 * hpa <= hi)) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "overlays[%zu].pressure_hpa: found %g, expected a pressure within the volume's, %.6g..%.6g hPa", i, hpa,
                  lo / 100.0, hi / 100.0);
    throw OverlayError(buf);
  }
}

}  // namespace

std::vector<BuiltOverlay> OverlayBuilder::build(const std::vector<core::OverlaySpec>& specs, core::CloudVolume& volume, std::size_t time_step,
                                                const core::Camera& cam) {
  std::vector<BuiltOverlay> built;
  if (specs.empty()) {
    cache_.clear();
    return built;
  }
  cache_.resize(specs.size());
  const double r0 = volume.grid.earth_radius_m;
  for (std::size_t i = 0; i < specs.size(); ++i) {
    const core::OverlaySpec& s = specs[i];
    BuiltOverlay b;
    b.name = s.type;
    b.line_width_px = s.numbers.count("line_width_px") ? static_cast<float>(s.number("line_width_px")) : 1.0f;
    if (!s.enabled) {
      built.push_back(b);
      continue;
    }
    const bool of_field = s.type == "isosurface" || s.type == "wind" || s.type == "arrows" || s.type == "section";
    const bool gshhg = s.type == "coastlines" || s.type == "borders" || s.type == "rivers";
    const char res = gshhg ? coastline_resolution(s.text("resolution"), cam.alt_m) : 0;
    const GeoBox box = gshhg ? overlay_box(volume.grid, res, cam) : GeoBox{};
    Entry& e = cache_[i];
    const bool same_box = e.box.global == box.global && e.box.lon_min == box.lon_min && e.box.lon_max == box.lon_max &&
                          e.box.lat_min == box.lat_min && e.box.lat_max == box.lat_max;
    const bool fresh = e.mesh && e.spec == s && e.resolution == res && same_box && (!of_field || e.time_step == time_step);
    if (!fresh) {
      const auto t0 = std::chrono::steady_clock::now();
      core::OverlayMesh m;
      if (s.type == "coastlines") m = build_coastlines(gshhg_dir_, res, r0, rgba(s.color("color")), 2000.0, box);
      if (s.type == "graticule") m = build_graticule(s.number("step_deg"), r0, rgba(s.color("color")));
      if (s.type == "borders" || s.type == "rivers") {
        // GMT's classes: borders 1 national, 2 states of the Americas, 3 marine, a all; rivers 1
        // permanent major, r all permanent, a all with canals.
        const std::string& c = s.text("class");
        const std::string select = c == "national" || c == "major" ? "1" : c == "states" ? "2" : c == "marine" ? "3" : c == "permanent" ? "r" : "a";
        m = build_gshhg(s.type == "borders" ? GshhgFeature::Border : GshhgFeature::River, res, select, box, r0, rgba(s.color("color")),
                        gshhg_dir_);
      }
      if (s.type == "isosurface") {
        const core::Field f = volume_field(volume, s.text("field"), "overlays[" + std::to_string(i) + "].field");
        const core::TimeStepData& data = volume.step(time_step);
        FieldColor by;
        if (s.text("color_field") != "none") {
          by.field = &data[volume_field(volume, s.text("color_field"), "overlays[" + std::to_string(i) + "].color_field")];
          by.lo = s.number("color_min"), by.hi = s.number("color_max"), by.brightness = s.number("brightness");
        }
        m = build_isosurface(volume.grid, data[f], s.number("value"), rgba(s.color("color")), by);
      }
      if (s.type == "section") {
        const core::TimeStepData& data = volume.step(time_step);
        const core::Field f = volume_field(volume, s.text("field"), "overlays[" + std::to_string(i) + "].field");
        const FieldColor by{nullptr, s.number("color_min"), s.number("color_max"), s.number("brightness")};
        if (s.text("kind") == "vertical") {
          m = build_vertical_section(volume.grid, data[f], s.number("from_lat"), s.number("from_lon"), s.number("to_lat"), s.number("to_lon"), by);
        } else if (s.text("kind") == "isobaric") {
          check_pressure_level(data[core::Field::Pressure], s.number("pressure_hpa"), i);
          m = build_isobaric_section(volume.grid, data[core::Field::Pressure], data[f], 100.0 * s.number("pressure_hpa"), by);
        } else {
          m = build_horizontal_section(volume.grid, data[f], s.number("altitude_m"), by);
        }
      }
      if (s.type == "wind") {
        const core::TimeStepData& data = volume.step(time_step);
        m = build_streamlines(volume.grid, data[core::Field::WindU], data[core::Field::WindV], data[core::Field::WindW],
                              s.number("altitude_m"), static_cast<int>(s.number("seeds")), s.number("length_cells"),
                              s.number("speed_max_m_s"), s.number("brightness"));
      }
      if (s.type == "arrows") {
        const core::TimeStepData& data = volume.step(time_step);
        ArrowStyle style;
        style.spacing_cells = static_cast<int>(std::lround(s.number("spacing_cells")));
        style.scale = s.number("scale"), style.speed_min_m_s = s.number("speed_min_m_s"), style.speed_max_m_s = s.number("speed_max_m_s");
        style.brightness = s.number("brightness");
        style.pressure_pa = 100.0 * s.number("pressure_hpa");
        if (style.pressure_pa > 0.0) check_pressure_level(data[core::Field::Pressure], s.number("pressure_hpa"), i);
        m = build_arrows(volume.grid, data[core::Field::WindU], data[core::Field::WindV], s.number("altitude_m"), style,
                         &data[core::Field::Pressure]);
      }
      if (s.type == "isosurface" || s.type == "section") {  // translucent below 1 (core::kOpaqueAlpha)
        m.colors.resize(m.positions.size(), glm::vec4(1.0f));
        for (glm::vec4& c : m.colors) c.a = static_cast<float>(s.number("opacity"));
      }
      e = {s, time_step, res, box, std::make_shared<const core::OverlayMesh>(std::move(m))};
      b.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      b.rebuilt = true;
    }
    b.mesh = e.mesh;
    if (s.type == "graticule" && s.number("label_px") > 0.0) {  // the labels face this view: made for it
      b.view_mesh = std::make_shared<const core::OverlayMesh>(
          graticule_labels(s.number("step_deg"), cam, r0, rgba(s.color("color")), s.number("label_px")));
    }
    if (s.type == "section" && s.number("legend_px") > 0.0) {  // the legend stands in front of this view
      const core::Field f = volume_field(volume, s.text("field"), "overlays[" + std::to_string(i) + "].field");
      b.view_mesh = std::make_shared<const core::OverlayMesh>(colour_bar(cam, r0, std::string(core::field_name(f)) + " " + core::field_units(f),
                                                                         s.number("color_min"), s.number("color_max"),
                                                                         s.number("brightness"), s.number("legend_px")));
    }
    built.push_back(b);
  }
  return built;
}

std::vector<render::OverlayDraw> OverlayBuilder::draws(const std::vector<BuiltOverlay>& built) {
  std::vector<render::OverlayDraw> d;
  for (const BuiltOverlay& b : built) d.push_back({b.name, b.mesh, b.view_mesh, b.line_width_px});  // one per overlay, in order
  return d;
}

}  // namespace cv::overlays
