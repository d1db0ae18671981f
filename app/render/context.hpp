// OpenGL 4.5 core contexts: headless through EGL (NVIDIA device platform, Mesa surfaceless) and
// windowed through GLFW. Anything less than 4.5 core is one clear error naming what was found.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>

struct GLFWwindow;

namespace cv::render {

class ContextError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct GlInfo {
  int major = 0;
  int minor = 0;
  bool core_profile = false;
  std::string vendor;
  std::string renderer;
  std::string version;
  std::string glsl_version;
  std::string platform;  // how the context was made, e.g. "EGL surfaceless (Mesa)"
  std::string summary() const;
};

class GlContext {
 public:
  virtual ~GlContext() = default;
  virtual void make_current() = 0;
  const GlInfo& info() const { return info_; }

 protected:
  GlInfo info_;
};

struct HeadlessOptions {
  // "auto" (GPU device first, then Mesa surfaceless, then software device), "device",
  // "surfaceless" or "default". The CLOUDVIEWER_EGL_PLATFORM environment variable overrides it.
  std::string platform = "auto";
  bool debug = false;
};

// A context with no window or X server. Throws ContextError when no 4.5 core context can be made.
std::unique_ptr<GlContext> make_headless_context(const HeadlessOptions& options = {});

class WindowContext : public GlContext {
 public:
  ~WindowContext() override;
  void make_current() override;
  GLFWwindow* window() const { return window_; }
  bool should_close() const;
  void swap_buffers();

 private:
  friend std::unique_ptr<WindowContext> make_window_context(int, int, const std::string&, bool);
  WindowContext() = default;
  GLFWwindow* window_ = nullptr;
};

// A GLFW window with a 4.5 core context. Throws ContextError without a display or without 4.5.
std::unique_ptr<WindowContext> make_window_context(int width, int height, const std::string& title,
                                                   bool visible = true);

// Fills GlInfo from the current context and throws ContextError unless it is 4.5 core or later.
GlInfo query_and_require_45(const std::string& platform);

}  // namespace cv::render
