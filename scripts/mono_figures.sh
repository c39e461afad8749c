#!/usr/bin/env bash
# Monocular mode (svslam run --mode mono): the rendered blimp flight at 1024 x 768 (the issue's)
# and euroc_mh01_first320 from cam0, ATE after Sim(3) alignment: the first stereo pair giving
# the scale (default configuration, config/mono_real_camera.yaml) and cam0 alone from its first
# frame (slam.mono_scale none: config/mono_no_scale.yaml, config/mono_real_camera_cam0.yaml).
# The altimeter as scale source is measured by slam_mono_start_test (SVSLAM_MONO_SPEC=synthetic
# for the 1024 x 768 flight).
#   scripts/mono_figures.sh [OUT_DIR]          (about 8 minutes on 2 cores)
# EuRoC lines are skipped when ../shared/data/euroc_mh01_first320 is absent.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=./build/pipeline/svslam
[ -x "$bin" ] || { echo "build first: $bin missing" >&2; exit 1; }
out=${1:-$(mktemp -d)}
mkdir -p "$out"
score() {  # score NAME GT EST [extra eval args]
  local name=$1 gt=$2 dir=$3; shift 3
  local j
  j=$("$bin" eval-trajectory --gt "$gt" --est "$dir/$est_file" --align sim3 \
        --cov "$dir/pose_covariance.txt" --segments 10 "$@")
  echo "$name: $(echo "$j" | grep -oE '"(path_length_m|ate_rmse_m|align_scale|final_att_err_deg|mean_nees|position_within_2sigma_pct)": [-0-9.e]+' | tr '\n' ' ')"
  grep -oE '"(frames_without_pose|frames_monocular|landmarks_added_from_bearings|ekf_median_ms)": [0-9.]+' "$dir/stats.json" | tr '\n' ' '
  echo
}
est_file=trajectory_kitti.txt
"$bin" run --mode mono --sequential --out "$out/synthetic" > /dev/null
score "synthetic 1024x768, defaults" "$out/synthetic/groundtruth_kitti.txt" "$out/synthetic"
"$bin" run --mode mono --sequential --config config/mono_no_scale.yaml --out "$out/synthetic_none" > /dev/null
score "synthetic 1024x768, mono_scale none" "$out/synthetic_none/groundtruth_kitti.txt" "$out/synthetic_none"
data=../shared/data/euroc_mh01_first320
if [ ! -d "$data" ]; then
  echo "skip: $data absent" >&2
  exit 0
fi
est_file=trajectory_tum.txt
for cfg in default real cam0; do
  args=()
  [ "$cfg" = real ] && args=(--config config/mono_real_camera.yaml)
  [ "$cfg" = cam0 ] && args=(--config config/mono_real_camera_cam0.yaml)
  # A diverged run may end with an error (a map too large to rasterise): report and go on.
  if ! "$bin" run --mode mono --sequential "${args[@]}" --source "euroc:$data" \
      --out "$out/euroc_$cfg" > /dev/null 2> "$out/euroc_$cfg.err"; then
    echo "euroc_mh01_first320 cam0, $cfg: run failed: $(tail -1 "$out/euroc_$cfg.err")"
    [ -f "$out/euroc_$cfg/trajectory_tum.txt" ] || continue
  fi
  score "euroc_mh01_first320 cam0, $cfg" "$data/groundtruth_per_frame_cam0_times.txt" \
    "$out/euroc_$cfg" --euroc "$data"
done
