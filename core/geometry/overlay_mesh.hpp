// Overlay geometry (coastlines, graticule, isosurfaces, ...) as plain data: Earth-centred vertices
// in double with a colour each, line segments and triangles. Built by the overlays layer
// (app/overlays, through VTK), drawn by the GPU overlay pass (app/render/overlay_pass) and cast by
// the CPU reference (cast_overlay below) into the same per-pixel opaque layer the march composites
// behind the clouds. Nothing here knows GL or VTK.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "frame/camera.hpp"
#include "reference/raymarcher.hpp"

namespace cv::core {

// One glyph (triangles in its own frame) drawn at many places, each with its own transform and
// colour (wind arrows). Instance k puts a glyph point g at
//   origins[k] + g.x * axis_x[k] + g.y * axis_y[k] + g.z * axis_z[k]
// (Earth-centred metres), formed in double from the float axes and glyph, on the GPU (the overlay
// pass's instanced draw) and the CPU (expand_instances) alike. Instances are opaque: their colour's
// alpha is taken as 1.
struct OverlayInstances {
  std::vector<glm::vec3> glyph_positions;      // glyph units
  std::vector<std::uint32_t> glyph_triangles;  // vertex index triples into glyph_positions
  std::vector<glm::dvec3> origins;             // Earth-centred metres
  std::vector<glm::vec3> axis_x, axis_y, axis_z;  // metres per glyph unit, Earth-centred directions
  std::vector<glm::vec4> colors;               // radiance (rgb, the march's units)
  std::size_t count() const { return origins.size(); }
  bool empty() const { return glyph_triangles.empty() || origins.empty(); }
};

struct OverlayMesh {
  std::vector<glm::dvec3> positions;     // Earth-centred, Earth-fixed metres (the renderer's sphere)
  std::vector<glm::vec4> colors;         // per vertex: radiance (rgb, the march's units) and alpha
  std::vector<std::uint32_t> lines;      // vertex index pairs
  std::vector<std::uint32_t> triangles;  // vertex index triples
  OverlayInstances instances;            // drawn instanced, besides the primitives above
  bool empty() const { return lines.empty() && triangles.empty() && instances.empty(); }
  // Appends another mesh's vertices and primitives (indices shifted). Its instances join this
  // mesh's when they share the glyph (or this mesh has none); else they are appended expanded.
  void append(const OverlayMesh& other);
};

// The mesh with its instances expanded into plain triangles (each instance's glyph transformed as
// OverlayInstances says, in double), after its own vertices; the CPU cast draws this.
OverlayMesh expand_instances(const OverlayMesh& mesh);

// Lines lie on surfaces (coastlines and the graticule on the ground): their distance is pulled
// toward the camera by this fraction, on the GPU and the CPU alike, so that the float distance
// and the march's own ground intersection do not decide between a line and the ground it lies on
// (400 m at 4000 km, 0.2 m at 2 km).
inline constexpr double kLineDistanceBias = 1e-4;

// Where a camera-relative point lands on the image: pixel coordinates (x right, y down, pixel
// centres at half-integers as camera_ray's) and the distance along the ray; `in_front` false when
// the point is behind the camera.
struct Projected {
  double x = 0.0, y = 0.0, distance_m = 0.0;
  bool in_front = false;
};
Projected project_point(const Camera& cam, const glm::dvec3& relative_m);

// Whether the sphere of radius r0_m hides the point `relative_m` (camera-relative) from a camera
// at `camera_m` (Earth-centred): the segment from the camera meets the sphere more than
// max(1 m, 1e-6 of its length) before the point. Points on the sphere's visible side are not hidden.
// The GPU overlay pass (shaders/render/overlay.frag) makes the same test in float.
bool hidden_by_sphere(const glm::dvec3& camera_m, const glm::dvec3& relative_m, double r0_m);

// The mesh's opaque layer as the march reads it (OpaqueLayer: distance along each pixel's ray to
// the nearest geometry, 0 where none, and its radiance), computed on the CPU: each pixel's ray (camera_ray)
// is intersected exactly with the triangles (double precision, Moller-Trumbore), and a line covers
// the pixels whose centres lie within half a pixel of its projected segment (its distance there
// is that of the segment's point nearest the ray, or of the ground the pixel's ray meets where
// that is nearer, less kLineDistanceBias of it). The nearest hit wins; geometry hidden by the
// sphere of radius r0_m is left out. Instances are cast as their expanded triangles
// (expand_instances). The GPU pass rasterises the same primitives: triangles agree to float
// precision, lines may differ by a pixel at their ends (GL's diamond-exit rule).
OpaqueLayer cast_overlay(const OverlayMesh& mesh, const Camera& cam, double r0_m);

}  // namespace cv::core
