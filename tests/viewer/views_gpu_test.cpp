// Several views on the GPU (issue 17: "swipe and grid give the same pixels as the single views for
// their regions"): two sources on different grids (two standard scenes), composed by the viewer's
// compose_views in a grid of 2, a grid of 4 and a swipe, against each view marched and drawn alone
// by a fresh renderer and presenter at its own size. Tolerance: none (every 8-bit value equal): a
// region is the same march of the same camera and settings, and the same draw, whose pixels come
// from gl_FragCoord less the viewport's origin; nothing is blended, so any difference is a bug
// (an offset viewport, a clip in the wrong place, state left from another view).
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "bench/standard_scenes.hpp"
#include "kernel/prepared_volume.hpp"
#include "render/context.hpp"
#include "render/frame_renderer.hpp"
#include "render/presenter.hpp"
#include "viewer/view_compose.hpp"

namespace {
using namespace cv;
using viewer::ViewLayout;
using viewer::ViewRect;

constexpr int kW = 64, kH = 36;

class ViewsGpu : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { ctx_ = render::make_headless_context().release(); }
  static void TearDownTestSuite() {
    delete ctx_;
    ctx_ = nullptr;
  }
  static render::GlContext* ctx_;
  render::ShaderLoader loader_{{render::ShaderLoader::default_shader_dir()}};
};
render::GlContext* ViewsGpu::ctx_ = nullptr;

// A view: a source (a standard scene, prepared once and shared by the views that show it) and a camera.
struct Source {
  bench::StandardScene scene;
  std::shared_ptr<const core::PreparedVolume> volume;
  explicit Source(const std::string& name) : scene(bench::standard_scene(name, kW, kH)) {
    volume = std::make_shared<const core::PreparedVolume>(core::prepare_volume(scene.grid, scene.data));
  }
};

struct View {
  const Source* source;
  double heading_offset_deg = 0.0;
};

// The view's frame at an output of w x h, marched at `scale` of it.
core::FrameSpec frame_of(const View& v, int w, int h, double scale) {
  core::FrameSpec f;
  f.camera = v.source->scene.camera;
  f.camera.heading_deg += v.heading_offset_deg;
  f.camera.width = w, f.camera.height = h;
  f.march_camera = f.camera;
  core::march_size(w, h, scale, f.march_camera.width, f.march_camera.height);
  f.sun = v.source->scene.sun;
  f.march = v.source->scene.march;
  return f;
}

// Marches a view into its own presenter (as the viewer does: march_into, then accumulate).
struct Marched {
  std::unique_ptr<render::FrameRenderer> renderer;
  std::unique_ptr<render::Presenter> presenter;
};
Marched march(const render::ShaderLoader& loader, const View& v, int w, int h, double scale) {
  Marched m{std::make_unique<render::FrameRenderer>(loader), std::make_unique<render::Presenter>(loader)};
  const core::FrameSpec f = frame_of(v, w, h, scale);
  m.renderer->use_volume(v.source->volume);
  m.presenter->resize(f.march_camera.width, f.march_camera.height);
  m.renderer->march_into(m.presenter->frame_texture(), f, 0);
  m.presenter->accumulate(0);
  return m;
}

// Runs draw() into a w x h RGBA8 target and reads it back, rows top to bottom.
template <class Draw>
std::vector<unsigned char> draw_into(int w, int h, Draw draw) {
  GLuint fbo = 0, color = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &color);
  glTextureStorage2D(color, 1, GL_RGBA8, w, h);
  glCreateFramebuffers(1, &fbo);
  glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0, color, 0);
  EXPECT_EQ(glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER), GLenum(GL_FRAMEBUFFER_COMPLETE));
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glClearColor(1.0f, 0.0f, 1.0f, 1.0f);  // magenta: a pixel no view drew shows up
  glClear(GL_COLOR_BUFFER_BIT);
  draw();
  std::vector<unsigned char> gl(static_cast<std::size_t>(w) * h * 4), out(gl.size());
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glGetTextureImage(color, 0, GL_RGBA, GL_UNSIGNED_BYTE, static_cast<GLsizei>(gl.size()), gl.data());
  render::check_gl("reading the composed views");
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glDeleteFramebuffers(1, &fbo);
  glDeleteTextures(1, &color);
  const std::size_t row = static_cast<std::size_t>(w) * 4;
  for (int y = 0; y < h; ++y) std::copy_n(gl.data() + (h - 1 - y) * row, row, out.data() + y * row);
  return out;
}

