// The march kernel's inputs as a GPU program declares them: the parameters as one uniform block
// (core/kernel/march_params.hpp packs it, std140), the prepared volume and the other textures, the
// pyramid and the counters, and the program's compile-time switches. shaders/render/raymarch.comp
// and the kernel's other GPU programs include it before the kernel, and call load_march_params()
// first in main.
#define CV_PARAM(T, name) T name;
#define CV_PARAM_ARRAY(T, name, N) T name[N];
layout(std140, binding = CV_UBO_MARCH) uniform MarchParams {
#include "../kernel/march_params.glsl"
} cv_march_params;
// The kernel reads per-invocation copies of the parameters, loaded once at the start of main: on
// llvmpipe a uniform (a block's member or a plain one alike) is loaded from its buffer where it is
// read, at every sample of both marches, while the copies are loaded once; that made the march
// about 15 % faster there, with the same images bit for bit (docs/BENCHMARKS.md, "Parameters
// loaded once per invocation").
#include "../kernel/march_params.glsl"
#undef CV_PARAM
#undef CV_PARAM_ARRAY
#define CV_PARAM(T, name) name = cv_march_params.name;
#define CV_PARAM_ARRAY(T, name, N) name = cv_march_params.name;
void load_march_params() {
#include "../kernel/march_params.glsl"
}
#undef CV_PARAM
#undef CV_PARAM_ARRAY

// The prepared volume and the other textures, fetched texel by texel (interpolated in the kernel).
layout(binding = CV_TEX_LIQUID) uniform sampler3D u_liquid;  // grid-mean extinction, 1/m (cf x in-cloud)
layout(binding = CV_TEX_ICE) uniform sampler3D u_ice;
// Per column, layer 0: vertical optical depth (r), ground altitude m (g), cumuliform (b) and cirriform
// (a) memberships; layer 1: the ice's part of the optical depth (r).
layout(binding = CV_TEX_COLUMN_TAU) uniform sampler2DArray u_column_tau;
layout(binding = CV_TEX_JITTER_MASK) uniform sampler2D u_jitter_mask;  // blue-noise rank / n^2, tiled
layout(binding = CV_TEX_GROUND) uniform sampler2D u_ground;  // linear albedo, equirectangular
layout(binding = CV_TEX_NOISE_LOW) uniform sampler3D u_noise_low;    // Perlin-Worley, periodic, [0, 1]
layout(binding = CV_TEX_NOISE_HIGH) uniform sampler3D u_noise_high;  // Worley fBm, periodic, [0, 1]
layout(binding = CV_TEX_DEPTH) uniform sampler2D u_depth;    // distance (m) from the camera to opaque geometry
layout(binding = CV_TEX_OPAQUE) uniform sampler2D u_opaque;  // that geometry's radiance
// Translucent geometry (shaders/render/overlay.frag, peeled): u_tl_count fragments per pixel, nearest
// first, side by side (fragment k of pixel (x, y) at (x + k * width, y)): the distance (m, 0: none)
// and the radiance with its alpha (not premultiplied).
layout(binding = CV_TEX_TL_DISTANCE) uniform sampler2D u_tl_distance;
layout(binding = CV_TEX_TL_COLOR) uniform sampler2D u_tl_color;
layout(binding = CV_TEX_MS_MOMENTS) uniform sampler3D u_ms_moments;        // two-stream diffuse radiance per unit irradiance, its first moment up (RG)
layout(binding = CV_TEX_MS_HORIZONTAL) uniform sampler3D u_ms_horizontal;  // the first moment east and north (RG; read when u_ms_lateral)
layout(binding = CV_TEX_FRACTION) uniform sampler3D u_fraction;  // cloud fraction per node (the modelled cloud's cover)
layout(binding = CV_TEX_DETAIL_TABLE) uniform sampler2D u_detail_table;  // (threshold, ramp mean) by cover (x) and cloud type (y) (core/noise detail_table)
layout(binding = CV_TEX_DETAIL_SHIFT) uniform sampler2D u_detail_shift;  // the detail's wind displacement per level, in tiles (core/kernel/detail_drift)
// The extinction pyramid: (min, max) per brick, levels one after the other, x fastest.
layout(std430, binding = CV_SSBO_PYRAMID) readonly buffer Pyramid { vec2 u_min_max[]; };
// The droplets' beam phase table (core/kernel/ms_source ms_beam_table), CV_MS_BEAM_ROWS x CV_MS_BEAM_ANGLES.
#include "../kernel/ms_beam.glsl"
layout(std430, binding = CV_SSBO_MS_BEAM) readonly buffer MsBeam { float u_ms_beam_table[]; };
// The higher-order source's slab table (core/kernel/ms_slab ms_slab_table), liquid then ice.
#include "../kernel/ms_slab.glsl"
layout(std430, binding = CV_SSBO_MS_SLAB) readonly buffer MsSlab { float u_ms_slab_table[]; };
// The same buffer four numbers at a time (its cells start on four: ms_slab.glsl).
layout(std430, binding = CV_SSBO_MS_SLAB) readonly buffer MsSlab4 { vec4 u_ms_slab_table4[]; };
// Per-frame counters (MarchStats), each as (low, high) 32-bit words.
layout(std430, binding = CV_SSBO_STATS) buffer Stats { uint u_stats[]; };
uint g_stats[CV_STAT_COUNT] = uint[CV_STAT_COUNT](0u, 0u, 0u, 0u, 0u, 0u, 0u, 0u);

// Program variants (kernel::MarchVariant::defines): llvmpipe runs both sides of a branch under masks,
// so code switched off by a uniform would still cost every iteration. Without defines (a bare
// compile): the defaults of MarchSettings.
#ifndef CV_SKIP_EMPTY
#define CV_SKIP_EMPTY 1
#endif
#ifndef CV_ADAPTIVE
#define CV_ADAPTIVE 0
#endif
#ifndef CV_ATMOSPHERE
#define CV_ATMOSPHERE 1
#endif
#ifndef CV_GLOBE
#define CV_GLOBE 1
#endif
#ifndef CV_NOISE
#define CV_NOISE 0
#endif
#ifndef CV_TWO_STREAM
#define CV_TWO_STREAM 0
#endif
#ifndef CV_TRANSLUCENT
#define CV_TRANSLUCENT 0
#endif
#ifndef CV_LAYER_MASK
#define CV_LAYER_MASK 0
#endif
#ifndef CV_TINT
#define CV_TINT 0
#endif
#ifndef CV_MODELLED
#define CV_MODELLED 0
#endif
#ifndef CV_MS_SLAB_SHAPE
#define CV_MS_SLAB_SHAPE 1
#endif
const bool kSkipEmpty = CV_SKIP_EMPTY != 0;
const bool kAdaptive = CV_ADAPTIVE != 0;
const bool kAtmosphere = CV_ATMOSPHERE != 0;
const bool kGlobe = CV_GLOBE != 0;
const bool kNoise = CV_NOISE != 0;
const bool kTwoStream = CV_TWO_STREAM != 0;  // the two-stream source; else the octave sum
const bool kTranslucent = CV_TRANSLUCENT != 0;  // translucent geometry composited among the samples
const bool kLayerMask = CV_LAYER_MASK != 0;     // a height band masks the medium (u_mask_band)
const bool kTint = CV_TINT != 0;                // false colour by liquid and ice (u_tint)
const bool kModelled = CV_MODELLED != 0;        // the modelled cloud: sub-grid detail keeping each cell's means
const bool kSlab = kTwoStream && CV_MS_SLAB_SHAPE != 0;  // the two-stream's diffuse light shaped by the slab tables
