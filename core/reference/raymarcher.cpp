// The CPU reference raymarcher.
#include "reference/raymarcher.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <glm/glm.hpp>

#include <array>
#include <limits>
#include <thread>

#include "geo/geodesy.hpp"
#include "kernel/march_kernel.hpp"
#include "kernel/prepared_volume.hpp"
#include "noise/blue_noise.hpp"
#include "physics/physics.hpp"

namespace cv::core {
namespace {
namespace p64 = cv::physics::f64;
constexpr double kDeg = 3.14159265358979323846 / 180.0;
}  // namespace

double sun_step_limit_m(const VolumeGrid& grid, const CloudLayer& layer, const MarchSettings& settings) {
  const glm::dvec3 start(grid.lon_deg.start, grid.lat_deg.start, grid.alt_m.start);
  const glm::dvec3 step(grid.lon_deg.step, grid.lat_deg.step, grid.alt_m.step);
  const glm::dvec3 count(grid.lon_deg.count, grid.lat_deg.count, grid.alt_m.count);
  const double floor_m = layer.empty ? grid.alt_m.start : layer.bottom_m;
  return p64::sun_step_limit_m(settings.max_sun_step_m, start, step, count, grid.earth_radius_m + std::max(floor_m, 0.0));
}

int max_sun_march_steps(int sun_steps, double max_step_m, double r0_m, double bottom_m, double top_m,
                        double mu_sun_min) {
  const int ss = std::max(sun_steps, 1);
  const double rb = r0_m + std::max(bottom_m, 0.0), rt = r0_m + std::max(top_m, bottom_m);
  if (mu_sun_min > 0.0) {
    // One segment, up through the top; 2 more steps for float rounding on the GPU.
    const double mu = std::min(mu_sun_min, 1.0);
    const double len_m = -rb * mu + std::sqrt(std::max(rb * rb * mu * mu + rt * rt - rb * rb, 0.0));
    const double steps = max_step_m > 0.0 ? std::max(static_cast<double>(ss), std::ceil(len_m / max_step_m)) : ss;
    return static_cast<int>(std::min(steps, static_cast<double>(std::max(p64::CV_SUN_SEGMENT_STEPS_MAX, ss)))) + 2;
  }
  if (!(max_step_m > 0.0)) return 2 * ss;
  const double chord_m = 2.0 * std::sqrt(std::max(rt * rt - rb * rb, 0.0));
  // Segments of lengths L0 + L1 <= chord: both at sun_steps (2 ss), one of them longer
  // (ss + L/step + 1), or both (chord/step + 2); 2 more for float rounding on the GPU.
  const double by_length = static_cast<double>(ss) + std::ceil(chord_m / max_step_m) + 4.0;
  const int cap = 2 * std::max(p64::CV_SUN_SEGMENT_STEPS_MAX, ss);
  return static_cast<int>(std::min(static_cast<double>(cap), std::max(2.0 * ss, by_length)));
}

double largest_extinction(const GridMeanExtinction& medium) {
  double m = 0.0;
  for (std::size_t i = 0; i < std::max(medium.liquid_per_m.size(), medium.ice_per_m.size()); ++i) {
    m = std::max(m, (i < medium.liquid_per_m.size() ? double(medium.liquid_per_m[i]) : 0.0) +
                        (i < medium.ice_per_m.size() ? double(medium.ice_per_m[i]) : 0.0));
  }
  return m;
}

glm::dvec3 AlbedoMap::at(double lat_rad, double lon_rad) const {
  const glm::dvec4 c = p64::equirect_texel(lat_rad, lon_rad, width, height);
  const int x0 = static_cast<int>(c.x), y0 = static_cast<int>(c.y);
  const int x1 = (x0 + 1) % width, y1 = std::min(y0 + 1, height - 1);
  auto texel = [&](int x, int y) {
    const std::size_t i = (static_cast<std::size_t>(y) * width + x) * 3;
    return glm::dvec3(rgb[i], rgb[i + 1], rgb[i + 2]);
  };
  const glm::dvec3 a = glm::mix(texel(x0, y0), texel(x1, y0), c.z), b = glm::mix(texel(x0, y1), texel(x1, y1), c.z);
  return glm::mix(a, b, c.w);
}

GridMeanExtinction grid_mean_extinction(const VolumeGrid& grid, const TimeStepData& data) {
  GridMeanExtinction m;
  const auto& cf = data[Field::CloudFraction];
  auto product = [&](const std::vector<float>& ext, std::vector<float>& out) {
    out.assign(grid.points(), 0.0f);
    if (ext.empty()) return;
    for (std::size_t p = 0; p < out.size(); ++p) {
      const float c = cf.empty() ? 1.0f : cf[p];
      const float v = c * ext[p];
      // NaN, negative and fill values (netCDF's 9.96921e36 left in a field, or a product with one)
      // are no data: no cloud. The comparison is false for NaN.
      out[p] = v >= 0.0f && v < kMaxGridMeanExtinctionPerM ? v : 0.0f;
    }
  };
  product(data[Field::ExtinctionLiquid], m.liquid_per_m);
  product(data[Field::ExtinctionIce], m.ice_per_m);
  return m;
}

CloudLayer cloud_layer(const VolumeGrid& grid, const GridMeanExtinction& medium) {
  const std::size_t per_level = grid.columns();
  int lo = -1, hi = -1;
  for (int k = 0; k < grid.alt_m.count; ++k) {
    bool any = false;
    for (const std::vector<float>* f : {&medium.liquid_per_m, &medium.ice_per_m}) {
      if (f->empty()) continue;
      const auto first = f->begin() + static_cast<std::ptrdiff_t>(per_level * k);
      any = any || std::any_of(first, first + static_cast<std::ptrdiff_t>(per_level), [](float v) { return v > 0.0f; });
    }
    if (any) {
      if (lo < 0) lo = k;
      hi = k;
    }
  }
  CloudLayer l;
  if (lo < 0) return l;
  l.empty = false;
  l.bottom_m = grid.alt_m.at(std::max(lo - 1, 0));
  l.top_m = grid.alt_m.at(std::min(hi + 1, grid.alt_m.count - 1));
  return l;
}

CameraFrame camera_frame(const Camera& cam) {
  const geo::EnuFrame f = geo::sphere_enu(cam.lat_deg, cam.lon_deg);
  const double h = cam.heading_deg * kDeg, pitch = cam.pitch_deg * kDeg;
  CameraFrame c;
  c.forward = std::cos(pitch) * (std::sin(h) * f.east + std::cos(h) * f.north) + std::sin(pitch) * f.up;
  // Right is the heading turned 90 degrees clockwise, level with the ground: defined also when
  // looking straight up or down, where the heading still sets which way the image turns.
  c.right = std::cos(h) * f.east - std::sin(h) * f.north;
  c.up = glm::cross(c.right, c.forward);
  c.tan_half = std::tan(0.5 * cam.fov_deg * kDeg);
  return c;
}

glm::dvec3 camera_ray(const Camera& cam, int px, int py) {
  const CameraFrame c = camera_frame(cam);
  const double x = (2.0 * (px + 0.5) / cam.width - 1.0) * c.tan_half;
  const double y = (1.0 - 2.0 * (py + 0.5) / cam.height) * c.tan_half * cam.height / cam.width;
  return glm::normalize(c.forward + x * c.right + y * c.up);
}

glm::dvec3 camera_ecef(const Camera& cam, double r0_m) {
  return geo::sphere_to_ecef({cam.lat_deg, cam.lon_deg, cam.alt_m}, r0_m);
}

glm::dmat4 camera_view_matrix(const Camera& cam) {
  const CameraFrame c = camera_frame(cam);
  // Rows: right, up, -forward (glm is column-major: m[column][row]).
  glm::dmat4 m(1.0);
  for (int i = 0; i < 3; ++i) {
    m[i][0] = c.right[i];
    m[i][1] = c.up[i];
    m[i][2] = -c.forward[i];
  }
  return m;
}

glm::dmat4 camera_projection_matrix(const Camera& cam, double near_m, double far_m) {
  const CameraFrame c = camera_frame(cam);
  const double aspect = static_cast<double>(cam.height) / cam.width;
  glm::dmat4 m(0.0);
  m[0][0] = 1.0 / c.tan_half;
  m[1][1] = -1.0 / (c.tan_half * aspect);  // row 0 at the top
  m[2][2] = -(far_m + near_m) / (far_m - near_m);
  m[2][3] = -1.0;
  m[3][2] = -2.0 * far_m * near_m / (far_m - near_m);
  return m;
}

glm::dvec3 grid_centre_ecef(const VolumeGrid& grid) {
  const double lat = grid.lat_deg.start + 0.5 * (grid.lat_deg.last() - grid.lat_deg.start);
  const double lon = grid.lon_deg.start + 0.5 * (grid.lon_deg.last() - grid.lon_deg.start);
  return geo::sphere_to_ecef({lat, lon, 0.0}, grid.earth_radius_m);
}

ReferenceImage render_reference(const PreparedVolume& v, const Camera& cam, const Sun& sun, const MarchSettings& s,
                                const ErosionNoise* noise, const AlbedoMap* ground_map, const OpaqueLayer* opaque) {
  const std::size_t pixels = static_cast<std::size_t>(cam.width) * cam.height;
  if (opaque && (opaque->distance_m.size() != pixels || (!opaque->radiance_rgba.empty() && opaque->radiance_rgba.size() != 4 * pixels))) {
    throw std::invalid_argument("render_reference: the opaque layer is not of the image's size");
  }
  const bool eroded = s.noise_amount > 0.0;
  if (eroded && !noise) throw std::invalid_argument("render_reference: noise_amount > 0 needs the erosion noise textures");
  if (eroded && !(s.noise_scale_m > 0.0)) throw std::invalid_argument("render_reference: noise_scale_m must be > 0");
  // The very kernel the GPU runs (shaders/kernel/march.glsl), in double, over the same texels.
  kernel::f64::MarchKernel k;
  static_cast<kernel::MarchParams&>(k) =
      march_params(v, cam, sun, s, ground_map ? glm::ivec2(ground_map->width, ground_map->height) : glm::ivec2(0));
  const VolumeGrid& g = v.grid;
  const glm::ivec3 n(g.lon_deg.count, g.lat_deg.count, g.alt_m.count);
  k.u_liquid = {v.extinction.liquid_per_m.data(), n};
  k.u_ice = {v.extinction.ice_per_m.data(), n};
  k.u_column_tau = {v.columns.tau.data(), {v.columns.nx, v.columns.ny}, 1};
  const BlueNoiseMask& mask = step_jitter_mask();
  k.u_jitter_mask = {mask.values.data(), {mask.n, mask.n}, 1};
  if (ground_map) k.u_ground = {ground_map->rgb.data(), {ground_map->width, ground_map->height}, 3};
  if (eroded) {
    k.u_noise_low = {noise->low.texels.data(), glm::ivec3(noise->low.n)};
    k.u_noise_high = {noise->high.texels.data(), glm::ivec3(noise->high.n)};
  }
  k.u_min_max = v.pyramid_packed.data();
  if (opaque) {
    k.u_has_depth = true;
    k.u_depth = {opaque->distance_m.data(), {cam.width, cam.height}, 1};
    k.u_has_opaque_color = !opaque->radiance_rgba.empty();
    if (k.u_has_opaque_color) k.u_opaque = {opaque->radiance_rgba.data(), {cam.width, cam.height}, 4};
  }
  k.kSkipEmpty = s.skip_empty;
  k.kAdaptive = s.adaptive_steps;
  k.kAtmosphere = s.atmosphere;
  k.kGlobe = s.globe;
  k.kNoise = eroded;

  ReferenceImage img;
  img.width = cam.width;
  img.height = cam.height;
  img.radiance.assign(static_cast<std::size_t>(cam.width) * cam.height, glm::dvec3(0.0));
  img.transmittance.assign(img.radiance.size(), 1.0);
  img.cloud_depth_m.assign(img.radiance.size(), 3.0e38);
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