render::ToneSettings tone() {
  render::ToneSettings t;
  t.exposure = 4.0;
  t.background = glm::dvec3(0.0);
  return t;
}

// The views composed in `layout`, each region against its view marched and drawn alone at the
// size it has there (the offsets of a view's own image: (ox, oy) = where the region starts in it).
void check_layout(const render::ShaderLoader& loader, const std::vector<View>& views, ViewLayout layout, double divider, double scale) {
  const int n = static_cast<int>(views.size());
  const std::vector<ViewRect> rects = viewer::view_rects(layout, n, kW, kH);
  std::vector<Marched> marched;
  std::vector<const render::Presenter*> presenters;
  for (int i = 0; i < n; ++i) {
    marched.push_back(march(loader, views[static_cast<std::size_t>(i)], rects[static_cast<std::size_t>(i)].w,
                            rects[static_cast<std::size_t>(i)].h, scale));
    presenters.push_back(marched.back().presenter.get());
  }
  const std::vector<render::ToneSettings> tones(static_cast<std::size_t>(n), tone());
  const std::vector<unsigned char> composed =
      draw_into(kW, kH, [&] { viewer::compose_views(presenters, tones, layout, divider, kW, kH); });
  std::vector<int> covered(static_cast<std::size_t>(kW) * kH, 0);
  for (int i = 0; i < n; ++i) {
    const ViewRect r = rects[static_cast<std::size_t>(i)], v = viewer::visible_rect(layout, n, i, kW, kH, divider);
    const Marched alone = march(loader, views[static_cast<std::size_t>(i)], r.w, r.h, scale);
    const std::vector<unsigned char> single = draw_into(r.w, r.h, [&] { alone.presenter->draw(tone(), 0, 0, r.w, r.h); });
    int lit = 0, differ = 0;
    for (int y = v.y; y < v.y + v.h; ++y) {
      for (int x = v.x; x < v.x + v.w; ++x) {
        ++covered[static_cast<std::size_t>(y) * kW + x];
        const std::size_t c = (static_cast<std::size_t>(y) * kW + x) * 4;
        const std::size_t s = (static_cast<std::size_t>(y - r.y) * r.w + (x - r.x)) * 4;
        for (int ch = 0; ch < 3; ++ch) {
          if (composed[c + ch] != single[s + ch]) ++differ;
        }
        if (single[s] + single[s + 1] + single[s + 2] > 30) ++lit;
      }
    }
    EXPECT_EQ(differ, 0) << viewer::view_layout_name(layout) << ": view " << i << " of " << n << ": values that differ from the view alone";
    EXPECT_GT(lit, v.w * v.h / 10) << "view " << i << ": the region is nearly black, the comparison would prove little";
  }
  for (std::size_t p = 0; p < covered.size(); ++p) ASSERT_EQ(covered[p], 1) << "pixel " << p << " drawn by " << covered[p] << " views";
}

TEST_F(ViewsGpu, GridOfTwoSourcesOnTheirOwnGridsGivesEachViewsPixels) {
  const Source a("stratocumulus"), b("orbit_globe");
  check_layout(loader_, {{&a}, {&b}}, ViewLayout::Grid, 0.5, 1.0);
  check_layout(loader_, {{&a}, {&b}}, ViewLayout::Grid, 0.5, 0.5);  // marched at half size, upscaled in its cell
}

TEST_F(ViewsGpu, GridOfFourGivesEachViewsPixels) {
  const Source a("stratocumulus"), b("orbit_globe");
  check_layout(loader_, {{&a}, {&b}, {&a, 25.0}, {&b, -25.0}}, ViewLayout::Grid, 0.5, 1.0);
}

TEST_F(ViewsGpu, SwipeGivesEachSideTheViewsPixels) {
  const Source a("stratocumulus"), b("orbit_globe");
  check_layout(loader_, {{&a}, {&b}}, ViewLayout::Swipe, 0.4, 1.0);
  check_layout(loader_, {{&a}, {&b}}, ViewLayout::Swipe, 0.77, 0.5);
}

}  // namespace
