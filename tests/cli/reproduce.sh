#!/bin/sh
# Renders with options and --save-scene, renders again from the saved scene alone, and requires
# identical files: the saved scene must hold everything that decided the image.
# usage: reproduce.sh CLOUDVIEWER SAMPLE.nc WORKDIR
set -eu
exe=$1 sample=$2 dir=$3
rm -rf "$dir" && mkdir -p "$dir/scenes"
"$exe" render "$sample" --size 48x27 --time 2 --quality low --octaves 2 --accumulate 2 --exposure 7 \
  --region 175,205,30,55 --levels 200:1000 --stride 2 --sun-time 2024-06-01T06:30:00Z \
  -o "$dir/a.png" --pfm "$dir/a.pfm" --save-scene "$dir/scenes/a.json"
"$exe" render "$dir/scenes/a.json" -o "$dir/b.png" --pfm "$dir/b.pfm"
cmp "$dir/a.png" "$dir/b.png"
cmp "$dir/a.pfm" "$dir/b.pfm"
cmp "$dir/a.transmittance.pfm" "$dir/b.transmittance.pfm"
echo "reproduced exactly"
