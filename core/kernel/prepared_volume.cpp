// Preparing a time step for the march, and the kernel's per-frame parameters.
#include "kernel/prepared_volume.hpp"

#include <cmath>

#include <algorithm>
#include <chrono>
#include <limits>
#include <utility>

#include "geo/geodesy.hpp"
#include "kernel/march_limits.hpp"
#include "kernel/ms_source.hpp"
#include "noise/noise.hpp"
#include "physics/physics.hpp"
#include "reference/earth_shadow.hpp"
#include "volume/sampler.hpp"

namespace cv::core {

namespace {
// The ice's part of each column's optical depth, of the medium the mask shows, into the column
// map's second layer (.r): column_depth's trapezoid, in the same order.
void fill_ice_depths(const PreparedVolume& v, const MediumMask& mask, std::vector<float>& maps) {
  const VolumeGrid& g = v.grid;
  const int nz = g.alt_m.count;
  const std::size_t columns = static_cast<std::size_t>(g.lon_deg.count) * static_cast<std::size_t>(g.lat_deg.count);
  if (maps.size() < kColumnMapLayers * kColumnMapChannels * columns) return;
  const std::vector<float>& ice = v.extinction.ice_per_m;
  std::vector<float> sum(columns, 0.0f);
  // Level by level along the field's layout, in float (a column's levels lie a layer apart: read
  // column by column in double the pass took about 90 ms on a global 0.25-degree grid of 46 levels,
  // level by level about 10 ms; float's rounding over the levels is a few parts in a million).
  if (!ice.empty() && !mask.hide_ice && nz > 1 && ice.size() >= columns * static_cast<std::size_t>(nz)) {
    for (int k = 0; k < nz; ++k) {
      const float* level = ice.data() + static_cast<std::size_t>(k) * columns;
      const float w = k == 0 || k == nz - 1 ? 0.5f : 1.0f;
      const double alt = g.alt_m.at(k);
      if (!mask.band) {
        for (std::size_t c = 0; c < columns; ++c) sum[c] += w * std::max(0.0f, level[c]);
        continue;
      }
      for (std::size_t c = 0; c < columns; ++c) {
        if (mask.shown(alt, maps[kColumnMapChannels * c + 1])) sum[c] += w * std::max(0.0f, level[c]);
      }
    }
  }
  float* layer = maps.data() + kColumnMapChannels * columns;
  for (std::size_t c = 0; c < columns; ++c) layer[kColumnMapChannels * c] = static_cast<float>(double(sum[c]) * g.alt_m.step);
}
}  // namespace

PreparedVolume prepare_volume(const VolumeGrid& grid, GridMeanExtinction extinction, bool weather) {
  PreparedVolume v;
  v.grid = grid;
  v.extinction = std::move(extinction);
  // A field left empty is no cloud: the kernel fetches every node of both.
  for (std::vector<float>* f : {&v.extinction.liquid_per_m, &v.extinction.ice_per_m}) {
    if (f->empty()) f->assign(grid.points(), 0.0f);
  }
  // The weather textures, and the cover diagnosed from the water where the file gives none.
  if (weather) {
    const auto t0 = std::chrono::steady_clock::now();
    const bool diagnose = v.extinction.fraction.size() != grid.points();
    if (diagnose) v.extinction.fraction = diagnosed_fraction(grid, v.extinction);
    v.weather = weather_textures(grid, v.extinction, diagnose);
    v.weather.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  }
  const GridMeanExtinction& e = v.extinction;
  v.layer = cloud_layer(grid, e);
  v.sigma_max_per_m = largest_extinction(e);
  v.wraps = grid.wraps_lon();
  v.global_lat = VolumeSampler(grid, e.liquid_per_m).global_lat();
  v.columns = column_depth(grid, e.liquid_per_m, e.ice_per_m);
  v.column_maps.assign(kColumnMapLayers * kColumnMapChannels * v.columns.tau.size(), 0.0f);
  const std::vector<float> types = detail_type_memberships(grid, v.weather);
  for (std::size_t c = 0; c < v.columns.tau.size(); ++c) {
    v.column_maps[kColumnMapChannels * c] = v.columns.tau[c];
    const float ground = c < e.ground_m.size() ? e.ground_m[c] : 0.0f;
    v.column_maps[kColumnMapChannels * c + 1] = std::isfinite(ground) ? ground : 0.0f;  // unknown terrain: sea level
    v.column_maps[kColumnMapChannels * c + 2] = types[2 * c];
    v.column_maps[kColumnMapChannels * c + 3] = types[2 * c + 1];
  }
  fill_ice_depths(v, MediumMask{}, v.column_maps);
  v.pyramid = ExtinctionPyramid(grid, e.liquid_per_m, e.ice_per_m);
  int offset = 0;
  const auto& levels = v.pyramid.levels();
  for (std::size_t l = 0; l < levels.size(); ++l) {
    v.level_offset[l] = offset;
    offset += static_cast<int>(levels[l].min_max.size());
    v.pyramid_packed.insert(v.pyramid_packed.end(), levels[l].min_max.begin(), levels[l].min_max.end());
  }
  return v;
}

kernel::MarchParams march_params(const PreparedVolume& v, const Camera& cam, const Sun& sun, const MarchSettings& s,
                                 glm::ivec2 ground_size) {
  const VolumeGrid& grid = v.grid;
  const double r0 = grid.earth_radius_m;
  const CameraFrame c = camera_frame(cam);
  kernel::MarchParams p;
  // The settings that go in as they are (CV_MARCH_UNIFORM rows of march_settings.def); the rest
  // below are derived from the settings, the camera, the sun and the prepared volume.
#define CV_MARCH_SETTING(TYPE, NAME, DEF, GROUP, FIELDS)
#define CV_MARCH_UNIFORM(GROUP, MEMBER, UNIFORM) p.UNIFORM = s.CV_SETTING_GROUP(GROUP).MEMBER;
#include "settings/march_settings.def"
#undef CV_MARCH_UNIFORM
#undef CV_MARCH_SETTING
  p.u_size = {cam.width, cam.height};
  p.u_pixel_shift = {cam.pixel_shift_x, cam.pixel_shift_y};
  p.u_pixel_block = cam.pixel_block;
  p.u_block_origin = {cam.block_x, cam.block_y};
  p.u_cam_ecef = geo::sphere_to_ecef({cam.lat_deg, cam.lon_deg, cam.alt_m}, r0);
  p.u_cam_alt = cam.alt_m;
  p.u_cam_up = geo::sphere_enu(cam.lat_deg, cam.lon_deg).up;
  p.u_forward = c.forward;
  p.u_right = c.right;
  p.u_upv = c.up;
  p.u_tan_half = c.tan_half;
  p.u_to_sun = glm::normalize(geo::sphere_to_ecef({sun.subsolar_lat_deg, sun.subsolar_lon_deg, 0.0}, r0));
  // Night over the whole cloud layer: decided here once, in double, with a margin (earth_shadow.hpp).
  p.u_sun_down = s.features.leave_out_night && layer_in_earth_shadow(grid, v.layer, p.u_to_sun);
  p.u_irradiance = sun.irradiance;
  p.u_r0 = r0;
  p.u_grid_start = {grid.lon_deg.start, grid.lat_deg.start, grid.alt_m.start};
  p.u_grid_step = {grid.lon_deg.step, grid.lat_deg.step, grid.alt_m.step};
  p.u_grid_count = {double(grid.lon_deg.count), double(grid.lat_deg.count), double(grid.alt_m.count)};
  p.u_wraps = v.wraps;
  p.u_global_lat = v.global_lat;
  p.u_layer = {v.layer.bottom_m, v.layer.top_m};
  p.u_cloudless = v.layer.empty;
  p.u_mask_band = layer_band_set(s);
  p.u_tint = tint_set(s);
  p.u_sigma_max = v.sigma_max_per_m;
  p.u_sun_step_max = sun_step_limit_m(grid, v.layer, s);
  p.u_octave_abc = {s.medium.octave_a, s.medium.octave_b, s.medium.octave_c};
  if (s.medium.ms_two_stream) {
    const MsPeaks peaks = ms_peaks(s);
    p.u_ms_peak_liquid = peaks.liquid.cut;
    p.u_ms_peak_ice = peaks.ice.cut;
    p.u_ms_peak_g_liquid = peaks.liquid.g;
    p.u_ms_peak_g_ice = peaks.ice.g;
    p.u_ms_beam_a_liquid = peaks.beam ? peaks.beam->spike_share : 0.0;
    p.u_ms_f_liquid = peaks.f_liquid;
    p.u_ms_f_ice = peaks.f_ice;
  }
  if (s.medium.noise_amount > 0.0) {
    const NoiseAnchor a = noise_anchor(grid_centre_ecef(grid), s.medium.noise_scale_m);
    p.u_noise_anchor = a.ecef_m;  // float-exact by construction
    p.u_noise_anchor_frac = a.frac;
    p.u_noise_period = s.medium.noise_scale_m;
    p.u_noise_amount = s.medium.noise_amount;
  }
  if (s.medium.modelled) {
    // Whole noise tiles per grid cell, each about detail_scale_m wide at the grid's middle latitude;
    // one tile per level spacing in altitude.
    const double deg = 3.14159265358979323846 / 180.0;
    const double mid_lat = grid.lat_deg.start + 0.5 * grid.lat_deg.step * (grid.lat_deg.count - 1);
    const double dx_m = std::abs(grid.lon_deg.step) * deg * r0 * std::max(std::cos(mid_lat * deg), 0.05);
    const double dy_m = std::abs(grid.lat_deg.step) * deg * r0;
    auto tiles = [&](double cell_m) { return std::max(1.0, std::round(cell_m / s.medium.detail_scale_m)); };
    p.u_detail_tiles = {tiles(dx_m), tiles(dy_m), 1.0};
    p.u_has_fraction = v.extinction.fraction.size() == grid.points();
  }
  p.u_ground_size = ground_size;
  // Float's largest finite value bounds it, so the GPU's copy is never Inf.
  p.u_sun_tau_limit = std::min(3.0e38, physics::f64::sun_march_tau_limit(s.quality.octaves, s.medium.octave_a, s.quality.min_transmittance));
  const auto& levels = v.pyramid.levels();
  p.u_levels = static_cast<int>(levels.size());
  for (std::size_t l = 0; l < levels.size(); ++l) {
    p.u_bricks[l] = {levels[l].nx, levels[l].ny, levels[l].nz, 0};
    p.u_level_nodes[static_cast<int>(l)] = levels[l].nodes;
    p.u_level_offset[static_cast<int>(l)] = v.level_offset[l];
  }
  return p;
}

std::vector<double> detail_least_means(const std::vector<float>& table) {
  constexpr std::size_t row = CV_DETAIL_COVERS + 1;
  std::vector<double> out(std::size_t(CV_DETAIL_TYPES) * row, 0.0);
  for (int type = 0; type < CV_DETAIL_TYPES; ++type) {
    for (std::size_t e = 0; e < row; ++e) {
      auto mean_at = [&](std::size_t r) {
        const std::size_t i = 2 * (r * row + e) + 1;
        return i < table.size() ? double(table[i]) : std::numeric_limits<double>::infinity();
      };
      double m = mean_at(static_cast<std::size_t>(type));
      for (int j = 0; j < CV_DETAIL_SLICES; ++j) {
        m = std::min(m, mean_at(std::size_t(CV_DETAIL_SLICE_ROW0) + std::size_t(j) * CV_DETAIL_TYPES + static_cast<std::size_t>(type)));
      }
      out[std::size_t(type) * row + e] = std::isfinite(m) ? m : 0.0;
    }
  }
  return out;
}

double medium_majorant(const PreparedVolume& v, const MarchSettings& s, const std::vector<float>& table) {
  if (!s.medium.modelled) return v.sigma_max_per_m;
  // c / m(c) = 1 at full cover; the types' blend is at most the largest row's, and a blend of two
  // slices' rows at most the larger of theirs: every (threshold, mean) row, the whole tile's and
  // each slice's.
  double k = 1.0;
  const std::vector<double> least = detail_least_means(table);
  for (int type = 0; type < CV_DETAIL_TYPES; ++type) {
    for (int e = 1; e <= CV_DETAIL_COVERS; ++e) {
      const double c = (double(e) / CV_DETAIL_COVERS) * (double(e) / CV_DETAIL_COVERS);
      const double m = least[std::size_t(type) * (CV_DETAIL_COVERS + 1) + std::size_t(e)];
      if (m > 0.0) k = std::max(k, c / m);
    }
  }
  const GridMeanExtinction& x = v.extinction;
  double in_cloud = 0.0;
  if (x.fraction.empty()) {
    in_cloud = v.sigma_max_per_m;  // cover 1 everywhere: s / c = s
  } else {
    for (std::size_t i = 0; i < x.fraction.size(); ++i) {
      const double sum = (i < x.liquid_per_m.size() ? double(x.liquid_per_m[i]) : 0.0) + (i < x.ice_per_m.size() ? double(x.ice_per_m[i]) : 0.0);
      if (!(sum > 0.0)) continue;
      if (!(x.fraction[i] > 0.0f)) return std::numeric_limits<double>::infinity();
      in_cloud = std::max(in_cloud, sum / double(x.fraction[i]));
    }
  }
  const double a = std::clamp(s.medium.detail_amount, 0.0, 1.0);
  // The cell-mean correction multiplies the factor by at most CV_DETAIL_CORRECTION_MAX.
  return CV_DETAIL_CORRECTION_MAX * ((1.0 - a) * v.sigma_max_per_m + a * k * in_cloud);
}

std::vector<glm::vec2> medium_pyramid(const PreparedVolume& v, const MarchSettings& s, const std::vector<float>& table) {
  if (!s.medium.modelled) return v.pyramid_packed;
  const GridMeanExtinction& x = v.extinction;
  const std::size_t n = v.grid.points();
  constexpr float kHuge = 3.0e38f;  // extinction without a fraction to bound it: never skipped, never a small step
  std::vector<float> ratio(n, 0.0f), cover(n, 1.0f);
  const bool has_fraction = x.fraction.size() == n;
  for (std::size_t i = 0; i < n; ++i) {
    const double sum = (i < x.liquid_per_m.size() ? double(x.liquid_per_m[i]) : 0.0) + (i < x.ice_per_m.size() ? double(x.ice_per_m[i]) : 0.0);
    const double c = has_fraction ? std::clamp(double(x.fraction[i]), 0.0, 1.0) : 1.0;  // NaN -> 0 (prepare_volume made none)
    cover[i] = static_cast<float>(c);
    if (!(sum > 0.0)) continue;
    // Rounded up, so the float bound is not below the double ratio.
    ratio[i] = c > 0.0 ? static_cast<float>(std::min(sum / c * (1.0 + 1e-6), double(kHuge))) : kHuge;
  }
  // Each brick's largest ratio, and its smallest and largest cover, over the same dilated nodes.
  const ExtinctionPyramid pr(v.grid, ratio, {}), pc(v.grid, cover, {});
  // K of one type's row over table entries e0..e1: the largest c / m(c) (1 at full cover).
  constexpr int covers = CV_DETAIL_COVERS;
  const int rows = std::min(int(table.size() / (2 * (covers + 1))), CV_DETAIL_TYPES);  // the types' (t, m) rows
  const std::vector<double> least = detail_least_means(table);
  auto k_row = [&](int row, double lo, double hi) {
    const int e0 = std::clamp(int(std::floor(std::sqrt(std::max(lo, 0.0)) * covers)), 0, covers);
    const int e1 = std::clamp(int(std::ceil(std::sqrt(std::min(hi, 1.0)) * covers)), e0, covers);
    double k = 1.0;
    for (int e = std::max(e0, 1); e <= e1; ++e) {
      const double c = (double(e) / covers) * (double(e) / covers);
      const double m = least[std::size_t(row) * (covers + 1) + std::size_t(e)];
      if (m > 0.0) k = std::max(k, c / m);
    }
    return k;
  };
  // The types a brick's samples can blend (march.glsl detail_factor_of: the memberships bilinear
  // from the columns, so those of the brick's dilated columns): the factor is at most
  // sum_k w_k / m_k, so c x factor at most min(max_k K_k, sum_k (largest w_k) K_k) over the types
  // present. Per level, per column of bricks.
  const VolumeGrid& g = v.grid;
  const int gx = g.lon_deg.count, gy = g.lat_deg.count;
  const bool wraps = g.wraps_lon();
  auto weights = [&](std::size_t col) {
    const std::size_t at = kColumnMapChannels * col;
    const double cu = at + 3 < v.column_maps.size() ? std::clamp(double(v.column_maps[at + 2]), 0.0, 1.0) : 0.0;
    const double ci = at + 3 < v.column_maps.size() ? std::clamp(double(v.column_maps[at + 3]), 0.0, 1.0 - cu) : 0.0;
    return glm::dvec3(1.0 - cu - ci, cu, ci);
  };
  const double a = std::clamp(s.medium.detail_amount, 0.0, 1.0);
  std::vector<glm::vec2> out;
  out.reserve(v.pyramid_packed.size());
  const auto& ls = v.pyramid.levels();
  for (std::size_t l = 0; l < ls.size(); ++l) {
    const auto& S = ls[l].min_max;
    const auto& R = pr.levels()[l].min_max;
    const auto& C = pc.levels()[l].min_max;
    const ExtinctionPyramid::Level& lv = ls[l];
    std::vector<glm::dvec3> wmax(std::size_t(lv.nx) * std::size_t(lv.ny), glm::dvec3(0.0));
    for (int by = 0; by < lv.ny; ++by) {
      for (int bx = 0; bx < lv.nx; ++bx) {
        glm::dvec3& w = wmax[std::size_t(by) * std::size_t(lv.nx) + std::size_t(bx)];
        for (int j = by * lv.nodes - 1; j <= by * lv.nodes + lv.nodes; ++j) {
          for (int i = bx * lv.nodes - 1; i <= bx * lv.nodes + lv.nodes; ++i) {
            int ii = i;
            if (ii < 0 || ii >= gx) ii = wraps ? (ii + gx) % gx : -1;
            // Beyond a regional grid's border the column map reads 0: all stratiform.
            w = glm::max(w, ii < 0 || j < 0 || j >= gy ? glm::dvec3(1.0, 0.0, 0.0) : weights(g.column(ii, j)));
          }
        }
      }
    }
    for (std::size_t b = 0; b < S.size(); ++b) {
      double bound = 0.0;
      if (R[b].y > 0.0f) {
        const double c_lo = C[b].x, c_hi = C[b].y;
        const glm::dvec3 w = wmax[b % (std::size_t(lv.nx) * std::size_t(lv.ny))];
        double k_max = rows < 1 ? double(kHuge) : 1.0, k_sum = 0.0;
        for (int row = 0; row < rows; ++row) {
          if (!(w[row] > 0.0)) continue;
          const double k = k_row(row, c_lo, c_hi);
          k_max = std::max(k_max, k), k_sum += w[row] * k;
        }
        const double k = rows < 1 ? double(kHuge) : std::min(k_max, std::max(k_sum, 1.0));
        const double r = double(R[b].y) >= double(kHuge) ? double(kHuge) : double(R[b].y) * k;
        bound = std::min(CV_DETAIL_CORRECTION_MAX * ((1.0 - a) * double(S[b].y) + a * r), double(kHuge));  // with the cell-mean correction
      }
      out.emplace_back(0.0f, static_cast<float>(bound * (1.0 + 1e-6)));
    }
  }
  return out;
}

MediumMask medium_mask(const MarchSettings& s) {
  MediumMask m;
  m.hide_liquid = s.medium.hide_liquid;
  m.hide_ice = s.medium.hide_ice;
  m.band = layer_band_set(s);
  if (m.band) {
    m.sea_level = s.medium.layer_sea_level;
    m.bottom_m = s.medium.layer_bottom_m;
    m.top_m = s.medium.layer_top_m;
  }
  return m;
}

std::vector<float> column_maps_for(const PreparedVolume& v, const MediumMask& mask) {
  if (!mask.any()) return v.column_maps;
  std::vector<float> out = v.column_maps;
  const VolumeGrid& g = v.grid;
  const int nz = g.alt_m.count;
  const std::vector<float>& liquid = v.extinction.liquid_per_m;
  const std::vector<float>& ice = v.extinction.ice_per_m;
  for (int y = 0; y < g.lat_deg.count; ++y) {
    for (int x = 0; x < g.lon_deg.count; ++x) {
      const std::size_t c = g.column(x, y);
      const double ground = out[kColumnMapChannels * c + 1];
      double sum = 0.0;  // column_depth's trapezoid, in the same order
      for (int k = 0; k < nz; ++k) {
        const std::size_t i = g.index(x, y, k);
        if (!mask.shown(g.alt_m.at(k), ground)) continue;
        const double s = (liquid.empty() || mask.hide_liquid ? 0.0 : double(liquid[i])) + (ice.empty() || mask.hide_ice ? 0.0 : double(ice[i]));
        sum += k == 0 || k == nz - 1 ? 0.5 * s : s;
      }
      out[kColumnMapChannels * c] = nz > 1 ? static_cast<float>(sum * g.alt_m.step) : 0.0f;
    }
  }
  fill_ice_depths(v, mask, out);
  return out;
}

}  // namespace cv::core
