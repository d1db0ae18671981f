// results.csv, summary.md and the Pareto plots of `cloudviewer bench` (see bench_report.hpp).
#include "bench_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "bench/plot.hpp"
#include "render/image_output.hpp"
#include "volume/volume_io.hpp"

namespace cv::cli {

const char* kind_name(ConfigKind k) {
  switch (k) {
    case ConfigKind::Seed: return "seed";
    case ConfigKind::Preset: return "preset";
    case ConfigKind::PathTracer: return "path_tracer";
    case ConfigKind::Sweep: break;
  }
  return "sweep";
}

namespace {

std::vector<std::string> scene_order(const std::vector<BenchRow>& rows) {
  std::vector<std::string> out;
  for (const auto& r : rows) {
    if (std::find(out.begin(), out.end(), r.scene) == out.end()) out.push_back(r.scene);
  }
  return out;
}

std::vector<const BenchRow*> rows_of(const std::vector<BenchRow>& rows, const std::string& scene) {
  std::vector<const BenchRow*> out;
  for (const auto& r : rows) {
    if (r.scene == scene) out.push_back(&r);
  }
  return out;
}

// "%.3g", or "n/a" for NaN.
std::string num(double v, const char* fmt = "%.3g") {
  if (std::isnan(v)) return "n/a";
  char b[48];
  std::snprintf(b, sizeof b, fmt, v);
  return b;
}

}  // namespace

void mark_pareto(std::vector<BenchRow>& rows) {
  for (const auto& scene : scene_order(rows)) {
    std::vector<std::size_t> idx;
    std::vector<bench::TimeError> pts;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      if (rows[i].scene != scene || rows[i].kind == ConfigKind::PathTracer) continue;
      idx.push_back(i);
      pts.push_back({rows[i].wall_ms, rows[i].err.rel_rmse});
    }
    for (std::size_t k : bench::pareto_front(pts)) rows[idx[k]].pareto = true;
  }
}

const char* results_csv_header() {
  return "scene,config,kind,view_step_m,sun_steps,octaves,accumulate,resolution_scale,liquid_phase,adaptive_steps,"
         "wall_ms,gpu_ms,rel_rmse,rel_rmse_raw,ref_noise_floor,rel_rmse_resolution,rel_bias,worst_pixel,psnr_db,pareto,ref_spp,ref_mean_rel_stderr,"
         "error_image,path_spp,path_rel_stderr";
}

void write_results_csv(const std::string& path, const std::vector<BenchRow>& rows, const std::vector<SceneReference>& refs) {
  core::write_file_atomically(path, [&](std::FILE* f) {
    std::fprintf(f, "%s\n", results_csv_header());
    for (const auto& r : rows) {
      const SceneReference* ref = nullptr;
      for (const auto& s : refs) {
        if (s.scene == r.scene) ref = &s;
      }
      std::fprintf(f, "%s,%s,%s,%.6g,%d,%d,%d,%.3g,%s,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%d,%d,%.6g,%s,%d,%.6g\n",
                   r.scene.c_str(), r.config.c_str(), kind_name(r.kind), r.view_step_m, r.knobs.sun_steps, r.knobs.octaves,
                   r.knobs.accumulate, r.knobs.resolution_scale, r.phase_hg ? "hg" : "mie", r.knobs.adaptive ? 1 : 0, r.wall_ms, r.gpu_ms,
                   r.err.rel_rmse, r.err.rel_rmse_raw, r.err.rel_noise_floor, r.err.rel_rmse_resolution, r.err.rel_bias, r.err.worst, r.err.psnr_db, r.pareto ? 1 : 0, ref ? ref->spp : 0,
                   ref ? ref->mean_rel_stderr : 0.0, r.error_image.c_str(), r.spp, r.own_rel_stderr);
    }
  });
}

