// The Monte Carlo reference: delta tracking, ratio-tracked sun rays, phase sampling, roulette.
#include "reference/monte_carlo.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>
#include <thread>

#include <glm/glm.hpp>

#include "geo/geodesy.hpp"
#include "kernel/prepared_volume.hpp"
#include "physics/physics.hpp"
#include "reference/track_kernel.hpp"

namespace cv::core {
namespace {
namespace p64 = cv::physics::f64;
constexpr double kDeg = 3.14159265358979323846 / 180.0;
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
                                       const MonteCarloSettings& mc, const ErosionNoise* noise)
    : grid_(grid),
      ext_(ext),
      cam_(cam),
      sun_(sun),
      march_(march),
      mc_(mc),
      noise_(noise) {
  if (march.features.atmosphere) {
    throw std::invalid_argument(
        "monte carlo: atmosphere on is not modelled (clouds only, optionally the globe)");
  }
  if (mc.max_bounces < 1) throw std::invalid_argument("monte carlo: max_bounces must be >= 1");
  if (march.medium.noise_amount > 0.0 && !noise) throw std::invalid_argument("monte carlo: noise_amount > 0 needs the erosion noise textures");
  // The medium as the march kernel reads it (shaders/kernel/march.glsl medium_at_point), erosion
  // included, and the kernel's tracking (tracking.glsl) over it.
  volume_ = std::make_shared<const PreparedVolume>(prepare_volume(grid, ext));
  kernel_ = std::make_shared<kernel::f64::TrackKernel>();
  kernel::f64::TrackKernel& k = *kernel_;
  static_cast<kernel::MarchParams&>(k) = march_params(*volume_, cam, sun, march);
  const glm::ivec3 n(grid.lon_deg.count, grid.lat_deg.count, grid.alt_m.count);
  k.u_liquid = {volume_->extinction.liquid_per_m.data(), n};
  k.u_ice = {volume_->extinction.ice_per_m.data(), n};
  k.u_min_max = volume_->pyramid_packed.data();
  k.kNoise = march.medium.noise_amount > 0.0;
  if (k.kNoise) {
    k.u_noise_low = {noise->low.texels.data(), glm::ivec3(noise->low.n)};
    k.u_noise_high = {noise->high.texels.data(), glm::ivec3(noise->high.n)};
  }
  // Trilinear weights are convex, so liquid + ice anywhere is at most the largest node sum; erosion
  // only lowers extinction (erode_extinction keeps at most the data's value).
  k.u_track_majorant = volume_->sigma_max_per_m;
  k.u_track_bricks = mc.brick_majorants;
  to_sun_ = glm::normalize(
      geo::sphere_to_ecef({sun.subsolar_lat_deg, sun.subsolar_lon_deg, 0.0}, grid.earth_radius_m));
}

double MonteCarloRenderer::majorant_per_m() const { return kernel_->u_track_majorant; }

void MonteCarloRenderer::extinction(const glm::dvec3& p, double& sl, double& si) const { kernel_->medium_at_point(p, sl, si); }

int MonteCarloRenderer::shell_parts(const glm::dvec3& p, const glm::dvec3& d, double seg[4],
                                    double& t_ground) const {
  const double r0 = grid_.earth_radius_m;
  const double r = glm::length(p), alt = r - r0;
  const glm::dvec3 up = p / r;
  const double mu = glm::dot(d, up), nu = glm::length(glm::cross(d, up));
  t_ground = kInf;
  double g0, g1;
  // A rising ray from the ground or above never meets it: a point placed on the ground may round to
  // a nanometre below it, and must not then find the ground at t = 0.
  const bool rising = mu >= 0.0 && alt > -1.0;
  if (!rising && p64::ray_sphere_rel_nu(r0, alt, mu, nu, 0.0, g0, g1) && g1 > 0.0) {
    t_ground = std::max(g0, 0.0);
  }
  glm::dvec4 s;
  const int n = p64::ray_shell_rel_nu(r0, alt, mu, nu, grid_.alt_m.start, grid_.alt_m.last(), s);
  int kept = 0;
  for (int k = 0; k < n; ++k) {
    const double a = s[2 * k], b = std::min(s[2 * k + 1], t_ground);
    if (b > a) {
      seg[2 * kept] = a;
      seg[2 * kept + 1] = b;
      ++kept;
    }
  }
  return kept;
}

double MonteCarloRenderer::free_path(const glm::dvec3& p, const glm::dvec3& d, PathRng& rng,
                                     MonteCarloStats& st, double* ground_m) const {
  double seg[4], t_ground;
  const int n = shell_parts(p, d, seg, t_ground);
  if (ground_m) *ground_m = t_ground;
  // Delta tracking: a tentative collision is real with probability sigma / majorant.
  kernel::f64::TrackKernel::TrackCounts c = kernel_->track_counts();
  const double t = kernel_->delta_track(p, d, glm::dvec4(seg[0], seg[1], seg[2], seg[3]), n, rng, c);
  st.null_collisions += c.null_collisions;
  st.majorant_exceeded += c.exceeded;
  return t < 3.0e38 ? t : kInf;
}

double MonteCarloRenderer::transmittance(const glm::dvec3& p, const glm::dvec3& d, PathRng& rng,
                                         MonteCarloStats& st) const {
  double seg[4], t_ground;
  const int n = shell_parts(p, d, seg, t_ground);
  if (std::isfinite(t_ground)) return 0.0;  // the Earth's shadow
  // Ratio tracking, with roulette deep in thick cloud.
  kernel::f64::TrackKernel::TrackCounts c = kernel_->track_counts();
  const double tr = kernel_->ratio_track(p, d, glm::dvec4(seg[0], seg[1], seg[2], seg[3]), n, rng, c);
  st.shadow_lookups += c.lookups;
  st.majorant_exceeded += c.exceeded;
  return tr;
}

MonteCarloRenderer::PathResult MonteCarloRenderer::trace(glm::dvec3 p, glm::dvec3 d, PathRng& rng,
                                                         MonteCarloStats& st) const {
  const double r0 = grid_.earth_radius_m;
  const p64::MieParams mie = p64::mie_params(march_.medium.droplet_diameter_um);
  const double liquid_g = p64::mie_mean_cosine(mie);  // for liquid_phase_hg
  // The phase function of a point holding liquid sl and ice si, at scattering cosine mu: the mix by
  // extinction share, which is also the density of the direction the path draws there.
  auto phase_at = [&](double sl, double si, double mu) {
    const double sigma = sl + si;
    if (!(sigma > 0.0)) return p64::phase_isotropic();
    return (sl * (march_.medium.liquid_phase_hg ? p64::phase_hg(mu, liquid_g) : p64::phase_mie(mu, mie)) +
            si * p64::phase_hg(mu, march_.medium.ice_g)) / sigma;
  };
  // The second technique for the direction into a vertex (peak_mis): the droplets' HG peak lobe
  // around the sun, drawn at every cloud vertex holding liquid. q(w) is its density.
  const bool peak = mc_.peak_mis && !march_.medium.liquid_phase_hg;
  auto peak_density = [&](const glm::dvec3& w) { return p64::phase_hg_c(glm::dot(w, to_sun_), mie.g_hg, mie.c_hg); };
  PathResult r;
  glm::dvec3 beta(1.0);
  ++st.paths;
  // The vertex the current direction was drawn at, when the peak technique could have drawn it too.
  bool prev_peak = false;
  double prev_sl = 0.0, prev_si = 0.0;
  glm::dvec3 prev_d(0.0);
  for (;;) {
    double t_ground;
    const double t = free_path(p, d, rng, st, &t_ground);
    if (std::isfinite(t)) {
      p += t * d;
      double sl, si;
      extinction(p, sl, si);
      const double sigma = sl + si;
      ++r.scatterings;
      ++st.scatterings;
      // Next-event estimation: the sun is a delta light, reachable only this way. The scattering
      // cosine is between the sunlight's propagation (-to_sun) and the light's toward the camera (-d).
      // Balance heuristic against the peak technique, which could have drawn d at the vertex before.
      double w = 1.0;
      if (prev_peak) {
        const double p_prev = phase_at(prev_sl, prev_si, glm::dot(prev_d, d));
        w = p_prev / (p_prev + peak_density(d));
      }
      r.radiance += beta * sun_.irradiance * (w * phase_at(sl, si, glm::dot(d, to_sun_)) * transmittance(p, to_sun_, rng, st));
      if (r.scatterings >= mc_.max_bounces) {
        r.end = End::Truncated;
        ++st.truncated;
        break;
      }
      if (!roulette(r, beta, rng, st)) break;
      // The peak technique: a direction w ~ q around the sun, the free path along it, the sun's light
      // at the vertex it reaches, weighted q / (p + q) (the path's own technique is weighted above).
      prev_peak = peak && sl > 0.0;
      if (prev_peak) {
        ++st.peak_samples;
        double q;
        const glm::dvec3 wq = p64::sample_hg(to_sun_, mie.g_hg, glm::dvec2(rng.uniform(), rng.uniform()), q);
        q = peak_density(wq);  // with c_hg kept apart (the sampler's pdf loses digits near g = 1)
        const double p_here = phase_at(sl, si, glm::dot(d, wq));
        const double tq = free_path(p, wq, rng, st);
        if (std::isfinite(tq) && p_here > 0.0) {
          const glm::dvec3 x = p + tq * wq;
          double sl2, si2;
          extinction(x, sl2, si2);
          r.radiance += beta * sun_.irradiance *
                        (p_here / (p_here + q) * phase_at(sl2, si2, glm::dot(wq, to_sun_)) * transmittance(x, to_sun_, rng, st));
        }
        prev_sl = sl, prev_si = si, prev_d = d;
      }
      // Clouds do not absorb (albedo 1): the new direction is drawn from the phase function of the
      // component that scattered, chosen by its share of the extinction, and beta is unchanged.
      double pdf;
      if (rng.uniform() * sigma < sl || !(sigma > 0.0)) {
        if (march_.medium.liquid_phase_hg) {
          d = p64::sample_hg(d, liquid_g, glm::dvec2(rng.uniform(), rng.uniform()), pdf);
        } else {
          std::uint32_t state = rng.bits32();
          d = p64::sample_mie(d, mie, state, pdf);
        }
      } else {
        d = p64::sample_hg(d, march_.medium.ice_g, glm::dvec2(rng.uniform(), rng.uniform()), pdf);
      }
    } else if (march_.features.globe && std::isfinite(t_ground)) {
      // A Lambertian ground of constant albedo: lit by the sun through the clouds, and reflecting
      // a cosine-distributed new direction with throughput times albedo.
      p = glm::normalize(p + t_ground * d) * r0;
      const glm::dvec3 n = p / r0;
      ++r.scatterings;
      ++st.scatterings;
      const double mu_s = glm::dot(n, to_sun_);
      if (mu_s > 0.0) {
        const double tr = transmittance(p, to_sun_, rng, st);
        r.radiance += beta * sun_.irradiance *
                      p64::ground_radiance(march_.medium.ground_albedo, mu_s, glm::dvec3(tr), glm::dvec3(0.0));
      }
      r.absorbed += beta * (glm::dvec3(1.0) - march_.medium.ground_albedo);
      beta *= march_.medium.ground_albedo;
      if (r.scatterings >= mc_.max_bounces) {
        r.end = End::Truncated;
        ++st.truncated;
        break;
      }
      if (!roulette(r, beta, rng, st)) break;
      prev_peak = false;  // a cosine draw from the ground: no other technique makes it
      d = p64::direction_around(n, std::sqrt(rng.uniform()), p64::CV_TWO_PI * rng.uniform());
    } else {
      r.end = std::isfinite(t_ground) ? End::Ground : End::Space;
      break;
    }
  }
  r.weight = beta;
  return r;
}

bool MonteCarloRenderer::roulette(PathResult& r, glm::dvec3& beta, PathRng& rng, MonteCarloStats& st) const {
  if (r.scatterings < mc_.roulette_after) return true;
  const double q = std::min(1.0, std::max({beta.x, beta.y, beta.z}));
  if (q >= 1.0) return true;
  if (rng.uniform() >= q) {
    r.end = End::Roulette;
    ++st.roulette_killed;
    return false;
  }
  beta /= q;
  return true;
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
  const double r0 = grid_.earth_radius_m, ht = grid_.alt_m.last();
  const glm::dvec3 cam_ecef = geo::sphere_to_ecef({cam_.lat_deg, cam_.lon_deg, cam_.alt_m}, r0);
  const std::uint64_t first = img.spp;
  unsigned threads = mc_.threads ? mc_.threads : std::max(1u, std::thread::hardware_concurrency());
  threads = std::min<unsigned>(threads, static_cast<unsigned>(cam_.height));
  std::vector<MonteCarloStats> stats(threads);
  std::atomic<int> next_row{0};
  auto work = [&](unsigned w) {
    for (int py = next_row++; py < cam_.height; py = next_row++) {
      for (int px = 0; px < cam_.width; ++px) {
        const glm::dvec3 d = camera_ray(cam_, px, py);
        // A camera above the shell starts its rays where they enter it, on the exact sphere, as
        // render_reference does: distant cameras then keep the digits of the positions they sample.
        glm::dvec3 o = cam_ecef;
        bool misses = false;
        if (cam_.alt_m > ht) {
          const glm::dvec3 up = glm::normalize(cam_ecef);
          double e0, e1;
          if (!p64::ray_sphere_rel_nu(r0, cam_.alt_m, glm::dot(d, up), glm::length(glm::cross(d, up)), ht, e0,
                                      e1) ||
              e1 < 0.0) {
            misses = true;
          } else if (e0 > 0.0) {
            o = glm::normalize(o + e0 * d) * (r0 + ht);
          }
        }
        const std::size_t idx = static_cast<std::size_t>(py) * cam_.width + px;
        // Samples in index order into this pixel's sums: the same sums whichever thread does it.
        for (std::uint64_t s = first; s < first + static_cast<std::uint64_t>(spp); ++s) {
          glm::dvec3 v(0.0);
          if (!misses) {
            PathRng rng(mc_.seed, idx, s);
            v = trace(o, d, rng, stats[w]).radiance;
          }
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
                                   const MonteCarloSettings& mc, int spp, const ErosionNoise* noise) {
  const MonteCarloRenderer r(grid, medium, cam, sun, march, mc, noise);
  MonteCarloImage img = r.start();
  r.add_samples(img, spp);
  return img;
}

}  // namespace cv::core
