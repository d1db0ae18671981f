// The slab table of the higher-order diffuse source (core/kernel/ms_slab ms_slab_table, read by
// march.glsl ms_slab_in_scatter): its layout, named once for GLSL and C++. Per phase (liquid, then
// ice) and per sun (CV_MS_SLAB_SUNS cosines mu0 evenly from CV_MS_SLAB_MU0_LO to 1), a grid of the
// optical depth above a point, t, and below it, b, each mapped to u = t / (t + CV_MS_SLAB_T0) in
// [0, 1] (u = 1: a half-space), and per cell CV_MS_SLAB_MOMENTS numbers: (2l + 1) / 2 chi'_l psi_lm
// per unit irradiance, first m = 0 with l = 0 .. CV_MS_SLAB_L0, then m = 1 .. CV_MS_SLAB_L each
// with l = m .. CV_MS_SLAB_L.
#ifndef CV_MS_SLAB_GLSL
#define CV_MS_SLAB_GLSL
#define CV_MS_SLAB_L 7    // the degree of the moments with m >= 1
#define CV_MS_SLAB_L0 15  // and of the azimuthal mean's (m = 0): at the poles of the sun's frame (a sun
                          // overhead seen from straight above) the series converges slowest
#define CV_MS_SLAB_MOMENTS (CV_MS_SLAB_L0 + 1 + CV_MS_SLAB_L * (CV_MS_SLAB_L + 1) / 2)
#define CV_MS_SLAB_DEPTHS 16
#define CV_MS_SLAB_SUNS 10
#define CV_MS_SLAB_T0 2.0
#define CV_MS_SLAB_MU0_LO 0.05
// Per cell the moments, then the diffuse flux going down there (per unit irradiance, the light a
// ground under the column takes), then the mean radiance the delta-scaled two-stream gives there
// (ms_slab_two_stream_i0), against which the source's I0 is measured.
#define CV_MS_SLAB_FLUX_DOWN CV_MS_SLAB_MOMENTS
#define CV_MS_SLAB_TWO_STREAM_I0 (CV_MS_SLAB_MOMENTS + 1)
// (two numbers of padding: a cell starts on four numbers, which the march reads as one vec4, 11
// reads instead of 44 a corner: on llvmpipe the slab shape's frame 2.0 -> 1.7x the octave sum's)
#define CV_MS_SLAB_STRIDE (CV_MS_SLAB_MOMENTS + 4)
#define CV_MS_SLAB_PHASE_SIZE (CV_MS_SLAB_SUNS * CV_MS_SLAB_DEPTHS * CV_MS_SLAB_DEPTHS * CV_MS_SLAB_STRIDE)
// After both phases' blocks, per phase the slab lit from below by isotropic radiance 1 (a ground's
// light; no sun, so no mu0): per (b, t) cell the azimuthal mean's moments to degree CV_MS_SLAB_BELOW_L
// times (2l + 1) / 2 chi'_l, the diffuse flux going down, and the two-stream's I0 per unit of that
// radiance.
#define CV_MS_SLAB_BELOW_L 15
#define CV_MS_SLAB_BELOW_FLUX_DOWN (CV_MS_SLAB_BELOW_L + 1)
#define CV_MS_SLAB_BELOW_TWO_STREAM_I0 (CV_MS_SLAB_BELOW_L + 2)
#define CV_MS_SLAB_BELOW_STRIDE (CV_MS_SLAB_BELOW_L + 5)  // (two of padding, as above)
#define CV_MS_SLAB_BELOW_SIZE (CV_MS_SLAB_DEPTHS * CV_MS_SLAB_DEPTHS * CV_MS_SLAB_BELOW_STRIDE)
#define CV_MS_SLAB_BELOW_OFFSET (2 * CV_MS_SLAB_PHASE_SIZE)
#define CV_MS_SLAB_TOTAL (2 * (CV_MS_SLAB_PHASE_SIZE + CV_MS_SLAB_BELOW_SIZE))
#endif
