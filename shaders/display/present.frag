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

void main() {
  vec4 p = texture(u_image, v_uv);
  vec3 e;
  for (int c = 0; c < 3; ++c) {
    float v = u_exposure * p[c] + p.a * u_background[c];
    // A non-finite pixel shows white, never noise.
    e[c] = (isnan(v) || isinf(v)) ? 1.0 : srgb(filmic(v));
  }
  o_color = vec4(clamp(e, 0.0, 1.0), 1.0);
}
