// CF layout detection: axes and role variables.
#include "cf_layout.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <optional>
#include <regex>

namespace cv::importers {
namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

bool in(const std::string& s, std::initializer_list<const char*> list) {
  for (const char* x : list) {
    if (s == x) return true;
  }
  return false;
}

// Multiplier from a pressure unit to Pa, or 0 when the unit is not a pressure.
double pressure_scale(const std::string& units) {
  const std::string u = lower(units);
  if (in(u, {"pa", "pascal", "pascals"})) return 1.0;
  if (in(u, {"hpa", "mb", "mbar", "millibar", "millibars", "hectopascal", "hectopascals"})) return 100.0;
  if (in(u, {"kpa"})) return 1000.0;
  return 0.0;
}

enum class Kind { None, Lon, Lat, Vertical, Time };

// A units string in one spelling: lower case, spaces as underscores ("degrees north" is UDUNITS'
// "degrees_north" too).
std::string units_key(const std::string& units) {
  std::string u = lower(units);
  while (!u.empty() && u.back() == ' ') u.pop_back();
  while (!u.empty() && u.front() == ' ') u.erase(u.begin());
  std::replace(u.begin(), u.end(), ' ', '_');
  return u;
}

Kind classify(const NcVar& v, std::string& how, const std::vector<double>* values) {
  const std::string units = units_key(v.text("units"));
  const std::string sn = lower(v.text("standard_name"));
  const std::string axis = lower(v.text("axis"));
  const std::string name = lower(v.name);
  if (sn == "longitude" || in(units, {"degrees_east", "degree_east", "degree_e", "degrees_e", "degreee", "degreese", "deg_e", "degrees_e"}) ||
      (axis == "x" && units.find("degree") != std::string::npos)) {
    how = "by attributes (units '" + v.text("units") + "', standard_name '" + v.text("standard_name") + "')";
    return Kind::Lon;
  }
  if (sn == "latitude" || in(units, {"degrees_north", "degree_north", "degree_n", "degrees_n", "degreen", "degreesn", "deg_n"}) ||
      (axis == "y" && units.find("degree") != std::string::npos)) {
    how = "by attributes (units '" + v.text("units") + "')";
    return Kind::Lat;
  }
  if (sn == "time" || axis == "t" || lower(v.text("units")).find(" since ") != std::string::npos) {
    how = "by attributes (units '" + v.text("units") + "')";
    return Kind::Time;
  }
  const std::string long_name = lower(v.text("long_name"));
  if (in(sn, {"air_pressure", "height", "altitude", "model_level_number", "atmosphere_hybrid_sigma_pressure_coordinate",
              "hybrid_sigma_pressure"}) ||
      axis == "z" || !v.text("positive").empty() || pressure_scale(units) > 0 ||
      long_name == "model_level_number" || long_name.rfind("hybrid level", 0) == 0) {
    how = "by attributes (units '" + v.text("units") + "', positive '" + v.text("positive") + "')";
    return Kind::Vertical;
  }
  // Name alone is not enough; a conventional name whose values fit the axis is accepted, noted.
  if (values && !values->empty()) {
    const auto [mn, mx] = std::minmax_element(values->begin(), values->end());
    const std::string why = v.att("units") ? "has units '" + v.text("units") + "', not a CF longitude or latitude unit"
                                           : "has no units attribute";
    if (in(name, {"lon", "long", "longitude"}) && *mn >= -360.0 && *mx <= 720.0) {
      how = "by its name and values (" + v.name + " " + why + "; values within -360..720)";
      return Kind::Lon;
    }
    if (in(name, {"lat", "latitude"}) && *mn >= -90.0 && *mx <= 90.0) {
      how = "by its name and values (" + v.name + " " + why + "; values within -90..90)";
      return Kind::Lat;
    }
  }
  return Kind::None;
}

// How a role is recognised. standard_name first, then GRIB parameter attributes (GRIB2
// discipline-category-number as netCDF-Java, NCL and cfgrib write them, or the NCEP/ECMWF short
// name), then the variable's name (lower case, without a netCDF-Java "_isobaric..." or an NCL
// "_P0_L100_GLL0" suffix). A variable whose units do not fit the role is never taken.
struct Grib2 {
  int discipline, category, number;
};
struct RoleSpec {
  Role role;
  std::initializer_list<const char*> standard_names;
  std::initializer_list<Grib2> grib;
  std::initializer_list<const char*> short_names;  // GRIB shortName / NCEP abbreviation, lower case
  std::initializer_list<const char*> names;        // lower case
};

const RoleSpec kRoles[] = {
    {Role::CloudFraction, {"cloud_area_fraction_in_atmosphere_layer", "fraction_of_cloud_cover"}, {{0, 6, 32}, {0, 6, 22}, {0, 6, 1}},
     {"cc", "tcc", "tcdc", "cdcc", "fraccc"}, {"cc", "fraction_of_cloud_cover", "cloud_fraction", "total_cloud_cover", "cloud_cover", "cldfra"}},
    {Role::Liquid, {"mass_fraction_of_cloud_liquid_water_in_air", "specific_cloud_liquid_water_content", "cloud_liquid_water_mixing_ratio"},
     {{0, 1, 83}, {0, 1, 22}}, {"clwc", "clwmr"},
     {"clwc", "specific_cloud_liquid_water_content", "cloud_mixing_ratio", "cloud_water_mixing_ratio", "cloud_liquid_water_mixing_ratio", "clwmr"}},
    {Role::Ice, {"mass_fraction_of_cloud_ice_in_air", "specific_cloud_ice_water_content", "cloud_ice_mixing_ratio"},
     {{0, 1, 84}, {0, 1, 23}, {0, 1, 82}}, {"ciwc", "icmr", "cimixr"},
     {"ciwc", "specific_cloud_ice_water_content", "ice_water_mixing_ratio", "cloud_ice_mixing_ratio", "icmr"}},
    {Role::Geopotential, {"geopotential"}, {{0, 3, 4}}, {"z", "gp"}, {"z", "geopotential"}},
    {Role::GeopotentialHeight, {"geopotential_height"}, {{0, 3, 5}}, {"gh", "hgt"}, {"gh", "geopotential_height", "hgt"}},
    {Role::Temperature, {"air_temperature"}, {{0, 0, 0}}, {"t", "tmp"}, {"t", "air_temperature", "temperature", "tmp"}},
    {Role::Humidity, {"specific_humidity"}, {{0, 1, 0}}, {"q", "spfh"}, {"q", "specific_humidity", "spfh"}},
    {Role::U, {"eastward_wind"}, {{0, 2, 2}}, {"u", "ugrd"}, {"u", "eastward_wind", "u-component_of_wind", "u_component_of_wind", "ugrd"}},
    {Role::V, {"northward_wind"}, {{0, 2, 3}}, {"v", "vgrd"}, {"v", "northward_wind", "v-component_of_wind", "v_component_of_wind", "vgrd"}},
    {Role::Omega, {"lagrangian_tendency_of_air_pressure"}, {{0, 2, 8}}, {"w", "vvel"},
     {"w", "lagrangian_tendency_of_air_pressure", "vertical_velocity_pressure", "vvel"}},
    {Role::UpwardVelocity, {"upward_air_velocity"}, {{0, 2, 9}}, {"wz", "dzdt"}, {"vertical_velocity_geometric", "dzdt"}},
    {Role::Snow, {"mass_fraction_of_snow_in_air", "specific_snow_water_content"}, {{0, 1, 86}, {0, 1, 25}}, {"cswc", "snmr"},
     {"cswc", "specific_snow_water_content", "snow_mixing_ratio", "snmr"}},
    {Role::RelativeHumidity, {"relative_humidity"}, {{0, 1, 1}}, {"r", "rh"}, {"r", "relative_humidity", "rh"}},
};

// Precipitation, recognised so the report can say it is left out.
const RoleSpec kPrecipitation[] = {
    {Role::Liquid, {"mass_fraction_of_rain_in_air", "specific_rain_water_content"}, {{0, 1, 85}, {0, 1, 24}}, {"crwc", "rwmr"},
     {"crwc", "specific_rain_water_content", "rain_mixing_ratio", "rwmr"}},
    {Role::Liquid, {"mass_fraction_of_graupel_in_air"}, {{0, 1, 32}}, {"grle"}, {"graupel", "graupel_snow_pellets", "grle"}},
};

// Whether `units` fit the role, and the factor to the conversion's units. Empty units pass (the
// values' range checks still apply); wrong ones do not.
bool units_fit(Role r, const std::string& raw_units, double& scale) {
  const std::string u = units_key(raw_units);
  scale = 1.0;
  if (u.empty()) return true;
  const bool ratio = in(u, {"kg/kg", "kg_kg-1", "kg_kg**-1", "kg_kg^-1", "kg.kg-1", "1", "kg_kg**(-1)", "kg/kg_(moist_air)"});
  const bool per_mille = in(u, {"g/kg", "g_kg-1", "g_kg**-1", "g_kg^-1", "g.kg-1"});
  const bool percent = in(u, {"%", "percent", "pct"});
  switch (r) {
    case Role::CloudFraction:
    case Role::RelativeHumidity:
      if (percent) scale = 0.01;
      return percent || in(u, {"1", "(0_-_1)", "0-1", "(0-1)", "fraction", "dimensionless", "-"});
    case Role::Liquid:
    case Role::Ice:
    case Role::Snow:
    case Role::Humidity:
      if (per_mille) scale = 1e-3;
      return ratio || per_mille;
    case Role::Temperature: return in(u, {"k", "kelvin", "degk", "deg_k", "degrees_k"});
    case Role::U:
    case Role::V:
    case Role::UpwardVelocity:
      return in(u, {"m_s-1", "m_s**-1", "m/s", "m.s-1", "m_s^-1", "meters/second", "metres/second", "m_sec-1"});
    default: return true;  // geopotential and omega: their units are settled after detection
  }
}

// The GRIB2 parameter a variable's attributes name, if any: netCDF-Java's Grib2_Parameter
// (discipline, category, number) and Grib_Variable_Id "VAR_0-1-23_L100"; NCL's
// parameter_discipline_and_category / parameter_template_discipline_category_number.
std::optional<Grib2> grib2_of(const NcVar& v) {
  // A GRIB code is a whole number 0..65535; anything else names no parameter (a huge value would
  // overflow the conversion to int, as fuzzing found for another attribute).
  auto code = [](double x) -> std::optional<int> {
    if (!(x >= 0.0 && x <= 65535.0) || x != std::floor(x)) return std::nullopt;
    return static_cast<int>(x);
  };
  auto grib = [](std::optional<int> d, std::optional<int> c, std::optional<int> n) -> std::optional<Grib2> {
    if (d && c && n) return Grib2{*d, *c, *n};
    return std::nullopt;
  };
  if (const NcAtt* a = v.att("Grib2_Parameter"); a && a->values.size() == 3) {
    return grib(code(a->values[0]), code(a->values[1]), code(a->values[2]));
  }
  if (const NcAtt* a = v.att("parameter_template_discipline_category_number"); a && a->values.size() == 4) {
    return grib(code(a->values[1]), code(a->values[2]), code(a->values[3]));
  }
  static const std::regex id("^VAR_(\\d{1,5})-(\\d{1,5})-(\\d{1,5})(_|$)");
  std::smatch m;
  const std::string vid = v.text("Grib_Variable_Id");
  if (std::regex_search(vid, m, id)) return grib(code(std::stod(m[1])), code(std::stod(m[2])), code(std::stod(m[3])));
  return std::nullopt;
}

// The GRIB short name a variable's attributes give (cfgrib's GRIB_shortName, netCDF-Java's and
// NCEP's abbreviation), lower case.
std::string short_name_of(const NcVar& v) {
  for (const char* a : {"GRIB_shortName", "abbreviation", "short_name"}) {
    if (!v.text(a).empty()) return lower(v.text(a));
  }
  return "";
}

// A variable's name without the level-type suffixes GRIB converters add, lower case:
// "Ice_water_mixing_ratio_isobaric" -> "ice_water_mixing_ratio", "ICMR_P0_L100_GLL0" -> "icmr".
std::string base_name(const std::string& name) {
  std::string n = lower(name);
  static const std::regex ncl("^([a-z0-9]+)_p[0-9]+_l[0-9]+(_.*)?$");
  std::smatch m;
  if (std::regex_match(n, m, ncl)) return m[1];
  for (const char* suffix : {"_isobaric", "_hybrid", "_height_above_ground", "_sigma", "_altitude_above_msl", "_pressure"}) {
    const auto at = n.find(suffix);
    if (at != std::string::npos && at > 0) return n.substr(0, at);
  }
  return n;
}
}  // namespace

