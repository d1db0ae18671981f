// A sequence of the viewer's reprojected frames against full marches of the same cameras (render/
// reprojector): the reprojection test and bench_reprojection share it.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <vector>

#include "bench/standard_scenes.hpp"
#include "render/frame_renderer.hpp"
#include "render/gl.hpp"
#include "render/reprojector.hpp"

namespace cv::test_support {

inline double luminance(const glm::vec4& c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; }

inline std::vector<glm::vec4> read_rgba(GLuint tex, int w, int h) {
  std::vector<glm::vec4> out(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
  glGetTextureImage(tex, 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(out.size() * sizeof(glm::vec4)), out.data());
  return out;
}

struct Errors {
  std::vector<double> all;  // |dL| / the first frame's brightest, every pixel of every frame measured
  double mean() const {
    double s = 0.0;
    for (double e : all) s += e;
    return all.empty() ? 0.0 : s / double(all.size());
  }
  double p99() const {
    std::vector<double> v = all;
    if (v.empty()) return 0.0;
    const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(0.99 * double(v.size())));
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    return v[k];
  }
};

enum class Mode { Reproject, NoClamp, SpatialOnly, NoWind };

// Runs `frames` frames of the scene with the camera moved by `step` before each (frame 0 as it is),
// reprojected as `mode` says, and measures each frame from `skip` on against the full march, in
// units of the first frame's brightest pixel.
// `before(k)` runs before frame k marches and says whether the medium changed there; `times`, when
// given, receives each frame's sparse march and resolve (ms, after glFinish).
inline Errors run_sequence(render::FrameRenderer& fr, render::Reprojector& rp, const core::FrameSpec& base, double r0_m, int frames, int skip,
                    const std::function<void(core::Camera&)>& step, Mode mode,
                    const std::function<bool(int)>& before = [](int) { return false; }, std::vector<double>* times = nullptr) {
  core::FrameSpec full = base;
  full.march_camera = full.camera;
  full.accumulate = 1;
  const int w = full.camera.width, h = full.camera.height;
  GLuint out = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &out);
  glTextureStorage2D(out, 1, GL_RGBA32F, w, h);
  rp.reset();
  rp.set_clamp(mode != Mode::NoClamp);
  rp.set_wind_motion(mode != Mode::NoWind);
  Errors e;
  double peak = 0.0;
  for (int k = 0; k < frames; ++k) {
    if (k > 0) step(full.camera);
    const bool changed = before(k);
    full.march_camera = full.camera;
    glFinish();
    const auto t0 = std::chrono::steady_clock::now();
    core::FrameSpec sparse = full;
    sparse.march_camera = render::Reprojector::sparse_camera(full.camera, k);
    fr.march_into(rp.sparse_target(full.camera), sparse, 0);
    if (mode == Mode::SpatialOnly) rp.reset();
    rp.resolve(fr.raymarcher().cloud_depth_texture(), full.camera, k, changed, r0_m, out, fr.volume());
    if (times) {  // the sparse march and the resolve, as the viewer pays them per frame
      glFinish();
      times->push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    }
    const std::vector<glm::vec4> got = read_rgba(out, w, h);
    if (k == 0) {  // the scale of the errors: the first frame's brightest pixel, fully marched
      for (const glm::vec4& c : fr.render(full)) peak = std::max(peak, luminance(c));
    }
    if (k < skip || !(peak > 0.0)) continue;
    const std::vector<glm::vec4> want = fr.render(full);
    for (std::size_t i = 0; i < want.size(); ++i) e.all.push_back(std::abs(luminance(got[i]) - luminance(want[i])) / peak);
  }
  glDeleteTextures(1, &out);
  return e;
}

}  // namespace cv::test_support
