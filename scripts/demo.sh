#!/usr/bin/env bash
# Installs dependencies, builds, and runs the main job on the built-in default source: dense
# disparity of the built-in synthetic pair, scored against its exact ground truth.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
mkdir -p out
./build/pipeline/svslam disparity --threads 2 --repeat 5 --out out/disparity.pfm --sigma out/sigma.pfm --color out/disparity.png
echo "wrote out/disparity.pfm, out/sigma.pfm, out/disparity.png"
