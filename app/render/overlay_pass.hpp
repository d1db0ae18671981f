// The overlay pass: draws overlay geometry (core::OverlayMesh, built by app/overlays) with our
// own OpenGL into the two textures the march reads as its opaque input (render::OpaqueInput): the
// distance along each pixel's ray to the nearest geometry and the geometry's radiance. Vertices go
// to the GPU camera-relative (double on the CPU, then float), so they keep their digits at orbit and
// at the ground alike. No VTK here: only its geometry, as plain data.
#pragma once

#include <vector>

#include "frame/camera.hpp"
#include "geometry/overlay_mesh.hpp"
#include "render/raymarcher.hpp"
#include "render/shader_loader.hpp"

namespace cv::render {

class OverlayPass {
 public:
  // Needs a current OpenGL 4.5 context; compiles shaders/render/overlay.vert/.frag.
  explicit OverlayPass(const ShaderLoader& loader);
  ~OverlayPass();
  OverlayPass(const OverlayPass&) = delete;
  OverlayPass& operator=(const OverlayPass&) = delete;

  // Starts a frame of cam's size: distance 0 (none) and radiance 0 everywhere.
  void begin(const core::Camera& cam, double r0_m);
  // Draws a mesh (lines line_width_px wide where the driver allows; 1 otherwise); returns the
  // wall time of the draw in ms (it waits for the GPU to finish).
  double draw(const core::OverlayMesh& mesh, float line_width_px = 1.0f);
  // The textures for the march (valid until the next begin).
  OpaqueInput output() const { return {distance_, color_}; }

  // The frame read back (rows top to bottom), as core::OpaqueLayer.
  core::OpaqueLayer read() const;

 private:
  GlProgram program_;
  GLuint fbo_ = 0, distance_ = 0, color_ = 0, depth_ = 0;
  GLuint vao_ = 0, vbo_pos_ = 0, vbo_color_ = 0, ibo_ = 0;
  int w_ = 0, h_ = 0;
  core::Camera cam_;
  double r0_m_ = 0.0;
  glm::dvec3 camera_m_{0.0};
};

}  // namespace cv::render
