#!/bin/sh
# `cloudviewer record` end to end on the bundled sample (issue 16): bad input refused with exit 2
# before anything is rendered, deterministic frames, frame ranges and --assemble equal to one run,
# and a run killed with SIGKILL resumed to the same video as an uninterrupted run.
# usage: record.sh CLOUDVIEWER SAMPLE WORKDIR
set -u
cv="$1"; sample="$2"; work="$3"
rm -rf "$work"; mkdir -p "$work"
fail() { echo "FAIL: $*"; exit 1; }

# A short path over the sample, the weather running 1 h per second from 03 UTC.
scene() {  # scene FILE KEYFRAMES [EXTRA]
  cat > "$1" <<EOF
{ "version": 1, "data": { "path": "$sample" }, "width": 32, "height": 18, "time": { "interpolation": "linear" },
  "render": { "quality": "low", "exposure": 6 $3 },
  "path": { "weather_hours_per_s": 1.0, "keyframes": [ $2 ] } }
EOF
}
K0='{ "t_s": 0, "lat_deg": 20, "lon_deg": 190, "alt_m": 3000000, "heading_deg": 0, "pitch_deg": -60, "valid_utc": "2024-01-15T03:00:00Z" }'
K1='{ "t_s": 1, "lat_deg": 30, "lon_deg": 188, "alt_m": 400000, "heading_deg": 10, "pitch_deg": -30 }'
K2='{ "t_s": 2, "lat_deg": 34, "lon_deg": 187, "alt_m": 60000, "heading_deg": 20, "pitch_deg": -10 }'
scene "$work/fly.json" "$K0, $K1, $K2" ""

# Bad input: exit 2, one line naming the file and key, and no frames folder made.
expect2() {  # expect2 NAME PATTERN COMMAND...
  name="$1"; pattern="$2"; shift 2
  err=$("$@" 2>&1 >/dev/null); rc=$?
  [ $rc -eq 2 ] || fail "$name: exit $rc, expected 2 ($err)"
  [ "$(printf '%s\n' "$err" | wc -l)" -eq 1 ] || fail "$name: expected one line, got: $err"
  printf '%s\n' "$err" | grep -q -- "$pattern" || fail "$name: '$err' does not name '$pattern'"
}
scene "$work/one.json" "$K0" ""
expect2 one_keyframe "one.json: path.keyframes: found 1 keyframe, expected at least 2" "$cv" record "$work/one.json" -o "$work/bad/one.mp4"
scene "$work/order.json" "$K0, $K2, $K1" ""
expect2 non_increasing "order.json: path.keyframes\[2\].t_s: found 1, expected more than keyframe 1's 2 s" \
  "$cv" record "$work/order.json" -o "$work/bad.mp4"
scene "$work/ground.json" "$K0, { \"t_s\": 1, \"lat_deg\": 30, \"lon_deg\": 188, \"alt_m\": -10 }" ""
expect2 below_ground "ground.json: path.keyframes\[1\].alt_m: found -10, expected an altitude in metres 0..4e8 (not below the ground)" \
  "$cv" record "$work/ground.json" -o "$work/bad.mp4"
scene "$work/late.json" "$K0, $K1, $K2" ""
sed -i 's/2024-01-15T03:00:00Z/2024-01-16T03:00:00Z/' "$work/late.json"
expect2 valid_time_outside "late.json: path.keyframes\[0\].valid_utc: found \"2024-01-16T03:00:00Z\", expected a valid time within the data's" \
  "$cv" record "$work/late.json" -o "$work/bad.mp4"
scene "$work/fast.json" "$K0, $K1, $K2" ""
sed -i 's/"weather_hours_per_s": 1.0/"weather_hours_per_s": 10/' "$work/fast.json"
expect2 rate_runs_outside "fast.json: path.weather_hours_per_s: found \"2024-01-15T23:00:00Z\" at the path's end" \
  "$cv" record "$work/fast.json" -o "$work/bad.mp4"
