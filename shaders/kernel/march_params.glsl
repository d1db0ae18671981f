// X-macro table: the march kernel's parameters, one line each: CV_PARAM(type, name) in the shared
// dialect's types. Expanded at each include (app/render/shader_loader repeats it there; the first
// line's words say so): in GLSL as the members of the uniform block, as the per-invocation copies
// the kernel reads and as their loading (shaders/kernel/gpu_inputs.glsl); in C++ as the
// double-precision members of the C++ kernel (core/kernel/march_kernel.hpp) and as the float
// std140 struct the host uploads (core/kernel/march_params.hpp, its layout checked there). The
// order is the std140 packing: each vec3 is followed by a scalar that fills its fourth slot.
// Everything here is per frame; nothing per dispatch (the driver's own uniforms hold that).
CV_PARAM(real3, u_cam_ecef)          // metres (float: 0.5 m near the Earth, +-32 m at 4e8 m; rays re-anchor)
CV_PARAM(real, u_cam_alt)            // metres, from double on the CPU
CV_PARAM(real3, u_cam_up)            // local vertical at the camera
CV_PARAM(real, u_tan_half)           // of the horizontal field of view
CV_PARAM(real3, u_forward)
CV_PARAM(real, u_r0)                 // the sphere's radius, m
CV_PARAM(real3, u_right)
CV_PARAM(real, u_view_step)          // view step, m
CV_PARAM(real3, u_upv)
CV_PARAM(real, u_sigma_max)          // the volume's largest extinction, 1/m (PreparedVolume)
CV_PARAM(real3, u_to_sun)
CV_PARAM(real, u_sun_step_tau)       // optical depth a sun step may hold at u_sigma_max (sun_march_steps)
CV_PARAM(real3, u_irradiance)
CV_PARAM(real, u_sun_step_max)       // the longest a sun step may be, m (core::sun_step_limit_m)
CV_PARAM(real3, u_grid_start)        // (lon deg, lat deg, alt m)
CV_PARAM(real, u_max_step_tau)       // optical depth a view substep may hold (adaptive steps)
CV_PARAM(real3, u_grid_step)
CV_PARAM(real, u_min_t)              // view rays stop below this transmittance
CV_PARAM(real3, u_grid_count)
CV_PARAM(real, u_sun_tau_limit)      // sun marches stop past this optical depth (sun_march_tau_limit)
CV_PARAM(real3, u_octave_abc)
CV_PARAM(real, u_droplet_um)
CV_PARAM(real3, u_ground_albedo)     // linear, when there is no ground texture
CV_PARAM(real, u_ice_g)
CV_PARAM(real3, u_noise_anchor)      // metres, Earth-centred, a float-exact point near the data
CV_PARAM(real, u_noise_period)       // metres, the low-frequency tile
CV_PARAM(real3, u_noise_anchor_frac) // the anchor's position in tiles, from double on the CPU
CV_PARAM(real, u_noise_amount)
CV_PARAM(real2, u_layer)             // altitudes (m) between which the data holds cloud (CloudLayer)
CV_PARAM(ivec2, u_size)              // image size, pixels
CV_PARAM(real2, u_pixel_shift)       // where each pixel's ray passes, from its centre, pixels (Camera::pixel_shift_x, _y)
CV_PARAM(int, u_pixel_block)         // pixel px stands for pixel px * this + u_block_origin of a larger image (Camera::pixel_block)
CV_PARAM(ivec2, u_block_origin)      // (Camera::block_x, _y)
CV_PARAM(ivec2, u_ground_size)       // of the albedo texture; (0, 0): constant albedo
CV_PARAM(real3, u_tint_liquid)       // false colour (hue) of the liquid's light (march_settings.def tint_liquid)
CV_PARAM(bool, u_tint)               // a tint is set: each sample's light takes the hue of its tints
CV_PARAM(real3, u_tint_ice)          // false colour (hue) of the ice's light
CV_PARAM(real, u_ambient)            // strength of the isotropic sky light on clouds
CV_PARAM(real, u_ocean_wind)         // m/s, the sea's roughness for the sun glint (cox_munk_mss)
CV_PARAM(int, u_sun_steps)
CV_PARAM(int, u_octaves)
CV_PARAM(int, u_frame)               // -1: step middles; else the accumulation frame whose jitter places the samples
CV_PARAM(int, u_sky_steps)           // steps of a sky in-scatter integral
CV_PARAM(int, u_atmo_sun_steps)      // steps of an atmospheric transmittance toward the sun
CV_PARAM(int, u_levels)              // pyramid levels, 0: no pyramid
CV_PARAM(int, u_tl_count)            // translucent fragments per pixel in u_tl_distance, u_tl_color (0: none)
CV_PARAM(bool, u_wraps)
CV_PARAM(bool, u_global_lat)
CV_PARAM(bool, u_cloudless)          // no cloud anywhere: nothing to march
CV_PARAM(bool, u_sun_down)           // the whole cloud layer is in the Earth's shadow (layer_in_earth_shadow)
CV_PARAM(bool, u_octave_gate)        // weight octave i >= 1 by w^i from the column's optical depth
CV_PARAM(bool, u_ms_lateral)         // the two-stream source has a horizontal first moment (u_ms_horizontal)
CV_PARAM(bool, u_liquid_phase_hg)    // Henyey-Greenstein with the Mie fit's mean cosine instead of the fit
CV_PARAM(bool, u_blue_noise)         // the jitter from the blue-noise mask, else the hash
CV_PARAM(bool, u_anti_alias)         // accumulation frames >= 1 spread their rays over the pixel (pixel_jitter)
CV_PARAM(bool, u_has_depth)          // u_depth holds the distance to opaque geometry per pixel
CV_PARAM(bool, u_has_opaque_color)   // u_opaque holds that geometry's radiance, composited behind
CV_PARAM(real, u_mask_bottom)        // layer mask: the lowest height shown, m (march_settings.def layer_bottom_m)
CV_PARAM(real, u_mask_top)           // layer mask: heights from here up are hidden, m
CV_PARAM(bool, u_mask_sea_level)     // heights above sea level, else above the ground (u_column_tau.g)
CV_PARAM(bool, u_mask_band)          // the band hides something (not the whole column)
CV_PARAM(bool, u_hide_liquid)
CV_PARAM(bool, u_hide_ice)
CV_PARAM(real3, u_detail_tiles)      // modelled cloud: noise tiles per grid cell along lon, lat, altitude (whole numbers)
CV_PARAM(real, u_detail_amount)      // 0: the data's field, 1: the whole sub-grid shape (march_settings.def)
CV_PARAM(bool, u_has_fraction)       // u_fraction holds the cloud fraction; else the cover is 1 where there is cloud
CV_PARAM(real, u_ms_peak_liquid)     // two-stream: the liquid phase's cut (1/sr) above which its forward peak holds g^2 (ms_peak_cut)
CV_PARAM(real, u_ms_peak_ice)        // the same for the ice's Henyey-Greenstein phase
CV_PARAM(real, u_ms_peak_g_liquid)   // two-stream, liquid_phase_hg: the mean cosine of the liquid phase's peak above the cut (ms_peak)
CV_PARAM(real, u_ms_peak_g_ice)      // the same for ice
CV_PARAM(real, u_ms_beam_a_liquid)   // two-stream, Mie droplets: the fit's HG lobe's share of the peak kernel (ms_beam_table)
CV_PARAM(real, u_ms_f_liquid)        // two-stream: the share of the liquid phase taken as no scattering (g^2; the higher-order source's ms_slab_share)
CV_PARAM(real, u_ms_f_ice)           // the same for ice
CV_PARAM(ivec4, u_level_nodes)       // grid nodes per brick side, finest level first
CV_PARAM(ivec4, u_level_offset)      // first brick of each level in u_min_max
CV_PARAM_ARRAY(ivec4, u_bricks, 4)   // bricks per axis (xyz), finest level first
