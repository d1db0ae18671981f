#!/bin/sh
# The viewer plays the sample under a throwaway X server: the instant advances every frame, each
# instant's two-stream source is the one the prefetcher built on its thread (none is built on the
# render thread), and the image at the end differs from the paused viewer's after as many frames.
# usage: play_smoke.sh CLOUDVIEWER SAMPLE OUT_PREFIX [xvfb-run ...]
set -e
cv="$1"; sample="$2"; out="$3"; shift 3
played=$("$@" "$cv" view "$sample" --size 64x36 --frames 4 --play 3 --hide-ui --screenshot "${out}_played.png")
echo "$played"
instants=$(echo "$played" | sed -n 's/^frame [0-9]*: instant //p')
test "$(echo "$instants" | wc -l)" -eq 4 || { echo "expected 4 instants, one per frame"; exit 1; }
test "$(echo "$instants" | sort -u | wc -l)" -eq 4 || { echo "the instant did not advance every frame"; exit 1; }
test "$(echo "$instants" | sort)" = "$instants" || { echo "the instants do not ascend"; exit 1; }
echo "$played" | grep -q "^two-stream sources of view 0: 4 taken as the prefetcher built them, 0 built on the render thread" ||
  { echo "expected the four instants' sources taken as the prefetcher built them"; exit 1; }
"$@" "$cv" view "$sample" --size 64x36 --frames 4 --hide-ui --screenshot "${out}_paused.png" > /dev/null
if cmp -s "${out}_played.png" "${out}_paused.png"; then echo "playing did not change the image"; exit 1; fi
echo "played: the time advanced and the image changed"
