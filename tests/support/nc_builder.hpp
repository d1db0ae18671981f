// Writes small NetCDF files for importer tests, with every trap real files contain available as an
// option, and the analytic values the tests expect.
#pragma once

#include <netcdf.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace cv::test {

inline void nc_check(int status, const std::string& what) {
  if (status != NC_NOERR) throw std::runtime_error(what + ": " + nc_strerror(status));
}

class NcBuilder {
 public:
  explicit NcBuilder(const std::string& path, int mode = NC_CLOBBER | NC_NETCDF4) : path_(path) {
    nc_check(nc_create(path.c_str(), mode, &id_), "create " + path);
  }
  ~NcBuilder() {
    if (id_ >= 0) nc_close(id_);
  }
  int dim(const std::string& name, std::size_t len) {
    int d;
    nc_check(nc_def_dim(id_, name.c_str(), len, &d), "dim " + name);
    return d;
  }
  int var(const std::string& name, nc_type type, const std::vector<int>& dims) {
    int v;
    nc_check(nc_def_var(id_, name.c_str(), type, static_cast<int>(dims.size()), dims.data(), &v), "var " + name);
    return v;
  }
  void text(int var, const std::string& name, const std::string& value) {
    nc_check(nc_put_att_text(id_, var, name.c_str(), value.size(), value.c_str()), "att " + name);
  }
  void number(int var, const std::string& name, nc_type type, std::vector<double> values) {
    nc_check(nc_put_att_double(id_, var, name.c_str(), type, values.size(), values.data()), "att " + name);
  }
  void put(int var, const std::vector<double>& values) {
    nc_check(nc_enddef_if_needed(), "enddef");
    nc_check(nc_put_var_double(id_, var, values.data()), "put");
  }
  void put_short(int var, const std::vector<short>& values) {
    nc_check(nc_enddef_if_needed(), "enddef");
    nc_check(nc_put_var_short(id_, var, values.data()), "put");
  }
  void close() {
    nc_check(nc_close(id_), "close");
    id_ = -1;
  }

 private:
  int nc_enddef_if_needed() {
    const int s = nc_enddef(id_);
    return s == NC_ENOTINDEFINE ? NC_NOERR : s;
  }
  std::string path_;
  int id_ = -1;
};

// A small ERA5-like file on pressure levels. The fields are analytic so tests know every value:
//   geopotential: g0 * ISA height of the level (so heights are the standard atmosphere's, exactly)
//   temperature:  260 K everywhere; specific humidity 1e-3 kg/kg
//   cloud fraction: 0.5 on the 700 hPa level, 0 elsewhere (and 0.8 at the column lon_index 0 at 700)
//   liquid water (grid-box mean): 2e-4 kg/kg where the cloud fraction is non-zero
//   winds: u = 10 + lat/10, v = lon/100 (degrees as stored in the -180..180 convention)
struct SynthOptions {
  std::vector<double> lons{170, 175, 180, 185, 190, 195};  // east-going, any convention
  std::vector<double> lats{40, 45, 50, 55};                // as stored
  std::vector<double> levels_hpa{1000, 850, 700, 500, 300};  // as stored
  std::string level_units = "hPa";
  double level_scale = 1.0;      // stored level = hPa * scale (100 for Pa)
  bool lon_first_order = false;  // (longitude, latitude, level, time) instead of (time, level, lat, lon)
  int times = 2;
  bool time_variable = true;
  std::string time_units = "hours since 2024-01-15 00:00:00";
  std::string calendar = "gregorian";
  bool packed = true;
  bool negative_scale = false;
  bool fill_differs_from_missing = false;  // _FillValue -32767, missing_value -32766, both used
  std::string cc_name = "cc", clwc_name = "clwc";
  std::string cc_standard_name;  // set to find the variable by standard_name
  double cc_override = -1.0;     // when >= 0, every cc value (absurd-value tests)
  double z_override = NAN;       // when set, every geopotential value
  int z_bad_row = -1;            // when >= 0, the geopotential at this stored row, level 1 and
  double z_bad_value = NAN;      // column 2 (every step) is z_bad_value instead
  double clwc_noise = 0.0;       // subtract this from the clear points (tiny negatives after unpacking)
  bool with_cloud = true;
  nc_type coord_type = NC_FLOAT;  // of longitude and latitude
};

inline double isa_height_m(double p_pa) {
  if (p_pa >= 22632.06) return 288.15 / 0.0065 * (1.0 - std::pow(p_pa / 101325.0, 287.05 * 0.0065 / 9.80665));
  return 11000.0 + 287.05 * 216.65 / 9.80665 * std::log(22632.06 / p_pa);
}

inline double synth_lon180(double lon) { return std::fmod(std::fmod(lon + 180.0, 360.0) + 360.0, 360.0) - 180.0; }

