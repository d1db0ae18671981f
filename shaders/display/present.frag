// The viewer's tonemap: exposure, compositing over the background through the transmittance, the
// filmic curve and sRGB encoding, exactly as app/render/image_output.cpp does on the CPU (a test
// holds the two to one 8-bit step).
in vec2 v_uv;  // unused: pixels are addressed through gl_FragCoord, exactly
out vec4 o_color;

layout(binding = 0) uniform sampler2D u_image;  // rgb = linear radiance, a = view transmittance
uniform float u_exposure;                        // radiance multiplier before the curve
uniform vec3 u_background;                       // linear, seen through the clouds
uniform ivec4 u_viewport;                        // x, y, width, height of the draw, window pixels

// Narkowicz's fit of the ACES reference tone scale: toe and shoulder, 1 at white.
float filmic(float x) { return clamp(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0); }
float srgb(float linear) { return linear <= 0.0031308 ? 12.92 * linear : 1.055 * pow(linear, 1.0 / 2.4) - 0.055; }

vec3 tonemap(vec4 p) {
  vec3 e;
  for (int c = 0; c < 3; ++c) {
    float v = u_exposure * p[c] + p.a * u_background[c];
    // A non-finite pixel shows white, never noise. Tested on the bits: GLSL's isnan/isinf may be
    // folded away by an optimising compiler.
    bool finite = (floatBitsToUint(v) & 0x7f800000u) != 0x7f800000u;
    e[c] = finite ? srgb(filmic(v)) : 1.0;
  }
  return clamp(e, 0.0, 1.0);
}

// The interpolation weight of output pixel o between input texels i0 and i1 = min(i0 + 1, n - 1) when
// n input texels stretch over m output pixels: written as image_output.cpp's upscale_linear writes
// it, in float, so the viewer and `render` compute the same pixels.
int texel_below(int o, int n, int m, out int i1, out float t) {
  float f = clamp((float(o) + 0.5) * float(n) / float(m) - 0.5, 0.0, float(n - 1));
  int i0 = int(f);
  i1 = min(i0 + 1, n - 1);
  t = f - float(i0);
  return i0;
}
// A weight of 0 takes a alone: a non-finite neighbour does not reach a pixel it does not cover.
vec4 lerp_texels(vec4 a, vec4 b, float t) { return t > 0.0 ? mix(a, b, t) : a; }

void main() {
  // Bilinear upscaling from a reduced march size in linear radiance, then the tonemap, as `render`
  // does (upscale_linear, tonemap_srgb8). At 1:1 each pixel is exactly its texel.
  ivec2 size = textureSize(u_image, 0);
  ivec2 o = ivec2(gl_FragCoord.xy) - u_viewport.xy;
  o.y = u_viewport.w - 1 - o.y;  // image rows run top to bottom
  int x1;
  int y1;
  float tx;
  float ty;
  int x0 = texel_below(o.x, size.x, u_viewport.z, x1, tx);
  int y0 = texel_below(o.y, size.y, u_viewport.w, y1, ty);
  vec4 top = lerp_texels(texelFetch(u_image, ivec2(x0, y0), 0), texelFetch(u_image, ivec2(x1, y0), 0), tx);
  vec4 bottom = lerp_texels(texelFetch(u_image, ivec2(x0, y1), 0), texelFetch(u_image, ivec2(x1, y1), 0), tx);
  o_color = vec4(tonemap(lerp_texels(top, bottom, ty)), 1.0);
}
