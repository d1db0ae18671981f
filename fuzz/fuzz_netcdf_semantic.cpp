// libFuzzer target: the NetCDF importers (the body of netcdf_target.hpp) on files whose meaning is
// mutated, not their bytes. A custom mutator reads the input with netCDF (netcdf_model.hpp),
// changes one thing a real file could get wrong, and writes it back as a well-formed file:
//   - an attribute's value (NaN, infinities, zero, huge, negative; units, calendars, projection
//     names, garbage and very long text), added where it was not, or removed;
//   - a variable's values (special values in some or all, a constant, reversed, two swapped, scaled),
//     its type, its name (to another role's: QCLOUD, clwc, XLAT, time, ...), or the variable removed;
//   - a dimension shortened (down to 0) with its variables cropped, or renamed.
// One call in four is left to libFuzzer's own byte mutations, so both kinds mix. The byte-level
// target is fuzz_netcdf; the fixed semantic cases are the HostileImport tests.
#include <random>

#include "nc_file.hpp"
#include "netcdf_model.hpp"
#include "netcdf_target.hpp"

extern "C" std::size_t LLVMFuzzerMutate(std::uint8_t* data, std::size_t size, std::size_t max_size);

namespace {
using cv::fuzz::NcAtt;
using cv::fuzz::NcModel;
using cv::fuzz::NcVar;

const double kSpecial[] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                           -std::numeric_limits<double>::infinity(), 0.0, -0.0, -1.0, 1.0, 1e-300, 1e300, 3.4e38,
                           -3.4e38, 2147483648.0, 65535.0, -32768.0, 1e-12, 9.999e36};

const char* const kText[] = {"", "K", "Pa", "hPa", "m", "km", "m2 s-2", "m**2 s**-2", "kg kg-1", "kg kg**-1", "g/kg",
                             "g kg-1", "1", "%", "0-1", "(0 - 1)", "degrees_east", "degrees_north", "degrees", "degree_east",
                             "hours since 1900-01-01 00:00:00.0", "days since 2024-13-45", "seconds since garbage",
                             "months since 2000-01-01", "minutes since 2005-08-28 00:00:00 UTC", "360_day", "noleap",
                             "julian", "none", "up", "down", "X", "Y", "Z", "T", "lambert_conformal_conic",
                             "latitude_longitude", "air_pressure", "geopotential", "geopotential_height",
                             "cloud_area_fraction_in_atmosphere_layer", "mass_fraction_of_cloud_liquid_water_in_air",
                             "mass_fraction_of_cloud_ice_in_air", "eastward_wind", "northward_wind", "altitude",
                             "2005-13-41_25:61:61", "2024-01-15_00:00:00", "\xff\xfe\x80 not utf-8"};

const char* const kVarNames[] = {"time", "Time", "lat", "latitude", "lon", "longitude", "level", "plev", "isobaric",
                                 "z", "gh", "cc", "clwc", "ciwc", "crwc", "cswc", "QCLOUD", "QICE", "QRAIN", "QSNOW",
                                 "CLDFRA", "XLAT", "XLONG", "PH", "PHB", "P", "PB", "T", "U", "V", "W", "Times",
                                 "ice_water_mixing_ratio", "cloud_mixing_ratio_isobaric", "t", "u", "v", "HGT"};

const char* const kAttNames[] = {"_FillValue", "missing_value", "scale_factor", "add_offset", "valid_min", "valid_max",
                                 "valid_range", "units", "standard_name", "positive", "axis", "calendar", "MAP_PROJ",
                                 "TRUELAT1", "TRUELAT2", "STAND_LON", "CEN_LAT", "CEN_LON", "DX", "DY", "coordinates",
                                 "GRIB_paramId", "GRIB_shortName", "long_name"};

class Mutator {
 public:
  explicit Mutator(unsigned seed) : rng_(seed) {}

