// The GLFW window context (run under xvfb-run by CTest): 4.5 core, and a frame really reaches it.
#include <gtest/gtest.h>

#include "render/context.hpp"
#include "render/gl.hpp"

namespace {
using namespace cv::render;

TEST(Window, OpensA45CoreContextAndPresentsAFrame) {
  auto win = make_window_context(64, 48, "cloudviewer window test", false);
  EXPECT_GE(win->info().major * 10 + win->info().minor, 45);
  EXPECT_TRUE(win->info().core_profile);
  glViewport(0, 0, 64, 48);
  glClearColor(0.25f, 0.5f, 0.75f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT);
  unsigned char px[4] = {0, 0, 0, 0};
  glReadPixels(10, 10, 1, 1, GL_RGBA, GL_UNSIGNED_BYTE, px);
  check_gl("clearing and reading the window's back buffer");
  EXPECT_NEAR(px[0], 64, 1);
  EXPECT_NEAR(px[1], 128, 1);
  EXPECT_NEAR(px[2], 191, 1);
  win->swap_buffers();
  EXPECT_FALSE(win->should_close());
}

}  // namespace
