// The Monte Carlo reference: delta tracking, ratio-tracked sun rays, phase sampling, roulette.
#include "reference/monte_carlo.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>
#include <thread>

#include <glm/glm.hpp>

#include "geo/geodesy.hpp"
#include "kernel/detail_drift.hpp"
#include "kernel/prepared_volume.hpp"
#include "physics/physics.hpp"
#include "reference/track_kernel.hpp"

namespace cv::core {
namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
const glm::dvec3 kLumWeights(0.2126, 0.7152, 0.0722);


}  // namespace

void MonteCarloStats::add(const MonteCarloStats& o) {
  paths += o.paths;
  scatterings += o.scatterings;
  null_collisions += o.null_collisions;
  shadow_lookups += o.shadow_lookups;
  truncated += o.truncated;
  roulette_killed += o.roulette_killed;
  majorant_exceeded += o.majorant_exceeded;
  peak_samples += o.peak_samples;
}

// ---- accumulator ----

glm::dvec3 MonteCarloImage::mean(std::size_t i) const {
  return spp ? sum[i] / static_cast<double>(spp) : glm::dvec3(0.0);
}

glm::dvec3 MonteCarloImage::standard_error(std::size_t i) const {
  if (spp < 2) return glm::dvec3(kInf);
  const double n = static_cast<double>(spp);
  const glm::dvec3 m = sum[i] / n;
  // Sample variance (n - 1 in the denominator), then the variance of the mean.
  const glm::dvec3 var = glm::max(sum_sq[i] - n * m * m, glm::dvec3(0.0)) / (n - 1.0);
  return glm::sqrt(var / n);
}

double MonteCarloImage::luminance(std::size_t i) const {
  return spp ? lum_sum[i] / static_cast<double>(spp) : 0.0;
}

double MonteCarloImage::luminance_standard_error(std::size_t i) const {
  if (spp < 2) return kInf;
  const double n = static_cast<double>(spp), m = lum_sum[i] / n;
  return std::sqrt(std::max(lum_sq[i] - n * m * m, 0.0) / (n - 1.0) / n);
}

std::vector<double> MonteCarloImage::luminance_variance() const {
  std::vector<double> var(lum_sum.size(), 0.0);
  for (std::size_t i = 0; i < var.size(); ++i) {
    const double se = luminance_standard_error(i);
    var[i] = std::isfinite(se) ? se * se : 0.0;
  }
  return var;
}

double MonteCarloImage::image_mean_relative_error() const {
  double lum = 0.0, var = 0.0;
  for (std::size_t i = 0; i < lum_sum.size(); ++i) {
    const double se = luminance_standard_error(i);
    lum += luminance(i);
    var += std::isfinite(se) ? se * se : 0.0;
  }
  return lum > 0.0 ? std::sqrt(var) / lum : 0.0;
}

double MonteCarloImage::mean_relative_standard_error(double floor_fraction) const {
  double top = 0.0;
  for (std::size_t i = 0; i < lum_sum.size(); ++i) top = std::max(top, luminance(i));
  double total = 0.0;
  int count = 0;
  for (std::size_t i = 0; i < lum_sum.size(); ++i) {
    const double l = luminance(i);
    if (l > 0.0 && l >= floor_fraction * top) {
      total += luminance_standard_error(i) / l;
      ++count;
    }
  }
  return count ? total / count : 0.0;
}

std::vector<glm::dvec3> MonteCarloImage::radiance() const {
  std::vector<glm::dvec3> out(sum.size());
  for (std::size_t i = 0; i < sum.size(); ++i) out[i] = mean(i);
  return out;
}

// ---- random numbers ----


// ---- the tracer ----

