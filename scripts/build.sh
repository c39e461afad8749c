#!/usr/bin/env bash
# Configures and builds svslam into BUILD_DIR (default build/). SANITIZE=1 adds ASan + UBSan.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
extra=()
if [ "${SANITIZE:-0}" = "1" ]; then extra+=(-DSVSLAM_SANITIZE=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSVSLAM_BUILD_BENCH=OFF); fi
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release -DSVSLAM_WERROR=ON "${extra[@]}"
cmake --build "$BUILD_DIR" -j "$(nproc)"