expect2 no_path "sample_scene.json: path: found nothing" "$cv" record "$(dirname "$cv")/../tests/sample_scene.json" -o "$work/bad.mp4"
expect2 folder_missing "no/such/folder" "$cv" record "$work/fly.json" -o "$work/no/such/folder/x.mp4"
expect2 not_mp4 "-o: .*expected .*\.mp4" "$cv" record "$work/fly.json" -o "$work/x.png"
expect2 no_ffmpeg "ffmpeg: found no 'ffmpeg' program on PATH" env PATH=/nonexistent "$cv" record "$work/fly.json" -o "$work/bad.mp4"
expect2 frames_beyond "--frames: found 0:99, expected frames within 0:20" "$cv" record "$work/fly.json" -o "$work/bad.mp4" --fps 10 --frames 0:99
for f in bad one bad_frames; do [ ! -e "$work/$f" ] || fail "a refused run left $work/$f"; done
echo "bad input refused before rendering"

# One uninterrupted run, 21 frames.
mkdir -p "$work/a" "$work/b" "$work/c" "$work/d"
"$cv" record "$work/fly.json" -o "$work/a/v.mp4" --fps 10 > "$work/a.log" 2>&1 || { cat "$work/a.log"; fail "record failed"; }
grep -q "frame 21 of 21 (frame_00020.png), .* frames/min, ETA" "$work/a.log" || fail "no progress line"
[ -s "$work/a/v.mp4" ] || fail "no video"
[ "$(ls "$work"/a/v_frames/*.png | wc -l)" -eq 21 ] || fail "expected 21 frames"
# Frames of other settings are never mixed in: a rerun at another size into the same folder is refused.
expect2 other_settings "v_frames/record.json: found frames rendered with other settings" \
  "$cv" record "$work/fly.json" -o "$work/a/v.mp4" --fps 10 --size 34x18
ffprobe -v error -select_streams v:0 -show_entries stream=codec_name,pix_fmt,nb_frames -of csv=p=0 "$work/a/v.mp4" | grep -q "^h264,yuv420p,21$" ||
  fail "the video is not 21 frames of H.264 yuv420p: $(ffprobe -v error -select_streams v:0 -show_entries stream=codec_name,pix_fmt,nb_frames -of csv=p=0 "$work/a/v.mp4")"
# The weather runs and the camera moves: consecutive frames differ.
cmp -s "$work/a/v_frames/frame_00009.png" "$work/a/v_frames/frame_00010.png" && fail "frames 9 and 10 are equal"

