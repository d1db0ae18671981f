// quality_front.json: reading it strictly (every problem named by file and key), writing it, ranking
// its configurations across scenes, and the choice of the most accurate one within a time budget.
#include "bench/quality_front.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include <nlohmann/json.hpp>

#include "scene/quality.hpp"
#include "volume/volume_io.hpp"

namespace cv::bench {
namespace {

using json = nlohmann::json;
using ojson = nlohmann::ordered_json;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr const char* kFormat = "cloudviewer-quality-front";

std::string shown(const json& v) {
  std::string s = v.dump();
  if (s.size() > 40) s = s.substr(0, 37) + "...";
  return s;
}

// One object of the file, with its key path for messages.
class Reader {
 public:
  Reader(const std::string& source, const json& obj, std::string path)
      : source_(source), obj_(obj), path_(std::move(path)) {}
  [[noreturn]] void fail(const std::string& key, const std::string& found,
                         const std::string& expected) const {
    throw FrontError(source_ + ": " + path_ + key + ": found " + found + ", expected " + expected);
  }
  const json& need(const char* key, const std::string& expected) const {
    const auto it = obj_.find(key);
    if (it == obj_.end()) fail(key, "nothing", expected);
    return *it;
  }
  double number(const char* key, double lo, double hi, const std::string& expected) const {
    const json& v = need(key, expected);
    if (!v.is_number() || !(v.get<double>() >= lo && v.get<double>() <= hi)) fail(key, shown(v), expected);
    return v.get<double>();
  }
  int integer(const char* key, int lo, int hi) const {
    const std::string expected = "an integer " + std::to_string(lo) + ".." + std::to_string(hi);
    const json& v = need(key, expected);
    if (!v.is_number_integer() || v.get<long long>() < lo || v.get<long long>() > hi)
      fail(key, shown(v), expected);
    return static_cast<int>(v.get<long long>());
  }
  bool boolean(const char* key) const {
    const json& v = need(key, "true or false");
    if (!v.is_boolean()) fail(key, shown(v), "true or false");
    return v.get<bool>();
  }
  std::string string(const char* key, const std::string& expected = "a string") const {
    const json& v = need(key, expected);
    if (!v.is_string()) fail(key, shown(v), expected);
    return v.get<std::string>();
  }
  // A quality knob by its row (quality_knobs.def): range and message from the table.
  void knob(const SettingRow& row, double& out) const {
    out = number(row.key, row.lo, row.hi, expected_text(row));
  }
  void knob(const SettingRow& row, int& out) const {
    out = integer(row.key, static_cast<int>(row.lo), static_cast<int>(row.hi));
  }
  void knob(const SettingRow& row, bool& out) const { out = boolean(row.key); }
  const std::string& source() const { return source_; }
  const std::string& path() const { return path_; }

