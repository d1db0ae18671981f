// The CPU reference raymarcher.
#include "reference/raymarcher.hpp"

#include <algorithm>
#include <array>
#include <limits>
#include <stdexcept>
#include <thread>

#include <glm/glm.hpp>

#include "kernel/detail_drift.hpp"
#include "kernel/march_kernel.hpp"
#include "kernel/ms_source.hpp"
#include "kernel/prepared_volume.hpp"
#include "noise/blue_noise.hpp"
#include "physics/physics.hpp"

namespace cv::core {

ReferenceImage render_reference(const PreparedVolume& v, const Camera& cam, const Sun& sun, const MarchSettings& s,
                                const ErosionNoise* noise, const AlbedoMap* ground_map, const OpaqueLayer* opaque) {
  const std::size_t pixels = static_cast<std::size_t>(cam.width) * cam.height;
  if (opaque && (opaque->distance_m.size() != pixels || (!opaque->radiance_rgba.empty() && opaque->radiance_rgba.size() != 4 * pixels))) {
    throw std::invalid_argument("render_reference: the opaque layer is not of the image's size");
  }
  const bool eroded = s.medium.noise_amount > 0.0;
  if (eroded && !noise) throw std::invalid_argument("render_reference: noise_amount > 0 needs the erosion noise textures");
  if (eroded && !(s.medium.noise_scale_m > 0.0)) throw std::invalid_argument("render_reference: noise_scale_m must be > 0");
  if (s.medium.modelled && (!noise || noise->detail.empty())) {
    throw std::invalid_argument("render_reference: cloud_model modelled needs the erosion noise textures and their detail table");
  }
  // The very kernel the GPU runs (shaders/kernel/march.glsl), in double, over the same texels.
  kernel::f64::MarchKernel k;
  static_cast<kernel::MarchParams&>(k) =
      march_params(v, cam, sun, s, ground_map ? glm::ivec2(ground_map->width, ground_map->height) : glm::ivec2(0));
  const VolumeGrid& g = v.grid;
  const glm::ivec3 n(g.lon_deg.count, g.lat_deg.count, g.alt_m.count);
  k.u_liquid = {v.extinction.liquid_per_m.data(), n};
  k.u_ice = {v.extinction.ice_per_m.data(), n};
  // The octave gate's column depths of what the march shows (the prepared map when nothing is hidden).
  const MediumMask hidden = medium_mask(s);
  const std::vector<float> masked_columns = hidden.any() ? column_maps_for(v, hidden) : std::vector<float>{};
  k.u_column_tau = {(hidden.any() ? masked_columns : v.column_maps).data(), {v.columns.nx, v.columns.ny, int(kColumnMapLayers)},
                    int(kColumnMapChannels)};
  std::shared_ptr<const MsSource> ms;  // the two-stream source, as the GPU's (core/kernel/ms_source)
  std::vector<float> ms_moments, ms_horizontal;  // its textures, two or four channels per node
  if (s.medium.ms_two_stream) {
    ms = ms_source_for(v, ms_source_key(s, k.u_to_sun, ground_map));
    ms_moments = ms_moments_texels(*ms);
    ms_horizontal = ms_horizontal_texels(*ms);
    k.u_ms_moments = {ms_moments.data(), n, ms_moments_channels(*ms)};
    k.u_ms_lateral = !ms->i1e.empty();
    k.u_ms_horizontal = !ms_horizontal.empty() ? kernel::sampler3D{ms_horizontal.data(), n, ms_horizontal_channels(*ms)} : k.u_ms_moments;
  }
  const MsPeaks peaks = s.medium.ms_two_stream ? ms_peaks(s) : MsPeaks{};  // holds the droplets' beam table
  if (peaks.beam) k.u_ms_beam_table = peaks.beam->values.data();
  const std::shared_ptr<const std::vector<float>> slab_tables = ms_slab_on(s) ? ms_slab_tables(s) : nullptr;
  if (slab_tables) k.u_ms_slab_table = slab_tables->data();
  const BlueNoiseMask& mask = step_jitter_mask();
  k.u_jitter_mask = {mask.values.data(), {mask.n, mask.n}, 1};
  if (ground_map) k.u_ground = {ground_map->rgba.data(), {ground_map->width, ground_map->height}, 4};
  const std::vector<float> detail_shift = s.medium.modelled ? detail_shift_texels(v, k) : std::vector<float>{};
  if (s.medium.modelled) {  // the modelled cloud: the cover per node and the table over the noise tiles
    if (k.u_has_fraction) k.u_fraction = {v.extinction.fraction.data(), n};
    k.u_detail_table = {noise->detail.data(), {CV_DETAIL_COVERS + 1, CV_DETAIL_ROWS}, 2};
    k.u_detail_shift = {detail_shift.data(), {g.alt_m.count, 1}, 2};
  }
  if (eroded || s.medium.modelled) {
    k.u_noise_low = {noise->low.texels.data(), glm::ivec3(noise->low.n)};
    k.u_noise_high = {noise->high.texels.data(), glm::ivec3(noise->high.n)};
  }
  const std::vector<glm::vec2> modelled_bricks = s.medium.modelled ? medium_pyramid(v, s, noise->detail) : std::vector<glm::vec2>{};
  k.u_min_max = s.medium.modelled ? modelled_bricks.data() : v.pyramid_packed.data();
  if (opaque) {
    k.u_has_depth = true;
    k.u_depth = {opaque->distance_m.data(), {cam.width, cam.height}, 1};
    k.u_has_opaque_color = !opaque->radiance_rgba.empty();
    if (k.u_has_opaque_color) k.u_opaque = {opaque->radiance_rgba.data(), {cam.width, cam.height}, 4};
    if (opaque->layers > 0) {
      k.u_tl_count = opaque->layers;
      k.u_tl_distance = {opaque->layer_distance_m.data(), {opaque->layers * cam.width, cam.height}, 1};
      k.u_tl_color = {opaque->layer_rgba.data(), {opaque->layers * cam.width, cam.height}, 4};
    }
  }
  k.kSkipEmpty = s.features.skip_empty;
  k.kAdaptive = s.features.adaptive_steps;
  k.kAtmosphere = s.features.atmosphere;
  k.kGlobe = s.features.globe;
  k.kNoise = eroded;
  k.kTwoStream = s.medium.ms_two_stream;
  k.kTranslucent = k.u_tl_count > 0;
  k.kModelled = s.medium.modelled;
  k.kSlab = ms_slab_on(s);

  ReferenceImage img;
  img.width = cam.width;
  img.height = cam.height;
  img.radiance.assign(static_cast<std::size_t>(cam.width) * cam.height, glm::dvec3(0.0));
  img.transmittance.assign(img.radiance.size(), 1.0);
  img.cloud_depth_m.assign(img.radiance.size(), 3.0e38);
  img.first_cloud_m.assign(img.radiance.size(), 3.0e38);
  img.stats.sun_down = k.u_sun_down;
  // Rows in stripes over the cores, each with its own copy of the kernel (its counters); the image
  // does not depend on the thread count.
  const unsigned threads = std::max(1u, std::min(std::thread::hardware_concurrency(), static_cast<unsigned>(cam.height)));
  std::vector<std::array<std::uint64_t, CV_STAT_COUNT>> counts(threads);
  auto rows = [&](unsigned t) {
    kernel::f64::MarchKernel kt = k;
    auto& c = counts[t];
    c.fill(0);
    for (int py = static_cast<int>(t); py < cam.height; py += static_cast<int>(threads)) {
      for (int px = 0; px < cam.width; ++px) {
        const glm::ivec2 pixel(px, py);
        const auto ray = kt.march_ray(pixel);
        auto state = kt.march_start();
        kt.march_advance(ray, pixel, 0, std::numeric_limits<int>::max(), state);
        const glm::dvec4 out = kt.march_finish(ray, pixel, state);
        const std::size_t idx = static_cast<std::size_t>(py) * cam.width + px;
        img.radiance[idx] = glm::dvec3(out);
        img.transmittance[idx] = out.w;
        img.cloud_depth_m[idx] = state.t_half;
        img.first_cloud_m[idx] = state.t_first;
        for (int i = 0; i < CV_STAT_COUNT; ++i) c[i] += kt.g_stats[i], kt.g_stats[i] = 0;
      }
    }
  };
  if (threads == 1) {
    rows(0);
  } else {
    std::vector<std::thread> pool;
    for (unsigned t = 0; t < threads; ++t) pool.emplace_back(rows, t);
    for (auto& th : pool) th.join();
  }
  for (const auto& c : counts) {
    img.stats.view_samples += c[CV_STAT_VIEW_SAMPLES];
    img.stats.view_skipped += c[CV_STAT_VIEW_SKIPPED];
    img.stats.bricks_jumped += c[CV_STAT_BRICKS_JUMPED];
    img.stats.sun_samples += c[CV_STAT_SUN_SAMPLES];
    img.stats.sun_skipped += c[CV_STAT_SUN_SKIPPED];
    img.stats.rays_missed += c[CV_STAT_RAYS_MISSED];
    img.stats.octave_terms += c[CV_STAT_OCTAVE_TERMS];
    img.stats.octave_terms_full += c[CV_STAT_OCTAVE_TERMS_FULL];
  }
  return img;
}

ReferenceImage render_reference(const VolumeGrid& grid, const GridMeanExtinction& medium, const Camera& cam, const Sun& sun,
                                const MarchSettings& settings, const ErosionNoise* noise, const AlbedoMap* ground) {
  return render_reference(prepare_volume(grid, medium), cam, sun, settings, noise, ground);
}

}  // namespace cv::core
