// The plane-parallel slab of issue 11 through the normal path: a CF NetCDF file written here, the
// importer, the grid-mean medium, and the Monte Carlo reference, for the comparison with the
// independent adding-doubling solver (tests/physics/slab_solver.hpp). Shared by the test
// (tests/core/slab_check_test.cpp) and the sweep (tests/bench/slab_sweep.cpp).
#pragma once

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <glm/glm.hpp>

#include "geo/geodesy.hpp"
#include "importer.hpp"
#include "reference/monte_carlo.hpp"
#include "reference/raymarcher.hpp"
#include "support/cf_writer.hpp"
#include "volume/grid_mean.hpp"

namespace cv::test::slab {

// Henyey-Greenstein g = 0.85 goes in as ice (the Monte Carlo's ice phase is HG with ice_g); the
// droplet phase goes in as liquid (approximate Mie at 2 r_eff).
enum class SlabPhase { HG085, Mie };
inline const char* phase_name(SlabPhase p) { return p == SlabPhase::HG085 ? "HG 0.85" : "Mie 20 um"; }

// The slab's layout. Levels every dz_m from base_m up; water on levels 1 .. levels - 3, none on the
// first and the last two, so the extinction ramps linearly over one level at the base and at the
// top. The extra clear level on top keeps the cloud inside the volume whichever way the importer's
// altitude grid rounds: it spans floor((z_max - z_min) / dz) + 1 nodes, and z_max recovered from
// the geopotential lands a hair below a whole number of dz, so the highest level falls off. A
// plane-parallel answer depends on the optical depth alone, not on how extinction is spread in the
// vertical (the transfer equation in optical depth is the same), so the ramps do not matter.
struct SlabLayout {
  double half_width_deg = 3.0;  // +-333 km around (0, 0) against 1 km of depth
  double lon_lat_step_deg = 0.5;
  double base_m = 1000.0, dz_m = 100.0;
  int levels = 12;                  // 1000 .. 2100 m, cloud from 1000 to 2000 m
  double temperature_k = 280.0;
  double r_eff_liquid_um = 10.0;    // droplet diameter 20 um, the Mie phase's
  double r_eff_ice_um = 30.0;
  bool cloudy(int k) const { return k >= 1 && k <= levels - 3; }
  // Column optical depth per unit in-cloud extinction (the trapezoid of the piecewise-linear profile).
  double depth_per_sigma_m() const { return dz_m * (levels - 3); }
  double pressure_pa(int k) const { return 90000.0 - 1000.0 * k; }
};

// The file: pressure levels with geopotential (giving the altitudes exactly) and temperature, no
// humidity (q_v = 0) and no cloud fraction (water fills its box), and the cloud water chosen per
// level so that 3 rho q / (2 rho_w r_eff) (rho = p / (R_d T)) is tau / depth_per_sigma_m on the
// inner levels. One time step.
inline void write_slab_file(const std::string& path, double tau, SlabPhase phase, const SlabLayout& L = {}) {
  constexpr double kR = 6371000.0, kG0 = 9.80665, kRd = 287.05;
  const int nx = static_cast<int>(std::lround(2.0 * L.half_width_deg / L.lon_lat_step_deg)) + 1, ny = nx;
  const bool ice = phase == SlabPhase::HG085;
  const double sigma = tau / L.depth_per_sigma_m();
  const double rho_particle = ice ? 917.0 : 1000.0, r_eff_m = (ice ? L.r_eff_ice_um : L.r_eff_liquid_um) * 1e-6;
  PressureLevelFile f;
  for (int i = 0; i < nx; ++i) f.lon.push_back(-L.half_width_deg + L.lon_lat_step_deg * i);
  for (int j = 0; j < ny; ++j) f.lat.push_back(-L.half_width_deg + L.lon_lat_step_deg * j);
  for (int k = 0; k < L.levels; ++k) f.levels_pa.push_back(L.pressure_pa(k));
  f.ice = ice;
  f.geopotential = [&](int, int, int k) {
    const double alt = L.base_m + L.dz_m * k;
    return kG0 * kR * alt / (kR + alt);  // inverse of z = Phi R / (g0 R - Phi)
  };
  f.temperature = [&](int, int, int) { return L.temperature_k; };
  f.water = [&](int, int, int k) {
    const double rho = L.pressure_pa(k) / (kRd * L.temperature_k);
    return !L.cloudy(k) ? 0.0 : 2.0 * rho_particle * r_eff_m * sigma / (3.0 * rho);
  };
  write_pressure_level_file(path, f);
}

// The imported slab: its grid, the renderer's medium, and the column optical depth measured on it.
struct ImportedSlab {
  core::VolumeGrid grid;
  core::GridMeanExtinction medium;
  double liquid_r_eff_um = 10.0;
  double column_tau = 0.0;      // trapezoid over the altitude nodes at the centre column
  double column_spread = 0.0;   // largest relative difference of any column's from it
  std::vector<std::string> warnings;
};

inline ImportedSlab import_slab(const std::string& path, SlabPhase phase, const SlabLayout& L = {}) {
  importers::ImportOptions o;
  o.dz_m = L.dz_m;
  o.r_eff_liquid_um = L.r_eff_liquid_um;
  o.r_eff_ice_um = L.r_eff_ice_um;
  core::CloudVolume vol = importers::import_file(path, o);
  ImportedSlab s;
  s.grid = vol.grid;
  s.liquid_r_eff_um = vol.liquid_r_eff_um;
  s.medium = core::grid_mean_extinction(vol.grid, vol.step(0));
  for (const auto& w : vol.report.warnings) s.warnings.push_back(w);
  const std::vector<float>& f = phase == SlabPhase::HG085 ? s.medium.ice_per_m : s.medium.liquid_per_m;
  const auto& g = s.grid;
  auto column = [&](int i, int j) {
    double tau = 0.0;
    for (int k = 0; k + 1 < g.alt_m.count; ++k) {
      tau += 0.5 * (double(f[g.index(i, j, k)]) + double(f[g.index(i, j, k + 1)])) * g.alt_m.step;
    }
    return tau;
  };
  s.column_tau = column(g.lon_deg.count / 2, g.lat_deg.count / 2);
  for (int j = 0; j < g.lat_deg.count; ++j)
    for (int i = 0; i < g.lon_deg.count; ++i) {
      s.column_spread = std::max(s.column_spread, std::abs(column(i, j) / s.column_tau - 1.0));
    }
  return s;
}

// Clouds only (no air, no globe: black space above and the ground absorbs), the slab's phase.
inline core::MarchSettings march_for(SlabPhase phase, const ImportedSlab& s) {
  core::MarchSettings m;
  m.features.atmosphere = false;
  m.features.globe = false;
  m.medium.ice_g = 0.85;
  m.medium.liquid_phase_hg = false;
  m.medium.droplet_diameter_um = 2.0 * s.liquid_r_eff_um;  // as core::resolve_frame takes it from the data
  (void)phase;
  return m;
}

struct Estimate {
  double mean = 0.0, se = 0.0;
  std::uint64_t paths = 0, truncated = 0, scatterings = 0;
  double seconds = 0.0;
};

inline core::Sun sun_at_zenith_angle(double theta0_deg) {
  core::Sun sun;
  sun.subsolar_lat_deg = theta0_deg;  // seen from (0, 0), where the camera looks
  sun.subsolar_lon_deg = 0.0;
  sun.irradiance = glm::dvec3(1.0);
  return sun;
}

// Reflected radiance per unit irradiance normal to the sun's rays (I / E), from the renderer's pixels
// of `cam` (1 x rows pixels of 1e-3 degree field, a row per thread), their means averaged; `medium`
// is the slab's own or a variant of it.
inline Estimate mc_view_radiance(const ImportedSlab& s, const core::GridMeanExtinction& medium, const core::MarchSettings& m,
                                 const core::Camera& cam, double theta0_deg, int spp, std::uint64_t seed,
                                 int max_bounces = 1000000) {
  core::MonteCarloSettings mc;
  mc.seed = seed;
  mc.max_bounces = max_bounces;
  mc.threads = static_cast<unsigned>(cam.height);
  const auto t0 = std::chrono::steady_clock::now();
  const core::MonteCarloImage img = core::render_monte_carlo(s.grid, medium, cam, sun_at_zenith_angle(theta0_deg), m, mc, spp);
  Estimate e;
  e.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  double var = 0.0;
  for (std::size_t i = 0; i < img.sum.size(); ++i) {
    e.mean += img.mean(i).y / static_cast<double>(img.sum.size());
    var += img.standard_error(i).y * img.standard_error(i).y;
  }
  e.se = std::sqrt(var) / static_cast<double>(img.sum.size());
  e.paths = img.stats.paths;
  e.truncated = img.stats.truncated;
  e.scatterings = img.stats.scatterings;
  return e;
}

// The march kernel's (CPU) reflected radiance per unit irradiance at nadir over (0, 0): a camera
// 10 km up looking straight down, one pixel, 5 m view steps and 256 sun steps; the globe takes its
// ground from `ground` where given (else the constant ground_albedo).
inline double march_nadir_radiance(const ImportedSlab& s, core::MarchSettings m, double theta0_deg,
                                   const core::AlbedoMap* ground = nullptr) {
  core::Camera cam;
  cam.alt_m = 10000.0;
  cam.pitch_deg = -90.0;
  cam.fov_deg = 1e-3;
  cam.width = cam.height = 1;
  m.quality.view_step_m = 5.0;
  m.quality.sun_steps = 256;
  return core::render_reference(s.grid, s.medium, cam, sun_at_zenith_angle(theta0_deg), m, nullptr, ground).radiance[0].y;
}

// Reflected radiance at nadir over (0, 0): a camera 10 km up looking straight down.
inline Estimate mc_nadir_radiance(const ImportedSlab& s, const core::MarchSettings& m, double theta0_deg, int spp,
                                  std::uint64_t seed, int rows = 2) {
  core::Camera cam;
  cam.alt_m = 10000.0;
  cam.pitch_deg = -90.0;
  cam.fov_deg = 1e-3;
  cam.width = 1;
  cam.height = rows;
  return mc_view_radiance(s, s.medium, m, cam, theta0_deg, spp, seed);
}

// A camera over (0, 0) that sees the slab's top at view zenith angle view_zenith_deg, heading
// heading_deg from the sun's azimuth (0: looking toward the sun; the sun is to the north). It stands
// 2.5 km up, half a kilometre above the top, so that even an 85-degree view meets the top within
// 6 km, where the Earth's curvature turns the view by 0.06 degrees (from 10 km up the top lies about
// 100 km off at 85 degrees, 0.9 degrees turned, and the curved slab's radiance there is 1-10 % below
// the plane-parallel one).
inline core::Camera oblique_camera(double view_zenith_deg, double heading_deg, int rows = 2) {
  core::Camera cam;
  cam.alt_m = 2500.0;
  cam.heading_deg = heading_deg;
  cam.pitch_deg = -(90.0 - view_zenith_deg);
  cam.fov_deg = 1e-3;
  cam.width = 1;
  cam.height = rows;
  return cam;
}

// Plane albedo and transmission by the analog estimator: paths started just above the top at (0, 0)
// along the sun's rays, traced by MonteCarloRenderer::trace (delta tracking, phase sampling; its
// next-event radiance is not used), each ending in space (reflected), on the ground (transmitted,
// direct beam included) or cut short (lost). Binomial standard errors. Two lanes of fixed index sets,
// each on its own thread, so the counts do not depend on the machine.
struct AnalogFluxes {
  std::uint64_t paths = 0, reflected = 0, transmitted = 0, lost = 0, scatterings = 0;
  double seconds = 0.0;
  double albedo() const { return double(reflected) / double(paths); }
  double transmission() const { return double(transmitted) / double(paths); }
  double albedo_se() const { return std::sqrt(albedo() * (1.0 - albedo()) / double(paths)); }
};

inline AnalogFluxes mc_analog_fluxes(const ImportedSlab& s, const core::MarchSettings& m, double theta0_deg, int paths,
                                     std::uint64_t seed) {
  core::Camera cam;  // unused by trace, required by the renderer
  cam.width = cam.height = 1;
  core::MonteCarloSettings mc;
  mc.seed = seed;
  mc.max_bounces = 1000000;
  mc.peak_mis = false;  // the analog walk: the peak technique's branches would weight it
  const core::Sun sun = sun_at_zenith_angle(theta0_deg);
  const core::MonteCarloRenderer r(s.grid, s.medium, cam, sun, m, mc);
  const double r0 = s.grid.earth_radius_m;
  const glm::dvec3 to_sun = glm::normalize(geo::sphere_to_ecef({sun.subsolar_lat_deg, sun.subsolar_lon_deg, 0.0}, r0));
  // On the sun's ray through the top of the slab above (0, 0), 10 m above the top.
  const glm::dvec3 top = geo::sphere_to_ecef({0.0, 0.0, s.grid.alt_m.last()}, r0);
  const glm::dvec3 start = top + 10.0 / glm::dot(to_sun, glm::normalize(top)) * to_sun;
  constexpr int kLanes = 2;
  AnalogFluxes lane[kLanes];
  const auto t0 = std::chrono::steady_clock::now();
  auto work = [&](int w) {
    core::MonteCarloStats st;
    for (int i = w; i < paths; i += kLanes) {
      core::PathRng rng(seed, 0, static_cast<std::uint64_t>(i));
      const auto res = r.trace(start, -to_sun, rng, st);
      ++lane[w].paths;
      switch (res.end) {
        case core::MonteCarloRenderer::End::Space: ++lane[w].reflected; break;
        case core::MonteCarloRenderer::End::Ground: ++lane[w].transmitted; break;
        default: ++lane[w].lost; break;
      }
      lane[w].scatterings += static_cast<std::uint64_t>(res.scatterings);
    }
  };
  std::thread other(work, 1);
  work(0);
  other.join();
  AnalogFluxes f;
  for (const auto& l : lane) {
    f.paths += l.paths;
    f.reflected += l.reflected;
    f.transmitted += l.transmitted;
    f.lost += l.lost;
    f.scatterings += l.scatterings;
  }
  f.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return f;
}

}  // namespace cv::test::slab
