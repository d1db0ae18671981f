// The viewer's tonemap: exposure, compositing over the background through the transmittance, the
// filmic curve and sRGB encoding, exactly as app/render/image_output.cpp does on the CPU (a test
// holds the two to one 8-bit step).
in vec2 v_uv;
out vec4 o_color;

layout(binding = 0) uniform sampler2D u_image;  // rgb = linear radiance, a = view transmittance
uniform float u_exposure;                        // radiance multiplier before the curve
uniform vec3 u_background;                       // linear, seen through the clouds

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

void main() {
  // Bilinear upscaling from a reduced march size, done on tonemapped texels: a non-finite texel
  // stays one white texel instead of spreading NaN through the filter weights (0 x NaN is NaN).
  // At 1:1 the weights are 0 and 1 and each pixel is exactly its texel.
  ivec2 size = textureSize(u_image, 0);
  vec2 t = v_uv * vec2(size) - 0.5;
  ivec2 i0 = ivec2(floor(t));
  vec2 f = t - vec2(i0);
  ivec2 a = clamp(i0, ivec2(0), size - 1);
  ivec2 b = clamp(i0 + 1, ivec2(0), size - 1);
  vec3 c00 = tonemap(texelFetch(u_image, ivec2(a.x, a.y), 0));
  vec3 c10 = tonemap(texelFetch(u_image, ivec2(b.x, a.y), 0));
  vec3 c01 = tonemap(texelFetch(u_image, ivec2(a.x, b.y), 0));
  vec3 c11 = tonemap(texelFetch(u_image, ivec2(b.x, b.y), 0));
  o_color = vec4(mix(mix(c00, c10, f.x), mix(c01, c11, f.x), f.y), 1.0);
}
