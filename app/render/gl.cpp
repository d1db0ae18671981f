// GL error checking.
#include "render/gl.hpp"

namespace cv::render {

const char* gl_error_name(GLenum err) {
  switch (err) {
    case GL_NO_ERROR: return "GL_NO_ERROR";
    case GL_INVALID_ENUM: return "GL_INVALID_ENUM";
    case GL_INVALID_VALUE: return "GL_INVALID_VALUE";
    case GL_INVALID_OPERATION: return "GL_INVALID_OPERATION";
    case GL_INVALID_FRAMEBUFFER_OPERATION: return "GL_INVALID_FRAMEBUFFER_OPERATION";
    case GL_OUT_OF_MEMORY: return "GL_OUT_OF_MEMORY";
    case GL_STACK_UNDERFLOW: return "GL_STACK_UNDERFLOW";
    case GL_STACK_OVERFLOW: return "GL_STACK_OVERFLOW";
    default: return "unknown GL error";
  }
}

void check_gl(const char* what) {
  GLenum err = glGetError();
  if (err == GL_NO_ERROR) return;
  std::string msg = std::string("OpenGL error during ") + what + ": " + gl_error_name(err);
  // Several errors can be queued; report them all and leave none behind for the next check.
  for (int i = 0; i < 16 && (err = glGetError()) != GL_NO_ERROR; ++i) {
    msg += std::string(", ") + gl_error_name(err);
  }
  throw GlError(msg);
}

}  // namespace cv::render