MonteCarloRenderer::MonteCarloRenderer(const VolumeGrid& grid, const GridMeanExtinction& ext,
                                       const Camera& cam, const Sun& sun, const MarchSettings& march,
                                       const MonteCarloSettings& mc, const ErosionNoise* noise,
                                       const AlbedoMap* ground_map)
    : grid_(grid),
      ext_(ext),
      cam_(cam),
      sun_(sun),
      march_(march),
      mc_(mc),
      noise_(noise),
      ground_map_(ground_map) {
  if (mc.max_bounces < 1) throw std::invalid_argument("monte carlo: max_bounces must be >= 1");
  if (march.medium.noise_amount > 0.0 && !noise) throw std::invalid_argument("monte carlo: noise_amount > 0 needs the erosion noise textures");
  if (march.medium.modelled && (!noise || noise->detail.empty())) {
    throw std::invalid_argument("monte carlo: cloud_model modelled needs the erosion noise textures and their detail table");
  }
  // The medium as the march kernel reads it (shaders/kernel/march.glsl medium_at_point), erosion
  // included, and the kernel's tracking (tracking.glsl) over it.
  volume_ = std::make_shared<const PreparedVolume>(prepare_volume(grid, ext));
  kernel_ = std::make_shared<kernel::f64::TrackKernel>();
  kernel::f64::TrackKernel& k = *kernel_;
  static_cast<kernel::MarchParams&>(k) =
      march_params(*volume_, cam, sun, march, ground_map ? glm::ivec2(ground_map->width, ground_map->height) : glm::ivec2(0));
  if (ground_map) k.u_ground = {ground_map->rgba.data(), {ground_map->width, ground_map->height}, 4};
  const glm::ivec3 n(grid.lon_deg.count, grid.lat_deg.count, grid.alt_m.count);
  k.u_liquid = {volume_->extinction.liquid_per_m.data(), n};
  k.u_ice = {volume_->extinction.ice_per_m.data(), n};
  if (march.medium.modelled) {  // the modelled cloud's own brick bounds
    bricks_ = std::make_shared<const std::vector<glm::vec2>>(medium_pyramid(*volume_, march, noise->detail));
    k.u_min_max = bricks_->data();
  } else {
    k.u_min_max = volume_->pyramid_packed.data();
  }
  k.kNoise = march.medium.noise_amount > 0.0;
  k.kModelled = march.medium.modelled;
  // The column maps: the ground (layer masks) and the modelled cloud's type per column.
  k.u_column_tau = {volume_->column_maps.data(), {volume_->columns.nx, volume_->columns.ny, int(kColumnMapLayers)}, int(kColumnMapChannels)};
  if (k.kModelled) {  // the modelled cloud: the cover per node and the table over the noise tiles
    if (k.u_has_fraction) k.u_fraction = {volume_->extinction.fraction.data(), n};
    k.u_detail_table = {noise->detail.data(), {CV_DETAIL_COVERS + 1, CV_DETAIL_ROWS}, 2};
    detail_shift_ = std::make_shared<const std::vector<float>>(detail_shift_texels(*volume_, k));
    k.u_detail_shift = {detail_shift_->data(), {grid.alt_m.count, 1}, 2};
  }
  if (k.kNoise || k.kModelled) {
    k.u_noise_low = {noise->low.texels.data(), glm::ivec3(noise->low.n)};
    k.u_noise_high = {noise->high.texels.data(), glm::ivec3(noise->high.n)};
  }
  // Trilinear weights are convex, so liquid + ice anywhere is at most the largest node sum; erosion
  // only lowers extinction (erode_extinction keeps at most the data's value). The modelled cloud
  // exceeds the data inside its shapes: its own bound (medium_majorant), and no brick bounds (the
  // pyramid's are the data's).
  k.u_track_majorant = medium_majorant(*volume_, march, noise ? noise->detail : std::vector<float>{});
  if (!std::isfinite(k.u_track_majorant)) {
    throw std::invalid_argument("monte carlo: the modelled cloud has extinction where the cloud fraction is 0: no majorant bounds it");
  }
  k.u_track_bricks = mc.brick_majorants;
  k.u_path_max_bounces = mc.max_bounces;
  k.u_path_roulette_after = mc.roulette_after;
  k.u_path_peak_mis = mc.peak_mis;
  k.kGlobe = march.features.globe;
  k.kAtmosphere = march.features.atmosphere;
}

double MonteCarloRenderer::majorant_per_m() const { return kernel_->u_track_majorant; }


double MonteCarloRenderer::free_path(const glm::dvec3& p, const glm::dvec3& d, PathRng& rng,
                                     MonteCarloStats& st, double* ground_m) const {
  kernel::f64::TrackKernel::TrackCounts c = kernel_->track_counts();
  double t_ground;
  const double t = kernel_->path_free_path(p, d, rng, c, t_ground);
  if (ground_m) *ground_m = t_ground < 3.0e38 ? t_ground : kInf;
  st.null_collisions += c.null_collisions;
  st.majorant_exceeded += c.exceeded;
  return t < 3.0e38 ? t : kInf;
}

double MonteCarloRenderer::transmittance(const glm::dvec3& p, const glm::dvec3& d, PathRng& rng,
                                         MonteCarloStats& st) const {
  kernel::f64::TrackKernel::TrackCounts c = kernel_->track_counts();
  const double tr = kernel_->path_transmittance(p, d, rng, c);
  st.shadow_lookups += c.lookups;
  st.majorant_exceeded += c.exceeded;
  return tr;
}

// The path is the kernel's (shaders/kernel/path.glsl), the one the GPU path tracer runs.
MonteCarloRenderer::PathResult MonteCarloRenderer::trace(glm::dvec3 p, glm::dvec3 d, PathRng& rng,
                                                         MonteCarloStats& st) const {
  kernel::f64::TrackKernel::TrackCounts c = kernel_->track_counts();
  kernel::f64::TrackKernel::PathCounts pc = kernel_->path_counts();
  kernel::f64::TrackKernel::path_branches().clear();  // trace_path empties it; a path never starts on another's branches
  const kernel::f64::TrackKernel::PathResult k = kernel_->trace_path(p, d, rng, c, pc);
  ++st.paths;
  st.scatterings += static_cast<std::uint64_t>(k.scatterings + k.scatterings_branches);
  st.null_collisions += c.null_collisions;
  st.shadow_lookups += c.lookups;
  st.majorant_exceeded += c.exceeded;
  st.truncated += pc.truncated;
  st.roulette_killed += pc.roulette_killed;
  st.peak_samples += pc.peak_samples;
  PathResult r;
  r.radiance = k.radiance;
  r.weight = k.weight;
  r.absorbed = k.absorbed;
  r.escaped = k.escaped;
  r.grounded = k.grounded;
  r.scatterings = k.scatterings;
  r.end = k.end == CV_PATH_GROUND ? End::Ground
          : k.end == CV_PATH_TRUNCATED ? End::Truncated
          : k.end == CV_PATH_ROULETTE ? End::Roulette
                                      : End::Space;
  return r;
}

