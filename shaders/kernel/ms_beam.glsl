// The droplets' beam phase table (core/kernel/ms_source ms_beam_table, read by march.glsl
// ms_beam_phase_mie): its size, named once for GLSL and C++. Rows are the mean number of forward-peak
// scatterings lambda, mapped to s = lambda / (lambda + CV_MS_BEAM_LAMBDA0) in [0, 1] (s = 1: lambda
// infinite); columns the scattering angle, 0 to pi evenly.
#ifndef CV_MS_BEAM_GLSL
#define CV_MS_BEAM_GLSL
#define CV_MS_BEAM_ANGLES 256
#define CV_MS_BEAM_ROWS 64
#define CV_MS_BEAM_LAMBDA0 4.0
#define CV_MS_BEAM_SPIKE_TERMS 8
#endif
