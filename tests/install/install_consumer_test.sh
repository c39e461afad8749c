#!/usr/bin/env bash
# `cmake --install` into a temporary prefix, then a process outside svslam built against the
# installed files only (tests/install_consumer: find_package(svslam_lcm_types)) decodes a pose
# the installed `svslam run` published into an LCM log, with the C++ and the C types.
# Usage: install_consumer_test.sh BUILD_DIR SOURCE_DIR JAR_EXPECTED(0|1)
set -euo pipefail
build=$1 src=$2 want_jar=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix
fail() { echo "FAIL: $*"; exit 1; }

cmake --install "$build" --prefix "$prefix" > "$tmp/install.txt" || { cat "$tmp/install.txt"; fail "cmake --install"; }
# Nothing may land outside the prefix (an absolute DESTINATION would write to the host).
if grep -v -e "-- Install configuration" -e "$prefix/" "$tmp/install.txt"; then
  fail "files installed outside $prefix"
fi

expected=(bin/svslam lib/systemd/system/svslam.service share/svslam/svslam.yaml
          lib/cmake/svslam_lcm_types/svslam_lcm_typesConfig.cmake lib/pkgconfig/svslam_lcm_types.pc
          lib/libsvslam_lcm_c.a)
for t in pose_t stats_t map_summary_t map_tile_t pose_correction_t altitude_t command_t command_status_t \
         stereo_image_t; do
  expected+=("include/svslam/lcm/svslam_lcm/$t.hpp" "include/svslam/lcm/svslam_lcm_$t.h")
done
[ "$want_jar" = 1 ] && expected+=(share/java/svslam_lcm_types.jar)
for f in "${expected[@]}"; do
  [ -f "$prefix/$f" ] || fail "cmake --install did not lay out $f"
done
[ -x "$prefix/bin/svslam" ] || fail "bin/svslam is not executable"
echo "layout OK: ${#expected[@]} files"

# pkg-config finds the installed headers.
cflags=$(PKG_CONFIG_PATH="$prefix/lib/pkgconfig" pkg-config --cflags svslam_lcm_types)
[ -f "$(echo "$cflags" | sed 's/^-I\([^ ]*\).*/\1/')/svslam_lcm/pose_t.hpp" ] ||
  fail "pkg-config --cflags svslam_lcm_types gives '$cflags'"

# The consumer, configured with the installed prefix only (a fresh CMake cache, no launcher).
env -u CMAKE_PREFIX_PATH cmake -S "$src/tests/install_consumer" -B "$tmp/consumer" \
  -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" > "$tmp/configure.txt" 2>&1 ||
  { cat "$tmp/configure.txt"; fail "configuring the consumer"; }
cmake --build "$tmp/consumer" > "$tmp/build.txt" 2>&1 || { cat "$tmp/build.txt"; fail "building the consumer"; }

# A short run of the installed binary publishes its poses into a log; the consumer replays it.
"$prefix/bin/svslam" run --source synthetic:width=320,height=240,frames=3 \
  --lcm-url "file://$tmp/run.lcmlog?mode=w" --out "$tmp/out" > "$tmp/run.txt" 2>&1 ||
  { cat "$tmp/run.txt"; fail "installed svslam run"; }
"$tmp/consumer/svslam_pose_consumer" "file://$tmp/run.lcmlog?speed=0" > "$tmp/pose.txt" ||
  fail "the consumer decoded no pose"
cat "$tmp/pose.txt"
grep -q "^pose seq 0 utime [0-9]* frame svslam_world position " "$tmp/pose.txt" ||
  fail "unexpected consumer output"
grep -q "^C decoder agrees$" "$tmp/pose.txt" || fail "the C types were not checked"
echo "OK"
