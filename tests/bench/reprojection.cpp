// bench_reprojection: the viewer's temporal reprojection on a file at a size, the camera orbiting as
// `view --orbit PX` drags it: per frame the sparse march and the resolve (ms), against a full march
// of the same camera (ms), and the reprojected frames' error against the full marches (mean and
// 99th percentile of |dL| / the first frame's brightest), with the clamp, without it and without the
// history. Not a test: docs/BENCHMARKS.md records what it prints.
//   bench_reprojection FILE [WxH] [FRAMES] [PX] [QUALITY]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "importer.hpp"
#include "render/context.hpp"
#include "render/frame_renderer.hpp"
#include "scene/quality.hpp"
#include "support/reprojection_sequence.hpp"
#include "viewer/camera_controller.hpp"

int main(int argc, char** argv) {
  using namespace cv;
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_reprojection FILE [WxH] [FRAMES] [PX] [QUALITY]\n");
    return 2;
  }
  int w = 640, h = 360;
  if (argc > 2 && std::sscanf(argv[2], "%dx%d", &w, &h) != 2) return 2;
  const int frames = argc > 3 ? std::atoi(argv[3]) : 48;
  const double px = argc > 4 ? std::atof(argv[4]) : 4.0;
  const std::string quality = argc > 5 ? argv[5] : "default";
  auto ctx = render::make_headless_context();
  core::CloudVolume vol = importers::import_file(argv[1]);
  core::Scene scene;
  scene.data.path = argv[1];
  scene.width = render::Reprojector::whole_blocks(w), scene.height = render::Reprojector::whole_blocks(h);
  scene.sun.mode = core::SunMode::LocalNoon;
  core::apply_quality(quality, scene.render);
  const render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  render::FrameRenderer fr(loader);
  fr.use_volume(std::make_shared<const core::PreparedVolume>(core::prepare_volume(vol.grid, vol.step(0))));
  core::FrameSpec base = render::resolve_frame(scene, vol);
  const double r0 = vol.grid.earth_radius_m;
  auto orbit = [&](core::Camera& c) { viewer::orbit(c, px, 0.0, r0); };
  render::Reprojector rp(loader);
  // The full march's time per frame, as the viewer without reprojection pays it.
  std::vector<double> full_ms;
  {
    core::FrameSpec f = base;
    f.march_camera = f.camera;
    f.accumulate = 1;
    GLuint target = 0;
    glCreateTextures(GL_TEXTURE_2D, 1, &target);
    glTextureStorage2D(target, 1, GL_RGBA32F, f.camera.width, f.camera.height);
    for (int k = 0; k < 4; ++k) {
      glFinish();
      const auto t0 = std::chrono::steady_clock::now();
      fr.march_into(target, f, 0);
      glFinish();
      if (k > 0) full_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    }
    glDeleteTextures(1, &target);
  }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
  };
  std::printf("%s at %dx%d, quality %s, the camera orbiting %.1f px per frame, %d frames (measured from frame 16):\n", argv[1],
              base.camera.width, base.camera.height, quality.c_str(), px, frames);
  std::printf("  full march: %.1f ms per frame (median of 3)\n", median(full_ms));
  for (test_support::Mode mode : {test_support::Mode::Reproject, test_support::Mode::NoClamp, test_support::Mode::SpatialOnly}) {
    std::vector<double> times;
    const test_support::Errors e = test_support::run_sequence(fr, rp, base, r0, frames, 16, orbit, mode, [](int) { return false; }, &times);
    std::vector<double> later(times.begin() + std::min<std::ptrdiff_t>(1, static_cast<std::ptrdiff_t>(times.size())), times.end());
    std::printf("  %-34s sparse march + resolve %.1f ms per frame (median), error mean %.4f, 99th percentile %.4f\n",
                mode == test_support::Mode::Reproject  ? "reprojected (clamp after a move):"
                : mode == test_support::Mode::NoClamp ? "reprojected without the clamp:"
                                                       : "the new samples' blend alone:",
                median(later), e.mean(), e.p99());
  }
  return 0;
}
