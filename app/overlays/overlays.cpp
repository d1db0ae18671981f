// The overlays' geometry, built by VTK filters.
#include "overlays/overlays.hpp"

#include <atomic>
#include <cstdio>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>

#include <glm/glm.hpp>

#include <vtkCellArray.h>
#include <vtkCleanPolyData.h>
#include <vtkFloatArray.h>
#include <vtkFlyingEdges3D.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
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
    if (specs[i].type == "isosurface") volume_field(volume, specs[i].text("field"), at + ".field");
    if (specs[i].type == "coastlines") {
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

core::OverlayMesh build_coastlines(const std::string& dir, char res, double r0_m, const glm::vec4& color, double max_segment_m) {
  // For each level the requested resolution, else the nearest installed (finer first).
  const std::string order = "clihf";
  const std::size_t fit = std::min(order.find(res), order.size() - 1);
  std::string preference(1, order[fit]);
  for (std::size_t k = fit + 1; k < order.size(); ++k) preference += order[k];
  for (std::size_t k = fit; k-- > 0;) preference += order[k];
  std::vector<render::ShorePolygon> polygons;
  bool land = false;
  for (int level = 1; level <= 2; ++level) {
    for (char r : preference) {
      const std::string base = dir + "/" + r + "/GSHHS_" + r + "_L" + std::to_string(level);
      if (!std::filesystem::exists(base + ".shp")) continue;
      render::read_shore_polygons(base, level, polygons);
      land = land || level == 1;
      break;
    }
  }
  if (!land) {
    throw OverlayError("overlays: coastlines: no GSHHS shorelines (GSHHS_<res>_L1.shp) under " + dir +
                       ", expected the files of the Debian package python-cartopy-data (apt-get install python-cartopy-data)");
  }
  // The rings as closed polylines in (lon, lat); vtkCleanPolyData merges the repeated closing
  // vertex and any duplicate points, and drops degenerate segments.
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();  // degrees in float would move a vertex by up to half a metre
  vtkNew<vtkCellArray> cells;
  for (const render::ShorePolygon& p : polygons) {
    for (const auto& ring : p.rings) {
      const vtkIdType n = static_cast<vtkIdType>(ring.size() / 2);
      const vtkIdType first = points->GetNumberOfPoints();
      cells->InsertNextCell(n + 1);
      for (vtkIdType k = 0; k < n; ++k) {
        points->InsertNextPoint(ring[2 * k], ring[2 * k + 1], 0.0);
        cells->InsertCellPoint(first + k);
      }
      cells->InsertCellPoint(first);
    }
  }
  vtkNew<vtkPolyData> pd;
  pd->SetPoints(points);
  pd->SetLines(cells);
  vtkNew<vtkCleanPolyData> clean;
  clean->SetInputData(pd);
  clean->PointMergingOn();
  clean->SetTolerance(0.0);
  clean->Update();
  ++g_vtk_runs;
  core::OverlayMesh out;
  polylines_to_sphere(clean->GetOutput(), r0_m, max_segment_m, color, out);
  return out;
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
  // f upper left, g middle) and strokes of their own for N, E, W and the minus sign.
  static const double seg[7][4] = {{0, 6, 4, 6}, {4, 6, 4, 3}, {4, 3, 4, 0}, {0, 0, 4, 0}, {0, 0, 0, 3}, {0, 3, 0, 6}, {0, 3, 4, 3}};
  static const char* digits[10] = {"abcdef", "bc", "abged", "abgcd", "fgbc", "afgcd", "afgedc", "abc", "abcdefg", "abcdfg"};
  std::vector<std::array<double, 4>> out;
  double x = 0.0;
  auto add = [&](double x0, double y0, double x1, double y1) { out.push_back({x + x0, y0, x + x1, y1}); };
  for (char ch : text) {
    if (ch >= '0' && ch <= '9') {
      for (const char* p = digits[ch - '0']; *p; ++p) {
        const double* q = seg[*p - 'a'];
        add(q[0], q[1], q[2], q[3]);
      }
    } else if (ch == 'S') {
      for (const char* p = digits[5]; *p; ++p) {
        const double* q = seg[*p - 'a'];
        add(q[0], q[1], q[2], q[3]);
      }
    } else if (ch == 'N') {
      add(0, 0, 0, 6), add(0, 6, 4, 0), add(4, 0, 4, 6);
    } else if (ch == 'E') {
      add(0, 0, 0, 6), add(0, 6, 4, 6), add(0, 3, 3, 3), add(0, 0, 4, 0);
    } else if (ch == 'W') {
      add(0, 6, 1, 0), add(1, 0, 2, 4), add(2, 4, 3, 0), add(3, 0, 4, 6);
    } else if (ch == '-') {
      add(0, 3, 4, 3);
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

core::OverlayMesh build_isosurface(const core::VolumeGrid& grid, const std::vector<float>& field, double value, const glm::vec4& color) {
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
    out.colors.push_back(color);
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
    const bool of_field = s.type == "isosurface";
    const char res = s.type == "coastlines" ? coastline_resolution(s.text("resolution"), cam.alt_m) : 0;
    Entry& e = cache_[i];
    const bool fresh = e.mesh && e.spec == s && e.resolution == res && (!of_field || e.time_step == time_step);
    if (!fresh) {
      const auto t0 = std::chrono::steady_clock::now();
      core::OverlayMesh m;
      if (s.type == "coastlines") m = build_coastlines(gshhs_dir_, res, r0, rgba(s.color("color")));
      if (s.type == "graticule") m = build_graticule(s.number("step_deg"), r0, rgba(s.color("color")));
      if (s.type == "isosurface") {
        const core::Field f = volume_field(volume, s.text("field"), "overlays[" + std::to_string(i) + "].field");
        m = build_isosurface(volume.grid, volume.step(time_step)[f], s.number("value"), rgba(s.color("color")));
      }
      e = {s, time_step, res, std::make_shared<const core::OverlayMesh>(std::move(m))};
      b.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      b.rebuilt = true;
    }
    b.mesh = e.mesh;
    if (s.type == "graticule" && s.number("label_px") > 0.0) {  // the labels face this view: made for it
      auto with_labels = std::make_shared<core::OverlayMesh>(*e.mesh);
      with_labels->append(graticule_labels(s.number("step_deg"), cam, r0, rgba(s.color("color")), s.number("label_px")));
      b.mesh = std::move(with_labels);
    }
    built.push_back(b);
  }
  return built;
}

std::vector<render::OverlayDraw> OverlayBuilder::draws(const std::vector<BuiltOverlay>& built) {
  std::vector<render::OverlayDraw> d;
  for (const BuiltOverlay& b : built) d.push_back({b.name, b.mesh, b.line_width_px});  // one per overlay, in order
  return d;
}

}  // namespace cv::overlays
