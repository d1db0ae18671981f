// A netCDF classic file as plain data (dimensions, attributes, variables with their values), read
// from and written to memory with netCDF's own in-memory API, so that the semantic fuzzer can
// change what a file means (a unit, a coordinate's order, a fill value, a variable's type or name)
// and still hand the importers a well-formed file. Only the classic data model (CDF-1, -2, -5):
// NC_STRING and user types are not kept.
#pragma once

#include <netcdf.h>
#include <netcdf_mem.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace cv::fuzz {

struct NcAtt {
  std::string name;
  nc_type type = NC_CHAR;
  std::string text;            // NC_CHAR
  std::vector<double> values;  // every other type
};

struct NcVar {
  std::string name;
  nc_type type = NC_FLOAT;
  std::vector<int> dims;
  std::vector<NcAtt> atts;
  std::vector<double> values;  // numeric types, in the file's order
  std::string text;            // NC_CHAR
};

struct NcModel {
  int format = NC_FORMAT_64BIT_DATA;
  std::vector<std::pair<std::string, std::size_t>> dims;
  int unlimited = -1;
  std::vector<NcAtt> atts;
  std::vector<NcVar> vars;

  std::size_t count(const NcVar& v) const {
    std::size_t n = 1;
    for (int d : v.dims) n *= dims[static_cast<std::size_t>(d)].second;
    return n;
  }
};

namespace detail {

inline bool read_atts(int nc, int var, int n, std::vector<NcAtt>& out) {
  for (int a = 0; a < n; ++a) {
    char name[NC_MAX_NAME + 1] = {};
    nc_type t;
    std::size_t len = 0;
    if (nc_inq_attname(nc, var, a, name) != NC_NOERR || nc_inq_att(nc, var, name, &t, &len) != NC_NOERR) return false;
    if (len > (1u << 16)) return false;
    NcAtt at;
    at.name = name;
    at.type = t;
    if (t == NC_CHAR) {
      at.text.resize(len);
      if (len && nc_get_att_text(nc, var, name, at.text.data()) != NC_NOERR) return false;
    } else if (t >= NC_BYTE && t <= NC_UINT64) {
      at.values.resize(len);
      if (len && nc_get_att_double(nc, var, name, at.values.data()) != NC_NOERR && len) at.values.assign(len, 0.0);
    } else {
      continue;
    }
    out.push_back(std::move(at));
  }
  return true;
}

inline double type_low(nc_type t) {
  switch (t) {
    case NC_BYTE: return -128;
    case NC_UBYTE: return 0;
    case NC_SHORT: return -32768;
    case NC_USHORT: return 0;
    case NC_INT: return -2147483648.0;
    case NC_UINT: return 0;
    case NC_INT64: return -9.2e18;
    case NC_UINT64: return 0;
    default: return -std::numeric_limits<double>::infinity();
  }
}
inline double type_high(nc_type t) {
  switch (t) {
    case NC_BYTE: return 127;
    case NC_UBYTE: return 255;
    case NC_SHORT: return 32767;
    case NC_USHORT: return 65535;
    case NC_INT: return 2147483647.0;
    case NC_UINT: return 4294967295.0;
    case NC_INT64: return 9.2e18;
    case NC_UINT64: return 1.8e19;
    case NC_FLOAT: return std::numeric_limits<float>::max();
    default: return std::numeric_limits<double>::infinity();
  }
}
// A value the type can hold: integers rounded and clamped (NaN to 0), floats clamped to +-max
// unless infinite or NaN (which a float holds).
inline double representable(nc_type t, double v) {
  if (t == NC_FLOAT || t == NC_DOUBLE) {
    if (std::isnan(v) || std::isinf(v)) return v;
    return std::clamp(v, -type_high(t), type_high(t));
  }
  if (std::isnan(v)) return 0.0;
  return std::clamp(std::round(v), type_low(t), type_high(t));
}

}  // namespace detail