  // One semantic change; false when the model offers nothing to change that way.
  bool mutate(NcModel& m) {
    switch (pick(10)) {
      case 0: return attribute_value(m);
      case 1: return attribute_added(m);
      case 2: return attribute_removed(m);
      case 3:
      case 4: return values(m);
      case 5: return renamed_variable(m);
      case 6: return retyped(m);
      case 7: return removed_variable(m);
      case 8: return shortened_dimension(m);
      default: return renamed_dimension(m);
    }
  }

 private:
  std::mt19937 rng_;

  std::size_t pick(std::size_t n) { return n == 0 ? 0 : std::uniform_int_distribution<std::size_t>(0, n - 1)(rng_); }
  template <class T, std::size_t N>
  const T& one_of(const T (&a)[N]) { return a[pick(N)]; }
  double special() {
    if (pick(4) == 0) return std::uniform_real_distribution<double>(-1e6, 1e6)(rng_);
    return one_of(kSpecial);
  }
  std::string text() {
    if (pick(10) == 0) return std::string(20000, 'a');
    if (pick(10) == 0) return std::string("units\0hidden", 12);
    return one_of(kText);
  }
  // The attributes of a random place: the file's (NC_GLOBAL) or a variable's.
  std::vector<NcAtt>& atts_of(NcModel& m) {
    if (m.vars.empty() || pick(4) == 0) return m.atts;
    return m.vars[pick(m.vars.size())].atts;
  }
  NcVar* numeric_var(NcModel& m) {
    std::vector<NcVar*> v;
    for (auto& x : m.vars) {
      if (x.type != NC_CHAR && !x.values.empty()) v.push_back(&x);
    }
    return v.empty() ? nullptr : v[pick(v.size())];
  }

