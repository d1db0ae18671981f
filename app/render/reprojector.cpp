// The viewer's temporal reprojection.
#include "render/reprojector.hpp"

#include "render/gl.hpp"

namespace cv::render {
namespace {

GLint loc(GLuint program, const char* name) { return glGetUniformLocation(program, name); }

void set3(GLuint p, const char* name, const glm::dvec3& v) {
  glProgramUniform3f(p, loc(p, name), static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z));
}

bool same_camera(const core::Camera& a, const core::Camera& b) {
  return a.lat_deg == b.lat_deg && a.lon_deg == b.lon_deg && a.alt_m == b.alt_m && a.heading_deg == b.heading_deg &&
         a.pitch_deg == b.pitch_deg && a.fov_deg == b.fov_deg && a.width == b.width && a.height == b.height;
}

}  // namespace

Reprojector::Reprojector(const ShaderLoader& loader)
    : program_(load_compute(loader, ShaderLoader::default_shader_dir() / "display" / "reproject.comp")) {}

Reprojector::~Reprojector() {
  if (history_) glDeleteTextures(1, &history_);
  if (sparse_) glDeleteTextures(1, &sparse_);
}

glm::ivec2 Reprojector::offset_of(int index) {
  // The 4 x 4 Bayer matrix: frame k marches the block's pixel whose entry is k, so consecutive frames
  // are far apart and any 4 consecutive ones cover each 2 x 2 quarter of the block once.
  static const int bayer[kBlock][kBlock] = {{0, 8, 2, 10}, {12, 4, 14, 6}, {3, 11, 1, 9}, {15, 7, 13, 5}};
  const int k = ((index % kFramesToComplete) + kFramesToComplete) % kFramesToComplete;
  for (int y = 0; y < kBlock; ++y)
    for (int x = 0; x < kBlock; ++x)
      if (bayer[y][x] == k) return {x, y};
  return {0, 0};
}

core::Camera Reprojector::sparse_camera(const core::Camera& full, int index) {
  const glm::ivec2 o = offset_of(index);
  core::Camera c = full;
  c.width = full.width / kBlock;
  c.height = full.height / kBlock;
  // Pixel (i, j)'s ray passes at (4 i + o + 1/2) / 4 of a sparse pixel: its centre plus (2 o - 3) / 8.
  c.pixel_shift_x = (2.0 * o.x - 3.0) / (2.0 * kBlock);
  c.pixel_shift_y = (2.0 * o.y - 3.0) / (2.0 * kBlock);
  return c;
}

unsigned Reprojector::sparse_target(const core::Camera& full) {
  const int w = full.width / kBlock, h = full.height / kBlock;
  if (w < 1 || h < 1 || full.width % kBlock || full.height % kBlock) {
    throw GlError("reprojection: the image must be whole 4 x 4 blocks, at least 4 x 4 pixels");
  }
  if (!sparse_ || w != sparse_w_ || h != sparse_h_) {
    if (sparse_) glDeleteTextures(1, &sparse_);
    glCreateTextures(GL_TEXTURE_2D, 1, &sparse_);
    glTextureStorage2D(sparse_, 1, GL_RGBA32F, w, h);
    sparse_w_ = w, sparse_h_ = h;
    check_gl("allocating the sparse frame");
  }
  return sparse_;
}

void Reprojector::reset() {
  previous_.reset();
  frames_since_change_ = 0;
  frames_since_doubt_ = kFramesToComplete;
}

void Reprojector::resolve(unsigned sparse_depth, const core::Camera& full, int index, bool changed, double r0_m, unsigned out) {
  if (!sparse_ || full.width / kBlock != sparse_w_ || full.height / kBlock != sparse_h_) {
    throw GlError("reprojection: march the sparse frame into sparse_target() first");
  }
  if (!history_ || full.width != width_ || full.height != height_) {
    if (history_) glDeleteTextures(1, &history_);
    glCreateTextures(GL_TEXTURE_2D, 1, &history_);
    glTextureStorage2D(history_, 1, GL_RGBA32F, full.width, full.height);
    glTextureParameteri(history_, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(history_, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(history_, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(history_, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    width_ = full.width, height_ = full.height;
    previous_.reset();  // nothing to reproject from
    check_gl("allocating the reprojection history");
  }
  const bool has_history = previous_.has_value();
  const bool moved = has_history && !same_camera(*previous_, full);
  // A turn or a zoom of the lens moves every point the same way whatever its depth, so the history
  // is exact there; a camera that moved, or a medium that changed, leaves history that may be wrong
  // until each pixel is marched again: the clamp holds for the 16 frames that take.
  const bool translated = has_history && (previous_->lat_deg != full.lat_deg || previous_->lon_deg != full.lon_deg ||
                                          previous_->alt_m != full.alt_m);
  if (!has_history || moved || changed) frames_since_change_ = 0;
  if (translated || changed) frames_since_doubt_ = 0;
  const core::Camera prev = has_history ? *previous_ : full;
  const core::CameraFrame now = core::camera_frame(full), then = core::camera_frame(prev);
  const GLuint p = program_.id();
  glProgramUniform2i(p, loc(p, "u_full"), full.width, full.height);
  const glm::ivec2 o = offset_of(index);
  glProgramUniform2i(p, loc(p, "u_offset"), o.x, o.y);
  glProgramUniform1i(p, loc(p, "u_has_history"), has_history ? 1 : 0);
  glProgramUniform1i(p, loc(p, "u_clamp"), clamp_ && frames_since_doubt_ < kFramesToComplete ? 1 : 0);
  set3(p, "u_delta", core::camera_ecef(full, r0_m) - core::camera_ecef(prev, r0_m));  // in double, then float
  set3(p, "u_forward", now.forward);
  set3(p, "u_right", now.right);
  set3(p, "u_up", now.up);
  glProgramUniform1f(p, loc(p, "u_tan_half"), static_cast<float>(now.tan_half));
  set3(p, "u_cam", core::camera_ecef(full, r0_m));
  glProgramUniform1f(p, loc(p, "u_r0"), static_cast<float>(r0_m));
  set3(p, "u_prev_forward", then.forward);
  set3(p, "u_prev_right", then.right);
  set3(p, "u_prev_up", then.up);
  glProgramUniform1f(p, loc(p, "u_prev_tan_half"), static_cast<float>(then.tan_half));
  glBindImageTexture(0, out, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
  glBindTextureUnit(0, history_);
  glBindTextureUnit(1, sparse_);
  glBindTextureUnit(2, sparse_depth);
  glUseProgram(p);
  glDispatchCompute(static_cast<GLuint>((full.width + 7) / 8), static_cast<GLuint>((full.height + 7) / 8), 1);
  glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
  // The result is the next frame's history.
  glCopyImageSubData(out, GL_TEXTURE_2D, 0, 0, 0, 0, history_, GL_TEXTURE_2D, 0, 0, 0, 0, full.width, full.height, 1);
  glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
  check_gl("reprojecting the viewer's frame");
  previous_ = full;
  ++frames_since_change_;
  ++frames_since_doubt_;
}

}  // namespace cv::render
