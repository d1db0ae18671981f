// cloudviewer-make-sample: writes the project's bundled sample forecast, a SYNTHETIC idealised
// mid-latitude cyclone over the North Pacific, as a CF-1.6 NetCDF file laid out the way ERA5
// pressure-level data come from the CDS: dimensions (time, level, latitude, longitude), ERA5 short
// names, int16 packing with scale_factor/add_offset, latitude descending, levels ascending in hPa.
//
// Usage: cloudviewer-make-sample OUT.nc [--seed N]
//
// Everything is computed from closed-form expressions plus a small seeded generator (SplitMix64),
// so the same seed gives the same bytes. Nothing here is observed data and nothing is a forecast.
//
// Units: pressure in hPa, distances in km unless a name says otherwise, heights in geopotential
// metres, temperature in K, wind in m s-1, water contents in kg kg-1, cloud cover as a fraction.
//
// The atmosphere, in short:
//  - z: ISA heights, a 40 m s-1 westerly jet at 250 hPa / 45N made geostrophic by a poleward
//    height slope, and a Gaussian low (-150 m at 500 hPa when fully deep, 420 km scale) that tilts
//    westward with height, moves ENE at 10 m s-1 from (175E, 45N) across 180 and deepens by a third.
//  - t: ISA plus the hydrostatic temperature of those height anomalies (T' = -(g/R) dZ'/dln p), plus
//    a frontal contrast (+4 K warm sector, -6 K cold air) fading out by 400 hPa.
//  - u, v: the jet plus the geostrophic wind of the low (about 20 m s-1 at low levels).
//  - q: relative humidity (75 % at 1000 hPa down to 3 % at 100 hPa, moister in the warm sector,
//    saturated in cloud) times the saturation specific humidity.
//  - cc, clwc, ciwc: a comma-shaped frontal cloud band, warm-sector cumulus, a cirrus shield ahead
//    of the warm front and one growing convective tower; water contents are grid-box means.

#include <netcdf.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace {

// ---------------------------------------------------------------------------------------------
// Physical constants
// ---------------------------------------------------------------------------------------------
constexpr double kG0 = 9.80665;  // standard gravity, m s-2 (geopotential = kG0 * height)
constexpr double kRd = 287.053;  // gas constant of dry air as used by the ISA, J kg-1 K-1
constexpr double kEarthRadiusKm = 6371.0;
constexpr double kOmega = 7.292115e-5;  // Earth's rotation rate, rad s-1
constexpr double kDegToRad = std::numbers::pi / 180.0;

// International Standard Atmosphere: 288.15 K and 1013.25 hPa at 0 m, lapse rate 6.5 K/km up to the
// tropopause at 11 km, isothermal (216.65 K) above.
constexpr double kIsaT0 = 288.15;           // K
constexpr double kIsaP0 = 1013.25;          // hPa
constexpr double kIsaLapse = 6.5e-3;        // K m-1
constexpr double kIsaTropopause = 11000.0;  // m
// Temperature of the isothermal layer above the tropopause, 216.65 K.
constexpr double kIsaT11 = kIsaT0 - kIsaLapse * kIsaTropopause;

// ---------------------------------------------------------------------------------------------
// Grid and time axis
// ---------------------------------------------------------------------------------------------
constexpr int kNLon = 121;  // 160E .. 220E (0..360 convention), ascending, 0.5 deg
constexpr int kNLat = 81;   // 65N .. 25N, descending as in ERA5, 0.5 deg
constexpr double kLon0 = 160.0;
constexpr double kLat0 = 65.0;
constexpr double kDeg = 0.5;
constexpr std::array<int, 12> kLevels = {100, 150, 200, 250, 300, 400,
                                         500, 600, 700, 850, 925, 1000};  // hPa, top first
constexpr int kNLev = static_cast<int>(kLevels.size());
constexpr int kNTime = 6;
constexpr int kStepHours = 3;
constexpr std::size_t kPlane = static_cast<std::size_t>(kNLat) * kNLon;
constexpr std::size_t kStepSize = kPlane * kNLev;

// ---------------------------------------------------------------------------------------------
// The cyclone
// ---------------------------------------------------------------------------------------------
constexpr double kStartLon = 175.0;       // deg E, centre at the first step
constexpr double kStartLat = 45.0;        // deg N
constexpr double kSpeed = 10.0;           // m s-1, translation speed of the centre
constexpr double kHeading = 67.5;         // deg clockwise from north: east-north-east
constexpr double kDepth500 = 150.0;       // m, height deficit at 500 hPa at the centre, fully deep
constexpr double kRadius = 420.0;         // km, e-folding scale of the height deficit
constexpr double kTiltKm = 140.0;         // km westward shift of the low per halving of pressure
constexpr double kWarmFrontDeg = -10.0;   // direction of the surface warm front from the centre
constexpr double kColdFrontDeg = -105.0;  // direction of the surface cold front from the centre
constexpr double kColdBend = 1.3e-4;      // km-1: the cold front trails westward, 300 km at 1500 km
constexpr double kWarmSlope = 100.0;      // km of horizontal distance per km of height (1:100)
constexpr double kColdSlope = 50.0;       // the cold frontal surface is steeper (1:50)

// Westerly jet: 5 m s-1 at the ground, 40 m s-1 at 250 hPa, centred on 45N, 8 deg wide.
constexpr double kJetLat = 45.0;
constexpr double kJetWidthDeg = 8.0;

