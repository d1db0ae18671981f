// The overlay pass (app/render/overlay_pass.cpp): overlay geometry given camera-relative (its
// Earth-centred position minus the camera's, formed in double on the CPU, so float keeps its
// digits at any distance), projected with core::camera_view_matrix and camera_projection_matrix.
layout(location = 0) in vec3 a_rel;    // m, camera-relative
layout(location = 1) in vec4 a_color;  // radiance and alpha
uniform mat4 u_view_proj;
out vec3 v_rel;
out vec4 v_color;

void main() {
  v_rel = a_rel;
  v_color = a_color;
  gl_Position = u_view_proj * vec4(a_rel, 1.0);
}
