// The pinhole camera on the spherical Earth: its orientation, the ray of each pixel, and the
// camera-relative matrices for geometry other passes draw with the clouds.
#pragma once

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

namespace cv::core {

// A pinhole camera on the spherical Earth. Heading is clockwise from north, pitch up from the
// horizon, fov the horizontal field of view; all in degrees.
struct Camera {
  double lat_deg = 0.0, lon_deg = 0.0, alt_m = 0.0;
  double heading_deg = 0.0, pitch_deg = 0.0, fov_deg = 60.0;
  int width = 64, height = 36;
  // Where in each pixel its ray passes, from the centre, in pixels (x right, y down): 0 everywhere
  // but the viewer's sparse frames (render/reprojector), whose pixels stand for one pixel of a
  // block of a larger image.
  double pixel_shift_x = 0.0, pixel_shift_y = 0.0;
  // Pixel (px, py) stands for pixel (block px + block_x, block py + block_y) of an image `block`
  // times larger (the reprojection's sparse frames: 4): an accumulation frame's jitters, of the
  // steps and of the rays within the pixel (march.glsl step_offset, pixel_jitter), are that pixel's,
  // so a sparse frame marches what the full frame marches there. 1, 0, 0 everywhere else.
  int pixel_block = 1, block_x = 0, block_y = 0;
};

// A camera's orientation in Earth-centred coordinates, and its half-width: pixel (px, py) looks
// along forward + x right + y up with x, y in [-tan_half, tan_half] (y scaled by the aspect).
struct CameraFrame {
  glm::dvec3 forward, right, up;
  double tan_half = 0.0;
};
CameraFrame camera_frame(const Camera& cam);

// The direction of a pixel's ray in Earth-centred coordinates.
glm::dvec3 camera_ray(const Camera& cam, int px, int py);

// Matrices for geometry that other passes draw with the clouds, camera-relative: a vertex is given
// as its Earth-centred position minus camera_ecef, formed in double (float then keeps its digits at
// any distance). The view matrix turns such an offset into eye space (x right, y up, looking down
// -z); the projection maps eye space to OpenGL clip space so that a point on the ray of pixel
// (px, py) lands on that pixel's centre in the renderer's row order (row 0 at the top, as every image
// the march writes: y is flipped against OpenGL's window rows, so front faces wind clockwise), with
// depth from near_m to far_m. The march's depth input is the distance along the ray, which a
// fragment shader takes as the length of the camera-relative position.
glm::dvec3 camera_ecef(const Camera& cam, double r0_m);
glm::dmat4 camera_view_matrix(const Camera& cam);
glm::dmat4 camera_projection_matrix(const Camera& cam, double near_m, double far_m);

}  // namespace cv::core
