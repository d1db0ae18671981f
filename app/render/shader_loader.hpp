// Loads GLSL with `#include "file"` (each file once per program, an X-macro table at each include), a prelude that defines the
// physics dialect and the feature macros, and `#line` directives so compiler messages name the
// right file and line; compiles compute programs and rewrites their logs with file names.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "render/gl.hpp"
#include "render/shader_features.hpp"

namespace cv::render {

// A shader that failed to load or compile; the message holds the remapped log.
class ShaderError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ShaderSource {
  std::string text;                 // complete GLSL, ready for glShaderSource
  std::vector<std::string> files;   // source-string number -> file; [0] is the prelude
  // Rewrites "0:12(3): error" (Mesa) and "0(12) : error" (NVIDIA) into "file:12(3): error".
  std::string remap_log(const std::string& log) const;
};

class ShaderLoader {
 public:
  // Includes resolve against the including file's folder first, then these folders in order.
  explicit ShaderLoader(std::vector<std::filesystem::path> include_dirs);

  // The folder of shaders this build was made from, or $CLOUDVIEWER_SHADER_DIR when set.
  static std::filesystem::path default_shader_dir();

  ShaderSource load(const std::filesystem::path& file, const ShaderFeatures& features = {},
                    const std::vector<std::pair<std::string, std::string>>& defines = {}) const;

  // The GLSL prelude: version, the physics dialect (real = float, CV_FN, ...), features, defines.
  static std::string prelude(const ShaderFeatures& features,
                             const std::vector<std::pair<std::string, std::string>>& defines);

 private:
  std::filesystem::path resolve(const std::string& name, const std::filesystem::path& from_dir,
                                const std::string& where) const;
  void append(const std::filesystem::path& file, ShaderSource& out, std::vector<std::string>& stack) const;
  std::vector<std::filesystem::path> include_dirs_;
};

// An owned GL program object.
class GlProgram {
 public:
  GlProgram() = default;
  explicit GlProgram(GLuint id) : id_(id) {}
  GlProgram(GlProgram&& o) noexcept : id_(std::exchange(o.id_, 0)) {}
  GlProgram& operator=(GlProgram&& o) noexcept {
    std::swap(id_, o.id_);
    return *this;
  }
  GlProgram(const GlProgram&) = delete;
  GlProgram& operator=(const GlProgram&) = delete;
  ~GlProgram() {
    if (id_) glDeleteProgram(id_);
  }
  GLuint id() const { return id_; }

 private:
  GLuint id_ = 0;
};

// Compiles and links a compute shader; throws ShaderError with the remapped log, the top file's
// path and the driver's GLSL version.
GlProgram compile_compute(const ShaderSource& source);

// Loads and compiles in one step (needs a current context).
GlProgram load_compute(const ShaderLoader& loader, const std::filesystem::path& file,
                       const ShaderFeatures& features = {},
                       const std::vector<std::pair<std::string, std::string>>& defines = {});

}  // namespace cv::render
