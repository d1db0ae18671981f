// Shader loading: includes, prelude, #line remapping, compute program compilation.
#include "render/shader_loader.hpp"

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <regex>
#include <sstream>

namespace cv::render {

namespace fs = std::filesystem;

const char* feature_macro(ShaderFeature f) {
  switch (f) {
    case ShaderFeature::MultipleScattering: return "CV_FEATURE_MULTIPLE_SCATTERING";
    case ShaderFeature::MiePhase: return "CV_FEATURE_MIE_PHASE";
    case ShaderFeature::IcePhase: return "CV_FEATURE_ICE_PHASE";
    case ShaderFeature::SunShadow: return "CV_FEATURE_SUN_SHADOW";
    case ShaderFeature::NoiseDetail: return "CV_FEATURE_NOISE_DETAIL";
    case ShaderFeature::EmptySpaceSkip: return "CV_FEATURE_EMPTY_SPACE_SKIP";
    case ShaderFeature::SkyAmbient: return "CV_FEATURE_SKY_AMBIENT";
  }
  return "CV_FEATURE_UNKNOWN";
}

std::string ShaderFeatures::defines() const {
  std::string out;
  for (std::uint32_t bit = 1; bit != 0 && bit <= bits_; bit <<= 1) {
    if (bits_ & bit) out += std::string("#define ") + feature_macro(static_cast<ShaderFeature>(bit)) + " 1\n";
  }
  return out;
}

namespace {
// Mesa (22.x) ignores the source-string number of `#line` in its messages, so the file index also
// goes into the line number itself: line n of file k is reported as k * kLineBase + n.
constexpr long kLineBase = 100000;

std::string line_directive(int file_index, int line) {
  return "#line " + std::to_string(file_index * kLineBase + line) + " " + std::to_string(file_index) + "\n";
}
}  // namespace

ShaderLoader::ShaderLoader(std::vector<fs::path> include_dirs) : include_dirs_(std::move(include_dirs)) {}

fs::path ShaderLoader::default_shader_dir() {
  if (const char* env = std::getenv("CLOUDVIEWER_SHADER_DIR"); env && *env) return env;
  return CV_SHADER_DIR;
}

std::string ShaderLoader::prelude(const ShaderFeatures& features,
                                  const std::vector<std::pair<std::string, std::string>>& defines) {
  std::string p =
      "#version 450 core\n"
      "#define CV_GLSL 1\n"
      // The physics dialect shared with C++ (core/physics/physics.hpp defines the C++ side).
      "#define real float\n#define real2 vec2\n#define real3 vec3\n#define real4 vec4\n"
      "#define CV_FN\n#define CV_IN(T) in T\n#define CV_OUT(T) out T\n#define CV_INOUT(T) inout T\n"
      "const float CV_SPLITTER = 4097.0;\n";
  p += features.defines();
  for (const auto& [name, value] : defines) p += "#define " + name + " " + value + "\n";
  return p;
}

fs::path ShaderLoader::resolve(const std::string& name, const fs::path& from_dir, const std::string& where) const {
  std::vector<fs::path> tried;
  tried.push_back(from_dir / name);
  for (const auto& d : include_dirs_) tried.push_back(d / name);
  for (const auto& p : tried) {
    std::error_code ec;
    if (fs::is_regular_file(p, ec)) return fs::weakly_canonical(p);
  }
  std::string list;
  for (const auto& p : tried) list += (list.empty() ? "" : ", ") + p.string();
  throw ShaderError(where + ": cannot find include \"" + name + "\" (looked for " + list + ")");
}

void ShaderLoader::append(const fs::path& file, ShaderSource& out, std::vector<std::string>& stack) const {
  const std::string key = file.string();
  std::ifstream in(file);
  if (!in) throw ShaderError(key + ": cannot read shader file");
  // Each file once per program, like #pragma once, except an X-macro table (its first line begins
  // "// X-macro table"), which is expanded again at each include under the includer's macros.
  std::string first;
  std::getline(in, first);
  const bool table = first.rfind("// X-macro table", 0) == 0;
  in.clear();
  in.seekg(0);
  int index = -1;
  for (std::size_t i = 0; i < out.files.size(); ++i) {
    if (out.files[i] == key) index = static_cast<int>(i);
  }
  if (index >= 0 && !table) return;
  if (index < 0) {
    index = static_cast<int>(out.files.size());
    out.files.push_back(key);
  }
  stack.push_back(key);

  static const std::regex include_re(R"(^\s*#\s*include\s*[<"]([^">]+)[">]\s*(//.*)?$)");
  static const std::regex version_re(R"(^\s*#\s*version\b)");
  out.text += line_directive(index, 1);
  std::string line;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    std::smatch m;
    const std::string where = key + ":" + std::to_string(lineno);
    if (std::regex_search(line, version_re)) {
      throw ShaderError(where + ": #version is set by the shader loader (450 core); remove this line");
    }
    if (std::regex_match(line, m, include_re)) {
      const fs::path inc = resolve(m[1].str(), file.parent_path(), where);
      for (const auto& s : stack) {
        if (s == inc.string()) throw ShaderError(where + ": include cycle through " + inc.string());
      }
      append(inc, out, stack);
      // Back in this file: the next line is lineno + 1.
      out.text += line_directive(index, lineno + 1);
      continue;
    }
    out.text += line;
    out.text += '\n';
  }
  stack.pop_back();
}

ShaderSource ShaderLoader::load(const fs::path& file, const ShaderFeatures& features,
                                const std::vector<std::pair<std::string, std::string>>& defines) const {
  ShaderSource out;
  out.files.push_back("<prelude>");
  out.text = prelude(features, defines);
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) throw ShaderError(file.string() + ": shader file not found");
  std::vector<std::string> stack;
  append(fs::weakly_canonical(file), out, stack);
  return out;
}

std::string ShaderSource::remap_log(const std::string& log) const {
  static const std::regex mesa_re(R"(^(\d+):(\d+)\((\d+)\):)");
  static const std::regex nvidia_re(R"(^(\d+)\((\d+)\)\s*:)");
  std::istringstream in(log);
  std::string line, out;
  while (std::getline(in, line)) {
    std::smatch m;
    // "file:line" from the reported source number and line, preferring the index encoded in the line.
    auto locate = [&](const std::string& src, const std::string& ln) {
      long idx = std::stol(src), l = std::stol(ln);
      if (l >= kLineBase) {
        idx = l / kLineBase;
        l %= kLineBase;
      }
      const std::string file =
          idx >= 0 && static_cast<size_t>(idx) < files.size() ? files[static_cast<size_t>(idx)] : "source " + src;
      return file + ":" + std::to_string(l);
    };
    if (std::regex_search(line, m, mesa_re)) {
      line = locate(m[1], m[2]) + "(" + m[3].str() + "):" + m.suffix().str();
    } else if (std::regex_search(line, m, nvidia_re)) {
      line = locate(m[1], m[2]) + ":" + m.suffix().str();
    }
    out += line + "\n";
  }
  return out;
}

namespace {
std::string info_log(GLuint obj, bool program) {
  GLint len = 0;
  program ? glGetProgramiv(obj, GL_INFO_LOG_LENGTH, &len) : glGetShaderiv(obj, GL_INFO_LOG_LENGTH, &len);
  std::string log(static_cast<size_t>(len > 0 ? len : 1), '\0');
  program ? glGetProgramInfoLog(obj, len, nullptr, log.data()) : glGetShaderInfoLog(obj, len, nullptr, log.data());
  log.resize(std::strlen(log.c_str()));
  return log;
}
}  // namespace

GlProgram compile_compute(const ShaderSource& source) {
  const std::string top = source.files.size() > 1 ? source.files[1] : "<unnamed>";
  const auto* glsl = reinterpret_cast<const char*>(glGetString(GL_SHADING_LANGUAGE_VERSION));
  const std::string glsl_version = glsl ? glsl : "?";
  GLuint shader = glCreateShader(GL_COMPUTE_SHADER);
  const char* text = source.text.c_str();
  glShaderSource(shader, 1, &text, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    const std::string log = source.remap_log(info_log(shader, false));
    glDeleteShader(shader);
    throw ShaderError(top + ": compute shader failed to compile (driver GLSL " + glsl_version + "):\n" + log);
  }
  GLuint program = glCreateProgram();
  glAttachShader(program, shader);
  glLinkProgram(program);
  glDeleteShader(shader);
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    const std::string log = source.remap_log(info_log(program, true));
    glDeleteProgram(program);
    throw ShaderError(top + ": compute program failed to link (driver GLSL " + glsl_version + "):\n" + log);
  }
  check_gl("compiling a compute shader");
  return GlProgram(program);
}

GlProgram load_compute(const ShaderLoader& loader, const fs::path& file, const ShaderFeatures& features,
                       const std::vector<std::pair<std::string, std::string>>& defines) {
  return compile_compute(loader.load(file, features, defines));
}

}  // namespace cv::render
