// The viewer's GPU path (headless): the tonemap shader against image_output's CPU tonemap, the
// running-mean accumulation against a CPU mean, and every vertex/fragment shader pair compiling.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <filesystem>
#include <limits>
#include <random>
#include <vector>

#include <glm/vec4.hpp>

#include <unistd.h>

#include "io/output_file.hpp"
#include "render/context.hpp"
#include "render/exr_output.hpp"
#include "render/image_output.hpp"
#include "render/presenter.hpp"

namespace {
using namespace cv::render;
namespace fs = std::filesystem;

class PresenterTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { ctx_ = make_headless_context().release(); }
  static void TearDownTestSuite() {
    delete ctx_;
    ctx_ = nullptr;
  }
  static GlContext* ctx_;
  ShaderLoader loader_{{ShaderLoader::default_shader_dir()}};
};
GlContext* PresenterTest::ctx_ = nullptr;

void upload(GLuint tex, int w, int h, const std::vector<glm::vec4>& px) {
  glTextureSubImage2D(tex, 0, 0, 0, w, h, GL_RGBA, GL_FLOAT, px.data());
}

// The presenter's draw into a W x H RGBA8 target, read back (rows bottom to top, as GL stores them).
std::vector<unsigned char> draw_rgba8(const Presenter& p, const ToneSettings& tone, int W, int H) {
  GLuint fbo = 0, color = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &color);
  glTextureStorage2D(color, 1, GL_RGBA8, W, H);
  glCreateFramebuffers(1, &fbo);
  glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0, color, 0);
  if (glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) ADD_FAILURE() << "incomplete framebuffer";
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  p.draw(tone, 0, 0, W, H);
  std::vector<unsigned char> out(static_cast<std::size_t>(W) * H * 4);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glGetTextureImage(color, 0, GL_RGBA, GL_UNSIGNED_BYTE, static_cast<GLsizei>(out.size()), out.data());
  check_gl("reading the presenter's draw");
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glDeleteFramebuffers(1, &fbo);
  glDeleteTextures(1, &color);
  return out;
}

TEST_F(PresenterTest, TonemapShaderMatchesTheCpuTonemapWithinOneStep) {
  // Radiance over five decades, transmittance 0..1, and the non-finite cases.
  const int w = 48, h = 27;
  std::vector<glm::vec4> px(static_cast<std::size_t>(w) * h);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (std::size_t i = 0; i < px.size(); ++i) {
    const float r = std::pow(10.0f, -4.0f + 5.0f * u(rng));
    px[i] = glm::vec4(r, r * u(rng), r * u(rng) * 0.5f, u(rng));
  }
  px[0] = glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);  // clear sky: the background only
  px[1] = glm::vec4(std::numeric_limits<float>::quiet_NaN(), 1.0f, std::numeric_limits<float>::infinity(), 0.0f);
  Presenter p(loader_);
  p.resize(w, h);
  upload(p.frame_texture(), w, h, px);
  p.accumulate(0);  // one frame: the mean is the frame
  ToneSettings tone;
  tone.exposure = 4.0;
  const std::vector<unsigned char> gpu = draw_rgba8(p, tone, w, h);
  const std::vector<unsigned char> cpu = tonemap_srgb8(px, tone);
  int worst = 0, differ = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      // The texture's row 0 is the image's top row; the draw puts it at the framebuffer's top (row h-1).
      const std::size_t i = static_cast<std::size_t>(y) * w + x, j = static_cast<std::size_t>(h - 1 - y) * w + x;
      for (int c = 0; c < 3; ++c) {
        const int d = std::abs(int(gpu[j * 4 + c]) - int(cpu[i * 3 + c]));
        worst = std::max(worst, d);
        if (d > 1) ADD_FAILURE() << "pixel " << x << "," << y << " channel " << c << ": GPU " << int(gpu[j * 4 + c]) << ", CPU "
                                 << int(cpu[i * 3 + c]) << " from " << px[i][c] << " (a " << px[i].w << ")";
        differ += d > 0;
      }
    }
  }
  EXPECT_LE(worst, 1) << differ << " channel values differ";
  // A sanity check on the comparison itself: the test image is not one colour.
  EXPECT_NE(cpu[0], cpu[3 * 100]);
}

