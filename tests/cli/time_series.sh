#!/bin/sh
# `render --times A..B --every D`: the frames are written, numbered, and a second run skips them all.
# usage: time_series.sh CLOUDVIEWER SAMPLE OUTDIR
set -e
cv="$1"; sample="$2"; out="$3"
rm -rf "$out"
"$cv" render "$sample" --size 32x18 --quality low --times 2024-01-15T03:00:00Z..2024-01-15T06:00:00Z --every 90m -o "$out"
for f in frame_00000.png frame_00001.png frame_00002.png; do
  test -s "$out/$f" || { echo "missing $out/$f"; exit 1; }
done
test ! -e "$out/frame_00003.png" || { echo "one frame too many"; exit 1; }
# The middle frame is between steps: it differs from both ends.
if cmp -s "$out/frame_00000.png" "$out/frame_00001.png" || cmp -s "$out/frame_00001.png" "$out/frame_00002.png"; then
  echo "the interpolated frame equals a step's frame"; exit 1
fi
again=$("$cv" render "$sample" --size 32x18 --quality low --times 2024-01-15T03:00:00Z..2024-01-15T06:00:00Z --every 90m -o "$out")
echo "$again" | grep -q "wrote 0 frame(s), skipped 3 already written" || { echo "$again"; echo "the second run did not skip"; exit 1; }
echo "series written and resumed"
