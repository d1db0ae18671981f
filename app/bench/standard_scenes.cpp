// The standard scenes (see standard_scenes.hpp): analytic cloud fields, deterministic, built in
// milliseconds, small enough for the CPU reference at test sizes.
#include "bench/standard_scenes.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <stdexcept>

#include <glm/glm.hpp>

#include "geo/geodesy.hpp"

namespace cv::bench {
namespace {
constexpr double kPi = 3.14159265358979323846;

// In-cloud liquid and ice extinction (1/m) and cloud fraction at a grid node.
struct Cell {
  double liquid_per_m = 0.0, ice_per_m = 0.0, fraction = 0.0;
};
using FieldFn = std::function<Cell(double lon_deg, double lat_deg, double alt_m)>;

VolumeGrid make_grid(RegularAxis lon, RegularAxis lat, RegularAxis alt) {
  VolumeGrid g;
  g.lon_deg = lon;
  g.lat_deg = lat;
  g.alt_m = alt;
  return g;
}

TimeStepData fill(const VolumeGrid& g, const FieldFn& fn) {
  TimeStepData d;
  auto& liq = d[Field::ExtinctionLiquid];
  auto& ice = d[Field::ExtinctionIce];
  auto& cf = d[Field::CloudFraction];
  liq.assign(g.points(), 0.0f);
  ice.assign(g.points(), 0.0f);
  cf.assign(g.points(), 0.0f);
  for (int k = 0; k < g.alt_m.count; ++k)
    for (int j = 0; j < g.lat_deg.count; ++j)
      for (int i = 0; i < g.lon_deg.count; ++i) {
        const Cell c = fn(g.lon_deg.at(i), g.lat_deg.at(j), g.alt_m.at(k));
        const std::size_t p = g.index(i, j, k);
        const bool cloudy = c.fraction > 0.0 && (c.liquid_per_m > 0.0 || c.ice_per_m > 0.0);
        liq[p] = cloudy ? static_cast<float>(c.liquid_per_m) : 0.0f;
        ice[p] = cloudy ? static_cast<float>(c.ice_per_m) : 0.0f;
        cf[p] = cloudy ? static_cast<float>(std::clamp(c.fraction, 0.0, 1.0)) : 0.0f;
      }
  derive_maps(g, d);
  return d;
}

// A camera at (lat, lon, alt) aimed at a target point.
Camera look_at(double lat, double lon, double alt, double t_lat, double t_lon, double t_alt, double fov, int w, int h) {
  Camera c;
  c.lat_deg = lat, c.lon_deg = lon, c.alt_m = alt, c.fov_deg = fov, c.width = w, c.height = h;
  const double r0 = VolumeGrid{}.earth_radius_m;
  const glm::dvec3 dir = glm::normalize(geo::sphere_to_ecef({t_lat, t_lon, t_alt}, r0) - geo::sphere_to_ecef({lat, lon, alt}, r0));
  const geo::EnuFrame f = geo::sphere_enu(lat, lon);
  c.pitch_deg = std::asin(std::clamp(glm::dot(dir, f.up), -1.0, 1.0)) * 180.0 / kPi;
  c.heading_deg = std::atan2(glm::dot(dir, f.east), glm::dot(dir, f.north)) * 180.0 / kPi;
  return c;
}

Camera aimed(double lat, double lon, double alt, double heading, double pitch, double fov, int w, int h) {
  Camera c;
  c.lat_deg = lat, c.lon_deg = lon, c.alt_m = alt, c.heading_deg = heading, c.pitch_deg = pitch, c.fov_deg = fov;
  c.width = w, c.height = h;
  return c;
}

Sun sun_at(double lat, double lon) {
  Sun s;
  s.subsolar_lat_deg = lat, s.subsolar_lon_deg = lon;
  return s;
}

MarchSettings march(double view_step_m) {
  MarchSettings m;
  m.quality.view_step_m = view_step_m;
  m.quality.sun_steps = 16;
  m.quality.octaves = 4;
  return m;
}

// splitmix64: a fixed sequence on every platform (std distributions are not).
struct Rng {
  std::uint64_t s;
  double uniform() {
    std::uint64_t z = (s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return static_cast<double>((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
  }
};

double smooth01(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

// Kilometres per degree on the renderer's sphere.
constexpr double kKmPerDeg = 6371.0 * kPi / 180.0;

// Stratocumulus: a deck from 800 to 1400 m whose extinction grows with height (adiabatic water),
// broken into closed cells 22 km across; vertical optical depth up to 6.
FieldFn stratocumulus() {
  return [](double lon, double lat, double z) {
    Cell c;
    if (z < 800.0 || z > 1400.0) return c;
    c.fraction = std::clamp(0.55 + 0.45 * std::cos(2 * kPi * lon / 0.2) * std::cos(2 * kPi * lat / 0.2), 0.0, 1.0);
    c.liquid_per_m = 0.02 * (z - 800.0) / 600.0;
    return c;
  };
}

// Fair-weather cumulus: 30 cells 1-2.5 km in radius, bases at 1 km, tops 1.8-3.5 km, on a
// 1 x 1 degree box around (0, 0); peak extinction 0.03 /m.
FieldFn cumulus_field() {
  struct Cu {
    double lon, lat, radius_km, top_m;
  };
  std::vector<Cu> cells;
  Rng rng{20240115};
  for (int n = 0; n < 30; ++n) {
    Cu c;
    c.lon = -0.4 + 0.8 * rng.uniform();
    c.lat = -0.4 + 0.8 * rng.uniform();
    c.radius_km = 1.0 + 1.5 * rng.uniform();
    c.top_m = 1800.0 + 1700.0 * rng.uniform();
    cells.push_back(c);
  }
  return [cells](double lon, double lat, double z) {
    Cell out;
    for (const Cu& c : cells) {
      const double base = 1000.0, mid = 0.5 * (base + c.top_m), half = 0.5 * (c.top_m - base);
      const double dx = (lon - c.lon) * kKmPerDeg * std::cos(lat * kPi / 180.0), dy = (lat - c.lat) * kKmPerDeg;
      const double r2 = (dx * dx + dy * dy) / (c.radius_km * c.radius_km) + (z - mid) * (z - mid) / (half * half);
      if (r2 < 1.0 && z >= base) out.liquid_per_m = std::max(out.liquid_per_m, 0.03 * (1.0 - r2));
    }
    out.fraction = out.liquid_per_m > 0.0 ? 1.0 : 0.0;
    return out;
  };
}

// A cumulonimbus: a 6 km-radius column from 1 to 10 km (liquid 0.05 /m below 5 km, turning to
// ice 0.02 /m by 7 km) under an anvil of ice 10-12.5 km up and 20 km across. Optical depth through
// the core: about 600 horizontally, 400 vertically.
FieldFn towering_cell() {
  return [](double lon, double lat, double z) {
    Cell c;
    const double dx = lon * kKmPerDeg * std::cos(lat * kPi / 180.0), dy = lat * kKmPerDeg;
    const double r_km = std::sqrt(dx * dx + dy * dy);
    const double column = (z >= 1000.0 && z <= 10000.0) ? 1.0 - smooth01((r_km - 5.0) / 1.0) : 0.0;
    const double anvil = (z >= 10000.0 && z <= 12500.0) ? 1.0 - smooth01((r_km - 18.0) / 2.0) : 0.0;
    const double ice_share = smooth01((z - 5000.0) / 2000.0);
    c.liquid_per_m = 0.05 * column * (1.0 - ice_share);
    c.ice_per_m = 0.02 * column * ice_share + 0.004 * anvil;
    c.fraction = std::max(column, anvil);
    return c;
  };
}

// Cirrus: ice 9-11 km up in bands, 2e-4 /m at most; vertical optical depth about 0.1-0.25.
FieldFn thin_cirrus() {
  return [](double lon, double lat, double z) {
    Cell c;
    if (z < 9000.0 || z > 11000.0) return c;
    const double band = 0.5 + 0.5 * std::sin(2 * kPi * lon / 0.5 + 0.7 * std::sin(2 * kPi * lat / 0.7));
    c.ice_per_m = 2e-4 * band * std::sin(kPi * (z - 9000.0) / 2000.0);
    c.fraction = band;
    return c;
  };
}

// The globe: convection along the equator with cirrus above it, mid-latitude storm-track bands,
// and Southern Ocean stratocumulus.
FieldFn globe() {
  return [](double lon, double lat, double z) {
    Cell c;
    const double l = lon * kPi / 180.0;
    if (std::abs(lat) <= 8.0 && z >= 1000.0 && z <= 12000.0 && std::cos(3.0 * l) > 0.2) {
      c.liquid_per_m += z < 6000.0 ? 5e-3 : 0.0;
      c.ice_per_m += z >= 6000.0 ? 1e-3 : 0.0;
    }
    if (std::abs(lat) <= 12.0 && z >= 10000.0 && z <= 12000.0) c.ice_per_m += 3e-4;
    if (std::abs(std::abs(lat) - 45.0) <= 10.0 && z >= 1000.0 && z <= 6000.0 && std::cos(6.0 * l + 0.2 * lat) > 0.3)
      c.liquid_per_m += 2e-3;
    if (lat <= -55.0 && lat >= -65.0 && z >= 1000.0 && z <= 2000.0) c.liquid_per_m += 8e-3;
    c.fraction = (c.liquid_per_m > 0.0 || c.ice_per_m > 0.0) ? 1.0 : 0.0;
    return c;
  };
}

// Trade cumulus in patches across the date line (170 E to 170 W), 1-2.5 km up.
FieldFn date_line() {
  return [](double lon, double lat, double z) {
    Cell c;
    if (z < 1000.0 || z > 2500.0) return c;
    const double patch = std::sin(2 * kPi * lon / 2.0) * std::cos(2 * kPi * lat / 1.5);
    c.fraction = std::clamp(patch, 0.0, 1.0);
    c.liquid_per_m = 0.01 * std::sin(kPi * (z - 1000.0) / 1500.0);
    return c;
  };
}

// A polar low: spiral bands 2-15 degrees from the north pole, 1-5 km up (none on the pole row,
// where every longitude is the same point).
FieldFn polar_low() {
  return [](double lon, double lat, double z) {
    Cell c;
    const double rho = 90.0 - lat;
    if (z < 1000.0 || z > 5000.0 || rho < 2.0 || rho > 15.0) return c;
    const double band = std::sin(2.0 * lon * kPi / 180.0 + rho / 2.0);
    c.fraction = std::clamp((band - 0.2) / 0.5, 0.0, 1.0);
    c.liquid_per_m = 0.01 * std::sin(kPi * (z - 1000.0) / 4000.0);
    return c;
  };
}

StandardScene regional(const std::string& name, const std::string& desc, const FieldFn& fn, RegularAxis lon, RegularAxis lat,
                       RegularAxis alt) {
  StandardScene s;
  s.name = name;
  s.description = desc;
  s.grid = make_grid(lon, lat, alt);
  s.data = fill(s.grid, fn);
  return s;
}

}  // namespace

std::vector<std::string> standard_scene_names() {
  return {"clear_sky", "thin_cirrus", "stratocumulus", "cumulus_field", "towering_cell",
          "sunset", "inside_cloud", "orbit_globe", "date_line", "pole"};
}

StandardScene standard_scene(const std::string& name, int w, int h) {
  const RegularAxis box2{-1.0, 0.05, 41};
  if (name == "clear_sky") {
    StandardScene s = regional(name, "no cloud anywhere in the data", [](double, double, double) { return Cell{}; }, box2,
                               box2, {500.0, 500.0, 24});
    s.camera = look_at(-1.2, 0.0, 2000.0, 0.0, 0.0, 3000.0, 60.0, w, h);
    s.sun = sun_at(25.0, 15.0);
    s.march = march(250.0);
    return s;
  }
  if (name == "thin_cirrus") {
    StandardScene s = regional(name, "banded ice cloud 9-11 km up, optical depth 0.1-0.25, seen from the ground",
                               thin_cirrus(), box2, box2, {8000.0, 200.0, 21});
    s.camera = aimed(-0.3, 0.0, 10.0, 0.0, 35.0, 70.0, w, h);
    s.sun = sun_at(20.0, 10.0);
    s.march = march(100.0);
    return s;
  }
  const RegularAxis box2_fine{-1.0, 0.025, 81};
  if (name == "stratocumulus" || name == "inside_cloud") {
    StandardScene s = regional(name, "", stratocumulus(), box2_fine, box2_fine, {500.0, 100.0, 21});
    if (name == "stratocumulus") {
      s.description = "a closed-cell deck 800-1400 m up, optical depth up to 6, from 5 km above";
      s.camera = look_at(-1.1, 0.0, 5000.0, 0.0, 0.0, 1000.0, 60.0, w, h);
    } else {
      s.description = "the camera inside the stratocumulus deck, 1150 m up";
      s.camera = aimed(0.0, 0.0, 1150.0, 45.0, 10.0, 90.0, w, h);
    }
    s.sun = sun_at(30.0, 0.0);
    s.march = march(50.0);
    return s;
  }
  const RegularAxis box1{-0.5, 0.01, 101};
  if (name == "cumulus_field" || name == "sunset") {
    StandardScene s = regional(name, "", cumulus_field(), box1, box1, {500.0, 125.0, 29});
    if (name == "cumulus_field") {
      s.description = "30 fair-weather cumuli, bases 1 km, tops 1.8-3.5 km";
      s.camera = aimed(-0.55, 0.0, 1500.0, 0.0, 3.0, 70.0, w, h);
      s.sun = sun_at(25.0, -30.0);
    } else {
      s.description = "the cumulus field with the sun on the horizon, looking toward it";
      s.camera = aimed(0.0, -0.55, 1500.0, 90.0, 2.0, 70.0, w, h);
      s.sun = sun_at(0.0, 90.0);
    }
    s.march = march(100.0);
    return s;
  }
  if (name == "towering_cell") {
    StandardScene s = regional(name, "a cumulonimbus with an anvil, optical depth about 600 through its core", towering_cell(),
                               box1, box1, {500.0, 250.0, 51});
    s.camera = look_at(-0.35, 0.0, 2000.0, 0.0, 0.0, 6000.0, 60.0, w, h);
    s.sun = sun_at(20.0, 30.0);
    s.march = march(200.0);
    return s;
  }
  if (name == "orbit_globe") {
    StandardScene s = regional(name, "a global field seen whole from 400 000 km", globe(), {0.0, 5.0, 72}, {-90.0, 5.0, 37},
                               {500.0, 500.0, 25});
    s.camera = aimed(15.0, 20.0, 4.0e8, 0.0, -90.0, 2.5, w, h);
    s.sun = sun_at(-20.0, 60.0);
    s.march = march(500.0);
    return s;
  }
  if (name == "date_line") {
    StandardScene s = regional(name, "trade cumulus from 170 E to 170 W, looking east across 180", date_line(),
                               {170.0, 0.25, 81}, {-5.0, 0.25, 41}, {500.0, 250.0, 23});
    s.camera = aimed(0.0, 178.0, 3000.0, 90.0, -5.0, 60.0, w, h);
    s.sun = sun_at(0.0, 150.0);
    s.march = march(250.0);
    return s;
  }
  if (name == "pole") {
    StandardScene s = regional(name, "a polar low around the north pole, from 300 km up looking across the pole",
                               polar_low(), {0.0, 2.0, 180}, {70.0, 0.5, 41}, {500.0, 250.0, 31});
    s.camera = aimed(80.0, 0.0, 3.0e5, 0.0, -35.0, 60.0, w, h);
    s.sun = sun_at(15.0, 0.0);
    s.march = march(250.0);
    return s;
  }
  std::string known;
  for (const auto& n : standard_scene_names()) known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown scene '" + name + "', expected one of: " + known);
}

}  // namespace cv::bench