// ---------------------------------------------------------------------------------------------
// Small helpers
// ---------------------------------------------------------------------------------------------

// Smooth C2 ramp: 0 at x = e0, 1 at x = e1 (e0 > e1 gives a falling ramp), flat outside.
double ramp(double x, double e0, double e1) {
  const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
  return t * t * t * (t * (6.0 * t - 15.0) + 10.0);
}

// 1 on [lo, hi], falling smoothly to 0 over `edge` on either side.
double bump(double x, double lo, double hi, double edge) {
  return ramp(x, lo - edge, lo) * ramp(x, hi + edge, hi);
}

// Compactly supported round kernel: 1 at r = 0, 0 from r = radius on, C2 at both ends.
double falloff(double r, double radius) { return r >= radius ? 0.0 : ramp(r, radius, 0.0); }

// SplitMix64 (Steele, Lea & Flood 2014): fully specified, so the sample is the same with every
// standard library (std::uniform_real_distribution is not).
class SplitMix64 {
 public:
  explicit SplitMix64(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  // Uniform in [lo, hi), from the top 53 bits.
  double uniform(double lo, double hi) {
    return lo + (hi - lo) * static_cast<double>(next() >> 11) * 0x1.0p-53;
  }

 private:
  std::uint64_t state_;
};

// ISA geopotential height (m) of a pressure level (hPa).
double isa_height(double p) {
  const double p11 = kIsaP0 * std::pow(kIsaT11 / kIsaT0, kG0 / (kRd * kIsaLapse));  // 226.32 hPa
  if (p >= p11) return kIsaT0 / kIsaLapse * (1.0 - std::pow(p / kIsaP0, kRd * kIsaLapse / kG0));
  return kIsaTropopause + kRd * kIsaT11 / kG0 * std::log(p11 / p);
}

// ISA temperature (K) at a geopotential height (m).
double isa_temperature(double h) { return h < kIsaTropopause ? kIsaT0 - kIsaLapse * h : kIsaT11; }

// Saturation vapour pressure (hPa) as in the ECMWF IFS: Tetens' formula over water above 0 C, over
// ice below -23 C, and a quadratic blend between.
double saturation_vapour_pressure(double t) {
  constexpr double kT0 = 273.16;
  const double ew = 6.1121 * std::exp(17.502 * (t - kT0) / (t - 32.19));
  const double ei = 6.1121 * std::exp(22.587 * (t - kT0) / (t + 0.7));
  constexpr double kTice = 250.16;
  if (t >= kT0) return ew;
  if (t <= kTice) return ei;
  const double a = (t - kTice) / (kT0 - kTice);
  return a * a * ew + (1.0 - a * a) * ei;
}

// Saturation specific humidity (kg kg-1) at temperature t (K) and pressure p (hPa).
double saturation_specific_humidity(double t, double p) {
  constexpr double kEps = 0.621981;  // ratio of the molar masses of water and dry air
  const double e = std::min(saturation_vapour_pressure(t), 0.5 * p);
  return kEps * e / (p - (1.0 - kEps) * e);
}

// Liquid share of cloud condensate: all liquid above 268 K, all ice below 253 K, mixed between.
double liquid_fraction(double t) { return ramp(t, 253.0, 268.0); }

// Background relative humidity (0..1) by pressure, linear in ln p between these nodes: moist
// boundary layer, drier free troposphere, very dry stratosphere.
double background_relative_humidity(double p) {
  constexpr std::array<std::array<double, 2>, 9> kNodes = {{{100, 0.03},
                                                            {150, 0.06},
                                                            {200, 0.15},
                                                            {250, 0.30},
                                                            {300, 0.40},
                                                            {500, 0.45},
                                                            {700, 0.60},
                                                            {850, 0.70},
                                                            {1000, 0.75}}};
  if (p <= kNodes.front()[0]) return kNodes.front()[1];
  for (std::size_t i = 1; i < kNodes.size(); ++i) {
    if (p <= kNodes[i][0]) {
      const double a = std::log(p / kNodes[i - 1][0]) / std::log(kNodes[i][0] / kNodes[i - 1][0]);
      return kNodes[i - 1][1] + a * (kNodes[i][1] - kNodes[i - 1][1]);
    }
  }
  return kNodes.back()[1];
}

// ---------------------------------------------------------------------------------------------
// Balanced background: zonal jet in geostrophic and hydrostatic balance
// ---------------------------------------------------------------------------------------------

// Jet speed profile (m s-1) at the jet axis as a function of ln p.
double jet_speed(double ln_p) {
  const double x = (ln_p - std::log(250.0)) / 0.55;
  return 5.0 + 35.0 * std::exp(-x * x);
}

// Height anomaly (m) that keeps u = jet_speed * exp(-((lat - 45)/8)^2) geostrophic with a constant
// Coriolis parameter f0 = f(45N): dZ/dy = -f0 u / g integrates to an error function.
double jet_height_anomaly(double ln_p, double lat) {
  const double f0 = 2.0 * kOmega * std::sin(kJetLat * kDegToRad);
  const double width_m = kJetWidthDeg * kDegToRad * kEarthRadiusKm * 1000.0;
  const double integral =
      width_m * 0.5 * std::sqrt(std::numbers::pi) * std::erf((lat - kJetLat) / kJetWidthDeg);
  return -f0 / kG0 * jet_speed(ln_p) * integral;
}

double jet_wind(double ln_p, double lat) {
  const double y = (lat - kJetLat) / kJetWidthDeg;
  return jet_speed(ln_p) * std::exp(-y * y);
}

// ---------------------------------------------------------------------------------------------
// The cyclone's height field
// ---------------------------------------------------------------------------------------------

// Vertical structure of the height deficit, 1 at 500 hPa: 0.9 at 1000 hPa, growing with height
// through the troposphere (a cold-core low), weakening above the tropopause (warm lower
// stratosphere over the low).
double deficit_profile(double ln_p) {
  const double halvings = (std::log(1000.0) - ln_p) / std::numbers::ln2;  // 0 at 1000, 1 at 500
  const double trop = 0.9 + 0.1 * halvings;
  const double strat = ramp(ln_p, std::log(250.0), std::log(100.0));  // 0 at 250 hPa, 1 at 100
  return trop * (1.0 - 0.58 * strat);
}

// Height anomaly (m) of the low at cyclone-relative position (x east, y north, km) and ln p; the
// low tilts westward with height as a developing baroclinic low does.
double cyclone_height_anomaly(double x, double y, double ln_p, double deepening) {
  const double halvings = std::min((std::log(1000.0) - ln_p) / std::numbers::ln2, 2.0);
  const double dx = x + kTiltKm * halvings;
  const double r2 = dx * dx + y * y;
  return -kDepth500 * deepening * deficit_profile(ln_p) * std::exp(-0.5 * r2 / (kRadius * kRadius));
}

// ---------------------------------------------------------------------------------------------
// Seeded features
// ---------------------------------------------------------------------------------------------
struct CumulusCell {
  double x, y;    // km, cyclone-relative
  double radius;  // km
  double peak;    // cloud fraction at the cell centre at full development, 0.2..0.6
  double top;     // hPa, cloud top
  double period;  // h, life cycle
  double phase;   // 0..1
};

struct Wave {
  double kx, ky;  // rad km-1
  double phase;   // rad
  double drift;   // rad h-1
};

struct Features {
  std::vector<CumulusCell> cumulus;
  std::array<Wave, 5> cirrus_texture;
  double tower_x, tower_y;  // km, cyclone-relative position of the convective cell
};

// Warm-sector test at the surface, used when scattering the cumulus.
double surface_warm_sector(double x, double y);

Features make_features(std::uint64_t seed) {
  SplitMix64 rng(seed);
  Features f{};
  // Cumulus cells scattered over a box south-east of the low, kept where the surface is in the
  // warm sector (about a third of the box).
  for (int i = 0; i < 600; ++i) {
    CumulusCell c{};
    c.x = rng.uniform(-500.0, 2000.0);
    c.y = rng.uniform(-2200.0, 100.0);
    c.radius = rng.uniform(50.0, 110.0);
    c.peak = rng.uniform(0.2, 0.6);
    c.top = rng.uniform(700.0, 850.0);
    c.period = rng.uniform(9.0, 24.0);
    c.phase = rng.uniform(0.0, 1.0);
    if (surface_warm_sector(c.x, c.y) > 0.6) f.cumulus.push_back(c);
  }
  for (Wave& w : f.cirrus_texture) {
    const double wavelength = rng.uniform(180.0, 600.0);
    const double dir = rng.uniform(0.0, 2.0 * std::numbers::pi);
    w.kx = 2.0 * std::numbers::pi / wavelength * std::cos(dir);
    w.ky = 2.0 * std::numbers::pi / wavelength * std::sin(dir);
    w.phase = rng.uniform(0.0, 2.0 * std::numbers::pi);
    w.drift = rng.uniform(-0.3, 0.3);
  }
  f.tower_x = 450.0 + rng.uniform(-80.0, 80.0);
  f.tower_y = -750.0 + rng.uniform(-80.0, 80.0);
  return f;
}

// ---------------------------------------------------------------------------------------------
// Fronts. Coordinates are cyclone-relative (km, x east, y north, origin at the surface low).
// Signed distances are positive on the warm side. Aloft, a frontal surface lies over the cold air,
// displaced from its surface position by height times the inverse slope.
// ---------------------------------------------------------------------------------------------
struct FrontFrame {
  double warm_surface;  // signed distance to the surface warm front
  double warm_along;    // distance along the warm front from the centre
  double cold_surface;  // signed distance to the surface cold front (bent westward)
  double cold_along;
};

FrontFrame front_frame(double x, double y) {
  const double tw = kWarmFrontDeg * kDegToRad;
  const double tc = kColdFrontDeg * kDegToRad;
  FrontFrame f{};
  // The warm sector lies to the right of the warm front (looking out from the low) and to the left
  // of the cold front.
  f.warm_surface = std::sin(tw) * x - std::cos(tw) * y;
  f.warm_along = std::cos(tw) * x + std::sin(tw) * y;
  f.cold_along = std::cos(tc) * x + std::sin(tc) * y;
  const double trail = std::max(f.cold_along, 0.0);
  f.cold_surface = -std::sin(tc) * x + std::cos(tc) * y + kColdBend * trail * trail;
  return f;
}

// 0 in cold air, 1 in warm air at height h_km, with a 120 km wide transition across each front.
double warm_sector(const FrontFrame& f, double h_km) {
  const double dw = f.warm_surface + kWarmSlope * h_km;
  const double dc = f.cold_surface + kColdSlope * h_km;
  return ramp(dw, -60.0, 60.0) * ramp(dc, -60.0, 60.0);
}

double surface_warm_sector(double x, double y) { return warm_sector(front_frame(x, y), 0.0); }

// ---------------------------------------------------------------------------------------------
// One time step
// ---------------------------------------------------------------------------------------------
enum Var { kZ, kT, kU, kV, kQ, kCC, kCLWC, kCIWC, kNVar };

struct VarInfo {
  const char* name;
  const char* units;
  const char* long_name;
  const char* standard_name;
};

constexpr std::array<VarInfo, kNVar> kVarInfo = {{
    {"z", "m**2 s**-2", "Geopotential", "geopotential"},
    {"t", "K", "Temperature", "air_temperature"},
    {"u", "m s**-1", "U component of wind", "eastward_wind"},
    {"v", "m s**-1", "V component of wind", "northward_wind"},
    {"q", "kg kg**-1", "Specific humidity", "specific_humidity"},
    {"cc", "(0 - 1)", "Fraction of cloud cover", "cloud_area_fraction_in_atmosphere_layer"},
    {"clwc", "kg kg**-1", "Specific cloud liquid water content",
     "mass_fraction_of_cloud_liquid_water_in_air"},
    {"ciwc", "kg kg**-1", "Specific cloud ice water content", "mass_fraction_of_cloud_ice_in_air"},
}};

struct Centre {
  double lon, lat;   // deg
  double deepening;  // 0.75 at the first step, 1 at the last
};

// Centre track: constant speed and heading on the sphere, integrated in 10-minute steps.
Centre centre_at(int step) {
  double lon = kStartLon;
  double lat = kStartLat;
  const int substeps = step * kStepHours * 6;
  const double ds_km = kSpeed * 600.0 / 1000.0;
  for (int i = 0; i < substeps; ++i) {
    lat += ds_km * std::cos(kHeading * kDegToRad) / kEarthRadiusKm / kDegToRad;
    lon += ds_km * std::sin(kHeading * kDegToRad) / (kEarthRadiusKm * std::cos(lat * kDegToRad)) / kDegToRad;
  }
  return {lon, lat, 0.75 + 0.25 * step / (kNTime - 1)};
}

struct StepSummary {
  Centre centre;
  double z500_anomaly_min;  // m
  double cc_max;
  double wind_max;  // m s-1
};

// Fills fields[var][level][lat][lon] for one step (the arrays hold this step only).
StepSummary compute_step(int step, const Features& feat, std::array<std::vector<double>, kNVar>& fields) {
  const Centre c = centre_at(step);
  const double hours = static_cast<double>(step * kStepHours);
  const double growth = static_cast<double>(step) / (kNTime - 1);  // convective cell, 0..1
  const double coslat_c = std::cos(c.lat * kDegToRad);
  StepSummary s{c, 0.0, 0.0, 0.0};

  // Cumulus life cycles this step: 0.3..1 of the peak cloud fraction.
  std::vector<double> cu_amp(feat.cumulus.size());
  for (std::size_t i = 0; i < feat.cumulus.size(); ++i) {
    const CumulusCell& cu = feat.cumulus[i];
    const double cycle = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * (hours / cu.period + cu.phase));
    cu_amp[i] = cu.peak * (0.3 + 0.7 * cycle);
  }

