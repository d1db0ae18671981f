#!/bin/sh
# The Slurm array of scripts/slurm/record.sbatch on a real single-node cluster (scripts/slurm-local):
# 4 tasks each render a range of a short path's frames, a dependent job assembles the MP4, and the
# frames and the MP4 equal a single-process run's. Starts the cluster, uses it, stops it and removes
# everything it made. usage: slurm_record.sh CLOUDVIEWER SAMPLE WORKDIR SOURCE_DIR
set -u
cv="$1"; sample="$2"; work="$3"; src="$4"
rm -rf "$work"; mkdir -p "$work/one" "$work/array"
fail() { echo "FAIL: $*"; exit 1; }
cluster="$work/cluster"
"$src/scripts/slurm-local" start "$cluster" > "$work/start.log" 2>&1 || { cat "$work/start.log"; fail "the cluster did not start"; }
trap '"$src/scripts/slurm-local" stop "$cluster"' EXIT
export SLURM_CONF="$cluster/slurm.conf"

cat > "$work/fly.json" <<JSON
{ "version": 1, "data": { "path": "$sample" }, "width": 32, "height": 18, "time": { "interpolation": "linear" },
  "render": { "quality": "low", "exposure": 6 },
  "path": { "weather_hours_per_s": 2.0, "keyframes": [
    { "t_s": 0, "lat_deg": 20, "lon_deg": 190, "alt_m": 3000000, "pitch_deg": -60, "valid_utc": "2024-01-15T03:00:00Z" },
    { "t_s": 1, "lat_deg": 32, "lon_deg": 188, "alt_m": 200000, "heading_deg": 15, "pitch_deg": -20 } ] } }
JSON
t0=$(date +%s.%N)
"$cv" record "$work/fly.json" -o "$work/one/v.mp4" --fps 9 > "$work/one.log" 2>&1 || { cat "$work/one.log"; fail "the single run failed"; }
t1=$(date +%s.%N)
ids=$(CLOUDVIEWER="$cv" "$src/scripts/slurm/record.sbatch" "$work/fly.json" "$work/array/v.mp4" 9 4) || fail "submitting failed: $ids"
echo "$ids"
echo "$ids" | grep -q "array job [0-9]* (4 tasks over 10 frames), assemble job [0-9]* after it" || fail "unexpected submission: $ids"
i=0
while [ -n "$(squeue -h -o %i 2>/dev/null)" ] && [ $i -lt 1200 ]; do sleep 0.1; i=$((i + 1)); done
t2=$(date +%s.%N)
[ -z "$(squeue -h -o %i)" ] || fail "jobs still queued after 120 s: $(squeue)"
for log in "$work"/array/cv-record-*.log; do grep -q "record" "$log" 2>/dev/null || true; done
[ -s "$work/array/v.mp4" ] || { cat "$work"/array/*.log; fail "the assemble job wrote no video"; }
[ "$(ls "$work"/array/cv-record-*_?.log | wc -l)" -eq 4 ] || fail "expected 4 task logs"
for f in "$work"/one/v_frames/*.png; do
  cmp -s "$f" "$work/array/v_frames/$(basename "$f")" || fail "$(basename "$f") differs between the array and one process"
done
[ "$(ls "$work"/array/v_frames/*.png | wc -l)" -eq 10 ] || fail "expected 10 frames from the array"
cmp -s "$work/one/v.mp4" "$work/array/v.mp4" || fail "the array's MP4 differs from one process's"
awk -v a="$t0" -v b="$t1" -v c="$t2" 'BEGIN { printf "one process %.1f s, Slurm array of 4 (submit to assembled) %.1f s\n", b - a, c - b }'
"$src/scripts/slurm-local" stop "$cluster"
trap - EXIT
[ ! -e "$cluster" ] || fail "the cluster's folder was left behind"
rm -rf "$work"
echo "slurm array equals one process"
