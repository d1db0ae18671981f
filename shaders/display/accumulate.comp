// The viewer's temporal accumulation: a running mean of jittered raymarcher frames, kept on the GPU.
// After frame n (0-based) the mean is mean + (frame - mean) / (n + 1), so frame 0 replaces it.
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform image2D u_mean;                 // read and written
layout(rgba32f, binding = 1) readonly uniform image2D u_frame;       // the frame just marched
uniform ivec2 u_size;
uniform int u_count;  // frames already in the mean (0 starts afresh)

void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  if (px.x >= u_size.x || px.y >= u_size.y) return;
  vec4 f = imageLoad(u_frame, px);
  vec4 m = u_count == 0 ? f : imageLoad(u_mean, px);
  imageStore(u_mean, px, m + (f - m) / float(u_count + 1));
}
