// The modelled cloud's sub-grid shape (issue 18; docs/physics.md, "The modelled cloud"), shared by
// the march kernel (shaders/kernel/march.glsl detail_factor) and the table it reads
// (core/noise/detail_table). In every grid cell the noise n in [0, 1] is laid out in whole tiles,
// so the cell holds the tile's distribution of n exactly. For a cover c the threshold t(c) leaves a
// share c of the tile above it, and the cloud's shape there is the ramp h = clamp((n - t) / s, 0, 1)
// (s: the cloud type's softness, detail_softness); dividing by the tile's mean of h, m(c), keeps the
// cell's mean. The threshold does not depend on s (h > 0 exactly where n > t), so the cloudy share
// is c whatever blend of the types' ramps a point takes.

// Covers in the table: c = (k / CV_DETAIL_COVERS)^2, k = 0..CV_DETAIL_COVERS (denser at low cover,
// where the threshold moves fastest: the noise's thin upper tail).
#define CV_DETAIL_COVERS 256
// The table's rows: one per cloud type of the weather textures (core/kernel/weather_textures), in
// the order stratiform, cumuliform, cirriform; then, per type, CV_DETAIL_PHASES rows of the tile's
// first moments along longitude (x) and latitude (y) at the phases p / CV_DETAIL_PHASES
// (detail_first_moment: the cell-mean correction of march.glsl detail_factor).
// Then, per horizontal slice of the tile (CV_DETAIL_SLICES of them, by the tile's height, which the
// kernel mirrors so that each level holds it once going up and once coming down), a row per type
// of the slice's own threshold and ramp mean: a slice of the tile does not hold the whole tile's
// distribution (at a cover of 0.3 the share above the tile's threshold ranged 0.20-0.38 over 16
// slices), so a cover or an extinction that changes with height within a level would meet that
// difference; with each slice's own threshold every horizontal slice of a cell keeps its cover and
// mean (docs/physics.md, "The modelled cloud").
#define CV_DETAIL_TYPES 3
#define CV_DETAIL_PHASES 64
#define CV_DETAIL_SLICES 32
#define CV_DETAIL_SLICE_ROW0 (CV_DETAIL_TYPES * (1 + CV_DETAIL_PHASES))
#define CV_DETAIL_ROWS (CV_DETAIL_SLICE_ROW0 + CV_DETAIL_SLICES * CV_DETAIL_TYPES)
// The correction's bounds: it multiplies the modelled extinction by 1 / 1.1 to 1.1 (the majorants
// take the upper one).
#define CV_DETAIL_CORRECTION_MAX 1.1

// The ramp's width in noise units for a type (row): the cloud's water grows over this much of n
// above the threshold. A deck's water varies softly through it (stratiform 0.12), a cumulus has
// crisp edges (0.05), a cirrus sheet is wispy (0.10). A softer ramp has a smaller mean m(c) at low
// cover, so a larger peak c / m(c) (the tracking's majorant: about 176 x the softness at the
// smallest cover; 0.25 made the path tracer's null collisions 2.6 times as many as 0.08 did).
CV_FN real detail_softness(int type) { return type == 0 ? real(0.12) : type == 1 ? real(0.05) : real(0.10); }

CV_FN real detail_ramp(real n, real t, real softness) { return clamp((n - t) / softness, real(0.0), real(1.0)); }

// The noise of the modelled cloud from the two erosion tiles' values at a point: the low-frequency
// Perlin-Worley with a quarter of the billowy Worley detail (erosion.glsl's weights).
CV_FN real detail_noise_mix(real n_low, real n_high) { return real(0.75) * n_low + real(0.25) * n_high; }