  // Convective tower: top rises from 600 hPa to 150 hPa, radius of the cc = 1 core grows.
  const double tower_top = std::exp(std::log(600.0) + growth * (std::log(150.0) - std::log(600.0)));
  const double tower_radius = 50.0 + 60.0 * growth;  // km, edge of the cloud

  for (int k = 0; k < kNLev; ++k) {
    const double p = kLevels[static_cast<std::size_t>(k)];
    const double ln_p = std::log(p);
    const double h_m = isa_height(p);
    const double h_km = h_m / 1000.0;
    const double t_isa = isa_temperature(h_m);

    // Vertical envelopes (pressure in hPa).
    const double v_front_t = ramp(ln_p, std::log(400.0), std::log(850.0));  // frontal T contrast
    const double v_band = ramp(p, 1000.0, 925.0) * ramp(p, 220.0, 300.0);   // deep band 925-300
    const double v_head = ramp(p, 1000.0, 925.0) * ramp(p, 280.0, 350.0);   // comma head 925-350
    const double v_cirrus = bump(p, 200.0, 300.0, 45.0);                    // cirrus 300-200
    const double v_tower = ramp(p, 1000.0, 925.0) * ramp(p, tower_top - 40.0, tower_top);
    const double v_anvil = ramp(p, 350.0, 300.0) * ramp(p, tower_top - 40.0, tower_top);

    // Frontal band water: 4e-4 kg/kg in-cloud at 1.5-2 km, falling off with a 2.2 km scale above.
    const double band_water = 4.0e-4 * ramp(h_km, 0.3, 1.5) * std::exp(-std::max(h_km - 2.0, 0.0) / 2.2);
    // Convective tower water (in-cloud): liquid peaks at 3 km, ice at 8 km.
    const double tower_liquid = 1.5e-3 * std::exp(-std::pow((h_km - 3.0) / 2.0, 2.0));
    const double tower_ice = 8.0e-4 * std::exp(-std::pow((h_km - 8.0) / 2.5, 2.0));
    const double tower_intensity = 0.4 + 0.6 * growth;
    // Cumulus water (in-cloud): grows with height above the base, as an adiabatic parcel's does.
    const double cu_water = 1.5e-4 + 2.0e-4 * std::clamp((925.0 - p) / 225.0, 0.0, 1.0);

    // The cyclone's height anomaly and its hydrostatic temperature, T' = -(g/R) dZ'/dln p, and the
    // same for the jet; derivatives by central differences.
    constexpr double kDlnp = 1.0e-3;

    for (int j = 0; j < kNLat; ++j) {
      const double lat = kLat0 - kDeg * j;
      const double coslat = std::cos(lat * kDegToRad);
      const double f_cor = 2.0 * kOmega * std::sin(lat * kDegToRad);
      for (int i = 0; i < kNLon; ++i) {
        const double lon = kLon0 + kDeg * i;
        double dlon = lon - c.lon;
        dlon -= 360.0 * std::round(dlon / 360.0);
        // Cyclone-relative map coordinates: x = a cos(lat_c) dlon, y = a dlat (km).
        const double x = kEarthRadiusKm * coslat_c * dlon * kDegToRad;
        const double y = kEarthRadiusKm * (lat - c.lat) * kDegToRad;
        const double r = std::hypot(x, y);
        const std::size_t idx = static_cast<std::size_t>(k) * kPlane + static_cast<std::size_t>(j) * kNLon +
                                static_cast<std::size_t>(i);

        // --- geopotential -------------------------------------------------------------------
        const double zc = cyclone_height_anomaly(x, y, ln_p, c.deepening);
        const double zj = jet_height_anomaly(ln_p, lat);
        fields[kZ][idx] = kG0 * (h_m + zj + zc);
        if (p == 500.0) s.z500_anomaly_min = std::min(s.z500_anomaly_min, zc);

        // --- wind: jet plus geostrophic wind of the low -------------------------------------
        // With x = a cos(lat_c) dlon: d/d(east) = cos(lat_c)/cos(lat) d/dx, d/d(north) = d/dy.
        constexpr double kDxy = 1.0;  // km
        const double dzdx = (cyclone_height_anomaly(x + kDxy, y, ln_p, c.deepening) -
                             cyclone_height_anomaly(x - kDxy, y, ln_p, c.deepening)) /
                            (2000.0 * kDxy);
        const double dzdy = (cyclone_height_anomaly(x, y + kDxy, ln_p, c.deepening) -
                             cyclone_height_anomaly(x, y - kDxy, ln_p, c.deepening)) /
                            (2000.0 * kDxy);
        const double u = jet_wind(ln_p, lat) - kG0 / f_cor * dzdy;
        const double v = kG0 / f_cor * (coslat_c / coslat) * dzdx;
        fields[kU][idx] = u;
        fields[kV][idx] = v;
        s.wind_max = std::max(s.wind_max, std::hypot(u, v));

        // --- temperature --------------------------------------------------------------------
        const double dz_dlnp =
            (cyclone_height_anomaly(x, y, ln_p + kDlnp, c.deepening) -
             cyclone_height_anomaly(x, y, ln_p - kDlnp, c.deepening) + jet_height_anomaly(ln_p + kDlnp, lat) -
             jet_height_anomaly(ln_p - kDlnp, lat)) /
            (2.0 * kDlnp);
        const double t_balanced = -kG0 / kRd * dz_dlnp;
        const FrontFrame ff = front_frame(x, y);
        const double warm = warm_sector(ff, h_km);
        // Frontal contrast: +4 K in the warm sector, -6 K in the cold air, within ~2500 km of the
        // low and fading out by 400 hPa.
        const double envelope = std::exp(-std::pow(r / 2500.0, 2.0));
        const double t_front = envelope * v_front_t * (-6.0 + 10.0 * warm);
        const double t = t_isa + t_balanced + t_front;
        fields[kT][idx] = t;
        const double liquid = liquid_fraction(t);

        // --- clouds: each feature gives a cover and an in-cloud liquid and ice content ------
        // Frontal band. Warm front: cloud from the surface front forward to where the frontal
        // surface reaches this height, so the band widens with height over the cold air.
        const double wf = bump(ff.warm_surface, -(kWarmSlope * h_km + 50.0), 80.0, 80.0) *
                          bump(ff.warm_along, 0.0, 1400.0, 350.0);
        // Cold front: narrower, leaning back over the cold air, trailing 2000 km.
        const double cf = bump(ff.cold_surface, -(kColdSlope * h_km + 40.0), 70.0, 70.0) *
                          bump(ff.cold_along, 0.0, 2000.0, 400.0);
        // Comma head: an arc around the pole side of the low from the warm front westward,
        // fading out between 180 and 240 degrees from the warm front.
        double alpha = std::atan2(y, x) - kWarmFrontDeg * kDegToRad;
        alpha -= 2.0 * std::numbers::pi * std::floor(alpha / (2.0 * std::numbers::pi));
        const double head = bump(r, 100.0, 550.0, 150.0) * ramp(alpha, 4.19, std::numbers::pi);
        const double cc_front = std::max(v_band * std::max(wf, cf), v_head * head);

        // Cirrus shield ahead of the warm front at 300-200 hPa, textured between 0.3 and 0.8.
        double texture = 0.0;
        for (const Wave& w : feat.cirrus_texture) {
          texture += std::sin(w.kx * x + w.ky * y + w.phase + w.drift * hours);
        }
        texture /= static_cast<double>(feat.cirrus_texture.size());
        const double cirrus_area =
            bump(ff.warm_surface, -1400.0, -450.0, 200.0) * bump(ff.warm_along, -100.0, 2300.0, 300.0);
        const double cc_cirrus =
            v_cirrus * cirrus_area * (0.55 + 0.25 * std::clamp(2.0 * texture, -1.0, 1.0));

        // Warm-sector cumulus: randomly overlapping cells, only in warm air at the ground.
        double clear_cu = 1.0;
        if (p >= 600.0) {
          for (std::size_t n = 0; n < feat.cumulus.size(); ++n) {
            const CumulusCell& cu = feat.cumulus[n];
            const double d = std::hypot(x - cu.x, y - cu.y);
            if (d >= cu.radius) continue;
            const double vert = ramp(p, 1000.0, 925.0) * ramp(p, cu.top - 60.0, cu.top);
            clear_cu *= 1.0 - cu_amp[n] * falloff(d, cu.radius) * vert;
          }
        }
        const double cc_cu = (1.0 - clear_cu) * surface_warm_sector(x, y);

        // Convective tower: cc = 1 in the core, anvil spreading downstream near the top.
        const double dt = std::hypot(x - feat.tower_x, y - feat.tower_y);
        const double cc_tower = v_tower * std::min(1.0, 1.6 * falloff(dt, tower_radius));
        const double anvil_radius = tower_radius * (1.0 + 2.0 * growth * growth);
        const double da = std::hypot(x - feat.tower_x - 100.0 * growth, y - feat.tower_y);
        const double cc_anvil = v_anvil * growth * 0.9 * falloff(da, anvil_radius);

        // Random overlap of the features within the grid box.
        const double cc =
            1.0 - (1.0 - cc_front) * (1.0 - cc_cirrus) * (1.0 - cc_cu) * (1.0 - cc_tower) * (1.0 - cc_anvil);
        // Grid-box means (as ERA5 stores them): total cover times the in-cloud content, which is
        // the cover-weighted mean of the features' in-cloud contents, split by temperature. The
        // band's ice is limited to 1e-4 kg/kg; the cirrus and the anvil are ice whatever T is.
        const double weight = cc_front + cc_cirrus + cc_cu + cc_tower + cc_anvil;
        double lw = 0.0;
        double iw = 0.0;
        if (weight > 0.0) {
          const double in_liquid =
              liquid * (cc_front * band_water + cc_cu * cu_water + cc_tower * tower_intensity * tower_liquid);
          const double in_ice = (1.0 - liquid) * (cc_front * std::min(band_water, 1.0e-4) +
                                                  cc_tower * tower_intensity * tower_ice) +
                                cc_anvil * 1.5e-4 + cc_cirrus * 1.6e-5;
          lw = cc * in_liquid / weight;
          iw = cc * in_ice / weight;
        }
        fields[kCC][idx] = std::clamp(cc, 0.0, 1.0);
        fields[kCLWC][idx] = std::clamp(lw, 0.0, 1.5e-3);
        fields[kCIWC][idx] = std::clamp(iw, 0.0, 8.0e-4);
        s.cc_max = std::max(s.cc_max, cc);

        // --- humidity: relative humidity times saturation, saturated in cloud --------------
        double rh = background_relative_humidity(p) +
                    envelope * v_front_t * (-0.10 + 0.18 * warm);  // moist warm sector
        rh = std::clamp(rh, 0.02, 0.95);
        rh += (1.0 - rh) * std::clamp(cc, 0.0, 1.0);
        fields[kQ][idx] = rh * saturation_specific_humidity(t, p);
      }
    }
  }
  return s;
}