void write_summary_md(const std::string& path, const std::vector<BenchRow>& rows, const std::vector<SceneReference>& refs,
                      const std::string& command, const std::string& machine) {
  core::write_file_atomically(path, [&](std::FILE* f) {
    std::fprintf(f, "# cloudviewer bench\n\nCommand: `%s`\n\nMachine: %s\n\n", command.c_str(), machine.c_str());
    const bool timing_only = refs.empty();  // --timing-only: no reference was rendered
    if (timing_only) {
      std::fprintf(f, "Frame times only (`--timing-only`): no reference, so no error, no Pareto front and no plots. For the "
                      "path tracer, `own s.e.` is its own mean relative standard error (its noise, which falls as "
                      "1/sqrt(spp)).\n\n");
    }
    std::fprintf(f,
                 "Error = luminance against a Monte Carlo reference with full multiple scattering (clouds only: no air, "
                 "no globe, no ambient light), so it includes the octave approximation's bias, not only the step "
                 "and sampling error. rel. RMSE = sqrt(mean((L - L_ref)^2 - var L_ref)) / mean L_ref: the reference's "
                 "own variance (its per-pixel standard error squared) is taken out, which leaves an unbiased estimate "
                 "of the error against the converged image; raw = without that correction; floor = sqrt(mean var "
                 "L_ref) / mean L_ref, the reference's noise: a rel. RMSE well below the floor is not resolved by this "
                 "reference (droplet clouds' Monte Carlo estimates are heavy-tailed, so their standard error can "
                 "understate the spread); \"< x\" = below x, the smallest error this reference resolves (sqrt of 2 "
                 "standard errors of the corrected mean square, from the spread over pixels). bias = mean(L - L_ref) / mean L_ref; "
                 "worst = max |L - L_ref| / max L_ref; PSNR against max L_ref. Time = wall time per output image "
                 "(all its accumulated frames, read-back included), median of the repeats. `*` = on the Pareto front "
                 "(time, rel. RMSE) of all configurations. Plots: rel. RMSE (log, vertical, decades labelled eN) "
                 "against wall ms (log, horizontal); blue = sweep, green = our presets, orange = seed presets, purple = "
                 "the GPU path tracer (`render --quality reference`, full multiple scattering) at the samples per pixel "
                 "its name gives, red = Pareto front of the march configurations. The path tracer's error is its own "
                 "noise against the reference's (its paths use another seed, so the two share no random numbers); "
                 "it is timed once, not over the repeats, and is no candidate for --budget-ms.\n\n");
    for (const auto& scene : scene_order(rows)) {
      auto list = rows_of(rows, scene);
      std::sort(list.begin(), list.end(), [](const BenchRow* a, const BenchRow* b) { return a->wall_ms < b->wall_ms; });
      std::fprintf(f, "## %s\n\n", scene.c_str());
      for (const auto& ref : refs) {
        if (ref.scene == scene) {
          const std::string origin =
              ref.cached_spp == ref.spp ? "all from the cache"
              : ref.cached_spp > 0      ? std::to_string(ref.cached_spp) + " from the cache, " +
                                         std::to_string(ref.spp - ref.cached_spp) + " added in " +
                                         num(ref.seconds, "%.1f") + " s"
                                        : "rendered in " + num(ref.seconds, "%.1f") + " s";
          std::fprintf(f, "Reference: %d samples per pixel (%s), mean relative standard error %.3g; `%s`.\n\n", ref.spp,
                       origin.c_str(), ref.mean_rel_stderr, ref.file.c_str());
        }
      }
      std::fprintf(f, "![error against time](%s_pareto.png)\n\n", scene.c_str());
      std::fprintf(f, "| | config | kind | step m | sun | oct | acc | scale | phase | wall ms | GPU ms | rel. RMSE | raw | floor | bias | worst | PSNR dB |\n");
      std::fprintf(f, "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
      for (const BenchRow* r : list) {
        const bool pt = r->kind == ConfigKind::PathTracer;
        std::fprintf(f, "| %s | %s | %s | %s | %s | %s | %s | %s | %s | %.4g | %s | %s | %s | %s | %s | %s | %s |\n",
                     r->pareto ? "*" : "", r->config.c_str(), kind_name(r->kind),
                     pt ? "-" : (num(r->view_step_m, "%.4g") + (r->knobs.adaptive ? " adapt." : "")).c_str(),
                     pt ? "-" : std::to_string(r->knobs.sun_steps).c_str(), pt ? "-" : std::to_string(r->knobs.octaves).c_str(),
                     pt ? (std::to_string(r->spp) + " spp").c_str() : std::to_string(r->knobs.accumulate).c_str(),
                     pt ? "-" : num(r->knobs.resolution_scale, "%.2g").c_str(), r->phase_hg ? "HG" : "Mie", r->wall_ms,
                     r->gpu_ms > 0 ? num(r->gpu_ms, "%.4g").c_str() : "-",
                     r->err.rel_rmse < r->err.rel_rmse_resolution ? ("< " + num(r->err.rel_rmse_resolution)).c_str()
                                                                   : num(r->err.rel_rmse).c_str(),
                     num(r->err.rel_rmse_raw).c_str(), num(r->err.rel_noise_floor).c_str(), num(r->err.rel_bias, "%+.3g").c_str(), num(r->err.worst).c_str(), num(r->err.psnr_db, "%.1f").c_str());
      }
      if (timing_only) {
        std::fprintf(f, "\n| path tracer | spp | wall ms | own s.e. |\n|---|---|---|---|\n");
        for (const BenchRow* r : list) {
          if (r->kind == ConfigKind::PathTracer) std::fprintf(f, "| %s | %d | %.4g | %s |\n", r->config.c_str(), r->spp, r->wall_ms, num(r->own_rel_stderr).c_str());
        }
        std::fprintf(f, "\n");
        continue;
      }
      // Ratios: our configurations' own front (sweep and presets, no seed) interpolated in log-log.
      std::vector<bench::TimeError> ours_pts;
      const BenchRow* def = nullptr;
      for (const BenchRow* r : list) {
        if (r->kind == ConfigKind::Sweep || r->kind == ConfigKind::Preset) ours_pts.push_back({r->wall_ms, r->err.rel_rmse});
        if (r->config == "default") def = r;
      }
      std::vector<bench::TimeError> front;
      for (std::size_t k : bench::pareto_front(ours_pts)) front.push_back(ours_pts[k]);
      std::fprintf(f,
                   "\nAgainst the seed presets. \"Our front\" = the Pareto front of our sweep and presets only; between "
                   "its measured points time and error are interpolated linearly in log-log, never extrapolated (n/a: "
                   "outside the measured range; at or above the front's fastest point's error the fastest point's time "
                   "is taken, an upper bound). The default preset's own ratios use its single measured point.\n\n");
      std::fprintf(f, "| seed preset | its ms | its rel. RMSE | our front's time to its error (ratio) | our front's error at its time (ratio) | default: time ratio | default: error ratio |\n");
      std::fprintf(f, "|---|---|---|---|---|---|---|\n");
      for (const BenchRow* r : list) {
        if (r->kind != ConfigKind::Seed) continue;
        if (r->err.rel_rmse < r->err.rel_rmse_resolution) {
          // Its error is not told from zero by this reference: any ratio to it would compare noise.
          std::fprintf(f, "| %s | %.4g | < %s | not resolved: a reference with more samples is needed | | | |\n",
                       r->config.c_str(), r->wall_ms, num(r->err.rel_rmse_resolution).c_str());
          continue;
        }
        const double t = bench::front_time_for_error(front, r->err.rel_rmse);
        const double e = bench::front_error_at_time(front, r->wall_ms);
        std::fprintf(f, "| %s | %.4g | %s | %s ms (%s) | %s (%s) | %s | %s |\n", r->config.c_str(), r->wall_ms,
                     num(r->err.rel_rmse).c_str(), num(t, "%.4g").c_str(), num(t / r->wall_ms).c_str(), num(e).c_str(),
                     num(e / r->err.rel_rmse).c_str(), def ? num(def->wall_ms / r->wall_ms).c_str() : "n/a",
                     def ? num(def->err.rel_rmse / r->err.rel_rmse).c_str() : "n/a");
      }
      std::fprintf(f, "\n");
    }
  });
}

std::vector<std::string> write_plots(const std::string& dir, const std::vector<BenchRow>& rows) {
  std::vector<std::string> out;
  for (const auto& scene : scene_order(rows)) {
    std::vector<bench::PlotPoint> pts;
    std::vector<bench::TimeError> te;
    std::vector<std::size_t> te_at;  // te[k] is pts[te_at[k]]
    for (const BenchRow* r : rows_of(rows, scene)) {
      pts.push_back({{r->wall_ms, r->err.rel_rmse}, static_cast<int>(r->kind)});
      if (r->kind == ConfigKind::PathTracer) continue;  // the front is the march configurations'
      te.push_back(pts.back().p);
      te_at.push_back(pts.size() - 1);
    }
    std::vector<std::size_t> front;
    for (std::size_t k : bench::pareto_front(te)) front.push_back(te_at[k]);
    const auto img = bench::plot_error_vs_time(pts, front, 320, 240);
    const std::string name = scene + "_pareto.png";
    render::write_png(dir + "/" + name, img.width, img.height, img.rgb);
    out.push_back(name);
  }
  return out;
}

}  // namespace cv::cli
