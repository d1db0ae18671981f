// The CPU reference raymarcher: the GPU's march kernel (shaders/kernel) run in double precision, so
// tests can hold the GPU image against it. Single scattering toward the sun with the
// multiple-scattering octaves, sunlight through the atmosphere, an ambient sky term, the sky's
// in-scatter around the clouds and the globe with the clouds' shadows.
#pragma once

#include <string>
#include <cstdint>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "noise/noise.hpp"
#include "settings/march_settings.hpp"
#include "volume/cloud_volume.hpp"

namespace cv::core {

// A pinhole camera on the spherical Earth. Heading is clockwise from north, pitch up from the
// horizon, fov the horizontal field of view; all in degrees.
struct Camera {
  double lat_deg = 0.0, lon_deg = 0.0, alt_m = 0.0;
  double heading_deg = 0.0, pitch_deg = 0.0, fov_deg = 60.0;
  int width = 64, height = 36;
};

// The sun by its subsolar point (where it stands at the zenith) and the irradiance it delivers
// perpendicular to its rays at the top of the cloud layer (per channel, W/m2 or relative units).
struct Sun {
  double subsolar_lat_deg = 0.0, subsolar_lon_deg = 0.0;
  glm::dvec3 irradiance{1.0, 1.0, 1.0};
};

// MarchSettings: one table of rows, settings/march_settings.def.

// An equirectangular ground albedo image: linear rgb per texel, rows from latitude 90 down to -90,
// columns from longitude -180 east to 180.
struct AlbedoMap {
  int width = 0, height = 0;
  std::vector<float> rgb;
  // Bilinear over texel centres (shaders/common/ground.glsl equirect_texel), as the GPU samples it.
  glm::dvec3 at(double lat_rad, double lon_rad) const;
};

// What a frame's march did, summed over its pixels (the GPU counts with atomics).
struct MarchStats {
  std::uint64_t view_samples = 0;   // medium lookups along view rays (substeps included)
  std::uint64_t view_skipped = 0;   // view step positions jumped over in empty bricks
  std::uint64_t bricks_jumped = 0;  // jumps over empty bricks, view and sun rays
  std::uint64_t sun_samples = 0;    // medium lookups along sun rays
  std::uint64_t sun_skipped = 0;    // sun step positions jumped over or cut off by sun_march_tau_limit
  std::uint64_t rays_missed = 0;    // pixels whose ray never crossed the cloud shell
  bool sun_down = false;  // the whole cloud layer was in the Earth's shadow: no sun march or octave sum ran
  // Octave terms evaluated at sunlit samples (octave_terms in octaves.glsl, per sample once for both
  // phases), and what the classic sum would have taken there (octaves per sunlit sample): the
  // difference is what the octave gate left out.
  std::uint64_t octave_terms = 0, octave_terms_full = 0;
};

struct ReferenceImage {
  int width = 0, height = 0;
  std::vector<glm::dvec3> radiance;    // scattered toward the camera, per pixel
  std::vector<double> transmittance;   // of the view ray through the clouds (and air); 0 on the globe
  // The distance (m) from the camera at which the view transmittance fell to 0.5 (3e38: never).
  std::vector<double> cloud_depth_m;
  MarchStats stats;
};

// Opaque geometry for the march to stop at, per pixel (rows top to bottom): the distance (m) from
// the camera along the pixel's ray (0: none there) and, optionally, the geometry's radiance (see
// render::OpaqueInput: composited behind the clouds when given, else alpha is the transmittance).
struct OpaqueLayer {
  std::vector<float> distance_m;
  std::vector<float> radiance_rgba;  // 4 floats per pixel, or empty
};

// The renderer's medium: grid-box-mean extinction (cloud fraction x in-cloud extinction) of
// liquid and of ice per grid node, no data as 0. Both the CPU reference and the GPU interpolate
// these products, never the factors separately.
struct GridMeanExtinction {
  std::vector<float> liquid_per_m, ice_per_m;
};
// Extinctions from this up are not data but fill values left in a field (netCDF's default float
// fill is 9.96921e36): the densest fog is ~0.1 /m, and float sums of sigma x phase (up to 1.6e5 /sr
// at g = 0.999) x step would overflow to Inf near 1e33 /m. grid_mean_extinction takes them as no cloud.
constexpr float kMaxGridMeanExtinctionPerM = 1e6f;
// cloud fraction x in-cloud extinction per node; NaN, negative and >= kMaxGridMeanExtinctionPerM -> 0.
GridMeanExtinction grid_mean_extinction(const VolumeGrid& grid, const TimeStepData& data);

// The altitudes between which a volume holds cloud: from the level below its lowest level with any
// extinction to the level above its highest (trilinear sampling reads cloud between those), so the
// marchers intersect this thinner shell and never step through layers that hold nothing. `empty`
// when no node holds cloud: then nothing is marched at all.
struct CloudLayer {
  double bottom_m = 0.0, top_m = 0.0;
  bool empty = true;
};
CloudLayer cloud_layer(const VolumeGrid& grid, const GridMeanExtinction& medium);

// The largest extinction (liquid + ice, 1/m) of any node: a bound on what sampling can return,
// which sizes the sun marches' steps (MarchSettings::max_sun_step_optical_depth).
double largest_extinction(const GridMeanExtinction& medium);

// The longest a sun step may be (m) for this grid and layer: settings.max_sun_step_m, or where
// that is 0 the grid's horizontal cell size at the layer's floor (sun_step_limit_m in
// shaders/common/march_control.glsl). Both marchers take it from here, once per frame.
double sun_step_limit_m(const VolumeGrid& grid, const CloudLayer& layer, const MarchSettings& settings);

// At most how many sun steps one sun march takes over both its shell segments through the layer
// [bottom_m, top_m] above the sphere of radius r0_m: each segment takes sun_steps or
// ceil(length / max_step_m) (at most CV_SUN_SEGMENT_STEPS_MAX), and the two segments of a line
// through a shell are together no longer than its chord tangent to the floor,
// 2 sqrt(r_top^2 - r_bottom^2), so at most max(2 sun_steps, sun_steps + chord / max_step_m + 2),
// 2 more for rounding. Sizes llvmpipe's dispatches.
// mu_sun_min > 0 (smallest_sun_cosine in reference/earth_shadow.hpp): every sample that holds cloud
// sees the sun at least that high, so its sun ray leaves the shell through the top in one segment
// no longer than the path from the floor at that cosine, -rb mu + sqrt(rb^2 mu^2 + rt^2 - rb^2):
// a high sun then sizes the dispatches for its own short marches, not for a grazing one.
int max_sun_march_steps(int sun_steps, double max_step_m, double r0_m, double bottom_m, double top_m,
                        double mu_sun_min = -1.0);

// A camera's orientation in Earth-centred coordinates, and its half-width: pixel (px, py) looks
// along forward + x right + y up with x, y in [-tan_half, tan_half] (y scaled by the aspect).
struct CameraFrame {
  glm::dvec3 forward, right, up;
  double tan_half = 0.0;
};
CameraFrame camera_frame(const Camera& cam);

// The direction of a pixel's ray in Earth-centred coordinates.
glm::dvec3 camera_ray(const Camera& cam, int px, int py);

// Matrices for geometry that other passes draw with the clouds, camera-relative: a vertex is given
// as its Earth-centred position minus camera_ecef, formed in double (float then keeps its digits at
// any distance). The view matrix turns such an offset into eye space (x right, y up, looking down
// -z); the projection maps eye space to OpenGL clip space so that a point on the ray of pixel
// (px, py) lands on that pixel's centre in the renderer's row order (row 0 at the top, as every image
// the march writes: y is flipped against OpenGL's window rows, so front faces wind clockwise), with
// depth from near_m to far_m. The march's depth input is the distance along the ray, which a
// fragment shader takes as the length of the camera-relative position.
glm::dvec3 camera_ecef(const Camera& cam, double r0_m);
glm::dmat4 camera_view_matrix(const Camera& cam);
glm::dmat4 camera_projection_matrix(const Camera& cam, double near_m, double far_m);

// The centre of a volume on the sphere (altitude 0), Earth-centred, metres: the erosion noise's
// anchor (noise_anchor) for this grid, the same on the CPU and the GPU.
glm::dvec3 grid_centre_ecef(const VolumeGrid& grid);

struct PreparedVolume;  // kernel/prepared_volume.hpp

// Renders one time step of a volume through the march kernel (shaders/kernel/march.glsl) in
// double. `noise` is needed when settings.noise_amount > 0 (std::invalid_argument otherwise) and is
// not read when it is 0. The globe takes its albedo from `ground` when given (the caller loads
// settings.ground_texture: core reads no images), else from settings.ground_albedo.
ReferenceImage render_reference(const PreparedVolume& volume, const Camera& cam, const Sun& sun, const MarchSettings& settings,
                                const ErosionNoise* noise = nullptr, const AlbedoMap* ground = nullptr,
                                const OpaqueLayer* opaque = nullptr);
// The same, preparing the volume first (prepare_volume).
ReferenceImage render_reference(const VolumeGrid& grid, const GridMeanExtinction& medium, const Camera& cam, const Sun& sun,
                                const MarchSettings& settings, const ErosionNoise* noise = nullptr,
                                const AlbedoMap* ground = nullptr);
inline ReferenceImage render_reference(const VolumeGrid& grid, const TimeStepData& data, const Camera& cam, const Sun& sun,
                                       const MarchSettings& settings, const ErosionNoise* noise = nullptr,
                                       const AlbedoMap* ground = nullptr) {
  return render_reference(grid, grid_mean_extinction(grid, data), cam, sun, settings, noise, ground);
}

}  // namespace cv::core
