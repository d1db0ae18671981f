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
  // Optical depth of the clouds from p (altitude alt_p) toward the sun (cosine mu_sun, sine nu_sun
  // with the local up at p): sun_steps per shell segment, as cloud_sun_depth in raymarch.comp.
  double sun_depth(const glm::dvec3& p, double alt_p, double mu_sun, double nu_sun, const glm::dvec3& to_sun,
                   int sun_steps) const {
    glm::dvec4 sseg;
    const int sn = p64::ray_shell_rel_nu(grid.earth_radius_m, alt_p, mu_sun, nu_sun, grid.alt_m.start, grid.alt_m.last(), sseg);
    double tau = 0.0;
    for (int q = 0; q < sn; ++q) {
      const double ds = (sseg[2 * q + 1] - sseg[2 * q]) / sun_steps;
      for (int j = 0; j < sun_steps; ++j) {
        double a, b;
        at(p + (sseg[2 * q] + (j + 0.5) * ds) * to_sun, a, b);
        tau += (a + b) * ds;
      }
    }
    return tau;
  }
};

// The air and the ground around the clouds, as sky_and_ground in shaders/render/sky_ground.glsl:
// sky in front + T (cloud + cloud_t (sky behind + T ground)); alpha 0 where the globe shows.
glm::dvec4 sky_and_ground(const Medium& medium, const MarchSettings& s, const AlbedoMap* map, const glm::dvec3& cam_ecef,
                          double cam_alt, const glm::dvec3& d, const glm::dvec3& to_sun, const glm::dvec3& irradiance,
                          const glm::dvec3& cloud_l, double cloud_t, bool has_cloud, const glm::dvec3& p_cloud) {
  const double r0 = medium.grid.earth_radius_m, top = p64::CV_ATMO_TOP_M;
  glm::dvec3 o = cam_ecef, up = glm::normalize(cam_ecef);
  double h = cam_alt, mu = glm::dot(d, up), nu = glm::length(glm::cross(d, up));
  double a0, a1;
  if (!p64::ray_sphere_rel_nu(r0, h, mu, nu, top, a0, a1) || a1 < 0.0) return glm::dvec4(cloud_l, cloud_t);
  if (h > top && a0 > 0.0) {
    o = glm::normalize(o + a0 * d) * (r0 + top);
    h = top;
    up = glm::normalize(o);
    mu = glm::dot(d, up);
    nu = glm::length(glm::cross(d, up));
    p64::ray_sphere_rel_nu(r0, h, mu, nu, top, a0, a1);
  }
  double g0, g1;
  const bool hits_ground = p64::ray_sphere_rel_nu(r0, h, mu, nu, 0.0, g0, g1) && g1 > 0.0;
  const double t_end = hits_ground ? std::max(g0, 0.0) : a1;
  const double t_cloud = has_cloud ? std::clamp(glm::dot(p_cloud - o, d), 0.0, t_end) : t_end;
  glm::dvec3 sky_front(0.0), sky_back(0.0), tr_front(1.0), tr_back(1.0);
  if (s.atmosphere) {
    const double mu_s = glm::dot(to_sun, up), nu_vs = glm::dot(d, to_sun);
    sky_front = irradiance * p64::atmo_inscatter(r0, h, mu, mu_s, nu_vs, 0.0, t_cloud, s.sky_steps, s.atmo_sun_steps, tr_front);
    if (t_end > t_cloud) {
      sky_back = irradiance * p64::atmo_inscatter(r0, h, mu, mu_s, nu_vs, t_cloud, t_end, s.sky_steps, s.atmo_sun_steps, tr_back);
    }
  }
  glm::dvec3 ground(0.0);
  const bool globe = hits_ground && s.globe;
  if (globe) {
    const glm::dvec3 pg = glm::normalize(o + t_end * d) * r0, n = glm::normalize(pg);
    const double mu_sg = glm::dot(to_sun, n), nu_sg = glm::length(glm::cross(to_sun, n));
    glm::dvec3 sun_air(mu_sg > 0.0 ? 1.0 : 0.0), e_sky(0.0);
    if (s.atmosphere) {
      sun_air = p64::atmo_transmittance(r0, 0.0, mu_sg, nu_sg, s.atmo_sun_steps);
      e_sky = p64::sky_irradiance(sun_air, mu_sg);
    }
    // The clouds' shadow: the same sun march the cloud samples use.
    const double shadow = mu_sg > 0.0 ? p64::transmittance(medium.sun_depth(pg, 0.0, mu_sg, nu_sg, to_sun, s.sun_steps)) : 0.0;
    const glm::dvec3 ll = p64::ecef_to_sphere(pg, r0);
    const glm::dvec3 albedo = map ? map->at(ll.x, ll.y) : s.ground_albedo;
    ground = irradiance * p64::ground_radiance(albedo, mu_sg, sun_air * shadow, e_sky);
  }
  const glm::dvec3 l = sky_front + tr_front * (cloud_l + cloud_t * (sky_back + tr_back * ground));
  return glm::dvec4(l, globe ? 0.0 : cloud_t * tr_front.y * tr_back.y);
}
}  // namespace

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
                                const MarchSettings& s, const ErosionNoise* noise, const AlbedoMap* ground_map) {
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
      bool in_shell = true;  // false: the ray misses the cloud shell (the sky may still show)
      if (h > ht) {
        double e0, e1;
        if (!p64::ray_sphere_rel_nu(r0, h, mu_up, nu_up, ht, e0, e1) || e1 < 0.0) {
          in_shell = false;
        } else if (e0 > 0.0) {
          origin = glm::normalize(origin + e0 * d) * (r0 + ht);
          h = ht;
          up = glm::normalize(origin);
          mu_up = glm::dot(d, up);
          nu_up = glm::length(glm::cross(d, up));
        }
      }
      glm::dvec4 seg;
      const int n = in_shell ? p64::ray_shell_rel_nu(r0, h, mu_up, nu_up, hb, ht, seg) : 0;
      // The ground ends the ray.
      double tg0, tg1;
      const double t_ground = p64::ray_sphere_rel_nu(r0, h, mu_up, nu_up, 0.0, tg0, tg1) && tg1 > 0.0 ? std::max(tg0, 0.0) : 1e300;
      // Sunlight propagates along -to_sun and leaves toward the camera along -d: the scattering
      // cosine between the two propagation directions is dot(to_sun, d).
      const double mu = glm::dot(d, to_sun);
      glm::dvec3 radiance(0.0);
      double transmittance = 1.0;
      double depth_w = 0.0, depth_t = 0.0;  // where the cloud is: the mean depth of the light it takes out
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
          double e0, e1;
          const bool lit = !(p64::ray_sphere_rel_nu(r0, alt_p, mu_sun, nu_sun, 0.0, e0, e1) && e1 > 0.0);
          const double tau_sun = lit ? medium.sun_depth(p, alt_p, mu_sun, nu_sun, to_sun, s.sun_steps) : 0.0;
          // Sunlight reaches the sample through the air (reddened when low), and the sky lights it
          // too: isotropic irradiance E_sky scattered as sigma_s E_sky / (2 pi) (docs/physics.md).
          const glm::dvec3 sun_air = s.atmosphere && lit ? p64::atmo_transmittance(r0, alt_p, mu_sun, nu_sun, s.atmo_sun_steps)
                                                         : glm::dvec3(1.0);
          const glm::dvec3 ambient = s.atmosphere ? s.ambient * p64::sky_irradiance(sun_air, mu_sun) * (sigma / p64::CV_TWO_PI)
                                                  : glm::dvec3(0.0);
          // In-scattered radiance per metre: the octave sums of both phases (clouds do not absorb).
          const double scatter = lit ? p64::ms_octaves_mie(sl, mu, mie, tau_sun, s.octaves, s.octave_a, s.octave_b, s.octave_c) +
                                           p64::ms_octaves_hg(si, mu, s.ice_g, tau_sun, s.octaves, s.octave_a, s.octave_b, s.octave_c)
                                     : 0.0;
          radiance += transmittance * p64::segment_integral(sun.irradiance * (sun_air * scatter + ambient), sigma, dt);
          // The light the step takes out of the view, T (1 - exp(-sigma dt)), as raymarch.comp
          // forms it (there, T - T_next would cancel in float).
          const double taken = transmittance * p64::segment_integral(sigma, sigma, dt);
          depth_w += taken;
          depth_t += taken * (t_start + (i + offset) * dt);
          transmittance *= p64::transmittance(sigma * dt);
        }
      }
      const std::size_t idx = static_cast<std::size_t>(py) * cam.width + px;
      if (s.atmosphere || s.globe) {
        const glm::dvec3 p_cloud = origin + (depth_w > 0.0 ? depth_t / depth_w : 0.0) * d;
        const glm::dvec4 c = sky_and_ground(medium, s, ground_map, o, cam.alt_m, d, to_sun, sun.irradiance, radiance,
                                            transmittance, depth_w > 1e-6, p_cloud);
        radiance = glm::dvec3(c);
        transmittance = c.w;
      }
      img.radiance[idx] = radiance;
      img.transmittance[idx] = transmittance;
    }
  }
  return img;
}

}  // namespace cv::core
