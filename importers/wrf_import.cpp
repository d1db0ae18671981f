// WRF output to a CloudVolume: Lambert conformal, Mercator and polar stereographic grids (projection
// math from GeographicLib, on WRF's 6370 km sphere) resampled onto a lon/lat grid without inventing
// data outside the model domain; destaggering; heights from (PH + PHB) / g; T from perturbation
// potential temperature; winds rotated from grid-relative to earth-relative.
#include <GeographicLib/LambertConformalConic.hpp>
#include <GeographicLib/PolarStereographic.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "cf_time.hpp"
#include "checks.hpp"
#include "column.hpp"
#include "importer.hpp"
#include "nc_file.hpp"
#include "scene/framing.hpp"
#include "wrf_import.hpp"

namespace cv::importers {
namespace {

constexpr double kWrfEarthRadiusM = 6370000.0;  // the sphere WRF's map projections use
constexpr double kKappa = 287.05 / 1004.6;      // R_d / c_p
// WRF's own gravity: its heights are (PH + PHB) / 9.81 (that reproduces HGT at the lowest level;
// 9.80665 puts the ground 1.7 m high on the Tibetan Plateau), with no geometric correction.
constexpr double kWrfG = 9.81;
constexpr double kDeg = 3.14159265358979323846 / 180.0;

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}

// Map projection of a WRF domain: (lat, lon) -> metres in the projection plane, and the angle from
// grid north to true north (for rotating winds).
class WrfProjection {
 public:
  WrfProjection(const NcFile& f) : path_(f.path()) {
    auto need = [&](const char* name) {
      const auto v = f.global_number(name);
      if (!v) throw ImportError(path_ + ": global attribute '" + std::string(name) + "' is missing; expected WRF map projection attributes");
      return *v;
    };
    // Checked before it becomes an int: a huge or NaN value would overflow the conversion (found
    // by fuzz_netcdf_semantic: MAP_PROJ = 3.4e38).
    const double map_proj = need("MAP_PROJ");
    if (!(map_proj == 1.0 || map_proj == 2.0 || map_proj == 3.0)) {
      throw ImportError(path_ + ": MAP_PROJ is " + fmt(map_proj) +
                        ", expected 1 (Lambert conformal), 2 (polar stereographic) or 3 (Mercator)");
    }
    proj_ = static_cast<int>(map_proj);
    truelat1_ = need("TRUELAT1");
    truelat2_ = f.global_number("TRUELAT2").value_or(truelat1_);
    stand_lon_ = need("STAND_LON");
    dx_ = need("DX");
    dy_ = need("DY");
    for (const auto& [name, value] : {std::pair{"TRUELAT1", truelat1_}, std::pair{"TRUELAT2", truelat2_}}) {
      if (!(std::abs(value) <= 90.0)) {
        throw ImportError(path_ + ": global attribute '" + name + "' is " + fmt(value) + ", expected a latitude within -90..90");
      }
    }
    if (!(std::abs(stand_lon_) <= 360.0)) {
      throw ImportError(path_ + ": global attribute 'STAND_LON' is " + fmt(stand_lon_) + ", expected a longitude within -360..360");
    }
    if (!(dx_ >= 1 && dy_ >= 1 && dx_ < 1e6 && dy_ < 1e6)) {
      throw ImportError(path_ + ": DX/DY are " + fmt(dx_) + "/" + fmt(dy_) + " m, expected grid spacings between 1 m and 1000 km");
    }
    if (proj_ == 1) {
      lcc_ = std::make_unique<GeographicLib::LambertConformalConic>(kWrfEarthRadiusM, 0.0, truelat1_, truelat2_, 1.0);
    } else if (proj_ == 2) {
      ps_ = std::make_unique<GeographicLib::PolarStereographic>(kWrfEarthRadiusM, 0.0, 1.0);
      north_ = truelat1_ >= 0.0;
      ps_->SetScale(std::abs(truelat1_), 1.0);  // GeographicLib takes the latitude in the projection's own hemisphere
    } else if (proj_ == 3) {
      mercator_k_ = std::cos(truelat1_ * kDeg);
    } else {
      throw ImportError(path_ + ": MAP_PROJ is " + std::to_string(proj_) +
                        ", expected 1 (Lambert conformal), 2 (polar stereographic) or 3 (Mercator)");
    }
  }
  std::string name() const {
    return proj_ == 1 ? "Lambert conformal (true latitudes " + fmt(truelat1_) + ", " + fmt(truelat2_) + ")"
         : proj_ == 2 ? "polar stereographic (true latitude " + fmt(truelat1_) + ")"
                      : "Mercator (true latitude " + fmt(truelat1_) + ")";
  }
  double dx() const { return dx_; }
  double dy() const { return dy_; }
  // Projected metres; gamma_deg is the meridian convergence (grid north relative to true north).
  void forward(double lat, double lon, double& x, double& y, double& gamma_deg) const {
    double k = 1.0;
    const double dl = std::remainder(lon - stand_lon_, 360.0);
    if (lcc_) {
      lcc_->Forward(stand_lon_, lat, stand_lon_ + dl, x, y, gamma_deg, k);
    } else if (ps_) {
      ps_->Forward(north_, lat, dl, x, y, gamma_deg, k);
    } else {
      x = kWrfEarthRadiusM * mercator_k_ * dl * kDeg;
      y = kWrfEarthRadiusM * mercator_k_ * std::log(std::tan(3.14159265358979323846 / 4.0 + lat * kDeg / 2.0));
      gamma_deg = 0.0;
    }
  }

