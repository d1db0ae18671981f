// The CPU reference raymarcher: double precision, through the same physics functions
// (shaders/common) and the same sampling of the data (volume/sampler) as the GPU will use, so
// tests can hold the GPU image against it. Single scattering toward the sun with the
// multiple-scattering octaves; no sky, ground or ambient term yet (the renderer issue adds them).
#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

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

struct MarchSettings {
  double view_step_m = 100.0;  // march step along view rays
  int sun_steps = 32;          // steps of the secondary march toward the sun
  int octaves = 1;             // 1 = single scattering
  double octave_a = 0.5, octave_b = 0.5, octave_c = 0.5;
  double droplet_diameter_um = 20.0;  // approximate Mie phase for liquid
  double ice_g = 0.75;                // Henyey-Greenstein for ice
  // -1: sample each step at its middle; otherwise the accumulation frame whose jittered offsets
  // (shaders/common/rng.glsl step_jitter) place the samples, so banding averages away over frames.
  int frame = -1;
  // Acceleration (shaders/common/march_control.glsl). Skipping jumps over bricks of the extinction
  // pyramid that hold no cloud and resumes on the same sample grid: the image does not change.
  bool skip_empty = true;
  // Splits a view step into substeps where the brick's largest extinction would give a step an
  // optical depth above max_step_optical_depth (thick cores are then not under-sampled).
  bool adaptive_steps = false;
  double max_step_optical_depth = 1.0;
  // View rays stop below this transmittance, sun marches once every octave's attenuation is below it.
  double min_transmittance = 1e-6;
};

// What a frame's march did, summed over its pixels (the GPU counts with atomics).
struct MarchStats {
  std::uint64_t view_samples = 0;   // medium lookups along view rays (substeps included)
  std::uint64_t view_skipped = 0;   // view step positions jumped over in empty bricks
  std::uint64_t bricks_jumped = 0;  // jumps over empty bricks, view and sun rays
  std::uint64_t sun_samples = 0;    // medium lookups along sun rays
  std::uint64_t sun_skipped = 0;    // sun step positions jumped over or cut off by sun_march_tau_limit
  std::uint64_t rays_missed = 0;    // pixels whose ray never crossed the cloud shell
};

struct ReferenceImage {
  int width = 0, height = 0;
  std::vector<glm::dvec3> radiance;    // scattered toward the camera, per pixel
  std::vector<double> transmittance;   // of the view ray through the clouds
  MarchStats stats;
};

// The renderer's medium: grid-box-mean extinction (cloud fraction x in-cloud extinction) of
// liquid and of ice per grid node, no data as 0. Both the CPU reference and the GPU interpolate
// these products, never the factors separately.
struct GridMeanExtinction {
  std::vector<float> liquid_per_m, ice_per_m;
};
GridMeanExtinction grid_mean_extinction(const VolumeGrid& grid, const TimeStepData& data);

// A camera's orientation in Earth-centred coordinates, and its half-width: pixel (px, py) looks
// along forward + x right + y up with x, y in [-tan_half, tan_half] (y scaled by the aspect).
struct CameraFrame {
  glm::dvec3 forward, right, up;
  double tan_half = 0.0;
};
CameraFrame camera_frame(const Camera& cam);

// The direction of a pixel's ray in Earth-centred coordinates.
glm::dvec3 camera_ray(const Camera& cam, int px, int py);

// Renders one time step of a volume.
ReferenceImage render_reference(const VolumeGrid& grid, const GridMeanExtinction& medium, const Camera& cam, const Sun& sun,
                                const MarchSettings& settings);
inline ReferenceImage render_reference(const VolumeGrid& grid, const TimeStepData& data, const Camera& cam, const Sun& sun,
                                       const MarchSettings& settings) {
  return render_reference(grid, grid_mean_extinction(grid, data), cam, sun, settings);
}

}  // namespace cv::core
