// Reading and writing scene files with nlohmann-json: a strict reader that names the key path of
// every problem, and a writer that writes every key.
#include "scene/scene_json.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <optional>
#include <sstream>
#include <type_traits>
#include <vector>

#include <nlohmann/json.hpp>

#include "scene/framing.hpp"
#include "scene/quality.hpp"
#include "settings/overlay_settings.hpp"
#include "settings/quality_knobs.hpp"
#include "volume/volume_io.hpp"

namespace cv::core {
namespace {

using json = nlohmann::json;
using ojson = nlohmann::ordered_json;

// What a value looked like, for messages: JSON as written (strings keep their quotes), shortened.
// Written by hand with a budget, so a huge or deep value costs no more than the 40 characters shown.
void show_into(const json& v, std::string& out, std::size_t budget) {
  if (out.size() > budget) return;
  if (v.is_array() || v.is_object()) {
    out += v.is_array() ? '[' : '{';
    bool first = true;
    for (auto it = v.begin(); it != v.end() && out.size() <= budget; ++it) {
      if (!first) out += ',';
      first = false;
      if (v.is_object()) out += json(it.key()).dump() + ':';
      show_into(*it, out, budget);
    }
    out += v.is_array() ? ']' : '}';
  } else {
    out += v.dump();
  }
}
std::string shown(const json& v) {
  std::string s;
  show_into(v, s, 40);
  if (s.size() > 40) s = s.substr(0, 37) + "...";
  return s;
}

// Reads one object of the scene, remembering its key path for messages.
class Reader {
 public:
  Reader(const std::string& source, const json& obj, std::string path) : source_(source), obj_(obj), path_(std::move(path)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& found, const std::string& expected) const {
    throw SceneError(source_ + ": " + where(key) + ": found " + found + ", expected " + expected);
  }

  // Every key must be one of `known`: a misspelt key would otherwise be ignored without a word.
  void only(std::initializer_list<const char*> known) const { only(std::vector<const char*>(known)); }
  void only(const std::vector<const char*>& known) const {
    for (const auto& [key, value] : obj_.items()) {
      bool ok = false;
      for (const char* k : known) ok = ok || key == k;
      if (!ok) {
        std::string list;
        for (const char* k : known) list += std::string(list.empty() ? "" : ", ") + k;
        throw SceneError(source_ + ": " + where(key) + ": unknown key, expected one of " + list);
      }
    }
  }

  const json* find(const char* key) const {
    const auto it = obj_.find(key);
    return it == obj_.end() ? nullptr : &*it;
  }

  void number(const char* key, double& out, double lo, double hi, const std::string& expected) const {
    const json* v = find(key);
    if (!v) return;
    if (!v->is_number() || !(v->get<double>() >= lo && v->get<double>() <= hi)) fail(key, shown(*v), expected);
    out = v->get<double>();
  }

  void integer(const char* key, int& out, int lo, int hi) const {
    const json* v = find(key);
    if (!v) return;
    const std::string expected = "an integer " + std::to_string(lo) + ".." + std::to_string(hi);
    if (!v->is_number()) fail(key, shown(*v), expected);
    const double d = v->get<double>();
    if (!(d >= lo && d <= hi) || d != std::floor(d)) fail(key, shown(*v), expected);
    out = static_cast<int>(d);
  }

  void boolean(const char* key, bool& out) const {
    const json* v = find(key);
    if (!v) return;
    if (!v->is_boolean()) fail(key, shown(*v), "true or false");
    out = v->get<bool>();
  }

  void string(const char* key, std::string& out) const {
    const json* v = find(key);
    if (!v) return;
    if (!v->is_string()) fail(key, shown(*v), "a string");
    out = v->get<std::string>();
  }

  // A nested object (nothing when absent or null), checked to be an object.
  std::optional<Reader> child(const char* key) const {
    const json* v = find(key);
    if (!v || v->is_null()) return std::nullopt;
    if (!v->is_object()) fail(key, shown(*v), "an object { ... }");
    return Reader(source_, *v, where(key));
  }

  // A fixed-length array of numbers (nothing when absent or null).
  template <std::size_t N>
  std::optional<std::array<double, N>> numbers(const char* key, const std::string& expected) const {
    const json* v = find(key);
    if (!v || v->is_null()) return std::nullopt;
    if (!v->is_array() || v->size() != N) fail(key, shown(*v), expected);
    std::array<double, N> out{};
    for (std::size_t i = 0; i < N; ++i) {
      if (!(*v)[i].is_number()) fail(key, shown(*v), expected);
      out[i] = (*v)[i].get<double>();
    }
    return out;
  }