// ---------------------------------------------------------------------------------------------
// Packing (ERA5 scheme) and writing
// ---------------------------------------------------------------------------------------------
constexpr short kFill = -32767;

struct Packing {
  double scale;
  double offset;
};

// ERA5 packs with add_offset = (max + min)/2 and scale_factor = (max - min)/(2^16 - 2), which
// would give the minimum the code -32767, the fill value. The range is therefore extended down by
// one step, so that the data occupy codes -32766..32767 and -32767 only ever means missing.
Packing packing_for(double lo, double hi) {
  if (!(hi > lo)) return {1.0, lo};  // constant field: every value packs to 0
  const double step = (hi - lo) / 65533.0;
  const double lo_ext = lo - step;
  Packing pk{(hi - lo_ext) / 65534.0, 0.5 * (hi + lo_ext)};
  // Rounding can leave the unpacked ends a few ulps outside [lo, hi] (a clear-sky cloud cover of
  // -1e-18, say); nudge the attributes until code -32766 unpacks to >= lo and 32767 to <= hi.
  for (int i = 0; i < 256 && -32766.0 * pk.scale + pk.offset < lo; ++i) {
    pk.offset = std::nextafter(pk.offset, hi);
  }
  for (int i = 0; i < 256 && 32767.0 * pk.scale + pk.offset > hi; ++i) {
    pk.scale = std::nextafter(pk.scale, 0.0);
  }
  return pk;
}

