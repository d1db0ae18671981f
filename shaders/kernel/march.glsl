// The march kernel, written once in the shared dialect: the GPU driver (shaders/render/raymarch.comp)
// runs it in float, the CPU reference (core/kernel/march_kernel.hpp) in double. It reads the medium
// through typed volumes (a sampler3D in GLSL; a small C++ class with the same texelFetch), walks the
// extinction pyramid, marches toward the sun, sums the sample source and advances the view march as
// a state, then composites sky and ground. The parameters are shaders/kernel/march_params.glsl.
//
// What the including side declares before this file: the parameters (u_*), the textures u_liquid,
// u_ice (sampler3D, grid-mean extinction 1/m), u_ms_moments, u_ms_horizontal (sampler3D, the two-stream source: I0 and I1 up; I1 east and north), u_column_tau, u_jitter_mask, u_ground, u_depth (the
// distance to opaque geometry per pixel, m), u_opaque (that geometry's radiance), u_tl_distance and
// u_tl_color (translucent fragments, u_tl_count per pixel side by side, nearest first) (sampler2D),
// u_noise_low, u_noise_high (sampler3D), the pyramid u_min_max (vec2 per brick, levels one after
// the other), the droplets' beam table u_ms_beam_table (floats, ms_beam.glsl's size), the counters
// g_stats[CV_STAT_COUNT] (uint, indices in march_stats.glsl) and the switches kSkipEmpty, kAdaptive,
// kAtmosphere, kGlobe, kNoise, kTwoStream and kTranslucent (compile-time constants on the GPU, where llvmpipe runs both sides
// of a branch under masks; plain members in C++).
//
// Loops are shaped for Mesa's llvmpipe: all loops of one invocation share a budget of 65 535
// iterations (LP_MAX_TGSI_LOOP_ITERATIONS in gallivm), after which every loop runs its body once
// and stops, silently. So the pyramid's levels and a cell's 8 nodes are written out, a view march
// takes one loop iteration per sample (substeps included), and the march advances over a range of
// steps (march_advance) that the GPU driver sizes to fit a dispatch (app/render/raymarcher.cpp).

#define CV_KDEG real(0.017453292519943295)

// Trilinear over texel centres: no data reads as 0, and so do the border nodes (index -1 or n) a
// regional grid fades into.
CV_FN real node(sampler3D tex, int x, int y, int z) {
  ivec3 n = ivec3(u_grid_count);
  return x < 0 || x >= n.x || y < 0 || y >= n.y ? real(0.0) : real(texelFetch(tex, ivec3(x, y, z), 0).r);
}

// The trilinear value at f (x) with its cell's shape from the same 8 nodes: their mean (y, the
// cell's mean of the trilinear field) and the differences between the cell's faces along the
// longitude (z) and latitude (w) indices (face means, upper minus lower).
// The cell at f: its lower and upper node indices (longitude wrapping where the grid does) and the
// trilinear weights.
CV_FN void cell_at(real3 f, CV_OUT(ivec3) lo, CV_OUT(ivec3) hi, CV_OUT(real3) w) {
  ivec3 n = ivec3(u_grid_count);
  real wx;
  real wy;
  real wz;
  lo = ivec3(volume_fetch_index(f.x, n.x, wx), volume_fetch_index(f.y, n.y, wy), volume_fetch_index(f.z, n.z, wz));
  hi = ivec3(u_wraps ? (lo.x + 1) % n.x : lo.x + 1, lo.y + 1, min(lo.z + 1, n.z - 1));
  w = real3(wx, wy, wz);
}

CV_FN real4 fetch_cell(sampler3D tex, real3 f) {
  ivec3 lo;
  ivec3 hi;
  real3 w;
  cell_at(f, lo, hi, w);
  int x0 = lo.x;
  int y0 = lo.y;
  int z0 = lo.z;
  int x1 = hi.x;
  int y1 = hi.y;
  int z1 = hi.z;
  real wx = w.x;
  real wy = w.y;
  real wz = w.z;
  real n000 = node(tex, x0, y0, z0);
  real n100 = node(tex, x1, y0, z0);
  real n010 = node(tex, x0, y1, z0);
  real n110 = node(tex, x1, y1, z0);
  real n001 = node(tex, x0, y0, z1);
  real n101 = node(tex, x1, y0, z1);
  real n011 = node(tex, x0, y1, z1);
  real n111 = node(tex, x1, y1, z1);
  real v = mix(mix(mix(n000, n100, wx), mix(n010, n110, wx), wy), mix(mix(n001, n101, wx), mix(n011, n111, wx), wy), wz);
  real mean = (n000 + n100 + n010 + n110 + n001 + n101 + n011 + n111) * real(0.125);
  real dx = (n100 + n110 + n101 + n111 - n000 - n010 - n001 - n011) * real(0.25);
  real dy = (n010 + n110 + n011 + n111 - n000 - n100 - n001 - n101) * real(0.25);
  return real4(v, mean, dx, dy);
}

// The trilinear value at f (the shape's sums are left to the compiler to drop).
CV_FN real fetch(sampler3D tex, real3 f) { return fetch_cell(tex, f).x; }

// A node of a texture of up to four channels (0 beside a regional grid), and the bilinear value
// over the level z of the cell between a and b (cell_at's corners and weights).
CV_FN real4 node4(sampler3D tex, int x, int y, int z) {
  ivec3 n = ivec3(u_grid_count);
  if (x < 0 || x >= n.x || y < 0 || y >= n.y) return real4(0.0);
  return real4(texelFetch(tex, ivec3(x, y, z), 0));
}
CV_FN real4 level4(sampler3D tex, ivec3 a, ivec3 b, real3 w, int z) {
  return mix(mix(node4(tex, a.x, a.y, z), node4(tex, b.x, a.y, z), w.x), mix(node4(tex, a.x, b.y, z), node4(tex, b.x, b.y, z), w.x), w.y);
}

// The trilinear value of a two-channel texture (red, green) at f, as fetch.
CV_FN real2 node2(sampler3D tex, int x, int y, int z) {
  real4 t = node4(tex, x, y, z);
  return real2(t.x, t.y);
}
CV_FN real2 fetch2(sampler3D tex, real3 f) {
  ivec3 a;
  ivec3 b;
  real3 w;
  cell_at(f, a, b, w);
  real2 lo = mix(mix(node2(tex, a.x, a.y, a.z), node2(tex, b.x, a.y, a.z), w.x), mix(node2(tex, a.x, b.y, a.z), node2(tex, b.x, b.y, a.z), w.x), w.y);
  real2 hi = mix(mix(node2(tex, a.x, a.y, b.z), node2(tex, b.x, a.y, b.z), w.x), mix(node2(tex, a.x, b.y, b.z), node2(tex, b.x, b.y, b.z), w.x), w.y);
  return mix(lo, hi, w.z);
}

// Trilinear with wrap-around over a periodic noise tile (x, then y, then z).
CV_FN real fetch_noise(sampler3D tex, real3 t) {
  int n = textureSize(tex, 0).x;
  ivec3 i0;
  ivec3 i1;
  real3 w;
  noise_texel_pair(t.x, n, i0.x, i1.x, w.x);
  noise_texel_pair(t.y, n, i0.y, i1.y, w.y);
  noise_texel_pair(t.z, n, i0.z, i1.z, w.z);
  real c00 = mix(real(texelFetch(tex, ivec3(i0.x, i0.y, i0.z), 0).r), real(texelFetch(tex, ivec3(i1.x, i0.y, i0.z), 0).r), w.x);
  real c10 = mix(real(texelFetch(tex, ivec3(i0.x, i1.y, i0.z), 0).r), real(texelFetch(tex, ivec3(i1.x, i1.y, i0.z), 0).r), w.x);
  real c01 = mix(real(texelFetch(tex, ivec3(i0.x, i0.y, i1.z), 0).r), real(texelFetch(tex, ivec3(i1.x, i0.y, i1.z), 0).r), w.x);
  real c11 = mix(real(texelFetch(tex, ivec3(i0.x, i1.y, i1.z), 0).r), real(texelFetch(tex, ivec3(i1.x, i1.y, i1.z), 0).r), w.x);
  return mix(mix(c00, c10, w.y), mix(c01, c11, w.y), w.z);
}

// Sub-grid erosion (shaders/common/erosion.glsl) of both extinctions at p.
CV_FN void erode_at(real3 p, CV_INOUT(real) sl, CV_INOUT(real) si) {
  real3 t = noise_tile_coords(p - u_noise_anchor, u_noise_anchor_frac, u_noise_period);
  real e = erosion_threshold(fetch_noise(u_noise_low, t), fetch_noise(u_noise_high, noise_high_coords(t)), u_noise_amount);
  real feature_m = noise_feature_m(u_noise_period);
  sl = erode_extinction(sl, e, feature_m);
  si = erode_extinction(si, e, feature_m);
}

// The column map at grid index f, bilinear with the 3-D fetch's horizontal rules (wrap, pole clamp,
// regional border 0), from the prepared volume's column map (u_column_tau, four channels): the
// column's vertical optical depth (x), the ground's altitude in metres (y), and the weather
// textures' cumuliform (z) and cirriform (w) memberships (core/kernel/weather_textures); layer 1
// holds the ice's part of the optical depth (x).
CV_FN real4 column_texel_of(real3 f, int layer) {
  ivec2 n = ivec2(u_grid_count);
  real wx;
  real wy;
  int x0 = volume_fetch_index(f.x, n.x, wx);
  int y0 = volume_fetch_index(f.y, n.y, wy);
  int x1 = u_wraps ? (x0 + 1) % n.x : x0 + 1;
  int y1 = y0 + 1;
  real4 t00 = x0 < 0 || x0 >= n.x || y0 < 0 || y0 >= n.y ? real4(0.0) : real4(texelFetch(u_column_tau, ivec3(x0, y0, layer), 0));
  real4 t10 = x1 < 0 || x1 >= n.x || y0 < 0 || y0 >= n.y ? real4(0.0) : real4(texelFetch(u_column_tau, ivec3(x1, y0, layer), 0));
  real4 t01 = x0 < 0 || x0 >= n.x || y1 < 0 || y1 >= n.y ? real4(0.0) : real4(texelFetch(u_column_tau, ivec3(x0, y1, layer), 0));
  real4 t11 = x1 < 0 || x1 >= n.x || y1 < 0 || y1 >= n.y ? real4(0.0) : real4(texelFetch(u_column_tau, ivec3(x1, y1, layer), 0));
  return mix(mix(t00, t10, wx), mix(t01, t11, wx), wy);
}
CV_FN real4 column_texel(real3 f) { return column_texel_of(f, 0); }

// The column's optical depth (x) and ground altitude (y) at grid index f.
CV_FN real2 column_map(real3 f) {
  real4 t = column_texel(f);
  return real2(t.x, t.y);
}

