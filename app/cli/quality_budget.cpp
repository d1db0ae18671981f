// The front file from `bench`'s rows, and the budget choice of `render`: each candidate rendered
// once on this scene at this size, the most accurate that fits kept.
#include "quality_budget.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>

#include "cli_common.hpp"
#include "render/raymarcher.hpp"
#include "scene/quality.hpp"

namespace cv::cli {
namespace {

namespace fs = std::filesystem;
using bench::FrontConfig;

// Calibration frames larger than this many pixels are marched at a reduced size of about this many
// pixels, and their time scaled by the pixel count (march time grows with the pixels marched; a
// 960x540 candidate is then timed in a fraction of its own frame time).
constexpr double kCalibrationPixels = 320.0 * 180.0;

}  // namespace

void write_quality_front(const std::string& out_dir, const std::vector<BenchRow>& rows,
                         const std::map<std::string, double>& dz_by_scene, const std::string& machine,
                         int width, int height, const std::string& command, bool cache) {
  bench::QualityFront front;
  front.machine = machine, front.width = width, front.height = height, front.command = command;
  std::map<std::string, std::size_t> index;  // config name -> position in front.configs (first-seen order)
  std::map<std::string, std::pair<double, int>>
      log_ratio;  // sum of log(view step / dz) and count, per config
  for (const BenchRow& r : rows) {
    if (r.kind == ConfigKind::PathTracer) continue;  // not march settings: nothing a budget could apply
    auto [it, fresh] = index.emplace(r.config, front.configs.size());
    if (fresh) {
      FrontConfig c;
      c.name = r.config, c.kind = kind_name(r.kind);
      c.knobs = r.knobs, c.phase_hg = r.phase_hg;
      c.knobs.view_step_dz = 1.0, c.knobs.view_step_min_m = 0.0;  // below: over all its scenes
      front.configs.push_back(c);
    }
    FrontConfig& c = front.configs[it->second];
    c.scenes.push_back({r.scene, r.view_step_m, r.wall_ms, r.err.rel_rmse, r.pareto});
    const auto dz = dz_by_scene.find(r.scene);
    if (dz != dz_by_scene.end() && dz->second > 0.0 && r.view_step_m > 0.0) {
      auto& lr = log_ratio[r.config];
      lr.first += std::log(r.view_step_m / dz->second);
      ++lr.second;
    }
  }
  for (FrontConfig& c : front.configs) {
    const core::QualityPreset* p = c.kind == "preset" ? core::find_quality(c.name) : nullptr;
    if (p) {  // a preset's own definition, floor included
      c.knobs.view_step_dz = p->knobs.view_step_dz, c.knobs.view_step_min_m = p->knobs.view_step_min_m;
    } else if (const auto lr = log_ratio.find(c.name); lr != log_ratio.end() && lr->second.second > 0) {
      c.knobs.view_step_dz = std::exp(lr->second.first / lr->second.second);
    }
  }
  bench::rank_front(front);
  const std::string path = (fs::path(out_dir) / "quality_front.json").string();
  bench::save_front(front, path);
  std::printf("wrote %s (%zu configurations, %zu candidates for --budget-ms)\n", path.c_str(),
              front.configs.size(), bench::front_candidates(front).size());
  if (!cache) return;
  const std::string cached = bench::front_cache_path();
  if (cached.empty()) {
    std::printf("not cached: neither XDG_CACHE_HOME nor HOME is set\n");
    return;
  }
  try {
    bench::save_front(front, cached);
    std::printf(
        "cached it as %s (render --budget-ms and the viewer's frame budget use it; --no-cache to skip)\n",
        cached.c_str());
  } catch (const std::exception& e) {
    std::printf("not cached: %s\n", e.what());
  }
}

void apply_front_config(const FrontConfig& c, double dz_m, core::RenderSettings& render) {
  render.quality = c.kind == "preset" && core::find_quality(c.name) ? c.name : "custom";
  core::apply_knobs(c.knobs, dz_m, render);
}

void choose_by_budget(render::GpuRaymarcher& gpu, const core::Camera& cam, const core::Sun& sun,
                      const core::MarchSettings& base, double dz_m, double budget_ms,
                      const std::string& front_file, const std::string& machine,
                      core::RenderSettings& render) {
  bench::CandidateSource src;
  try {
    // Ranked on the measurements of the cloud model this frame draws, where the front has them.
    src = bench::budget_candidates(front_file, machine,
                                   base.medium.modelled ? bench::FrontModel::Modelled : bench::FrontModel::Data);
  } catch (const bench::FrontError& e) {
    throw UsageError{std::string("cloudviewer render: --front: ") + e.what()};
  }
  if (!src.warning.empty()) std::printf("budget: %s\n", src.warning.c_str());
  std::printf("budget %.4g ms: candidates from %s\n", budget_ms, src.source.c_str());
  std::set<std::string> warm;  // program variants compiled already (compiling is not frame time)
  using clock = std::chrono::steady_clock;
  auto measure = [&](std::size_t i) {
    const FrontConfig& c = src.candidates[i];
    core::RenderSettings knobbed;  // base with the candidate's knobs
    knobbed.march = base;
    core::apply_knobs(c.knobs, dz_m, knobbed);
    core::MarchSettings m = knobbed.march;
    m.per_frame.frame = c.knobs.accumulate > 1 ? 0 : -1;
    const double mw = std::max(1.0, std::round(cam.width * c.knobs.resolution_scale));
    const double mh = std::max(1.0, std::round(cam.height * c.knobs.resolution_scale));
    const double shrink = std::min(1.0, std::sqrt(kCalibrationPixels / (mw * mh)));
    core::Camera cal = cam;
    cal.width = std::max(1, static_cast<int>(std::lround(mw * shrink)));
    cal.height = std::max(1, static_cast<int>(std::lround(mh * shrink)));
    const std::string variant = std::to_string(kernel::MarchVariant::of(m).key());
    if (warm.insert(variant).second) gpu.render(cal, sun, m);
    const auto t0 = clock::now();
    gpu.render(cal, sun, m);
    const double frame_ms = std::chrono::duration<double, std::milli>(clock::now() - t0).count();
    const double ms = frame_ms * (mw * mh) / (static_cast<double>(cal.width) * cal.height) * c.knobs.accumulate;
    std::printf("budget: %-24s %9.1f ms", c.name.c_str(), ms);
    if (cal.width != static_cast<int>(mw) || cal.height != static_cast<int>(mh)) {
      std::printf("  (one frame at %dx%d, scaled by pixel count to %.0fx%.0f", cal.width, cal.height, mw, mh);
    } else {
      std::printf("  (one frame at %.0fx%.0f", mw, mh);
    }
    if (c.knobs.accumulate > 1)
      std::printf(", times %d frames)\n", c.knobs.accumulate);
    else
      std::printf(")\n");
    std::fflush(stdout);
    return ms;
  };
  const auto t_choice = clock::now();
  const bench::BudgetChoice choice =
      bench::choose_under_budget(src.candidates, budget_ms, measure);
  std::printf("budget: %zu of %zu candidate(s) timed in %.2f s\n", choice.trials.size(),
              src.candidates.size(), std::chrono::duration<double>(clock::now() - t_choice).count());
  const FrontConfig& c = src.candidates[choice.index];
  apply_front_config(c, dz_m, render);
  if (choice.met) {
    std::printf("budget %.4g ms: chose %s (%s), measured %.1f ms\n", budget_ms, c.name.c_str(),
                bench::describe_config(c).c_str(), choice.ms);
  } else {
    std::printf(
        "budget %.4g ms: chose %s (%s), measured %.1f ms: budget not met, %.1f ms (%.0f%%) over; the fastest "
        "candidate\n",
        budget_ms, c.name.c_str(), bench::describe_config(c).c_str(), choice.ms, choice.ms - budget_ms,
        100.0 * (choice.ms - budget_ms) / budget_ms);
  }
}

}  // namespace cv::cli
