// Benchmark (not a test): the multiple-scattering models against the Monte Carlo reference on the
// standard scenes, clouds only, with the CPU kernel (the GPU runs the same kernel). For each scene:
// the reference's mean luminance and its noise, then per model (the octave sum, the two-stream
// source with its diffuse light linear in angle, and shaped by the slab tables) the image-mean bias
// and the noise-corrected relative RMSE (app/bench/metrics image_error), and the source's build time
// (with the slab's depths and shares, as the default builds it). usage: bench_ms_model [--size WxH] [--spp N] [--max-bounces N] [--rows] [SCENE...]
// --max-bounces 1 compares single scattering alone (the Monte Carlo cut at one event against the
// octave sum with one octave; the two-stream columns then show their single-scattering term with the
// forward peak's light kept in the beam, and their diffuse term); --rows prints each image row's mean
// luminance (top row first) for the reference and the models, to see where in a view they differ.
// --reference-dir DIR keeps the references in DIR with their sums (app/bench/reference_cache, the
// files `cloudviewer bench --out DIR` keeps): a later run reads them, and a larger --spp extends them.
// --ground-albedo A draws the globe under the clouds (still no air and no sky light) as a Lambertian
// ground of albedo A, in the reference (its paths bounce off it) and the march alike; references
// with a ground are not kept in --reference-dir (they would be taken for the clouds-only ones).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench/bench_args.hpp"
#include "bench/metrics.hpp"
#include "bench/reference_cache.hpp"
#include "bench/standard_scenes.hpp"
#include "geo/geodesy.hpp"
#include "kernel/ms_source.hpp"
#include "reference/monte_carlo.hpp"
#include "reference/raymarcher.hpp"
#include "volume/grid_mean.hpp"