 private:
  std::string path_;
  int proj_ = 0;
  double truelat1_ = 0, truelat2_ = 0, stand_lon_ = 0, dx_ = 0, dy_ = 0, mercator_k_ = 1;
  bool north_ = true;
  std::unique_ptr<GeographicLib::LambertConformalConic> lcc_;
  std::unique_ptr<GeographicLib::PolarStereographic> ps_;
};

// Where each output column falls in the WRF mass grid.
struct Sample {
  bool inside = false;
  int i0 = 0, j0 = 0;
  double wi = 0, wj = 0;
  double cos_a = 1, sin_a = 0;  // grid -> earth wind rotation
};

}  // namespace

struct WrfSource {
  std::unique_ptr<NcFile> file;
  std::unique_ptr<WrfProjection> proj;
  int nx = 0, ny = 0, nz = 0;
  std::vector<Sample> samples;  // per output column (of the first step when the nest moves)
  bool moving = false;          // XLAT/XLONG change between steps: each step is placed on its own
  std::vector<int> steps;
  ImportOptions options;
  int dim_time = -1;
};

namespace {

// One variable at one time, as a (k, j, i) array with its own extents (staggered ones are larger).
struct Field3 {
  std::vector<double> v;
  int nx = 0, ny = 0, nz = 0;
  bool present = false;
  double at(int i, int j, int k) const { return v[(static_cast<std::size_t>(k) * ny + j) * nx + i]; }
};

Field3 read3(const WrfSource& S, const char* name, int t, bool required) {
  const NcFile& f = *S.file;
  Field3 out;
  const NcVar* v = f.find(name);
  if (!v) {
    if (required) throw ImportError(f.path() + ": variable '" + std::string(name) + "' is missing; a WRF import needs it");
    return out;
  }
  std::vector<std::size_t> start(v->dims.size(), 0), count;
  for (std::size_t d = 0; d < v->dims.size(); ++d) count.push_back(f.dim_length(*v, d));
  std::size_t a = 0;
  if (v->dims.size() == 4 || (v->dims.size() == 3 && v->dims[0] == S.dim_time)) {
    start[0] = static_cast<std::size_t>(t);
    count[0] = 1;
    a = 1;
  }
  const std::size_t rank = v->dims.size() - a;
  out.nz = rank == 3 ? static_cast<int>(count[a]) : 1;
  out.ny = static_cast<int>(count[a + rank - 2]);
  out.nx = static_cast<int>(count[a + rank - 1]);
  out.v = f.read(*v, start, count);
  out.present = true;
  return out;
}

// Bilinear interpolation of a mass-point field at an output column.
double bilinear(const Field3& f, const Sample& s, int k) {
  const int i1 = std::min(s.i0 + 1, f.nx - 1), j1 = std::min(s.j0 + 1, f.ny - 1);
  return (1 - s.wj) * ((1 - s.wi) * f.at(s.i0, s.j0, k) + s.wi * f.at(i1, s.j0, k)) +
         s.wj * ((1 - s.wi) * f.at(s.i0, j1, k) + s.wi * f.at(i1, j1, k));
}

// WRF's "2005-09-21_00:00:00" as a valid time.
core::ValidTime wrf_time(const std::string& s, const std::string& where) {
  int y, mo, d, h, mi, se;
  if (std::sscanf(s.c_str(), "%d-%d-%d_%d:%d:%d", &y, &mo, &d, &h, &mi, &se) != 6) {
    throw ImportError(where + ": time '" + s + "', expected YYYY-MM-DD_hh:mm:ss");
  }
  core::ValidTime t;
  char buf[96];
  std::snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%02dZ", y, mo, d, h, mi, se);
  // Every field in its range (month 1..12, the day within its month, hh:mm:ss of a day).
  if (y < 1 || y > 9999 || !core::parse_iso_utc(buf)) {
    throw ImportError(where + ": time '" + s + "' is no real date and time, expected YYYY-MM-DD_hh:mm:ss with each field in range");
  }
  t.iso_utc = buf;
  t.unix_s = days_from_civil(y, mo, d) * 86400 + h * 3600 + mi * 60 + se;
  return t;
}

// A 2-D mass-grid variable (XLAT, XLONG, COSALPHA, ...) at time index t (ignored without a Time
// dimension).
std::vector<double> read_mass2d(const WrfSource& S, const char* name, int t) {
  const NcFile& f = *S.file;
  const NcVar& v = f.var(name);
  std::vector<std::size_t> start(v.dims.size(), 0), count;
  for (std::size_t d = 0; d < v.dims.size(); ++d) count.push_back(f.dim_length(v, d));
  if (v.dims.size() == 3) count[0] = 1, start[0] = static_cast<std::size_t>(t);
  if (v.dims.size() < 2 || v.dims.size() > 3 || count[count.size() - 1] != static_cast<std::size_t>(S.nx) ||
      count[count.size() - 2] != static_cast<std::size_t>(S.ny)) {
    throw ImportError(f.path() + ": variable '" + std::string(name) + "' is not on the mass grid (" + std::to_string(S.ny) + " x " +
                      std::to_string(S.nx) + ")");
  }
  return f.read(v, start, count);
}

// Where each output column falls in the mass grid whose first point is (lat0, lon0), with the
// grid-to-earth wind rotation: COSALPHA/SINALPHA interpolated bilinearly like any field, or the
// projection's meridian convergence. Checks that the projection reproduces the far corner.
std::vector<Sample> place_samples(const WrfSource& S, const core::VolumeGrid& grid, const std::vector<double>& xlat,
                                  const std::vector<double>& xlon, const std::vector<double>& cos_alpha,
                                  const std::vector<double>& sin_alpha, int t, double* corner_error_m) {
  const WrfProjection& proj = *S.proj;
  const std::string& path = S.file->path();
  double x0, y0, g;
  proj.forward(xlat[0], xlon[0], x0, y0, g);
  {
    const std::size_t last = xlat.size() - 1;
    double xc, yc;
    proj.forward(xlat[last], xlon[last], xc, yc, g);
    const double ex = xc - (x0 + (S.nx - 1) * proj.dx()), ey = yc - (y0 + (S.ny - 1) * proj.dy());
    if (std::hypot(ex, ey) > 0.25 * std::min(proj.dx(), proj.dy())) {
      throw ImportError(path + ": the map projection (MAP_PROJ, TRUELAT1/2, STAND_LON, DX, DY) puts the last mass point " +
                        fmt(std::hypot(ex, ey)) + " m from XLAT/XLONG at time step " + std::to_string(t) +
                        "; expected under a quarter of a grid cell");
    }
    if (corner_error_m) *corner_error_m = std::hypot(ex, ey);
  }
  std::vector<Sample> samples(grid.columns());
  auto at = [&](const std::vector<double>& a, int i, int j) {
    return a[static_cast<std::size_t>(j) * static_cast<std::size_t>(S.nx) + static_cast<std::size_t>(i)];
  };
  for (int y = 0; y < grid.lat_deg.count; ++y) {
    for (int x = 0; x < grid.lon_deg.count; ++x) {
      double px, py, gamma;
      proj.forward(grid.lat_deg.at(y), grid.lon_deg.at(x), px, py, gamma);
      const double fi = (px - x0) / proj.dx(), fj = (py - y0) / proj.dy();
      Sample& s = samples[grid.column(x, y)];
      if (fi < -1e-9 || fj < -1e-9 || fi > S.nx - 1 + 1e-9 || fj > S.ny - 1 + 1e-9) continue;
      s.inside = true;
      s.i0 = std::clamp(static_cast<int>(std::floor(fi)), 0, S.nx - 2);
      s.j0 = std::clamp(static_cast<int>(std::floor(fj)), 0, S.ny - 2);
      s.wi = std::clamp(fi - s.i0, 0.0, 1.0);
      s.wj = std::clamp(fj - s.j0, 0.0, 1.0);
      if (!cos_alpha.empty()) {
        auto lerp2 = [&](const std::vector<double>& a) {
          return (1 - s.wj) * ((1 - s.wi) * at(a, s.i0, s.j0) + s.wi * at(a, s.i0 + 1, s.j0)) +
                 s.wj * ((1 - s.wi) * at(a, s.i0, s.j0 + 1) + s.wi * at(a, s.i0 + 1, s.j0 + 1));
        };
        s.cos_a = lerp2(cos_alpha);
        s.sin_a = lerp2(sin_alpha);
      } else {
        // Grid north lies gamma degrees clockwise of true north.
        s.cos_a = std::cos(-gamma * kDeg);
        s.sin_a = std::sin(-gamma * kDeg);
      }
    }
  }
  return samples;
}

// The samples of time index t, from that step's own XLAT/XLONG (a moving nest).
std::vector<Sample> samples_at(const WrfSource& S, const core::VolumeGrid& grid, int t) {
  std::vector<double> ca, sa;
  if (S.file->find("COSALPHA") && S.file->find("SINALPHA")) ca = read_mass2d(S, "COSALPHA", t), sa = read_mass2d(S, "SINALPHA", t);
  return place_samples(S, grid, read_mass2d(S, "XLAT", t), read_mass2d(S, "XLONG", t), ca, sa, t, nullptr);
}

}  // namespace