const char* role_name(Role r) {
  static const char* names[kRoleCount] = {"cloud fraction", "cloud liquid water", "cloud ice water", "geopotential",
                                          "geopotential height", "temperature", "specific humidity", "eastward wind",
                                          "northward wind", "vertical velocity (omega)", "upward air velocity",
                                          "snow (added to the ice)", "relative humidity"};
  return names[static_cast<int>(r)];
}

CfLayout detect_cf_layout(const NcFile& f) {
  CfLayout L;
  const std::string& path = f.path();
  // Coordinate variables: 1-D, named like their dimension. A file may hold several of one kind
  // (GRIB converters write isobaric1, isobaric3, height_above_ground1, ... for the levels different
  // variables use): each is a candidate, and the axes the variables used sit on are chosen below.
  std::vector<Axis> candidates[4];  // lon, lat, vertical, time
  for (const auto& v : f.vars()) {
    if (v.dims.size() != 1 || f.dims()[static_cast<std::size_t>(v.dims[0])].name != v.name) continue;
    if (f.size(v) > (1u << 24)) throw ImportError(path + ": coordinate '" + v.name + "' has an implausible length");
    std::vector<double> values;
    if (v.type != 2 /* NC_CHAR */) values = f.read(v);
    std::string how;
    const Kind k = classify(v, how, &values);
    if (k == Kind::None) continue;
    Axis a;
    a.dim = v.dims[0];
    a.var = &v;
    a.values = std::move(values);
    a.how = how;
    candidates[static_cast<int>(k) - 1].push_back(std::move(a));
  }
  // Rotated-pole and projected grids are not longitude/latitude grids, whatever their units say.
  for (const auto& v : f.vars()) {
    const std::string sn = lower(v.text("standard_name"));
    const std::string mapping = v.text("grid_mapping_name");
    if (sn == "grid_longitude" || sn == "grid_latitude" || sn == "projection_x_coordinate" ||
        (!mapping.empty() && mapping != "latitude_longitude")) {
      throw ImportError(path + ": variable '" + v.name + "' describes a " + (mapping.empty() ? sn : mapping) +
                        " grid; expected a plain longitude/latitude grid (rotated-pole and projected CF grids are not supported yet)");
    }
  }
  auto on_candidate = [&](const NcVar& v, int kind) {
    for (const Axis& a : candidates[kind]) {
      if (std::count(v.dims.begin(), v.dims.end(), a.dim) == 1) return &a;
    }
    return static_cast<const Axis*>(nullptr);
  };
  // Surface geopotential (or altitude) for heights above ground and hybrid levels.
  for (const auto& v : f.vars()) {
    const std::string sn = lower(v.text("standard_name"));
    if (v.dims.size() < 2 || v.dims.size() > 3) continue;
    if (sn == "surface_geopotential" && !L.surface_geopotential) L.surface_geopotential = &v;
    if (sn == "surface_altitude" && !L.surface_geopotential) {
      L.surface_geopotential = &v;
      L.surface_geopotential_scale = 9.80665;
    }
  }
  // Roles: standard_name first, then GRIB parameter attributes, then names; only a variable on a
  // longitude, a latitude and a vertical axis, with units that fit, is taken.
  auto find_role = [&](const RoleSpec& spec, double& scale) -> const NcVar* {
    // Cloud water on one level only cannot fill a volume: said when nothing else takes the role,
    // never dropped without a word.
    const bool cloud_role = spec.role == Role::CloudFraction || spec.role == Role::Liquid || spec.role == Role::Ice;
    const NcVar* flat = nullptr;
    for (int pass = 0; pass < 3; ++pass) {
      for (const auto& v : f.vars()) {
        if (&v == L.surface_geopotential) continue;
        bool match = false;
        if (pass == 0) {
          for (const char* sn : spec.standard_names) match |= v.text("standard_name") == sn;
        } else if (pass == 1) {
          const auto g = grib2_of(v);
          for (const Grib2& want : spec.grib) {
            match |= g && g->discipline == want.discipline && g->category == want.category && g->number == want.number;
          }
          const std::string sh = short_name_of(v);
          for (const char* n : spec.short_names) match |= !sh.empty() && sh == n;
        } else {
          const std::string n = lower(v.name), base = base_name(v.name);
          for (const char* want : spec.names) match |= n == want || base == want;
        }
        if (match && cloud_role && !flat && !v.dims.empty() && v.dims.size() < 3) flat = &v;
        if (!match || !on_candidate(v, 0) || !on_candidate(v, 1) || !on_candidate(v, 2)) continue;
        if (!units_fit(spec.role, v.text("units"), scale)) {
          L.notes.push_back("'" + v.name + "' looks like " + role_name(spec.role) + " but has units '" + v.text("units") +
                            "': not used");
          continue;
        }
        return &v;
      }
    }
    if (flat) {
      std::string dims;
      for (int d : flat->dims) dims += (dims.empty() ? "" : ", ") + f.dims()[static_cast<std::size_t>(d)].name;
      throw ImportError(path + ": variable '" + flat->name + "' (" + role_name(spec.role) + ") has " +
                        std::to_string(flat->dims.size()) + " dimension(s) (" + dims +
                        "), expected a 3-D field on longitude, latitude and levels");
    }
    return nullptr;
  };
  for (const RoleSpec& spec : kRoles) {
    double scale = 1.0;
    const NcVar* v = find_role(spec, scale);
    // One variable, one role (a standard_name-less "t" must not also be found as something else).
    for (int r = 0; v && r < kRoleCount; ++r) {
      if (L.roles[r] == v) v = nullptr;
    }
    L.roles[static_cast<int>(spec.role)] = v;
    L.role_scale[static_cast<int>(spec.role)] = scale;
  }
  for (const RoleSpec& spec : kPrecipitation) {
    double scale = 1.0;
    if (const NcVar* v = find_role(spec, scale)) L.precipitation.push_back(v->name);
  }
  // The axes: where there are several candidates of a kind, the one the cloud variables (else the
  // first other variable, in role order) sit on. Variables on another candidate of that kind are
  // not used, and the report says so.
  const Role priority[] = {Role::CloudFraction, Role::Liquid, Role::Ice, Role::Snow, Role::Geopotential,
                           Role::GeopotentialHeight, Role::Temperature, Role::Humidity, Role::RelativeHumidity,
                           Role::U, Role::V, Role::Omega, Role::UpwardVelocity};
  Axis* chosen[4] = {&L.lon, &L.lat, &L.vertical, &L.time};
  for (int kind = 0; kind < 4; ++kind) {
    if (candidates[kind].empty()) continue;
    const Axis* pick = &candidates[kind].front();
    if (candidates[kind].size() > 1) {
      for (Role r : priority) {
        const NcVar* v = L.roles[static_cast<int>(r)];
        if (const Axis* a = v ? on_candidate(*v, kind) : nullptr) {
          pick = a;
          break;
        }
      }
      for (int r = 0; r < kRoleCount; ++r) {
        const NcVar* v = L.roles[r];
        if (!v || std::count(v->dims.begin(), v->dims.end(), pick->dim) == 1) continue;
        if (const Axis* other = on_candidate(*v, kind)) {
          L.notes.push_back("'" + v->name + "' (" + role_name(static_cast<Role>(r)) + ") lies on '" + other->var->name +
                            "', not on '" + pick->var->name + "' where the other variables are: not used");
          L.roles[r] = nullptr;
        }
      }
    }
    *chosen[kind] = *pick;
    for (double x : chosen[kind]->values) {
      if (!std::isfinite(x)) {
        throw ImportError(path + ": coordinate '" + chosen[kind]->var->name +
                          "' has a missing or infinite value; expected every value set and finite");
      }
    }
  }
  if (!L.lon.var) throw ImportError(path + ": no longitude coordinate (expected units degrees_east or standard_name longitude)");
  if (!L.lat.var) throw ImportError(path + ": no latitude coordinate (expected units degrees_north or standard_name latitude)");
  // Each longitude and latitude names its own place: all-equal values (a step of 0) or two turns
  // interleaved (0..720) give no grid. Longitudes equal modulo 360 are allowed only as the first
  // and last value (a wrap column).
  for (const Axis* a : {&L.lon, &L.lat}) {
    std::vector<double> v = a->values;
    const bool lon = a == &L.lon;
    if (lon) {
      for (double& x : v) x = std::fmod(std::fmod(x, 360.0) + 360.0, 360.0);
    }
    std::sort(v.begin(), v.end());
    std::size_t same = 0;
    for (std::size_t i = 1; i < v.size(); ++i) same += std::abs(v[i] - v[i - 1]) <= 1e-9 * std::max(1.0, std::abs(v[i]));
    const bool wrap = lon && same == 1 && a->values.size() > 2 &&
                      std::abs(std::abs(a->values.back() - a->values.front()) - 360.0) <= 1e-6;
    if (same > (wrap ? 1u : 0u)) {
      throw ImportError(path + ": coordinate '" + a->var->name + "' has " + std::to_string(same + 1 - (wrap ? 1 : 0)) +
                        " values at the same " + (lon ? "longitude (modulo 360)" : "latitude") + ", expected " +
                        std::to_string(a->values.size()) + " distinct " + (lon ? "longitudes within one turn" : "latitudes"));
    }
  }
  if (!L.vertical.var) {
    throw ImportError(path + ": no vertical coordinate (expected pressure levels in Pa/hPa/mb, or standard_name air_pressure)");
  }
  const NcVar& zv = *L.vertical.var;
  const std::string vunits = lower(zv.text("units"));
  const std::string vsn = lower(zv.text("standard_name"));
  L.pressure_scale_to_pa = pressure_scale(vunits);
  // CF's name, and the one cdo writes.
  if ((vsn == "atmosphere_hybrid_sigma_pressure_coordinate" || vsn == "hybrid_sigma_pressure") && !zv.text("formula_terms").empty()) {
    // formula_terms: "a: A b: B p0: P0 ps: PS" or "ap: AP b: B ps: PS".
    L.vertical_kind = Vertical::Hybrid;
    const std::string ft = zv.text("formula_terms");
    auto term = [&](const std::string& key) -> const NcVar* {
      const std::regex re("(^|\\s)" + key + ":\\s*([^\\s]+)");
      std::smatch m;
      if (!std::regex_search(ft, m, re)) return nullptr;
      const NcVar* v = f.find(m[2]);
      if (!v) throw ImportError(path + ": formula_terms of '" + zv.name + "' name '" + m[2].str() + "', which is not in the file");
      return v;
    };
    const NcVar* a = term("a");
    const NcVar* ap = term("ap");
    const NcVar* b = term("b");
    const NcVar* p0 = term("p0");
    L.surface_pressure = term("ps");
    if ((!a && !ap) || !b || !L.surface_pressure || (a && !p0)) {
      throw ImportError(path + ": hybrid coordinate '" + zv.name + "' has formula_terms '" + ft +
                        "', expected 'a: A b: B p0: P0 ps: PS' or 'ap: AP b: B ps: PS'");
    }
    const double p0v = a ? f.read(*p0).at(0) : 1.0;
    const std::vector<double> av = f.read(a ? *a : *ap), bv = f.read(*b);
    if (av.size() != L.vertical.values.size() || bv.size() != L.vertical.values.size()) {
      throw ImportError(path + ": hybrid coefficients of '" + zv.name + "' do not have one value per level");
    }
    const double ascale = a ? p0v : std::max(1.0, pressure_scale((ap)->text("units")));
    for (std::size_t k = 0; k < av.size(); ++k) {
      L.hybrid_a_pa.push_back(av[k] * ascale);
      L.hybrid_b.push_back(bv[k]);
    }
  } else if (L.pressure_scale_to_pa == 0.0 && (vsn == "model_level_number" || lower(zv.text("long_name")) == "model_level_number" ||
                                               vunits.empty() || vunits == "1" || vunits == "level")) {
    // IFS model levels as cdo writes them: no formula_terms, but coefficient tables hyam/hybm (Pa
    // and 1) and the surface pressure as ps, sp or lnsp (its logarithm).
    const NcVar* a = f.find("hyam");
    const NcVar* b = f.find("hybm");
    const NcVar* sp = f.find("lnsp") ? f.find("lnsp") : f.find("ps") ? f.find("ps") : f.find("sp");
    const std::size_t n = L.vertical.values.size();
    if (!a || !b || !sp || f.size(*a) != n || f.size(*b) != n) {
      throw ImportError(path + ": vertical coordinate '" + zv.name + "' numbers model levels; model-level numbers need "
                        "their coefficients: expected formula_terms, or hyam (Pa) and hybm with one value per level and "
                        "a surface pressure (ps, sp or lnsp)");
    }
    L.vertical_kind = Vertical::Hybrid;
    L.surface_pressure = sp;
    L.surface_pressure_is_log = sp->name == "lnsp";
    const std::vector<double> av = f.read(*a), bv = f.read(*b);
    for (std::size_t k = 0; k < n; ++k) {
      L.hybrid_a_pa.push_back(av[k] * std::max(1.0, pressure_scale(lower(a->text("units")))));
      L.hybrid_b.push_back(bv[k]);
    }
    L.notes.push_back("model levels: p = hyam + hybm ps from '" + a->name + "', '" + b->name + "' and '" + sp->name + "'");
  } else if (L.pressure_scale_to_pa == 0.0) {
    const double hs = in(vunits, {"m", "meter", "meters", "metre", "metres"}) ? 1.0 : in(vunits, {"km", "kilometer", "kilometers", "kilometre", "kilometres"}) ? 1000.0 : 0.0;
    if (hs == 0.0 || lower(zv.text("positive")) == "down") {
      throw ImportError(path + ": vertical coordinate '" + zv.name + "' has units '" + zv.text("units") +
                        "' (standard_name '" + zv.text("standard_name") +
                        "'); expected pressure levels (Pa, hPa, mb), heights (m, km, positive up) or hybrid "
                        "sigma-pressure levels with formula_terms; model-level numbers need their coefficients");
    }
    L.vertical_kind = Vertical::Height;
    L.height_scale_to_m = hs;
    L.height_above_ground = vsn == "height";
  }
  // Names are not units: a "z" in metres is a geopotential height, a "w" in m/s an upward velocity.
  auto units_of = [](const NcVar* v) { return lower(v->text("units")); };
  // Water is read as a mass fraction (kg/kg): other units would scale it silently.
  for (Role r : {Role::Liquid, Role::Ice}) {
    const NcVar* w = L.roles[static_cast<int>(r)];
    if (!w) continue;
    std::string u = units_of(w);
    u.erase(std::remove(u.begin(), u.end(), ' '), u.end());
    if (!in(u, {"", "1", "kgkg-1", "kg/kg", "kgkg**-1", "kgkg^-1", "kg.kg-1", "kg*kg-1", "kgkg-1(mass)", "kg(kg)-1", "-", "dimensionless"})) {
      throw ImportError(path + ": variable '" + w->name + "' (" + role_name(r) + ") has units '" + w->text("units") +
                        "', expected a mass fraction in kg kg-1 (or 1)");
    }
  }
  if (const NcVar* z = L.roles[static_cast<int>(Role::Geopotential)]) {
    const std::string u = units_of(z);
    if (in(u, {"m", "gpm", "meter", "meters", "metre", "metres"})) {
      if (!L.roles[static_cast<int>(Role::GeopotentialHeight)]) L.roles[static_cast<int>(Role::GeopotentialHeight)] = z;
      L.roles[static_cast<int>(Role::Geopotential)] = nullptr;
      L.notes.push_back("'" + z->name + "' has units '" + z->text("units") + "': read as geopotential height");
    } else if (!u.empty() && u.find('s') == std::string::npos) {  // m2 s-2, m**2 s**-2, m^2/s^2 all name seconds
      throw ImportError(path + ": variable '" + z->name + "' has units '" + z->text("units") +
                        "', expected geopotential (m2 s-2) or geopotential height (m, gpm)");
    }
  }
  if (const NcVar* w = L.roles[static_cast<int>(Role::Omega)]) {
    const std::string u = units_of(w);
    const bool pressure_rate = u.rfind("pa", 0) == 0 || u.rfind("hpa", 0) == 0;
    if (!pressure_rate) {
      L.roles[static_cast<int>(Role::Omega)] = nullptr;
      if (lower(w->text("standard_name")) == "upward_air_velocity" || u == "m s-1" || u == "m s**-1" || u == "m/s") {
        L.roles[static_cast<int>(Role::UpwardVelocity)] = w;
      } else {
        L.notes.push_back("'" + w->name + "' has units '" + w->text("units") + "' (neither Pa/s nor m/s): not used");
      }
    }
  }
  // Time: a time dimension without a coordinate variable still orders the steps.
  int time_dim = L.time.dim;
  if (!L.time.var) {
    for (std::size_t d = 0; d < f.dims().size(); ++d) {
      const std::string n = lower(f.dims()[d].name);
      if (n == "time" || n.rfind("time", 0) == 0 || f.dims()[d].unlimited) {
        time_dim = static_cast<int>(d);
        break;
      }
    }
    L.time.dim = time_dim;
  }
  // Every 3-D+ role variable must span exactly lon, lat, vertical and (optionally) time, in any order.
  for (int r = 0; r < kRoleCount; ++r) {
    const NcVar* v = L.roles[r];
    if (!v) continue;
    for (int d : v->dims) {
      if (d != L.lon.dim && d != L.lat.dim && d != L.vertical.dim && d != time_dim) {
        throw ImportError(path + ": variable '" + v->name + "' has dimension '" + f.dims()[static_cast<std::size_t>(d)].name +
                          "'; expected only " + f.dims()[static_cast<std::size_t>(L.lon.dim)].name + ", " +
                          f.dims()[static_cast<std::size_t>(L.lat.dim)].name + ", " +
                          f.dims()[static_cast<std::size_t>(L.vertical.dim)].name +
                          (time_dim >= 0 ? ", " + f.dims()[static_cast<std::size_t>(time_dim)].name : std::string()));
      }
    }
    const bool has_all = std::count(v->dims.begin(), v->dims.end(), L.lon.dim) == 1 &&
                         std::count(v->dims.begin(), v->dims.end(), L.lat.dim) == 1 &&
                         std::count(v->dims.begin(), v->dims.end(), L.vertical.dim) == 1;
    if (!has_all) {
      throw ImportError(path + ": variable '" + v->name + "' does not span longitude, latitude and the vertical axis once each");
    }
  }
  // Valid times.
  const std::size_t nt = time_dim >= 0 ? f.dims()[static_cast<std::size_t>(time_dim)].length : 1;
  if (L.time.var) {
    const TimeUnits u = parse_time_units(L.time.var->text("units"), L.time.var->text("calendar"),
                                         path + ": variable '" + L.time.var->name + "'");
    bool approx_any = false;
    for (double x : L.time.values) {
      if (!std::isfinite(x) || std::abs(x * u.seconds_per_unit) > 3.2e11) {
        throw ImportError(path + ": variable '" + L.time.var->name + "' has value " + std::to_string(x) +
                          ", expected a time within 10 000 years of its reference date");
      }
      bool approx = false;
      L.times.push_back(valid_time(u, x, &approx));
      approx_any |= approx;
    }
    if (approx_any) {
      L.notes.push_back("calendar '" + L.time.var->text("calendar") +
                        "': dates are kept as written; the sun uses the nearest real date");
    }
    for (std::size_t i = 2; i < L.times.size(); ++i) {
      const auto d1 = L.times[i].unix_s - L.times[i - 1].unix_s, d0 = L.times[1].unix_s - L.times[0].unix_s;
      if (d1 != d0) L.times_uneven = true;
    }
  } else {
    // A coordinate variable on the time dimension that was not recognised has units nobody can read:
    // said, not taken as "no time coordinate".
    if (time_dim >= 0) {
      const std::string& dn = f.dims()[static_cast<std::size_t>(time_dim)].name;
      if (const NcVar* tv = f.find(dn); tv && tv->dims.size() == 1 && tv->dims[0] == time_dim && tv->type != 2 /* NC_CHAR */) {
        throw ImportError(path + ": variable '" + tv->name + "' (the time coordinate) has units '" + tv->text("units") +
                          "', expected '<unit> since YYYY-MM-DD[ hh:mm:ss]'");
      }
    }
    for (std::size_t i = 0; i < nt; ++i) L.times.push_back({0, "step " + std::to_string(i) + " (no time coordinate)"});
    L.notes.push_back("no time coordinate: steps are numbered, valid times unknown");
  }
  return L;
}

bool has_cloud(const CfLayout& L) {
  for (Role r : {Role::CloudFraction, Role::Liquid, Role::Ice, Role::Snow}) {
    if (L.roles[static_cast<int>(r)]) return true;
  }
  return false;
}

}  // namespace cv::importers
