// The weather textures: per-column maps and the types' vertical profiles (docs/physics.md).
#include "kernel/weather_textures.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

namespace cv::core {

namespace {

double ramp(double x, double lo, double hi) { return std::clamp((x - lo) / (hi - lo), 0.0, 1.0); }
double smooth(double lo, double hi, double x) {
  const double t = ramp(x, lo, hi);
  return t * t * (3.0 - 2.0 * t);
}

// A run of cloudy levels in one column, lowest first.
struct Run {
  int k_base = 0, k_top = 0;
  double tau_liquid = 0.0, tau_ice = 0.0, cover_sum = 0.0;
};

// The runs of a column: contiguous levels for which cloudy(k) holds.
template <class Cloudy, class Node>
void column_runs(int levels, double dz, Cloudy cloudy, Node node, std::vector<Run>& runs) {
  runs.clear();
  bool open = false;
  for (int k = 0; k < levels; ++k) {
    if (!cloudy(k)) {
      open = false;
      continue;
    }
    if (!open) runs.push_back(Run{k, k}), open = true;
    Run& r = runs.back();
    r.k_top = k;
    double sl, si, c;
    node(k, sl, si, c);
    r.tau_liquid += sl * dz, r.tau_ice += si * dz, r.cover_sum += c;
  }
}

CloudLayerTraits traits_of(const Run& r, const VolumeGrid& grid, double ground, double lapse) {
  CloudLayerTraits t;
  const double dz = grid.alt_m.step;
  t.thickness_m = grid.alt_m.at(r.k_top) - grid.alt_m.at(r.k_base) + dz;
  t.base_above_ground_m = grid.alt_m.at(r.k_base) - ground;
  const double tau = r.tau_liquid + r.tau_ice;
  t.ice_share = tau > 0.0 ? r.tau_ice / tau : 0.0;
  t.mean_cover = r.cover_sum / double(r.k_top - r.k_base + 1);
  t.lapse_k_per_km = lapse;
  return t;
}

// The normalised height of level k in its run: the middle of the level's share of the run.
double eta_in(const Run& r, int k) { return (double(k - r.k_base) + 0.5) / double(r.k_top - r.k_base + 1); }

double ground_of(const GridMeanExtinction& m, std::size_t col) {
  return col < m.ground_m.size() && std::isfinite(m.ground_m[col]) ? m.ground_m[col] : 0.0;
}
double lapse_of(const GridMeanExtinction& m, std::size_t col) {
  return col < m.lapse_k_per_km.size() ? m.lapse_k_per_km[col] : std::numeric_limits<double>::quiet_NaN();
}
double at(const std::vector<float>& f, std::size_t p) { return p < f.size() && f[p] > 0.0f ? f[p] : 0.0; }

// The first guess of the diagnosed cover, without a profile: the share of the box that holds the
// water at the typical in-cloud extinctions.
double plain_cover(double sl, double si) {
  return std::min(1.0, std::max(sl / kTypicalLiquidExtinctionPerM, si / kTypicalIceExtinctionPerM));
}

}  // namespace

const char* cloud_type_name(CloudType t) {
  switch (t) {
    case CloudType::Stratiform: return "stratiform";
    case CloudType::Cumuliform: return "cumuliform";
    case CloudType::Cirriform: return "cirriform";
    default: return "none";
  }
}

std::array<double, 3> cloud_type_memberships(const CloudLayerTraits& t) {
  // Cirriform: mostly ice, based high above the ground.
  const double ci = ramp(t.ice_share, 0.5, 0.9) * ramp(t.base_above_ground_m, 4500.0, 6500.0);
  // The convective signal: broken cover, and a lapse rate steeper than the moist adiabat's where the
  // file gives temperatures; the depth tips it (a deep layer leans cumuliform, a thin one stratiform).
  const double broken = 1.0 - ramp(t.mean_cover, 0.4, 0.8);
  const double x = std::isfinite(t.lapse_k_per_km) ? 0.5 * (broken + ramp(t.lapse_k_per_km, 5.5, 7.5)) : broken;
  const double depth = ramp(t.thickness_m, 1000.0, 4000.0);
  const double cu = std::clamp(x + 0.3 * (depth - 0.5), 0.0, 1.0);
  return {(1.0 - ci) * (1.0 - cu), (1.0 - ci) * cu, ci};
}

CloudType dominant_type(const std::array<double, 3>& m) {
  if (m[0] + m[1] + m[2] <= 0.0) return CloudType::None;
  const int i = m[2] >= m[0] && m[2] >= m[1] ? 2 : m[1] > m[0] ? 1 : 0;
  return static_cast<CloudType>(i + 1);
}

double type_profile(CloudType t, double eta) {
  eta = std::clamp(eta, 0.0, 1.0);
  switch (t) {
    case CloudType::Stratiform:  // water growing with height (adiabatic), cut at the top by entrainment
      return (0.3 + 0.7 * eta) * (1.0 - smooth(0.85, 1.0, eta)) * smooth(0.0, 0.1, eta);
    case CloudType::Cumuliform:  // a flat base, the core low, thinning towards a rounded top
      return smooth(0.0, 0.1, eta) * (1.0 - smooth(0.5, 1.0, eta) * 0.9);
    case CloudType::Cirriform:  // a thin sheet, densest in its middle
      return 4.0 * eta * (1.0 - eta);
    default: return 1.0;
  }
}

std::vector<float> diagnosed_fraction(const VolumeGrid& grid, const GridMeanExtinction& m) {
  const int nz = grid.alt_m.count;
  std::vector<float> out(grid.points(), 0.0f);
  std::vector<Run> runs;
  for (int j = 0; j < grid.lat_deg.count; ++j) {
    for (int i = 0; i < grid.lon_deg.count; ++i) {
      const std::size_t col = grid.column(i, j);
      const auto s_l = [&](int k) { return at(m.liquid_per_m, grid.index(i, j, k)); };
      const auto s_i = [&](int k) { return at(m.ice_per_m, grid.index(i, j, k)); };
      // Runs of levels with water, classified with the plain cover as their mean cover.
      column_runs(
          nz, grid.alt_m.step, [&](int k) { return s_l(k) + s_i(k) >= 1e-8; },
          [&](int k, double& sl, double& si, double& c) { sl = s_l(k), si = s_i(k), c = plain_cover(sl, si); }, runs);
      for (const Run& r : runs) {
        const CloudType type = dominant_type(cloud_type_memberships(traits_of(r, grid, ground_of(m, col), lapse_of(m, col))));
        for (int k = r.k_base; k <= r.k_top; ++k) {
          const double shape = 0.25 + 0.75 * type_profile(type, eta_in(r, k));
          const double c = std::max(s_l(k) / (kTypicalLiquidExtinctionPerM * shape), s_i(k) / (kTypicalIceExtinctionPerM * shape));
          out[grid.index(i, j, k)] = static_cast<float>(std::min(1.0, c));
        }
      }
      // Water below the run threshold (packing noise) still gets its plain share, so no node with
      // extinction is left without cover.
      for (int k = 0; k < nz; ++k) {
        float& c = out[grid.index(i, j, k)];
        if (c == 0.0f && s_l(k) + s_i(k) > 0.0) c = static_cast<float>(std::max(plain_cover(s_l(k), s_i(k)), 1e-6));
      }
    }
  }
  return out;
}

WeatherTextures weather_textures(const VolumeGrid& grid, const GridMeanExtinction& m, bool fraction_diagnosed) {
  const auto t0 = std::chrono::steady_clock::now();
  WeatherTextures w;
  w.nx = grid.lon_deg.count, w.ny = grid.lat_deg.count;
  const std::size_t ncol = grid.columns();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (auto* v : {&w.cover, &w.cover_low, &w.cover_mid, &w.cover_high}) v->assign(ncol, 0.0f);
  for (auto* v : {&w.base_m, &w.top_m, &w.ice_share}) v->assign(ncol, nan);
  w.type.assign(ncol, CloudType::None);
  w.memberships.assign(3 * ncol, 0.0f);
  w.cover_from_water = fraction_diagnosed;
  w.heights_above_ground = m.ground_m.size() == ncol;
  w.has_lapse_rate = m.lapse_k_per_km.size() == ncol;
  const MapOptions o;
  const int nz = grid.alt_m.count;
  const bool has_fraction = m.fraction.size() == grid.points();
  std::vector<Run> runs;
  for (int j = 0; j < grid.lat_deg.count; ++j) {
    for (int i = 0; i < grid.lon_deg.count; ++i) {
      const std::size_t col = grid.column(i, j);
      const double ground = ground_of(m, col);
      const auto node = [&](int k, double& sl, double& si, double& c) {
        const std::size_t p = grid.index(i, j, k);
        sl = at(m.liquid_per_m, p), si = at(m.ice_per_m, p);
        c = has_fraction ? std::min(1.0, at(m.fraction, p)) : (sl + si > 0.0 ? 1.0 : 0.0);
      };
      // A level is cloudy as the derived maps count it: its cover and in-cloud extinction (grid-mean
      // over cover) both reach MapOptions' thresholds.
      const auto cloudy = [&](int k) {
        double sl, si, c;
        node(k, sl, si, c);
        return c > 0.0 && map_cloudy(c, (sl + si) / c, o);
      };
      column_runs(nz, grid.alt_m.step, cloudy, node, runs);
      if (runs.empty()) continue;
      MaxRandomOverlap all, low, mid, high;
      double tau_l = 0.0, tau_i = 0.0;
      for (int k = nz - 1; k >= 0; --k) {  // from the top, as MaxRandomOverlap is fed
        const double above = grid.alt_m.at(k) - ground;
        MaxRandomOverlap& layer = above < o.low_top_m ? low : above < o.mid_top_m ? mid : high;
        if (!cloudy(k)) {
          all.gap(), layer.gap();
          continue;
        }
        double sl, si, c;
        node(k, sl, si, c);
        all.add(c), layer.add(c);
      }
      const Run* main = &runs.front();
      for (const Run& r : runs) {
        tau_l += r.tau_liquid, tau_i += r.tau_ice;
        if (r.tau_liquid + r.tau_ice > main->tau_liquid + main->tau_ice) main = &r;
      }
      w.cover[col] = float(all.cover()), w.cover_low[col] = float(low.cover());
      w.cover_mid[col] = float(mid.cover()), w.cover_high[col] = float(high.cover());
      w.base_m[col] = float(grid.alt_m.at(runs.front().k_base));
      w.top_m[col] = float(grid.alt_m.at(runs.back().k_top));
      w.ice_share[col] = tau_l + tau_i > 0.0 ? float(tau_i / (tau_l + tau_i)) : 0.0f;
      const std::array<double, 3> mem = cloud_type_memberships(traits_of(*main, grid, ground, lapse_of(m, col)));
      for (int t = 0; t < 3; ++t) w.memberships[3 * col + std::size_t(t)] = float(mem[std::size_t(t)]);
      w.type[col] = dominant_type(mem);
      ++w.columns_of_type[static_cast<std::size_t>(w.type[col])];
    }
  }
  w.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return w;
}

std::vector<float> detail_type_memberships(const VolumeGrid& grid, const WeatherTextures& w) {
  const int nx = grid.lon_deg.count, ny = grid.lat_deg.count;
  const std::size_t ncol = grid.columns();
  std::vector<float> out(2 * ncol, 0.0f);
  if (w.type.size() != ncol) return out;
  std::vector<char> known(ncol, 0);
  for (std::size_t c = 0; c < ncol; ++c) {
    if (w.type[c] == CloudType::None) continue;
    known[c] = 1;
    out[2 * c] = w.memberships[3 * c + 1];
    out[2 * c + 1] = w.memberships[3 * c + 2];
  }
  const bool wraps = grid.wraps_lon();
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<char> next = known;
    std::vector<float> filled = out;
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        const std::size_t c = grid.column(i, j);
        if (known[c]) continue;
        double cu = 0.0, ci = 0.0;
        int count = 0;
        for (int dj = -1; dj <= 1; ++dj) {
          for (int di = -1; di <= 1; ++di) {
            int x = i + di;
            const int y = j + dj;
            if (y < 0 || y >= ny) continue;
            if (x < 0 || x >= nx) {
              if (!wraps) continue;
              x = (x + nx) % nx;
            }
            const std::size_t n = grid.column(x, y);
            if (!known[n]) continue;
            cu += out[2 * n], ci += out[2 * n + 1], ++count;
          }
        }
        if (count == 0) continue;
        filled[2 * c] = float(cu / count), filled[2 * c + 1] = float(ci / count);
        next[c] = 1;
      }
    }
    out.swap(filled);
    known.swap(next);
  }
  return out;
}

