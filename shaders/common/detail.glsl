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
// the order stratiform, cumuliform, cirriform.
#define CV_DETAIL_TYPES 3

// The ramp's width in noise units for a type (row): the cloud's water grows over this much of n
// above the threshold. A deck's water varies softly through it (stratiform 0.25), a cumulus has
// crisp edges (0.05), a cirrus sheet is wispy (0.15).
CV_FN real detail_softness(int type) { return type == 0 ? real(0.25) : type == 1 ? real(0.05) : real(0.15); }

CV_FN real detail_ramp(real n, real t, real softness) { return clamp((n - t) / softness, real(0.0), real(1.0)); }

// The noise of the modelled cloud from the two erosion tiles' values at a point: the low-frequency
// Perlin-Worley with a quarter of the billowy Worley detail (erosion.glsl's weights).
CV_FN real detail_noise_mix(real n_low, real n_high) { return real(0.75) * n_low + real(0.25) * n_high; }
