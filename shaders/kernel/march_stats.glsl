// The march's counters (core::MarchStats), by index into g_stats: named once for GLSL and C++.
#define CV_STAT_VIEW_SAMPLES 0
#define CV_STAT_VIEW_SKIPPED 1
#define CV_STAT_BRICKS_JUMPED 2
#define CV_STAT_SUN_SAMPLES 3
#define CV_STAT_SUN_SKIPPED 4
#define CV_STAT_RAYS_MISSED 5
#define CV_STAT_OCTAVE_TERMS 6
#define CV_STAT_OCTAVE_TERMS_FULL 7
#define CV_STAT_COUNT 8
