// The overlay pass (app/render/overlay_pass.cpp): overlay geometry given Earth-centred in double
// and made camera-relative here, in double, before it is rounded to float (so float keeps its
// digits at any distance, and a moving camera needs no new upload), then projected with
// core::camera_view_matrix and camera_projection_matrix.
// Instanced draws (u_instanced: a mesh's core::OverlayInstances, the wind arrows) give one glyph
// and, per instance, an origin (in a_position, double), three axes and a colour: the glyph point
// is placed in double (origin + x + y + z, in the order core::expand_instances adds them on the
// CPU) and then made camera-relative the same way. The origin takes a_position's location 0 in
// both vertex arrays: Mesa fetched nothing for the other inputs when a double input at another
// location was fed and location 0 was not.
layout(location = 0) in dvec3 a_position;  // m, Earth-centred; instanced: the instance's origin
layout(location = 1) in vec4 a_color;      // radiance and alpha
layout(location = 2) in vec3 a_glyph;      // instanced: glyph units
layout(location = 3) in vec3 a_axis_x;     // instanced, per instance: m per glyph unit
layout(location = 4) in vec3 a_axis_y;
layout(location = 5) in vec3 a_axis_z;
layout(location = 6) in vec4 a_instance_color;  // instanced, per instance: radiance, alpha 1
uniform mat4 u_view_proj;
uniform dvec3 u_camera;  // the camera, Earth-centred (m)
uniform bool u_instanced;
out vec3 v_rel;
out vec4 v_color;

void main() {
  if (u_instanced) {
    dvec3 p = ((a_position + dvec3(a_axis_x) * double(a_glyph.x)) + dvec3(a_axis_y) * double(a_glyph.y)) + dvec3(a_axis_z) * double(a_glyph.z);
    v_rel = vec3(p - u_camera);
    v_color = a_instance_color;
  } else {
    v_rel = vec3(a_position - u_camera);
    v_color = a_color;
  }
  gl_Position = u_view_proj * vec4(v_rel, 1.0);
}
