// Temporal reprojection for the viewer (issue 18, item 4; docs/physics.md "Temporal reprojection"):
// each frame marches one pixel of every 4 x 4 block of the image (1/16 of the pixels, in a 4 x 4
// Bayer order, so 16 frames of a still camera march every pixel once), and the other pixels take
// the previous frame's image where the point they see stood in the previous camera (from the new
// samples' cloud depth, else the Earth's surface, else the sky's direction), clamped to the range of
// the nearby new samples for 16 frames after the camera moved or the medium changed (against
// ghosting; a turn or a zoom of the lens reprojects exactly and is not clamped), or the new
// samples' bilinear blend where the history never saw the point (disocclusion, the view's edges).
// Where time moved between two frames and the medium carries the wind (the modelled cloud's
// displacement, core::DetailDrift, one per level; or, for an advected medium, the winds' angular
// flow, core::angular_flow, per coarse node), a point in cloud is looked up where the wind held it
// in the previous frame: the camera's motion and the wind's both reproject.
// A still view keeps refining after its first 16 frames: pass c marches each pixel once more as
// accumulation frame c and averages it in (next_cycle), which gives the still image the
// accumulation's step jitter and anti-aliasing.
// Offline renders never use it: `render` and `record` march every pixel.
#pragma once

#include <array>
#include <limits>
#include <optional>
#include <vector>

#include <glm/vec2.hpp>

#include "frame/camera.hpp"
#include "kernel/prepared_volume.hpp"
#include "render/shader_loader.hpp"

namespace cv::render {

class Reprojector {
 public:
  static constexpr int kBlock = 4;
  static constexpr int kFramesToComplete = kBlock * kBlock;

  // Needs a current OpenGL 4.5 context; compiles shaders/display/reproject.comp.
  explicit Reprojector(const ShaderLoader& loader);
  ~Reprojector();
  Reprojector(const Reprojector&) = delete;
  Reprojector& operator=(const Reprojector&) = delete;

  // The pixel of each block that sparse frame `index` marches (the 4 x 4 Bayer order).
  static glm::ivec2 offset_of(int index);
  // The full image's size rounded up to whole blocks (the viewer's march size when reprojecting).
  static int whole_blocks(int pixels) { return (pixels + kBlock - 1) / kBlock * kBlock; }
  // The camera of sparse frame `index` for a full camera whose width and height are whole blocks:
  // width/4 x height/4 pixels, pixel (i, j) on the ray of the full image's pixel (4 i + o.x, 4 j + o.y).
  static core::Camera sparse_camera(const core::Camera& full, int index);

  // An RGBA32F texture of the sparse size for `full` to march into (made again when the size changes).
  unsigned sparse_target(const core::Camera& full);

  // Makes the full image (into `out`, RGBA32F of full's size) from sparse frame `index` just marched
  // into sparse_target() with its cloud depth in `sparse_depth` (R32F of the sparse size), and the
  // history. `changed`: the medium or the settings changed since the last resolve (the camera's own
  // motion is found here). `volume`: the medium marched (its detail drift, else its flow times the
  // time since the previous resolve's medium, gives the wind's motion; null, or neither: no wind
  // motion). The result becomes the next frame's history.
  void resolve(unsigned sparse_depth, const core::Camera& full, int index, bool changed, double r0_m, unsigned out,
               const core::PreparedVolume* volume = nullptr);

  // The wind's motion between two media, per level (longitude and latitude, degrees): the
  // difference of their detail drifts times the grid's steps. Empty when either has no drift, the
  // grids differ, or nothing moved.
  static std::vector<float> wind_motion_deg(const core::VolumeGrid& then_grid, const std::vector<double>& then_drift,
                                            const core::VolumeGrid& now_grid, const std::vector<double>& now_drift);

  // The pass over every pixel (16 frames each) that the next frame of `full` belongs to, with
  // `changed` as resolve will be told: 0 after any change, then 1, 2, ... while the view stays. From
  // the second pass on, a marched pixel's sample joins its running mean (the mean of passes 0..c):
  // the caller marches pass c as accumulation frame c (jittered steps, and with
  // march.anti_alias its rays spread over the pixel), so a still view converges as `render
  // --accumulate` does.
  int next_cycle(const core::Camera& full, bool changed) const;
  // Frames resolved since the last change (camera, medium or settings); the image holds only
  // freshly marched pixels from kFramesToComplete on.
  int frames_since_change() const { return frames_since_change_; }
  bool complete() const { return frames_since_change_ >= kFramesToComplete; }
  // Forgets the history: the next resolve blends the new samples alone.
  void reset();
  // The neighbourhood clamp (on; off only to measure what it does against ghosting).
  void set_clamp(bool on) { clamp_ = on; }
  // The wind's motion of the history (on; off only to measure what it does).
  void set_wind_motion(bool on) { wind_ = on; }
  // Whether the last resolve moved the history with the wind.
  bool wind_moved() const { return wind_moved_; }

 private:
  // The motion texture (RG32F, 3-D: longitude, latitude, level) made again when its size changes.
  void upload_motion(int nx, int ny, int levels, const float* rg);

  GlProgram program_;
  unsigned history_ = 0, sparse_ = 0, motion_ = 0;
  std::array<int, 3> motion_size_{};
  // What the motion texture holds: its nodes' first longitude, longitude step, first latitude and
  // latitude step (degrees; 1 x 1 per level for a drift), and the factor its values take (the
  // seconds between two media for a flow, 1 for a drift's degrees).
  std::array<float, 4> motion_axes_{};
  float motion_scale_ = 1.0f;
  bool motion_is_flow_ = false;
  int width_ = 0, height_ = 0, sparse_w_ = 0, sparse_h_ = 0;
  std::optional<core::Camera> previous_;
  int frames_since_change_ = 0;
  int frames_since_doubt_ = kFramesToComplete;  // since the camera moved or the medium changed
  bool clamp_ = true, wind_ = true, wind_moved_ = false;
  // The previous resolve's medium: its grid and detail drift (cells, 2 per level).
  std::optional<core::VolumeGrid> previous_grid_;
  std::vector<double> previous_drift_;
  double previous_time_s_ = std::numeric_limits<double>::quiet_NaN();
  bool previous_flowed_ = false;  // the last resolve moved the history by its medium's flow, still uploaded
};

}  // namespace cv::render