int main(int argc, char** argv) {
  int w = 32, h = 18, spp = 256, max_bounces = 0;
  bool rows = false;
  std::string ref_dir;
  std::vector<double> grounds{0.0};
  std::vector<std::string> scenes;
  namespace ba = cv::bench_args;
  const int code = ba::parse("bench_ms_model",
                             "usage: bench_ms_model [--size WxH] [--spp N] [--max-bounces N] [--rows] [--reference-dir DIR] [--ground-albedo A]\n"
                             "         [SCENE...]\n"
                             "  octave sum and two-stream source against the Monte Carlo reference, clouds only\n"
                             "  --max-bounces N  cut the reference's paths at N scattering events (1: single scattering,\n"
                             "                   against one octave)\n"
                             "  --rows           print each image row's mean luminance: reference, octaves, linear, slab\n"
                             "  --reference-dir DIR  read the references from DIR and save them there with their sums\n"
                             "                   (as `cloudviewer bench --out DIR`): a larger --spp extends a saved one\n"
                             "  --ground-albedo A  a Lambertian ground of albedo A under the clouds (no air), in both\n",
                             argc, argv,
                             {ba::size("--size", w, h), ba::integer("--spp", spp), ba::integer("--max-bounces", max_bounces),
                              ba::flag("--rows", rows), ba::folder("--reference-dir", ref_dir),
                              ba::numbers("--ground-albedo", grounds)},
                             &scenes);
  if (code >= 0) return code;
  if (grounds.size() != 1 || !(grounds[0] >= 0.0 && grounds[0] < 1.0)) {
    std::fprintf(stderr, "bench_ms_model: --ground-albedo: expected one albedo in 0..1 (below 1)\n");
    return 2;
  }
  const double ground = grounds[0];
  if (ground > 0.0 && !ref_dir.empty()) {
    std::fprintf(stderr, "bench_ms_model: --ground-albedo: found it with --reference-dir, expected one or the other (the saved references are clouds only)\n");
    return 2;
  }
  if (scenes.empty()) {
    for (const auto& n : cv::bench::standard_scene_names()) if (n != "clear_sky") scenes.push_back(n);
  }
  using clock = std::chrono::steady_clock;
  std::printf("%-14s %10s %7s | %-18s | %-18s | %-18s | %s\n", "scene", "MC lum", "noise", "octaves: bias rmse",
              "linear: bias rmse", "slab: bias rmse", "source ms");
  for (const std::string& name : scenes) {
    cv::bench::StandardScene sc;
    try {
      sc = cv::bench::standard_scene(name, w, h);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "bench_ms_model: %s\n", e.what());
      return 2;
    }
    const cv::core::GridMeanExtinction ext = cv::core::grid_mean_extinction(sc.grid, sc.data);
    cv::core::MarchSettings m = sc.march;
    m.features.atmosphere = m.features.globe = false;
    m.medium.ambient = 0.0, m.medium.noise_amount = 0.0;
    if (ground > 0.0) {
      m.features.globe = true;
      m.medium.ground_texture = "none";
      m.medium.ground_albedo = glm::dvec3(ground);
    }
    // The march renders one frame through pixel centres: the reference takes the same rays (as
    // `bench` does), so the error is the transport's, not a box filter's against point samples.
    m.quality.anti_alias = false;
    if (!(m.medium.droplet_diameter_um > 0.0)) m.medium.droplet_diameter_um = 20.0;
    cv::core::MonteCarloSettings mc;
    if (max_bounces > 0) mc.max_bounces = max_bounces;
    if (max_bounces == 1) m.quality.octaves = 1;
    const cv::core::MonteCarloImage img =
        ref_dir.empty() ? cv::core::render_monte_carlo(sc.grid, ext, sc.camera, sc.sun, m, mc, spp)
                        : cv::bench::extend_reference(ref_dir, name, sc, ext, m, mc, spp, 0.0, nullptr, stderr).img;
    const std::vector<glm::dvec3> ref = img.radiance();
    const std::vector<double> var = img.luminance_variance();
    double lum = 0.0;
    for (std::size_t i = 0; i < ref.size(); ++i) lum += img.luminance(i);
    std::printf("%-14s %10.4g %6.1f%% |", name.c_str(), lum / ref.size(), 100.0 * img.image_mean_relative_error());
    std::vector<std::vector<glm::dvec3>> images;
    // The octave sum, the two-stream source with its diffuse light linear in angle, and shaped by
    // the slab tables.
    for (int model : {0, 1, 2}) {
      cv::core::MarchSettings mm = m;
      mm.medium.ms_two_stream = model > 0;
      mm.medium.ms_slab = model == 2;
      const cv::core::ReferenceImage r = cv::core::render_reference(sc.grid, ext, sc.camera, sc.sun, mm);
      const cv::bench::ImageError e = cv::bench::image_error(r.radiance, ref, var);
      std::printf(" %+7.1f%% %7.1f%% |", 100.0 * e.rel_bias, 100.0 * e.rel_rmse);
      images.push_back(r.radiance);
    }
    // The source's build for the scene's own sun (the subsolar point's direction), the least of
    // three builds.
    const auto prepared = cv::core::prepare_volume(sc.grid, ext);
    const glm::dvec3 to_sun = glm::normalize(cv::geo::sphere_to_ecef({sc.sun.subsolar_lat_deg, sc.sun.subsolar_lon_deg, 0.0}, 1.0));
    double least = 1e30;
    for (int rep = 0; rep < 3; ++rep) {
      const auto t0 = clock::now();
      const cv::core::MsSource src = cv::core::build_ms_source(prepared, cv::core::ms_source_key(m, to_sun));
      least = std::min(least, std::chrono::duration<double, std::milli>(clock::now() - t0).count());
      (void)src;
    }
    std::printf(" %.2f\n", least);
    if (rows) {
      auto lum = [](const glm::dvec3& c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; };
      for (int y = 0; y < h; ++y) {
        double a = 0.0, m3[3] = {0.0, 0.0, 0.0};
        for (int x = 0; x < w; ++x) {
          const std::size_t i = static_cast<std::size_t>(y) * w + x;
          a += lum(ref[i]);
          for (int k = 0; k < 3; ++k) m3[k] += lum(images[static_cast<std::size_t>(k)][i]);
        }
        auto rel = [&](double v) { return a > 0.0 ? 100.0 * (v / a - 1.0) : 0.0; };
        std::printf("  row %3d: reference %10.4g  octaves %10.4g (%+6.1f%%)  linear %10.4g (%+6.1f%%)  slab %10.4g (%+6.1f%%)\n", y, a / w,
                    m3[0] / w, rel(m3[0]), m3[1] / w, rel(m3[1]), m3[2] / w, rel(m3[2]));
      }
    }
    std::fflush(stdout);
  }
  return 0;
}
