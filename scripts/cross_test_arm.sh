#!/usr/bin/env bash
# Cross-builds svslam for ARM and runs its unit tests under qemu-user, so the NEON backend is held
# to the scalar reference (and the rest of the library is exercised on a 64-bit ARM ABI) without
# ARM hardware. This is the SVSLAM_CROSS step of .ci/run.
#
#   scripts/cross_test_arm.sh [aarch64] [armhf]     (default: both)
#
# aarch64  svslam_src + every unit test whose sources depend on svslam_src alone (found below),
#          run through ctest under qemu-aarch64-static (the toolchain's
#          CMAKE_CROSSCOMPILING_EMULATOR).
# armhf    svslam_src + simd_stereo_kernels_test, run under qemu-arm-static; this proves the
#          32-bit NEON build compiles and is bit-exact. SVSLAM_CROSS_ARMHF_ALL=1 builds and runs
#          the same test set as aarch64 instead.
#
# Not cross-built: drivers/, pipeline/, the svslam CLI, bench/, svslam_graph (Ceres) and every
# test that includes drivers/, pipeline/, lcm/, OpenCV or Ceres headers or loop/pose_graph.hpp
# (SVSLAM_BUILD_TOOLS=OFF: no OpenCV, yaml-cpp, LCM or Ceres for the target is installed; README
# "Cross-building for ARM" has the recipe to add them).
# Speed under qemu means nothing: never time NEON kernels here (run bench/ on a real board).
#
# Needs (Debian 12; scripts/install_deps.sh installs them):
#   apt-get install g++-aarch64-linux-gnu g++-arm-linux-gnueabihf qemu-user-static \
#                   googletest libeigen3-dev cmake
# binfmt_misc is not needed: the emulator is called explicitly.
# Build trees go to $SVSLAM_CROSS_BUILD_ROOT (default build-cross/ in this checkout, git-ignored).
# JOBS (default nproc) sets build and ctest parallelism.
set -euo pipefail

