// The GSHHS shorelines rasterised into a water fraction per texel.
#include "render/land_sea_mask.hpp"

#include <shapefil.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <stdexcept>

namespace cv::render {

WaterFraction rasterise_water(const std::vector<ShorePolygon>& polygons, int w, int h, int ss) {
  if (w < 1 || h < 1 || ss < 1) throw std::invalid_argument("rasterise_water: the grid needs at least 1 x 1 texels and samples");
  const int sw = w * ss, sh = h * ss;
  // The highest level of the polygons containing each sample (0: none).
  std::vector<std::uint8_t> level(static_cast<std::size_t>(sw) * sh, 0);
  std::vector<double> xs;
  for (const ShorePolygon& p : polygons) {
    double lat_lo = 90.0, lat_hi = -90.0;
    for (const auto& ring : p.rings) {
      for (std::size_t k = 1; k < ring.size(); k += 2) lat_lo = std::min(lat_lo, ring[k]), lat_hi = std::max(lat_hi, ring[k]);
    }
    if (lat_hi < lat_lo) continue;
    // Sample rows whose centre latitude 90 - (j + 0.5) 180 / sh lies within the polygon's span.
    const int j0 = std::max(0, static_cast<int>(std::floor((90.0 - lat_hi) * sh / 180.0 - 0.5)));
    const int j1 = std::min(sh - 1, static_cast<int>(std::ceil((90.0 - lat_lo) * sh / 180.0 - 0.5)));
    const auto lv = static_cast<std::uint8_t>(std::clamp(p.level, 0, 255));
    for (int j = j0; j <= j1; ++j) {
      const double lat = 90.0 - (j + 0.5) * 180.0 / sh;
      xs.clear();
      // Crossings of the row with every edge (half-open in latitude, so a vertex on the row counts
      // once); even-odd over all rings of the polygon.
      for (const auto& ring : p.rings) {
        const std::size_t n = ring.size() / 2;
        for (std::size_t k = 0; k < n; ++k) {
          const double x0 = ring[2 * k], y0 = ring[2 * k + 1];
          const double x1 = ring[2 * ((k + 1) % n)], y1 = ring[2 * ((k + 1) % n) + 1];
          if ((y0 > lat) == (y1 > lat)) continue;
          xs.push_back(x0 + (lat - y0) * (x1 - x0) / (y1 - y0));
        }
      }
      std::sort(xs.begin(), xs.end());
      for (std::size_t k = 0; k + 1 < xs.size(); k += 2) {
        // Columns whose centre -180 + (i + 0.5) 360 / sw lies in [xs[k], xs[k + 1]).
        const int i0 = std::max(0, static_cast<int>(std::ceil((xs[k] + 180.0) * sw / 360.0 - 0.5)));
        const int i1 = std::min(sw, static_cast<int>(std::ceil((xs[k + 1] + 180.0) * sw / 360.0 - 0.5)));
        std::uint8_t* row = level.data() + static_cast<std::size_t>(j) * sw;
        for (int i = i0; i < i1; ++i) row[i] = std::max(row[i], lv);
      }
    }
  }
  WaterFraction out;
  out.width = w;
  out.height = h;
  out.water.assign(static_cast<std::size_t>(w) * h, 0.0f);
  const float per_sample = 1.0f / static_cast<float>(ss * ss);
  for (int j = 0; j < sh; ++j) {
    for (int i = 0; i < sw; ++i) {
      if (level[static_cast<std::size_t>(j) * sw + i] % 2 == 0) out.water[static_cast<std::size_t>(j / ss) * w + i / ss] += per_sample;
    }
  }
  for (float& f : out.water) f = std::min(f, 1.0f);
  return out;
}

char gshhs_resolution_for(int w) {
  // Shoreline detail of each resolution (GSHHS README: crude ~25 km, low ~5 km, intermediate ~1 km,
  // high ~0.2 km, full) against half a texel at the equator.
  const double half_texel_km = 0.5 * 40030.0 / std::max(w, 1);
  if (half_texel_km >= 25.0) return 'c';
  if (half_texel_km >= 5.0) return 'l';
  if (half_texel_km >= 1.0) return 'i';
  if (half_texel_km >= 0.2) return 'h';
  return 'f';
}

// The polygons of one shapefile (without .shp), all of `level`.
void read_shore_polygons(const std::string& base, int level, std::vector<ShorePolygon>& out) {
  SHPHandle shp = SHPOpen(base.c_str(), "rb");
  if (!shp) throw std::runtime_error(base + ".shp: cannot read the shapefile, expected GSHHS shoreline polygons");
  int count = 0, type = 0;
  SHPGetInfo(shp, &count, &type, nullptr, nullptr);
  if (type != SHPT_POLYGON) {
    SHPClose(shp);
    throw std::runtime_error(base + ".shp: shapes of type " + std::to_string(type) + ", expected polygons (type 5)");
  }
  for (int i = 0; i < count; ++i) {
    SHPObject* o = SHPReadObject(shp, i);
    if (!o) continue;
    ShorePolygon p;
    p.level = level;
    for (int part = 0; part < o->nParts; ++part) {
      const int b = o->panPartStart[part];
      const int e = part + 1 < o->nParts ? o->panPartStart[part + 1] : o->nVertices;
      std::vector<double> ring;
      ring.reserve(static_cast<std::size_t>(2 * std::max(e - b, 0)));
      for (int v = b; v < e; ++v) ring.push_back(o->padfX[v]), ring.push_back(o->padfY[v]);
      if (ring.size() >= 6) p.rings.push_back(std::move(ring));
    }
    SHPDestroyObject(o);
    if (!p.rings.empty()) out.push_back(std::move(p));
  }
  SHPClose(shp);
}

std::optional<WaterFraction> gshhs_water_fraction(int w, int h, const std::string& dir) {
  // Resolutions from coarse to fine; for each level the one that fits, then finer, then coarser.
  const std::string order = "clihf";
  const std::size_t fit = order.find(gshhs_resolution_for(w));
  std::string preference(1, order[fit]);
  for (std::size_t k = fit + 1; k < order.size(); ++k) preference += order[k];
  for (std::size_t k = fit; k-- > 0;) preference += order[k];
  std::vector<ShorePolygon> polygons;
  std::string used;
  for (int level = 1; level <= 4; ++level) {
    for (char r : preference) {
      const std::string base = dir + "/" + r + "/GSHHS_" + r + "_L" + std::to_string(level);
      if (!std::filesystem::exists(base + ".shp")) continue;
      read_shore_polygons(base, level, polygons);
      used += (used.empty() ? "" : ", ") + std::string(1, r) + " L" + std::to_string(level);
      break;
    }
    if (level == 1 && used.empty()) return std::nullopt;
  }
  // About 4 samples per texel side on the 720-pixel Natural Earth map; fewer on finer maps.
  const int ss = std::clamp((2880 + w - 1) / std::max(w, 1), 1, 8);
  WaterFraction f = rasterise_water(polygons, w, h, ss);
  f.source = "GSHHS " + used + " (" + std::to_string(ss) + " x " + std::to_string(ss) + " samples per texel)";
  return f;
}

}  // namespace cv::render
