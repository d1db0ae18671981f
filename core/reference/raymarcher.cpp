// The CPU reference raymarcher.
#include "reference/raymarcher.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <glm/glm.hpp>

#include "geo/geodesy.hpp"
#include "noise/blue_noise.hpp"
#include "physics/physics.hpp"
#include "reference/earth_shadow.hpp"
#include "volume/column_depth.hpp"
#include "volume/extinction_pyramid.hpp"
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
  // The largest extinction (liquid + ice) trilinear sampling can return in the grid cell around p:
  // the largest of the 8 nodes the sampler reads there, border nodes as 0 (as cell_max in
  // raymarch.comp); 0 outside.
  double cell_max(const glm::dvec3& p) const {
    const glm::dvec3 g = p64::ecef_to_sphere(p, grid.earth_radius_m);
    const glm::dvec3 start(grid.lon_deg.start, grid.lat_deg.start, grid.alt_m.start);
    const glm::dvec3 step(grid.lon_deg.step, grid.lat_deg.step, grid.alt_m.step);
    const glm::dvec3 count(grid.lon_deg.count, grid.lat_deg.count, grid.alt_m.count);
    glm::dvec3 f;
    if (!p64::volume_coords(g.x / kDeg, g.y / kDeg, g.z, start, step, count, wraps, global_lat, f)) return 0.0;
    const int nx = grid.lon_deg.count, ny = grid.lat_deg.count, nz = grid.alt_m.count;
    double w;
    const int x0 = p64::volume_fetch_index(f.x, nx, w), y0 = p64::volume_fetch_index(f.y, ny, w);
    const int z0 = p64::volume_fetch_index(f.z, nz, w);
    const int x1 = wraps ? (x0 + 1) % nx : x0 + 1, y1 = y0 + 1, z1 = std::min(z0 + 1, nz - 1);
    double m = 0.0;
    for (int c = 0; c < 8; ++c) {
      const int x = c & 1 ? x1 : x0, y = c & 2 ? y1 : y0, z = c & 4 ? z1 : z0;
      if (x < 0 || x >= nx || y < 0 || y >= ny) continue;  // the border: no cloud
      const std::size_t idx = grid.index(x, y, z);
      m = std::max(m, (liquid_per_m.empty() ? 0.0 : liquid_per_m[idx]) + (ice_per_m.empty() ? 0.0 : ice_per_m[idx]));
    }
    return m;
  }
  // Optical depth of the clouds from p (altitude alt_p) toward the sun (cosine mu_sun, sine nu_sun
  // with the local up at p): sun_steps per shell segment, more where the segment is long
  // (sun_step_max_m), fewer in thin cloud (sun_march_steps), empty bricks jumped, stopped past
  // sun_tau_limit, as cloud_sun_depth in raymarch.comp. Counts into *stats.
  double sun_depth(const glm::dvec3& p, double alt_p, double mu_sun, double nu_sun, const glm::dvec3& to_sun,
                   int sun_steps) const {
    glm::dvec4 sseg;
    const int sn = layer.empty ? 0 : p64::ray_shell_rel_nu(grid.earth_radius_m, alt_p, mu_sun, nu_sun, layer.bottom_m, layer.top_m, sseg);
    double tau = 0.0;
    int steps[2] = {0, 0};
    for (int q = 0; q < sn; ++q) steps[q] = p64::sun_march_steps(sigma_max, sseg[2 * q + 1] - sseg[2 * q], sun_step_tau, sun_steps,
                                                         sun_step_max_m);
    for (int q = 0; q < sn; ++q) {
      const int n = steps[q];
      const double ds = (sseg[2 * q + 1] - sseg[2 * q]) / n;
      double known_end = -1.0;
      for (int j = 0; j < n;) {
        const double t_rel = (j + 0.5) * ds;
        const glm::dvec3 ps = p + (sseg[2 * q] + t_rel) * to_sun;
        if (skip_empty && !(t_rel < known_end)) {
          const ExtinctionPyramid::Space sp = pyramid->at(ps, to_sun);
          if (sp.empty) {
            const int next = p64::march_resume_index(j, sp.extent_m, ds);
            stats->sun_skipped += static_cast<std::uint64_t>(std::min(next, n) - j);
            stats->bricks_jumped += next - j > 1;
            j = next;
            continue;
          }
          known_end = t_rel + sp.extent_m;
        }
        double a, b;
        at(ps, a, b);
        tau += (a + b) * ds;
        ++stats->sun_samples;
        ++j;
        if (tau > sun_tau_limit) {
          stats->sun_skipped += static_cast<std::uint64_t>((q == 0 ? steps[1] : 0) + n - j);
          return tau;
        }
      }
    }
    return tau;
  }
  const std::vector<float>& liquid_per_m;
  const std::vector<float>& ice_per_m;
  CloudLayer layer;
  bool wraps = false, global_lat = false;
  const ExtinctionPyramid* pyramid = nullptr;
  bool skip_empty = false;
  double sun_tau_limit = 3.0e38;
  MarchStats* stats = nullptr;
  bool sun_down = false;  // the whole layer is in the Earth's shadow: no sun march can find cloud
  double sigma_max = 0.0;     // the volume's largest extinction (1/m): sizes the sun marches' steps
  double sun_step_tau = 0.0;  // MarchSettings::max_sun_step_optical_depth
  double sun_step_max_m = 0.0;  // the longest sun step (m): sun_step_limit_m of MarchSettings::max_sun_step_m
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
    // With the whole layer in the Earth's shadow no sunlit ray crosses cloud (a point on a sunlit
    // ray is sunlit): the march would find none, and is left out.
    const double shadow = mu_sg > 0.0 ? medium.sun_down ? 1.0 : p64::transmittance(medium.sun_depth(pg, 0.0, mu_sg, nu_sg, to_sun, s.sun_steps))
                                      : 0.0;
    const glm::dvec3 ll = p64::ecef_to_sphere(pg, r0);
    const glm::dvec3 albedo = map ? map->at(ll.x, ll.y) : s.ground_albedo;
    ground = irradiance * p64::ground_radiance(albedo, mu_sg, sun_air * shadow, e_sky);
  }
  const glm::dvec3 l = sky_front + tr_front * (cloud_l + cloud_t * (sky_back + tr_back * ground));
  return glm::dvec4(l, globe ? 0.0 : cloud_t * tr_front.y * tr_back.y);
}
// Where in its step a pixel's view samples lie (0..1): step middles without a frame, else the
// frame's jitter, computed as the GPU computes it (shaders/render/raymarch.comp).
double step_offset(const MarchSettings& s, int px, int py) {
  if (s.frame < 0) return 0.5;
  const auto x = static_cast<p64::uint>(px), y = static_cast<p64::uint>(py), f = static_cast<p64::uint>(s.frame);
  return s.blue_noise ? p64::blue_noise_jitter(step_jitter_mask().at(x, y), f) : p64::step_jitter(x, y, f);
}

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
  // Only the layer that holds cloud is marched (and nothing when none does).
  const CloudLayer layer = cloud_layer(grid, ext);
  const bool use_pyramid = s.skip_empty || s.adaptive_steps;
  const double r0 = grid.earth_radius_m;
  const glm::dvec3 to_sun = glm::normalize(geo::sphere_to_ecef({sun.subsolar_lat_deg, sun.subsolar_lon_deg, 0.0}, r0));
  // Night over the whole layer: every sample's own test would find it unlit.
  img.stats.sun_down = s.leave_out_night && layer_in_earth_shadow(grid, layer, to_sun);
  const ExtinctionPyramid pyramid =
      use_pyramid ? ExtinctionPyramid(grid, ext.liquid_per_m, ext.ice_per_m) : ExtinctionPyramid();
  const VolumeSampler liquid_sampler(grid, ext.liquid_per_m);
  const Medium medium{grid,
                      liquid_sampler,
                      VolumeSampler(grid, ext.ice_per_m),
                      erosion,
                      ext.liquid_per_m,
                      ext.ice_per_m,
                      layer,
                      grid.wraps_lon(),
                      liquid_sampler.global_lat(),
                      &pyramid,
                      s.skip_empty,
                      p64::sun_march_tau_limit(s.octaves, s.octave_a, s.min_transmittance),
                      &img.stats,
                      img.stats.sun_down,
                      largest_extinction(ext),
                      s.max_sun_step_optical_depth,
                      sun_step_limit_m(grid, layer, s)};
  const double hb = layer.bottom_m, ht = layer.top_m;
  const glm::dvec3 o = geo::sphere_to_ecef({cam.lat_deg, cam.lon_deg, cam.alt_m}, r0);
  const p64::MieParams mie = p64::mie_params(s.droplet_diameter_um);
  const double liquid_g = p64::mie_mean_cosine(mie);  // for liquid_phase_hg
  const glm::dvec3 up_cam = glm::normalize(o);
  // The octave gate's column optical depths (only when there are octaves to gate).
  const bool gate = s.octave_gate && s.octaves > 1;
  const ColumnDepth columns = gate ? column_depth(grid, ext.liquid_per_m, ext.ice_per_m) : ColumnDepth();
  const double gate_tol = gate ? p64::CV_OCTAVE_GATE_TOL : 0.0;
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
      const int n = in_shell && !layer.empty ? p64::ray_shell_rel_nu(r0, h, mu_up, nu_up, hb, ht, seg) : 0;
      // The ground ends the ray.
      double tg0, tg1;
      const double t_ground = p64::ray_sphere_rel_nu(r0, h, mu_up, nu_up, 0.0, tg0, tg1) && tg1 > 0.0 ? std::max(tg0, 0.0) : 1e300;
      // Sunlight propagates along -to_sun and leaves toward the camera along -d: the scattering
      // cosine between the two propagation directions is dot(to_sun, d).
      const double mu = glm::dot(d, to_sun);
      glm::dvec3 radiance(0.0);
      double transmittance = 1.0;
      double depth_w = 0.0, depth_t = 0.0;  // where the cloud is: the mean depth of the light it takes out
      // One view sample at distance t standing for a step of ds: in-scattered light and attenuation.
      auto march_sample = [&](double t, double ds) {
        const glm::dvec3 p = origin + t * d;
        double sl, si;
        medium.at(p, sl, si);
        ++img.stats.view_samples;
        const double sigma = sl + si;
        if (sigma <= 0.0) return;
        // Optical depth toward the sun, unless the Earth is in the way.
        const glm::dvec3 up_p = glm::normalize(p);
        const double alt_p = glm::length(p) - r0;
        const double mu_sun = glm::dot(to_sun, up_p), nu_sun = glm::length(glm::cross(to_sun, up_p));
        double e0, e1;
        const bool lit = !medium.sun_down && !(p64::ray_sphere_rel_nu(r0, alt_p, mu_sun, nu_sun, 0.0, e0, e1) && e1 > 0.0);
        const double tau_sun = lit ? medium.sun_depth(p, alt_p, mu_sun, nu_sun, to_sun, s.sun_steps) : 0.0;
        // Sunlight reaches the sample through the air (reddened when low), and the sky lights it
        // too: isotropic irradiance E_sky scattered as sigma_s E_sky / (2 pi) (docs/physics.md).
        const glm::dvec3 sun_air = s.atmosphere && lit ? p64::atmo_transmittance(r0, alt_p, mu_sun, nu_sun, s.atmo_sun_steps)
                                                       : glm::dvec3(1.0);
        const glm::dvec3 ambient = s.atmosphere ? s.ambient * p64::sky_irradiance(sun_air, mu_sun) * (sigma / p64::CV_TWO_PI)
                                                : glm::dvec3(0.0);
        // In-scattered radiance per metre: the octave sums of both phases (clouds do not absorb),
        // gated by the column's optical depth when the gate is on.
        double scatter = 0.0;  // left out where the sun is down (the octave sums cost as much as the rest)
        if (lit) {
          double w = 1.0;
          if (gate) {
            const glm::dvec3 g = p64::ecef_to_sphere(p, r0);
            w = p64::octave_gate_weight(columns.at(grid, g.x / kDeg, g.y / kDeg));
          }
          img.stats.octave_terms += static_cast<std::uint64_t>(p64::octave_terms(s.octaves, s.octave_b, w, gate_tol));
          img.stats.octave_terms_full += static_cast<std::uint64_t>(std::max(s.octaves, 0));
          scatter = (s.liquid_phase_hg ? p64::ms_octaves_hg_gated(sl, mu, liquid_g, tau_sun, s.octaves, s.octave_a, s.octave_b,
                                                                 s.octave_c, w, gate_tol)
                                       : p64::ms_octaves_mie_gated(sl, mu, mie, tau_sun, s.octaves, s.octave_a, s.octave_b,
                                                                   s.octave_c, w, gate_tol)) +
                    p64::ms_octaves_hg_gated(si, mu, s.ice_g, tau_sun, s.octaves, s.octave_a, s.octave_b, s.octave_c, w, gate_tol);
        }
        radiance += transmittance * p64::segment_integral(sun.irradiance * (sun_air * scatter + ambient), sigma, ds);
        // The light the step takes out of the view, T (1 - exp(-sigma ds)), formed as the GPU forms it.
        const double taken = transmittance * p64::segment_integral(sigma, sigma, ds);
        depth_w += taken;
        depth_t += taken * t;
        transmittance *= p64::transmittance(sigma * ds);
      };
      bool crossed = false;
      for (int k = 0; k < n && transmittance > s.min_transmittance; ++k) {
        const double t_start = seg[2 * k], t_end = std::min(seg[2 * k + 1], t_ground);
        if (!(t_end > t_start)) continue;
        crossed = true;
        const int steps = std::max(1, static_cast<int>(std::ceil((t_end - t_start) / s.view_step_m)));
        const double dt = (t_end - t_start) / steps;
        const double offset = step_offset(s, px, py);
        // What the pyramid said about the brick ahead: valid for sample distances below known_end.
        double known_end = -1.0, sigma_max = 0.0;
        for (int i = 0; i < steps && transmittance > s.min_transmittance;) {
          const double t_rel = (i + offset) * dt;
          int substeps = 1;
          if (use_pyramid && !(t_rel < known_end)) {
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
          for (int j = 0; j < substeps && transmittance > s.min_transmittance; ++j) {
            march_sample(t_start + (i + (j + offset) / substeps) * dt, dt / substeps);
          }
          ++i;
        }
      }
      img.stats.rays_missed += !crossed;
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