std::string weather_at_text(const VolumeGrid& grid, const WeatherTextures& w, double lat_deg, double lon_deg) {
  if (w.nx != grid.lon_deg.count || w.ny != grid.lat_deg.count || w.type.size() != grid.columns()) return {};
  // The longitude east of the grid's first by 0..360, then the nearest column (a point just west of
  // the first column is nearest to it: taken 360 lower).
  const double east = std::fmod(std::fmod(lon_deg - grid.lon_deg.start, 360.0) + 360.0, 360.0);
  long ii = std::lround(east / grid.lon_deg.step);
  if (ii >= w.nx) ii = grid.wraps_lon() || east - 360.0 >= -0.5 * grid.lon_deg.step ? (grid.wraps_lon() ? ii % w.nx : 0) : -1;
  const long j = std::lround((lat_deg - grid.lat_deg.start) / grid.lat_deg.step);
  if (ii < 0 || ii >= w.nx || j < 0 || j >= w.ny) return {};
  const std::size_t c = grid.column(int(ii), int(j));
  char line[512];
  if (w.type[c] == CloudType::None) {
    std::snprintf(line, sizeof line, "weather textures at the nearest column (lat %.6g, lon %.6g): no cloud", grid.lat_deg.at(int(j)),
                  grid.lon_deg.at(int(ii)));
    return line;
  }
  std::snprintf(line, sizeof line,
                "weather textures at the nearest column (lat %.6g, lon %.6g): %s (stratiform %.2f, cumuliform %.2f, cirriform %.2f), "
                "cover %.3f (low %.3f, mid %.3f, high %.3f above %s)%s, base %.1f m, top %.1f m, ice share %.3f",
                grid.lat_deg.at(int(j)), grid.lon_deg.at(int(ii)), cloud_type_name(w.type[c]), w.memberships[3 * c], w.memberships[3 * c + 1],
                w.memberships[3 * c + 2], w.cover[c], w.cover_low[c], w.cover_mid[c], w.cover_high[c],
                w.heights_above_ground ? "the ground" : "sea level", w.cover_from_water ? " diagnosed from the water" : "", w.base_m[c],
                w.top_m[c], w.ice_share[c]);
  return line;
}

std::string weather_textures_note(const WeatherTextures& w) {
  const std::size_t cloudy = w.columns_of_type[1] + w.columns_of_type[2] + w.columns_of_type[3];
  char line[512];
  if (cloudy == 0) {
    std::snprintf(line, sizeof line, "weather textures: no cloudy column");
    return line;
  }
  const auto pct = [&](int t) { return 100.0 * double(w.columns_of_type[std::size_t(t)]) / double(cloudy); };
  std::snprintf(line, sizeof line,
                "weather textures: %zu cloudy columns, %.0f %% stratiform, %.0f %% cumuliform, %.0f %% cirriform (%s%s); "
                "layers measured above %s; built in %.1f ms",
                cloudy, pct(1), pct(2), pct(3),
                w.has_lapse_rate ? "convective signal from cover and the 0-3 km lapse rate" : "convective signal from cover alone: no temperatures",
                w.cover_from_water ? "; cover diagnosed from the water: the file has no cloud fraction" : "",
                w.heights_above_ground ? "the ground" : "sea level", w.build_ms);
  return line;
}

}  // namespace cv::core
