#!/usr/bin/env bash
# Camera loss on the rendered blimp flight (100 frames): the right camera black from frame 40 to
# the end, and frozen from 40 to 60 then back, against the stereo EKF on the same flight.
#   scripts/camera_loss_figures.sh [SPEC...]
# SPEC defaults to the issue's 1024 x 768 flight ("synthetic") and seeds 1-4 at 512 x 384; each
# line: final position error and its ratio to stereo, share of frames within 2 sigma, mean NEES,
# mono frames, landmarks initialised from bearings. About 4 minutes a 1024 x 768 flight.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=./build/tests/slam_camera_loss_test
[ -x "$bin" ] || { echo "build first: $bin missing" >&2; exit 1; }
specs=("$@")
if [ ${#specs[@]} -eq 0 ]; then
  specs=(synthetic)
  for s in 1 2 3 4; do specs+=("synthetic:width=512,height=384,seed=$s"); done
fi
for spec in "${specs[@]}"; do
  echo "== $spec"
  SVSLAM_CAMERA_LOSS_SPEC="$spec" "$bin" 2>&1 | grep -E "camera loss,|Failure" || true
done
