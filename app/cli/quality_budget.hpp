// Quality by budget in the commands: `bench` writes the measured front (quality_front.json, and a
// per-user cached copy), `render --budget-ms` measures the candidates here and picks one.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "bench/quality_front.hpp"
#include "bench_report.hpp"
#include "frame/camera.hpp"
#include "frame/march_stats.hpp"
#include "frame/sun.hpp"
#include "settings/march_settings.hpp"
#include "scene/scene.hpp"

namespace cv::render {
class GpuRaymarcher;
}

namespace cv::cli {

// Writes <out_dir>/quality_front.json from the bench rows (mark_pareto done) and, when
// `cache` is true, copies it to bench::front_cache_path(). dz_by_scene: each scene's vertical
// grid spacing in metres (view steps are stored as multiples of it). Prints where it wrote.
void write_quality_front(const std::string& out_dir, const std::vector<BenchRow>& rows,
                         const std::map<std::string, double>& dz_by_scene, const std::string& machine,
                         int width, int height, const std::string& command, bool cache);

// Sets the quality knobs of `render` to the candidate's on a grid of vertical spacing dz_m.
void apply_front_config(const bench::FrontConfig& c, double dz_m, core::RenderSettings& render);

// `render --budget-ms`: the candidates (--front FILE, the cache or the preset ladder), each rendered
// once here at the camera's size (or a calibration size with the time scaled by pixel count) with
// `base` as the rest of the march settings, and the most accurate within budget_ms applied to
// `render`. Prints the source, each trial and one line with the choice. A bad --front file throws
// UsageError.
void choose_by_budget(render::GpuRaymarcher& gpu, const core::Camera& cam, const core::Sun& sun,
                      const core::MarchSettings& base, double dz_m, double budget_ms,
                      const std::string& front_file, const std::string& machine,
                      core::RenderSettings& render);

}  // namespace cv::cli