bool is_wrf_file(const NcFile& f) { return f.find("XLAT") && f.global_number("MAP_PROJ").has_value(); }

bool is_wrf_geogrid_file(const NcFile& f) { return !f.find("XLAT") && f.find("XLAT_M") && f.find("XLONG_M"); }

std::string wrf_geogrid_message(const NcFile& f) {
  return f.path() + ": a WRF GEOGRID static file (XLAT_M, XLONG_M" + (f.find("HGT_M") ? ", HGT_M" : "") +
         "): it holds terrain and land use, no cloud; expected WRF model output (wrfout: XLAT, XLONG and QCLOUD, QICE or CLDFRA)";
}

std::pair<double, double> wrf_rotation_from_projection(const NcFile& f, double lat, double lon) {
  const WrfProjection proj(f);
  double x, y, gamma;
  proj.forward(lat, lon, x, y, gamma);
  return {std::cos(-gamma * kDeg), std::sin(-gamma * kDeg)};
}

void load_wrf_step(const WrfSource& S, const core::VolumeGrid& grid, std::size_t step, core::ImportReport& report,
                   core::TimeStepData& out) {
  const int t = S.steps[step];
  const std::string& path = S.file->path();
  const Field3 ph = read3(S, "PH", t, true), phb = read3(S, "PHB", t, true);
  const Field3 p = read3(S, "P", t, true), pb = read3(S, "PB", t, true), th = read3(S, "T", t, true);
  const Field3 qv = read3(S, "QVAPOR", t, false), qc = read3(S, "QCLOUD", t, false), qi = read3(S, "QICE", t, false);
  const Field3 qs = read3(S, "QSNOW", t, false), cf = read3(S, "CLDFRA", t, false);
  const Field3 u = read3(S, "U", t, false), v = read3(S, "V", t, false), w = read3(S, "W", t, false);
  auto stats = [&](const char* role, const char* name, const Field3& f, const std::string& conv) {
    if (!f.present) return;
    auto& use = report.use(role);
    use.variable = name;
    use.units = S.file->var(name).text("units");
    use.conversion = conv;
    use.before.add_all(f.v.data(), f.v.size());
  };
  stats("geopotential (perturbation)", "PH", ph, "z = (PH + PHB) / 9.81 (WRF's g) on staggered levels, averaged to mass levels");
  stats("pressure (perturbation)", "P", p, "p = P + PB");
  stats("potential temperature perturbation", "T", th, "T = (T + 300) (p / 1e5)^(R_d / c_p)");
  stats("water vapour mixing ratio", "QVAPOR", qv, "specific humidity q = r / (1 + r), for air density");
  const std::string in_cloud = cf.present ? "grid-box mean interpolated with CLDFRA, in-cloud = mean / CLDFRA" : "no CLDFRA: q fills the box";
  stats("cloud liquid water", "QCLOUD", qc, "mixing ratio to specific; " + in_cloud + "; sigma = 3 rho q / (2 rho_w r_eff)");
  stats("cloud ice water", "QICE", qi, "QICE + QSNOW; " + in_cloud + "; sigma = 3 rho q / (2 917 kg/m3 r_eff)");
  stats("snow (counted as ice)", "QSNOW", qs, "added to QICE");
  stats("cloud fraction", "CLDFRA", cf, "clamped to 0..1");
  stats("grid-relative u", "U", u, "destaggered in x, rotated to earth-relative");
  stats("grid-relative v", "V", v, "destaggered in y, rotated to earth-relative");
  stats("vertical wind", "W", w, "destaggered in z");
  for (const Field3* f : {&ph, &phb}) {
    if (f->nz != S.nz + 1) throw ImportError(path + ": PH/PHB have " + std::to_string(f->nz) + " levels, expected " + std::to_string(S.nz + 1));
  }

  auto alloc = [&](core::Field fld, bool on) {
    if (on) out[fld].assign(grid.points(), std::numeric_limits<float>::quiet_NaN());
    else out[fld].clear();
  };
  alloc(core::Field::ExtinctionLiquid, qc.present);
  alloc(core::Field::ExtinctionIce, qi.present || qs.present);
  alloc(core::Field::CloudFraction, cf.present);
  alloc(core::Field::WindU, u.present && v.present);
  alloc(core::Field::WindV, u.present && v.present);
  alloc(core::Field::WindW, w.present);
  alloc(core::Field::Temperature, true);
  alloc(core::Field::Pressure, true);  // P + PB
  out.ground_m.assign(grid.columns(), std::numeric_limits<float>::quiet_NaN());
  // A moving nest: this step's own grid.
  std::vector<Sample> own;
  if (S.moving) own = samples_at(S, grid, t);
  const std::vector<Sample>& samples = S.moving ? own : S.samples;
  // The consistency counts over the file's own boxes (the resampled points are counted apart).
  ColumnCounts file_counts;
  if (cf.present && (qc.present || qi.present || qs.present)) {
    for (std::size_t n = 0; n < cf.v.size(); ++n) {
      double total = 0.0;
      for (const Field3* q : {&qc, &qi, &qs}) {
        if (q->present && q->v[n] > 0.0) total += q->v[n];
      }
      if (total > 0.0 && cf.v[n] < kZeroCloudFraction) {
        ++file_counts.water_without_cf;
        if (total > kZeroWater) ++file_counts.water_without_cf_significant;
        file_counts.most_water_without_cf = std::max(file_counts.most_water_without_cf, total);
      }
      if (cf.v[n] > 0.1 && total <= kZeroWater) ++file_counts.cf_without_water;
    }
  }
  ColumnCounts counts;
  ConversionOptions conv{S.options.r_eff_liquid_um, S.options.r_eff_ice_um};
  std::vector<LevelSample> column(static_cast<std::size_t>(S.nz));
  std::size_t negative = 0, clamped = 0;
  auto bad = [&](const char* var, double val, const char* expected) {
    throw ImportError(path + ": variable '" + std::string(var) + "' has value " + fmt(val) + " at time step " +
                      std::to_string(t) + ", expected " + expected);
  };
  for (int y = 0; y < grid.lat_deg.count; ++y) {
    for (int x = 0; x < grid.lon_deg.count; ++x) {
      const Sample& s = samples[grid.column(x, y)];
      if (!s.inside) continue;  // outside the model domain: no data, never an invented value
      out.ground_m[grid.column(x, y)] = static_cast<float>((bilinear(ph, s, 0) + bilinear(phb, s, 0)) / kWrfG);
      for (int k = 0; k < S.nz; ++k) {
        LevelSample& c = column[static_cast<std::size_t>(k)];
        c = LevelSample{};
        const double phi = 0.5 * (bilinear(ph, s, k) + bilinear(phb, s, k) + bilinear(ph, s, k + 1) + bilinear(phb, s, k + 1));
        c.z_m = phi / kWrfG;
        if (!(c.z_m > -1000.0 && c.z_m < 1.0e5)) bad("PH", c.z_m, "(PH + PHB) / g between -1 km and 100 km");
        c.p_pa = bilinear(p, s, k) + bilinear(pb, s, k);
        if (!(c.p_pa > 0.0 && c.p_pa < 1.2e5)) bad("P", c.p_pa, "P + PB between 0 and 1200 hPa");
        const double r = qv.present ? std::max(0.0, bilinear(qv, s, k)) : 0.0;
        c.qv = r / (1.0 + r);
        c.t_k = (bilinear(th, s, k) + 300.0) * std::pow(c.p_pa / 1.0e5, kKappa);
        if (!(c.t_k > 100.0 && c.t_k < 400.0)) bad("T", c.t_k, "a temperature between 100 and 400 K");
        auto water = [&](const Field3& f, const char* name) {
          double q = bilinear(f, s, k);
          if (q < -1e-5 || q > 0.05) bad(name, q, "a mixing ratio between 0 and 0.05 kg/kg");
          if (q < 0.0) {
            ++negative;
            q = 0.0;
          }
          return q / (1.0 + r);  // per kg of moist air
        };
        if (qc.present) c.q_liquid = water(qc, "QCLOUD");
        if (qi.present || qs.present) c.q_ice = (qi.present ? water(qi, "QICE") : 0.0) + (qs.present ? water(qs, "QSNOW") : 0.0);
        if (cf.present) {
          c.cf = bilinear(cf, s, k);
          if (c.cf < -0.01 || c.cf > 1.01) bad("CLDFRA", c.cf, "a fraction between 0 and 1");
          if (c.cf < 0.0 || c.cf > 1.0) ++clamped, c.cf = std::clamp(c.cf, 0.0, 1.0);
        }
        if (u.present && v.present) {
          // U sits on the west and east faces (index i and i + 1 of the mass cell), V on the south and
          // north faces: average the two faces, then rotate grid-relative to earth-relative.
          Sample east = s, north = s;
          east.i0 += 1;
          north.j0 += 1;
          const double ug = 0.5 * (bilinear(u, s, k) + bilinear(u, east, k));
          const double vg = 0.5 * (bilinear(v, s, k) + bilinear(v, north, k));
          c.u = ug * s.cos_a - vg * s.sin_a;
          c.v = vg * s.cos_a + ug * s.sin_a;
        }
        if (w.present) c.w = 0.5 * (bilinear(w, s, k) + bilinear(w, s, k + 1));
      }
      place_column(column, grid, x, y, conv, out, counts);
    }
  }
  if (negative) report.warn(std::to_string(negative) + " negative mixing ratios set to 0 at time step " + std::to_string(t));
  if (clamped) report.use("cloud fraction").clamped += clamped;
  report_counts(file_counts, t, "file boxes", report);
  report_counts(counts, t, "resampled points (output columns x model levels)", report);
  auto after = [&](const char* role, core::Field f) {
    auto& use = report.use(role);
    use.after.add_all(out[f].data(), out[f].size());
    use.after_units = core::field_units(f);
  };
  if (qc.present) after("cloud liquid water", core::Field::ExtinctionLiquid);
  if (qi.present) after("cloud ice water", core::Field::ExtinctionIce);
  if (cf.present) after("cloud fraction", core::Field::CloudFraction);
  if (u.present && v.present) after("grid-relative u", core::Field::WindU), after("grid-relative v", core::Field::WindV);
  if (w.present) after("vertical wind", core::Field::WindW);
  after("potential temperature perturbation", core::Field::Temperature);
}

