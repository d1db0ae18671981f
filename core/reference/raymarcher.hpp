// The CPU reference raymarcher: the GPU's march kernel (shaders/kernel) run in double precision, so
// tests can hold the GPU image against it. Single scattering toward the sun with the
// multiple-scattering octaves, sunlight through the atmosphere, an ambient sky term, the sky's
// in-scatter around the clouds and the globe with the clouds' shadows.
#pragma once

#include <vector>

#include <glm/vec3.hpp>

#include "frame/albedo_map.hpp"
#include "frame/camera.hpp"
#include "frame/march_stats.hpp"
#include "frame/sun.hpp"
#include "kernel/march_limits.hpp"
#include "noise/noise.hpp"
#include "settings/march_settings.hpp"
#include "volume/cloud_volume.hpp"
#include "volume/grid_mean.hpp"

namespace cv::core {

struct ReferenceImage {
  int width = 0, height = 0;
  std::vector<glm::dvec3> radiance;    // scattered toward the camera, per pixel
  std::vector<double> transmittance;   // of the view ray through the clouds (and air); 0 on the globe
  // The distance (m) from the camera at which the view transmittance fell to 0.5 (3e38: never).
  std::vector<double> cloud_depth_m;
  // The distance (m) from the camera to the first view step that held cloud (3e38: none).
  std::vector<double> first_cloud_m;
  MarchStats stats;
};

// Opaque geometry for the march to stop at, per pixel (rows top to bottom): the distance (m) from
// the camera along the pixel's ray (0: none there) and, optionally, the geometry's radiance (see
// render::OpaqueInput: composited behind the clouds when given, else alpha is the transmittance).
// Translucent geometry (triangles whose alpha is below 1) is not opaque: `layers` fragments per
// pixel, nearest first and all nearer than the opaque geometry there, which the march composites in
// depth order with its cloud samples (shaders/kernel/march.glsl, tl_composite). Row y holds the
// layers side by side: fragment k of pixel x at y * layers * width + k * width + x.
inline constexpr int kTranslucentLayers = 4;  // the most fragments per pixel kept (the nearest)
// A fragment is translucent when its alpha is below this (interpolating three alphas of 1 can
// round a few ulps below 1; overlay.frag holds the same number).
inline constexpr float kOpaqueAlpha = 0.9999f;
struct OpaqueLayer {
  std::vector<float> distance_m;
  std::vector<float> radiance_rgba;  // 4 floats per pixel, or empty
  int layers = 0;                    // translucent fragments per pixel held (0: none)
  std::vector<float> layer_distance_m;  // layers per pixel, m from the camera (0: none)
  std::vector<float> layer_rgba;        // 4 floats each: radiance and alpha (not premultiplied)
};

struct PreparedVolume;  // kernel/prepared_volume.hpp

// Renders one time step of a volume through the march kernel (shaders/kernel/march.glsl) in
// double. `noise` is needed when settings.noise_amount > 0 (std::invalid_argument otherwise) and is
// not read when it is 0. The globe takes its land albedo and water from `ground` when given (the
// caller loads settings.ground_texture with render::load_albedo_map: core reads no images), else
// the constant settings.ground_albedo, all land.
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