short pack(double value, const Packing& pk) {
  const double code = std::round((value - pk.offset) / pk.scale);
  return static_cast<short>(std::clamp(code, -32766.0, 32767.0));
}

void nc_check(int status, const std::string& what) {
  if (status != NC_NOERR) throw std::runtime_error(what + ": " + nc_strerror(status));
}

void put_text(int ncid, int varid, const char* name, const std::string& value) {
  nc_check(nc_put_att_text(ncid, varid, name, value.size(), value.c_str()),
           std::string("writing attribute ") + name);
}

// Days from 1970-01-01 to a proleptic Gregorian date (Hinnant's days_from_civil algorithm).
long days_from_civil(long y, long m, long d) {
  y -= m <= 2 ? 1 : 0;
  const long era = (y >= 0 ? y : y - 399) / 400;
  const long yoe = y - era * 400;
  const long doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const long doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + doe - 719468;
}

struct Args {
  std::string out;
  std::uint64_t seed = 1;
};

constexpr const char* kProg = "cloudviewer-make-sample";

[[noreturn]] void bad_argument(const std::string& arg, const std::string& found,
                               const std::string& expected) {
  std::fprintf(stderr, "%s: argument %s: found %s, expected %s\n", kProg, arg.c_str(), found.c_str(),
               expected.c_str());
  std::exit(2);
}

