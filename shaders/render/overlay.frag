// The overlay pass's fragments: the distance along the pixel's ray (what the march's depth input
// holds, shaders/kernel/march.glsl) and the geometry's radiance. The depth test runs on that
// distance over the far plane (linear: a metre's resolution out to 1e8 m in a 32-bit float depth,
// where the projection's own depth would lose tens of percent at orbit). Geometry behind the
// Earth's sphere is discarded as core::hidden_by_sphere does on the CPU, in double. Triangle
// fragments with alpha below 1 are translucent: left out of the opaque pass (u_peel 0) and peeled
// one layer at a time (u_peel 1): the nearest strictly behind the layer before (u_prev) and in
// front of the opaque geometry (u_front_opaque), as core::cast_overlay keeps them.
in vec3 v_rel;
in vec4 v_color;
uniform dvec3 u_camera;  // the camera, Earth-centred (m)
uniform double u_cq;     // |camera|^2 - r0^2, formed in double on the CPU
uniform float u_far;     // m
uniform float u_bias;    // lines: core::kLineDistanceBias, pulled toward the camera; triangles 0
// The camera's frame (core::camera_frame) and the image size, for the pixel's own ray: a line has
// no width, so a one-pixel line's fragment stands off its pixel's ray, by kilometres at a grazing
// view; a line there is taken at the ground the pixel's ray meets, where that is nearer.
uniform vec3 u_forward, u_right, u_up;
uniform vec2 u_tan_half;  // x, and y scaled by the aspect
uniform vec2 u_size;      // pixels
uniform int u_peel;       // 0: the opaque pass; 1: a translucent layer
uniform bool u_has_prev;  // peeling a layer after the first
layout(binding = 14) uniform sampler2D u_prev;          // the layer before's distance (m, 0: none)
layout(binding = 15) uniform sampler2D u_front_opaque;  // the opaque pass's distance (m, 0: none)
layout(location = 0) out float o_distance;
layout(location = 1) out vec4 o_color;

void main() {
  dvec3 rel = dvec3(v_rel);
  double dist = length(rel);
  dvec3 d = rel / dist;
  double b = dot(d, u_camera);
  double disc = b * b - u_cq;
  if (disc >= 0.0) {
    double s = sqrt(disc);
    double t0 = b < 0.0 ? u_cq / (-b + s) : -b - s;
    if (t0 >= 0.0 && t0 < dist - max(1.0, 1e-6 * dist)) discard;
  }
  double t = dist;
  if (u_bias > 0.0) {
    // The pixel's ray (rows top to bottom, as the projection puts them) and where it meets the sphere.
    vec2 ndc = vec2(2.0 * gl_FragCoord.x / u_size.x - 1.0, 1.0 - 2.0 * gl_FragCoord.y / u_size.y);
    dvec3 ray = normalize(dvec3(u_forward) + double(ndc.x * u_tan_half.x) * dvec3(u_right) + double(ndc.y * u_tan_half.y) * dvec3(u_up));
    double bp = dot(ray, u_camera);
    double dp = bp * bp - u_cq;
    if (dp >= 0.0) {
      double sp = sqrt(dp);
      double tg = bp < 0.0 ? u_cq / (-bp + sp) : -bp - sp;
      if (tg > 0.0) t = min(t, tg);
    }
  }
  float shown = float(t * (1.0 - double(u_bias)));
  bool translucent = u_bias == 0.0 && v_color.a < 0.9999;  // core::kOpaqueAlpha
  if (u_peel == 0) {
    if (translucent) discard;
  } else {
    if (!translucent) discard;
    ivec2 px = ivec2(gl_FragCoord.xy);
    float opaque = texelFetch(u_front_opaque, px, 0).r;
    if (opaque > 0.0 && !(shown < opaque)) discard;
    if (u_has_prev) {
      float prev = texelFetch(u_prev, px, 0).r;  // 0: the layer before is empty, and so is this one
      if (!(prev > 0.0) || !(shown > prev)) discard;
    }
  }
  o_distance = shown;
  o_color = v_color;
  gl_FragDepth = clamp(shown / u_far, 0.0, 1.0);
}
