// The Monte Carlo reference: volumetric path tracing of the scene render_reference draws (same
// medium lookup, phase functions, camera and sun), with full multiple scattering, so the
// raymarcher's approximations (octaves, steps) can be measured against the transport solution.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include <glm/vec3.hpp>

#include "noise/noise.hpp"
#include "reference/path_rng.hpp"
#include "reference/raymarcher.hpp"
#include "volume/cloud_volume.hpp"

namespace cv::kernel::f64 {
struct TrackKernel;
}

namespace cv::core {

struct MonteCarloSettings {
  // Scattering events per path (cloud and ground together). 1 = single scattering, the quantity
  // render_reference computes with octaves = 1. Paths cut at this depth are counted in
  // MonteCarloStats::truncated so an image states whether the cut matters.
  int max_bounces = 1000;
  // Russian roulette on the path throughput from this depth on. Clouds do not absorb, so in the
  // clouds-only configuration it never fires; it ends paths whose throughput the ground has reduced.
  int roulette_after = 4;
  // Per-brick majorants from the extinction pyramid; false: the grid's largest extinction
  // everywhere. Either gives the same expectation. Off by default: a pyramid query costs several
  // medium lookups and its brick-exit distances are conservative (short near brick faces), so on
  // the standard scenes it was 2-5x slower than null collisions against the global majorant
  // (docs/physics.md, "Monte Carlo reference").
  bool brick_majorants = false;
  // Multiple importance sampling of the droplets' forward peak toward the sun (docs/physics.md,
  // "A reference that converges"): at every cloud vertex holding liquid a second direction is drawn
  // around the sun from the peak's own lobe and starts a branch of the path, the two continuations
  // weighted by the balance heuristic (splitting; the GPU path tracer weights only the next-event
  // estimate at the vertex that direction reaches). Unbiased either way; without
  // it, light scattered once through the peak (p up to ~5e3 /sr) is found only by rare paths and
  // droplet-cloud references do not converge as 1/sqrt(N). Only with the Mie phase (HG has no peak).
  bool peak_mis = true;
  unsigned threads = 0;  // 0: std::thread::hardware_concurrency()
  std::uint64_t seed = 1;
};

// What the tracer did, summed over all samples (integers: the same for any thread count).
struct MonteCarloStats {
  std::uint64_t paths = 0;
  std::uint64_t scatterings = 0;        // real collisions in cloud, plus ground bounces
  std::uint64_t null_collisions = 0;    // tentative collisions rejected by delta tracking
  std::uint64_t shadow_lookups = 0;     // medium lookups of ratio tracking toward the sun
  std::uint64_t truncated = 0;          // paths stopped at max_bounces while still in flight
  std::uint64_t roulette_killed = 0;    // paths ended by Russian roulette
  std::uint64_t majorant_exceeded = 0;  // lookups above their majorant (a bug if ever non-zero)
  std::uint64_t peak_samples = 0;       // branches started around the sun (peak_mis; the GPU: directions drawn there)
  void add(const MonteCarloStats& o);
};

// A progressive estimate: running sums per pixel, from which the mean and its standard error follow.
struct MonteCarloImage {
  int width = 0, height = 0;
  std::uint64_t spp = 0;                // samples per pixel so far
  std::vector<glm::dvec3> sum, sum_sq;  // of per-sample radiance (per unit sun irradiance times it)
  std::vector<double> lum_sum, lum_sq;  // of per-sample luminance (Rec. 709 weights)
  MonteCarloStats stats;

