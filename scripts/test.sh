#!/usr/bin/env bash
# Installs dependencies, builds and runs every test (ctest). SANITIZE=1 builds into
# build-asan/ with AddressSanitizer + UndefinedBehaviorSanitizer instead.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
if [ "${SANITIZE:-0}" = "1" ]; then export BUILD_DIR=${BUILD_DIR:-build-asan}; fi
BUILD_DIR=${BUILD_DIR:-build}
export BUILD_DIR
bash scripts/build.sh
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$(nproc)"