inline void write_synth(const std::string& path, const SynthOptions& o) {
  NcBuilder b(path);
  const int nx = static_cast<int>(o.lons.size()), ny = static_cast<int>(o.lats.size()),
            nz = static_cast<int>(o.levels_hpa.size()), nt = o.times;
  const int dt = b.dim("time", static_cast<std::size_t>(nt)), dz = b.dim("level", static_cast<std::size_t>(nz));
  const int dy = b.dim("latitude", static_cast<std::size_t>(ny)), dx = b.dim("longitude", static_cast<std::size_t>(nx));
  const int vlon = b.var("longitude", o.coord_type, {dx});
  b.text(vlon, "units", "degrees_east");
  const int vlat = b.var("latitude", o.coord_type, {dy});
  b.text(vlat, "units", "degrees_north");
  const int vlev = b.var("level", NC_INT, {dz});
  b.text(vlev, "units", o.level_units);
  int vtime = -1;
  if (o.time_variable) {
    vtime = b.var("time", NC_INT, {dt});
    b.text(vtime, "units", o.time_units);
    b.text(vtime, "calendar", o.calendar);
  }
  const std::vector<int> dims = o.lon_first_order ? std::vector<int>{dx, dy, dz, dt} : std::vector<int>{dt, dz, dy, dx};
  struct Field {
    std::string name, units, standard_name;
    int id;
    std::vector<double> v;
  };
  std::vector<Field> fields = {{"z", "m**2 s**-2", "geopotential", 0, {}}, {"t", "K", "air_temperature", 0, {}},
                               {"q", "kg kg**-1", "specific_humidity", 0, {}}, {"u", "m s**-1", "eastward_wind", 0, {}},
                               {"v", "m s**-1", "northward_wind", 0, {}}};
  if (o.with_cloud) {
    fields.push_back({o.cc_name, "(0 - 1)", o.cc_standard_name, 0, {}});
    fields.push_back({o.clwc_name, "kg kg**-1", "", 0, {}});
  }
  for (auto& f : fields) {
    f.id = b.var(f.name, o.packed ? NC_SHORT : NC_FLOAT, dims);
    b.text(f.id, "units", f.units);
    if (!f.standard_name.empty()) b.text(f.id, "standard_name", f.standard_name);
  }
  auto at = [&](int t, int k, int j, int i) {
    return o.lon_first_order ? ((static_cast<std::size_t>(i) * ny + j) * nz + k) * nt + t
                             : ((static_cast<std::size_t>(t) * nz + k) * ny + j) * nx + i;
  };
  const std::size_t n = static_cast<std::size_t>(nx) * ny * nz * nt;
  for (auto& f : fields) f.v.assign(n, 0.0);
  for (int t = 0; t < nt; ++t)
    for (int k = 0; k < nz; ++k)
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          const std::size_t p = at(t, k, j, i);
          const double hpa = o.levels_hpa[static_cast<std::size_t>(k)];
          fields[0].v[p] = std::isnan(o.z_override) ? 9.80665 * isa_height_m(hpa * 100.0) : o.z_override;
          if (j == o.z_bad_row && k == 1 && i == 2) fields[0].v[p] = o.z_bad_value;
          fields[1].v[p] = 260.0;
          fields[2].v[p] = 1e-3;
          fields[3].v[p] = 10.0 + o.lats[static_cast<std::size_t>(j)] / 10.0;
          fields[4].v[p] = synth_lon180(o.lons[static_cast<std::size_t>(i)]) / 100.0;
          if (o.with_cloud) {
            const bool cloud = hpa == 700.0;
            double cc = cloud ? (synth_lon180(o.lons[static_cast<std::size_t>(i)]) == 170.0 ? 0.8 : 0.5) : 0.0;
            if (o.cc_override >= 0) cc = o.cc_override;
            fields[5].v[p] = cc;
            fields[6].v[p] = cloud ? 2e-4 : -o.clwc_noise;
          }
        }
  // Pack each field into int16 with the ERA5 scheme (optionally a negative scale).
  std::vector<std::vector<short>> packed(fields.size());
  for (std::size_t fi = 0; fi < fields.size(); ++fi) {
    auto& f = fields[fi];
    if (!o.packed) continue;
    double mn = f.v[0], mx = f.v[0];
    for (double x : f.v) mn = std::min(mn, x), mx = std::max(mx, x);
    if (mx == mn) mx = mn + 1.0;
    // Extremes map to +-32766, clear of the fill value -32767.
    double scale = (mx - mn) / 65532.0, offset = (mx + mn) / 2.0;
    if (o.negative_scale) scale = -scale;
    b.number(f.id, "scale_factor", NC_DOUBLE, {scale});
    b.number(f.id, "add_offset", NC_DOUBLE, {offset});
    b.number(f.id, "_FillValue", NC_SHORT, {-32767});
    b.number(f.id, "missing_value", NC_SHORT, {o.fill_differs_from_missing ? 32767.0 : -32767.0});
    for (double x : f.v) packed[fi].push_back(static_cast<short>(std::lround((x - offset) / scale)));
  }
  if (o.packed && o.fill_differs_from_missing && o.with_cloud) {
    packed[5][at(0, 0, 0, 1)] = -32767;  // fill value
    packed[5][at(0, 0, 0, 2)] = 32767;   // missing value
  }
  std::vector<double> lev;
  for (double h : o.levels_hpa) lev.push_back(h * o.level_scale);
  b.put(vlon, o.lons);
  b.put(vlat, o.lats);
  b.put(vlev, lev);
  if (vtime >= 0) {
    std::vector<double> tv;
    for (int t = 0; t < nt; ++t) tv.push_back(3.0 * t);
    b.put(vtime, tv);
  }
  for (std::size_t fi = 0; fi < fields.size(); ++fi) {
    if (o.packed) b.put_short(fields[fi].id, packed[fi]);
    else b.put(fields[fi].id, fields[fi].v);
  }
  b.close();
}

// A fresh temporary folder per test.
inline std::filesystem::path temp_dir(const std::string& name) {
  const auto d = std::filesystem::temp_directory_path() / ("cv_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

}  // namespace cv::test
