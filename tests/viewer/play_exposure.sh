#!/bin/sh
# Playing the sample's afternoon into dusk under a throwaway X server: the automatic exposure is
# held at the brightest frame's, so it never rises while the light fades (frame by frame it rose
# from 11 to 1e5 as the sun set, lifting dusk back to noon's brightness).
# usage: play_exposure.sh CLOUDVIEWER SAMPLE [xvfb-run ...]
set -e
cv="$1"; sample="$2"; shift 2
played=$("$@" "$cv" view "$sample" --size 64x36 --frames 12 --play 3 --time 2024-01-15T04:00:00Z --hide-ui)
lines=$(echo "$played" | sed -n 's/^frame [0-9]*: exposure \([^ ]*\) held while playing (this frame.s own \([^ )]*\).*/\1 \2/p')
echo "$lines"
test "$(echo "$lines" | wc -l)" -ge 10 || { echo "expected an exposure line per frame played"; exit 1; }
# Held: never rising; and the light did fade (some frame's own exposure at least twice the first).
echo "$lines" | awk 'NR == 1 { first = $1; prev = $1 }
  { if ($1 > prev * (1 + 1e-9)) { print "the exposure rose from " prev " to " $1 " while playing"; bad = 1 }
    prev = $1; if ($2 != "none:" && $2 + 0 > 2 * first) faded = 1 }
  END { if (!faded) { print "no frame was darker than the first: the test saw no fading light"; bad = 1 }
        if (bad) exit 1 }'
echo "held: the exposure did not rise while the light faded"
