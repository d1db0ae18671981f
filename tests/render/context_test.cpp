// Headless contexts: 4.5 core through EGL on llvmpipe, and clear errors when that cannot be had.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "render/context.hpp"
#include "render/gl.hpp"

namespace {
using namespace cv::render;

TEST(Context, HeadlessGivesOpenGl45Core) {
  auto ctx = make_headless_context();
  const GlInfo& info = ctx->info();
  EXPECT_GE(info.major * 10 + info.minor, 45);
  EXPECT_TRUE(info.core_profile);
  EXPECT_FALSE(info.renderer.empty());
  GLint invocations = 0;
  glGetIntegerv(GL_MAX_COMPUTE_WORK_GROUP_INVOCATIONS, &invocations);
  EXPECT_GE(invocations, 1024);  // compute shaders are there
  check_gl("querying compute limits");
  std::printf("%s\n", info.summary().c_str());
}

TEST(Context, UnknownPlatformIsOneClearError) {
  setenv("CLOUDVIEWER_EGL_PLATFORM", "bogus", 1);
  try {
    make_headless_context();
    FAIL() << "expected ContextError";
  } catch (const ContextError& e) {
    EXPECT_NE(std::string(e.what()).find("'bogus' is unknown"), std::string::npos) << e.what();
  }
  unsetenv("CLOUDVIEWER_EGL_PLATFORM");
}

TEST(Context, TooOldADriverIsNamedInTheError) {
  // Mesa can be told to offer only OpenGL 3.3; the error must say what was found.
  setenv("MESA_GL_VERSION_OVERRIDE", "3.3", 1);
  setenv("CLOUDVIEWER_EGL_PLATFORM", "surfaceless", 1);
  try {
    auto ctx = make_headless_context();
    FAIL() << "expected ContextError, got " << ctx->info().summary();
  } catch (const ContextError& e) {
    EXPECT_NE(std::string(e.what()).find("3.3"), std::string::npos) << e.what();
  }
  unsetenv("MESA_GL_VERSION_OVERRIDE");
  unsetenv("CLOUDVIEWER_EGL_PLATFORM");
}

TEST(Context, GlErrorsAreReportedByName) {
  auto ctx = make_headless_context();
  glBindBuffer(0x1234, 0);  // an invalid target
  try {
    check_gl("binding a buffer to a bad target");
    FAIL() << "expected GlError";
  } catch (const GlError& e) {
    EXPECT_NE(std::string(e.what()).find("GL_INVALID_ENUM"), std::string::npos) << e.what();
  }
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));  // nothing left behind
}

}  // namespace
