// The viewer's temporal reprojection.
#include "render/reprojector.hpp"

#include <cmath>
#include <limits>

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

bool same_volume_grid(const core::VolumeGrid& a, const core::VolumeGrid& b) {
  const auto same_axis = [](const core::RegularAxis& x, const core::RegularAxis& y) {
    return x.start == y.start && x.step == y.step && x.count == y.count;
  };
  return same_axis(a.lon_deg, b.lon_deg) && same_axis(a.lat_deg, b.lat_deg) && same_axis(a.alt_m, b.alt_m) &&
         a.earth_radius_m == b.earth_radius_m;
}

}  // namespace

void Reprojector::upload_motion(int nx, int ny, int levels, const float* rg) {
  if (!motion_ || nx != motion_size_[0] || ny != motion_size_[1] || levels != motion_size_[2]) {
    if (motion_) glDeleteTextures(1, &motion_);
    glCreateTextures(GL_TEXTURE_3D, 1, &motion_);
    glTextureStorage3D(motion_, 1, GL_RG32F, nx, ny, levels);
    glTextureParameteri(motion_, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(motion_, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(motion_, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(motion_, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTextureParameteri(motion_, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
    motion_size_ = {nx, ny, levels};
  }
  glTextureSubImage3D(motion_, 0, 0, 0, 0, nx, ny, levels, GL_RG, GL_FLOAT, rg);
  check_gl("uploading the wind's motion");
}

Reprojector::Reprojector(const ShaderLoader& loader)
    : program_(load_compute(loader, ShaderLoader::default_shader_dir() / "display" / "reproject.comp")) {}

Reprojector::~Reprojector() {
  if (history_) glDeleteTextures(1, &history_);
  if (sparse_) glDeleteTextures(1, &sparse_);
  if (motion_) glDeleteTextures(1, &motion_);
}

std::vector<float> Reprojector::wind_motion_deg(const core::VolumeGrid& then_grid, const std::vector<double>& then_drift,
                                                const core::VolumeGrid& now_grid, const std::vector<double>& now_drift) {
  const std::size_t levels = static_cast<std::size_t>(now_grid.alt_m.count);
  const auto same_axis = [](const core::RegularAxis& a, const core::RegularAxis& b) {
    return a.start == b.start && a.step == b.step && a.count == b.count;
  };
  if (now_drift.size() != 2 * levels || then_drift.size() != now_drift.size() || !same_axis(then_grid.lon_deg, now_grid.lon_deg) ||
      !same_axis(then_grid.lat_deg, now_grid.lat_deg) || !same_axis(then_grid.alt_m, now_grid.alt_m)) {
    return {};
  }
  std::vector<float> out(2 * levels);
  bool moved = false;
  for (std::size_t k = 0; k < levels; ++k) {
    const double dlon = (now_drift[2 * k] - then_drift[2 * k]) * now_grid.lon_deg.step;
    const double dlat = (now_drift[2 * k + 1] - then_drift[2 * k + 1]) * now_grid.lat_deg.step;
    if (!std::isfinite(dlon) || !std::isfinite(dlat)) return {};
    out[2 * k] = static_cast<float>(dlon);
    out[2 * k + 1] = static_cast<float>(dlat);
    moved = moved || dlon != 0.0 || dlat != 0.0;
  }
  return moved ? out : std::vector<float>{};
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
  c.pixel_block = kBlock, c.block_x = o.x, c.block_y = o.y;  // its jitters are the full pixel's
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

int Reprojector::next_cycle(const core::Camera& full, bool changed) const {
  if (changed || !previous_ || !history_ || full.width != width_ || full.height != height_ || !same_camera(*previous_, full)) return 0;
  return frames_since_change_ / kFramesToComplete;
}

void Reprojector::reset() {
  previous_.reset();
  previous_grid_.reset();
  previous_drift_.clear();
  previous_time_s_ = std::numeric_limits<double>::quiet_NaN();
  previous_flowed_ = false;
  frames_since_change_ = 0;
  frames_since_doubt_ = kFramesToComplete;
}

void Reprojector::resolve(unsigned sparse_depth, const core::Camera& full, int index, bool changed, double r0_m, unsigned out,
                          const core::PreparedVolume* volume) {
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
  // The pass over every pixel this frame belongs to: from the second on (a still view), each pixel
  // marched adds its new sample to its running mean instead of replacing it.
  const int cycle = frames_since_change_ / kFramesToComplete;
  if (translated || changed) frames_since_doubt_ = 0;
  const core::Camera prev = has_history ? *previous_ : full;
  const core::CameraFrame now = core::camera_frame(full), then = core::camera_frame(prev);
  const GLuint p = program_.id();
  glProgramUniform2i(p, loc(p, "u_full"), full.width, full.height);
  const glm::ivec2 o = offset_of(index);
  glProgramUniform2i(p, loc(p, "u_offset"), o.x, o.y);
  glProgramUniform1i(p, loc(p, "u_has_history"), has_history ? 1 : 0);
  glProgramUniform1i(p, loc(p, "u_cycle"), cycle);
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
  // The wind's motion since the history's medium: the modelled cloud's detail drift (per level),
  // else the advected medium's flow (per coarse node) times the time between the two media.
  wind_moved_ = false;
  if (wind_ && has_history && volume && previous_grid_) {
    const std::vector<float> per_level =
        wind_motion_deg(*previous_grid_, previous_drift_, volume->grid, volume->extinction.detail_drift_cells);
    const double dt_s = volume->time_s - previous_time_s_;
    const bool same_grid = same_volume_grid(*previous_grid_, volume->grid);
    if (!per_level.empty()) {
      const int levels = static_cast<int>(per_level.size() / 2);
      upload_motion(1, 1, levels, per_level.data());
      motion_axes_ = {0.0f, 1.0f, 0.0f, 1.0f};
      motion_scale_ = 1.0f;
      motion_is_flow_ = false;
      wind_moved_ = true;
    } else if (same_grid && std::isfinite(dt_s) && dt_s != 0.0 && !volume->flow.empty() &&
               volume->flow.levels == volume->grid.alt_m.count) {
      const core::AngularFlow& f = volume->flow;
      upload_motion(f.lon_deg.count, f.lat_deg.count, f.levels, f.deg_per_s.data());
      motion_axes_ = {static_cast<float>(f.lon_deg.start), static_cast<float>(f.lon_deg.step), static_cast<float>(f.lat_deg.start),
                      static_cast<float>(f.lat_deg.step)};
      motion_scale_ = static_cast<float>(dt_s);
      motion_is_flow_ = true;
      wind_moved_ = true;
    } else if (same_grid && std::isfinite(dt_s) && dt_s != 0.0 && motion_is_flow_ && previous_flowed_) {
      // A medium at a step itself carries no flow: the previous instant's flow, still uploaded, moves it.
      motion_scale_ = static_cast<float>(dt_s);
      wind_moved_ = true;
    }
  }
  if (wind_moved_) {
    glProgramUniform4f(p, loc(p, "u_motion_axes"), motion_axes_[0], motion_axes_[1], motion_axes_[2], motion_axes_[3]);
    glProgramUniform1f(p, loc(p, "u_motion_scale"), motion_scale_);
    glProgramUniform3f(p, loc(p, "u_alt_axis"), static_cast<float>(volume->grid.alt_m.start), static_cast<float>(volume->grid.alt_m.step),
                       static_cast<float>(volume->grid.alt_m.count));
  }
  glProgramUniform1i(p, loc(p, "u_wind"), wind_moved_ ? 1 : 0);
  glBindImageTexture(0, out, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
  if (wind_moved_) glBindTextureUnit(3, motion_);
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
  if (volume) {
    previous_grid_ = volume->grid;
    previous_drift_ = volume->extinction.detail_drift_cells;
    previous_time_s_ = volume->time_s;
    previous_flowed_ = !volume->flow.empty() && motion_is_flow_ && wind_moved_;
  } else {
    previous_grid_.reset();
    previous_drift_.clear();
    previous_time_s_ = std::numeric_limits<double>::quiet_NaN();
    previous_flowed_ = false;
  }
  ++frames_since_change_;
  ++frames_since_doubt_;
}

}  // namespace cv::render