MonteCarloImage MonteCarloRenderer::start() const {
  MonteCarloImage img;
  img.width = cam_.width;
  img.height = cam_.height;
  const std::size_t n = static_cast<std::size_t>(cam_.width) * static_cast<std::size_t>(cam_.height);
  img.sum.assign(n, glm::dvec3(0.0));
  img.sum_sq.assign(n, glm::dvec3(0.0));
  img.lum_sum.assign(n, 0.0);
  img.lum_sq.assign(n, 0.0);
  return img;
}

void MonteCarloRenderer::add_samples(MonteCarloImage& img, int spp) const {
  if (img.width != cam_.width || img.height != cam_.height ||
      img.sum.size() != static_cast<std::size_t>(cam_.width) * cam_.height) {
    throw std::invalid_argument("monte carlo: the accumulator was not made for this camera");
  }
  if (spp <= 0) return;
  const std::uint64_t first = img.spp;
  unsigned threads = mc_.threads ? mc_.threads : std::max(1u, std::thread::hardware_concurrency());
  threads = std::min<unsigned>(threads, static_cast<unsigned>(cam_.height));
  std::vector<MonteCarloStats> stats(threads);
  std::atomic<int> next_row{0};
  auto work = [&](unsigned w) {
    for (int py = next_row++; py < cam_.height; py = next_row++) {
      for (int px = 0; px < cam_.width; ++px) {
        // The kernel's start of a path (path_camera_origin): a camera above the grid starts where the
        // ray enters it, on the exact sphere. With anti-aliasing each sample's ray passes through a
        // uniform point of the pixel (the box filter the march's accumulated frames tend to), drawn
        // first from the sample's own stream; else every sample takes the centre's ray.
        const bool area = kernel_->u_anti_alias;
        const glm::ivec2 pixel(px, py);
        auto start = [&](const glm::dvec3& d, glm::dvec3& o, glm::dvec3& sky) {
          bool misses = false;
          o = kernel_->path_camera_origin(d, misses);
          sky = glm::dvec3(0.0);  // a ray that misses the shell sees the sky (none without air)
          if (misses) {
            kernel::f64::TrackKernel::TrackCounts c = kernel_->track_counts();
            sky = kernel_->path_miss(d, c);
          }
          return misses;
        };
        const glm::dvec3 d_centre = kernel_->pixel_direction(pixel);
        glm::dvec3 o_centre(0.0), sky_centre(0.0);
        const bool misses_centre = area ? false : start(d_centre, o_centre, sky_centre);
        const std::size_t idx = static_cast<std::size_t>(py) * cam_.width + px;
        // Samples in index order into this pixel's sums: the same sums whichever thread does it.
        for (std::uint64_t s = first; s < first + static_cast<std::uint64_t>(spp); ++s) {
          PathRng rng(mc_.seed, idx, s);
          glm::dvec3 d = d_centre, o = o_centre, v = sky_centre;
          bool misses = misses_centre;
          if (area) {
            const double jx = rng.uniform() - 0.5, jy = rng.uniform() - 0.5;
            d = kernel_->pixel_direction_jittered(pixel, glm::dvec2(jx, jy) / double(kernel_->u_pixel_block));
            misses = start(d, o, v);
          }
          if (!misses) v = trace(o, d, rng, stats[w]).radiance;
          const double l = glm::dot(v, kLumWeights);
          img.sum[idx] += v;
          img.sum_sq[idx] += v * v;
          img.lum_sum[idx] += l;
          img.lum_sq[idx] += l * l;
        }
      }
    }
  };
  std::vector<std::thread> pool;
  for (unsigned w = 1; w < threads; ++w) pool.emplace_back(work, w);
  work(0);
  for (auto& th : pool) th.join();
  for (const auto& s : stats) img.stats.add(s);
  img.spp += static_cast<std::uint64_t>(spp);
}

MonteCarloImage render_monte_carlo(const VolumeGrid& grid, const GridMeanExtinction& medium,
                                   const Camera& cam, const Sun& sun, const MarchSettings& march,
                                   const MonteCarloSettings& mc, int spp, const ErosionNoise* noise,
                                   const AlbedoMap* ground_map) {
  const MonteCarloRenderer r(grid, medium, cam, sun, march, mc, noise, ground_map);
  MonteCarloImage img = r.start();
  r.add_samples(img, spp);
  return img;
}

}  // namespace cv::core
