#!/bin/sh
# Smoke test of `cloudviewer bench`: one scene, tiny size and spp, into a fresh folder; the CSV must
# have the expected header and one row per configuration, the summary and plot must exist, and a
# second run must reuse the cached reference. The quality front is written beside them and into the
# per-user cache (here a folder of the run's own, so that a test never touches the real one). The
# GPU path tracer's rows (--path-spp) are in the CSV and the plot, and never in the front.
set -eu
exe=$1 dir=$2
rm -rf "$dir"
XDG_CACHE_HOME=$dir/cache
export XDG_CACHE_HOME
"$exe" bench stratocumulus --size 24x14 --reference-spp 32 --repeats 1 --path-spp 1,4 --out "$dir"
header='scene,config,kind,view_step_m,sun_steps,octaves,accumulate,resolution_scale,liquid_phase,adaptive_steps,wall_ms,gpu_ms,rel_rmse,rel_rmse_raw,ref_noise_floor,rel_rmse_resolution,rel_bias,worst_pixel,psnr_db,pareto,ref_spp,ref_mean_rel_stderr,error_image,path_spp,path_rel_stderr'
test "$(head -n 1 "$dir/results.csv")" = "$header" || { echo "bad header: $(head -n 1 "$dir/results.csv")"; exit 1; }
rows=$(tail -n +2 "$dir/results.csv" | grep -c '^stratocumulus,')
test "$rows" -eq 23 || { echo "expected 23 rows, found $rows"; exit 1; }
for n in 1 4; do
  awk -F, -v n=$n '$2 == "path_" n "spp" && $3 == "path_tracer" && $20 == 0 && $24 == n { f = 1 } END { exit !f }' "$dir/results.csv" \
    || { echo "no path tracer row at $n spp (kind path_tracer, off the front)"; exit 1; }
  test -s "$dir/stratocumulus/err_path_${n}spp.png" || { echo "no error image of the path tracer at $n spp"; exit 1; }
done
# Unbiased, so more samples bring the error down (here 4x the samples: about half the error, far
# from equal given 336 pixels).
awk -F, '$2 == "path_1spp" { a = $13 } $2 == "path_4spp" { b = $13 } END { exit !(b < 0.8 * a) }' "$dir/results.csv" \
  || { echo "the path tracer's error did not fall from 1 to 4 spp"; exit 1; }
if grep -q '"name": "path_' "$dir/quality_front.json"; then echo "a path tracer row is in the quality front"; exit 1; fi
for c in low default high two_stream_linear costa2023 haggstrom2018 fordsung2024; do
  grep -q "^stratocumulus,$c," "$dir/results.csv" || { echo "no row for $c"; exit 1; }
done
test "$(awk -F, 'NR > 1 && $20 == 1' "$dir/results.csv" | wc -l)" -ge 1 || { echo "no configuration on the Pareto front"; exit 1; }
test -s "$dir/summary.md" && test -s "$dir/stratocumulus_pareto.png" && test -s "$dir/stratocumulus/err_default.png"
# (Output to a file first: grep -q on a pipe would end the run early by SIGPIPE.)
"$exe" bench stratocumulus --size 24x14 --reference-spp 32 --repeats 1 --path-spp none --out "$dir" > "$dir/run2.txt"
grep -q 'holds 32 spp' "$dir/run2.txt" \
  || { echo "the second run did not reuse the cached reference"; exit 1; }
grep -q '"format": "cloudviewer-quality-front"' "$dir/quality_front.json" || { echo "no quality_front.json"; exit 1; }
grep -q '"candidate": true' "$dir/quality_front.json" || { echo "no candidate in quality_front.json"; exit 1; }
cmp -s "$dir/quality_front.json" "$dir/cache/cloudviewer/quality_front.json" || { echo "the front was not cached"; exit 1; }
rm "$dir/cache/cloudviewer/quality_front.json"
"$exe" bench stratocumulus --size 24x14 --reference-spp 32 --repeats 1 --path-spp none --out "$dir" --no-cache >/dev/null
test ! -e "$dir/cache/cloudviewer/quality_front.json" || { echo "--no-cache wrote the cache"; exit 1; }
# A larger --reference-spp extends the cached reference instead of starting over.
"$exe" bench stratocumulus --size 24x14 --reference-spp 33 --repeats 1 --path-spp none --out "$dir" > "$dir/run3.txt"
grep -q 'at 33 spp (1 new' "$dir/run3.txt" \
  || { echo "the third run did not extend the cached reference"; exit 1; }
test "$(awk -F, 'NR == 2 { print $21 }' "$dir/results.csv")" = 33 || { echo "results.csv does not say 33 spp"; exit 1; }
# --timing-only: frame times without a reference (no error, no front, no plots); the path tracer
# with its own noise estimate.
"$exe" bench stratocumulus --size 24x14 --repeats 1 --path-spp 2 --timing-only --out "$dir/timing" --no-cache > "$dir/run4.txt"
test "$(tail -n +2 "$dir/timing/results.csv" | grep -c '^stratocumulus,')" -eq 22 || { echo "timing only: expected 22 rows"; exit 1; }
test ! -e "$dir/timing/quality_front.json" && test ! -e "$dir/timing/stratocumulus_pareto.png" || { echo "timing only wrote a front or a plot"; exit 1; }
awk -F, '$2 == "default" && $13 == "nan" && $11 > 0 { f = 1 } END { exit !f }' "$dir/timing/results.csv" || { echo "timing only: the default row has an error or no time"; exit 1; }
awk -F, '$2 == "path_2spp" && $25 > 0 && $25 < 1e300 { f = 1 } END { exit !f }' "$dir/timing/results.csv" || { echo "timing only: no noise estimate of the path tracer"; exit 1; }
# --cloud-model both: each scene also as <scene>+modelled, against a reference of the modelled
# density (its own cached file), its rows in the CSV and its scene in the front.
"$exe" bench stratocumulus --size 24x14 --reference-spp 32 --repeats 1 --path-spp 1 --cloud-model both --out "$dir/models" --no-cache > "$dir/run5.txt"
test "$(tail -n +2 "$dir/models/results.csv" | grep -c '^stratocumulus+modelled,')" -eq 22 || { echo "modelled: expected 22 rows"; exit 1; }
test "$(tail -n +2 "$dir/models/results.csv" | grep -c '^stratocumulus,')" -eq 22 || { echo "both: expected 22 data rows"; exit 1; }
test "$(ls "$dir/models"/ref_stratocumulus+modelled_24x14_*.cvref | wc -l)" -eq 1 || { echo "no reference of the modelled cloud"; exit 1; }
test "$(ls "$dir/models"/ref_stratocumulus_24x14_*.cvref | wc -l)" -eq 1 || { echo "no reference of the data mode"; exit 1; }
grep -q '"scene": "stratocumulus+modelled"' "$dir/models/quality_front.json" || { echo "the modelled scene is not in the front"; exit 1; }
test -s "$dir/models/stratocumulus+modelled/err_default.png" || { echo "no error image of the modelled default"; exit 1; }
# The modelled images differ from the data mode's (the default row's raw error, with the noise left
# in, is not the data row's: the noise-corrected error of both can be clamped to 0 against a reference
# of few samples once the model is close to it).
awk -F, '$2 == "default" { e[$1] = $14 } END { exit !(e["stratocumulus"] != e["stratocumulus+modelled"]) }' "$dir/models/results.csv" \
  || { echo "the modelled rows are the data rows"; exit 1; }
echo "bench smoke: $rows rows"
