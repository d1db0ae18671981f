// The CPU reference raymarcher.
#include "reference/raymarcher.hpp"

#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>

#include "geo/geodesy.hpp"
#include "physics/physics.hpp"
#include "volume/extinction_pyramid.hpp"
#include "volume/sampler.hpp"

namespace cv::core {
namespace {
namespace p64 = cv::physics::f64;
constexpr double kDeg = 3.14159265358979323846 / 180.0;

// Grid-box-mean extinction of liquid and of ice at an Earth-centred point.
struct Medium {
  const VolumeGrid& grid;
  VolumeSampler liquid, ice;
  void at(const glm::dvec3& p, double& sigma_liquid, double& sigma_ice) const {
    const glm::dvec3 g = p64::ecef_to_sphere(p, grid.earth_radius_m);
    const double lat = g.x / kDeg, lon = g.y / kDeg, alt = g.z;
    sigma_liquid = liquid.sample(lat, lon, alt, 0.0);
    sigma_ice = ice.sample(lat, lon, alt, 0.0);
  }
  // The largest extinction (liquid + ice) trilinear sampling can return in the grid cell around p:
  // the largest of the 8 nodes the sampler reads there (as fetch in raymarch.comp); 0 outside.
  double cell_max(const glm::dvec3& p) const {
    const glm::dvec3 g = p64::ecef_to_sphere(p, grid.earth_radius_m);
    const glm::dvec3 start(grid.lon_deg.start, grid.lat_deg.start, grid.alt_m.start);
    const glm::dvec3 step(grid.lon_deg.step, grid.lat_deg.step, grid.alt_m.step);
    const glm::dvec3 count(grid.lon_deg.count, grid.lat_deg.count, grid.alt_m.count);
    glm::dvec3 f;
    if (!p64::volume_coords(g.x / kDeg, g.y / kDeg, g.z, start, step, count, wraps, global_lat, f)) return 0.0;
    const int nx = grid.lon_deg.count, ny = grid.lat_deg.count, nz = grid.alt_m.count;
    const int x0 = std::min(static_cast<int>(std::floor(f.x)), nx - 1);
    const int y0 = std::min(static_cast<int>(std::floor(f.y)), std::max(0, ny - 2));
    const int z0 = std::min(static_cast<int>(std::floor(f.z)), std::max(0, nz - 2));
    const int x1 = wraps ? (x0 + 1) % nx : std::min(x0 + 1, nx - 1);
    const int y1 = std::min(y0 + 1, ny - 1), z1 = std::min(z0 + 1, nz - 1);
    double m = 0.0;
    for (int c = 0; c < 8; ++c) {
      const std::size_t idx = grid.index(c & 1 ? x1 : x0, c & 2 ? y1 : y0, c & 4 ? z1 : z0);
      const double v = (liquid_per_m.empty() ? 0.0 : liquid_per_m[idx]) + (ice_per_m.empty() ? 0.0 : ice_per_m[idx]);
      m = std::max(m, v);
    }
    return m;
  }
  const std::vector<float>& liquid_per_m;
  const std::vector<float>& ice_per_m;
  bool wraps, global_lat;
};
}  // namespace

GridMeanExtinction grid_mean_extinction(const VolumeGrid& grid, const TimeStepData& data) {
  GridMeanExtinction m;
  const auto& cf = data[Field::CloudFraction];
  auto product = [&](const std::vector<float>& ext, std::vector<float>& out) {
    out.assign(grid.points(), 0.0f);
    if (ext.empty()) return;
    for (std::size_t p = 0; p < out.size(); ++p) {
      const float c = cf.empty() ? 1.0f : cf[p];
      const float v = c * ext[p];
      out[p] = std::isnan(v) || v < 0.0f ? 0.0f : v;
    }
  };
  product(data[Field::ExtinctionLiquid], m.liquid_per_m);
  product(data[Field::ExtinctionIce], m.ice_per_m);
  return m;
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

ReferenceImage render_reference(const VolumeGrid& grid, const GridMeanExtinction& ext, const Camera& cam, const Sun& sun,
                                const MarchSettings& s) {
  ReferenceImage img;
  img.width = cam.width;
  img.height = cam.height;
  img.radiance.assign(static_cast<std::size_t>(cam.width) * cam.height, glm::dvec3(0.0));
  img.transmittance.assign(img.radiance.size(), 1.0);
  const VolumeSampler liquid_sampler(grid, ext.liquid_per_m);
  const Medium medium{grid,           liquid_sampler,   VolumeSampler(grid, ext.ice_per_m), ext.liquid_per_m, ext.ice_per_m,
                      grid.wraps_lon(), liquid_sampler.global_lat()};
  const double r0 = grid.earth_radius_m;
  const double hb = grid.alt_m.start, ht = grid.alt_m.last();
  const glm::dvec3 o = geo::sphere_to_ecef({cam.lat_deg, cam.lon_deg, cam.alt_m}, r0);
  const glm::dvec3 to_sun = glm::normalize(geo::sphere_to_ecef({sun.subsolar_lat_deg, sun.subsolar_lon_deg, 0.0}, r0));
  const p64::MieParams mie = p64::mie_params(s.droplet_diameter_um);
  const glm::dvec3 up_cam = glm::normalize(o);
  const double sun_tau_limit = p64::sun_march_tau_limit(s.octaves, s.octave_a, s.min_transmittance);
  const bool use_pyramid = s.skip_empty || s.adaptive_steps;
  const ExtinctionPyramid pyramid =
      use_pyramid ? ExtinctionPyramid(grid, ext.liquid_per_m, ext.ice_per_m) : ExtinctionPyramid();
  // Optical depth from p toward the sun through the shell; false when the Earth is in the way.
  auto sun_optical_depth = [&](const glm::dvec3& p, double& tau_sun) {
    tau_sun = 0.0;
    const glm::dvec3 up_p = glm::normalize(p);
    const double alt_p = glm::length(p) - r0;
    const double mu_sun = glm::dot(to_sun, up_p), nu_sun = glm::length(glm::cross(to_sun, up_p));
    double e0, e1;
    if (p64::ray_sphere_rel_nu(r0, alt_p, mu_sun, nu_sun, 0.0, e0, e1) && e1 > 0.0) return false;
    glm::dvec4 sseg;
    const int sn = p64::ray_shell_rel_nu(r0, alt_p, mu_sun, nu_sun, hb, ht, sseg);
    for (int q = 0; q < sn; ++q) {
      const double ds = (sseg[2 * q + 1] - sseg[2 * q]) / s.sun_steps;
      double known_end = -1.0;
      for (int j = 0; j < s.sun_steps;) {
        const double t_rel = (j + 0.5) * ds;
        const glm::dvec3 ps = p + (sseg[2 * q] + t_rel) * to_sun;
        if (s.skip_empty && !(t_rel < known_end)) {
          const ExtinctionPyramid::Space sp = pyramid.at(ps, to_sun);
          if (sp.empty) {
            const int next = p64::march_resume_index(j, sp.extent_m, ds);
            img.stats.sun_skipped += static_cast<std::uint64_t>(std::min(next, s.sun_steps) - j);
            img.stats.bricks_jumped += next - j > 1;
            j = next;
            continue;
          }
          known_end = t_rel + sp.extent_m;
        }
        double a, b;
        medium.at(ps, a, b);
        tau_sun += (a + b) * ds;
        ++img.stats.sun_samples;
        ++j;
        if (tau_sun > sun_tau_limit) {
          img.stats.sun_skipped += static_cast<std::uint64_t>((sn - q - 1) * s.sun_steps + s.sun_steps - j);
          return true;
        }
      }
    }
    return true;
  };
  // One view sample at p standing for a step of ds: in-scattered light and attenuation.
  auto march_sample = [&](const glm::dvec3& p, double ds, double mu, glm::dvec3& radiance, double& transmittance) {
    double sl, si;
    medium.at(p, sl, si);
    ++img.stats.view_samples;
    const double sigma = sl + si;
    if (sigma <= 0.0) return;
    double tau_sun = 0.0;
    const bool lit = sun_optical_depth(p, tau_sun);
    // In-scattered radiance per metre: the octave sums of both phases (clouds do not absorb).
    const double scatter = lit ? p64::ms_octaves_mie(sl, mu, mie, tau_sun, s.octaves, s.octave_a, s.octave_b, s.octave_c) +
                                     p64::ms_octaves_hg(si, mu, s.ice_g, tau_sun, s.octaves, s.octave_a, s.octave_b, s.octave_c)
                               : 0.0;
    radiance += transmittance * p64::segment_integral(sun.irradiance * scatter, sigma, ds);
    transmittance *= p64::transmittance(sigma * ds);
  };
  for (int py = 0; py < cam.height; ++py) {
    for (int px = 0; px < cam.width; ++px) {
      const glm::dvec3 d = camera_ray(cam, px, py);
      // A camera above the shell marches from where its ray enters the shell, placed on the exact
      // sphere: far cameras then sample near the Earth, where positions keep their digits (the GPU
      // does the same, and it matters there: float positions at 4e8 m are +-32 m).
      glm::dvec3 origin = o;
      double h = cam.alt_m;
      glm::dvec3 up = up_cam;
      double mu_up = glm::dot(d, up), nu_up = glm::length(glm::cross(d, up));
      bool skip = false;
      if (h > ht) {
        double e0, e1;
        if (!p64::ray_sphere_rel_nu(r0, h, mu_up, nu_up, ht, e0, e1) || e1 < 0.0) {
          skip = true;
        } else if (e0 > 0.0) {
          origin = glm::normalize(origin + e0 * d) * (r0 + ht);
          h = ht;
          up = glm::normalize(origin);
          mu_up = glm::dot(d, up);
          nu_up = glm::length(glm::cross(d, up));
        }
      }
      if (skip) {
        ++img.stats.rays_missed;
        continue;
      }
      glm::dvec4 seg;
      const int n = p64::ray_shell_rel_nu(r0, h, mu_up, nu_up, hb, ht, seg);
      // The ground ends the ray.
      double tg0, tg1;
      const double t_ground = p64::ray_sphere_rel_nu(r0, h, mu_up, nu_up, 0.0, tg0, tg1) && tg1 > 0.0 ? std::max(tg0, 0.0) : 1e300;
      // Sunlight propagates along -to_sun and leaves toward the camera along -d: the scattering
      // cosine between the two propagation directions is dot(to_sun, d).
      const double mu = glm::dot(d, to_sun);
      glm::dvec3 radiance(0.0);
      double transmittance = 1.0;
      bool crossed = false;
      for (int k = 0; k < n && transmittance > s.min_transmittance; ++k) {
        const double t_start = seg[2 * k], t_end = std::min(seg[2 * k + 1], t_ground);
        if (!(t_end > t_start)) continue;
        crossed = true;
        const int steps = std::max(1, static_cast<int>(std::ceil((t_end - t_start) / s.view_step_m)));
        const double dt = (t_end - t_start) / steps;
        const double offset = s.frame < 0 ? 0.5
                                          : p64::step_jitter(static_cast<p64::uint>(px), static_cast<p64::uint>(py),
                                                             static_cast<p64::uint>(s.frame));
        // What the pyramid said about the brick ahead: valid for sample distances below known_end.
        double known_end = -1.0, sigma_max = 0.0;
        const bool query = s.skip_empty || s.adaptive_steps;
        for (int i = 0; i < steps && transmittance > s.min_transmittance;) {
          const double t_rel = (i + offset) * dt;
          int substeps = 1;
          if (query && !(t_rel < known_end)) {
            const ExtinctionPyramid::Space sp = pyramid.at(origin + (t_start + t_rel) * d, d);
            if (sp.empty && s.skip_empty) {
              const int next = p64::march_resume_index(i, sp.extent_m, dt);
              img.stats.view_skipped += static_cast<std::uint64_t>(std::min(next, steps) - i);
              img.stats.bricks_jumped += next - i > 1;
              i = next;
              continue;
            }
            sigma_max = sp.empty ? 0.0 : sp.sigma_max_per_m;
            known_end = t_rel + sp.extent_m;
          }
          if (s.adaptive_steps && p64::march_substeps(sigma_max, dt, s.max_step_optical_depth) > 1) {
            // The brick's bound is loose (a brick spans 4 cells and more): bound the step by the
            // cells at its two ends instead, so only steps near thick cloud are divided.
            const double bound = std::max(medium.cell_max(origin + (t_start + i * dt) * d),
                                          medium.cell_max(origin + (t_start + (i + 1) * dt) * d));
            substeps = p64::march_substeps(bound, dt, s.max_step_optical_depth);
          }
          const double ds = dt / substeps;
          for (int j = 0; j < substeps && transmittance > s.min_transmittance; ++j) {
            const glm::dvec3 p = origin + (t_start + (i + (j + offset) / substeps) * dt) * d;
            march_sample(p, ds, mu, radiance, transmittance);
          }
          ++i;
        }
      }
      img.stats.rays_missed += !crossed;
      const std::size_t idx = static_cast<std::size_t>(py) * cam.width + px;
      img.radiance[idx] = radiance;
      img.transmittance[idx] = transmittance;
    }
  }
  return img;
}

}  // namespace cv::core