Args parse_args(int argc, char** argv) {
  Args a;
  bool have_out = false;
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::printf("usage: %s OUT.nc [--seed N]\n", kProg);
      std::exit(0);
    }
    if (arg == "--seed") {
      if (i + 1 >= argc) bad_argument("--seed", "nothing", "an unsigned integer seed after it");
      const std::string_view val = argv[++i];
      std::uint64_t seed = 0;
      const auto [ptr, ec] = std::from_chars(val.data(), val.data() + val.size(), seed);
      if (val.empty() || ec != std::errc() || ptr != val.data() + val.size()) {
        bad_argument("--seed", "'" + std::string(val) + "'", "an unsigned integer 0..2^64-1");
      }
      a.seed = seed;
    } else if (arg.size() > 1 && arg.front() == '-') {
      bad_argument(std::string(arg), "an unknown option", "OUT.nc or --seed N");
    } else if (have_out) {
      bad_argument(std::string(arg), "a second output path", "exactly one OUT.nc");
    } else {
      if (arg.size() < 4 || arg.substr(arg.size() - 3) != ".nc") {
        bad_argument("OUT.nc", "'" + std::string(arg) + "'", "an output path ending in .nc");
      }
      a.out = arg;
      have_out = true;
    }
  }
  if (!have_out) bad_argument("OUT.nc", "nothing", "an output path ending in .nc");
  return a;
}

