#!/usr/bin/env bash
# Installs dependencies, builds, and runs the main job on the built-in default source: `svslam
# run` (EKF SLAM over the stereo front end) on the rendered blimp flight (synthetic source: a
# 70 m loop at 25-30 m altitude, 1024x768, exact ground truth), then scores the trajectory.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
mkdir -p out
./build/pipeline/svslam run --out out/run
./build/pipeline/svslam eval-trajectory --gt out/run/groundtruth_kitti.txt \
  --est out/run/trajectory_kitti.txt --cov out/run/pose_covariance.txt --segments 10,20,40 --step 1
echo "wrote out/run/: trajectory_kitti.txt trajectory_tum.txt pose_covariance.txt landmarks.ply stats.json"
