// The viewer's path from the raymarcher to the screen, all on the GPU: the march target texture,
// a running-mean accumulation of jittered frames (shaders/display/accumulate.comp), and the
// fullscreen tonemap draw (present.vert/.frag) with the same curve as image_output.
#pragma once

#include <array>
#include <filesystem>
#include <optional>

#include "render/image_output.hpp"
#include "render/shader_loader.hpp"

namespace cv::render {

// Compiles and links a vertex + fragment pair; throws ShaderError with the remapped log.
GlProgram load_graphics(const ShaderLoader& loader, const std::filesystem::path& vertex,
                        const std::filesystem::path& fragment);

class Presenter {
 public:
  // Needs a current OpenGL 4.5 context; compiles the accumulation and tonemap programs.
  explicit Presenter(const ShaderLoader& loader);
  ~Presenter();
  Presenter(const Presenter&) = delete;
  Presenter& operator=(const Presenter&) = delete;

  // (Re)allocates the textures at the march size (pixels); the accumulation starts afresh.
  void resize(int width, int height);
  int width() const { return width_; }
  int height() const { return height_; }

  // The RGBA32F texture for GpuRaymarcher::render_into.
  GLuint frame_texture() const { return frame_; }
  // The running mean so far (RGBA32F: radiance, transmittance).
  GLuint mean_texture() const { return mean_; }

  // Folds the frame texture into the mean; `count` = frames already in it (0 replaces it).
  void accumulate(int count);

  // Draws the mean, tonemapped, over the currently bound framebuffer's viewport (x, y, w, h),
  // upscaled bilinearly in linear radiance when the march size differs, exactly as upscale_linear
  // (the `render` command's image). `clip`, when given (x, y, w, h in the same window pixels), keeps
  // the draw within that rectangle (a swipe divider's side): the pixels drawn are those of the whole draw.
  void draw(const ToneSettings& tone, int x, int y, int w, int h, const std::optional<std::array<int, 4>>& clip = std::nullopt) const;

 private:
  GlProgram accumulate_;
  GlProgram present_;
  GLuint vao_ = 0;
  GLuint frame_ = 0, mean_ = 0;
  int width_ = 0, height_ = 0;
};

}  // namespace cv::render