TEST_F(PresenterTest, ReducedResolutionUpscalesWithoutSpreadingANonFiniteTexel) {
  // A 12 x 7 march drawn over 48 x 27 pixels (resolution scale 1/4): a uniform image stays uniform,
  // and a NaN texel in the top-left corner whitens only pixels within one texel of it.
  const int w = 12, h = 7, W = 48, H = 27;
  std::vector<glm::vec4> px(static_cast<std::size_t>(w) * h, glm::vec4(0.05f, 0.04f, 0.03f, 0.2f));
  px[0] = glm::vec4(std::numeric_limits<float>::quiet_NaN());
  Presenter p(loader_);
  p.resize(w, h);
  upload(p.frame_texture(), w, h, px);
  p.accumulate(0);
  ToneSettings tone;
  const std::vector<unsigned char> out = draw_rgba8(p, tone, W, H);
  const std::vector<unsigned char> want = tonemap_srgb8({px[1]}, tone);
  int far_off = 0, near_white = 0;
  for (int y = 0; y < H; ++y) {
    for (int x = 0; x < W; ++x) {
      const unsigned char* o = &out[(static_cast<std::size_t>(H - 1 - y) * W + x) * 4];  // y from the top
      const bool near_corner = x < 2 * W / w && y < 2 * H / h + 1;  // within about one texel of texel (0, 0)
      if (near_corner) {
        near_white += o[0] > want[0] + 8;
      } else {
        for (int c = 0; c < 3; ++c) far_off += std::abs(int(o[c]) - int(want[static_cast<std::size_t>(c)])) > 1;
      }
    }
  }
  EXPECT_EQ(far_off, 0);
  EXPECT_GT(near_white, 0);  // the non-finite texel itself shows (white), as in image_output
}

TEST(UpscaleLinear, KeepsConstantsAndInterpolatesBetweenCentres) {
  const std::vector<glm::vec4> src = {glm::vec4(0.0f), glm::vec4(4.0f)};  // 2 x 1
  const auto out = upscale_linear(src, 2, 1, 4, 1);
  // Output centres 0.5, 1.5, 2.5, 3.5 of 4 map to source x -0.25 (clamped 0), 0.25, 0.75, 1.25 (clamped 1).
  EXPECT_FLOAT_EQ(out[0].x, 0.0f);
  EXPECT_FLOAT_EQ(out[1].x, 1.0f);
  EXPECT_FLOAT_EQ(out[2].x, 3.0f);
  EXPECT_FLOAT_EQ(out[3].x, 4.0f);
  // 1:1 is the image itself, a non-finite texel included, without touching its neighbours.
  const std::vector<glm::vec4> nan = {glm::vec4(1.0f), glm::vec4(std::numeric_limits<float>::quiet_NaN()), glm::vec4(2.0f)};
  const auto same = upscale_linear(nan, 3, 1, 3, 1);
  EXPECT_EQ(same[0].x, 1.0f);
  EXPECT_TRUE(std::isnan(same[1].x));
  EXPECT_EQ(same[2].x, 2.0f);
}

TEST_F(PresenterTest, UpscaledDrawIsTheCpuUpscaleTonemapped) {
  // The viewer's draw of a reduced march equals `render`'s upscale_linear then tonemap_srgb8, within
  // the tonemap's one step: both upscale in linear radiance with the same weights.
  const int w = 13, h = 8, W = 40, H = 23;
  std::vector<glm::vec4> px(static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) px[static_cast<std::size_t>(y) * w + x] = glm::vec4(0.02f * x, 0.3f * (y % 3), 0.01f * x * y, 0.1f * (y % 2));
  Presenter p(loader_);
  p.resize(w, h);
  upload(p.frame_texture(), w, h, px);
  p.accumulate(0);
  ToneSettings tone;
  tone.exposure = 3.0;
  const std::vector<unsigned char> out = draw_rgba8(p, tone, W, H);
  const std::vector<unsigned char> cpu = tonemap_srgb8(upscale_linear(px, w, h, W, H), tone);
  int worst = 0;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      for (int c = 0; c < 3; ++c)
        worst = std::max(worst, std::abs(int(out[(static_cast<std::size_t>(H - 1 - y) * W + x) * 4 + c]) -
                                         int(cpu[(static_cast<std::size_t>(y) * W + x) * 3 + c])));
  EXPECT_LE(worst, 1);
  EXPECT_NE(cpu[0], cpu[3 * (W - 1)]);  // the image is not one colour
}

