// The CPU reference raymarcher.
#include "reference/raymarcher.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <glm/glm.hpp>

#include "geo/geodesy.hpp"
#include "physics/physics.hpp"
#include "volume/sampler.hpp"

namespace cv::core {
namespace {
namespace p64 = cv::physics::f64;
constexpr double kDeg = 3.14159265358979323846 / 180.0;

// Erosion noise as the march uses it: the textures, where they are anchored, how strong.
struct Erosion {
  const ErosionNoise* noise = nullptr;  // null: off
  NoiseAnchor anchor;
  double period_m = 0.0, amount = 0.0;
  // Erodes both extinctions at p, as raymarch.comp's erode_at does.
  void apply(const glm::dvec3& p, double& sigma_liquid, double& sigma_ice) const {
    const glm::dvec3 t = p64::noise_tile_coords(p - anchor.ecef_m, anchor.frac, period_m);
    const double e = p64::erosion_threshold(noise->low.sample(t), noise->high.sample(p64::noise_high_coords(t)), amount);
    const double feature_m = p64::noise_feature_m(period_m);
    sigma_liquid = p64::erode_extinction(sigma_liquid, e, feature_m);
    sigma_ice = p64::erode_extinction(sigma_ice, e, feature_m);
  }
};

// Grid-box-mean extinction of liquid and of ice at an Earth-centred point, eroded by the noise if on.
struct Medium {
  const VolumeGrid& grid;
  VolumeSampler liquid, ice;
  Erosion erosion;
  void at(const glm::dvec3& p, double& sigma_liquid, double& sigma_ice) const {
    const glm::dvec3 g = p64::ecef_to_sphere(p, grid.earth_radius_m);
    const double lat = g.x / kDeg, lon = g.y / kDeg, alt = g.z;
    sigma_liquid = liquid.sample(lat, lon, alt, 0.0);
    sigma_ice = ice.sample(lat, lon, alt, 0.0);
    if (erosion.noise && sigma_liquid + sigma_ice > 0.0) erosion.apply(p, sigma_liquid, sigma_ice);
  }
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

glm::dvec3 grid_centre_ecef(const VolumeGrid& grid) {
  const double lat = grid.lat_deg.start + 0.5 * (grid.lat_deg.last() - grid.lat_deg.start);
  const double lon = grid.lon_deg.start + 0.5 * (grid.lon_deg.last() - grid.lon_deg.start);
  return geo::sphere_to_ecef({lat, lon, 0.0}, grid.earth_radius_m);
}

ReferenceImage render_reference(const VolumeGrid& grid, const GridMeanExtinction& ext, const Camera& cam, const Sun& sun,
                                const MarchSettings& s, const ErosionNoise* noise) {
  ReferenceImage img;
  img.width = cam.width;
  img.height = cam.height;
  img.radiance.assign(static_cast<std::size_t>(cam.width) * cam.height, glm::dvec3(0.0));
  img.transmittance.assign(img.radiance.size(), 1.0);
  Erosion erosion;
  if (s.noise_amount > 0.0) {
    if (!noise) throw std::invalid_argument("render_reference: noise_amount > 0 needs the erosion noise textures");
    if (!(s.noise_scale_m > 0.0)) throw std::invalid_argument("render_reference: noise_scale_m must be > 0");
    erosion = {noise, noise_anchor(grid_centre_ecef(grid), s.noise_scale_m), s.noise_scale_m, s.noise_amount};
  }
  const Medium medium{grid, VolumeSampler(grid, ext.liquid_per_m), VolumeSampler(grid, ext.ice_per_m), erosion};
  const double r0 = grid.earth_radius_m;
  const double hb = grid.alt_m.start, ht = grid.alt_m.last();
  const glm::dvec3 o = geo::sphere_to_ecef({cam.lat_deg, cam.lon_deg, cam.alt_m}, r0);
  const glm::dvec3 to_sun = glm::normalize(geo::sphere_to_ecef({sun.subsolar_lat_deg, sun.subsolar_lon_deg, 0.0}, r0));
  const p64::MieParams mie = p64::mie_params(s.droplet_diameter_um);
  const glm::dvec3 up_cam = glm::normalize(o);
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
      if (skip) continue;
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
      for (int k = 0; k < n && transmittance > 1e-6; ++k) {
        const double t_start = seg[2 * k], t_end = std::min(seg[2 * k + 1], t_ground);
        if (!(t_end > t_start)) continue;
        const int steps = std::max(1, static_cast<int>(std::ceil((t_end - t_start) / s.view_step_m)));
        const double dt = (t_end - t_start) / steps;
        const double offset = s.frame < 0 ? 0.5
                                          : p64::step_jitter(static_cast<p64::uint>(px), static_cast<p64::uint>(py),
                                                             static_cast<p64::uint>(s.frame));
        for (int i = 0; i < steps && transmittance > 1e-6; ++i) {
          const glm::dvec3 p = origin + (t_start + (i + offset) * dt) * d;
          double sl, si;
          medium.at(p, sl, si);
          const double sigma = sl + si;
          if (sigma <= 0.0) continue;
          // Optical depth toward the sun, unless the Earth is in the way.
          const glm::dvec3 up_p = glm::normalize(p);
          const double alt_p = glm::length(p) - r0;
          const double mu_sun = glm::dot(to_sun, up_p), nu_sun = glm::length(glm::cross(to_sun, up_p));
          double e0, e1, tau_sun = 0.0;
          bool lit = !(p64::ray_sphere_rel_nu(r0, alt_p, mu_sun, nu_sun, 0.0, e0, e1) && e1 > 0.0);
          if (lit) {
            glm::dvec4 sseg;
            const int sn = p64::ray_shell_rel_nu(r0, alt_p, mu_sun, nu_sun, hb, ht, sseg);
            for (int q = 0; q < sn; ++q) {
              const double ds = (sseg[2 * q + 1] - sseg[2 * q]) / s.sun_steps;
              for (int j = 0; j < s.sun_steps; ++j) {
                double a, b;
                medium.at(p + (sseg[2 * q] + (j + 0.5) * ds) * to_sun, a, b);
                tau_sun += (a + b) * ds;
              }
            }
          }
          // In-scattered radiance per metre: the octave sums of both phases (clouds do not absorb).
          const double scatter = lit ? p64::ms_octaves_mie(sl, mu, mie, tau_sun, s.octaves, s.octave_a, s.octave_b, s.octave_c) +
                                           p64::ms_octaves_hg(si, mu, s.ice_g, tau_sun, s.octaves, s.octave_a, s.octave_b, s.octave_c)
                                     : 0.0;
          radiance += transmittance * p64::segment_integral(sun.irradiance * scatter, sigma, dt);
          transmittance *= p64::transmittance(sigma * dt);
        }
      }
      const std::size_t idx = static_cast<std::size_t>(py) * cam.width + px;
      img.radiance[idx] = radiance;
      img.transmittance[idx] = transmittance;
    }
  }
  return img;
}

}  // namespace cv::core