# Deterministic, in ranges too: frames 0:6 and 7:20 rendered apart, then assembled, give the same bytes.
"$cv" record "$work/fly.json" -o "$work/b/v.mp4" --fps 10 --frames 7:20 > /dev/null 2>&1 || fail "--frames 7:20 failed"
[ ! -e "$work/b/v.mp4" ] || fail "--frames wrote a video"
out=$("$cv" record "$work/fly.json" -o "$work/b/v.mp4" --fps 10 --assemble 2>&1); rc=$?
[ $rc -eq 2 ] || fail "--assemble with frames missing: exit $rc"
echo "$out" | grep -q "frames 0-6 of 0..20 are missing" || fail "--assemble did not name the missing frames: $out"
"$cv" record "$work/fly.json" -o "$work/b/v.mp4" --fps 10 --frames 0:6 > /dev/null 2>&1 || fail "--frames 0:6 failed"
"$cv" record "$work/fly.json" -o "$work/b/v.mp4" --fps 10 --assemble > /dev/null 2>&1 || fail "--assemble failed"
for f in "$work"/a/v_frames/*.png; do
  cmp -s "$f" "$work/b/v_frames/$(basename "$f")" || fail "$(basename "$f") differs between one run and ranges"
done
cmp -s "$work/a/v.mp4" "$work/b/v.mp4" || fail "the assembled video differs from one run's"
echo "deterministic frames; ranges and --assemble equal one run"

# Verified, not just present: a damaged frame is rendered again.
head -c 100 "$work/a/v_frames/frame_00005.png" > "$work/c/short.png"
mkdir -p "$work/c/v_frames"; cp "$work"/a/v_frames/*.png "$work/c/v_frames/"
cp "$work/c/short.png" "$work/c/v_frames/frame_00005.png"
out=$("$cv" record "$work/fly.json" -o "$work/c/v.mp4" --fps 10 2>&1) || fail "resume over a damaged frame failed: $out"
echo "$out" | grep -q "rendered 1 frame(s), skipped 20 already whole" || fail "the damaged frame was not rendered again: $out"
cmp -s "$work/a/v_frames/frame_00005.png" "$work/c/v_frames/frame_00005.png" || fail "the re-rendered frame differs"

# Killed with SIGKILL part way, then resumed: the same frames and the same video.
# At the lowest priority, and watched every 20 ms, so that a loaded machine (ctest -j2) cannot
# let it finish all 21 small frames before the kill.
nice -n 19 "$cv" record "$work/fly.json" -o "$work/d/v.mp4" --fps 10 > "$work/d.log" 2>&1 &
pid=$!
i=0
while [ "$(ls "$work"/d/v_frames/*.png 2>/dev/null | wc -l)" -lt 3 ] && [ $i -lt 3000 ]; do sleep 0.02; i=$((i + 1)); done
kill -9 $pid; wait $pid 2>/dev/null
n=$(ls "$work"/d/v_frames/*.png | wc -l)
[ "$n" -lt 21 ] || fail "the run finished before it was killed"
[ ! -e "$work/d/v.mp4" ] || fail "a killed run left a video"
out=$("$cv" record "$work/fly.json" -o "$work/d/v.mp4" --fps 10 2>&1) || fail "resume failed: $out"
echo "$out" | grep -q "skipped $n already whole" || fail "the resumed run did not skip the $n frames on disk: $out"
cmp -s "$work/a/v.mp4" "$work/d/v.mp4" || fail "the resumed video differs from the uninterrupted run's"
ls -A "$work/d" "$work/d/v_frames" | grep -q '^\.' && fail "temporaries left behind"
echo "killed after $n frames and resumed to the same video"
# The path tracer per frame (--quality reference), seeded by the frame number: the same bytes twice.
mkdir -p "$work/e" "$work/f"
for d in e f; do
  "$cv" record "$work/fly.json" -o "$work/$d/v.mp4" --fps 10 --frames 3:3 --quality reference --spp 8 > "$work/$d.log" 2>&1 ||
    { cat "$work/$d.log"; fail "--quality reference failed"; }
done
grep -q "quality reference: the GPU path tracer, up to 8 samples per pixel" "$work/e.log" || fail "no path tracer line: $(cat "$work/e.log")"
cmp -s "$work/e/v_frames/frame_00003.png" "$work/f/v_frames/frame_00003.png" || fail "the path-traced frame differs between runs"
expect2 spp_without_reference "--spp and --target-error: found them without a path tracer" "$cv" record "$work/fly.json" -o "$work/bad.mp4" --spp 4
# OpenVDB per frame (--vdb): each frame's medium beside its PNG at the frame's weather instant
# (frame 1 at 03:06 UTC lies between forecast steps: the interpolated medium); a rerun writes none.
mkdir -p "$work/g"
out=$("$cv" record "$work/fly.json" -o "$work/g/v.mp4" --fps 10 --frames 0:2 --vdb 2>&1) || fail "--vdb failed: $out"
echo "$out" | grep -q "wrote 3 OpenVDB file(s)" || fail "--vdb did not write 3 files: $out"
for k in 0 1 2; do [ -s "$work/g/v_frames/frame_0000$k.vdb" ] || fail "no OpenVDB file for frame $k"; done
cmp -s "$work/g/v_frames/frame_00000.vdb" "$work/g/v_frames/frame_00001.vdb" && fail "frames 0 and 1 wrote the same medium"
cmp -s "$work/a/v_frames/frame_00001.png" "$work/g/v_frames/frame_00001.png" || fail "--vdb changed a frame's pixels"
out=$("$cv" record "$work/fly.json" -o "$work/g/v.mp4" --fps 10 --frames 0:2 --vdb 2>&1) || fail "--vdb rerun failed: $out"
echo "$out" | grep -q "wrote 0 OpenVDB file(s)" || fail "the rerun wrote OpenVDB files again: $out"
# OpenEXR per frame (--exr): beside each PNG, the PNG's pixels unchanged (the EXR's values are held
# to the PFM pair in CliHostile.ExrIsThePfmPairInOneFileAndItsArgumentsAreChecked); a frame is whole
# only with a whole EXR, so a frame whose EXR was removed or damaged is rendered again (to the same
# bytes), a rerun over whole frames renders nothing, and --assemble --exr names a missing EXR.
mkdir -p "$work/j"
out=$("$cv" record "$work/fly.json" -o "$work/j/v.mp4" --fps 10 --frames 0:2 --exr 2>&1) || fail "--exr failed: $out"
echo "$out" | grep -q "wrote 3 OpenEXR frame(s)" || fail "--exr did not write 3 frames: $out"
for k in 0 1 2; do
  f="$work/j/v_frames/frame_0000$k.exr"
  [ "$(od -An -tx1 -N4 "$f" | tr -d ' ')" = "762f3101" ] || fail "frame $k's EXR lacks the OpenEXR magic number"
  cmp -s "$work/a/v_frames/frame_0000$k.png" "$work/j/v_frames/frame_0000$k.png" || fail "--exr changed frame $k's pixels"
done
cmp -s "$work/j/v_frames/frame_00000.exr" "$work/j/v_frames/frame_00001.exr" && fail "frames 0 and 1 wrote the same EXR"
cp "$work/j/v_frames/frame_00001.exr" "$work/j/first1.exr"
cp "$work/j/v_frames/frame_00002.exr" "$work/j/first2.exr"
rm "$work/j/v_frames/frame_00001.exr"
head -c 300 "$work/j/first2.exr" > "$work/j/v_frames/frame_00002.exr"
out=$("$cv" record "$work/fly.json" -o "$work/j/v.mp4" --fps 10 --frames 0:2 --exr 2>&1) || fail "--exr rerun failed: $out"
echo "$out" | grep -q "rendered 2 frame(s), skipped 1 already whole" || fail "frames with a missing or damaged EXR were not rendered again: $out"
cmp -s "$work/j/first1.exr" "$work/j/v_frames/frame_00001.exr" || fail "the re-rendered EXR of frame 1 differs"
cmp -s "$work/j/first2.exr" "$work/j/v_frames/frame_00002.exr" || fail "the re-rendered EXR of frame 2 differs"
out=$("$cv" record "$work/fly.json" -o "$work/j/v.mp4" --fps 10 --frames 0:2 --exr 2>&1) || fail "--exr second rerun failed: $out"
echo "$out" | grep -q "rendered 0 frame(s), skipped 3 already whole" || fail "a rerun over whole frames rendered some: $out"
rm "$work/j/v_frames/frame_00001.exr"
expect2 assemble_exr "frames 1, 3-20 of 0..20 are missing or not whole 32x18 PNGs with their EXRs" \
  "$cv" record "$work/fly.json" -o "$work/j/v.mp4" --fps 10 --assemble --exr
echo "OpenEXR frames beside the PNGs, resumed"
# The automatic exposure: one for all frames from the same spread frames whatever the range, and
# the probed frames' kept images are the loop's own: frames 0:10 and 11:20 rendered apart equal one run.
scene "$work/auto.json" "$K0, $K1, $K2" ""
sed -i 's/"exposure": 6/"exposure": "auto"/' "$work/auto.json"
mkdir -p "$work/h" "$work/i"
out=$("$cv" record "$work/auto.json" -o "$work/h/v.mp4" --fps 10 2>&1) || fail "auto exposure run failed: $out"
echo "$out" | grep -q "exposure [0-9.e+-]* (auto, for every frame: the least of the automatic exposures of frames 0, 5, 10, 15, 20)" ||
  fail "no automatic exposure line: $out"
for range in 0:10 11:20; do
  "$cv" record "$work/auto.json" -o "$work/i/v.mp4" --fps 10 --frames $range > /dev/null 2>&1 || fail "auto exposure --frames $range failed"
done
for f in "$work"/h/v_frames/*.png; do
  cmp -s "$f" "$work/i/v_frames/$(basename "$f")" || fail "$(basename "$f") differs between one run and ranges with auto exposure"
done
echo "automatic exposure: ranges equal one run"
echo "record end to end passed"