// One type's first-order cell-mean error (detail_factor_of): the tile's first moments along the
// longitude and latitude indices at the cover entry im (weight wm towards im + 1, entries dc apart
// in cover) and the phase rows px, py, against the extinction's relative face differences gx, gy
// and the cover's gcx, gcy, over the tiles per cell.
CV_FN real detail_moment_term(int type, int im, real wm, real dc, int px, int py, real gx, real gy, real gcx, real gcy) {
  int rx = CV_DETAIL_TYPES + type * CV_DETAIL_PHASES + px;
  int ry = CV_DETAIL_TYPES + type * CV_DETAIL_PHASES + py;
  real mx0 = real(texelFetch(u_detail_table, ivec2(im, rx), 0).x);
  real mx1 = real(texelFetch(u_detail_table, ivec2(im + 1, rx), 0).x);
  real my0 = real(texelFetch(u_detail_table, ivec2(im, ry), 0).y);
  real my1 = real(texelFetch(u_detail_table, ivec2(im + 1, ry), 0).y);
  return (gx * mix(mx0, mx1, wm) + gcx * (mx1 - mx0) / dc) / u_detail_tiles.x + (gy * mix(my0, my1, wm) + gcy * (my1 - my0) / dc) / u_detail_tiles.y;
}

// The modelled cloud (kModelled; shaders/common/detail.glsl, docs/physics.md "The modelled cloud"):
// the factor by which the data's grid-mean extinction at grid index f is redistributed inside its
// cell. The noise lies in whole tiles per cell (u_detail_tiles along lon, lat and altitude), so a
// cell holds the tile's distribution of it; the cover c is the data's cloud fraction at f (1 without
// one); the table gives the threshold t(c) above which a share c of the tile lies and the tile's
// mean m(c) of the ramp above it. So (1 - a) + a h / m keeps the cell's mean extinction for any
// amount a, and with a = 1 the cloudy share of the cell is its cover. The tiles are displaced along
// the level-mean wind (u_detail_shift, per level in tiles, linear between levels: a shift constant
// over each horizontal slice of a cell keeps the slice's share of the periodic tile), so the detail
// travels with the cloud and every cell keeps its cover and mean at every instant. The ramp's
// softness is the cloud type's (the weather textures' memberships, bilinear from the columns: the
// table's rows); the types' factors, each of mean 1 over a cell, are blended by the memberships, and
// all share the threshold, so the cloudy share stays c.
//
// The cell-mean correction: where the extinction and the cover vary across a cell, they meet the
// pattern's first moments along it, and the cell's mean is off by (g M(c, phi) + gamma dM/dc) / T
// per horizontal axis to first order (g: the extinction's relative difference between the cell's
// faces, gamma: the cover's, T: tiles per cell, M: the tile's first moment of the factor at the
// phase phi where the cell starts in its tile; the table's moment rows). Dividing by 1 plus that
// sum, bounded to 1/1.1..1.1, takes it out; the vertical mirror leaves no moment in height.
// `s` is fetch_cell of the extinction shown (liquid + ice).
CV_FN real detail_factor_of(real3 f, real4 s) {
  real4 cc = u_has_fraction ? fetch_cell(u_fraction, f) : real4(1.0, 1.0, 0.0, 0.0);
  real c = clamp(cc.x, real(0.0), real(1.0));
  real x = sqrt(c) * real(CV_DETAIL_COVERS);  // the table's covers are (k / N)^2
  int i = min(int(x), CV_DETAIL_COVERS - 1);
  real w = x - real(i);
  real4 col = column_texel(f);
  real w_cu = clamp(col.z, real(0.0), real(1.0));
  real w_ci = clamp(col.w, real(0.0), real(1.0) - w_cu);
  real w_st = real(1.0) - w_cu - w_ci;
  real wz;
  int k0 = volume_fetch_index(f.z, int(u_grid_count.z), wz);
  int k1 = min(k0 + 1, int(u_grid_count.z) - 1);
  real4 s0 = real4(texelFetch(u_detail_shift, ivec2(k0, 0), 0));
  real4 s1 = real4(texelFetch(u_detail_shift, ivec2(k1, 0), 0));
  real3 tc = fract(f * u_detail_tiles - real3(mix(s0.x, s1.x, wz), mix(s0.y, s1.y, wz), real(0.0)));
  tc.z = real(1.0) - abs(real(2.0) * tc.z - real(1.0));  // mirrored about each tile's middle height
  // The threshold and the types' ramp means of the horizontal slice at the tile height tc.z: linear
  // between the two nearest slices' rows (centres at (j + 1/2) / SLICES), and between covers.
  real zs = clamp(tc.z * real(CV_DETAIL_SLICES) - real(0.5), real(0.0), real(CV_DETAIL_SLICES - 1));
  int j0 = min(int(floor(zs)), CV_DETAIL_SLICES - 2);
  real wj = zs - real(j0);
  int r0 = CV_DETAIL_SLICE_ROW0 + j0 * CV_DETAIL_TYPES;
  int r1 = r0 + CV_DETAIL_TYPES;
  real2 a0 = mix(real2(texelFetch(u_detail_table, ivec2(i, r0), 0)), real2(texelFetch(u_detail_table, ivec2(i + 1, r0), 0)), w);
  real2 b0 = mix(real2(texelFetch(u_detail_table, ivec2(i, r1), 0)), real2(texelFetch(u_detail_table, ivec2(i + 1, r1), 0)), w);
  real t = mix(a0.x, b0.x, wj);  // the same in every type's row
  real m0 = mix(a0.y, b0.y, wj);
  real m1 = mix(mix(real(texelFetch(u_detail_table, ivec2(i, r0 + 1), 0).y), real(texelFetch(u_detail_table, ivec2(i + 1, r0 + 1), 0).y), w),
                mix(real(texelFetch(u_detail_table, ivec2(i, r1 + 1), 0).y), real(texelFetch(u_detail_table, ivec2(i + 1, r1 + 1), 0).y), w), wj);
  real m2 = mix(mix(real(texelFetch(u_detail_table, ivec2(i, r0 + 2), 0).y), real(texelFetch(u_detail_table, ivec2(i + 1, r0 + 2), 0).y), w),
                mix(real(texelFetch(u_detail_table, ivec2(i, r1 + 2), 0).y), real(texelFetch(u_detail_table, ivec2(i + 1, r1 + 2), 0).y), w), wj);
  real n = detail_noise_mix(fetch_noise(u_noise_low, tc), fetch_noise(u_noise_high, noise_high_coords(tc)));
  real g = (m0 > real(0.0) ? w_st * detail_ramp(n, t, detail_softness(0)) / m0 : real(0.0)) +
           (m1 > real(0.0) ? w_cu * detail_ramp(n, t, detail_softness(1)) / m1 : real(0.0)) +
           (m2 > real(0.0) ? w_ci * detail_ramp(n, t, detail_softness(2)) / m2 : real(0.0));
  // The correction, at the cell's mean cover and the phases where the cell starts in its tiles.
  real cm = clamp(cc.y, real(0.0), real(1.0));
  real xm = sqrt(cm) * real(CV_DETAIL_COVERS);
  int im = min(int(xm), CV_DETAIL_COVERS - 1);
  real wm = xm - real(im);
  real dc = (real(im + 1) * real(im + 1) - real(im) * real(im)) / real(CV_DETAIL_COVERS * CV_DETAIL_COVERS);
  real2 phase = fract(-real2(mix(s0.x, s1.x, wz), mix(s0.y, s1.y, wz)));
  int px = int(floor(phase.x * real(CV_DETAIL_PHASES) + real(0.5))) % CV_DETAIL_PHASES;
  int py = int(floor(phase.y * real(CV_DETAIL_PHASES) + real(0.5))) % CV_DETAIL_PHASES;
  real gx = s.y > real(0.0) ? s.z / s.y : real(0.0);
  real gy = s.y > real(0.0) ? s.w / s.y : real(0.0);
  // Written out per type, not looped (llvmpipe's loop budget is shared by the whole march).
  real corr = w_st * detail_moment_term(0, im, wm, dc, px, py, gx, gy, cc.z, cc.w) +
              w_cu * detail_moment_term(1, im, wm, dc, px, py, gx, gy, cc.z, cc.w) +
              w_ci * detail_moment_term(2, im, wm, dc, px, py, gx, gy, cc.z, cc.w);
  real kappa = clamp(real(1.0) / max(real(1.0) + u_detail_amount * corr, real(1e-6)), real(1.0) / real(CV_DETAIL_CORRECTION_MAX),
                     real(CV_DETAIL_CORRECTION_MAX));
  return (real(1.0) - u_detail_amount + u_detail_amount * g) * kappa;
}

// The factor at f, fetching the extinction's cell itself (for callers outside the march).
CV_FN real detail_factor(real3 f) {
  real4 s = fetch_cell(u_liquid, f) * (u_hide_liquid ? real(0.0) : real(1.0)) + fetch_cell(u_ice, f) * (u_hide_ice ? real(0.0) : real(1.0));
  return detail_factor_of(f, s);
}

// The column's vertical optical depth at p (the column map's x).
CV_FN real column_tau(real3 p) {
  real3 g = ecef_to_sphere(p, u_r0);
  real3 f;
  if (!volume_coords(g.x / CV_KDEG, g.y / CV_KDEG, u_grid_start.z, u_grid_start, u_grid_step, u_grid_count, u_wraps, u_global_lat, f)) return real(0.0);
  return column_map(f).x;
}

// The column's vertical optical depth at p as the sky's light through it sees it: each phase's
// part times 1 - its mean cosine (liquid g_liquid, ice g_ice), the depth that sets a conservative
// layer's spherical transmittance (sky_share_of_depth).
CV_FN real column_diffusion_depth(real3 p, real g_liquid, real g_ice) {
  real3 g = ecef_to_sphere(p, u_r0);
  real3 f;
  if (!volume_coords(g.x / CV_KDEG, g.y / CV_KDEG, u_grid_start.z, u_grid_start, u_grid_step, u_grid_count, u_wraps, u_global_lat, f)) return real(0.0);
  real tau = column_texel_of(f, 0).x;
  real tau_ice = min(max(column_texel_of(f, 1).x, real(0.0)), max(tau, real(0.0)));
  return (real(1.0) - g_liquid) * max(tau - tau_ice, real(0.0)) + (real(1.0) - g_ice) * tau_ice;
}

CV_FN real node_sum(int x, int y, int z) { return node(u_liquid, x, y, z) + node(u_ice, x, y, z); }

// The largest extinction (1/m, liquid + ice) that trilinear sampling can return in the grid cell
// around p (altitude alt_m): the largest of the 8 nodes fetch reads there; 0 outside the grid.
CV_FN real cell_max(real3 p, real alt_m) {
  real3 g = ecef_to_sphere(p, u_r0);
  real3 f;
  if (!volume_coords(g.x / CV_KDEG, g.y / CV_KDEG, alt_m, u_grid_start, u_grid_step, u_grid_count, u_wraps, u_global_lat, f)) return real(0.0);
  ivec3 n = ivec3(u_grid_count);
  real w;
  int x0 = volume_fetch_index(f.x, n.x, w);
  int y0 = volume_fetch_index(f.y, n.y, w);
  int z0 = volume_fetch_index(f.z, n.z, w);
  int x1 = u_wraps ? (x0 + 1) % n.x : x0 + 1;
  int y1 = y0 + 1;
  int z1 = min(z0 + 1, n.z - 1);
  // Written out, not looped (llvmpipe's loop budget).
  real m = max(max(node_sum(x0, y0, z0), node_sum(x1, y0, z0)), max(node_sum(x0, y1, z0), node_sum(x1, y1, z0)));
  m = max(m, max(max(node_sum(x0, y0, z1), node_sum(x1, y0, z1)), max(node_sum(x0, y1, z1), node_sum(x1, y1, z1))));
  return m;
}

