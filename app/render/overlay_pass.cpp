// The overlay pass: camera-relative geometry into distance and radiance textures.
#include "render/overlay_pass.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <glm/glm.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "render/presenter.hpp"

namespace cv::render {
namespace {
constexpr GLuint kPrevUnit = 14, kOpaqueUnit = 15;  // overlay.frag's u_prev and u_front_opaque
constexpr double kNearM = 0.05;   // the projection's clip planes: a metre's depth resolution comes
constexpr double kFarM = 1.0e8;   // from the linear distance the fragment writes, not from these
}  // namespace

OverlayPass::OverlayPass(const ShaderLoader& loader)
    : program_(load_graphics(loader, ShaderLoader::default_shader_dir() / "render" / "overlay.vert",
                             ShaderLoader::default_shader_dir() / "render" / "overlay.frag")) {
  glCreateFramebuffers(1, &fbo_);
  check_gl("creating the overlay pass");
}

OverlayPass::~OverlayPass() {
  const GLuint textures[] = {distance_, color_, depth_};
  glDeleteTextures(3, textures);
  glDeleteFramebuffers(1, &fbo_);
  for (Buffers& b : transient_) free_buffers(b);
  for (Kept& k : kept_) free_buffers(k.buffers);
  const GLuint peel[] = {peel_distance_[0], peel_distance_[1], peel_color_[0], peel_color_[1], peel_depth_, layer_distance_, layer_color_};
  glDeleteTextures(7, peel);
  glDeleteFramebuffers(1, &peel_fbo_);
}

OverlayPass::Buffers OverlayPass::make_buffers(const core::OverlayMesh& mesh) {
  Buffers b;
  const core::OverlayInstances& in = mesh.instances;
  if (!in.empty()) {
    glCreateVertexArrays(1, &b.inst_vao);
    glCreateBuffers(1, &b.glyph);
    glCreateBuffers(1, &b.glyph_index);
    glCreateBuffers(1, &b.origins);
    glCreateBuffers(1, &b.frames);
    glNamedBufferStorage(b.glyph, static_cast<GLsizeiptr>(in.glyph_positions.size() * sizeof(glm::vec3)), in.glyph_positions.data(), 0);
    glNamedBufferStorage(b.glyph_index, static_cast<GLsizeiptr>(in.glyph_triangles.size() * sizeof(std::uint32_t)), in.glyph_triangles.data(),
                         0);
    glNamedBufferStorage(b.origins, static_cast<GLsizeiptr>(in.count() * sizeof(glm::dvec3)), in.origins.data(), 0);
    // Per instance: axis x, y, z (3 floats each), colour (4, alpha 1: instances are opaque), 3 spare.
    std::vector<float> frames(16 * in.count(), 0.0f);
    for (std::size_t k = 0; k < in.count(); ++k) {
      float* f = &frames[16 * k];
      for (int c = 0; c < 3; ++c) f[c] = in.axis_x[k][c], f[3 + c] = in.axis_y[k][c], f[6 + c] = in.axis_z[k][c];
      const glm::vec4 color = k < in.colors.size() ? in.colors[k] : glm::vec4(1.0f);
      for (int c = 0; c < 3; ++c) f[9 + c] = color[c];
      f[12] = 1.0f;
    }
    glNamedBufferStorage(b.frames, static_cast<GLsizeiptr>(frames.size() * sizeof(float)), frames.data(), 0);
    // overlay.vert's locations: 2 the glyph's vertex; per instance (divisor 1) 0 the origin in
    // double (a_position's location), 3, 4, 5 the axes and 6 the colour.
    glVertexArrayVertexBuffer(b.inst_vao, 0, b.glyph, 0, sizeof(glm::vec3));
    glVertexArrayAttribFormat(b.inst_vao, 2, 3, GL_FLOAT, GL_FALSE, 0);
    glVertexArrayAttribBinding(b.inst_vao, 2, 0);
    glEnableVertexArrayAttrib(b.inst_vao, 2);
    glVertexArrayVertexBuffer(b.inst_vao, 1, b.origins, 0, sizeof(glm::dvec3));
    glVertexArrayBindingDivisor(b.inst_vao, 1, 1);
    glVertexArrayAttribLFormat(b.inst_vao, 0, 3, GL_DOUBLE, 0);
    glVertexArrayAttribBinding(b.inst_vao, 0, 1);
    glEnableVertexArrayAttrib(b.inst_vao, 0);
    glVertexArrayVertexBuffer(b.inst_vao, 2, b.frames, 0, 16 * sizeof(float));
    glVertexArrayBindingDivisor(b.inst_vao, 2, 1);
    for (GLuint a = 0; a < 4; ++a) {
      glVertexArrayAttribFormat(b.inst_vao, 3 + a, a < 3 ? 3 : 4, GL_FLOAT, GL_FALSE, static_cast<GLuint>(3 * a * sizeof(float)));
      glVertexArrayAttribBinding(b.inst_vao, 3 + a, 2);
      glEnableVertexArrayAttrib(b.inst_vao, 3 + a);
    }
    glVertexArrayElementBuffer(b.inst_vao, b.glyph_index);
    b.glyph_indices = in.glyph_triangles.size();
    b.instances = in.count();
  }
  if (mesh.triangles.empty() && mesh.lines.empty()) {  // instances alone (a buffer of no bytes is an error)
    ++uploads_;
    check_gl("uploading overlay geometry");
    return b;
  }
  glCreateVertexArrays(1, &b.vao);
  glCreateBuffers(1, &b.pos);
  glCreateBuffers(1, &b.color);
  glCreateBuffers(1, &b.index);
  // Positions as doubles (64-bit attributes, glVertexArrayAttribLFormat): the vertex shader takes
  // the camera off in double.
  glNamedBufferStorage(b.pos, static_cast<GLsizeiptr>(mesh.positions.size() * sizeof(glm::dvec3)), mesh.positions.data(), 0);
  std::vector<glm::vec4> colors = mesh.colors;
  colors.resize(mesh.positions.size(), glm::vec4(1.0f));
  glNamedBufferStorage(b.color, static_cast<GLsizeiptr>(colors.size() * sizeof(glm::vec4)), colors.data(), 0);
  std::vector<std::uint32_t> indices = mesh.triangles;
  indices.insert(indices.end(), mesh.lines.begin(), mesh.lines.end());
  glNamedBufferStorage(b.index, static_cast<GLsizeiptr>(indices.size() * sizeof(std::uint32_t)), indices.data(), 0);
  glVertexArrayVertexBuffer(b.vao, 0, b.pos, 0, sizeof(glm::dvec3));
  glVertexArrayAttribLFormat(b.vao, 0, 3, GL_DOUBLE, 0);
  glVertexArrayAttribBinding(b.vao, 0, 0);
  glEnableVertexArrayAttrib(b.vao, 0);
  glVertexArrayVertexBuffer(b.vao, 1, b.color, 0, sizeof(glm::vec4));
  glVertexArrayAttribFormat(b.vao, 1, 4, GL_FLOAT, GL_FALSE, 0);
  glVertexArrayAttribBinding(b.vao, 1, 1);
  glEnableVertexArrayAttrib(b.vao, 1);
  glVertexArrayElementBuffer(b.vao, b.index);
  b.triangles = mesh.triangles.size();
  b.lines = mesh.lines.size();
  for (std::size_t k = 0; k < mesh.triangles.size() && !b.translucent; ++k) b.translucent = colors[mesh.triangles[k]].a < core::kOpaqueAlpha;
  ++uploads_;
  check_gl("uploading overlay geometry");
  return b;
}

void OverlayPass::free_buffers(Buffers& b) {
  const GLuint buffers[] = {b.pos, b.color, b.index, b.glyph, b.glyph_index, b.origins, b.frames};
  glDeleteBuffers(7, buffers);
  const GLuint arrays[] = {b.vao, b.inst_vao};
  glDeleteVertexArrays(2, arrays);
  b = Buffers{};
}

void OverlayPass::begin(const core::Camera& cam, double r0_m) {
  if (cam.width != w_ || cam.height != h_) {
    const GLuint textures[] = {distance_, color_, depth_};
    glDeleteTextures(3, textures);
    w_ = cam.width, h_ = cam.height;
    glCreateTextures(GL_TEXTURE_2D, 1, &distance_);
    glTextureStorage2D(distance_, 1, GL_R32F, w_, h_);
    glCreateTextures(GL_TEXTURE_2D, 1, &color_);
    glTextureStorage2D(color_, 1, GL_RGBA32F, w_, h_);
    glCreateTextures(GL_TEXTURE_2D, 1, &depth_);
    glTextureStorage2D(depth_, 1, GL_DEPTH_COMPONENT32F, w_, h_);
    glNamedFramebufferTexture(fbo_, GL_COLOR_ATTACHMENT0, distance_, 0);
    glNamedFramebufferTexture(fbo_, GL_COLOR_ATTACHMENT1, color_, 0);
    glNamedFramebufferTexture(fbo_, GL_DEPTH_ATTACHMENT, depth_, 0);
    const GLenum draw_buffers[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glNamedFramebufferDrawBuffers(fbo_, 2, draw_buffers);
    if (glCheckNamedFramebufferStatus(fbo_, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
      throw GlError("the overlay pass's framebuffer is incomplete");
    }
  }
  // Kept meshes not drawn in the last frame are released (and their meshes with them).
  std::erase_if(kept_, [](Kept& k) {
    if (!k.drawn) free_buffers(k.buffers);
    return !k.drawn;
  });
  for (Kept& k : kept_) k.drawn = false;
  for (Buffers& b : transient_) free_buffers(b);
  transient_.clear();
  translucent_.clear();
  peeled_ = true;
  peel_ms_ = 0.0;
  cam_ = cam;
  r0_m_ = r0_m;
  camera_m_ = core::camera_ecef(cam, r0_m);
  const float zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
  const float one = 1.0f;
  glClearNamedFramebufferfv(fbo_, GL_COLOR, 0, zero);
  glClearNamedFramebufferfv(fbo_, GL_COLOR, 1, zero);
  glClearNamedFramebufferfv(fbo_, GL_DEPTH, 0, &one);
  check_gl("starting the overlay pass");
}

double OverlayPass::draw(const core::OverlayMesh& mesh, float line_width_px) {
  const auto t0 = std::chrono::steady_clock::now();
  if (mesh.empty() || w_ == 0) return 0.0;
  transient_.push_back(make_buffers(mesh));  // kept until the next begin, for peeling
  return draw_buffers(transient_.back(), line_width_px, t0);
}

double OverlayPass::draw(const std::shared_ptr<const core::OverlayMesh>& mesh, float line_width_px) {
  const auto t0 = std::chrono::steady_clock::now();
  if (!mesh || mesh->empty() || w_ == 0) return 0.0;
  auto it = std::find_if(kept_.begin(), kept_.end(), [&](const Kept& k) { return k.mesh == mesh; });
  if (it == kept_.end()) it = kept_.insert(kept_.end(), Kept{mesh, make_buffers(*mesh), false});
  it->drawn = true;
  return draw_buffers(it->buffers, line_width_px, t0);
}

void OverlayPass::use_program(int peel) {
  const glm::mat4 view_proj(core::camera_projection_matrix(cam_, kNearM, kFarM) * core::camera_view_matrix(cam_));
  glBindFramebuffer(GL_FRAMEBUFFER, peel < 0 ? fbo_ : peel_fbo_);
  glViewport(0, 0, w_, h_);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  glUseProgram(program_.id());
  glUniformMatrix4fv(glGetUniformLocation(program_.id(), "u_view_proj"), 1, GL_FALSE, glm::value_ptr(view_proj));
  glUniform3d(glGetUniformLocation(program_.id(), "u_camera"), camera_m_.x, camera_m_.y, camera_m_.z);
  glUniform1d(glGetUniformLocation(program_.id(), "u_cq"), glm::dot(camera_m_, camera_m_) - r0_m_ * r0_m_);
  glUniform1f(glGetUniformLocation(program_.id(), "u_far"), static_cast<float>(kFarM));
  const core::CameraFrame cf = core::camera_frame(cam_);
  const glm::vec3 fw(cf.forward), rt(cf.right), up(cf.up);
  glUniform3fv(glGetUniformLocation(program_.id(), "u_forward"), 1, glm::value_ptr(fw));
  glUniform3fv(glGetUniformLocation(program_.id(), "u_right"), 1, glm::value_ptr(rt));
  glUniform3fv(glGetUniformLocation(program_.id(), "u_up"), 1, glm::value_ptr(up));
  glUniform2f(glGetUniformLocation(program_.id(), "u_tan_half"), static_cast<float>(cf.tan_half),
              static_cast<float>(cf.tan_half * h_ / w_));
  glUniform2f(glGetUniformLocation(program_.id(), "u_size"), static_cast<float>(w_), static_cast<float>(h_));
  glUniform1i(glGetUniformLocation(program_.id(), "u_peel"), peel < 0 ? 0 : 1);
  glUniform1i(glGetUniformLocation(program_.id(), "u_has_prev"), peel > 0 ? 1 : 0);
  glUniform1f(glGetUniformLocation(program_.id(), "u_bias"), 0.0f);
  glUniform1i(glGetUniformLocation(program_.id(), "u_instanced"), 0);
  if (peel >= 0) {
    glBindTextureUnit(kPrevUnit, peel > 0 ? peel_distance_[(peel - 1) % 2] : 0);
    glBindTextureUnit(kOpaqueUnit, distance_);
  }
}

double OverlayPass::draw_buffers(const Buffers& b, float line_width_px, std::chrono::steady_clock::time_point t0) {
  if (b.translucent) {
    translucent_.push_back(b);
    peeled_ = false;
  }
  use_program(-1);
  glBindVertexArray(b.vao);
  const GLint bias = glGetUniformLocation(program_.id(), "u_bias");
  if (b.triangles > 0) glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(b.triangles), GL_UNSIGNED_INT, nullptr);
  if (b.lines > 0) {
    // Wide lines where the driver draws them (a forward-compatible context refuses widths over 1).
    GLfloat range[2] = {1.0f, 1.0f};
    glGetFloatv(GL_ALIASED_LINE_WIDTH_RANGE, range);
    const float width = std::clamp(line_width_px, 1.0f, range[1]);
    glUniform1f(bias, static_cast<float>(core::kLineDistanceBias));
    glLineWidth(width);
    if (glGetError() != GL_NO_ERROR) glLineWidth(1.0f);
    glDrawElements(GL_LINES, static_cast<GLsizei>(b.lines), GL_UNSIGNED_INT,
                   reinterpret_cast<const void*>(b.triangles * sizeof(std::uint32_t)));
    glLineWidth(1.0f);
  }
  if (b.instances > 0) {  // one draw of the glyph for every instance
    glUniform1i(glGetUniformLocation(program_.id(), "u_instanced"), 1);
    glBindVertexArray(b.inst_vao);
    glDrawElementsInstanced(GL_TRIANGLES, static_cast<GLsizei>(b.glyph_indices), GL_UNSIGNED_INT, nullptr, static_cast<GLsizei>(b.instances));
    glUniform1i(glGetUniformLocation(program_.id(), "u_instanced"), 0);
  }
  glBindVertexArray(0);
  glUseProgram(0);
  glDisable(GL_DEPTH_TEST);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glFinish();
  check_gl("drawing overlays");
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

void OverlayPass::peel() {
  if (peeled_) return;
  peeled_ = true;
  const auto t0 = std::chrono::steady_clock::now();
  const int n = core::kTranslucentLayers;
  if (peel_w_ != w_ || peel_h_ != h_) {  // made on the first frame that has translucent geometry
    const GLuint old[] = {peel_distance_[0], peel_distance_[1], peel_color_[0], peel_color_[1], peel_depth_, layer_distance_, layer_color_};
    glDeleteTextures(7, old);
    if (!peel_fbo_) glCreateFramebuffers(1, &peel_fbo_);
    glCreateTextures(GL_TEXTURE_2D, 2, peel_distance_);
    glCreateTextures(GL_TEXTURE_2D, 2, peel_color_);
    for (int i = 0; i < 2; ++i) {
      glTextureStorage2D(peel_distance_[i], 1, GL_R32F, w_, h_);
      glTextureStorage2D(peel_color_[i], 1, GL_RGBA32F, w_, h_);
    }
    glCreateTextures(GL_TEXTURE_2D, 1, &peel_depth_);
    glTextureStorage2D(peel_depth_, 1, GL_DEPTH_COMPONENT32F, w_, h_);
    glCreateTextures(GL_TEXTURE_2D, 1, &layer_distance_);
    glTextureStorage2D(layer_distance_, 1, GL_R32F, n * w_, h_);
    glCreateTextures(GL_TEXTURE_2D, 1, &layer_color_);
    glTextureStorage2D(layer_color_, 1, GL_RGBA32F, n * w_, h_);
    glNamedFramebufferTexture(peel_fbo_, GL_DEPTH_ATTACHMENT, peel_depth_, 0);
    const GLenum draw_buffers[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glNamedFramebufferDrawBuffers(peel_fbo_, 2, draw_buffers);
    peel_w_ = w_, peel_h_ = h_;
  }
  const float zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
  const float one = 1.0f;
  // Layer k: the nearest translucent fragment strictly behind layer k - 1 and in front of the
  // opaque geometry (overlay.frag), by the depth test; then copied to its place side by side.
  for (int k = 0; k < n; ++k) {
    const int target = k % 2;
    glNamedFramebufferTexture(peel_fbo_, GL_COLOR_ATTACHMENT0, peel_distance_[target], 0);
    glNamedFramebufferTexture(peel_fbo_, GL_COLOR_ATTACHMENT1, peel_color_[target], 0);
    if (glCheckNamedFramebufferStatus(peel_fbo_, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
      throw GlError("the overlay pass's peeling framebuffer is incomplete");
    }
    glClearNamedFramebufferfv(peel_fbo_, GL_COLOR, 0, zero);
    glClearNamedFramebufferfv(peel_fbo_, GL_COLOR, 1, zero);
    glClearNamedFramebufferfv(peel_fbo_, GL_DEPTH, 0, &one);
    use_program(k);
    for (const Buffers& b : translucent_) {
      glBindVertexArray(b.vao);
      glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(b.triangles), GL_UNSIGNED_INT, nullptr);
    }
    glBindVertexArray(0);
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
    glCopyImageSubData(peel_distance_[target], GL_TEXTURE_2D, 0, 0, 0, 0, layer_distance_, GL_TEXTURE_2D, 0, k * w_, 0, 0, w_, h_, 1);
    glCopyImageSubData(peel_color_[target], GL_TEXTURE_2D, 0, 0, 0, 0, layer_color_, GL_TEXTURE_2D, 0, k * w_, 0, 0, w_, h_, 1);
  }
  glBindTextureUnit(kPrevUnit, 0);
  glBindTextureUnit(kOpaqueUnit, 0);
  glUseProgram(0);
  glDisable(GL_DEPTH_TEST);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glFinish();
  check_gl("peeling translucent overlays");
  peel_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

OpaqueInput OverlayPass::output() {
  peel();
  if (translucent_.empty()) return {distance_, color_};
  return {distance_, color_, layer_distance_, layer_color_, core::kTranslucentLayers};
}

core::OpaqueLayer OverlayPass::read() {
  peel();
  core::OpaqueLayer layer;
  layer.distance_m.resize(static_cast<std::size_t>(w_) * h_);
  layer.radiance_rgba.resize(4 * layer.distance_m.size());
  glGetTextureImage(distance_, 0, GL_RED, GL_FLOAT, static_cast<GLsizei>(layer.distance_m.size() * sizeof(float)), layer.distance_m.data());
  glGetTextureImage(color_, 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(layer.radiance_rgba.size() * sizeof(float)), layer.radiance_rgba.data());
  if (!translucent_.empty()) {
    layer.layers = core::kTranslucentLayers;
    layer.layer_distance_m.resize(static_cast<std::size_t>(layer.layers) * layer.distance_m.size());
    layer.layer_rgba.resize(4 * layer.layer_distance_m.size());
    glGetTextureImage(layer_distance_, 0, GL_RED, GL_FLOAT, static_cast<GLsizei>(layer.layer_distance_m.size() * sizeof(float)),
                      layer.layer_distance_m.data());
    glGetTextureImage(layer_color_, 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(layer.layer_rgba.size() * sizeof(float)),
                      layer.layer_rgba.data());
  }
  check_gl("reading the overlay pass back");
  return layer;
}

}  // namespace cv::render
