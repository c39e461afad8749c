#!/usr/bin/env bash
# Clustered-feature ROI tracking (odometry.roi_tracking) against whole-image matching on the dev
# data: for each source, mode (ekf, vo) and setting, the trajectory scores (eval-trajectory), the
# front end's median compute time per frame (a --sequential run: stereo stage + estimator, ms)
# and, on the recorded sequences, the threaded run's frames per second (as fast as possible; the
# synthetic flights are bound by their renderer, so they run sequentially only, at 512x384).
#   scripts/roi_tracking_figures.sh [SVSLAM_BINARY]
# Prints one line per run. Needs ../shared/data (KITTI seq_a, EuRoC MH01); the synthetic
# flights need nothing.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-./build/pipeline/svslam}
data=../shared/data
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf 'odometry:\n  roi_tracking: true\n' > "$tmp/on.yaml"
printf 'odometry:\n  roi_tracking: false\n' > "$tmp/off.yaml"
field() { grep -o "\"$1\": [-0-9.e+]*" | head -1 | awk '{print $2}'; }
score() {  # name src mode setting eval-args...
  local name=$1 src=$2 mode=$3 setting=$4
  shift 4
  local o=$tmp/o
  rm -rf "$o" "$o.seq"
  "$bin" run --source "$src" --mode "$mode" --config "$tmp/$setting.yaml" --out "$o.seq" \
    --sequential > /dev/null 2>&1
  if [[ "$src" == synthetic* ]]; then
    cp -r "$o.seq" "$o"
    sed -i 's/"fps": [0-9.]*/"fps": -/' "$o/stats.json"
  else
    "$bin" run --source "$src" --mode "$mode" --config "$tmp/$setting.yaml" --out "$o" > /dev/null 2>&1
    cmp -s "$o/trajectory_kitti.txt" "$o.seq/trajectory_kitti.txt" || echo "threaded != sequential!"
  fi
  local est=$o/trajectory_kitti.txt
  [[ "$src" == euroc:* ]] && est=$o/trajectory_tum.txt
  local j
  j=$("$bin" eval-trajectory --est "$est" "$@")
  printf '%-18s %-4s roi %-3s drift %7s %%  ate %7s m  final %7s m  front_end %6s ms  fps %6s\n' \
    "$name" "$mode" "$setting" "$(echo "$j" | field t_err_pct)" "$(echo "$j" | field ate_rmse_m)" \
    "$(echo "$j" | field final_pos_err_m)" "$(field front_end_median_ms < "$o.seq/stats.json")" \
    "$(field fps < "$o/stats.json")"
}
for mode in ekf vo; do
  for setting in off on; do
    if [ -d "$data/kitti_odometry_seq_a" ]; then
      score kitti_seq_a "kitti:$data/kitti_odometry_seq_a" $mode $setting \
        --gt "$data/kitti_odometry_seq_a/poses.txt" --segments 10,20,40 --step 1
    fi
    if [ -d "$data/euroc_mh01_first320" ]; then
      e=$data/euroc_mh01_first320
      score euroc_mh01_320 "euroc:$e" $mode $setting --gt "$e/groundtruth_per_frame_cam0_times.txt" \
        --euroc "$e" --segments 1,2,4 --step 1
    fi
    for seed in 1 2 3; do
      score "synthetic_seed$seed" "synthetic:width=512,height=384,seed=$seed" $mode $setting \
        --gt "$tmp/o/groundtruth_kitti.txt" --segments 10,20,40 --step 1 --align none
    done
  done
done
