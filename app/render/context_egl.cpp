// Headless OpenGL 4.5 core contexts through EGL: the device platform (NVIDIA, or any GPU exposed
// by EGL_EXT_device_enumeration) and Mesa's surfaceless platform (llvmpipe), with no X server.
#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "render/context.hpp"
#include "render/gl.hpp"

namespace cv::render {
namespace {

bool has_extension(const char* list, const char* name) {
  if (list == nullptr) return false;
  const size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n) {
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  }
  return false;
}

std::string egl_error_string(EGLint e) {
  switch (e) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    default: return "EGL error " + std::to_string(e);
  }
}

class EglContext : public GlContext {
 public:
  EglContext(EGLDisplay display, EGLContext context, const std::string& platform)
      : display_(display), context_(context) {
    make_current();
    info_ = query_and_require_45(platform);
  }
  ~EglContext() override {
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display_, context_);
    eglTerminate(display_);
  }
  void make_current() override {
    if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_)) {
      throw ContextError("eglMakeCurrent failed: " + egl_error_string(eglGetError()));
    }
  }

 private:
  EGLDisplay display_;
  EGLContext context_;
};

struct Candidate {
  EGLDisplay display;
  std::string platform;
};

// Makes a context on an initialised display; returns EGL_NO_CONTEXT and a reason on failure.
EGLContext create_on(EGLDisplay dpy, bool debug, std::string& why) {
  const char* ext = eglQueryString(dpy, EGL_EXTENSIONS);
  if (!has_extension(ext, "EGL_KHR_surfaceless_context")) {
    why = "no EGL_KHR_surfaceless_context";
    return EGL_NO_CONTEXT;
  }
  if (!eglBindAPI(EGL_OPENGL_API)) {
    why = "eglBindAPI(EGL_OPENGL_API) failed: " + egl_error_string(eglGetError());
    return EGL_NO_CONTEXT;
  }
  EGLConfig config = nullptr;
  if (!has_extension(ext, "EGL_KHR_no_config_context")) {
    const EGLint cfg_attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
    EGLint n = 0;
    if (!eglChooseConfig(dpy, cfg_attribs, &config, 1, &n) || n < 1) {
      why = "no EGL config renders OpenGL";
      return EGL_NO_CONTEXT;
    }
  }
  const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4,
                            EGL_CONTEXT_MINOR_VERSION, 5,
                            EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                            EGL_CONTEXT_OPENGL_DEBUG, debug ? EGL_TRUE : EGL_FALSE,
                            EGL_NONE};
  EGLContext ctx = eglCreateContext(dpy, config, EGL_NO_CONTEXT, attribs);
  if (ctx != EGL_NO_CONTEXT) return ctx;
  why = "eglCreateContext(OpenGL 4.5 core) failed: " + egl_error_string(eglGetError());
  // Learn what the driver does offer, so the error can say what was found.
  const EGLint any[] = {EGL_NONE};
  EGLContext probe = eglCreateContext(dpy, config, EGL_NO_CONTEXT, any);
  if (probe != EGL_NO_CONTEXT) {
    if (eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, probe)) {
      const auto* v = reinterpret_cast<const char*>(glGetString(GL_VERSION));
      const auto* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
      why += std::string("; the driver offers OpenGL ") + (v ? v : "?") + " on " + (r ? r : "?");
      eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    }
    eglDestroyContext(dpy, probe);
  }
  return EGL_NO_CONTEXT;
}

std::vector<Candidate> candidates(const std::string& want, std::string& notes) {
  std::vector<Candidate> out;
  const char* client_ext = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  auto get_platform_display =
      reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));

  std::vector<Candidate> hardware, software;
  if ((want == "auto" || want == "device") && get_platform_display &&
      has_extension(client_ext, "EGL_EXT_platform_device")) {
    auto query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
    auto query_string =
        reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(eglGetProcAddress("eglQueryDeviceStringEXT"));
    EGLDeviceEXT devices[16];
    EGLint n = 0;
    if (query_devices && query_devices(16, devices, &n)) {
      for (EGLint i = 0; i < n; ++i) {
        const char* dev_ext = query_string ? query_string(devices[i], EGL_EXTENSIONS) : nullptr;
        const bool is_software = has_extension(dev_ext, "EGL_MESA_device_software");
        EGLDisplay d = get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
        if (d == EGL_NO_DISPLAY) continue;
        (is_software ? software : hardware)
            .push_back({d, std::string("EGL device ") + std::to_string(i) + (is_software ? " (software)" : "")});
      }
    }
  } else if (want == "device") {
    notes += "EGL_EXT_platform_device is not available; ";
  }
  for (auto& c : hardware) out.push_back(c);
  if ((want == "auto" || want == "surfaceless") && get_platform_display &&
      has_extension(client_ext, "EGL_MESA_platform_surfaceless")) {
    EGLDisplay d = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (d != EGL_NO_DISPLAY) out.push_back({d, "EGL surfaceless (Mesa)"});
  } else if (want == "surfaceless") {
    notes += "EGL_MESA_platform_surfaceless is not available; ";
  }
  for (auto& c : software) out.push_back(c);
  if (want == "auto" || want == "default") {
    EGLDisplay d = eglGetDisplay(EGL_DEFAULT_DISPLAY);
    if (d != EGL_NO_DISPLAY) out.push_back({d, "EGL default display"});
  }
  return out;
}

}  // namespace

std::unique_ptr<GlContext> make_headless_context(const HeadlessOptions& options) {
  std::string want = options.platform;
  if (const char* env = std::getenv("CLOUDVIEWER_EGL_PLATFORM"); env && *env) want = env;
  if (want != "auto" && want != "device" && want != "surfaceless" && want != "default") {
    throw ContextError("EGL platform '" + want + "' is unknown; expected auto, device, surfaceless or default");
  }
  std::string notes;
  for (const Candidate& c : candidates(want, notes)) {
    EGLint major = 0, minor = 0;
    if (!eglInitialize(c.display, &major, &minor)) {
      notes += c.platform + ": eglInitialize failed (" + egl_error_string(eglGetError()) + "); ";
      continue;
    }
    std::string why;
    EGLContext ctx = create_on(c.display, options.debug, why);
    if (ctx == EGL_NO_CONTEXT) {
      notes += c.platform + ": " + why + "; ";
      eglTerminate(c.display);
      continue;
    }
    return std::make_unique<EglContext>(c.display, ctx, c.platform);
  }
  throw ContextError("no headless OpenGL 4.5 core context (EGL platform '" + want + "'): " +
                     (notes.empty() ? std::string("no EGL display found") : notes));
}

}  // namespace cv::render
