// One frame renderer for every command: a resolved frame (core::FrameSpec) marched on the GPU at
// its march size, its jittered frames accumulated, upscaled in linear radiance to the output size.
// `render`, `bench` and the viewer march through it, so one scene gives one image whichever draws it.
#pragma once

#include <functional>
#include <memory>
#include <vector>

#include <glm/vec4.hpp>

#include "kernel/prepared_volume.hpp"
#include "noise/noise.hpp"
#include "geometry/overlay_mesh.hpp"
#include "render/overlay_pass.hpp"
#include "render/raymarcher.hpp"
#include "scene/camera_path.hpp"
#include "scene/frame_spec.hpp"

namespace cv::render {

// core::resolve_frame, the scene's ground texture found as well (resolve_ground_texture: an empty
// setting is the Natural Earth relief where it is installed).
core::FrameSpec resolve_frame(const core::Scene& scene, const core::CloudVolume& volume);

// Video frame k of a camera path at fps (`record`): the scene at the path's time for frame k
// (core::scene_at_path_time, returned in `at` when given), resolved as above, with its jitter
// indices from k * accumulate on, so every frame's seeds come from its number.
core::FrameSpec resolve_path_frame(const core::Scene& scene, const core::PathEvaluator& path, const core::CloudVolume& volume,
                                   int k, double fps, core::Scene* at = nullptr);

// One overlay's geometry for the frame (built by app/overlays), drawn by the overlay pass.
struct OverlayDraw {
  std::string name;
  std::shared_ptr<const core::OverlayMesh> mesh;       // kept on the GPU while drawn each frame
  std::shared_ptr<const core::OverlayMesh> view_mesh;  // made for this view: uploaded with each draw
  float line_width_px = 1.0f;
};

class FrameRenderer {
 public:
  // Needs a current OpenGL 4.5 context; the loader must outlive the renderer.
  explicit FrameRenderer(const ShaderLoader& loader);

  // Makes `volume` the time step marched, uploading it when it is not the one on the GPU already.
  void use_volume(std::shared_ptr<const core::PreparedVolume> volume);
  // The volume marched now (null before use_volume).
  const core::PreparedVolume* volume() const { return volume_.get(); }

  // The settings of frame `index` of an accumulation of `count`: a single frame keeps the settings'
  // own (step middles unless it names one), else the index's jitter.
  static core::MarchSettings frame_settings(const core::MarchSettings& march, int count, int index);

  // Marches frame `index` of the spec's accumulation at its march size into `out` (an RGBA32F
  // texture of at least that size), generating the erosion noise the first time it is needed.
  void march_into(GLuint out, const core::FrameSpec& frame, int index, const DispatchOptions& dispatch = {},
                  const OpaqueInput& opaque = {});

  // The image at the output size in linear radiance (rgb) and transmittance (a): the spec's
  // accumulate frames at the march size, their running mean (as the viewer's accumulate.comp), then
  // upscale_linear. on_frame(done, total) after each accumulated frame. `marched`, when given,
  // receives the mean at the march size (what auto_exposure reads, as the viewer does).
  std::vector<glm::vec4> render(const core::FrameSpec& frame, const DispatchOptions& dispatch = {},
                                const std::function<void(int, int)>& on_frame = {},
                                std::vector<glm::vec4>* marched = nullptr);

  // Adds `spp` path-traced samples per pixel of the spec's march camera into img (the GPU path
  // tracer, GpuRaymarcher::trace_paths; img empty or made for that camera), generating the erosion
  // noise the first time it is needed, with the overlays drawn for the march camera (the paths end
  // on their geometry and pass through their translucent surfaces). `render --quality reference`,
  // the viewer's progressive path tracer and `record` trace through it.
  void trace_paths(core::MonteCarloImage& img, const core::FrameSpec& frame, int spp, const PathTraceSettings& pt = {},
                   PathTraceStats* extra = nullptr);

  // The overlays drawn before each march (none, or none with geometry: no overlay pass is made or
  // run). Their
  // distance and radiance are the march's opaque input: it stops at the geometry and composites it
  // behind the cloud's transmittance in front.
  void set_overlays(std::vector<OverlayDraw> overlays);
  // Each overlay's draw time in the last frame that drew overlays (ms, in set_overlays' order; 0
  // for one without geometry).
  const std::vector<double>& overlay_draw_ms() const { return overlay_ms_; }
  // Whether an overlay pass exists: only once a frame has drawn overlays.
  bool has_overlay_pass() const { return overlay_pass_ != nullptr; }
  // The overlay pass's last frame read back (the CPU reference composites the same layer).
  core::OpaqueLayer read_overlays() const;

  GpuRaymarcher& raymarcher() { return gpu_; }
  const core::MarchStats& last_stats() { return gpu_.last_stats(); }

 private:
  void ensure_noise(const core::MarchSettings& m);
  // Draws the overlays from cam's view; the march's opaque input (none without overlays).
  OpaqueInput draw_overlays(const core::Camera& cam);
  GpuRaymarcher gpu_;
  const ShaderLoader& loader_;
  std::vector<OverlayDraw> overlays_;
  std::vector<double> overlay_ms_;
  std::unique_ptr<OverlayPass> overlay_pass_;
  std::shared_ptr<const core::PreparedVolume> volume_;
  bool noise_uploaded_ = false;
  core::ErosionNoise noise_;  // what was uploaded (its detail table made when the modelled cloud needs it)
};

}  // namespace cv::render