 private:
  const std::string& source_;
  const json& obj_;
  std::string path_;
};

// rel_rmse is NaN where the reference is black (clear sky): nothing to be relative to. A value of
// exactly 0 is floored so that its logarithm stays finite.
bool usable(const FrontScene& s) {
  return std::isfinite(s.rel_rmse) && s.rel_rmse >= 0.0 && std::isfinite(s.wall_ms) && s.wall_ms > 0.0;
}

}  // namespace

bool modelled_scene(const std::string& scene) {
  const std::string tag = "+modelled";
  return scene.size() > tag.size() && scene.compare(scene.size() - tag.size(), tag.size(), tag) == 0;
}

namespace {
bool of_model(const std::string& scene, FrontModel model) {
  return model == FrontModel::All || modelled_scene(scene) == (model == FrontModel::Modelled);
}
}  // namespace

bool front_measures(const QualityFront& front, FrontModel model) {
  for (const FrontConfig& c : front.configs)
    for (const FrontScene& s : c.scenes)
      if (of_model(s.scene, model)) return true;
  return false;
}

void rank_front(QualityFront& front, FrontModel model) {
  if (!front_measures(front, model)) model = FrontModel::All;
  for (FrontConfig& c : front.configs) {
    double log_e = 0.0, log_t = 0.0;
    int n = 0;
    bool on_a_front = false;
    for (const FrontScene& s : c.scenes) {
      if (!of_model(s.scene, model)) continue;
      on_a_front = on_a_front || s.pareto;
      if (!usable(s)) continue;
      log_e += std::log(std::max(s.rel_rmse, 1e-12));
      log_t += std::log(s.wall_ms);
      ++n;
    }
    c.error = n ? std::exp(log_e / n) : kNaN;
    c.ms = n ? std::exp(log_t / n) : kNaN;
    c.candidate = on_a_front && c.kind != "seed" && !c.phase_hg && n > 0;
  }
  // Across scenes: drop candidates another candidate dominates in the geometric means.
  std::vector<bool> dominated(front.configs.size(), false);
  for (std::size_t i = 0; i < front.configs.size(); ++i) {
    const FrontConfig& a = front.configs[i];
    if (!a.candidate) continue;
    for (const FrontConfig& b : front.configs) {
      if (&a == &b || !b.candidate) continue;
      if (b.ms <= a.ms && b.error <= a.error && (b.ms < a.ms || b.error < a.error)) dominated[i] = true;
    }
  }
  for (std::size_t i = 0; i < front.configs.size(); ++i)
    front.configs[i].candidate = front.configs[i].candidate && !dominated[i];
  std::stable_sort(front.configs.begin(), front.configs.end(),
                   [](const FrontConfig& a, const FrontConfig& b) {
                     const bool fa = std::isfinite(a.error), fb = std::isfinite(b.error);
                     if (fa != fb) return fa;  // unmeasurable errors last
                     if (fa && a.error != b.error) return a.error < b.error;
                     if (a.ms != b.ms && std::isfinite(a.ms) && std::isfinite(b.ms)) return a.ms < b.ms;
                     return a.name < b.name;
                   });
}

std::vector<FrontConfig> front_candidates(const QualityFront& front) {
  std::vector<FrontConfig> out;
  for (const FrontConfig& c : front.configs) {
    if (c.candidate) out.push_back(c);
  }
  return out;
}

std::vector<FrontConfig> preset_ladder() {
  std::vector<FrontConfig> out;
  const auto& presets = quality_presets();
  for (auto it = presets.rbegin(); it != presets.rend(); ++it) {
    FrontConfig c;
    c.name = it->name, c.kind = "preset";
    c.knobs = it->knobs;
    c.error = c.ms = kNaN;
    c.candidate = true;
    out.push_back(c);
  }
  return out;
}

std::string front_to_json(const QualityFront& front) {
  ojson root = ojson::object();
  root["format"] = kFormat;
  root["version"] = QualityFront::kVersion;
  root["machine"] = front.machine;
  root["width"] = front.width;
  root["height"] = front.height;
  root["command"] = front.command;
  // NaN is not JSON: an unmeasurable figure is written as null.
  auto num = [](double v) { return std::isfinite(v) ? ojson(v) : ojson(nullptr); };
  ojson configs = ojson::array();
  for (const FrontConfig& c : front.configs) {
    ojson scenes = ojson::array();
    for (const FrontScene& s : c.scenes) {
      scenes.push_back({{"scene", s.scene},
                        {"view_step_m", s.view_step_m},
                        {"wall_ms", num(s.wall_ms)},
                        {"rel_rmse", num(s.rel_rmse)},
                        {"pareto", s.pareto}});
    }
    ojson config = {{"name", c.name}, {"kind", c.kind}};
    for_each_quality_knob(c.knobs, [&](const KnobRow& k, const auto& v) { config[k.row.key] = v; });
    config["phase_hg"] = c.phase_hg;
    config["error_geomean"] = num(c.error);
    config["ms_geomean"] = num(c.ms);
    config["candidate"] = c.candidate;
    config["scenes"] = scenes;
    configs.push_back(config);
  }
  root["configs"] = configs;
  return root.dump(2) + "\n";
}

QualityFront front_from_json(const std::string& text, const std::string& source) {
  json root;
  try {
    // Nesting bounded while parsing (a front nests 4 deep): deep values cost stack in every walk.
    root = json::parse(text, [&](int depth, json::parse_event_t, json&) {
      if (depth > 32) throw FrontError(source + ": found values nested more than 32 levels deep, expected a quality front");
      return true;
    });
  } catch (const json::exception& e) {  // parse errors, and numbers beyond a double (out_of_range)
    std::string what = e.what();
    for (char& ch : what) ch = (ch == '\n' ? ' ' : ch);
    throw FrontError(source + ": not valid JSON: " + what);
  }
  if (!root.is_object())
    throw FrontError(source + ": found " + shown(root) + " at the top, expected a JSON object { ... }");
  const Reader r(source, root, "");
  if (r.string("format", std::string("\"") + kFormat + "\"") != kFormat) {
    r.fail("format", shown(root["format"]), std::string("\"") + kFormat + "\"");
  }
  r.integer("version", 1, QualityFront::kVersion);
  QualityFront f;
  f.machine = r.string("machine", "the renderer string of the machine that measured it");
  f.width = r.integer("width", 1, 16384);
  f.height = r.integer("height", 1, 16384);
  f.command = r.string("command");
  const json& configs = r.need("configs", "an array of configurations");
  if (!configs.is_array() || configs.empty())
    r.fail("configs", shown(configs), "a non-empty array of configurations");
  // A null figure is one that could not be measured (NaN when written).
  auto maybe_number = [](const Reader& rr, const json& obj, const char* key, const std::string& expected) {
    const auto it = obj.find(key);
    if (it != obj.end() && it->is_null()) return kNaN;
    return rr.number(key, 0.0, 1e300, expected);
  };
  for (std::size_t i = 0; i < configs.size(); ++i) {
    const std::string where = "configs[" + std::to_string(i) + "].";
    if (!configs[i].is_object()) r.fail("configs[" + std::to_string(i) + "]", shown(configs[i]), "an object");
    const Reader c(source, configs[i], where);
    FrontConfig fc;
    fc.name = c.string("name");
    fc.kind = c.string("kind", "\"sweep\", \"preset\" or \"seed\"");
    if (fc.kind != "sweep" && fc.kind != "preset" && fc.kind != "seed") {
      c.fail("kind", shown(configs[i]["kind"]), "\"sweep\", \"preset\" or \"seed\"");
    }
    for_each_quality_knob(fc.knobs, [&](const KnobRow& k, auto& v) { c.knob(k.row, v); });
    fc.phase_hg = c.boolean("phase_hg");
    fc.candidate = c.boolean("candidate");
    fc.error = maybe_number(c, configs[i], "error_geomean", "a relative error >= 0 or null");
    fc.ms = maybe_number(c, configs[i], "ms_geomean", "a time in ms >= 0 or null");
    const json& scenes = c.need("scenes", "an array of per-scene measurements");
    if (!scenes.is_array()) c.fail("scenes", shown(scenes), "an array of per-scene measurements");
    for (std::size_t k = 0; k < scenes.size(); ++k) {
      if (!scenes[k].is_object()) c.fail("scenes[" + std::to_string(k) + "]", shown(scenes[k]), "an object");
      const Reader s(source, scenes[k], where + "scenes[" + std::to_string(k) + "].");
      FrontScene fs;
      fs.scene = s.string("scene");
      fs.view_step_m = s.number("view_step_m", 0.0, 1e7, "a view step in metres 0..1e7");
      fs.wall_ms = maybe_number(s, scenes[k], "wall_ms", "a time in ms >= 0 or null");
      fs.rel_rmse = maybe_number(s, scenes[k], "rel_rmse", "a relative error >= 0 or null");
      fs.pareto = s.boolean("pareto");
      fc.scenes.push_back(fs);
    }
    f.configs.push_back(fc);
  }
  return f;
}

QualityFront load_front(const std::string& path) {
  std::string text;
  try {
    text = core::read_regular_file(path, "the quality front", 64u << 20);  // a FIFO or /dev/zero is refused, never read
  } catch (const core::InputError& e) {
    throw FrontError(e.what());
  }
  return front_from_json(text, path);
}

void save_front(const QualityFront& front, const std::string& path) {
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  std::error_code ec;
  if (!parent.empty()) std::filesystem::create_directories(parent, ec);
  const std::string text = front_to_json(front);
  write_file_atomically(path, [&](std::FILE* f) { std::fwrite(text.data(), 1, text.size(), f); });
}

void check_machine(const QualityFront& front, const std::string& machine, const std::string& source) {
  if (front.machine != machine) {
    throw FrontError(source + ": machine: found \"" + front.machine + "\", expected \"" + machine +
                     "\" (this machine; times do not carry over: run cloudviewer bench here)");
  }
}

std::string front_cache_path() {
  namespace fs = std::filesystem;
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  if (xdg && *xdg) return (fs::path(xdg) / "cloudviewer" / "quality_front.json").string();
  const char* home = std::getenv("HOME");
  if (home && *home) return (fs::path(home) / ".cache" / "cloudviewer" / "quality_front.json").string();
  return {};
}

CandidateSource budget_candidates(const std::string& front_file, const std::string& machine, FrontModel model) {
  CandidateSource out;
  auto from = [&](const std::string& path) {
    QualityFront f = load_front(path);
    check_machine(f, machine, path);
    rank_front(f, model);  // the file's order and flags are recomputed, not trusted
    out.candidates = front_candidates(f);
    if (out.candidates.empty())
      throw FrontError(
          path + ": configs: found no candidate, expected at least one configuration on a scene's front");
    std::string on;
    if (model != FrontModel::All) {
      const bool own = front_measures(f, model);
      const char* name = model == FrontModel::Modelled ? "modelled" : "data";
      on = own ? std::string(", ranked on its ") + name + " scenes"
               : std::string(", ranked on all its scenes: it measured no ") + name + " scene";
    }
    out.source = "the measured front " + path + " (" + std::to_string(out.candidates.size()) + " candidates" + on + ")";
  };
  if (!front_file.empty()) {
    from(front_file);
    return out;
  }
  const std::string cache = front_cache_path();
  if (!cache.empty() && std::filesystem::exists(cache)) {
    try {
      from(cache);
      return out;
    } catch (const FrontError& e) {
      out.warning = std::string(e.what()) + "; using the preset ladder";
    }
  }
  out.candidates = preset_ladder();
  out.source = "the preset ladder high > default > low (no measured front: run cloudviewer bench)";
  return out;
}

BudgetChoice choose_under_budget(const std::vector<FrontConfig>& cands, double budget_ms,
                                 const std::function<double(std::size_t)>& measure_ms) {
  if (cands.empty()) throw std::invalid_argument("choose_under_budget: no candidates");
  if (!(budget_ms > 0.0)) throw std::invalid_argument("choose_under_budget: the budget must be > 0 ms");
  BudgetChoice out;
  const bool predicted = std::any_of(cands.begin(), cands.end(), [](const FrontConfig& c) { return std::isfinite(c.ms); });
  if (!predicted) {
    // The preset ladder: each step more accurate costs more by construction (half the step, twice
    // the sun steps), so from the fastest up, stopping at the first that does not fit, never times
    // a candidate that cannot be chosen (the most accurate preset costs ~10x the next one).
    for (std::size_t k = cands.size(); k-- > 0;) {
      const double ms = measure_ms(k);
      out.trials.push_back({k, ms});
      if (ms > budget_ms) break;
      out.index = k, out.ms = ms, out.met = true;
    }
    if (!out.met) out.index = out.trials.front().index, out.ms = out.trials.front().ms;
    return out;
  }
  // The one that is always measured when nothing fits: the fastest the front predicts.
  std::size_t fastest = cands.size() - 1;
  for (std::size_t i = 0; i < cands.size(); ++i) {
    if (std::isfinite(cands[i].ms) && (!std::isfinite(cands[fastest].ms) || cands[i].ms < cands[fastest].ms))
      fastest = i;
  }
  double scale = kNaN;  // measured / predicted, from the last candidate measured that has a prediction
  for (std::size_t i = 0; i < cands.size(); ++i) {
    const double predicted = scale * cands[i].ms;
    if (i != fastest && std::isfinite(predicted) && predicted > 2.0 * budget_ms) continue;
    const double ms = measure_ms(i);
    out.trials.push_back({i, ms});
    if (std::isfinite(cands[i].ms) && cands[i].ms > 0.0) scale = ms / cands[i].ms;
    if (ms <= budget_ms) {
      out.index = i, out.ms = ms, out.met = true;
      return out;
    }
  }
  // None fits: the fastest measured.
  const auto best = std::min_element(out.trials.begin(), out.trials.end(),
                                     [](const BudgetTrial& a, const BudgetTrial& b) { return a.ms < b.ms; });
  out.index = best->index, out.ms = best->ms, out.met = false;
  return out;
}

std::string describe_config(const FrontConfig& c) { return describe_knobs(c.knobs); }

}  // namespace cv::bench