// The ground's altitude (m) under grid index f (the column map's y).
CV_FN real column_ground(real3 f) { return column_map(f).y; }

// The layer mask (march_settings.def, layer_bottom_m): whether the point at grid index f and
// altitude alt_m is in the band shown. Every point falls in exactly one of adjacent bands
// [a, b), [b, c): their images' media add up to the whole.
CV_FN bool layer_shown(real3 f, real alt_m) {
  // A compile-time switch (kLayerMask, set with u_mask_band): llvmpipe would run column_ground's
  // fetches at every sample under a uniform branch.
  if (!kLayerMask || !u_mask_band) return true;
  real h = u_mask_sea_level ? alt_m : alt_m - column_ground(f);
  return h >= u_mask_bottom && h < u_mask_top;
}

// The medium (liquid and ice extinction, 1/m) at Earth-centred point p, whose latitude and longitude
// g (radians, ecef_to_sphere) and altitude alt_m are given. Eroded by the noise where it is on.
CV_FN void medium_in(real3 p, real3 g, real alt_m, CV_OUT(real) sl, CV_OUT(real) si) {
  sl = real(0.0);
  si = real(0.0);
  real3 f;
  if (!volume_coords(g.x / CV_KDEG, g.y / CV_KDEG, alt_m, u_grid_start, u_grid_step, u_grid_count, u_wraps, u_global_lat, f)) return;
  if (!layer_shown(f, alt_m)) return;
  // Hidden phases as factors, not branches: the GLSL compiler puts a fetch under `hide ? 0 :
  // fetch` in a branch of its own, which llvmpipe runs under a mask at every view and sun sample.
  if (kModelled) {  // the cells' shapes too, from the same texels (detail_factor_of's correction)
    real4 cl = fetch_cell(u_liquid, f) * (u_hide_liquid ? real(0.0) : real(1.0));
    real4 ci = fetch_cell(u_ice, f) * (u_hide_ice ? real(0.0) : real(1.0));
    sl = cl.x;
    si = ci.x;
    if (sl + si > real(0.0)) {
      real k = detail_factor_of(f, cl + ci);
      sl *= k;
      si *= k;
    }
  } else {
    sl = fetch(u_liquid, f) * (u_hide_liquid ? real(0.0) : real(1.0));
    si = fetch(u_ice, f) * (u_hide_ice ? real(0.0) : real(1.0));
  }
  if (kNoise && sl + si > real(0.0)) erode_at(p, sl, si);
}

// The light between the columns (u_ms_lateral; else 0): the source's first moment's east and north
// parts h (the second texture's first two channels) as a vector at p (the local frame from p; at
// the axis, longitude 0's).
CV_FN real3 ms_horizontal_vector(real3 p, real2 h) {
  if (!u_ms_lateral) return real3(0.0);
  real3 up = normalize(p);
  real rho = length(real2(p.x, p.y));
  real3 east = rho > real(0.0) ? real3(-p.y / rho, p.x / rho, real(0.0)) : real3(0.0, 1.0, 0.0);
  real3 north = cross(up, east);
  return h.x * east + h.y * north;
}

// The two-stream source's moments (per unit irradiance) at p, altitude alt_m (core/kernel/ms_source).
CV_FN void ms_source_at(real3 p, real alt_m, CV_OUT(real) i0, CV_OUT(real3) i1) {
  i0 = real(0.0);
  i1 = real3(0.0);
  real3 g = ecef_to_sphere(p, u_r0);
  real3 f;
  if (!volume_coords(g.x / CV_KDEG, g.y / CV_KDEG, alt_m, u_grid_start, u_grid_step, u_grid_count, u_wraps, u_global_lat, f)) return;
  real2 m = fetch2(u_ms_moments, f);
  i0 = m.x;
  i1 = m.y * normalize(p) + (u_ms_lateral ? ms_horizontal_vector(p, fetch2(u_ms_horizontal, f)) : real3(0.0));
}

// The higher-order source at p (kSlab; core/kernel/ms_source): the nodes hold (I0, extinction,
// depth above, ground albedo) and (I1 east, I1 north, depth below, d0 = I0 - I0_slab against the
// slab of the node's depths). Between two levels the extinction is linear, so the depth above t
// grows quadratically from the upper node down and the depth below from the lower node up (a
// linear blend of the nodes' depths put the samples in a cloud's top layer as deep as its middle).
// Returns (I0, t, b, A) and, in d0 and share, how the sample is measured against its slab
// (ms_slab_keep): where the medium's column at p (the column map) holds the nodes' slab, t + b,
// the nodes' difference d0 (interpolated: a slab's light between two nodes follows the slab, which
// the nodes' light, linear between them, does not: thick slabs up to 5.5 % bright); where it holds
// less (share = column / (t + b) < 1: the fringe the interpolation spreads around a cloud, a cell
// wide, whose nodes carry the cloud's depths), the slab of the column's own depth, b = column - t,
// and the source's own light there. The light between the columns in i1h (ms_horizontal_vector).
CV_FN real4 ms_slab_source_at(real3 p, real alt_m, CV_OUT(real3) i1h, CV_OUT(real) d0, CV_OUT(real) share) {
  i1h = real3(0.0);
  d0 = real(0.0);
  share = real(1.0);
  real3 g = ecef_to_sphere(p, u_r0);
  real3 f;
  if (!volume_coords(g.x / CV_KDEG, g.y / CV_KDEG, alt_m, u_grid_start, u_grid_step, u_grid_count, u_wraps, u_global_lat, f)) return real4(0.0);
  ivec3 a;
  ivec3 b;
  real3 w;
  cell_at(f, a, b, w);
  real4 lo = level4(u_ms_moments, a, b, w, a.z);
  real4 hi = level4(u_ms_moments, a, b, w, b.z);
  real4 lo2 = level4(u_ms_horizontal, a, b, w, a.z);
  real4 hi2 = level4(u_ms_horizontal, a, b, w, b.z);
  real dz = abs(u_grid_step.z);
  real xi = real(1.0) - w.z;  // from the upper node down, in level spacings
  real t = hi.z + dz * xi * (hi.y + real(0.5) * (lo.y - hi.y) * xi);
  t = clamp(t, hi.z, max(lo.z, hi.z));
  real bn = lo2.z + dz * w.z * (lo.y + real(0.5) * (hi.y - lo.y) * w.z);
  bn = clamp(bn, lo2.z, max(lo2.z, hi2.z));
  real column = column_map(real3(f.x, f.y, real(0.0))).x;
  real bc = max(max(column, lo.z) - t, real(0.0));
  share = clamp(column / max(t + bn, real(1e-6)), real(0.0), real(1.0));
  d0 = mix(lo2.w, hi2.w, w.z);
  i1h = ms_horizontal_vector(p, real2(mix(lo2.x, hi2.x, w.z), mix(lo2.y, hi2.y, w.z)));
  return real4(mix(lo.x, hi.x, w.z), t, mix(bc, bn, share), mix(lo.w, hi.w, w.z));
}

// The diffuse light that the higher-order source scatters toward a direction of travel at cosine mu
// to the downward vertical and azimuth cos_phi from the sun's beam's, per unit irradiance, slab
// factor and scaled scattering coefficient: sum_lm C_lm Lambda_l^m(mu) cos(m phi), C from the slab table
// of phase `phase` (0 liquid, 1 ice) trilinear in the depths above and below (t, b) and the sun's
// cosine mu0 (docs/physics.md, "The higher-order source").
CV_FN real ms_slab_table_at(int i) { return real(u_ms_slab_table[i]); }
#ifdef __cplusplus
CV_FN real4 ms_slab_table4_at(int i) {
  return real4(real(u_ms_slab_table[i]), real(u_ms_slab_table[i + 1]), real(u_ms_slab_table[i + 2]), real(u_ms_slab_table[i + 3]));
}
#else
CV_FN real4 ms_slab_table4_at(int i) { return real4(u_ms_slab_table4[i >> 2]); }
#endif
#if CV_MS_SLAB_MOMENTS != 44
#error "ms_slab_in_scatter writes out 44 products"
#endif
#if CV_MS_SLAB_STRIDE % 4 != 0 || CV_MS_SLAB_BELOW_STRIDE % 4 != 0
#error "the slab table's cells are read four numbers at a time"
#endif
#define CV_MS_SLAB_DOT4(B, Y, I) dot(ms_slab_table4_at(B + I), real4(Y[I], Y[I + 1], Y[I + 2], Y[I + 3]))
// The table cell of depths t above and b below under a sun at mu0 (its lower corner) and the
// weights toward the next, in u = t / (t + T0), v and mu0.
CV_FN void ms_slab_cell(real t, real b, real mu0, CV_OUT(ivec3) c0, CV_OUT(real3) w) {
  real fu = clamp(t / (t + real(CV_MS_SLAB_T0)), real(0.0), real(1.0)) * real(CV_MS_SLAB_DEPTHS - 1);
  real fv = clamp(b / (b + real(CV_MS_SLAB_T0)), real(0.0), real(1.0)) * real(CV_MS_SLAB_DEPTHS - 1);
  real fs = clamp((mu0 - real(CV_MS_SLAB_MU0_LO)) / (real(1.0) - real(CV_MS_SLAB_MU0_LO)), real(0.0), real(1.0)) * real(CV_MS_SLAB_SUNS - 1);
  c0 = ivec3(clamp(int(fu), 0, CV_MS_SLAB_DEPTHS - 2), clamp(int(fv), 0, CV_MS_SLAB_DEPTHS - 2), clamp(int(fs), 0, CV_MS_SLAB_SUNS - 2));
  w = real3(fu - real(c0.x), fv - real(c0.y), fs - real(c0.z));
}
// One entry k of the slab table of `phase`, trilinear as ms_slab_in_scatter reads it.
CV_FN real ms_slab_entry(int phase, real t, real b, real mu0, int k) {
  ivec3 cell;
  real3 wc;
  ms_slab_cell(t, b, mu0, cell, wc);
  // The eight corners written out (no loop: llvmpipe counts loop iterations, see below).
  int c = phase * CV_MS_SLAB_PHASE_SIZE + ((cell.z * CV_MS_SLAB_DEPTHS + cell.y) * CV_MS_SLAB_DEPTHS + cell.x) * CV_MS_SLAB_STRIDE + k;
  int du = CV_MS_SLAB_STRIDE;
  int dv = CV_MS_SLAB_DEPTHS * CV_MS_SLAB_STRIDE;
  int ds = CV_MS_SLAB_DEPTHS * CV_MS_SLAB_DEPTHS * CV_MS_SLAB_STRIDE;
  real lo = mix(mix(ms_slab_table_at(c), ms_slab_table_at(c + du), wc.x), mix(ms_slab_table_at(c + dv), ms_slab_table_at(c + dv + du), wc.x), wc.y);
  real hi = mix(mix(ms_slab_table_at(c + ds), ms_slab_table_at(c + ds + du), wc.x), mix(ms_slab_table_at(c + ds + dv), ms_slab_table_at(c + ds + dv + du), wc.x), wc.y);
  return mix(lo, hi, wc.z);
}
// The slab lit from below (a ground's light; the table's second part): its cell, and entry k,
// bilinear in the depths.
CV_FN void ms_slab_below_cell(real t, real b, CV_OUT(int) u0, CV_OUT(int) v0, CV_OUT(real) wu, CV_OUT(real) wv) {
  ivec3 cell;
  real3 wc;
  ms_slab_cell(t, b, real(1.0), cell, wc);
  u0 = cell.x;
  v0 = cell.y;
  wu = wc.x;
  wv = wc.y;
}
CV_FN int ms_slab_below_base(int phase, int v, int u) {
  return CV_MS_SLAB_BELOW_OFFSET + phase * CV_MS_SLAB_BELOW_SIZE + (v * CV_MS_SLAB_DEPTHS + u) * CV_MS_SLAB_BELOW_STRIDE;
}
CV_FN real ms_slab_below_entry(int phase, real t, real b, int k) {
  int u0;
  int v0;
  real wu;
  real wv;
  ms_slab_below_cell(t, b, u0, v0, wu, wv);
  return mix(mix(ms_slab_table_at(ms_slab_below_base(phase, v0, u0) + k), ms_slab_table_at(ms_slab_below_base(phase, v0, u0 + 1) + k), wu),
             mix(ms_slab_table_at(ms_slab_below_base(phase, v0 + 1, u0) + k), ms_slab_table_at(ms_slab_below_base(phase, v0 + 1, u0 + 1) + k), wu), wv);
}
// The radiance of the ground of albedo A under the slab of total optical depth T (its phase's share
// f truncated) as the tables have it: the flux that reaches it, the scaled beam and the diffuse
// light, with what the slab sends back down of the ground's own light (s = its downward flux at the
// bottom per unit ground radiance, over pi): A E / (pi (1 - A s)).
CV_FN real ms_slab_ground_radiance(int phase, real T, real mu0, real f, real A) {
  if (!(A > real(0.0))) return real(0.0);
  real e = ms_slab_entry(phase, T, real(0.0), mu0, CV_MS_SLAB_FLUX_DOWN) + mu0 * transmittance((real(1.0) - f) * T / mu0);
  real s = ms_slab_below_entry(phase, T, real(0.0), CV_MS_SLAB_BELOW_FLUX_DOWN) / CV_PI;
  return A * e / (CV_PI * max(real(1.0) - A * s, real(1e-6)));
}

