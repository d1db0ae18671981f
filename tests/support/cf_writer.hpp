// A general small CF file for importer tests: any axes, any variables, values from functions of
// the indices, so each test writes exactly the trap it reproduces.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "support/nc_builder.hpp"

namespace cv::test {

struct CfAxis {
  std::string name;
  std::vector<double> values;
  std::vector<std::pair<std::string, std::string>> atts;  // text attributes (units, standard_name, ...)
};

struct CfVar {
  std::string name;
  std::vector<std::string> dims;  // axis names, slowest first
  std::vector<std::pair<std::string, std::string>> atts;
  std::vector<std::pair<std::string, std::vector<double>>> numbers;  // numeric attributes (as int)
  // Value at the index of each of its dims (in dims order).
  std::function<double(const std::vector<int>&)> value;
};

inline void write_cf(const std::string& path, const std::vector<CfAxis>& axes, const std::vector<CfVar>& vars) {
  NcBuilder b(path);
  std::vector<int> dim_ids, var_ids;
  auto axis_of = [&](const std::string& n) {
    for (std::size_t a = 0; a < axes.size(); ++a) {
      if (axes[a].name == n) return a;
    }
    throw std::runtime_error("write_cf: no axis " + n);
  };
  for (const auto& a : axes) dim_ids.push_back(b.dim(a.name, a.values.size()));
  std::vector<int> axis_vars;
  for (std::size_t a = 0; a < axes.size(); ++a) {
    axis_vars.push_back(b.var(axes[a].name, NC_DOUBLE, {dim_ids[a]}));
    for (const auto& [k, v] : axes[a].atts) b.text(axis_vars.back(), k, v);
  }
  for (const auto& v : vars) {
    std::vector<int> d;
    for (const auto& n : v.dims) d.push_back(dim_ids[axis_of(n)]);
    var_ids.push_back(b.var(v.name, NC_DOUBLE, d));
    for (const auto& [k, t] : v.atts) b.text(var_ids.back(), k, t);
    for (const auto& [k, n] : v.numbers) b.number(var_ids.back(), k, NC_INT, n);
  }
  for (std::size_t a = 0; a < axes.size(); ++a) b.put(axis_vars[a], axes[a].values);
  for (std::size_t i = 0; i < vars.size(); ++i) {
    const auto& v = vars[i];
    std::vector<int> ext;
    for (const auto& n : v.dims) ext.push_back(static_cast<int>(axes[axis_of(n)].values.size()));
    std::size_t total = 1;
    for (int e : ext) total *= static_cast<std::size_t>(e);
    std::vector<double> data(total);
    std::vector<int> idx(ext.size(), 0);
    for (std::size_t n = 0; n < total; ++n) {
      std::size_t r = n;
      for (int a = static_cast<int>(ext.size()) - 1; a >= 0; --a) {
        idx[static_cast<std::size_t>(a)] = static_cast<int>(r % static_cast<std::size_t>(ext[static_cast<std::size_t>(a)]));
        r /= static_cast<std::size_t>(ext[static_cast<std::size_t>(a)]);
      }
      data[n] = v.value(idx);
    }
    b.put(var_ids[i], data);
  }
  b.close();
}

// An ERA5-style file on pressure levels with one time step: longitude, latitude, level (Pa,
// positive down), time, then geopotential `z`, temperature `t` and one cloud water variable under
// ECMWF's names, their values functions of the longitude, latitude and level indices (i, j, k).
struct PressureLevelFile {
  std::vector<double> lon, lat, levels_pa;
  std::string time_units = "hours since 2024-06-21 00:00:00";
  std::function<double(int, int, int)> geopotential, temperature, water;
  bool ice = false;  // the water is `ciwc` (ice), else `clwc` (liquid)
};

inline void write_pressure_level_file(const std::string& path, const PressureLevelFile& f) {
  NcBuilder b(path);
  const int nx = static_cast<int>(f.lon.size()), ny = static_cast<int>(f.lat.size()), nz = static_cast<int>(f.levels_pa.size());
  const int dt = b.dim("time", 1), dz = b.dim("level", f.levels_pa.size());
  const int dy = b.dim("latitude", f.lat.size()), dx = b.dim("longitude", f.lon.size());
  const int vlon = b.var("longitude", NC_DOUBLE, {dx});
  b.text(vlon, "units", "degrees_east");
  b.text(vlon, "standard_name", "longitude");
  const int vlat = b.var("latitude", NC_DOUBLE, {dy});
  b.text(vlat, "units", "degrees_north");
  b.text(vlat, "standard_name", "latitude");
  const int vlev = b.var("level", NC_DOUBLE, {dz});
  b.text(vlev, "units", "Pa");
  b.text(vlev, "standard_name", "air_pressure");
  b.text(vlev, "positive", "down");
  const int vtime = b.var("time", NC_INT, {dt});
  b.text(vtime, "units", f.time_units);
  b.text(vtime, "calendar", "gregorian");
  const std::vector<int> dims{dt, dz, dy, dx};
  const int vz = b.var("z", NC_DOUBLE, dims);
  b.text(vz, "units", "m**2 s**-2");
  b.text(vz, "standard_name", "geopotential");
  const int vt = b.var("t", NC_DOUBLE, dims);
  b.text(vt, "units", "K");
  b.text(vt, "standard_name", "air_temperature");
  const int vq = b.var(f.ice ? "ciwc" : "clwc", NC_DOUBLE, dims);
  b.text(vq, "units", "kg kg**-1");
  b.text(vq, "long_name", f.ice ? "specific cloud ice water content" : "specific cloud liquid water content");
  std::vector<double> z, t, q;
  for (int k = 0; k < nz; ++k) {
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        z.push_back(f.geopotential(i, j, k));
        t.push_back(f.temperature(i, j, k));
        q.push_back(f.water(i, j, k));
      }
    }
  }
  b.put(vlon, f.lon);
  b.put(vlat, f.lat);
  b.put(vlev, f.levels_pa);
  b.put(vtime, {0.0});
  b.put(vz, z);
  b.put(vt, t);
  b.put(vq, q);
  b.close();
}

}  // namespace cv::test