  bool attribute_value(NcModel& m) {
    auto& atts = atts_of(m);
    if (atts.empty()) return false;
    NcAtt& a = atts[pick(atts.size())];
    if (a.type == NC_CHAR) {
      a.text = text();
    } else if (a.values.empty()) {
      a.values.push_back(special());
    } else {
      a.values[pick(a.values.size())] = special();
      if (pick(4) == 0) a.values.resize(pick(4));  // another count, none included
    }
    return true;
  }
  bool attribute_added(NcModel& m) {
    auto& atts = atts_of(m);
    NcAtt a;
    a.name = one_of(kAttNames);
    atts.erase(std::remove_if(atts.begin(), atts.end(), [&](const NcAtt& x) { return x.name == a.name; }), atts.end());
    const nc_type types[] = {NC_CHAR, NC_DOUBLE, NC_FLOAT, NC_INT, NC_SHORT, NC_BYTE};
    a.type = one_of(types);
    if (a.type == NC_CHAR) a.text = text();
    else a.values.assign(1 + pick(3), special());
    atts.push_back(std::move(a));
    return true;
  }
  bool attribute_removed(NcModel& m) {
    auto& atts = atts_of(m);
    if (atts.empty()) return false;
    atts.erase(atts.begin() + static_cast<std::ptrdiff_t>(pick(atts.size())));
    return true;
  }
  bool values(NcModel& m) {
    NcVar* v = numeric_var(m);
    if (!v) return false;
    auto& x = v->values;
    switch (pick(6)) {
      case 0:  // a few special values
        for (std::size_t k = 0, n = 1 + pick(4); k < n; ++k) x[pick(x.size())] = special();
        break;
      case 1: std::fill(x.begin(), x.end(), special()); break;  // all one value
      case 2: std::reverse(x.begin(), x.end()); break;
      case 3: std::swap(x[pick(x.size())], x[pick(x.size())]); break;  // a coordinate out of order
      case 4: {
        const double f[] = {1e3, 1e-3, -1.0, 100.0, 0.01, 9.81, 1.0 / 9.81};
        const double s = one_of(f);
        for (double& y : x) y *= s;
        break;
      }
      default:  // a neighbour repeated: a duplicate coordinate or time
        if (x.size() > 1) {
          const std::size_t i = pick(x.size() - 1);
          x[i + 1] = x[i];
        }
    }
    return true;
  }
  bool renamed_variable(NcModel& m) {
    if (m.vars.empty()) return false;
    const std::string name = one_of(kVarNames);
    for (const auto& v : m.vars) {
      if (v.name == name) return false;
    }
    m.vars[pick(m.vars.size())].name = name;
    return true;
  }
  bool retyped(NcModel& m) {
    NcVar* v = numeric_var(m);
    if (!v) return false;
    const nc_type types[] = {NC_BYTE, NC_UBYTE, NC_SHORT, NC_USHORT, NC_INT, NC_UINT, NC_INT64, NC_FLOAT, NC_DOUBLE};
    v->type = one_of(types);
    return true;
  }
  bool removed_variable(NcModel& m) {
    if (m.vars.empty()) return false;
    m.vars.erase(m.vars.begin() + static_cast<std::ptrdiff_t>(pick(m.vars.size())));
    return true;
  }
  bool renamed_dimension(NcModel& m) {
    if (m.dims.empty()) return false;
    const std::string name = one_of(kVarNames);
    for (const auto& d : m.dims) {
      if (d.first == name) return false;
    }
    m.dims[pick(m.dims.size())].first = name;
    return true;
  }
  // A dimension cut to a shorter length (0 included for the unlimited one), each variable on it
  // keeping its first entries along it.
  bool shortened_dimension(NcModel& m) {
    if (m.dims.empty()) return false;
    const std::size_t d = pick(m.dims.size());
    const std::size_t old_len = m.dims[d].second;
    if (old_len == 0) return false;
    const std::size_t min_len = static_cast<int>(d) == m.unlimited ? 0 : 1;
    if (old_len <= min_len) return false;
    const std::size_t new_len = min_len + pick(old_len - min_len);
    for (auto& v : m.vars) {
      const auto at = std::find(v.dims.begin(), v.dims.end(), static_cast<int>(d));
      if (at == v.dims.end()) continue;
      // Row-major: the entries before the dimension (outer), its own, and after it (inner).
      std::size_t outer = 1, inner = 1;
      for (auto it = v.dims.begin(); it != at; ++it) outer *= m.dims[static_cast<std::size_t>(*it)].second;
      for (auto it = at + 1; it != v.dims.end(); ++it) inner *= m.dims[static_cast<std::size_t>(*it)].second;
      auto crop = [&](auto& data) {
        std::remove_reference_t<decltype(data)> out;
        for (std::size_t o = 0; o < outer; ++o) {
          const auto first = data.begin() + static_cast<std::ptrdiff_t>(o * old_len * inner);
          out.insert(out.end(), first, first + static_cast<std::ptrdiff_t>(new_len * inner));
        }
        data = std::move(out);
      };
      if (v.type == NC_CHAR) crop(v.text);
      else crop(v.values);
    }
    m.dims[d].second = new_len;
    return true;
  }
};

}  // namespace

// The mutator opens its input with netCDF too, so it is held to the importers' header check first
// (an input libFuzzer's byte mutations broke would crash netCDF here, not in the code under test).
static bool header_is_sound(const std::uint8_t* data, std::size_t size) {
  const cv::fuzz::MemFile file(data, size, ".nc");
  if (file.path().empty()) return false;
  try {
    cv::importers::check_classic_header(file.path(), size);
    return true;
  } catch (const cv::core::InputError&) {
    return false;
  }
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) { return cv::fuzz::run_netcdf_input(data, size); }

extern "C" std::size_t LLVMFuzzerCustomMutator(std::uint8_t* data, std::size_t size, std::size_t max_size, unsigned int seed) {
  Mutator mut(seed);
  if (seed % 4 != 0 && cv::fuzz::is_classic_netcdf(data, size) && header_is_sound(data, size)) {
    if (auto m = cv::fuzz::read_model(data, size)) {
      bool changed = false;
      for (int tries = 0; tries < 8 && !changed; ++tries) changed = mut.mutate(*m);
      if (changed) {
        const std::vector<std::uint8_t> out = cv::fuzz::write_model(*m, max_size);
        if (!out.empty()) {
          std::memcpy(data, out.data(), out.size());
          return out.size();
        }
      }
    }
  }
  return LLVMFuzzerMutate(data, size, max_size);
}