// How much of its slab's light a point keeps: src = (I0, t, b, A), d0 and share as
// ms_slab_source_at gives them. Its light against the slab's two-stream I0 at its depths over its
// ground, d = share d0 + (1 - share) (I0 - I0_slab); the ground's radiance in ground_l, what it
// holds beyond the slab in extra (max(d, 0), isotropic), and keep = 1 + d / I0_dom where it holds
// less: I0_dom the slab's own mean radiance (its discrete-ordinates light, the table's first
// moment). (The two-stream's I0 is the g^2-truncated problem's; the slab's table holds the lighter
// truncation's diffuse light, which includes what the 3-D beam carries between the two: measured
// against the two-stream's I0, a node losing light lost that part too, and a small cumulus's
// shaded parts went dark.)
CV_FN real ms_slab_keep(int phase, real4 src, real d0, real share, real mu0, real f, CV_OUT(real) ground_l, CV_OUT(real) extra) {
  ground_l = ms_slab_ground_radiance(phase, src.y + src.z, mu0, f, src.w);
  real i0_slab = ms_slab_entry(phase, src.y, src.z, mu0, CV_MS_SLAB_TWO_STREAM_I0) +
                 ground_l * ms_slab_below_entry(phase, src.y, src.z, CV_MS_SLAB_BELOW_TWO_STREAM_I0);
  real d = mix(src.x - i0_slab, d0, share);
  extra = max(d, real(0.0));
  if (!(d < real(0.0))) return real(1.0);
  real i0_dom = ms_slab_entry(phase, src.y, src.z, mu0, 0) + ground_l * ms_slab_below_entry(phase, src.y, src.z, 0);
  return clamp(real(1.0) + d / max(i0_dom, real(1e-30)), real(0.0), real(1.0));
}

#if CV_MS_SLAB_BELOW_L != CV_MS_SLAB_L0
#error "the light from below takes the azimuthal mean's harmonics of ms_slab_in_scatter"
#endif
CV_FN real ms_slab_in_scatter(int phase, real t, real b, real mu0, real mu, real cos_phi, real ground_l) {
  // Lambda_l^m(mu) cos(m phi) in the table's order (m = 0 to degree L0, then m >= 1 to degree L).
  real y[CV_MS_SLAB_MOMENTS];
  real s = sqrt(max(real(1.0) - mu * mu, real(0.0)));
  real lmm = real(1.0);   // Lambda_m^m
  real cm = real(1.0);    // cos(m phi)
  real cprev = cos_phi;   // cos((m - 1) phi)
  int k = 0;
  for (int m = 0; m <= CV_MS_SLAB_L; ++m) {
    if (m > 0) {
      lmm *= sqrt(real(2 * m - 1) / real(2 * m)) * s;
      real cn = real(2.0) * cos_phi * cm - cprev;
      cprev = cm;
      cm = cn;
    }
    int top = m == 0 ? CV_MS_SLAB_L0 : CV_MS_SLAB_L;
    real a = lmm;
    real bb = sqrt(real(2 * m + 1)) * mu * lmm;
    y[k++] = a * cm;
    if (m < top) y[k++] = bb * cm;
    for (int l = m + 2; l <= top; ++l) {
      real c = (real(2 * l - 1) * mu * bb - sqrt(real((l - 1) * (l - 1) - m * m)) * a) / sqrt(real(l * l - m * m));
      y[k++] = c * cm;
      a = bb;
      bb = c;
    }
  }
  ivec3 cell;
  real3 wc;
  ms_slab_cell(t, b, mu0, cell, wc);
  real sum = real(0.0);
  for (int corner = 0; corner < 8; ++corner) {
    int du = corner & 1;
    int dv = (corner >> 1) & 1;
    int ds = corner >> 2;
    real w = (du == 1 ? wc.x : real(1.0) - wc.x) * (dv == 1 ? wc.y : real(1.0) - wc.y) * (ds == 1 ? wc.z : real(1.0) - wc.z);
    int b = phase * CV_MS_SLAB_PHASE_SIZE + (((cell.z + ds) * CV_MS_SLAB_DEPTHS + cell.y + dv) * CV_MS_SLAB_DEPTHS + cell.x + du) * CV_MS_SLAB_STRIDE;
    // The 44 products written out, four at a time: llvmpipe counts every loop iteration against
    // its budget (loop_iterations_per_view_step), and an inner loop here cost 352 a sample.
    real dotp = CV_MS_SLAB_DOT4(b, y, 0) + CV_MS_SLAB_DOT4(b, y, 4) + CV_MS_SLAB_DOT4(b, y, 8) + CV_MS_SLAB_DOT4(b, y, 12) +
                CV_MS_SLAB_DOT4(b, y, 16) + CV_MS_SLAB_DOT4(b, y, 20) + CV_MS_SLAB_DOT4(b, y, 24) + CV_MS_SLAB_DOT4(b, y, 28) +
                CV_MS_SLAB_DOT4(b, y, 32) + CV_MS_SLAB_DOT4(b, y, 36) + CV_MS_SLAB_DOT4(b, y, 40);
    sum += w * dotp;
  }
  // The light from the ground (the table's part lit from below), per unit of its radiance: the
  // azimuthal mean's harmonics are y's first CV_MS_SLAB_L0 + 1 (cos 0 = 1), bilinear in the depths.
  if (ground_l > real(0.0)) {
    int gu0;
    int gv0;
    real gwu;
    real gwv;
    ms_slab_below_cell(t, b, gu0, gv0, gwu, gwv);
    int b00 = ms_slab_below_base(phase, gv0, gu0);
    int b01 = ms_slab_below_base(phase, gv0, gu0 + 1);
    int b10 = ms_slab_below_base(phase, gv0 + 1, gu0);
    int b11 = ms_slab_below_base(phase, gv0 + 1, gu0 + 1);
    real l00 = CV_MS_SLAB_DOT4(b00, y, 0) + CV_MS_SLAB_DOT4(b00, y, 4) + CV_MS_SLAB_DOT4(b00, y, 8) + CV_MS_SLAB_DOT4(b00, y, 12);
    real l01 = CV_MS_SLAB_DOT4(b01, y, 0) + CV_MS_SLAB_DOT4(b01, y, 4) + CV_MS_SLAB_DOT4(b01, y, 8) + CV_MS_SLAB_DOT4(b01, y, 12);
    real l10 = CV_MS_SLAB_DOT4(b10, y, 0) + CV_MS_SLAB_DOT4(b10, y, 4) + CV_MS_SLAB_DOT4(b10, y, 8) + CV_MS_SLAB_DOT4(b10, y, 12);
    real l11 = CV_MS_SLAB_DOT4(b11, y, 0) + CV_MS_SLAB_DOT4(b11, y, 4) + CV_MS_SLAB_DOT4(b11, y, 8) + CV_MS_SLAB_DOT4(b11, y, 12);
    sum += ground_l * mix(mix(l00, l01, gwu), mix(l10, l11, gwu), gwv);
  }
  return sum;
}

// The medium at p whose altitude alt_m a marcher knows better than |p| - r0 (ray_altitude).
CV_FN void medium_at(real3 p, real alt_m, CV_OUT(real) sl, CV_OUT(real) si) { medium_in(p, ecef_to_sphere(p, u_r0), alt_m, sl, si); }

// The medium at p, its altitude from p (the Monte Carlo's free-flying points).
CV_FN void medium_at_point(real3 p, CV_OUT(real) sl, CV_OUT(real) si) {
  real3 g = ecef_to_sphere(p, u_r0);
  medium_in(p, g, g.z, sl, si);
}

// One level of the pyramid at grid index g (see space_at): true when its brick there is empty, with
// the distance the ray may jump; else the brick's largest extinction, and the distance it holds.
CV_FN bool level_empty(int l, real3 g, real lat, real r, real mu_up, CV_OUT(real) extent_m, CV_OUT(real) brick_max) {
  real3 nb = real3(u_bricks[l]);
  real nodes = real(u_level_nodes[l]);
  real3 b = march_brick(g, nodes);
  extent_m = march_brick_exit_m(lat, r, mu_up, g, b, nodes, nb, u_grid_start, u_grid_step, u_global_lat, u_r0);
  brick_max = real(0.0);
  if (march_brick_inside(b, nb)) {
    ivec3 bi = ivec3(b);
    brick_max = real(u_min_max[u_level_offset[l] + (bi.z * u_bricks[l].y + bi.y) * u_bricks[l].x + bi.x].y);
  }
  return !(brick_max > real(0.0));
}

// What a ray along dir learns about the space around p, at altitude alt_m: true when empty, with
// the distance (m) it may jump; else the finest brick's largest extinction (1/m) and the distance
// over which that holds. The levels are visited without a loop (llvmpipe's loop budget: this runs
// inside both marches).
CV_FN bool space_at(real3 p, real alt_m, real3 dir, CV_OUT(real) extent_m, CV_OUT(real) sigma_max) {
  extent_m = real(0.0);
  sigma_max = real(0.0);
  if (u_levels <= 0) return false;
  real3 g3 = ecef_to_sphere(p, u_r0);
  real lat = g3.x / CV_KDEG;
  real r = u_r0 + alt_m;
  real mu_up = dot(dir, p) / length(p);
  real3 g = march_grid_index(lat, g3.y / CV_KDEG, alt_m, u_grid_start, u_grid_step, u_grid_count, u_wraps, u_global_lat);
  real unused;
  if (u_levels > 3 && level_empty(3, g, lat, r, mu_up, extent_m, unused)) return true;
  if (u_levels > 2 && level_empty(2, g, lat, r, mu_up, extent_m, unused)) return true;
  if (u_levels > 1 && level_empty(1, g, lat, r, mu_up, extent_m, unused)) return true;
  return level_empty(0, g, lat, r, mu_up, extent_m, sigma_max);
}

