// The one place OpenGL headers come in: core-profile prototypes resolved by libOpenGL (glvnd), so
// no loader is needed, plus GL error checking that names what was being done.
#pragma once

#ifndef GL_GLEXT_PROTOTYPES
#define GL_GLEXT_PROTOTYPES 1
#endif
#include <GL/glcorearb.h>

#include <stdexcept>
#include <string>

namespace cv::render {

// An OpenGL failure; the message names the operation and the GL error(s).
class GlError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Name of a glGetError code, e.g. "GL_INVALID_OPERATION".
const char* gl_error_name(GLenum err);

// Throws GlError if any GL error is pending, naming `what` and draining every pending error.
void check_gl(const char* what);

}  // namespace cv::render
