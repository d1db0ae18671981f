// The GPU raymarcher (shaders/render/raymarch.comp): uploads a volume's grid-mean extinction as 3-D
// textures and renders a camera's view into linear radiance and transmittance, the same quantities
// as the CPU reference (core/reference/raymarcher).
#pragma once

#include <string>
#include <vector>

#include <glm/vec4.hpp>

#include "reference/raymarcher.hpp"
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

  // Renders: rgb = radiance, a = view transmittance (0 where the globe shows), rows top to bottom.
  // With settings.globe and a ground_texture, the image is loaded (once per path) with
  // load_albedo_map; a file that cannot be read throws std::runtime_error.
  std::vector<glm::vec4> render(const core::Camera& cam, const core::Sun& sun, const core::MarchSettings& settings);

 private:
  GlProgram program_;
  GLuint textures_[2] = {0, 0};
  GLuint ground_ = 0;               // linear albedo (RGB32F), loaded from ground_path_
  int ground_w_ = 0, ground_h_ = 0;
  std::string ground_path_;
  core::VolumeGrid grid_;
};

}  // namespace cv::render