src_dir="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# shellcheck source=scripts/ccache_env.sh
source "$src_dir/scripts/ccache_env.sh"
# Default build trees live in this checkout (build-cross/, ignored by git): a tree shared between
# checkouts would hold a CMake cache of another source folder and fail to configure.
build_root="${SVSLAM_CROSS_BUILD_ROOT:-$src_dir/build-cross}"
jobs="${JOBS:-$(nproc)}"
targets=("$@")
[[ ${#targets[@]} -eq 0 ]] && targets=(aarch64 armhf)

# Tests left out although they build with svslam_src alone: target -> reason (printed).
# (None at present: the whole svslam_src-only set takes well under a minute under qemu-aarch64.)
declare -A slow_skip=()

# Sources of test target $1, as listed in tests/CMakeLists.txt (paths relative to tests/).
test_sources() {
  sed -n "s/^[[:space:]]*svslam_test($1[[:space:]]\{1,\}\(.*\))[[:space:]]*$/\1/p" \
    "$src_dir/tests/CMakeLists.txt"
}

# Prints the first include of drivers/, pipeline/, lcm/, OpenCV or Ceres (directly, or through
# loop/pose_graph.hpp, whose code is in svslam_graph) in the sources of test $1 or in the
# test-local headers they include (one level); nothing if the test needs svslam_src alone.
foreign_include() {
  local f dir h files=()
  for f in $(test_sources "$1"); do
    [[ -f "$src_dir/tests/$f" ]] || continue
    files+=("$src_dir/tests/$f")
    dir="$(dirname "$src_dir/tests/$f")"
    for h in $(sed -n 's/^#include "\([^"/]*\)".*/\1/p' "$src_dir/tests/$f"); do
      [[ -f "$dir/$h" ]] && files+=("$dir/$h")
    done
  done
  [[ ${#files[@]} -eq 0 ]] && return 0
  grep -hoE '^#include [<"]((drivers|pipeline|lcm|opencv2|ceres)/[^">]*|loop/pose_graph[.]hpp)' \
    "${files[@]}" |
    head -n 1 | sed 's/^#include [<"]//' || true
}

check_tools() {
  local cxx="$1" qemu="$2"
  if ! command -v "$cxx" > /dev/null; then
    echo "missing $cxx; install: apt-get install g++-${cxx%-g++}" >&2
    return 1
  fi
  if ! command -v "$qemu" > /dev/null; then
    echo "missing $qemu; install: apt-get install qemu-user-static" >&2
    return 1
  fi
  if [[ ! -f /usr/src/googletest/CMakeLists.txt ]]; then
    echo "missing /usr/src/googletest; install: apt-get install googletest" >&2
    return 1
  fi
}

failed=()
summary=()
total_start=$SECONDS
for t in "${targets[@]}"; do
  case "$t" in
    aarch64)
      toolchain=aarch64-linux-gnu.cmake; cxx=aarch64-linux-gnu-g++; qemu=qemu-aarch64-static
      all_tests=1 ;;
    armhf)
      toolchain=armhf-linux-gnueabihf.cmake; cxx=arm-linux-gnueabihf-g++; qemu=qemu-arm-static
      all_tests="${SVSLAM_CROSS_ARMHF_ALL:-0}" ;;
    *) echo "unknown target '$t' (aarch64 or armhf)" >&2; exit 2 ;;
  esac
  check_tools "$cxx" "$qemu" || exit 2
  start=$SECONDS
  build="$build_root/$t"
  mkdir -p "$build_root"

  echo "== $t: configure in $build"
  if ! cmake -S "$src_dir" -B "$build" -DCMAKE_TOOLCHAIN_FILE="$src_dir/toolchains/$toolchain" \
      -DCMAKE_BUILD_TYPE=Release -DSVSLAM_WERROR=ON \
      -DSVSLAM_BUILD_TOOLS=OFF -DSVSLAM_BUILD_BENCH=OFF -DSVSLAM_BUILD_TESTS=ON "${ccache_args[@]}" \
      > "$build.configure.log" 2>&1; then
    cat "$build.configure.log" >&2
    failed+=("$t (configure)"); continue
  fi

  # Test targets defined in this configuration (tests/CMakeLists.txt adds one once its sources
  # exist, so tests that arrive later, e.g. slam_ekf_slam_test, are picked up by themselves).
  mapfile -t defined < <(cmake --build "$build" --target help |
    sed -n 's/^\.\.\. \([A-Za-z0-9_]*_test\)$/\1/p' | sort)
  selected=()
  if [[ "$all_tests" == 1 ]]; then
    for name in "${defined[@]}"; do
      inc="$(foreign_include "$name")"
      if [[ -n "$inc" ]]; then
        echo "   skip $name: includes $inc (drivers/pipeline/OpenCV/Ceres are not cross-built)"
      elif [[ -n "${slow_skip[$name]:-}" ]]; then
        echo "   skip $name: ${slow_skip[$name]}"
      else
        selected+=("$name")
      fi
    done
  else
    selected=(simd_stereo_kernels_test)
    echo "   $t runs simd_stereo_kernels_test only (SVSLAM_CROSS_ARMHF_ALL=1 for the full set;"
    echo "   the other tests are architecture-neutral C++ already run on aarch64 and x86-64)"
  fi
  echo "== $t: build svslam_src ${selected[*]}"
  if ! cmake --build "$build" -j "$jobs" --target svslam_src "${selected[@]}"; then
    failed+=("$t (build)"); continue
  fi

  echo "== $t: ${#selected[@]} test programs under $qemu (ctest)"
  regex="^($(IFS='|'; echo "${selected[*]}"))[.]"
  log="$build.ctest.log"
  # (ctest's "Start" lines are dropped from the screen; $log keeps everything.)
  if ctest --test-dir "$build" -R "$regex" --no-tests=error --output-on-failure -j "$jobs" \
      2>&1 | tee "$log" | sed '/^ *Start  *[0-9]*:/d'; then
    ok=1
  else
    ok=0
  fi
  # ctest counts GTEST_SKIP as passed: here those are the AVX2/AVX-512 instances of the backend
  # tests, which skip themselves on a CPU without those backends.
  n_pass="$(grep -cE '^ *[0-9]+/[0-9]+ Test +#[0-9]+: .* Passed ' "$log" || true)"
  n_skip="$(grep -cE '^ *[0-9]+/[0-9]+ Test +#[0-9]+: .*[*]{3}Skipped ' "$log" || true)"
  n_dis="$(grep -cE '^ *[0-9]+/[0-9]+ Test +#[0-9]+: .*Not Run [(]Disabled[)]' "$log" || true)"
  n_all="$(grep -cE '^ *[0-9]+/[0-9]+ Test +#[0-9]+: ' "$log" || true)"
  summary+=("$t: ${#selected[@]} programs, $n_all tests: $n_pass passed, $n_skip skipped (x86\
 backends), $n_dis disabled in the source, $((n_all - n_pass - n_skip - n_dis)) failed;\
 $((SECONDS - start)) s incl. build")
  if [[ "$ok" != 1 ]]; then
    failed+=("$t (tests)")
  fi
done

echo "== cross summary ($((SECONDS - total_start)) s)"
for s in "${summary[@]}"; do echo "   $s"; done
if [[ ${#failed[@]} -ne 0 ]]; then
  echo "cross build/test failed for: ${failed[*]}" >&2
  exit 1
fi
echo "cross tests passed for: ${targets[*]}"
