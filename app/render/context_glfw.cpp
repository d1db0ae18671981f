// Windowed OpenGL 4.5 core contexts through GLFW, and the version check shared by every context.
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <string>

#include "render/context.hpp"
#include "render/gl.hpp"

namespace cv::render {
namespace {
std::string last_glfw_error() {
  const char* desc = nullptr;
  const int code = glfwGetError(&desc);
  return code == GLFW_NO_ERROR ? std::string("no GLFW error reported") : std::string(desc ? desc : "?");
}

const char* gl_string(GLenum name) {
  const auto* s = reinterpret_cast<const char*>(glGetString(name));
  return s ? s : "";
}
}  // namespace

std::string GlInfo::summary() const {
  return "OpenGL " + std::to_string(major) + "." + std::to_string(minor) + (core_profile ? " core" : "") +
         " (" + version + "), GLSL " + glsl_version + ", " + renderer + " by " + vendor + ", via " + platform;
}

GlInfo query_and_require_45(const std::string& platform) {
  GlInfo info;
  info.platform = platform;
  glGetIntegerv(GL_MAJOR_VERSION, &info.major);
  glGetIntegerv(GL_MINOR_VERSION, &info.minor);
  GLint mask = 0;
  glGetIntegerv(GL_CONTEXT_PROFILE_MASK, &mask);
  info.core_profile = (mask & GL_CONTEXT_CORE_PROFILE_BIT) != 0;
  info.vendor = gl_string(GL_VENDOR);
  info.renderer = gl_string(GL_RENDERER);
  info.version = gl_string(GL_VERSION);
  info.glsl_version = gl_string(GL_SHADING_LANGUAGE_VERSION);
  glGetError();  // a pre-3.0 driver rejects GL_MAJOR_VERSION; that case is reported below
  if (info.major * 10 + info.minor < 45 || !info.core_profile) {
    throw ContextError("OpenGL 4.5 core profile required; " + platform + " gave " + info.version + " (" +
                       (info.core_profile ? "core" : "not core") + ") on " + info.renderer);
  }
  return info;
}

WindowContext::~WindowContext() {
  if (window_) glfwDestroyWindow(window_);
  glfwTerminate();
}

void WindowContext::make_current() { glfwMakeContextCurrent(window_); }
bool WindowContext::should_close() const { return glfwWindowShouldClose(window_) != 0; }
void WindowContext::swap_buffers() { glfwSwapBuffers(window_); }

std::unique_ptr<WindowContext> make_window_context(int width, int height, const std::string& title,
                                                   bool visible) {
  if (!glfwInit()) {
    throw ContextError("cannot open a window (GLFW): " + last_glfw_error() +
                       "; use the headless commands, or run under a display or xvfb-run");
  }
  glfwWindowHint(GLFW_CLIENT_API, GLFW_OPENGL_API);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_VISIBLE, visible ? GLFW_TRUE : GLFW_FALSE);
  std::unique_ptr<WindowContext> ctx(new WindowContext());
  ctx->window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
  if (!ctx->window_) {
    throw ContextError("cannot create an OpenGL 4.5 core window (GLFW): " + last_glfw_error());
  }
  ctx->make_current();
  ctx->info_ = query_and_require_45("GLFW window");
  return ctx;
}

}  // namespace cv::render
