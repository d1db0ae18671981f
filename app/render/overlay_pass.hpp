// The overlay pass: draws overlay geometry (core::OverlayMesh, built by app/overlays) with our
// own OpenGL into the two textures the march reads as its opaque input (render::OpaqueInput): the
// distance along each pixel's ray to the nearest geometry and the geometry's radiance. Vertices go
// to the GPU in double, Earth-centred, and the vertex shader makes them camera-relative in double
// before it rounds them to float, so they keep their digits at orbit and at the ground alike; a
// mesh held by a shared_ptr stays on the GPU for as long as it is drawn each frame, so a moving
// camera uploads nothing. A mesh's instances (core::OverlayInstances: wind arrows) are drawn with
// one instanced draw of their glyph, each instance's origin (double), axes and colour per-instance
// attributes (shaders/render/overlay.vert, u_instanced), through the same fragment shader. No VTK
// here: only its geometry, as plain data.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
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

  // Starts a frame of cam's size: distance 0 (none) and radiance 0 everywhere. Meshes kept on the
  // GPU (draw of a shared_ptr) that were not drawn since the previous begin are released.
  void begin(const core::Camera& cam, double r0_m);
  // Draws a mesh (lines line_width_px wide where the driver allows; 1 otherwise); returns the
  // wall time of the draw in ms (it waits for the GPU to finish). A mesh given by reference is
  // uploaded for this draw alone (labels and colour bars that follow the camera); one given by
  // shared_ptr is uploaded once and kept while it is drawn every frame (the pass holds a reference,
  // so the mesh cannot change or be replaced under the same address while it is kept).
  double draw(const core::OverlayMesh& mesh, float line_width_px = 1.0f);
  double draw(const std::shared_ptr<const core::OverlayMesh>& mesh, float line_width_px = 1.0f);
  // How many vertex uploads the pass has made since it was made (for tests and the bench).
  std::uint64_t uploads() const { return uploads_; }
  // The textures for the march (valid until the next begin). Translucent triangles drawn since
  // begin (alpha below 1) are peeled here into core::kTranslucentLayers layers, nearest first, each
  // nearer than the opaque geometry; none drawn, no peeling and no layer textures.
  OpaqueInput output();

  // The frame read back (rows top to bottom), as core::OpaqueLayer (with its translucent layers).
  core::OpaqueLayer read();
  // The wall time of the last peeling (ms; 0 without translucent geometry).
  double peel_ms() const { return peel_ms_; }

 private:
  // One mesh's buffers: Earth-centred positions in double, colours, triangle then line indices;
  // and its instances': the glyph's vertices and triangles, each instance's origin (double) and
  // axes and colour (float, 16 to an instance).
  struct Buffers {
    GLuint vao = 0, pos = 0, color = 0, index = 0;
    std::size_t triangles = 0, lines = 0;
    bool translucent = false;  // some triangle vertex has alpha below 1
    GLuint inst_vao = 0, glyph = 0, glyph_index = 0, origins = 0, frames = 0;
    std::size_t glyph_indices = 0, instances = 0;
  };
  Buffers make_buffers(const core::OverlayMesh& mesh);
  static void free_buffers(Buffers& b);
  // Sets the program's per-frame uniforms; peel: -1 for the opaque pass, else the layer peeled.
  void use_program(int peel);
  double draw_buffers(const Buffers& b, float line_width_px, std::chrono::steady_clock::time_point t0);
  void peel();
  struct Kept {
    std::shared_ptr<const core::OverlayMesh> mesh;
    Buffers buffers;
    bool drawn = false;  // since the last begin
  };

  GlProgram program_;
  GLuint fbo_ = 0, distance_ = 0, color_ = 0, depth_ = 0;
  std::vector<Buffers> transient_;    // meshes given by reference this frame, freed at begin
  std::vector<Buffers> translucent_;  // this frame's meshes with translucent triangles (not owned)
  bool peeled_ = true;
  double peel_ms_ = 0.0;
  // Peeling: two layers in turn (distance, colour) with their depth, and the layers side by side.
  GLuint peel_fbo_ = 0, peel_distance_[2] = {0, 0}, peel_color_[2] = {0, 0}, peel_depth_ = 0;
  GLuint layer_distance_ = 0, layer_color_ = 0;
  int peel_w_ = 0, peel_h_ = 0;
  std::vector<Kept> kept_;
  std::uint64_t uploads_ = 0;
  int w_ = 0, h_ = 0;
  core::Camera cam_;
  double r0_m_ = 0.0;
  glm::dvec3 camera_m_{0.0};
};

}  // namespace cv::render
