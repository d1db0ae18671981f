// Binding points of the march's textures, images and buffers, named once for GLSL and C++
// (app/render/raymarcher.cpp binds by these names). Texture units, image units, uniform and
// storage buffer bindings are separate name spaces in OpenGL.
#define CV_TEX_LIQUID 1
#define CV_TEX_ICE 2
#define CV_TEX_NOISE_LOW 3
#define CV_TEX_NOISE_HIGH 4
#define CV_TEX_GROUND 5
#define CV_TEX_JITTER_MASK 6
#define CV_TEX_COLUMN_TAU 7
#define CV_TEX_DEPTH 8
#define CV_TEX_OPAQUE 9
#define CV_TEX_MS_MOMENTS 10
#define CV_TEX_MS_HORIZONTAL 11
#define CV_TEX_TL_DISTANCE 12
#define CV_TEX_TL_COLOR 13
#define CV_TEX_FRACTION 14
#define CV_TEX_DETAIL_TABLE 15
#define CV_TEX_DETAIL_SHIFT 0  // unit 0 is free in the march's program: 16 units is GL's least for compute
#define CV_IMAGE_OUT 0
#define CV_IMAGE_STATE_L 6
#define CV_IMAGE_STATE_DEPTH 7
#define CV_IMAGE_STATE_MS 5
#define CV_IMAGE_CLOUD_DEPTH 4
#define CV_SSBO_PYRAMID 3
#define CV_SSBO_STATS 4
#define CV_UBO_MARCH 0
#define CV_SSBO_PATH_SUMS 5
#define CV_SSBO_PATH_STATS 6
#define CV_SSBO_PATH_STATE 7
#define CV_SSBO_PATH_BRANCHES 2
#define CV_SSBO_MS_BEAM 1
#define CV_SSBO_MS_SLAB 0