void write_file(const std::string& path, const Args& args,
                const std::vector<std::array<std::vector<double>, kNVar>>& steps) {
  int ncid = -1;
  nc_check(nc_create(path.c_str(), NC_CLOBBER | NC_NETCDF4 | NC_CLASSIC_MODEL, &ncid), "creating " + path);
  try {
    int dim_lon = 0, dim_lat = 0, dim_lev = 0, dim_time = 0;
    nc_check(nc_def_dim(ncid, "longitude", kNLon, &dim_lon), "defining longitude");
    nc_check(nc_def_dim(ncid, "latitude", kNLat, &dim_lat), "defining latitude");
    nc_check(nc_def_dim(ncid, "level", kNLev, &dim_lev), "defining level");
    nc_check(nc_def_dim(ncid, "time", NC_UNLIMITED, &dim_time), "defining time");

    int var_lon = 0, var_lat = 0, var_lev = 0, var_time = 0;
    nc_check(nc_def_var(ncid, "longitude", NC_FLOAT, 1, &dim_lon, &var_lon), "defining longitude");
    put_text(ncid, var_lon, "units", "degrees_east");
    put_text(ncid, var_lon, "long_name", "longitude");
    put_text(ncid, var_lon, "standard_name", "longitude");
    nc_check(nc_def_var(ncid, "latitude", NC_FLOAT, 1, &dim_lat, &var_lat), "defining latitude");
    put_text(ncid, var_lat, "units", "degrees_north");
    put_text(ncid, var_lat, "long_name", "latitude");
    put_text(ncid, var_lat, "standard_name", "latitude");
    nc_check(nc_def_var(ncid, "level", NC_INT, 1, &dim_lev, &var_lev), "defining level");
    put_text(ncid, var_lev, "units", "millibars");
    put_text(ncid, var_lev, "long_name", "pressure_level");
    put_text(ncid, var_lev, "standard_name", "air_pressure");
    put_text(ncid, var_lev, "positive", "down");
    nc_check(nc_def_var(ncid, "time", NC_INT, 1, &dim_time, &var_time), "defining time");
    put_text(ncid, var_time, "units", "hours since 1900-01-01 00:00:00.0");
    put_text(ncid, var_time, "long_name", "time");
    put_text(ncid, var_time, "calendar", "gregorian");

    // Packing from each variable's range over the whole file, as ERA5 files are packed.
    std::array<Packing, kNVar> packing{};
    const std::array<int, 4> dims = {dim_time, dim_lev, dim_lat, dim_lon};
    std::array<int, kNVar> varids{};
    for (int v = 0; v < kNVar; ++v) {
      double lo = steps[0][static_cast<std::size_t>(v)][0];
      double hi = lo;
      for (const auto& st : steps) {
        const auto [mn, mx] = std::minmax_element(st[static_cast<std::size_t>(v)].begin(),
                                                  st[static_cast<std::size_t>(v)].end());
        lo = std::min(lo, *mn);
        hi = std::max(hi, *mx);
      }
      const VarInfo& info = kVarInfo[static_cast<std::size_t>(v)];
      Packing& pk = packing[static_cast<std::size_t>(v)];
      pk = packing_for(lo, hi);
      int& id = varids[static_cast<std::size_t>(v)];
      nc_check(nc_def_var(ncid, info.name, NC_SHORT, 4, dims.data(), &id),
               std::string("defining ") + info.name);
      const std::array<std::size_t, 4> chunks = {1, 1, kNLat, kNLon};
      nc_check(nc_def_var_chunking(ncid, id, NC_CHUNKED, chunks.data()), "chunking");
      nc_check(nc_def_var_deflate(ncid, id, 1, 1, 4), "setting deflate");
      nc_check(nc_put_att_double(ncid, id, "scale_factor", NC_DOUBLE, 1, &pk.scale), "scale_factor");
      nc_check(nc_put_att_double(ncid, id, "add_offset", NC_DOUBLE, 1, &pk.offset), "add_offset");
      nc_check(nc_put_att_short(ncid, id, "_FillValue", NC_SHORT, 1, &kFill), "_FillValue");
      nc_check(nc_put_att_short(ncid, id, "missing_value", NC_SHORT, 1, &kFill), "missing_value");
      put_text(ncid, id, "units", info.units);
      put_text(ncid, id, "long_name", info.long_name);
      put_text(ncid, id, "standard_name", info.standard_name);
    }

    put_text(ncid, NC_GLOBAL, "Conventions", "CF-1.6");
    put_text(ncid, NC_GLOBAL, "title",
             "Idealised mid-latitude cyclone crossing the date line (synthetic ERA5-like sample)");
    put_text(ncid, NC_GLOBAL, "institution", "cloudviewer sample generator (synthetic data, not a forecast)");
    put_text(ncid, NC_GLOBAL, "source",
             "analytic model: ISA background, balanced westerly jet, geostrophic low with fronts, "
             "frontal cloud band, warm-sector cumulus, cirrus shield and one convective tower");
    put_text(ncid, NC_GLOBAL, "history",
             std::string(kProg) + " --seed " + std::to_string(args.seed) +
                 ": written by cloudviewer's own sample generator "
                 "(sample_data/generator/make_sample.cpp)");
    nc_check(nc_enddef(ncid), "leaving define mode");

    std::array<float, kNLon> lons{};
    for (int i = 0; i < kNLon; ++i) lons[static_cast<std::size_t>(i)] = static_cast<float>(kLon0 + kDeg * i);
    std::array<float, kNLat> lats{};
    for (int j = 0; j < kNLat; ++j) lats[static_cast<std::size_t>(j)] = static_cast<float>(kLat0 - kDeg * j);
    nc_check(nc_put_var_float(ncid, var_lon, lons.data()), "writing longitude");
    nc_check(nc_put_var_float(ncid, var_lat, lats.data()), "writing latitude");
    nc_check(nc_put_var_int(ncid, var_lev, kLevels.data()), "writing level");

    const int base_hours =
        static_cast<int>((days_from_civil(2024, 1, 15) - days_from_civil(1900, 1, 1)) * 24);
    std::vector<short> packed(kStepSize);
    for (int n = 0; n < kNTime; ++n) {
      const std::size_t start_t[1] = {static_cast<std::size_t>(n)};
      const std::size_t count_t[1] = {1};
      const int hours = base_hours + n * kStepHours;
      nc_check(nc_put_vara_int(ncid, var_time, start_t, count_t, &hours), "writing time");
      for (int v = 0; v < kNVar; ++v) {
        const std::vector<double>& src = steps[static_cast<std::size_t>(n)][static_cast<std::size_t>(v)];
        for (std::size_t e = 0; e < kStepSize; ++e)
          packed[e] = pack(src[e], packing[static_cast<std::size_t>(v)]);
        const std::array<std::size_t, 4> start = {static_cast<std::size_t>(n), 0, 0, 0};
        const std::array<std::size_t, 4> count = {1, kNLev, kNLat, kNLon};
        nc_check(nc_put_vara_short(ncid, varids[static_cast<std::size_t>(v)], start.data(), count.data(),
                                   packed.data()),
                 std::string("writing ") + kVarInfo[static_cast<std::size_t>(v)].name);
      }
    }
  } catch (...) {
    nc_close(ncid);
    throw;
  }
  nc_check(nc_close(ncid), "closing " + path);
}

}  // namespace