TEST_F(PresenterTest, AccumulationIsTheRunningMeanOfTheFrames) {
  const int w = 19, h = 11, frames = 6;  // not multiples of the 8 x 8 work groups
  Presenter p(loader_);
  p.resize(w, h);
  std::mt19937 rng(3);
  std::normal_distribution<float> n(1.0f, 0.5f);
  std::vector<glm::dvec4> mean(static_cast<std::size_t>(w) * h, glm::dvec4(0.0));
  for (int f = 0; f < frames; ++f) {
    std::vector<glm::vec4> px(mean.size());
    for (auto& v : px) v = glm::vec4(n(rng), n(rng), n(rng), n(rng));
    for (std::size_t i = 0; i < px.size(); ++i) mean[i] += glm::dvec4(px[i]) / double(frames);
    upload(p.frame_texture(), w, h, px);
    p.accumulate(f);
  }
  std::vector<glm::vec4> gpu(mean.size());
  glGetTextureImage(p.mean_texture(), 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(gpu.size() * sizeof(glm::vec4)), gpu.data());
  check_gl("reading the accumulated mean");
  double worst = 0.0;
  for (std::size_t i = 0; i < gpu.size(); ++i) {
    for (int c = 0; c < 4; ++c) worst = std::max(worst, std::abs(double(gpu[i][c]) - mean[i][c]));
  }
  EXPECT_LT(worst, 1e-5);  // float running mean of values ~1 over 6 frames
  // Restarting (count 0) replaces the mean with the new frame.
  std::vector<glm::vec4> one(mean.size(), glm::vec4(0.25f, 0.5f, 0.75f, 1.0f));
  upload(p.frame_texture(), w, h, one);
  p.accumulate(0);
  glGetTextureImage(p.mean_texture(), 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(gpu.size() * sizeof(glm::vec4)), gpu.data());
  EXPECT_EQ(gpu[5], one[5]);
  EXPECT_EQ(gpu.back(), one.back());
}

TEST_F(PresenterTest, EveryVertexAndFragmentShaderPairCompilesAndLinks) {
  // Graphics shaders come in pairs by name (x.vert + x.frag); the .comp files have their own test.
  const fs::path dir = ShaderLoader::default_shader_dir();
  int pairs = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    const fs::path& f = e.path();
    if (f.extension() == ".frag") {
      EXPECT_TRUE(fs::exists(fs::path(f).replace_extension(".vert"))) << f << " has no vertex shader";
    }
    if (f.extension() != ".vert") continue;
    const fs::path frag = fs::path(f).replace_extension(".frag");
    ASSERT_TRUE(fs::exists(frag)) << f << " has no fragment shader";
    EXPECT_NO_THROW(load_graphics(loader_, f, frag)) << f;
    ++pairs;
  }
  EXPECT_GE(pairs, 1);
}

}  // namespace

namespace {
// A PFM read back: its header's type and size, and the floats in file order (rows bottom to top).
struct Pfm {
  std::string type;
  int w = 0, h = 0;
  double scale = 0.0;
  std::vector<float> data;
};
Pfm read_pfm(const std::string& path) {
  Pfm p;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return p;
  char type[3] = {};
  if (std::fscanf(f, "%2s %d %d %lf", type, &p.w, &p.h, &p.scale) == 4 && std::fgetc(f) == '\n') {
    p.type = type;
    const std::size_t n = static_cast<std::size_t>(p.w) * p.h * (p.type == "PF" ? 3 : 1);
    p.data.resize(n);
    if (std::fread(p.data.data(), sizeof(float), n, f) != n) p.data.clear();
  }
  std::fclose(f);
  return p;
}
}  // namespace

// Linear output is radiance only: clouds on black stay black (no background colour added through
// the transmittance, whatever the tone settings), and the transmittance is its own one-channel file.
TEST(ImageOutput, PfmHoldsRadianceAloneAndTheTransmittanceBeside) {
  const fs::path dir = fs::temp_directory_path() / ("cv_pfm_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const int w = 3, h = 2;
  std::vector<glm::vec4> px = {{0, 0, 0, 1},       {0.5f, 0.25f, 0.125f, 0.5f}, {2, 3, 4, 0},
                               {1e-3f, 0, 0, 0.9f}, {0, 0, 0, 0},              {7, 8, 9, 0.25f}};
  const std::string path = (dir / "x.pfm").string();
  EXPECT_EQ(transmittance_pfm_path(path), (dir / "x.transmittance.pfm").string());
  EXPECT_EQ(transmittance_pfm_path("noext"), "noext.transmittance.pfm");
  write_pfm(path, w, h, px);
  write_pfm_transmittance(transmittance_pfm_path(path), w, h, px);
  const Pfm rgb = read_pfm(path), t = read_pfm(transmittance_pfm_path(path));
  ASSERT_EQ(rgb.type, "PF");
  ASSERT_EQ(t.type, "Pf");
  ASSERT_EQ(rgb.w, w);
  ASSERT_EQ(rgb.h, h);
  ASSERT_EQ(t.w, w);
  ASSERT_EQ(t.h, h);
  ASSERT_EQ(rgb.data.size(), 18u);
  ASSERT_EQ(t.data.size(), 6u);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const glm::vec4& p = px[static_cast<std::size_t>(y) * w + x];
      const std::size_t row = static_cast<std::size_t>(h - 1 - y) * w + x;  // PFM rows bottom to top
      for (int c = 0; c < 3; ++c) EXPECT_EQ(rgb.data[row * 3 + c], p[c]) << x << "," << y << " channel " << c;
      EXPECT_EQ(t.data[row], p.w) << x << "," << y;
    }
  }
  fs::remove_all(dir);
}

