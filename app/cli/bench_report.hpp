// What `cloudviewer bench` measured, and how it writes it: results.csv, summary.md (per scene a
// table by time with the Pareto front, and the ratios against the seed documents' presets) and
// the error-against-time plots.
#pragma once

#include <string>
#include <vector>

#include "bench/metrics.hpp"
#include "settings/quality_knobs.hpp"

namespace cv::cli {

// Which family a configuration belongs to: our sweep, our named presets, a seed document's preset,
// or the GPU path tracer (`--quality reference`) at a number of samples per pixel. The path tracer's
// rows are measured and plotted beside the others, but they are not march settings: they stay off
// the Pareto front of candidates that `render --budget-ms` and the viewer's frame budget choose from.
enum class ConfigKind { Sweep = 0, Preset = 1, Seed = 2, PathTracer = 3 };

// The kind as results.csv, summary.md and quality_front.json name it.
const char* kind_name(ConfigKind k);

struct BenchRow {
  std::string scene, config, description;
  ConfigKind kind = ConfigKind::Sweep;
  double view_step_m = 0.0;  // marched with, on this scene's grid
  // The quality knobs (core/settings/quality_knobs.def), view_step_dz this scene's step / dz.
  core::QualityKnobs knobs;
  bool phase_hg = false;
  int spp = 0;  // the path tracer's samples per pixel (ConfigKind::PathTracer), else 0
  double own_rel_stderr = 0.0;  // the path tracer's own mean relative standard error (its noise), else 0
  double wall_ms = 0.0;  // median over repeats, per output image (all its accumulated frames)
  double gpu_ms = 0.0;   // median GL_TIME_ELAPSED; 0 when the driver reports none
  bench::ImageError err;
  bool pareto = false;
  std::string error_image;  // relative to the output folder
};

struct SceneReference {
  std::string scene, file;
  int spp = 0;         // samples per pixel it holds now
  double mean_rel_stderr = 0.0;
  bool cached = false;
  double seconds = 0.0;  // to render the samples added in this run
  int cached_spp = 0;    // samples per pixel read from the cache
};

// Marks BenchRow::pareto on each scene's rows (by wall time and relative RMSE), over the march
// configurations (the path tracer's rows are never marked).
void mark_pareto(std::vector<BenchRow>& rows);

// The CSV header line (no newline), shared with the smoke test's expectation.
const char* results_csv_header();
void write_results_csv(const std::string& path, const std::vector<BenchRow>& rows, const std::vector<SceneReference>& refs);
void write_summary_md(const std::string& path, const std::vector<BenchRow>& rows, const std::vector<SceneReference>& refs,
                      const std::string& command, const std::string& machine);
// One PNG per scene: <dir>/<scene>_pareto.png; returns the file names.
std::vector<std::string> write_plots(const std::string& dir, const std::vector<BenchRow>& rows);

}  // namespace cv::cli