// Optical depth of the clouds from p (at altitude alt_p, m) toward the sun, whose cosine and sine
// with the local up at p are mu_sun and nu_sun: sun_march_steps per shell segment (more where the
// segment is long, a low sun; fewer where the volume is thin), empty bricks jumped, stopped past
// u_sun_tau_limit. The shell's (at most two) segments and their steps run as one loop. The cloud
// samples and the ground's shadow both use it. The liquid's and the ice's extinction count with the
// weights w_liquid and w_ice (1 and 1: the optical depth; 1 - g^2 each: the delta-scaled one).
CV_FN real cloud_sun_depth_weighted(real3 p, real alt_p, real mu_sun, real nu_sun, real w_liquid, real w_ice) {
  real hb = u_layer.x;
  real ht = u_layer.y;
  real tau_sun = real(0.0);
  real4 sseg;
  int sn = u_cloudless ? 0 : ray_shell_rel_nu(u_r0, alt_p, mu_sun, nu_sun, hb, ht, sseg);
  int n0 = sn > 0 ? sun_march_steps(u_sigma_max, sseg.y - sseg.x, u_sun_step_tau, u_sun_steps, u_sun_step_max) : 0;
  int n1 = sn > 1 ? sun_march_steps(u_sigma_max, sseg.w - sseg.z, u_sun_step_tau, u_sun_steps, u_sun_step_max) : 0;
  int total = n0 + n1;
  real known_end = real(-1.0);  // what the pyramid said holds below this distance into the segment
  for (int k = 0; k < total;) {
    int q = k < n0 ? 0 : 1;
    int nq = q == 0 ? n0 : n1;
    int j = q == 0 ? k : k - n0;
    if (j == 0) known_end = real(-1.0);
    real s0 = q == 0 ? sseg.x : sseg.z;
    real s1 = q == 0 ? sseg.y : sseg.w;
    real ds = (s1 - s0) / real(nq);
    real t_rel = (real(j) + real(0.5)) * ds;
    real3 ps = p + (s0 + t_rel) * u_to_sun;
    real alt_s = ray_altitude(u_r0, alt_p, mu_sun, s0 + t_rel);
    if (kSkipEmpty && !(t_rel < known_end)) {
      real extent;
      real smax;
      if (space_at(ps, alt_s, u_to_sun, extent, smax)) {
        int next = min(march_resume_index(j, extent, ds), nq);
        g_stats[CV_STAT_SUN_SKIPPED] += uint(next - j);
        g_stats[CV_STAT_BRICKS_JUMPED] += next - j > 1 ? 1u : 0u;
        k += next - j;
        continue;
      }
      known_end = t_rel + extent;
    }
    real a;
    real b;
    medium_at(ps, alt_s, a, b);
    tau_sun += (w_liquid * a + w_ice * b) * ds;
    g_stats[CV_STAT_SUN_SAMPLES] += 1u;
    ++k;
    if (tau_sun > u_sun_tau_limit) {
      g_stats[CV_STAT_SUN_SKIPPED] += uint(total - k);
      break;
    }
  }
  return tau_sun;
}

CV_FN real cloud_sun_depth(real3 p, real alt_p, real mu_sun, real nu_sun) {
  return cloud_sun_depth_weighted(p, alt_p, mu_sun, nu_sun, real(1.0), real(1.0));
}

// A view march's progress: the radiance gathered and the view transmittance so far, where the
// light was taken out of the view (depth_w, depth_t: the cloud's mean depth for the air around
// it), whether it has ended, and the next view step (counted over both shell segments).
struct MarchState {
  real3 radiance;
  real t_view;
  // kTwoStream: the view transmittance through the delta-scaled extinction (1 - g^2) sigma, along
  // which the scattered light travels to the camera (march_sample); the march goes on while either
  // transmittance is above u_min_t.
  real t_ms;
  real depth_w;
  real depth_t;
  bool ended;
  int next_step;
  real t_half;  // distance from the camera where the view transmittance fell to 0.5 (3e38: never)
  // The step where it fell, until march_advance ends (march_half_settle): its view transmittance
  // before, its extinction (0: none pending) and its length. The logarithm is taken once per ray,
  // not under a mask at every sample.
  real half_before;
  real half_sigma;
  real half_ds;
  int tl_next;  // the next translucent fragment to composite (kTranslucent)
  // Where the first step holding cloud began, from the camera (3e38: none). Read by the CPU's
  // probes (core/analysis); the GPU driver keeps no copy of it between its dispatches.
  real t_first;
};

// One view sample at p (altitude alt_p, distance t along the ray) standing for a step of ds that
// begins t_entry from the camera: in-scattered light (sun through the air, ambient sky light),
// attenuation, and where the view transmittance falls to 0.5 (exactly, for the step's constant
// extinction).
// The false colour of a sample (kTint): the hue of its tints weighted by its liquid and ice
// extinction, scaled to luminance 1 (Rec. 709), so the light keeps its luminance and takes the hue.
CV_FN real3 tint_hue(real sl, real si, real sigma) {
  real3 mixed = (sl * u_tint_liquid + si * u_tint_ice) / sigma;
  real lum = dot(mixed, real3(0.2126, 0.7152, 0.0722));
  return lum > real(0.0) ? mixed / lum : real3(0.0);
}

// The phase with which the delta-scaled beam exp(-(1 - f) tau_sun) scatters toward the camera. Its
// light has met a Poisson number k of forward-peak scatterings (mean lambda = f tau_sun: the beam
// without them is exp(-tau_sun)), each of which spreads it about the sun's direction. For a
// Henyey-Greenstein phase (ice, and liquid_phase_hg) the spread is taken as a Henyey-Greenstein
// kernel of the peak's mean cosine g_pk (ms_peak); kernels compose by multiplying their mean
// cosines: HG(g) spread by k of them is HG(g g_pk^k). CV_MS_PEAK_TERMS terms, the rest of the weight
// at k = max(terms, lambda). (The true kernel, max(p - c, 0) / f, ends at the cut's cone; with it
// thin HG slabs were 1-5 points darker still, docs/physics.md.) The droplets' Mie phase is spread by
// the true kernel: ms_beam_phase_mie.
#define CV_MS_PEAK_TERMS 8
CV_FN real ms_beam_phase_hg(real mu, real p0, real g, real g_pk, real lambda) {
  real l = clamp(lambda, real(0.0), real(1.0e4));
  real w = exp(-l);
  real sum = real(0.0);  // sum over k >= 1 of w_k HG(g g_pk^k)
  real mass = w;
  real gk = g;
  for (int k = 1; k < CV_MS_PEAK_TERMS; ++k) {
    w *= l / real(k);
    gk *= g_pk;
    sum += w * phase_hg(mu, gk);
    mass += w;
  }
  real tail = max(real(1.0) - mass, real(0.0));
  sum += tail * phase_hg(mu, g * pow(max(g_pk, real(0.0)), max(real(CV_MS_PEAK_TERMS), l)));
  return max(p0 + sum - (real(1.0) - exp(-l)) * phase_hg(mu, g), real(0.0));
}

// The droplets' beam phase (docs/physics.md, "The droplets' beam spread by the true peak kernel"):
// the light of the delta-scaled beam has met a Poisson number k of forward-peak scatterings (mean
// lambda), each of which turns it by the peak kernel K = max(p - c, 0) / f, so it scatters with the
// mixture over k of the Mie fit p convolved k times with K (core/kernel/ms_source ms_beam_table). The
// fit's narrow HG lobe (weight spike_w = 1 - w_d) has its own chain, spike_w sum_k e^-lambda
// (lambda a)^k / k! HG(g^(k+1)) (a = spike_w / f, u_ms_beam_a_liquid), summed here in closed form
// (no table could hold it); the rest is read from the table, bilinear in s = lambda / (lambda +
// lambda0) and the scattering angle. For droplets below about 2 um (a = 0) the table holds it all.
CV_FN real ms_beam_table_at(int row, int col) { return real(u_ms_beam_table[row * CV_MS_BEAM_ANGLES + col]); }
CV_FN real ms_beam_phase_mie(real mu, MieParams mie, real lambda) {
  // The table's indices stay in range whatever comes in (a NaN reads as lambda 0, mu -1).
  real l = lambda > real(0.0) ? min(lambda, real(1.0e4)) : real(0.0);
  real m = mu > real(-1.0) ? min(mu, real(1.0)) : real(-1.0);
  real s = l / (l + real(CV_MS_BEAM_LAMBDA0)) * real(CV_MS_BEAM_ROWS - 1);
  real th = acos(m) * (real(CV_MS_BEAM_ANGLES - 1) / CV_PI);
  int r0 = clamp(int(s), 0, CV_MS_BEAM_ROWS - 2);
  int c0 = clamp(int(th), 0, CV_MS_BEAM_ANGLES - 2);
  real fr = s - real(r0);
  real fc = th - real(c0);
  real p = mix(mix(ms_beam_table_at(r0, c0), ms_beam_table_at(r0, c0 + 1), fc),
               mix(ms_beam_table_at(r0 + 1, c0), ms_beam_table_at(r0 + 1, c0 + 1), fc), fr);
  real a = u_ms_beam_a_liquid;  // 0: the table holds the whole phase (small droplets, ms_peaks)
  real spike_w = a > real(0.0) ? real(1.0) - mie.w_d : real(0.0);
  real spike_c = mie.c_hg;
  real la = l * a;
  real w = exp(-l);
  real ck = spike_c;  // 1 - g^(k+1), without cancellation
  real sum = real(0.0);
  real mass = real(0.0);
  real moment = real(0.0);  // sum of w_k (1 - g^(k+1))
  for (int k = 0; k < CV_MS_BEAM_SPIKE_TERMS; ++k) {
    sum += w * phase_hg_c(m, real(1.0) - ck, ck);
    mass += w;
    moment += w * ck;
    w *= la / real(k + 1);
    ck = ck + spike_c - ck * spike_c;
  }
  // The terms beyond as one lobe with their mean cosine: over all k, sum w_k = e^-lambda(1 - a) and
  // sum w_k (1 - g^(k+1)) = e^-lambda(1 - a) (1 - g e^-x), x = lambda a (1 - g), written
  // x E(x) + (1 - g) e^-x without cancellation.
  real whole = exp(-l * (real(1.0) - a));
  real x = la * spike_c;
  real tail = max(whole - mass, real(0.0));
  real ct = tail > real(0.0) ? clamp((whole * (x * segment_factor(x) + spike_c * exp(-x)) - moment) / tail, ck, real(1.0)) : ck;
  p += spike_w * (sum + tail * phase_hg_c(m, real(1.0) - ct, ct));
  return max(p, real(0.0));
}

