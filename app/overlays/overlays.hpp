// The overlays layer (cv_overlays): a scene's overlays (core::OverlaySpec) built into geometry
// (core::OverlayMesh) by VTK filters, cached per time step and rebuilt only when their inputs change,
// for the frame renderer's overlay pass to draw. VTK is private to this layer: nothing above it
// sees a VTK type, and a scene without overlays makes no VTK call.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "frame/camera.hpp"
#include "geometry/overlay_mesh.hpp"
#include "overlays/gshhg.hpp"
#include "render/frame_renderer.hpp"
#include "render/land_sea_mask.hpp"
#include "settings/overlay_settings.hpp"
#include "volume/cloud_volume.hpp"

namespace cv::overlays {

// Bad overlay input (a field the volume does not hold, missing coastline data): one line naming
// the scene key and what was expected; `render` exits 2 on it.
class OverlayError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The field an overlay parameter names, or OverlayError ("overlays[2].field: found \"rain\",
// expected a 3-D field the volume holds: extinction_liquid, temperature").
core::Field volume_field(const core::CloudVolume& volume, const std::string& name, const std::string& where);

// Checks every overlay against the volume before anything is built (fields it must hold).
void check_overlays(const std::vector<core::OverlaySpec>& specs, const core::CloudVolume& volume);

// The GSHHS resolution the camera's view calls for: crude from orbit, finer toward the ground
// (docs/scene.md, "Overlays"), or the spec's own.
char coastline_resolution(const std::string& setting, double camera_alt_m);

// The built overlay: its geometry, how long the build took, and whether this call rebuilt it.
struct BuiltOverlay {
  std::string name;
  std::shared_ptr<const core::OverlayMesh> mesh;  // kept between frames (and on the GPU)
  // What faces this view (graticule labels, a section's colour bar): made for each frame, drawn
  // after `mesh`, so the kept geometry is neither copied nor uploaded again.
  std::shared_ptr<const core::OverlayMesh> view_mesh;
  float line_width_px = 1.0f;
  double build_ms = 0.0;
  bool rebuilt = false;
};

// Each overlay's geometry, kept between frames: an overlay is rebuilt only when its spec, the
// time step (for overlays of the volume's fields) or what the view selects (the coastlines'
// resolution) changes.
class OverlayBuilder {
 public:
  explicit OverlayBuilder(std::string gshhg_dir = kGshhgDir) : gshhg_dir_(std::move(gshhg_dir)) {}
  std::vector<BuiltOverlay> build(const std::vector<core::OverlaySpec>& specs, core::CloudVolume& volume, std::size_t time_step,
                                  const core::Camera& cam);
  // For the frame renderer.
  static std::vector<render::OverlayDraw> draws(const std::vector<BuiltOverlay>& built);

 private:
  struct Entry {
    core::OverlaySpec spec;
    std::size_t time_step = 0;
    char resolution = 0;
    GeoBox box;  // what borders and rivers were read for
    std::shared_ptr<const core::OverlayMesh> mesh;
  };
  std::string gshhg_dir_;
  std::vector<Entry> cache_;
};

// How many VTK pipelines have run in this process (a test that no overlay costs nothing).
std::uint64_t vtk_pipeline_runs();

// The builders, each running VTK filters (the tests call them directly).
// Coastlines: GSHHG's level-1 shorelines and level-2 lake shores (through the GMT library, as
// borders and rivers) of resolution `res` (the nearest installed when that one is not) inside
// `box`, on the sphere of radius r0_m, each segment divided so that no piece is longer than
// max_segment_m (a long chord would cut under the sphere). OverlayError naming gmt-gshhg-low (or
// -high, -full) when the files are not installed.
core::OverlayMesh build_coastlines(const std::string& gshhg_dir, char res, double r0_m, const glm::vec4& color,
                                   double max_segment_m = 2000.0, const GeoBox& box = {});
// GSHHG borders or rivers (read_gshhg_lines, through the GMT library) of resolution `res` inside
// `box`, on the sphere as the coastlines are (segments no longer than max_segment_m).
core::OverlayMesh build_gshhg(GshhgFeature feature, char res, const std::string& select, const GeoBox& box, double r0_m,
                              const glm::vec4& color, const std::string& dir = kGshhgDir, double max_segment_m = 2000.0);
// The box shorelines, borders and rivers are read for: the whole Earth at resolutions c, l and i;
// at h and f a box around the camera (15 and 4 degrees of latitude each way, its centre on a 5 and
// 1 degree lattice so a moving camera rebuilds only when it crosses a cell), cut to a regional
// volume's extent and a margin of 2 degrees.
GeoBox overlay_box(const core::VolumeGrid& grid, char res, const core::Camera& cam);
// Meridians and parallels every step_deg on the sphere, divided every fraction of a degree.
core::OverlayMesh build_graticule(double step_deg, double r0_m, const glm::vec4& color);
// The labels of that graticule for one view: each meridian's longitude where it crosses the
// parallel nearest the view's centre, and each parallel's latitude where it crosses the meridian
// nearest it ("20W", "60N"), drawn as strokes of a built-in font (label_strokes) label_px
// high, in the plane facing the camera at the crossing, so they are geometry composited by depth
// like the rest (no VTK: they change with every view). Crossings hidden by the Earth or outside
// the image are left out, and so is a label that would overlap one placed before it.
core::OverlayMesh graticule_labels(double step_deg, const core::Camera& cam, double r0_m, const glm::vec4& color, double label_px);
// The strokes of `text` in the font: segments in glyph units (a glyph 4 wide and 6 high, 6 apart),
// as x0, y0, x1, y1 with y up: digits, letters (drawn as capitals), - + . / _ and space; other
// characters are left out.
std::vector<std::array<double, 4>> label_strokes(const std::string& text);

// The isosurface field == value of a 3-D field on the volume's grid (vtkFlyingEdges3D in grid
// indices, then mapped to the sphere: index -> lon, lat, alt -> Earth-centred). NaN (no data) is
// treated as far below the value.
// A colour field (the same grid, or empty) colours each vertex through colormap over
// color_min..color_max instead.
struct FieldColor {
  const std::vector<float>* field = nullptr;
  double lo = 0.0, hi = 1.0, brightness = 1.0;
};
core::OverlayMesh build_isosurface(const core::VolumeGrid& grid, const std::vector<float>& field, double value, const glm::vec4& color,
                                   const FieldColor& by = {});

// Sections coloured by a field through the colour map (by.field is ignored: `field` colours them).
// Horizontal: the plane at altitude_m through the grid (vtkFlyingEdgesPlaneCutter, the field
// interpolated onto it). Vertical: a curtain from the ground to the grid's top along the great
// circle between two points, `columns` samples along it (vtkProbeFilter samples the field; a
// stretch outside the grid is left out).
core::OverlayMesh build_horizontal_section(const core::VolumeGrid& grid, const std::vector<float>& field, double altitude_m, const FieldColor& by);
// Isobaric: the surface p = pressure_pa, curved in altitude. In each column of the grid the
// lowest altitude where the pressure field falls through the value, between two nodes, with ln p
// taken as linear in altitude there (exact in an isothermal layer; the importers interpolate ln p
// the same way between the file's levels); the field there (linear between the two nodes) colours
// it. Neighbouring columns that both cross make the surface's triangles; a column without a
// crossing (no data, or the value outside its pressures) leaves a hole.
core::OverlayMesh build_isobaric_section(const core::VolumeGrid& grid, const std::vector<float>& pressure, const std::vector<float>& field,
                                         double pressure_pa, const FieldColor& by);
core::OverlayMesh build_vertical_section(const core::VolumeGrid& grid, const std::vector<float>& field, double from_lat, double from_lon,
                                         double to_lat, double to_lon, const FieldColor& by, int columns = 128);
// A colour bar legend for one view: the colour map from lo (bottom) to hi (top) as a bar at the
// image's right, five ticks with their values, and the title (field and units) above, text_px
// high; geometry 1 m in front of the camera, so it is drawn and composited as any overlay (no
// cloud lies in front of it).
core::OverlayMesh colour_bar(const core::Camera& cam, double r0_m, const std::string& title, double lo, double hi, double brightness,
                             double text_px);

// The colour map: cool (dark blue) through cyan, green and yellow to warm (red) over t in 0..1
// (clamped), brightest 1; written here as five control points, linear between them.
glm::vec4 colormap(double t, double brightness = 1.0);

// Streamlines of the wind (u, v and w, m/s; w may be empty) by vtkStreamTracer (RK45) in grid-index
// space, each component divided by its cell's size in metres, from a seeds x seeds lattice at
// altitude_m, each followed length_cells cells forward; coloured by speed over 0..speed_max.
core::OverlayMesh build_streamlines(const core::VolumeGrid& grid, const std::vector<float>& u, const std::vector<float>& v,
                                    const std::vector<float>& w, double altitude_m, int seeds, double length_cells,
                                    double speed_max_m_s, double brightness);
// The same from explicit seeds, given as fractional grid indices (i, j, k); each streamline's
// points in grid indices too (for the tests), and the mesh on the sphere.
core::OverlayMesh build_streamlines_from(const core::VolumeGrid& grid, const std::vector<float>& u, const std::vector<float>& v,
                                         const std::vector<float>& w, const std::vector<glm::dvec3>& seeds_ijk, double length_cells,
                                         double speed_max_m_s, double brightness,
                                         std::vector<std::vector<glm::dvec3>>* lines_ijk = nullptr);

// Wind arrows on a level, drawn instanced: one arrow glyph (arrow_glyph) and an instance at every
// spacing_cells-th grid point in longitude and latitude (the lattice centred on the grid), on the
// sphere at altitude_m. Each instance's glyph x axis points along the horizontal wind (u east, v
// north, interpolated linearly in altitude between the grid's levels) in the local east-north
// frame, y to its left and z up; the arrow's middle is at the grid point, its length
// scale x spacing x speed / speed_max_m_s (the spacing north-south in metres at the arrow), and
// its colour the colour map over speed_min_m_s..speed_max_m_s. Points without wind data (NaN) or
// with no wind at all get no arrow.
// With pressure_pa above 0 and a pressure field given, the level is that pressure surface instead
// of altitude_m: each arrow at its column's altitude of the surface (as build_isobaric_section
// finds it), the wind interpolated there; a column the surface does not cross gets no arrow.
struct ArrowStyle {
  int spacing_cells = 4;
  double scale = 1.0, speed_min_m_s = 0.0, speed_max_m_s = 30.0, brightness = 1.0;
  double pressure_pa = 0.0;
};
core::OverlayMesh build_arrows(const core::VolumeGrid& grid, const std::vector<float>& u, const std::vector<float>& v, double altitude_m,
                               const ArrowStyle& style, const std::vector<float>* pressure = nullptr);
// The arrow glyph: vtkArrowSource's arrow (a cylinder shaft and a cone tip, round about the x axis)
// triangulated by vtkTriangleFilter, from x = -0.5 (tail) to 0.5 (tip), tip radius 0.12 and shaft
// radius 0.04; glyph_positions and glyph_triangles are set, no instance.
core::OverlayInstances arrow_glyph();

}  // namespace cv::overlays
