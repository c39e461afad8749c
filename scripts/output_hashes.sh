#!/usr/bin/env bash
# Hashes of the outputs of `svslam run` (trajectory_kitti.txt, pose_covariance.txt,
# landmarks.ply) over the dev data and the default synthetic flight, ekf and vo, threaded and
# --sequential: a structural change that must not change behaviour is checked by comparing
# these hashes before and after it.
#   scripts/output_hashes.sh [SVSLAM_BINARY] > hashes.txt      # record
#   scripts/output_hashes.sh --check hashes.txt [SVSLAM_BINARY] # compare, exit 1 on a change
# Sources needing ../shared/data are skipped (said on stderr) when it is absent. Extra `svslam
# run` options for every run: SVSLAM_RUN_ARGS (e.g. "--config roi.yaml").
set -euo pipefail
cd "$(dirname "$0")/.."
check=""
if [ "${1:-}" = "--check" ]; then check=$2; shift 2; fi
bin=${1:-./build/pipeline/svslam}
data=../shared/data
sources=("synthetic")
[ -d "$data/kitti_odometry_seq_a" ] && sources+=("kitti:$data/kitti_odometry_seq_a") ||
  echo "skip kitti_odometry_seq_a: $data absent" >&2
[ -d "$data/euroc_mh01_first320" ] && sources+=("euroc:$data/euroc_mh01_first320") ||
  echo "skip euroc_mh01_first320: $data absent" >&2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
out=$tmp/hashes.txt
for src in "${sources[@]}"; do
  name=$(basename "${src#*:}")
  for mode in ekf vo; do
    for run in threaded sequential; do
      args=(run --source "$src" --mode "$mode" --out "$tmp/o")
      [ "$run" = sequential ] && args+=(--sequential)
      rm -rf "$tmp/o"
      # shellcheck disable=SC2086
      "$bin" "${args[@]}" ${SVSLAM_RUN_ARGS:-} > /dev/null
      for f in trajectory_kitti.txt pose_covariance.txt landmarks.ply; do
        [ -f "$tmp/o/$f" ] || continue
        echo "$name $mode $run $f $(sha256sum < "$tmp/o/$f" | cut -c1-16)" >> "$out"
      done
    done
  done
done
if [ -z "$check" ]; then cat "$out"; exit 0; fi
if diff "$check" "$out"; then echo "outputs unchanged ($(wc -l < "$out") files)"; exit 0; fi
echo "outputs CHANGED (diff above: < recorded, > now)"; exit 1
