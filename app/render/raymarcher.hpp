// The GPU raymarcher (shaders/render/raymarch.comp): uploads a volume's grid-mean extinction as 3-D
// textures and renders a camera's view into linear radiance and transmittance, the same quantities
// as the CPU reference (core/reference/raymarcher).
#pragma once

#include <vector>

#include <glm/vec4.hpp>

#include "reference/raymarcher.hpp"
#include "render/shader_loader.hpp"

namespace cv::render {

class GpuRaymarcher {
 public:
  // Needs a current OpenGL 4.5 context; compiles the raymarcher. Keeps a reference to the loader
  // (for the noise variant, compiled later), which must outlive it.
  explicit GpuRaymarcher(const ShaderLoader& loader);
  ~GpuRaymarcher();
  GpuRaymarcher(const GpuRaymarcher&) = delete;
  GpuRaymarcher& operator=(const GpuRaymarcher&) = delete;

  // Uploads one time step (replacing the previous one).
  void upload(const core::VolumeGrid& grid, const core::GridMeanExtinction& medium);

  // Uploads the erosion noise textures and compiles the noise variant of the raymarcher: needed
  // before a render with settings.noise_amount > 0, not done otherwise.
  void upload_noise(const core::ErosionNoise& noise);

  // Renders: rgb = radiance, a = view transmittance, rows top to bottom. With noise_amount 0 the
  // program without the noise code runs and the noise textures are not bound.
  std::vector<glm::vec4> render(const core::Camera& cam, const core::Sun& sun, const core::MarchSettings& settings);

 private:
  const ShaderLoader& loader_;
  GlProgram program_;
  GlProgram noise_program_;  // the NoiseDetail variant, compiled by upload_noise
  GLuint textures_[2] = {0, 0};
  GLuint noise_textures_[2] = {0, 0};
  core::VolumeGrid grid_;
};

}  // namespace cv::render