CV_FN void march_sample(real3 p, real alt_p, real t, real ds, real t_entry, real3 d, real mu, MieParams mie, CV_INOUT(MarchState) s) {
  real sl;
  real si;
  medium_at(p, alt_p, sl, si);
  g_stats[CV_STAT_VIEW_SAMPLES] += 1u;
  real sigma = sl + si;
  if (sigma <= real(0.0)) return;
  s.t_first = min(s.t_first, t_entry);
  real3 up_p = normalize(p);
  real mu_sun = dot(u_to_sun, up_p);
  real nu_sun = length(cross(u_to_sun, up_p));
  real e0;
  real e1;
  bool lit = !u_sun_down && !(ray_sphere_rel_nu(u_r0, alt_p, mu_sun, nu_sun, real(0.0), e0, e1) && e1 > real(0.0));
  real tau_sun = lit ? cloud_sun_depth(p, alt_p, mu_sun, nu_sun) : real(0.0);
  // Sunlight reaches the sample through the air (reddened when low), and the sky lights it too:
  // isotropic irradiance E_sky scattered as sigma_s E_sky / (2 pi) (docs/physics.md).
  real3 sun_air = kAtmosphere && lit ? atmo_transmittance(u_r0, alt_p, mu_sun, nu_sun, u_atmo_sun_steps) : real3(1.0);
  real3 ambient = kAtmosphere ? u_ambient * sky_irradiance(sun_air, mu_sun) * (sigma / CV_TWO_PI) : real3(0.0);
  // The octave sums of both phases (clouds do not absorb), only where the sun shines (llvmpipe runs
  // masked code: a ternary would not save them).
  real scatter = real(0.0);
  real3 scaled_source = real3(0.0);  // kTwoStream: the light that reaches the camera through t_ms
  real sigma_ms = sigma;
  if (kTwoStream) {
    // The two-stream model (docs/physics.md). Delta-Eddington takes the share f = g^2 of each
    // scattering as no scattering at all (the forward peak): the sun's beam is exp(-(1 - f) tau_sun)
    // and light on its way to the camera meets the scaled extinction sigma' = (1 - g^2) sigma. Along
    // that path travel the sun's beam scattered toward the camera (its peak-scattered light spread,
    // ms_beam_phase) with the phase below the peak's cut (u_ms_peak_*), and the column's diffuse
    // light I0 + I1 mu scattered by the truncated phase
    // (mean cosine g' = g / (1 + g)): sigma' I0 + sigma' g' I1 mu_out, sigma' g' = g (1 - g) sigma,
    // mu_out the cosine of the outgoing direction -d to the vertical. The peak above the cut, where
    // the phase changes faster than the scaling's pass-through can follow (toward the sun), takes
    // the true extinction.
    real g_liquid = mie_mean_cosine(mie);
    real g_ice = u_ice_g;
    real g_mix = (sl * g_liquid + si * g_ice) / sigma;
    // The share taken as no scattering: g^2, or the higher-order source's (u_ms_slab; ms_slab_share).
    real f_liquid = kSlab ? u_ms_f_liquid : g_liquid * g_liquid;
    real f_ice = kSlab ? u_ms_f_ice : g_ice * g_ice;
    real f_mix = kSlab ? (sl * f_liquid + si * f_ice) / sigma : g_mix * g_mix;
    if (lit) {
      real lambda = f_mix * tau_sun;  // forward-peak scatterings the beam has met, on average
      real p_liquid = real(0.0);
      real p_ice = real(0.0);
      if (sl > real(0.0)) p_liquid = u_liquid_phase_hg ? ms_beam_phase_hg(mu, phase_hg(mu, g_liquid), g_liquid, u_ms_peak_g_liquid, lambda)
                                                       : ms_beam_phase_mie(mu, mie, lambda);
      if (si > real(0.0)) p_ice = ms_beam_phase_hg(mu, phase_hg(mu, g_ice), g_ice, u_ms_peak_g_ice, lambda);
      real c_liquid = min(p_liquid, u_ms_peak_liquid);
      real c_ice = min(p_ice, u_ms_peak_ice);
      real beam = transmittance((real(1.0) - f_mix) * tau_sun);
      scatter = (sl * (p_liquid - c_liquid) + si * (p_ice - c_ice)) * beam;
      scaled_source = sun_air * ((sl * c_liquid + si * c_ice) * beam);
    }
    sigma_ms = sl * (real(1.0) - f_liquid) + si * (real(1.0) - f_ice);
    if (kSlab) {
      // The higher-order source: the slab tables' light toward the camera (the light travels along
      // -d; mu to the downward vertical, phi from the beam's azimuth).
      real3 i1h;
      real d0;
      real share;
      real4 src = ms_slab_source_at(p, alt_p, i1h, d0, share);
      real mu_out = dot(d, up_p);
      real3 out_h = -d + mu_out * up_p;
      real3 beam_h = -u_to_sun + mu_sun * up_p;
      real hh = length(out_h) * length(beam_h);
      real cos_phi = hh > real(1e-12) ? clamp(dot(out_h, beam_h) / hh, real(-1.0), real(1.0)) : real(1.0);
      real mu0_slab = max(abs(mu_sun), real(CV_MS_SLAB_MU0_LO));
      // The slab's light toward the camera, from the sun and from its ground (at radiance L),
      // scaled down where the source holds less than the slab (keep = 1 + d0 / I0_slab), and where
      // it holds more the rest as isotropic light (core/kernel/ms_source). One table is read, the
      // phase that scatters more here (mixed cloud takes the shape of its main phase; on llvmpipe
      // a read of each would cost both everywhere).
      real s_liquid = sl * (real(1.0) - f_liquid);
      real s_ice = si * (real(1.0) - f_ice);
      int phase = s_liquid >= s_ice ? 0 : 1;
      real ground_l;
      real extra;
      real keep = ms_slab_keep(phase, src, d0, share, mu0_slab, phase == 0 ? f_liquid : f_ice, ground_l, extra);
      real slab_light = ms_slab_in_scatter(phase, src.y, src.z, mu0_slab, mu_out, cos_phi, ground_l);
      real j = (s_liquid + s_ice) * (keep * slab_light + extra);
      // The light between the columns (the source's horizontal first moment; the slab has none
      // across its sun's azimuth and none from its neighbours) scattered by the truncated phase, as
      // the linear shape scatters it: sigma' g' I1 . (-d), sigma' g' = sigma (g - f) per phase.
      j -= (sl * max(g_liquid - f_liquid, real(0.0)) + si * max(g_ice - f_ice, real(0.0))) * dot(i1h, d);
      if (lit) scaled_source += sun_air * max(j, real(0.0));
    } else {
      real first = sl * g_liquid * (real(1.0) - g_liquid) + si * g_ice * (real(1.0) - g_ice);
      real i0;
      real3 i1;
      ms_source_at(p, alt_p, i0, i1);
      // In the Earth's shadow (a column lit by a sun below its horizon, its lower part in shadow) the
      // sun's light through the air is not known here: that diffuse light is left out.
      if (lit) scaled_source += sun_air * max(sigma_ms * i0 - first * dot(i1, d), real(0.0));
    }
  } else if (lit) {
    // The octave gate (octaves.glsl): w from the column's optical depth; off, the classic sum.
    bool gate = u_octave_gate && u_octaves > 1;
    real w = gate ? octave_gate_weight(column_tau(p)) : real(1.0);
    real tol = gate ? CV_OCTAVE_GATE_TOL : real(0.0);
    real3 abc = u_octave_abc;
    g_stats[CV_STAT_OCTAVE_TERMS] += uint(octave_terms(u_octaves, abc.y, w, tol));
    g_stats[CV_STAT_OCTAVE_TERMS_FULL] += uint(max(u_octaves, 0));
    real liquid = u_liquid_phase_hg ? ms_octaves_hg_gated(sl, mu, mie_mean_cosine(mie), tau_sun, u_octaves, abc.x, abc.y, abc.z, w, tol)
                                    : ms_octaves_mie_gated(sl, mu, mie, tau_sun, u_octaves, abc.x, abc.y, abc.z, w, tol);
    scatter = liquid + ms_octaves_hg_gated(si, mu, u_ice_g, tau_sun, u_octaves, abc.x, abc.y, abc.z, w, tol);
  }
  real3 source = u_irradiance * (sun_air * scatter + ambient);
  if (kTint && u_tint) source *= tint_hue(sl, si, sigma);
  s.radiance += s.t_view * segment_integral(source, sigma, ds);
  if (kTwoStream) {
    real3 source_ms = u_irradiance * scaled_source;
    if (kTint && u_tint) source_ms *= tint_hue(sl, si, sigma);
    s.radiance += s.t_ms * segment_integral(source_ms, sigma_ms, ds);
    s.t_ms *= transmittance(sigma_ms * ds);
  }
  // The light the step takes out of the view, t_view (1 - exp(-sigma ds)), without the cancellation
  // of t_view - t_next: in float that is a multiple of 6e-8, which left faint cloud with a mean
  // depth tens of kilometres off.
  real taken = s.t_view * segment_integral(sigma, sigma, ds);
  s.depth_w += taken;
  s.depth_t += taken * t;
  real t_before = s.t_view;
  s.t_view *= transmittance(sigma * ds);
  if (t_before > real(0.5) && !(s.t_view > real(0.5))) {
    s.t_half = t_entry;
    s.half_before = t_before;
    s.half_sigma = sigma;
    s.half_ds = ds;
  }
}

// Where in its step a pixel's view samples lie (0..1): step middles without a frame, else the
// frame's jitter from the blue-noise mask (or the white-noise hash).
// The jitter is that of the pixel px stands for (u_pixel_block): a sparse frame's samples are the
// full frame's.
CV_FN real step_offset(ivec2 px) {
  if (u_frame < 0) return real(0.5);
  ivec2 q = px * u_pixel_block + u_block_origin;
  if (!u_blue_noise) return step_jitter(uint(q.x), uint(q.y), uint(u_frame));
  ivec2 n = textureSize(u_jitter_mask, 0);
  return blue_noise_jitter(real(texelFetch(u_jitter_mask, q % n, 0).r), uint(u_frame));
}

// A pixel's view ray, from the camera or, for a camera above the cloud shell, from where the ray
// enters it, placed on the exact sphere: positions near the Earth keep their digits (at 4e8 m a
// float position is +-32 m), and nu = |d x up| keeps near-nadir and near-tangent rays right where
// mu rounds to +-1.
struct MarchRay {
  real3 d;
  real3 origin;
  real h;
  real mu_up;
  real nu_up;
  int n;         // shell segments the ray crosses (0: it misses the shell, or nothing holds cloud)
  real4 seg;     // their (entry, exit) distances from origin
  real t_ground; // where the ground or opaque geometry ends the ray, from origin (3e38: never)
  real t_offset; // the distance from the camera to origin
  real t_opaque; // the distance from the camera to opaque geometry (the depth input; 3e38: none)
};

// The depth input at a pixel: the distance (m) from the camera along its ray to opaque geometry
// drawn by another pass; 0 or less, or no depth input, is none.
CV_FN real opaque_distance(ivec2 px) {
  if (!u_has_depth) return real(3.0e38);
  real t = real(texelFetch(u_depth, px, 0).r);
  return t > real(0.0) ? t : real(3.0e38);
}

