// The GPU raymarcher (shaders/render/raymarch.comp): uploads a volume's grid-mean extinction as 3-D
// textures and renders a camera's view into linear radiance and transmittance, the same quantities
// as the CPU reference (core/reference/raymarcher).
#pragma once

#include <memory>
#include <vector>

#include <glm/vec4.hpp>

#include "reference/raymarcher.hpp"
#include "volume/extinction_pyramid.hpp"
#include "render/shader_loader.hpp"

namespace cv::render {

class GpuRaymarcher {
 public:
  // Needs a current OpenGL 4.5 context; compiles the raymarcher.
  explicit GpuRaymarcher(const ShaderLoader& loader);
  ~GpuRaymarcher();
  GpuRaymarcher(const GpuRaymarcher&) = delete;
  GpuRaymarcher& operator=(const GpuRaymarcher&) = delete;

  // Uploads one time step (replacing the previous one).
  void upload(const core::VolumeGrid& grid, const core::GridMeanExtinction& medium);

  // Renders: rgb = radiance, a = view transmittance, rows top to bottom.
  std::vector<glm::vec4> render(const core::Camera& cam, const core::Sun& sun, const core::MarchSettings& settings);

  // The counts of the last render (samples taken and skipped, rays that missed the shell).
  const core::MarchStats& last_stats() const { return stats_; }

 private:
  // The program for a march's switches (skip_empty, adaptive_steps), compiled on first use.
  const GlProgram& program_for(const core::MarchSettings& s);
  ShaderLoader loader_;
  std::unique_ptr<GlProgram> programs_[2][2];
  GLuint textures_[2] = {0, 0};
  GLuint pyramid_buffer_ = 0, stats_buffer_ = 0;
  core::ExtinctionPyramid pyramid_;
  core::VolumeGrid grid_;
  core::MarchStats stats_;
};

}  // namespace cv::render
