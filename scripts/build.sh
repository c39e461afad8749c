#!/usr/bin/env bash
# Configures and builds svslam into BUILD_DIR (default build/). SANITIZE=1 adds ASan + UBSan
# (line tables only, -g1: enough for the sanitizers' stack traces, and a fraction of the full
# debug information to compile and link).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
# shellcheck source=scripts/ccache_env.sh
source scripts/ccache_env.sh
extra=("${ccache_args[@]}")
if [ "${SANITIZE:-0}" = "1" ]; then
  extra+=(-DSVSLAM_SANITIZE=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo
          "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" -DSVSLAM_BUILD_BENCH=OFF)
fi
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release -DSVSLAM_WERROR=ON "${extra[@]}"
cmake --build "$BUILD_DIR" -j "$(nproc)"