  glm::dvec3 mean(std::size_t i) const;
  glm::dvec3 standard_error(std::size_t i) const;  // of the mean, per channel
  double luminance(std::size_t i) const;
  double luminance_standard_error(std::size_t i) const;
  // Mean over pixels of standard error / mean luminance, over pixels whose mean luminance is at
  // least `floor_fraction` of the image's largest (dark pixels have no meaningful relative error).
  double mean_relative_standard_error(double floor_fraction = 0.05) const;
  std::vector<glm::dvec3> radiance() const;  // the means
  // Each pixel's luminance variance of the mean (the squared standard error; 0 where it is not
  // finite, as before the second sample), as image_error takes it.
  std::vector<double> luminance_variance() const;
  // The image-mean luminance's relative standard error: sqrt(sum of the variances) / sum of the
  // means (0 for a black image).
  double image_mean_relative_error() const;
};

class MonteCarloRenderer {
 public:
  // `noise` is needed when march.noise_amount > 0. `ground_map` (land albedo and water fraction,
  // as render_reference takes it) is the globe's ground; without it the constant ground_albedo.
  // With march.atmosphere the sunlight is reddened by the air and the sky lights the paths that
  // leave (path.glsl); the air between vertices is not modelled.
  MonteCarloRenderer(const VolumeGrid& grid, const GridMeanExtinction& medium, const Camera& cam,
                     const Sun& sun, const MarchSettings& march, const MonteCarloSettings& mc,
                     const ErosionNoise* noise = nullptr, const AlbedoMap* ground_map = nullptr);

  // An empty accumulator for this camera.
  MonteCarloImage start() const;
  // Adds `spp` samples to every pixel, continuing the sample indices already in `img`: two calls
  // of n give bit for bit the image of one call of 2n, on any number of threads.
  void add_samples(MonteCarloImage& img, int spp) const;

  // The pieces, public for the validation tests. Rays start at Earth-centred p (m), unit d.
  // Distance to the first real collision by delta tracking, or +inf when the ray leaves the clouds
  // (through the top, or down to the ground: *ground_m then holds the distance to it, else +inf).
  double free_path(const glm::dvec3& p, const glm::dvec3& d, PathRng& rng, MonteCarloStats& st,
                   double* ground_m = nullptr) const;
  // Transmittance of the clouds from p along d by ratio tracking (unbiased, noisy); 0 if the ray
  // meets the Earth.
  double transmittance(const glm::dvec3& p, const glm::dvec3& d, PathRng& rng, MonteCarloStats& st) const;
  // How a path ended, for energy bookkeeping.
  enum class End { Space, Ground, Truncated, Roulette };
  struct PathResult {
    glm::dvec3 radiance{0.0};  // per unit sun irradiance
    glm::dvec3 weight{1.0};    // the throughput the path carried when it ended
    glm::dvec3 absorbed{0.0};  // throughput the ground took out (1 - albedo of what reached it), branches included
    glm::dvec3 escaped{0.0};   // throughput that left into space, the peak technique's branches included
    glm::dvec3 grounded{0.0};  // throughput that ended on a ground that takes it all (no globe), the same
    End end = End::Space;      // how the path itself ended (its branches may end otherwise)
    int scatterings = 0;       // the path's own vertices
  };
  // One path from p along d (the first segment is the view ray): next-event estimation toward the sun
  // at every vertex, new directions by the phase functions, roulette, until it ends.
  PathResult trace(glm::dvec3 p, glm::dvec3 d, PathRng& rng, MonteCarloStats& st) const;

  double majorant_per_m() const;

 private:
  const VolumeGrid& grid_;
  const GridMeanExtinction& ext_;
  Camera cam_;
  Sun sun_;
  MarchSettings march_;
  MonteCarloSettings mc_;
  const ErosionNoise* noise_ = nullptr;
  const AlbedoMap* ground_map_ = nullptr;
  std::shared_ptr<const PreparedVolume> volume_;
  // The march kernel's medium, tracking and path over volume_ (reference/track_kernel.hpp); its
  // functions called here write nothing, so the threads share it.
  std::shared_ptr<kernel::f64::TrackKernel> kernel_;
  std::shared_ptr<const std::vector<float>> detail_shift_;  // the kernel's u_detail_shift texels (the modelled cloud)
  std::shared_ptr<const std::vector<glm::vec2>> bricks_;     // the modelled cloud's brick bounds (core::medium_pyramid)
};

// One call: a fresh accumulator with `spp` samples per pixel.
MonteCarloImage render_monte_carlo(const VolumeGrid& grid, const GridMeanExtinction& medium,
                                   const Camera& cam, const Sun& sun, const MarchSettings& march,
                                   const MonteCarloSettings& mc, int spp,
                                   const ErosionNoise* noise = nullptr, const AlbedoMap* ground_map = nullptr);

}  // namespace cv::core