  std::string where(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  const std::string& source() const { return source_; }

 private:
  const std::string& source_;
  const json& obj_;
  std::string path_;
};

constexpr double kHuge = 1e300;  // "any finite number" as a range

void read_data(const Reader& r, DataSource& d) {
  r.only({"path", "region_deg", "levels_hpa", "horizontal_stride", "dz_m", "diagnose_cloud", "rh_critical"});
  r.string("path", d.path);
  d.region_deg = r.numbers<4>("region_deg", "[west, east, south, north] in degrees, or null");
  if (d.region_deg) {
    const auto& g = *d.region_deg;
    if (!(g[2] <= g[3] && g[2] >= -90.0 && g[3] <= 90.0)) {
      r.fail("region_deg", shown(json(g)), "south <= north within -90..90");
    }
  }
  d.levels_hpa = r.numbers<2>("levels_hpa", "[min, max] pressure in hPa, or null");
  if (d.levels_hpa && !((*d.levels_hpa)[0] <= (*d.levels_hpa)[1] && (*d.levels_hpa)[0] >= 0.0)) {
    r.fail("levels_hpa", shown(json(*d.levels_hpa)), "0 <= min <= max in hPa");
  }
  r.integer("horizontal_stride", d.horizontal_stride, 1, 1000000);
  r.number("dz_m", d.dz_m, 0.0, 1e5, "a vertical spacing in metres 0..100000 (0: the importer's default)");
  r.boolean("diagnose_cloud", d.diagnose_cloud);
  r.number("rh_critical", d.rh_critical, 0.5, 0.999999, "a critical relative humidity 0.5 <= RH < 1");
}

void read_camera(const Reader& r, Camera& c) {
  r.only({"lat_deg", "lon_deg", "alt_m", "heading_deg", "pitch_deg", "fov_deg"});
  r.number("lat_deg", c.lat_deg, -90.0, 90.0, "a latitude in degrees -90..90");
  r.number("lon_deg", c.lon_deg, -kHuge, kHuge, "a longitude in degrees");
  r.number("alt_m", c.alt_m, 0.0, 4e8, "an altitude in metres 0..4e8");
  r.number("heading_deg", c.heading_deg, -kHuge, kHuge, "a heading in degrees clockwise from north");
  r.number("pitch_deg", c.pitch_deg, -90.0, 90.0, "a pitch in degrees -90..90");
  r.number("fov_deg", c.fov_deg, 1e-6, 179.999, "a horizontal field of view in degrees, more than 0 and less than 180");
}

// "path": {"keyframes": [{"t_s", "lat_deg", ...}, ...], "weather_hours_per_s", "speed", "ease"},
// read key by key as the camera is, then checked as a whole (PathEvaluator) with the key named.
void read_path(const Reader& r, CameraPath& p) {
  r.only({"keyframes", "weather_hours_per_s", "speed", "ease"});
  const json* keys = r.find("keyframes");
  if (!keys) r.fail("keyframes", "nothing", "a list of at least 2 keyframes [{\"t_s\": ..., \"lat_deg\": ..., ...}, ...]");
  if (!keys->is_array()) r.fail("keyframes", shown(*keys), "a list of at least 2 keyframes [{\"t_s\": ..., ...}, ...]");
  for (std::size_t i = 0; i < keys->size(); ++i) {
    const std::string at = r.where("keyframes[" + std::to_string(i) + "]");
    const json& item = (*keys)[i];
    if (!item.is_object()) r.fail("keyframes[" + std::to_string(i) + "]", shown(item), "a keyframe object {\"t_s\": ..., ...}");
    const Reader k(r.source(), item, at);
    k.only({"t_s", "lat_deg", "lon_deg", "alt_m", "heading_deg", "pitch_deg", "fov_deg", "valid_utc"});
    for (const char* required : {"t_s", "lat_deg", "lon_deg", "alt_m"}) {
      if (!k.find(required)) k.fail(required, "nothing", "a number (t_s, lat_deg, lon_deg and alt_m are required)");
    }
    PathKeyframe f;
    k.number("t_s", f.t_s, -1e9, 1e9, "a path time in seconds -1e9..1e9");
    k.number("lat_deg", f.lat_deg, -90.0, 90.0, "a latitude in degrees -90..90");
    k.number("lon_deg", f.lon_deg, -kHuge, kHuge, "a longitude in degrees");
    k.number("alt_m", f.alt_m, 0.0, 4e8, "an altitude in metres 0..4e8 (not below the ground)");
    k.number("heading_deg", f.heading_deg, -kHuge, kHuge, "a heading in degrees clockwise from north");
    k.number("pitch_deg", f.pitch_deg, -90.0, 90.0, "a pitch in degrees -90..90");
    k.number("fov_deg", f.fov_deg, 1e-6, 179.999, "a horizontal field of view in degrees, more than 0 and less than 180");
    k.string("valid_utc", f.valid_utc);
    p.keyframes.push_back(f);
  }
  r.number("weather_hours_per_s", p.weather_hours_per_s, -1e6, 1e6, "hours of weather per path second, -1e6..1e6 (0: none)");
  std::string speed = p.speed == PathSpeed::Constant ? "constant" : "keyframes";
  r.string("speed", speed);
  if (speed != "keyframes" && speed != "constant") r.fail("speed", shown(json(speed)), "\"keyframes\" or \"constant\"");
  p.speed = speed == "constant" ? PathSpeed::Constant : PathSpeed::Keyframes;
  std::string ease = p.ease ? "in_out" : "none";
  r.string("ease", ease);
  if (ease != "none" && ease != "in_out") r.fail("ease", shown(json(ease)), "\"none\" or \"in_out\"");
  p.ease = ease == "in_out";
  try {
    const PathEvaluator check(p);
  } catch (const PathError& e) {
    throw SceneError(r.source() + ": " + r.where(e.key) + ": found " + e.found + ", expected " + e.expected);
  }
}

void read_sun(const Reader& r, SunSpec& s) {
  r.only({"mode", "datetime_utc", "subsolar_lat_deg", "subsolar_lon_deg", "irradiance"});
  std::string mode = sun_mode_name(s.mode);
  r.string("mode", mode);
  if (!parse_sun_mode(mode, s.mode)) r.fail("mode", shown(json(mode)), "\"valid_time\", \"datetime\", \"manual\" or \"local_noon\"");
  r.string("datetime_utc", s.datetime_utc);
  if ((s.mode == SunMode::DateTime || !s.datetime_utc.empty()) && !parse_iso_utc(s.datetime_utc)) {
    r.fail("datetime_utc", shown(json(s.datetime_utc)), "a UTC date-time YYYY-MM-DDThh:mm:ssZ");
  }
  r.number("subsolar_lat_deg", s.subsolar_lat_deg, -90.0, 90.0, "a latitude in degrees -90..90");
  r.number("subsolar_lon_deg", s.subsolar_lon_deg, -kHuge, kHuge, "a longitude in degrees");
  r.number("irradiance", s.irradiance, 1e-300, kHuge, "a relative irradiance > 0");
}

// render.march, row by row from the table (settings/march_settings.def): its keys, its ranges
// and its wording, so a new row is read without a line here.
void read_time(const Reader& r, TimeSpec& t) {
  r.only({"valid_utc", "interpolation"});
  r.string("valid_utc", t.valid_utc);
  if (!t.valid_utc.empty() && !parse_iso_utc(t.valid_utc)) {
    r.fail("valid_utc", shown(json(t.valid_utc)), "a UTC date-time YYYY-MM-DDThh:mm:ssZ (or \"\": time_step)");
  }
  std::string interp = time_interpolation_name(t.interpolation);
  r.string("interpolation", interp);
  if (!parse_time_interpolation(interp, t.interpolation)) {
    r.fail("interpolation", shown(json(interp)), "\"auto\", \"nearest\", \"linear\" or \"advected\"");
  }
}

void read_march(const Reader& r, MarchSettings& m) {
  std::vector<const char*> keys;
  for (const SettingRow& row : kMarchSettingRows) keys.push_back(row.key);
  r.only(keys);
  for_each_march_setting(m, [&](const SettingRow& row, auto& value) {
    using T = std::decay_t<decltype(value)>;
    const json* v = r.find(row.key);
    if (!v) return;
    const std::string expected = expected_text(row);
    if constexpr (std::is_same_v<T, bool>) {
      if (row.kind == SettingKind::Choice) {
        if (!v->is_string() || (*v != row.choices[0] && *v != row.choices[1])) r.fail(row.key, shown(*v), expected);
        value = *v == row.choices[1];
      } else {
        if (!v->is_boolean()) r.fail(row.key, shown(*v), expected);
        value = v->get<bool>();
      }
    } else if constexpr (std::is_same_v<T, int> || std::is_same_v<T, double>) {
      if (!v->is_number() || !in_range(row, v->get<double>())) r.fail(row.key, shown(*v), expected);
      value = static_cast<T>(v->get<double>());
    } else if constexpr (std::is_same_v<T, glm::dvec3>) {
      const auto a = r.numbers<3>(row.key, expected);
      if (!a) return;  // null: as if absent
      for (double x : *a) {
        if (!in_range(row, x)) {
          char found[64];
          std::snprintf(found, sizeof found, "a value of %g", x);
          r.fail(row.key, found, expected);
        }
      }
      value = glm::dvec3((*a)[0], (*a)[1], (*a)[2]);
    } else {
      if (!v->is_string()) r.fail(row.key, shown(*v), expected);
      value = v->get<std::string>();
    }
  });
}

void read_render(const Reader& r, RenderSettings& s) {
  r.only({"quality", "march", "accumulate", "resolution_scale", "exposure", "budget_ms"});
  // The preset first: march keys written in the file then override its values.
  std::string quality = s.quality;
  r.string("quality", quality);
  if (quality == "custom") {
    s.quality = quality;
  } else if (find_quality(quality)) {
    apply_quality(quality, s);
  } else {
    r.fail("quality", shown(json(quality)), "one of " + quality_names());
  }
  if (const auto m = r.child("march")) read_march(*m, s.march);
  {  // ranges from the quality knobs' rows (quality_knobs.def)
    const SettingRow& acc = find_quality_knob("accumulate")->row;
    const SettingRow& scale = find_quality_knob("resolution_scale")->row;
    r.integer(acc.key, s.accumulate, static_cast<int>(acc.lo), static_cast<int>(acc.hi));
    r.number(scale.key, s.resolution_scale, scale.lo, scale.hi, expected_text(scale));
  }
  if (const json* e = r.find("exposure"); e && e->is_string()) {
    if (e->get<std::string>() != "auto") r.fail("exposure", shown(*e), "an exposure > 0 or \"auto\"");
    s.auto_exposure = true;
  } else if (e) {
    r.number("exposure", s.exposure, 1e-300, kHuge, "an exposure > 0 or \"auto\"");
    s.auto_exposure = false;
  }
  r.number("budget_ms", s.budget_ms, 0.0, 1e7, "a frame-time budget in ms 0..1e7 (0: off)");
}

// Every row of the table, in its order, so a saved scene holds every setting.
ojson march_to_json(const MarchSettings& m) {
  ojson out = ojson::object();
  for_each_march_setting(m, [&](const SettingRow& row, const auto& value) {
    using T = std::decay_t<decltype(value)>;
    if constexpr (std::is_same_v<T, bool>) {
      out[row.key] = row.kind == SettingKind::Choice ? ojson(row.choices[value ? 1 : 0]) : ojson(value);
    } else if constexpr (std::is_same_v<T, glm::dvec3>) {
      out[row.key] = {value.x, value.y, value.z};
    } else {
      out[row.key] = value;
    }
  });
  return out;
}

// "overlays": each entry a type name (its defaults) or an object {"type": NAME, key: value, ...}
// typed by the overlay table (settings/overlay_settings.def).
// "views": {"layout": "grid"|"swipe", "linked": bool, "divider": 0..1,
//           "compare": [{"path": "b.nc", "time": "2024-01-15T06:00:00Z" | 3}, ...]}
void read_views(const Reader& r, ViewsSpec& v) {
  r.only({"layout", "linked", "divider", "compare"});
  r.string("layout", v.layout);
  if (v.layout != "grid" && v.layout != "swipe") r.fail("layout", json(v.layout).dump(), "\"grid\" or \"swipe\"");
  r.boolean("linked", v.linked);
  r.number("divider", v.divider, 0.0, 1.0, "a fraction of the width 0..1");
  if (const json* c = r.find("compare"); c && !c->is_null()) {
    const std::string most = std::to_string(ViewsSpec::kMaxCompare);
    if (!c->is_array() || c->size() > static_cast<std::size_t>(ViewsSpec::kMaxCompare)) {
      r.fail("compare", shown(*c), "an array of at most " + most + " views {\"path\": FILE, \"time\": UTC time or step}");
    }
    for (std::size_t i = 0; i < c->size(); ++i) {
      const std::string key = "compare[" + std::to_string(i) + "]";
      const json& e = (*c)[i];
      if (!e.is_object()) r.fail(key, shown(e), "an object {\"path\": FILE, \"time\": UTC time or step}");
      const Reader er(r.source(), e, r.where(key));
      er.only({"path", "time"});
      ViewSource s;
      er.string("path", s.path);
      if (const json* t = er.find("time"); t && !t->is_null()) {
        const std::string expected = "a UTC time YYYY-MM-DDThh:mm:ssZ or a step index >= 0";
        if (t->is_string()) {
          s.time = t->get<std::string>();
          if (!parse_iso_utc(s.time)) er.fail("time", shown(*t), expected);
        } else if (t->is_number_integer() && t->get<long long>() >= 0 && t->get<long long>() < (1LL << 30)) {
          s.time = std::to_string(t->get<long long>());
        } else {
          er.fail("time", shown(*t), expected);
        }
      }
      if (s.path.empty() && s.time.empty()) er.fail("path", "neither path nor time", "a file, a time of the scene's file, or both");
      v.compare.push_back(std::move(s));
    }
  }
  if (v.layout == "swipe" && v.compare.size() != 1) {
    r.fail("layout", "\"swipe\" with " + std::to_string(v.compare.size() + 1) + " view(s)",
           "exactly one view in compare (a swipe divider splits two views)");
  }
}

void read_overlays(const std::string& source, const json& o, std::vector<OverlaySpec>& out) {
  const json empty = json::object();
  const Reader top(source, empty, "");
  if (!o.is_array()) top.fail("overlays", shown(o), "an array of overlays (names or {\"type\": ...} objects)");
  for (std::size_t i = 0; i < o.size(); ++i) {
    const json& item = o[i];
    const std::string at = "overlays[" + std::to_string(i) + "]";
    if (item.is_string()) {
      if (!is_overlay_type(item.get<std::string>())) top.fail(at, shown(item), overlay_types_expected());
      out.push_back(default_overlay(item.get<std::string>()));
      continue;
    }
    if (!item.is_object()) top.fail(at, shown(item), "an overlay name or an object {\"type\": NAME, ...}");
    const auto type = item.find("type");
    if (type == item.end()) top.fail(at + ".type", "nothing", overlay_types_expected());
    if (!type->is_string() || !is_overlay_type(type->get<std::string>())) top.fail(at + ".type", shown(*type), overlay_types_expected());
    OverlaySpec spec = default_overlay(type->get<std::string>());
    std::vector<const char*> known = {"type"};
    for (const OverlayParamRow& row : overlay_param_rows()) {
      if (spec.type == row.overlay) known.push_back(row.key);
    }
    const Reader r(source, item, at);
    r.only(known);
    for (const auto& [key, value] : item.items()) {
      if (key == "type") continue;
      const OverlayParamRow& row = *overlay_param(spec.type, key);
      const std::string expected = overlay_param_expected(row);
      if (row.kind == OverlayParamKind::Number) {
        if (!value.is_number() || !(value.get<double>() >= row.lo && value.get<double>() <= row.hi)) r.fail(key, shown(value), expected);
        spec.numbers[key] = value.get<double>();
      } else if (row.kind == OverlayParamKind::Text) {
        if (!value.is_string() || value.get<std::string>().empty()) r.fail(key, shown(value), "a non-empty string: " + std::string(row.doc));
        spec.texts[key] = value.get<std::string>();
      } else {
        if (!value.is_array() || value.size() != 3) r.fail(key, shown(value), expected);
        glm::dvec3 c;
        for (int k = 0; k < 3; ++k) {
          if (!value[k].is_number() || !(value[k].get<double>() >= row.lo && value[k].get<double>() <= row.hi)) r.fail(key, shown(value), expected);
          c[k] = value[k].get<double>();
        }
        spec.colors[key] = c;
      }
    }
    out.push_back(std::move(spec));
  }
}

}  // namespace

Scene scene_from_json(const std::string& text, const std::string& source) {
  json root;
  try {
    // Nesting is bounded while parsing, before a deep value exists: nothing in a scene nests
    // deeper than 3, and deep values cost stack in every walk over them.
    root = json::parse(text, [&](int depth, json::parse_event_t, json&) {
      if (depth > kMaxSceneDepth) {
        throw SceneError(source + ": found values nested more than " + std::to_string(kMaxSceneDepth) +
                         " levels deep, expected a scene object (docs/scene.md)");
      }
      return true;
    });
  } catch (const json::out_of_range& e) {
    // A number beyond a double's range (1e400): nlohmann's message names it.
    std::string what = e.what();
    const std::size_t q = what.find('\'');
    throw SceneError(source + ": found the number " + (q == std::string::npos ? what : what.substr(q)) +
                     ", expected a finite number (at most 1.8e308 in size)");
  } catch (const json::exception& e) {
    // nlohmann's message names the byte and what it expected; keep it on one line.
    std::string what = e.what();
    for (char& c : what) c = (c == '\n' ? ' ' : c);
    throw SceneError(source + ": not valid JSON: " + what);
  }
  if (!root.is_object()) throw SceneError(source + ": found " + shown(root) + " at the top, expected a JSON object { ... }");
  const Reader r(source, root, "");
  r.only({"version", "data", "time_step", "time", "camera", "path", "width", "height", "sun", "render", "overlays", "views"});
  const json* version = r.find("version");
  if (!version) r.fail("version", "nothing", "\"version\": " + std::to_string(Scene::kVersion));
  if (!version->is_number_integer() || version->get<long long>() < 1) r.fail("version", shown(*version), "an integer >= 1");
  if (version->get<long long>() > Scene::kVersion) {
    r.fail("version", shown(*version),
           std::to_string(Scene::kVersion) + " or lower (the file was written by a newer cloudviewer)");
  }
  Scene scene;
  apply_quality(scene.render.quality, scene.render);  // a scene without render keys renders at "default"
  if (const auto d = r.child("data")) read_data(*d, scene.data);
  r.integer("time_step", scene.time_step, 0, 1 << 30);
  if (const auto t = r.child("time")) read_time(*t, scene.time);
  if (const auto c = r.child("camera")) {
    scene.camera = Camera{};
    read_camera(*c, *scene.camera);
  }
  if (const auto p = r.child("path")) {
    scene.path = CameraPath{};
    read_path(*p, *scene.path);
  }
  r.integer("width", scene.width, 1, 16384);
  r.integer("height", scene.height, 1, 16384);
  if (scene.camera) scene.camera->width = scene.width, scene.camera->height = scene.height;
  if (const auto s = r.child("sun")) read_sun(*s, scene.sun);
  if (const auto rs = r.child("render")) read_render(*rs, scene.render);
  if (const json* o = r.find("overlays")) read_overlays(source, *o, scene.overlays);
  if (const auto v = r.child("views")) {
    scene.views = ViewsSpec{};
    read_views(*v, *scene.views);
  }
  return scene;
}

std::string scene_to_json(const Scene& s) {
  // Keys in the order docs/scene.md lists them, not sorted, so the file reads top-down.
  ojson root = ojson::object();
  root["version"] = Scene::kVersion;
  ojson data = {{"path", s.data.path}, {"horizontal_stride", s.data.horizontal_stride}, {"dz_m", s.data.dz_m}};
  data["region_deg"] = s.data.region_deg ? ojson(*s.data.region_deg) : ojson(nullptr);
  data["levels_hpa"] = s.data.levels_hpa ? ojson(*s.data.levels_hpa) : ojson(nullptr);
  if (s.data.diagnose_cloud) {  // written only when asked for, so scenes of files with cloud read as before
    data["diagnose_cloud"] = true;
    data["rh_critical"] = s.data.rh_critical;
  }
  root["data"] = data;
  root["time_step"] = s.time_step;
  root["time"] = {{"valid_utc", s.time.valid_utc}, {"interpolation", time_interpolation_name(s.time.interpolation)}};
  root["width"] = s.width;
  root["height"] = s.height;
  if (s.camera) {
    const Camera& c = *s.camera;
    root["camera"] = {{"lat_deg", c.lat_deg},         {"lon_deg", c.lon_deg},     {"alt_m", c.alt_m},
                      {"heading_deg", c.heading_deg}, {"pitch_deg", c.pitch_deg}, {"fov_deg", c.fov_deg}};
  } else {
    root["camera"] = nullptr;  // automatic framing
  }
  if (s.path) {
    ojson keys = ojson::array();
    for (const PathKeyframe& k : s.path->keyframes) {
      keys.push_back({{"t_s", k.t_s},         {"lat_deg", k.lat_deg},     {"lon_deg", k.lon_deg}, {"alt_m", k.alt_m},
                      {"heading_deg", k.heading_deg}, {"pitch_deg", k.pitch_deg}, {"fov_deg", k.fov_deg}, {"valid_utc", k.valid_utc}});
    }
    root["path"] = {{"keyframes", keys},
                    {"weather_hours_per_s", s.path->weather_hours_per_s},
                    {"speed", s.path->speed == PathSpeed::Constant ? "constant" : "keyframes"},
                    {"ease", s.path->ease ? "in_out" : "none"}};
  } else {
    root["path"] = nullptr;  // no flyover
  }
  root["sun"] = {{"mode", sun_mode_name(s.sun.mode)},
                 {"datetime_utc", s.sun.datetime_utc},
                 {"subsolar_lat_deg", s.sun.subsolar_lat_deg},
                 {"subsolar_lon_deg", s.sun.subsolar_lon_deg},
                 {"irradiance", s.sun.irradiance}};
  root["render"] = {{"quality", s.render.quality},
                    {"accumulate", s.render.accumulate},
                    {"resolution_scale", s.render.resolution_scale},
                    {"exposure", s.render.auto_exposure ? ojson("auto") : ojson(s.render.exposure)},
                    {"budget_ms", s.render.budget_ms},
                    {"march", march_to_json(s.render.march)}};
  ojson overlays = ojson::array();
  for (const OverlaySpec& o : s.overlays) {
    ojson entry = {{"type", o.type}};
    for (const OverlayParamRow& row : overlay_param_rows()) {
      if (o.type != row.overlay) continue;
      if (row.kind == OverlayParamKind::Number) entry[row.key] = o.number(row.key);
      if (row.kind == OverlayParamKind::Text) entry[row.key] = o.text(row.key);
      if (row.kind == OverlayParamKind::Rgb) {
        const glm::dvec3 c = o.color(row.key);
        entry[row.key] = {c.x, c.y, c.z};
      }
    }
    overlays.push_back(entry);
  }
  root["overlays"] = overlays;
  if (s.views) {
    ojson compare = ojson::array();
    for (const ViewSource& v : s.views->compare) {
      ojson e = ojson::object();
      if (!v.path.empty()) e["path"] = v.path;
      if (!v.time.empty()) {
        // A step index is written as a number, a UTC time as a string.
        if (v.time.find_first_not_of("0123456789") == std::string::npos) e["time"] = std::stoll(v.time);
        else e["time"] = v.time;
      }
      compare.push_back(e);
    }
    root["views"] = {{"layout", s.views->layout}, {"linked", s.views->linked}, {"divider", s.views->divider}, {"compare", compare}};
  } else {
    root["views"] = nullptr;  // the scene's view alone
  }
  return root.dump(2) + "\n";
}

Scene load_scene(const std::string& path) {
  std::string text;
  if (file_kind(path) == "no such file") throw SceneError(path + ": cannot open the scene file (missing or unreadable)");
  try {
    text = read_regular_file(path, "the scene file", kMaxSceneBytes);
  } catch (const InputError& e) {
    throw SceneError(e.what());
  }
  Scene scene = scene_from_json(text, path);
  // Paths in a scene are relative to its folder, wherever it is run from.
  namespace fs = std::filesystem;
  auto beside = [&](std::string& p) {
    if (!p.empty() && fs::path(p).is_relative()) p = (fs::path(path).parent_path() / p).lexically_normal().string();
  };
  beside(scene.data.path);
  if (scene.render.march.medium.ground_texture != "none") beside(scene.render.march.medium.ground_texture);
  if (scene.views) {
    for (ViewSource& v : scene.views->compare) beside(v.path);
  }
  return scene;
}

void save_scene(const Scene& scene, const std::string& path) {
  const std::string text = scene_to_json(scene);
  write_file_atomically(path, [&](std::FILE* f) { std::fwrite(text.data(), 1, text.size(), f); });
}

}  // namespace cv::core