// Translucent fragment k of pixel px (kTranslucent): its distance from the camera (3e38: none).
CV_FN real tl_distance(ivec2 px, int k) {
  real t = real(texelFetch(u_tl_distance, ivec2(px.x + k * u_size.x, px.y), 0).r);
  return t > real(0.0) ? t : real(3.0e38);
}

// Composites the next translucent fragment where the march stands: its radiance times its alpha
// behind what the march gathered, and the view transmittance times 1 - alpha.
CV_FN void tl_composite(ivec2 px, CV_INOUT(MarchState) s) {
  real4 c = real4(texelFetch(u_tl_color, ivec2(px.x + s.tl_next * u_size.x, px.y), 0));
  s.radiance += s.t_view * c.w * real3(c.x, c.y, c.z);
  s.t_view *= real(1.0) - c.w;
  s.t_ms *= real(1.0) - c.w;
  s.tl_next += 1;
}

// The view ray through pixel px, `jitter` pixels from where u_pixel_shift puts it.
CV_FN real3 pixel_direction_jittered(ivec2 px, real2 jitter) {
  real x = (real(2.0) * (real(px.x) + real(0.5) + u_pixel_shift.x + jitter.x) / real(u_size.x) - real(1.0)) * u_tan_half;
  real y = (real(1.0) - real(2.0) * (real(px.y) + real(0.5) + u_pixel_shift.y + jitter.y) / real(u_size.y)) * u_tan_half *
           real(u_size.y) / real(u_size.x);
  return normalize(u_forward + x * u_right + y * u_upv);
}

CV_FN real3 pixel_direction(ivec2 px) { return pixel_direction_jittered(px, real2(real(0.0), real(0.0))); }

// Where frame u_frame of an accumulation passes its view rays within their pixels, from the
// centre (pixels, each in [-0.5, 0.5)): the R2 sequence (Roberts' generalised golden ratio,
// 1/phi2 and 1/phi2^2 with phi2^3 = phi2 + 1) started at the centre, so frame 0 and single frames
// (u_frame -1) are the centres and any N consecutive frames spread evenly over the pixel. Summed in
// 24-bit fixed point with integer wrap-around (as blue_noise_jitter), so float on the GPU and double
// on the CPU give the same offsets bit for bit at any frame; in the pixels of the image this one's
// pixels stand for (u_pixel_block: a sparse frame's pixel is 4 of the image's). Only the march takes
// it; the Monte Carlo and the path tracer sample the centres.
CV_FN real2 pixel_jitter() {
  if (!u_anti_alias || u_frame <= 0) return real2(real(0.0), real(0.0));
  uint k = uint(u_frame);
  uint x24 = (8388608u + k * 12664746u) & 16777215u;  // 0.7548776662466927 * 2^24
  uint y24 = (8388608u + k * 9560334u) & 16777215u;   // 0.5698402909980532 * 2^24
  return (real2(real(x24), real(y24)) * real(5.9604644775390625e-8) - real2(real(0.5), real(0.5))) / real(u_pixel_block);
}

CV_FN MarchRay march_ray(ivec2 px) {
  MarchRay r;
  r.d = pixel_direction_jittered(px, pixel_jitter());
  real ht = u_layer.y;
  r.origin = u_cam_ecef;
  r.h = u_cam_alt;
  r.t_offset = real(0.0);
  r.t_opaque = opaque_distance(px);
  real3 up = u_cam_up;
  r.mu_up = dot(r.d, up);
  r.nu_up = length(cross(r.d, up));
  bool in_shell = true;  // false: the ray misses the cloud shell (the sky may still show)
  if (r.h > ht) {
    real e0;
    real e1;
    if (!ray_sphere_rel_nu(u_r0, r.h, r.mu_up, r.nu_up, ht, e0, e1) || e1 < real(0.0)) {
      in_shell = false;
    } else if (e0 > real(0.0)) {
      r.origin = normalize(r.origin + e0 * r.d) * (u_r0 + ht);
      r.t_offset = e0;
      r.h = ht;
      up = normalize(r.origin);
      r.mu_up = dot(r.d, up);
      r.nu_up = length(cross(r.d, up));
    }
  }
  r.n = in_shell && !u_cloudless ? ray_shell_rel_nu(u_r0, r.h, r.mu_up, r.nu_up, u_layer.x, ht, r.seg) : 0;
  real tg0;
  real tg1;
  r.t_ground = ray_sphere_rel_nu(u_r0, r.h, r.mu_up, r.nu_up, real(0.0), tg0, tg1) && tg1 > real(0.0) ? max(tg0, real(0.0)) : real(3.0e38);
  // Opaque geometry stops the march where it stands.
  r.t_ground = min(r.t_ground, r.t_opaque - r.t_offset);
  return r;
}

// Whether light from further along the ray can still reach the camera: through the true extinction
// and, with the two-stream source, through the scaled one too.
CV_FN bool march_goes_on(CV_IN(MarchState) s) { return (kTwoStream ? max(s.t_view, s.t_ms) : s.t_view) > u_min_t; }

CV_FN MarchState march_start() {
  MarchState s;
  s.radiance = real3(0.0);
  s.t_view = real(1.0);
  s.t_ms = real(1.0);
  s.depth_w = real(0.0);
  s.depth_t = real(0.0);
  s.ended = false;
  s.next_step = 0;
  s.t_half = real(3.0e38);
  s.half_before = real(1.0);
  s.half_sigma = real(0.0);
  s.half_ds = real(0.0);
  s.tl_next = 0;
  s.t_first = real(3.0e38);
  return s;
}

// Where in the step recorded by march_sample the view transmittance fell to 0.5 (exactly, for the
// step's constant extinction): t_half becomes the distance from the camera.
CV_FN void march_half_settle(CV_INOUT(MarchState) s) {
  if (s.half_sigma > real(0.0)) {
    s.t_half += min(log(real(2.0) * s.half_before) / s.half_sigma, s.half_ds);
    s.half_sigma = real(0.0);
  }
}

// Advances the view march of ray r (pixel px) over the view steps [step_begin, step_begin +
// step_count), counted over both shell segments; a jump over an empty brick may carry past the
// range's end, and the next range starts there. The march ends when the view transmittance falls
// below u_min_t or the range reaches past the last step. The first range counts a ray that never
// crosses the shell.
CV_FN void march_advance(MarchRay r, ivec2 px, int step_begin, int step_count, CV_INOUT(MarchState) s) {
  // Sunlight propagates along -to_sun and leaves toward the camera along -d: the scattering cosine
  // between the two propagation directions is dot(d, to_sun).
  real mu = dot(r.d, u_to_sun);
  MieParams mie = mie_params(u_droplet_um);
  int next_step = max(step_begin, s.next_step);
  int range_end = step_begin + step_count;
  int base = 0;  // steps of the segments before segment k
  bool crossed = false;
  for (int k = 0; k < (s.ended ? 0 : r.n) && march_goes_on(s); ++k) {
    real t_start = k == 0 ? r.seg.x : r.seg.z;
    real t_end = min(k == 0 ? r.seg.y : r.seg.w, r.t_ground);
    if (!(t_end > t_start)) continue;
    crossed = true;
    int steps = max(1, int(ceil((t_end - t_start) / u_view_step)));
    real dt = (t_end - t_start) / real(steps);
    real offset = step_offset(px);
    int i_end = min(range_end - base, steps);
    int i = max(next_step - base, 0);
    base += steps;
    if (i >= i_end) continue;
    // What the pyramid said about the brick ahead: valid for sample distances below known_end.
    real known_end = real(-1.0);
    real sigma_max = real(0.0);
    // One loop iteration per sample, substeps included: sample j of the substeps of step i.
    int j = 0;
    int substeps = 1;
    while (i < i_end && march_goes_on(s)) {
      if (j == 0) {
        real t_rel = (real(i) + offset) * dt;
        if ((kSkipEmpty || kAdaptive) && !(t_rel < known_end)) {
          real extent;
          real t_q = t_start + t_rel;
          bool empty = space_at(r.origin + t_q * r.d, ray_altitude(u_r0, r.h, r.mu_up, t_q), r.d, extent, sigma_max);
          if (empty && kSkipEmpty) {
            int next = march_resume_index(i, extent, dt);
            g_stats[CV_STAT_VIEW_SKIPPED] += uint(min(next, steps) - i);
            g_stats[CV_STAT_BRICKS_JUMPED] += next - i > 1 ? 1u : 0u;
            i = next;
            next_step = base - steps + min(next, steps);  // where the march goes on, maybe in a later range
            continue;
          }
          known_end = t_rel + extent;
        }
        substeps = 1;
        if (kAdaptive && march_substeps(sigma_max, dt, u_max_step_tau) > 1) {
          // The brick's bound is loose (a brick spans 4 cells and more): bound the step by the
          // cells at its two ends instead, so only steps near thick cloud are divided.
          real ta = t_start + real(i) * dt;
          real tb = t_start + real(i + 1) * dt;
          real bound = max(cell_max(r.origin + ta * r.d, ray_altitude(u_r0, r.h, r.mu_up, ta)),
                           cell_max(r.origin + tb * r.d, ray_altitude(u_r0, r.h, r.mu_up, tb)));
          substeps = march_substeps(bound, dt, u_max_step_tau);
        }
      }
      real ds = dt / real(substeps);
      real t = t_start + (real(i) + (real(j) + offset) / real(substeps)) * dt;
      real t_in = t - offset * ds;  // where the sample's step begins, from origin
      if (kTranslucent) {
        // Translucent geometry within the step (or before it, in space the march jumped): the step
        // is divided at each fragment, which is composited in its place, so the cloud in front of
        // it and behind it are each taken where they stand.
        while (s.tl_next < u_tl_count) {
          real td = tl_distance(px, s.tl_next) - r.t_offset;
          if (!(td < t_in + ds)) break;
          real front = td - t_in;
          if (front > real(0.0)) {
            march_sample(r.origin + t * r.d, ray_altitude(u_r0, r.h, r.mu_up, t), t, front, r.t_offset + t_in, r.d, mu, mie, s);
            t_in = td;
            ds -= front;
          }
          tl_composite(px, s);
        }
      }
      march_sample(r.origin + t * r.d, ray_altitude(u_r0, r.h, r.mu_up, t), t, ds, r.t_offset + t_in, r.d, mu, mie, s);
      if (++j == substeps) {
        j = 0;
        ++i;
        next_step = base - steps + i;
      }
    }
  }
  if (step_begin == 0) g_stats[CV_STAT_RAYS_MISSED] += crossed ? 0u : 1u;
  march_half_settle(s);
  s.ended = !march_goes_on(s) || s.ended || range_end >= base;
  s.next_step = next_step;
}

// The ground at a point, bilinear over texel centres: linear land albedo (rgb) and water fraction (a)
// from the texture (render::load_albedo_map), else the constant albedo and no water.
CV_FN real4 ground_at(real lat_rad, real lon_rad) {
  if (u_ground_size.x <= 0) return real4(u_ground_albedo, real(0.0));
  real4 c = equirect_texel(lat_rad, lon_rad, u_ground_size.x, u_ground_size.y);
  int x0 = int(c.x);
  int y0 = int(c.y);
  int x1 = (x0 + 1) % u_ground_size.x;
  int y1 = min(y0 + 1, u_ground_size.y - 1);
  real4 a = mix(real4(texelFetch(u_ground, ivec2(x0, y0), 0)), real4(texelFetch(u_ground, ivec2(x1, y0), 0)), c.z);
  real4 b = mix(real4(texelFetch(u_ground, ivec2(x0, y1), 0)), real4(texelFetch(u_ground, ivec2(x1, y1), 0)), c.z);
  return mix(a, b, c.w);
}

