// The overlay pass (app/render/overlay_pass.cpp): overlay geometry given Earth-centred in double
// and made camera-relative here, in double, before it is rounded to float (so float keeps its
// digits at any distance, and a moving camera needs no new upload), then projected with
// core::camera_view_matrix and camera_projection_matrix.
layout(location = 0) in dvec3 a_position;  // m, Earth-centred
layout(location = 1) in vec4 a_color;      // radiance and alpha
uniform mat4 u_view_proj;
uniform dvec3 u_camera;  // the camera, Earth-centred (m)
out vec3 v_rel;
out vec4 v_color;

void main() {
  v_rel = vec3(a_position - u_camera);
  v_color = a_color;
  gl_Position = u_view_proj * vec4(v_rel, 1.0);
}