core::CloudVolume import_wrf(std::unique_ptr<NcFile> file, const ImportOptions& options) {
  auto S = std::make_shared<WrfSource>();
  S->file = std::move(file);
  S->options = options;
  const NcFile& f = *S->file;
  const std::string& path = f.path();
  S->proj = std::make_unique<WrfProjection>(f);
  const WrfProjection& proj = *S->proj;
  core::CloudVolume vol;
  vol.liquid_r_eff_um = options.r_eff_liquid_um;
  vol.report.file = path;
  vol.report.format = "WRF, " + proj.name();
  // Grid size from the dimensions: the global attributes may describe the uncropped domain.
  auto dim = [&](const char* name) -> int {
    for (const auto& d : f.dims()) {
      if (d.name == name) return static_cast<int>(d.length);
    }
    throw ImportError(path + ": dimension '" + std::string(name) + "' is missing; expected a WRF file");
  };
  S->nx = dim("west_east");
  S->ny = dim("south_north");
  S->nz = dim("bottom_top");
  for (std::size_t d = 0; d < f.dims().size(); ++d) {
    if (f.dims()[d].name == "Time") S->dim_time = static_cast<int>(d);
  }
  // Compared as numbers, not converted to int (a huge claim would overflow the conversion).
  if (const auto claimed = f.global_number("WEST-EAST_GRID_DIMENSION"); claimed && !(*claimed - 1.0 == static_cast<double>(S->nx))) {
    vol.report.notes.push_back("global attributes claim " + fmt(*claimed - 1) + " x " +
                               fmt(f.global_number("SOUTH-NORTH_GRID_DIMENSION").value_or(0) - 1) +
                               " mass points; the file holds " + std::to_string(S->nx) + " x " + std::to_string(S->ny) +
                               " (cropped?): its dimensions are used");
  }
  if (S->nx < 2 || S->ny < 2 || S->nz < 2) throw ImportError(path + ": the WRF grid is smaller than 2 x 2 x 2");
  // Every 3-D variable used must have the shape WRF gives it (staggered ones one longer), so no
  // read can run past an array.
  {
    struct Shape {
      const char* name;
      int dz, dy, dx;  // extra length over nz, ny, nx
    };
    const Shape shapes[] = {{"PH", 1, 0, 0}, {"PHB", 1, 0, 0}, {"W", 1, 0, 0},      {"P", 0, 0, 0},
                            {"PB", 0, 0, 0}, {"T", 0, 0, 0},   {"QVAPOR", 0, 0, 0}, {"QCLOUD", 0, 0, 0},
                            {"QICE", 0, 0, 0}, {"QSNOW", 0, 0, 0}, {"CLDFRA", 0, 0, 0}, {"U", 0, 0, 1}, {"V", 0, 1, 0}};
    for (const Shape& sh : shapes) {
      const NcVar* v = f.find(sh.name);
      if (!v) continue;
      const std::size_t want[3] = {static_cast<std::size_t>(S->nz + sh.dz), static_cast<std::size_t>(S->ny + sh.dy),
                                   static_cast<std::size_t>(S->nx + sh.dx)};
      const std::size_t r = v->dims.size();
      bool ok = r == 4 && v->dims[0] == S->dim_time;
      for (std::size_t a = 0; ok && a < 3; ++a) ok = f.dim_length(*v, a + 1) == want[a];
      if (!ok) {
        std::string got;
        for (std::size_t a = 0; a < r; ++a) got += (a ? " x " : "") + std::to_string(f.dim_length(*v, a));
        throw ImportError(path + ": variable '" + sh.name + "' has shape (" + got + "), expected (Time x " +
                          std::to_string(want[0]) + " x " + std::to_string(want[1]) + " x " + std::to_string(want[2]) + ")");
      }
    }
  }
  if (options.level_min_hpa > 0.0 || options.level_max_hpa < 1e9) {
    vol.report.warn("--levels applies to pressure-level files; a WRF file is read on all its model levels");
  }
  // Time steps (their grids may differ: a moving nest).
  std::vector<std::string> times;
  if (const NcVar* tv = f.find("Times")) times = f.read_strings(*tv);
  const int nt = S->dim_time >= 0 ? static_cast<int>(f.dims()[static_cast<std::size_t>(S->dim_time)].length) : 1;
  const int last = options.time_last < 0 ? nt - 1 : std::min(options.time_last, nt - 1);
  for (int t = std::max(0, options.time_first); t <= last; t += std::max(1, options.time_stride)) {
    const core::ValidTime vt = static_cast<std::size_t>(t) < times.size()
                                   ? wrf_time(times[static_cast<std::size_t>(t)], path + ": variable 'Times'")
                                   : core::ValidTime{0, "step " + std::to_string(t)};
    if (!in_time_range(vt, options)) continue;
    S->steps.push_back(t);
    vol.times.push_back(vt);
  }
  if (S->steps.empty()) throw ImportError(path + ": no time step in the requested range (the file has " + std::to_string(nt) + ")");
  // XLAT/XLONG, with or without a Time dimension. When they change from step to step (a
  // vortex-following nest), every step is placed with its own grid, in a box that holds them all.
  const std::vector<double> xlat = read_mass2d(*S, "XLAT", S->steps.front()), xlon = read_mass2d(*S, "XLONG", S->steps.front());
  double lon_min = 1e9, lon_max = -1e9, lat_min = 1e9, lat_max = -1e9;
  auto extend = [&](const std::vector<double>& la, const std::vector<double>& lo) {
    for (std::size_t n = 0; n < la.size(); ++n) {
      const double lon = xlon[0] + std::remainder(lo[n] - xlon[0], 360.0);
      lon_min = std::min(lon_min, lon), lon_max = std::max(lon_max, lon);
      lat_min = std::min(lat_min, la[n]), lat_max = std::max(lat_max, la[n]);
    }
  };
  // Every mass point's coordinates in range (a NaN XLAT would otherwise size the grid from NaN).
  auto check_coordinates = [&](const std::vector<double>& la, const std::vector<double>& lo) {
    for (std::size_t n = 0; n < la.size(); ++n) {
      if (!(std::abs(la[n]) <= 90.0) || !(std::abs(lo[n]) <= 360.0)) {
        const bool lat = !(std::abs(la[n]) <= 90.0);
        throw ImportError(path + ": variable '" + (lat ? "XLAT" : "XLONG") + "' has value " + fmt(lat ? la[n] : lo[n]) +
                          " at mass point " + std::to_string(n) + ", expected " +
                          (lat ? "a latitude within -90..90" : "a longitude within -360..360"));
      }
    }
  };
  check_coordinates(xlat, xlon);
  extend(xlat, xlon);
  double moved_km = 0.0;
  if (f.var("XLAT").dims.size() == 3 && S->steps.size() > 1) {
    for (std::size_t k = 1; k < S->steps.size(); ++k) {
      const std::vector<double> la = read_mass2d(*S, "XLAT", S->steps[k]), lo = read_mass2d(*S, "XLONG", S->steps[k]);
      check_coordinates(la, lo);
      double diff = 0.0;
      for (std::size_t n = 0; n < la.size(); ++n) {
        diff = std::max({diff, std::abs(la[n] - xlat[n]), std::abs(std::remainder(lo[n] - xlon[n], 360.0))});
      }
      if (diff > 1e-4) {
        S->moving = true;
        extend(la, lo);
        double xa, ya, xb, yb, g;
        proj.forward(xlat[0], xlon[0], xa, ya, g);
        proj.forward(la[0], lo[0], xb, yb, g);
        moved_km = std::max(moved_km, std::hypot(xb - xa, yb - ya) / 1000.0);
      }
    }
  }
  if (S->moving) {
    vol.report.warn("the nest moves: XLAT/XLONG change between time steps (its first mass point moves up to " + fmt(moved_km) +
                    " km from the first step's); each step is placed with its own grid");
  }
  // Output lon/lat grid: the domain's bounding box at about the model's spacing.
  if (options.region) {
    const auto& r = *options.region;
    double w = r.lon_west_deg, e = r.lon_east_deg;
    while (w > lon_min + 180.0) w -= 360.0;
    while (w < lon_min - 180.0) w += 360.0;
    while (e < w) e += 360.0;
    lon_min = std::max(lon_min, w), lon_max = std::min(lon_max, e);
    lat_min = std::max(lat_min, r.lat_south_deg), lat_max = std::min(lat_max, r.lat_north_deg);
    if (lon_min > lon_max || lat_min > lat_max) throw ImportError(path + ": the region does not overlap the WRF domain");
  }
  const int stride = std::max(1, options.horizontal_stride);
  const double dlat = proj.dy() / (kWrfEarthRadiusM * kDeg) * stride;
  const double dlon = dlat / std::max(0.05, std::cos(0.5 * (lat_min + lat_max) * kDeg));
  if (lon_min >= 180.0) lon_min -= 360.0, lon_max -= 360.0;
  vol.grid.lon_deg = {lon_min, dlon, static_cast<int>(std::floor((lon_max - lon_min) / dlon + 1e-9)) + 1};
  vol.grid.lat_deg = {lat_min, dlat, static_cast<int>(std::floor((lat_max - lat_min) / dlat + 1e-9)) + 1};
  vol.report.notes.push_back("resampled bilinearly from the " + std::to_string(S->nx) + " x " + std::to_string(S->ny) +
                             " model grid onto " + std::to_string(vol.grid.lon_deg.count) + " x " +
                             std::to_string(vol.grid.lat_deg.count) + " lon/lat columns; columns outside the domain hold no data");
  // Where each output column falls (the first step's grid), and its wind rotation.
  const NcVar* cosa = f.find("COSALPHA");
  const NcVar* sina = f.find("SINALPHA");
  std::vector<double> cos_alpha, sin_alpha;
  if (cosa && sina) cos_alpha = read_mass2d(*S, "COSALPHA", S->steps.front()), sin_alpha = read_mass2d(*S, "SINALPHA", S->steps.front());
  core::require_within_memory_limit(path, "the resampling of " + std::to_string(vol.grid.lon_deg.count) + " x " +
                                              std::to_string(vol.grid.lat_deg.count) + " columns",
                                    core::checked_product({vol.grid.columns(), sizeof(Sample)}));
  double corner = 0.0;
  S->samples = place_samples(*S, vol.grid, xlat, xlon, cos_alpha, sin_alpha, S->steps.front(), &corner);
  vol.report.notes.push_back("projection checked against XLAT/XLONG: the far corner lies " + fmt(corner) +
                             " m from where the grid puts it");
  std::size_t inside = 0;
  for (const Sample& smp : S->samples) inside += smp.inside ? 1 : 0;
  if (inside == 0 && !S->moving) throw ImportError(path + ": no output column falls inside the WRF domain");
  // Altitude grid from the mass-level heights over the domain: the first step's, or every step's
  // when the nest moves over different terrain.
  {
    double zmin = 1e30, zmax = -1e30;
    std::vector<double> thick;
    const std::vector<int> probe = S->moving ? S->steps : std::vector<int>{S->steps.front()};
    for (int t : probe) {
    const Field3 ph = read3(*S, "PH", t, true), phb = read3(*S, "PHB", t, true);
    for (int j = 0; j < S->ny; ++j) {
      for (int i = 0; i < S->nx; ++i) {
        double prev = NAN;
        for (int k = 0; k < S->nz; ++k) {
          const double phi = 0.5 * (ph.at(i, j, k) + phb.at(i, j, k) + ph.at(i, j, k + 1) + phb.at(i, j, k + 1));
          const double z = phi / kWrfG;
          if (!(z > -1000.0 && z < 1.0e5)) {
            throw ImportError(path + ": variable 'PH' gives a height of " + fmt(z) + " m, expected -1 km to 100 km");
          }
          zmin = std::min(zmin, z), zmax = std::max(zmax, z);
          if (!std::isnan(prev) && t == probe.front()) thick.push_back(z - prev);
          prev = z;
        }
      }
    }
    }
    double dz = options.dz_m;
    if (dz <= 0.0) {
      std::nth_element(thick.begin(), thick.begin() + static_cast<std::ptrdiff_t>(thick.size() / 2), thick.end());
      dz = std::clamp(thick[thick.size() / 2] / 2.0, 50.0, 500.0);
    }
    checked_level_count(path, zmin, zmax, dz, options.dz_m > 0.0 ? "--dz (dz_m)" : "PH/PHB");
    vol.grid.alt_m = altitude_axis(zmin, zmax, dz, options.dz_m <= 0.0);
  }
  check_imported_grid(path, vol.grid);
  const double bytes = static_cast<double>(vol.grid.points()) * core::kFieldCount * sizeof(float);
  if (bytes > options.max_volume_bytes) {
    throw ImportError(path + ": the volume would take " + fmt(bytes / 1e9) + " GB per time step; subset the region or stride, or raise --dz");
  }
  vol.has_field[static_cast<int>(core::Field::ExtinctionLiquid)] = f.find("QCLOUD") != nullptr;
  vol.has_field[static_cast<int>(core::Field::ExtinctionIce)] = f.find("QICE") || f.find("QSNOW");
  vol.has_field[static_cast<int>(core::Field::CloudFraction)] = f.find("CLDFRA") != nullptr;
  vol.has_field[static_cast<int>(core::Field::WindU)] = f.find("U") && f.find("V");
  vol.has_field[static_cast<int>(core::Field::WindV)] = vol.has_field[static_cast<int>(core::Field::WindU)];
  vol.has_field[static_cast<int>(core::Field::WindW)] = f.find("W") != nullptr;
  vol.has_field[static_cast<int>(core::Field::Temperature)] = true;
  vol.has_field[static_cast<int>(core::Field::Pressure)] = true;
  vol.has_ground = true;
  vol.report.notes.push_back("low/mid/high cover by height above the ground ((PH + PHB) / g at the lowest staggered level)");
  if (!f.find("QCLOUD") && !f.find("QICE") && !f.find("QSNOW") && !f.find("CLDFRA")) {
    throw ImportError(path + ": no cloud variable; expected QCLOUD, QICE, QSNOW or CLDFRA");
  }
  if (!f.find("CLDFRA")) vol.report.notes.push_back("no CLDFRA: cloud water is taken as filling its grid box");
  if (f.find("QRAIN") || f.find("QGRAUP")) vol.report.notes.push_back("QRAIN and QGRAUP (precipitation) are not part of the cloud volume");
  if (cosa) vol.report.notes.push_back("winds rotated to earth-relative with COSALPHA/SINALPHA");
  const core::VolumeGrid grid = vol.grid;
  vol.set_loader([S, grid](std::size_t step, core::ImportReport& report, core::TimeStepData& out) {
    load_wrf_step(*S, grid, step, report, out);
  }, options.cache_steps);
  return vol;
}

std::string describe_wrf(const NcFile& f) {
  const WrfProjection proj(f);
  std::string out = "format: WRF output (" + f.global_text("TITLE") + "), " + proj.name() + ", DX " + fmt(proj.dx()) + " m\n";
  for (const char* d : {"west_east", "south_north", "bottom_top", "Time"}) {
    for (const auto& dim : f.dims()) {
      if (dim.name == d) out += std::string("  ") + d + ": " + std::to_string(dim.length) + "\n";
    }
  }
  out += "variables used:";
  for (const char* v : {"PH", "PHB", "P", "PB", "T", "QVAPOR", "QCLOUD", "QICE", "QSNOW", "CLDFRA", "U", "V", "W", "XLAT", "XLONG", "Times"}) {
    out += std::string(" ") + v + (f.find(v) ? "" : " (absent)");
  }
  out += "\n";
  if (const NcVar* tv = f.find("Times")) {
    const auto t = f.read_strings(*tv);
    if (!t.empty()) out += "times: " + std::to_string(t.size()) + ", " + t.front() + " to " + t.back() + "\n";
  }
  return out;
}

}  // namespace cv::importers
