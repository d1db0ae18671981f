// The frame renderer: march, accumulate, upscale.
#include "render/frame_renderer.hpp"

#include "noise/noise.hpp"
#include "render/albedo_map.hpp"
#include "render/image_output.hpp"

namespace cv::render {

FrameRenderer::FrameRenderer(const ShaderLoader& loader) : gpu_(loader), loader_(loader) {}

void FrameRenderer::set_overlays(std::vector<OverlayDraw> overlays) {
  // Kept in order (overlay_draw_ms follows it); only geometry makes a pass.
  overlays_.clear();
  for (OverlayDraw& o : overlays) {
    if ((o.mesh && !o.mesh->empty()) || (o.view_mesh && !o.view_mesh->empty())) {
      overlays_ = std::move(overlays);
      return;
    }
  }
  overlay_ms_.assign(overlays.size(), 0.0);
}

OpaqueInput FrameRenderer::draw_overlays(const core::Camera& cam) {
  if (overlays_.empty()) return {};
  if (!overlay_pass_) overlay_pass_ = std::make_unique<OverlayPass>(loader_);
  const double r0 = volume_ ? volume_->grid.earth_radius_m : core::VolumeGrid{}.earth_radius_m;
  overlay_pass_->begin(cam, r0);
  overlay_ms_.clear();
  for (const OverlayDraw& o : overlays_) {
    overlay_ms_.push_back(overlay_pass_->draw(o.mesh, o.line_width_px) +
                          (o.view_mesh ? overlay_pass_->draw(*o.view_mesh, o.line_width_px) : 0.0));
  }
  return overlay_pass_->output();
}

core::OpaqueLayer FrameRenderer::read_overlays() const {
  return overlay_pass_ ? overlay_pass_->read() : core::OpaqueLayer{};
}

void FrameRenderer::use_volume(std::shared_ptr<const core::PreparedVolume> volume) {
  if (volume == volume_) return;
  gpu_.upload(volume);
  volume_ = std::move(volume);
}

core::MarchSettings FrameRenderer::frame_settings(const core::MarchSettings& march, int count, int index) {
  core::MarchSettings m = march;
  m.per_frame.frame = count <= 1 ? march.per_frame.frame : index;
  return m;
}

core::FrameSpec resolve_frame(const core::Scene& scene, const core::CloudVolume& volume) {
  core::FrameSpec f = core::resolve_frame(scene, volume);
  f.march.medium.ground_texture = resolve_ground_texture(f.march.medium.ground_texture);
  return f;
}

core::FrameSpec resolve_path_frame(const core::Scene& scene, const core::PathEvaluator& path, const core::CloudVolume& volume,
                                   int k, double fps, core::Scene* at) {
  const core::Scene s = core::scene_at_path_time(scene, path, core::path_frame_time_s(path, k, fps));
  core::FrameSpec f = render::resolve_frame(s, volume);
  f.jitter_base = k * f.accumulate;
  if (at) *at = s;
  return f;
}

void FrameRenderer::ensure_noise(const core::MarchSettings& m) {
  // Generated, compiled and bound only when used; the modelled cloud's table only for it.
  const bool table = m.medium.modelled && (!noise_uploaded_ || noise_.detail.empty());
  if ((m.medium.noise_amount > 0.0 || m.medium.modelled) && !noise_uploaded_) noise_ = core::make_erosion_noise();
  if (table) core::with_detail_table(noise_);
  if ((m.medium.noise_amount > 0.0 && !noise_uploaded_) || table) {
    gpu_.upload_noise(noise_);
    noise_uploaded_ = true;
  }
}

void FrameRenderer::march_into(GLuint out, const core::FrameSpec& f, int index, const DispatchOptions& dispatch,
                               const OpaqueInput& opaque) {
  const core::MarchSettings m = frame_settings(f.march, f.accumulate, f.jitter_base + index);
  ensure_noise(m);
  // The overlays, drawn once per accumulation (the camera does not move within one), unless the
  // caller brings its own opaque input.
  OpaqueInput in = opaque;
  if (in.depth == 0 && !overlays_.empty()) in = index == 0 || !overlay_pass_ ? draw_overlays(f.march_camera) : overlay_pass_->output();
  gpu_.render_into(out, f.march_camera, f.sun, m, dispatch, in);
}

void FrameRenderer::trace_paths(core::MonteCarloImage& img, const core::FrameSpec& f, int spp, const PathTraceSettings& pt,
                                PathTraceStats* extra) {
  ensure_noise(f.march);
  // The overlays, drawn once per mean (its camera does not move while it accumulates): none, and
  // no pass, without overlays.
  OpaqueInput opaque;
  if (!overlays_.empty()) opaque = img.spp == 0 || !overlay_pass_ ? draw_overlays(f.march_camera) : overlay_pass_->output();
  gpu_.trace_paths(img, f.march_camera, f.sun, f.march, spp, pt, extra, {}, opaque);
}

std::vector<glm::vec4> FrameRenderer::render(const core::FrameSpec& f, const DispatchOptions& dispatch,
                                             const std::function<void(int, int)>& on_frame,
                                             std::vector<glm::vec4>* marched) {
  const int mw = f.march_camera.width, mh = f.march_camera.height;
  std::vector<glm::vec4> mean;
  const OpaqueInput opaque = draw_overlays(f.march_camera);  // none, and no pass, without overlays
  for (int i = 0; i < f.accumulate; ++i) {
    const core::MarchSettings m = frame_settings(f.march, f.accumulate, f.jitter_base + i);
    ensure_noise(m);
    const std::vector<glm::vec4> frame = gpu_.render(f.march_camera, f.sun, m, dispatch, opaque);
    if (i == 0) {
      mean = frame;
    } else {
      for (std::size_t p = 0; p < mean.size(); ++p) mean[p] += (frame[p] - mean[p]) / static_cast<float>(i + 1);
    }
    if (on_frame) on_frame(i + 1, f.accumulate);
  }
  if (marched) *marched = mean;
  if (mw == f.camera.width && mh == f.camera.height) return mean;
  return upscale_linear(mean, mw, mh, f.camera.width, f.camera.height);
}

}  // namespace cv::render
