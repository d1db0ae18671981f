// The viewer's GPU path: graphics program linking, accumulation dispatch and the tonemap draw.
#include "render/presenter.hpp"

#include <string>

namespace cv::render {
namespace fs = std::filesystem;
namespace {
GLint loc(GLuint program, const char* name) { return glGetUniformLocation(program, name); }

std::string info_log(GLuint object, bool is_program) {
  GLint n = 0;
  if (is_program) glGetProgramiv(object, GL_INFO_LOG_LENGTH, &n);
  else glGetShaderiv(object, GL_INFO_LOG_LENGTH, &n);
  std::string log(static_cast<std::size_t>(n > 0 ? n : 1), '\0');
  if (is_program) glGetProgramInfoLog(object, n, nullptr, log.data());
  else glGetShaderInfoLog(object, n, nullptr, log.data());
  return log.c_str();
}

GLuint compile_stage(const ShaderLoader& loader, const fs::path& file, GLenum stage) {
  const ShaderSource src = loader.load(file);
  GLuint s = glCreateShader(stage);
  const char* text = src.text.c_str();
  glShaderSource(s, 1, &text, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    const std::string log = src.remap_log(info_log(s, false));
    glDeleteShader(s);
    throw ShaderError(file.string() + " does not compile:\n" + log);
  }
  return s;
}
}  // namespace

GlProgram load_graphics(const ShaderLoader& loader, const fs::path& vertex, const fs::path& fragment) {
  const GLuint vs = compile_stage(loader, vertex, GL_VERTEX_SHADER);
  GLuint fsh = 0;
  try {
    fsh = compile_stage(loader, fragment, GL_FRAGMENT_SHADER);
  } catch (...) {
    glDeleteShader(vs);
    throw;
  }
  GlProgram program(glCreateProgram());
  glAttachShader(program.id(), vs);
  glAttachShader(program.id(), fsh);
  glLinkProgram(program.id());
  glDeleteShader(vs);  // flagged for deletion; freed with the program
  glDeleteShader(fsh);
  GLint ok = 0;
  glGetProgramiv(program.id(), GL_LINK_STATUS, &ok);
  if (!ok) {
    throw ShaderError(vertex.string() + " + " + fragment.string() + " do not link:\n" + info_log(program.id(), true));
  }
  return program;
}

Presenter::Presenter(const ShaderLoader& loader)
    : accumulate_(load_compute(loader, ShaderLoader::default_shader_dir() / "display" / "accumulate.comp")),
      present_(load_graphics(loader, ShaderLoader::default_shader_dir() / "display" / "present.vert",
                             ShaderLoader::default_shader_dir() / "display" / "present.frag")) {
  // Core profile draws need a vertex array object bound, even one with no attributes.
  glCreateVertexArrays(1, &vao_);
  check_gl("creating the presenter's vertex array");
}

Presenter::~Presenter() {
  if (frame_) glDeleteTextures(1, &frame_);
  if (mean_) glDeleteTextures(1, &mean_);
  if (vao_) glDeleteVertexArrays(1, &vao_);
}

void Presenter::resize(int width, int height) {
  if (width < 1 || height < 1) throw GlError("presenter: the march size must be at least 1 x 1 pixels");
  if (frame_) glDeleteTextures(1, &frame_);
  if (mean_) glDeleteTextures(1, &mean_);
  frame_ = mean_ = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &frame_);
  glTextureStorage2D(frame_, 1, GL_RGBA32F, width, height);
  glCreateTextures(GL_TEXTURE_2D, 1, &mean_);
  glTextureStorage2D(mean_, 1, GL_RGBA32F, width, height);
  width_ = width;
  height_ = height;
  check_gl("allocating the viewer's march and accumulation textures");
}

void Presenter::accumulate(int count) {
  const GLuint p = accumulate_.id();
  glProgramUniform2i(p, loc(p, "u_size"), width_, height_);
  glProgramUniform1i(p, loc(p, "u_count"), count);
  glBindImageTexture(0, mean_, 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
  glBindImageTexture(1, frame_, 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
  glUseProgram(p);
  glDispatchCompute(static_cast<GLuint>((width_ + 7) / 8), static_cast<GLuint>((height_ + 7) / 8), 1);
  // The draw samples the mean; the next march overwrites the frame the dispatch has read.
  glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
  check_gl("accumulating the viewer's frames");
}

void Presenter::draw(const ToneSettings& tone, int x, int y, int w, int h, const std::optional<std::array<int, 4>>& clip) const {
  const GLuint p = present_.id();
  glProgramUniform1f(p, loc(p, "u_exposure"), static_cast<float>(tone.exposure));
  glProgramUniform3f(p, loc(p, "u_background"), static_cast<float>(tone.background.x),
                     static_cast<float>(tone.background.y), static_cast<float>(tone.background.z));
  glProgramUniform4i(p, loc(p, "u_viewport"), x, y, w, h);
  glViewport(x, y, w, h);
  glDisable(GL_BLEND);
  glDisable(GL_DEPTH_TEST);
  if (clip) {
    glEnable(GL_SCISSOR_TEST);
    glScissor((*clip)[0], (*clip)[1], (*clip)[2], (*clip)[3]);
  } else {
    glDisable(GL_SCISSOR_TEST);
  }
  glDisable(GL_CULL_FACE);
  glBindTextureUnit(0, mean_);
  glUseProgram(p);
  glBindVertexArray(vao_);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glBindVertexArray(0);
  glDisable(GL_SCISSOR_TEST);
  check_gl("drawing the tonemapped image");
}

}  // namespace cv::render
