#!/usr/bin/env bash
# The pictures of `svslam plot` shown in README.md and docs/pipeline.md (docs/images/plot_*.png):
# from a synthetic flight (with its exact ground truth and per-frame latency) the trajectory,
# landmarks and latency; from kitti_odometry_seq_a with its ground-truth poses (skipped when
# ../shared/data is absent) the altitude and the trajectory.
#   scripts/plot_figures.sh [SVSLAM_BINARY] [IMAGES_DIR]
# Prints the JSON of each `svslam plot`; the run folders are temporary.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-./build/pipeline/svslam}
images=${2:-docs/images}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$images"

# Synthetic flight (down-looking camera: gravity +z, the default of --gravity and of
# map.gravity_in_first_camera); latency.txt for the end-to-end histogram.
printf 'pipeline:\n  latency_log: true\n' > "$work/latency.yaml"
"$bin" run --source "synthetic:width=512,height=384" --config "$work/latency.yaml" \
  --out "$work/synthetic" > "$work/synthetic.json" 2> /dev/null
"$bin" plot --run "$work/synthetic" --out "$work/synthetic_plots"
for name in trajectory_top landmarks latency; do
  cp "$work/synthetic_plots/$name.png" "$images/plot_synthetic_$name.png"
done

kitti=../shared/data/kitti_odometry_seq_a
if [ -d "$kitti" ]; then
  # A car: y down in the camera frame, so the top view is x-z; ground truth = poses.txt.
  "$bin" run --source "kitti:$kitti" --out "$work/kitti" > "$work/kitti.json" 2> /dev/null
  "$bin" plot --run "$work/kitti" --ground-truth "$kitti/poses.txt" --gravity 0,1,0 \
    --out "$work/kitti_plots"
  for name in altitude trajectory_top; do
    cp "$work/kitti_plots/$name.png" "$images/plot_kitti_$name.png"
  done
else
  echo "skip kitti_odometry_seq_a: $kitti absent" >&2
fi
