// The viewer's temporal reprojection (app/render/reprojector.hpp): each frame the march draws one
// pixel of every 4 x 4 block (the sparse frame); the other pixels take the previous full image
// (the history) where the point they see stood in the previous camera, clamped to the range of the
// new samples around them when anything moved, or the new samples' bilinear blend where the history
// has nothing (out of the previous view, behind it, or no history yet).
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) writeonly uniform image2D u_out;  // the full image (rgb radiance, a transmittance)
layout(binding = 0) uniform sampler2D u_history;       // the previous full image (linear filtering, clamped to the edge)
layout(binding = 1) uniform sampler2D u_sparse;        // this frame's samples, one per block
layout(binding = 2) uniform sampler2D u_sparse_depth;  // the distance at which their view transmittance fell to 0.5 (3e38: never)
uniform ivec2 u_full;        // the full image's size (a multiple of the block in each axis)
uniform ivec2 u_offset;      // this frame's pixel within each block
uniform bool u_has_history;  // false: the spatial blend everywhere but the new samples
uniform bool u_clamp;        // the camera or the medium changed since the history was made
// The current camera: its position from the previous camera's (m, from double), its axes and the
// tangent of half its horizontal field of view; its position from the Earth's centre for the ground.
uniform vec3 u_delta;
uniform vec3 u_forward;
uniform vec3 u_right;
uniform vec3 u_up;
uniform float u_tan_half;
uniform vec3 u_cam;
uniform float u_r0;
// The previous camera's axes and half-width.
uniform vec3 u_prev_forward;
uniform vec3 u_prev_right;
uniform vec3 u_prev_up;
uniform float u_prev_tan_half;

const int kBlock = 4;

vec3 pixel_ray(vec2 centre) {
  float x = (2.0 * centre.x / float(u_full.x) - 1.0) * u_tan_half;
  float y = (1.0 - 2.0 * centre.y / float(u_full.y)) * u_tan_half * float(u_full.y) / float(u_full.x);
  return normalize(u_forward + x * u_right + y * u_up);
}

// The distance along d from the camera to the sphere of radius r0, or -1 when the ray misses it.
float earth_hit(vec3 o, vec3 d, float r0) {
  float b = dot(o, d);
  float c = dot(o, o) - r0 * r0;
  float disc = b * b - c;
  if (disc < 0.0) return -1.0;
  float t = -b - sqrt(disc);
  return t > 0.0 ? t : -1.0;
}

vec4 sparse_at(ivec2 b, ivec2 n) { return texelFetch(u_sparse, clamp(b, ivec2(0), n - 1), 0); }

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x >= u_full.x || p.y >= u_full.y) return;
  ivec2 n = textureSize(u_sparse, 0);
  ivec2 block = p / kBlock;
  if (p - block * kBlock == u_offset) {  // marched this frame: exact
    imageStore(u_out, p, sparse_at(block, n));
    return;
  }
  // The new samples stand at the centres of pixels block * 4 + offset: this pixel's place among them.
  vec2 f = (vec2(p) - vec2(u_offset)) / float(kBlock);
  ivec2 b0 = ivec2(floor(f));
  vec2 w = f - vec2(b0);
  vec4 s00 = sparse_at(b0, n), s10 = sparse_at(b0 + ivec2(1, 0), n);
  vec4 s01 = sparse_at(b0 + ivec2(0, 1), n), s11 = sparse_at(b0 + ivec2(1, 1), n);
  vec4 spatial = mix(mix(s00, s10, w.x), mix(s01, s11, w.x), w.y);
  if (!u_has_history) {
    imageStore(u_out, p, spatial);
    return;
  }
  // The point this pixel sees now: at the nearest new sample's cloud depth, else where the ray meets
  // the Earth, else a direction (the sky: only the camera's turn moves it).
  ivec2 nearest = clamp(ivec2(floor(f + 0.5)), ivec2(0), n - 1);
  float t = texelFetch(u_sparse_depth, nearest, 0).r;
  vec3 d = pixel_ray(vec2(p) + 0.5);
  vec3 q;
  if (t < 1.0e37) {
    q = u_delta + d * t;
  } else {
    float te = earth_hit(u_cam, d, u_r0);
    q = te > 0.0 ? u_delta + d * te : d;
  }
  float z = dot(q, u_prev_forward);
  vec2 prev = vec2(-1.0);
  if (z > 0.0) {
    float x = dot(q, u_prev_right) / (z * u_prev_tan_half);
    float y = dot(q, u_prev_up) / (z * u_prev_tan_half * float(u_full.y) / float(u_full.x));
    prev = vec2(0.5 * (x + 1.0) * float(u_full.x), 0.5 * (1.0 - y) * float(u_full.y));
  }
  if (!(prev.x >= 0.0 && prev.y >= 0.0 && prev.x <= float(u_full.x) && prev.y <= float(u_full.y))) {
    imageStore(u_out, p, spatial);  // disoccluded: the history never saw it
    return;
  }
  vec4 h = texture(u_history, prev / vec2(u_full));
  if (u_clamp) {
    // The range of the four new samples around this pixel: the history may not leave it, so what
    // moved or changed (or shines differently from the new viewpoint) does not linger as a ghost.
    vec4 lo = min(min(s00, s10), min(s01, s11));
    vec4 hi = max(max(s00, s10), max(s01, s11));
    h = mix(spatial, clamp(h, lo, hi), 0.5);
  }
  imageStore(u_out, p, h);
}
