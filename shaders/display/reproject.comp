// The viewer's temporal reprojection (app/render/reprojector.hpp): each frame the march draws one
// pixel of every 4 x 4 block (the sparse frame); the other pixels take the previous full image
// (the history) where the point they see stood in the previous camera, clamped to the range of the
// new samples around them when anything moved, or the new samples' bilinear blend where the history
// has nothing (out of the previous view, behind it, or no history yet). A point in cloud is looked
// up where the wind held it in the previous frame when the medium carries the wind's displacement
// (the modelled cloud's detail drift, per level; or an advected medium's angular flow, per coarse
// node) and time moved.
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) writeonly uniform image2D u_out;  // the full image (rgb radiance, a transmittance)
layout(binding = 0) uniform sampler2D u_history;       // the previous full image (read texel by texel)
layout(binding = 1) uniform sampler2D u_sparse;        // this frame's samples, one per block
layout(binding = 2) uniform sampler2D u_sparse_depth;  // the distance at which their view transmittance fell to 0.5 (3e38: never)
// The wind's motion since the history (longitude, latitude; degrees, after u_motion_scale), per node
// of (longitude, latitude, level): 1 x 1 per level for the modelled cloud's drift.
layout(binding = 3) uniform sampler3D u_wind_motion;
uniform bool u_wind;          // u_wind_motion holds a motion
uniform vec4 u_motion_axes;   // its nodes: first longitude, longitude step, first latitude, latitude step (degrees)
uniform float u_motion_scale; // what its values are multiplied by (seconds for a flow in degrees per second)
uniform vec3 u_alt_axis;      // the grid's levels: first altitude (m), spacing (m), count
uniform ivec2 u_full;        // the full image's size (a multiple of the block in each axis)
uniform ivec2 u_offset;      // this frame's pixel within each block
uniform bool u_has_history;  // false: the spatial blend everywhere but the new samples
uniform int u_cycle;         // the pass over every pixel (a still view from the second on: running means)
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

// Where the wind held the Earth-centred point x at the history's instant, as an offset from x: the
// point turned back by the motion at its place in longitude (about the polar axis) and latitude
// (along its meridian), at the same height. Between nodes and levels the motion is linear.
vec3 wind_back(vec3 x) {
  float r = length(x);
  float lat = asin(clamp(x.z / r, -1.0, 1.0));
  float lon = atan(x.y, x.x);
  vec3 size = vec3(textureSize(u_wind_motion, 0));
  // The longitude taken within half a turn of the nodes' middle, so a grid across the date line
  // (or a global one) finds its nodes.
  float middle = u_motion_axes.x + 0.5 * u_motion_axes.y * (size.x - 1.0);
  float rel = degrees(lon) - middle;
  rel -= 360.0 * floor((rel + 180.0) / 360.0);
  vec3 tc = vec3(((middle + rel - u_motion_axes.x) / u_motion_axes.y + 0.5) / size.x,
                 ((degrees(lat) - u_motion_axes.z) / u_motion_axes.w + 0.5) / size.y,
                 ((r - u_r0 - u_alt_axis.x) / u_alt_axis.y + 0.5) / size.z);
  vec2 m = radians(texture(u_wind_motion, tc).xy * u_motion_scale);
  float lat1 = lat - m.y, lon1 = lon - m.x;
  vec3 u1 = vec3(cos(lat1) * cos(lon1), cos(lat1) * sin(lon1), sin(lat1));
  return r * u1 - x;
}

// The history at pixel position x (pixel units, centres at half-integers) by Catmull-Rom
// interpolation over the 4 x 4 texels around it: a bilinear lookup would blur the history a little
// more at every frame that reprojects it by a fraction of a pixel; this keeps its detail. Its
// overshoot is taken off (radiance and transmittance stay within the taps' range).
vec4 history_at(vec2 x) {
  vec2 c = x - 0.5;
  vec2 i0 = floor(c);
  vec2 t = c - i0;
  vec2 t2 = t * t, t3 = t2 * t;
  vec2 w[4];
  w[0] = 0.5 * (-t3 + 2.0 * t2 - t);
  w[1] = 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0);
  w[2] = 0.5 * (-3.0 * t3 + 4.0 * t2 + t);
  w[3] = 0.5 * (t3 - t2);
  vec4 sum = vec4(0.0), lo = vec4(3.0e38), hi = vec4(-3.0e38);
  for (int j = 0; j < 4; ++j) {
    for (int i = 0; i < 4; ++i) {
      ivec2 q = clamp(ivec2(i0) + ivec2(i - 1, j - 1), ivec2(0), u_full - 1);
      vec4 h = texelFetch(u_history, q, 0);
      sum += w[i].x * w[j].y * h;
      if (i == 1 || i == 2) {
        if (j == 1 || j == 2) {
          lo = min(lo, h);
          hi = max(hi, h);
        }
      }
    }
  }
  return clamp(sum, lo, hi);
}

vec4 sparse_at(ivec2 b, ivec2 n) { return texelFetch(u_sparse, clamp(b, ivec2(0), n - 1), 0); }

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x >= u_full.x || p.y >= u_full.y) return;
  ivec2 n = textureSize(u_sparse, 0);
  ivec2 block = p / kBlock;
  if (p - block * kBlock == u_offset) {  // marched this frame: exact, or its pass's share of the mean
    vec4 s = sparse_at(block, n);
    if (u_has_history && u_cycle > 0) s = mix(texelFetch(u_history, p, 0), s, 1.0 / float(u_cycle + 1));
    imageStore(u_out, p, s);
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
  if (u_wind) {
    // With the wind, the closest cloud among the four new samples around: a gap in the cloud (the
    // ground seen through it) moves with the cloud around it, and an edge with the cloud in front.
    t = min(min(t, texelFetch(u_sparse_depth, clamp(b0, ivec2(0), n - 1), 0).r),
            min(texelFetch(u_sparse_depth, clamp(b0 + ivec2(1, 0), ivec2(0), n - 1), 0).r,
                min(texelFetch(u_sparse_depth, clamp(b0 + ivec2(0, 1), ivec2(0), n - 1), 0).r,
                    texelFetch(u_sparse_depth, clamp(b0 + ivec2(1, 1), ivec2(0), n - 1), 0).r)));
  }
  vec3 d = pixel_ray(vec2(p) + 0.5);
  vec3 q;
  if (t < 1.0e37) {
    q = u_delta + d * t;
    if (u_wind) q += wind_back(u_cam + d * t);
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
  vec4 h = history_at(prev);
  if (u_clamp) {
    // The range of the four new samples around this pixel: the history may not leave it, so what
    // moved or changed (or shines differently from the new viewpoint) does not linger as a ghost.
    vec4 lo = min(min(s00, s10), min(s01, s11));
    vec4 hi = max(max(s00, s10), max(s01, s11));
    h = mix(spatial, clamp(h, lo, hi), 0.5);
  }
  imageStore(u_out, p, h);
}