int main(int argc, char** argv) {
  const Args args = parse_args(argc, argv);
  const std::string tmp = args.out + ".tmp";
  try {
    const Features feat = make_features(args.seed);
    std::vector<std::array<std::vector<double>, kNVar>> steps(kNTime);
    for (int n = 0; n < kNTime; ++n) {
      auto& fields = steps[static_cast<std::size_t>(n)];
      for (auto& f : fields) f.assign(kStepSize, 0.0);
      const StepSummary s = compute_step(n, feat, fields);
      std::printf(
          "%s: step %d/%d 2024-01-15 %02d:00 UTC: low at %.2fE %.2fN, z500 anomaly %.0f m, "
          "max wind %.1f m/s, max cloud cover %.2f\n",
          kProg, n + 1, kNTime, n * kStepHours, s.centre.lon, s.centre.lat, s.z500_anomaly_min, s.wind_max,
          s.cc_max);
      std::fflush(stdout);
    }
    write_file(tmp, args, steps);
    std::filesystem::rename(tmp, args.out);
    std::printf("%s: wrote %s (seed %llu)\n", kProg, args.out.c_str(),
                static_cast<unsigned long long>(args.seed));
  } catch (const std::exception& e) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    std::fprintf(stderr, "%s: %s\n", kProg, e.what());
    return 1;
  }
  return 0;
}
