// The viewer's fullscreen triangle: one triangle covering the viewport, no vertex buffer needed.
out vec2 v_uv;  // 0..1 across the image, v = 0 at the top row (the raymarcher writes rows top to bottom)

void main() {
  // Vertices (-1,-1), (3,-1), (-1,3): the part inside the viewport is the whole screen.
  vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
  v_uv = vec2(0.5 * (p.x + 1.0), 1.0 - 0.5 * (p.y + 1.0));
  gl_Position = vec4(p, 0.0, 1.0);
}
