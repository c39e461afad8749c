#!/usr/bin/env bash
# Accuracy and consistency of `svslam run` on the real dev data at several frame rates:
# kitti_odometry_seq_a at every frame, every 2nd and every 3rd (drift over 10/20/40 m), and
# euroc_mh01_first320 at every frame, every 2nd and every 4th (ATE after SE(3) alignment).
# Lower rates are made by linking every N-th image pair (and ground-truth line) into a scratch
# folder, so larger motions between frames are seen as on a faster vehicle.
#   scripts/real_data_figures.sh [--config FILE] [SVSLAM_BINARY]
# Prints one line per case: drift or ATE, final attitude error, mean NEES (6-dof; position),
# share of frames within 2 sigma, frames without a pose.
set -euo pipefail
cd "$(dirname "$0")/.."
config=()
if [ "${1:-}" = "--config" ]; then config=(--config "$2"); shift 2; fi
bin=${1:-./build/pipeline/svslam}
data=../shared/data
if [ ! -d "$data/kitti_odometry_seq_a" ] || [ ! -d "$data/euroc_mh01_first320" ]; then
  echo "skip: $data/kitti_odometry_seq_a or euroc_mh01_first320 absent" >&2
  exit 0
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
kitti=$(cd "$data/kitti_odometry_seq_a" && pwd)
euroc=$(cd "$data/euroc_mh01_first320" && pwd)

# kitti_every N DIR: every N-th pair of kitti_odometry_seq_a, renumbered, with its poses.
kitti_every() {
  local n=$1 d=$2 i=0 j=0 f
  mkdir -p "$d/image_l" "$d/image_r"
  cp "$kitti/calib.txt" "$d/"
  for f in $(ls "$kitti/image_l"); do
    if [ $((i % n)) -eq 0 ]; then
      ln -s "$kitti/image_l/$f" "$d/image_l/$(printf %06d.png "$j")"
      ln -s "$kitti/image_r/$f" "$d/image_r/$(printf %06d.png "$j")"
      j=$((j + 1))
    fi
    i=$((i + 1))
  done
  awk -v n="$n" '(NR - 1) % n == 0' "$kitti/poses.txt" > "$d/poses.txt"
}

# euroc_every N DIR: every N-th line of both cameras' data.csv (images linked).
euroc_every() {
  local n=$1 d=$2 c
  for c in cam0 cam1; do
    mkdir -p "$d/mav0/$c"
    ln -s "$euroc/mav0/$c/data" "$d/mav0/$c/data"
    cp "$euroc/mav0/$c/sensor.yaml" "$d/mav0/$c/"
    awk -v n="$n" 'NR == 1 || (NR - 2) % n == 0' "$euroc/mav0/$c/data.csv" > "$d/mav0/$c/data.csv"
  done
}

# The first (top-level) value of a JSON key.
field() { grep -o "\"$1\": [^,}]*" | head -1 | sed 's/.*: //'; }

run_case() {
  local label=$1 kind=$2 dir=$3 out=$tmp/out_$1 ev
  "$bin" run --source "$kind:$dir" --out "$out" "${config[@]}" > /dev/null 2> "$tmp/err_$label" ||
    { echo "$label: svslam run failed: $(tail -1 "$tmp/err_$label")"; return; }
  if [ "$kind" = kitti ]; then
    ev=$("$bin" eval-trajectory --gt "$dir/poses.txt" --est "$out/trajectory_kitti.txt" \
      --segments 10,20,40 --step 1 --cov "$out/pose_covariance.txt")
    printf '%-16s drift %6.3f %%  ' "$label" "$(echo "$ev" | field t_err_pct)"
  else
    ev=$("$bin" eval-trajectory --gt "$euroc/groundtruth_per_frame_cam0_times.txt" \
      --est "$out/trajectory_tum.txt" --euroc "$euroc" \
      --cov "$out/pose_covariance.txt")
    printf '%-16s ATE %.4f m     ' "$label" "$(echo "$ev" | field ate_rmse_m)"
  fi
  printf 'att %6.3f deg  NEES %8.1f; %7.1f  within 2 sigma %5.1f %% (position %5.1f %%)  no pose %s\n' \
    "$(echo "$ev" | field final_att_err_deg)" "$(echo "$ev" | field mean_nees)" \
    "$(echo "$ev" | field mean_nees_position)" "$(echo "$ev" | field within_2sigma_pct)" \
    "$(echo "$ev" | field position_within_2sigma_pct)" \
    "$(field frames_without_pose < "$out/stats.json")"
}

kitti_every 2 "$tmp/kitti_2"
kitti_every 3 "$tmp/kitti_3"
euroc_every 2 "$tmp/euroc_2"
euroc_every 4 "$tmp/euroc_4"
run_case kitti_every_1 kitti "$kitti"
run_case kitti_every_2 kitti "$tmp/kitti_2"
run_case kitti_every_3 kitti "$tmp/kitti_3"
run_case euroc_every_1 euroc "$euroc"
run_case euroc_every_2 euroc "$tmp/euroc_2"
run_case euroc_every_4 euroc "$tmp/euroc_4"