// OpenEXR output: R, G, B the radiance alone and A = 1 - transmittance, float for float (so a
// compositor's RGB + (1 - A) x plate is the renderer's radiance + transmittance x background);
// without alpha (the path tracer's) R, G, B alone. Written atomically through the FILE the output
// gives; a stream that fails is a WriteError, not a truncated file taken for an image.
TEST(ImageOutput, ExrHoldsRadianceAndOneMinusTransmittance) {
  const fs::path dir = fs::temp_directory_path() / ("cv_exr_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const int w = 5, h = 3;  // not square, so swapped axes would show
  std::vector<glm::vec4> px(static_cast<std::size_t>(w) * h);
  for (std::size_t i = 0; i < px.size(); ++i) {
    const float k = static_cast<float>(i);
    px[i] = {0.01f * k, 1e-6f * k, 3.0f + k, std::fmod(0.37f * k, 1.0f)};
  }
  px[3] = {0, 0, 0, 1};     // clear sky: nothing, all shows through
  px[7] = {2, 2, 2, 0};     // opaque
  for (const bool alpha : {true, false}) {
    SCOPED_TRACE(alpha ? "with alpha" : "without");
    const std::string path = (dir / (alpha ? "a.exr" : "b.exr")).string();
    cv::core::write_file_atomically(path, [&](std::FILE* f) { encode_exr(f, w, h, px, alpha); });
    const ExrImage img = read_exr(path, alpha ? std::vector<std::string>{"R", "G", "B", "A"} : std::vector<std::string>{"R", "G", "B"});
    ASSERT_EQ(img.width, w);
    ASSERT_EQ(img.height, h);
    EXPECT_EQ(img.channels, alpha ? (std::vector<std::string>{"A", "B", "G", "R"}) : (std::vector<std::string>{"B", "G", "R"}));
    for (std::size_t i = 0; i < px.size(); ++i) {
      for (int c = 0; c < 3; ++c) EXPECT_EQ(img.values[static_cast<std::size_t>(c)][i], px[i][c]) << "pixel " << i << " channel " << c;
      if (alpha) {
        EXPECT_EQ(img.values[3][i], 1.0f - px[i].a) << "pixel " << i;
      }
    }
    if (alpha) {
      EXPECT_THROW(read_exr(path, {"Z"}), std::runtime_error);  // a channel the file lacks
    }
  }
  // A stream that cannot take the bytes: an image larger than stdio's buffer, so the failing write
  // itself is met, not only the final flush.
  if (std::FILE* full = std::fopen("/dev/full", "wb")) {
    std::vector<glm::vec4> big(256 * 256, glm::vec4(0.3f, 0.2f, 0.1f, 0.5f));
    for (std::size_t i = 0; i < big.size(); ++i) big[i].x = static_cast<float>(i);  // not compressed away
    EXPECT_THROW(encode_exr(full, 256, 256, big, true), cv::core::WriteError);
    std::fclose(full);
  }
  EXPECT_THROW(encode_exr(nullptr, w, h + 1, px, true), std::invalid_argument);  // pixels that do not fill the size
  fs::remove_all(dir);
}

// The automatic exposure puts the 99th percentile of the lit pixels' luminance at 0.8 on the filmic
// curve (sRGB byte 231 for grey), ignores unlit and non-finite pixels and the top 1 % (a stray hot
// pixel), scales inversely with the radiance, and falls back to the default on a black image.
TEST(ImageOutput, AutoExposurePutsTheBrightCloudsAtPointEight) {
  std::vector<glm::vec4> grey(1000, glm::vec4(0.1f, 0.1f, 0.1f, 0.0f));
  const double e = auto_exposure(grey);
  ToneSettings tone;
  tone.exposure = e;
  tone.background = glm::dvec3(0.0);
  const std::vector<unsigned char> out = tonemap_srgb8(grey, tone);
  const double srgb08 = 1.055 * std::pow(0.8, 1.0 / 2.4) - 0.055;
  EXPECT_EQ(static_cast<int>(out[0]), static_cast<int>(std::lround(srgb08 * 255.0)));

  std::vector<glm::vec4> spoilt = grey;
  for (int i = 0; i < 5; ++i) spoilt.push_back(glm::vec4(1e6f, 1e6f, 1e6f, 0.0f));  // hot pixels, 0.5 %
  spoilt.push_back(glm::vec4(std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f, 0.0f));
  spoilt.insert(spoilt.end(), 3000, glm::vec4(0.0f, 0.0f, 0.0f, 1.0f));  // clear sky on black
  EXPECT_DOUBLE_EQ(auto_exposure(spoilt), e);

  std::vector<glm::vec4> brighter(1000, glm::vec4(0.2f, 0.2f, 0.2f, 0.0f));
  EXPECT_NEAR(auto_exposure(brighter), e / 2.0, 1e-9 * e);

  EXPECT_EQ(auto_exposure(std::vector<glm::vec4>(64, glm::vec4(0.0f, 0.0f, 0.0f, 1.0f))), kDefaultExposure);
  EXPECT_EQ(auto_exposure({}), kDefaultExposure);
}

// A sequence is exposed from its first and last frames and three evenly between (all of them up to
// five), and the brightest lit one sets the exposure (the least): a series from dawn into the day is
// exposed for the day. Unlit frames are left out; a sequence with none lit keeps the default.
TEST(ImageOutput, ASequenceIsExposedForItsBrightestProbedFrame) {
  EXPECT_EQ(exposure_probe_frames(0), std::vector<int>{});
  EXPECT_EQ(exposure_probe_frames(1), std::vector<int>{0});
  EXPECT_EQ(exposure_probe_frames(3), (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(exposure_probe_frames(5), (std::vector<int>{0, 1, 2, 3, 4}));
  EXPECT_EQ(exposure_probe_frames(6), (std::vector<int>{0, 1, 3, 4, 5}));
  EXPECT_EQ(exposure_probe_frames(101), (std::vector<int>{0, 25, 50, 75, 100}));
  const std::vector<glm::vec4> dawn(100, glm::vec4(0.001f, 0.001f, 0.001f, 0.0f)), noon(100, glm::vec4(0.1f, 0.1f, 0.1f, 0.0f));
  const std::vector<glm::vec4> night(100, glm::vec4(0.0f, 0.0f, 0.0f, 1.0f));
  ASSERT_TRUE(auto_exposure_if_lit(dawn).has_value());
  EXPECT_FALSE(auto_exposure_if_lit(night).has_value());
  EXPECT_DOUBLE_EQ(*auto_exposure_if_lit(noon), auto_exposure(noon));
  EXPECT_DOUBLE_EQ(sequence_exposure({auto_exposure_if_lit(dawn), auto_exposure_if_lit(noon), auto_exposure_if_lit(night)}),
                   auto_exposure(noon));
  EXPECT_DOUBLE_EQ(sequence_exposure({auto_exposure_if_lit(night), auto_exposure_if_lit(dawn)}), auto_exposure(dawn));
  EXPECT_EQ(sequence_exposure({auto_exposure_if_lit(night)}), kDefaultExposure);
  EXPECT_EQ(sequence_exposure({}), kDefaultExposure);
}

// A frame with a NaN or an infinite channel is refused before anything is written, and the
// message names the input, the count and the first pixel's place (issue 13: "N pixels were not
// finite" used to leave the PNG written).
TEST(ImageOutput, NonFinitePixelsAreRefusedWithTheirCountAndPlace) {
  const int w = 5;
  std::vector<glm::vec4> px(20, glm::vec4(0.1f, 0.2f, 0.3f, 0.5f));
  EXPECT_NO_THROW(check_finite_pixels(px, w, "in.nc"));
  px[7].y = std::numeric_limits<float>::quiet_NaN();  // x 2, y 1
  px[13].w = std::numeric_limits<float>::infinity();
  px[19].x = -std::numeric_limits<float>::infinity();
  try {
    check_finite_pixels(px, w, "in.nc");
    ADD_FAILURE() << "three non-finite pixels were accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()),
              "in.nc: 3 of 20 pixels came out not finite (the first at x 2, y 1), expected finite radiance; nothing written");
  }
}