// Reads a classic-format file from memory; nullopt when netCDF cannot, or the file is larger than
// max_values values in all (the fuzzer's inputs are small crops).
inline std::optional<NcModel> read_model(const std::uint8_t* data, std::size_t size, std::size_t max_values = 1u << 20) {
  int nc = -1;
  std::vector<std::uint8_t> copy(data, data + size);  // nc_open_mem may keep a pointer to it
  if (nc_open_mem("fuzz-input.nc", NC_NOWRITE, size, copy.data(), &nc) != NC_NOERR) return std::nullopt;
  NcModel m;
  bool ok = true;
  int ndims = 0, nvars = 0, natts = 0;
  ok = nc_inq(nc, &ndims, &nvars, &natts, &m.unlimited) == NC_NOERR && nc_inq_format(nc, &m.format) == NC_NOERR;
  ok = ok && m.format != NC_FORMAT_NETCDF4 && m.format != NC_FORMAT_NETCDF4_CLASSIC;
  for (int d = 0; ok && d < ndims; ++d) {
    char name[NC_MAX_NAME + 1] = {};
    std::size_t len = 0;
    ok = nc_inq_dim(nc, d, name, &len) == NC_NOERR;
    m.dims.emplace_back(name, len);
  }
  ok = ok && detail::read_atts(nc, NC_GLOBAL, natts, m.atts);
  std::size_t total = 0;
  for (int v = 0; ok && v < nvars; ++v) {
    char name[NC_MAX_NAME + 1] = {};
    int nd = 0, na = 0, dims[NC_MAX_VAR_DIMS];
    NcVar var;
    ok = nc_inq_var(nc, v, name, &var.type, &nd, dims, &na) == NC_NOERR;
    if (!ok || var.type < NC_BYTE || var.type > NC_UINT64) continue;
    var.name = name;
    var.dims.assign(dims, dims + nd);
    ok = detail::read_atts(nc, v, na, var.atts);
    const std::size_t n = m.count(var);
    total += n;
    if (!ok || total > max_values) {
      ok = false;
      break;
    }
    if (var.type == NC_CHAR) {
      var.text.resize(n);
      if (n) ok = nc_get_var_text(nc, v, var.text.data()) == NC_NOERR;
    } else {
      var.values.resize(n);
      if (n && nc_get_var_double(nc, v, var.values.data()) != NC_NOERR) var.values.assign(n, 0.0);  // NC_ERANGE and the like
    }
    m.vars.push_back(std::move(var));
  }
  nc_close(nc);
  if (!ok) return std::nullopt;
  return m;
}

// Writes the model as a classic-format file in memory; empty when netCDF refuses it (a name it
// will not take, two variables of one name) or it is larger than max_size.
inline std::vector<std::uint8_t> write_model(const NcModel& m, std::size_t max_size) {
  int nc = -1;
  const int mode = m.format == NC_FORMAT_64BIT_DATA ? NC_64BIT_DATA : m.format == NC_FORMAT_64BIT_OFFSET ? NC_64BIT_OFFSET : 0;
  if (nc_create_mem("fuzz-output.nc", mode, 4096, &nc) != NC_NOERR) return {};
  bool ok = true;
  std::vector<int> dim_ids;
  for (std::size_t d = 0; ok && d < m.dims.size(); ++d) {
    int id;
    const std::size_t len = static_cast<int>(d) == m.unlimited ? NC_UNLIMITED : m.dims[d].second;
    ok = nc_def_dim(nc, m.dims[d].first.c_str(), len, &id) == NC_NOERR;
    dim_ids.push_back(id);
  }
  auto put_atts = [&](int var, const std::vector<NcAtt>& atts) {
    for (const auto& a : atts) {
      if (!ok) return;
      if (a.type == NC_CHAR) {
        ok = nc_put_att_text(nc, var, a.name.c_str(), a.text.size(), a.text.data()) == NC_NOERR;
      } else {
        std::vector<double> v(a.values.size());
        std::transform(a.values.begin(), a.values.end(), v.begin(), [&](double x) { return detail::representable(a.type, x); });
        ok = nc_put_att_double(nc, var, a.name.c_str(), a.type, v.size(), v.data()) == NC_NOERR;
      }
    }
  };
  put_atts(NC_GLOBAL, m.atts);
  std::vector<int> var_ids;
  for (const auto& v : m.vars) {
    if (!ok) break;
    int id;
    std::vector<int> dims;
    for (int d : v.dims) dims.push_back(dim_ids[static_cast<std::size_t>(d)]);
    ok = nc_def_var(nc, v.name.c_str(), v.type, static_cast<int>(dims.size()), dims.data(), &id) == NC_NOERR;
    if (ok) put_atts(id, v.atts);
    var_ids.push_back(id);
  }
  ok = ok && nc_enddef(nc) == NC_NOERR;
  for (std::size_t i = 0; ok && i < m.vars.size(); ++i) {
    const NcVar& v = m.vars[i];
    std::vector<std::size_t> start(v.dims.size(), 0), count;
    for (int d : v.dims) count.push_back(m.dims[static_cast<std::size_t>(d)].second);
    if (m.count(v) == 0) continue;
    if (v.type == NC_CHAR) {
      if (v.text.size() != m.count(v)) ok = false;
      else ok = nc_put_vara_text(nc, var_ids[i], start.data(), count.data(), v.text.data()) == NC_NOERR;
    } else {
      if (v.values.size() != m.count(v)) {
        ok = false;
        break;
      }
      std::vector<double> vals(v.values.size());
      std::transform(v.values.begin(), v.values.end(), vals.begin(), [&](double x) { return detail::representable(v.type, x); });
      ok = nc_put_vara_double(nc, var_ids[i], start.data(), count.data(), vals.data()) == NC_NOERR;
    }
  }
  NC_memio io{};
  const bool closed = nc_close_memio(nc, &io) == NC_NOERR;
  std::vector<std::uint8_t> out;
  if (ok && closed && io.memory && io.size <= max_size) {
    const auto* p = static_cast<const std::uint8_t*>(io.memory);
    out.assign(p, p + io.size);
  }
  std::free(io.memory);
  return out;
}

}  // namespace cv::fuzz