// Radiance l with transmittance t in front of the opaque geometry (when opaque): with the
// geometry's radiance given (u_has_opaque_color), composited behind and alpha 0; else alpha is the
// transmittance, for the pass that draws the geometry to composite it (l + alpha geometry).
CV_FN real4 over_opaque(real3 l, real t, bool opaque, real3 opaque_l) {
  return opaque && u_has_opaque_color ? real4(l + t * opaque_l, real(0.0)) : real4(l, t);
}

// Radiance and alpha of a pixel whose view ray d carries cloud radiance cloud_l and cloud
// transmittance cloud_t, the cloud (when has_cloud) standing at p_cloud for the air:
// sky in front + T (cloud + behind_t (sky behind + T ground)), the ground replaced by opaque
// geometry t_opaque from the camera where that is nearer (radiance opaque_l, see over_opaque).
// behind_t is the cloud's transmittance for the light behind it: cloud_t, or with the two-stream
// model the delta-scaled one (the light the droplets' forward peak passes on counts as passed).
// Alpha: 0 where the globe shows, else the cloud's times the air's (green) transmittance, for the
// background behind.
// The camera's view ray d in the air's own frame: a camera above the atmosphere starts from where
// its ray enters it, on the exact sphere (as march_ray): o, its altitude h, the up there and the
// ray's cosine and sine to it, t_in the distance from the camera to o; from o, t_end where the ray
// meets the ground (hits_ground) or leaves the air. in_air false: the ray misses the air. The
// march's sky (sky_and_ground) and the path tracer's air in front (path.glsl) both start here.
struct AirRay {
  bool in_air;
  real3 o;
  real h;
  real3 up;
  real mu;
  real nu;
  real t_in;
  real t_end;
  bool hits_ground;
};

CV_FN AirRay camera_air_ray(real3 d) {
  AirRay r;
  real top = CV_ATMO_TOP_M;
  r.o = u_cam_ecef;
  r.h = u_cam_alt;
  r.up = u_cam_up;
  r.mu = dot(d, r.up);
  r.nu = length(cross(d, r.up));
  r.t_in = real(0.0);
  r.t_end = real(0.0);
  r.hits_ground = false;
  real a0;
  real a1;
  r.in_air = ray_sphere_rel_nu(u_r0, r.h, r.mu, r.nu, top, a0, a1) && !(a1 < real(0.0));
  if (!r.in_air) return r;
  if (r.h > top && a0 > real(0.0)) {
    r.t_in = a0;
    r.o = normalize(r.o + a0 * d) * (u_r0 + top);
    r.h = top;
    r.up = normalize(r.o);
    r.mu = dot(d, r.up);
    r.nu = length(cross(d, r.up));
    ray_sphere_rel_nu(u_r0, r.h, r.mu, r.nu, top, a0, a1);
  }
  real g0;
  real g1;
  r.hits_ground = ray_sphere_rel_nu(u_r0, r.h, r.mu, r.nu, real(0.0), g0, g1) && g1 > real(0.0);
  r.t_end = r.hits_ground ? max(g0, real(0.0)) : a1;
  return r;
}

CV_FN real4 sky_and_ground(real3 d, real3 cloud_l, real cloud_t, real behind_t, bool has_cloud, real3 p_cloud, real t_opaque,
                           real3 opaque_l) {
  AirRay air = camera_air_ray(d);
  if (!air.in_air) return over_opaque(cloud_l, cloud_t, t_opaque < real(3.0e38), opaque_l);
  real3 o = air.o;
  real h = air.h;
  real3 up = air.up;
  real mu = air.mu;
  real t_air0 = air.t_in;  // the distance from the camera to o
  bool hits_ground = air.hits_ground;
  real t_end = air.t_end;
  // Opaque geometry nearer than the ground ends the ray there; beyond the top of the air it shows
  // behind all the air the ray crosses (as where the ray misses the air, above).
  bool opaque = t_opaque < real(3.0e38) && t_opaque - t_air0 < (hits_ground ? t_end : real(3.0e38));
  if (opaque) t_end = clamp(t_opaque - t_air0, real(0.0), t_end);
  real t_cloud = has_cloud ? clamp(dot(p_cloud - o, d), real(0.0), t_end) : t_end;
  real3 sky_front = real3(0.0);
  real3 sky_back = real3(0.0);
  real3 tr_front = real3(1.0);
  real3 tr_back = real3(1.0);
  if (kAtmosphere) {
    real mu_s = dot(u_to_sun, up);
    real nu_vs = dot(d, u_to_sun);
    sky_front = u_irradiance * atmo_inscatter(u_r0, h, mu, mu_s, nu_vs, real(0.0), t_cloud, u_sky_steps, u_atmo_sun_steps, tr_front);
    if (t_end > t_cloud) {
      sky_back = u_irradiance * atmo_inscatter(u_r0, h, mu, mu_s, nu_vs, t_cloud, t_end, u_sky_steps, u_atmo_sun_steps, tr_back);
    }
  }
  real3 ground = real3(0.0);
  bool globe = hits_ground && kGlobe && !opaque;
  if (globe) {
    real3 pg = normalize(o + t_end * d) * u_r0;
    real3 n = normalize(pg);
    real mu_sg = dot(u_to_sun, n);
    real nu_sg = length(cross(u_to_sun, n));
    real3 ll = ecef_to_sphere(pg, u_r0);
    real4 g = ground_at(ll.x, ll.y);
    real3 sun_air = real3(mu_sg > real(0.0) ? real(1.0) : real(0.0));
    real3 e_sky = real3(0.0);
    if (kAtmosphere) {
      sun_air = atmo_transmittance(u_r0, real(0.0), mu_sg, nu_sg, u_atmo_sun_steps);
      e_sky = sky_irradiance(sun_air, mu_sg);
    }
    // The clouds' shadow: the same sun march the cloud samples use. With the whole layer in the
    // Earth's shadow no sunlit ray crosses cloud: left out (u_sun_down).
    real shadow = mu_sg > real(0.0) && u_sun_down ? real(1.0) : real(0.0);
    if (!kTwoStream && mu_sg > real(0.0) && !u_sun_down) shadow = transmittance(cloud_sun_depth(pg, real(0.0), mu_sg, nu_sg));
    if (kTwoStream && mu_sg > real(0.0) && !u_sun_down) {
      // The two-stream model lights the ground under a cloud as its column does (docs/physics.md,
      // "The ground under the clouds"): the delta-scaled beam (the light the forward peak keeps on
      // the sun's rays passes), the column's diffuse light going down at its lowest node,
      // pi I0 - (2 pi / 3) I1 per unit irradiance, and the sky's light through the column, of which a
      // conservative layer passes its spherical transmittance (sky_through_cloud: Eddington's
      // coefficient, within 5 % of the slab solver's; liquid and ice each with their own mean cosine),
      // with what the ground under it sends back up and the cloud returns (sky_to_ground_of_depth). Before, the beam alone through the true optical depth made a
      // cloud of optical depth 1 over land of albedo 0.3 render 62-68 % dark at nadir.
      real g_liquid = mie_mean_cosine(mie_params(u_droplet_um));
      // (The higher-order source's beam keeps the smaller share f of its phases, u_ms_f_*: the rest
      // of the peak's light is in its slab's diffuse flux.)
      shadow = transmittance(cloud_sun_depth_weighted(pg, real(0.0), mu_sg, nu_sg, kSlab ? real(1.0) - u_ms_f_liquid : real(1.0) - g_liquid * g_liquid,
                                                      kSlab ? real(1.0) - u_ms_f_ice : real(1.0) - u_ice_g * u_ice_g));
      real i0;
      real3 i1;
      ms_source_at(pg, u_grid_start.z, i0, i1);
      real down = max(CV_PI * i0 - real(2.0) * CV_PI / real(3.0) * dot(i1, n), real(0.0));
      if (kSlab) {
        // The higher-order source: the slab's diffuse flux going down at the column's foot, from
        // the sun and from its ground's light (the droplets' table), as much as the source keeps.
        // What the source holds beyond the slab is left out here: at the foot it is mostly the
        // ground's light going up (counted as isotropic it made a bright ground under a cloud of
        // optical depth 2 5.5 % too bright).
        real3 i1h;
        real d0;
        real share;
        real4 src = ms_slab_source_at(pg, u_grid_start.z, i1h, d0, share);
        real mu0g = max(mu_sg, real(CV_MS_SLAB_MU0_LO));
        real ground_l;
        real extra;
        real keep = ms_slab_keep(0, src, d0, share, mu0g, u_ms_f_liquid, ground_l, extra);
        down = keep * (ms_slab_entry(0, src.y, src.z, mu0g, CV_MS_SLAB_FLUX_DOWN) +
                       ground_l * ms_slab_below_entry(0, src.y, src.z, CV_MS_SLAB_BELOW_FLUX_DOWN));
      }
      real x_sky = column_diffusion_depth(pg, g_liquid, u_ice_g);
      e_sky = e_sky * sky_to_ground_of_depth(x_sky, ground_diffuse_albedo(real3(g), g.w)) + sun_air * down;
    }
    // Water (g.w > 0) needs the view: the cosine toward the camera and between camera and sun.
    real mu_vg = -dot(d, n);
    real nu_svg = -dot(d, u_to_sun);
    ground = u_irradiance * ground_radiance_water(real3(g), g.w, CV_WATER_BODY, mu_sg, mu_vg, nu_svg,
                                                  cox_munk_mss(u_ocean_wind), sun_air * shadow, e_sky);
  }
  bool shown = opaque && u_has_opaque_color;  // the geometry's own radiance stands behind
  if (shown) ground = opaque_l;
  real3 l = sky_front + tr_front * (cloud_l + behind_t * (sky_back + tr_back * ground));
  return real4(l, globe || shown ? real(0.0) : cloud_t * tr_front.y * tr_back.y);
}

// The pixel's radiance (rgb) and alpha once its march has ended: the march's own where the scene
// has neither air nor globe, else the air and the ground composited around it, the cloud standing
// for the air at the mean depth of the light it takes out; opaque geometry behind as over_opaque.
CV_FN real4 march_finish(MarchRay r, ivec2 px, MarchState s) {
  // Translucent geometry behind the last sample (or on a ray that crossed no cloud).
  if (kTranslucent) {
    while (s.tl_next < u_tl_count && tl_distance(px, s.tl_next) < real(3.0e38)) tl_composite(px, s);
  }
  real3 opaque_l = u_has_opaque_color ? real3(texelFetch(u_opaque, px, 0)) : real3(0.0);
  if (!(kAtmosphere || kGlobe)) return over_opaque(s.radiance, s.t_view, r.t_opaque < real(3.0e38), opaque_l);
  real3 p_cloud = r.origin + (s.depth_w > real(0.0) ? s.depth_t / s.depth_w : real(0.0)) * r.d;
  return sky_and_ground(r.d, s.radiance, s.t_view, kTwoStream ? s.t_ms : s.t_view, s.depth_w > real(1e-6), p_cloud, r.t_opaque,
                        opaque_l);
}
