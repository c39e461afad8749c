#!/usr/bin/env bash
# The elevation map's figures (docs/map.md): DEM accuracy against the exact terrain on the
# default synthetic flight (1024x768) and its 512x384 version, and the flatness of the road
# under the car on kitti_odometry_seq_a (skipped when ../shared/data is absent).
#   scripts/map_figures.sh [SVSLAM_BINARY] [OUT_DIR]
# Prints one JSON line per measurement; the run folders stay in OUT_DIR (default: a temporary
# folder, removed).
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-./build/pipeline/svslam}
out=${2:-}
if [ -z "$out" ]; then
  out=$(mktemp -d)
  trap 'rm -rf "$out"' EXIT
fi
mkdir -p "$out"
for spec in "synthetic" "synthetic:width=512,height=384"; do
  name=$(echo "$spec" | tr ':=,' '___')
  "$bin" run --source "$spec" --out "$out/$name" > "$out/$name.json" 2> /dev/null
  echo "{\"source\": \"$spec\", \"dem\": $("$bin" eval-dem --dem "$out/$name/dem.tif" \
    --gt "$out/$name/groundtruth_dem.tif")}"
done
kitti=../shared/data/kitti_odometry_seq_a
if [ -d "$kitti" ]; then
  # A car: forward-looking level camera; the ground only (nothing 0.5 m above the camera:
  # street lamps and branches over the road stay out of the DEM).
  printf 'map:\n  gravity_in_first_camera: [0, 1, 0]\n  max_height_above_camera_m: 0.5\n' \
    > "$out/car.yaml"
  "$bin" run --source "kitti:$kitti" --config "$out/car.yaml" --out "$out/kitti" \
    > "$out/kitti.json" 2> /dev/null
  for hw in 0.5 1.0; do
    echo "{\"source\": \"kitti_odometry_seq_a\", \"road\": $("$bin" eval-dem \
      --dem "$out/kitti/dem.tif" --path "$out/kitti/trajectory_kitti.txt" --gravity 0,1,0 \
      --half-width-m "$hw")}"
  done
else
  echo "skip kitti_odometry_seq_a: $kitti absent" >&2
fi
