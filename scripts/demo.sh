#!/usr/bin/env bash
# Installs dependencies, builds, and runs the main job on the built-in default source: `svslam
# run` (EKF SLAM over the stereo front end) on the rendered blimp flight (synthetic source: a
# 70 m loop at 25-30 m altitude, 1024x768, exact ground truth), then scores the trajectory and
# the elevation map against the exact terrain.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
mkdir -p out
./build/pipeline/svslam run --out out/run
./build/pipeline/svslam eval-trajectory --gt out/run/groundtruth_kitti.txt \
  --est out/run/trajectory_kitti.txt --cov out/run/pose_covariance.txt --segments 10,20,40 --step 1
./build/pipeline/svslam eval-dem --dem out/run/dem.tif --gt out/run/groundtruth_dem.tif
echo "wrote out/run/: trajectory_kitti.txt trajectory_tum.txt pose_covariance.txt landmarks.ply" \
  "dem.tif ortho.tif ortho.png dem_hillshade.png groundtruth_dem.tif stats.json"
