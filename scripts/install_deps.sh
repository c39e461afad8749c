#!/usr/bin/env bash
# Installs what svslam needs to build and test on Debian 12 (run as root).
set -euo pipefail
export DEBIAN_FRONTEND=noninteractive
APT="apt-get -o DPkg::Lock::Timeout=600 -y -q"
packages=(build-essential cmake pkg-config git
          libopencv-dev libeigen3-dev libgtest-dev libgmock-dev libbenchmark-dev
          libyaml-cpp-dev
          # LLVM linker: used when present, links the test executables several times faster
          lld
          # build cache: the build scripts compile through it when present (scripts/ccache_env.sh)
          ccache
          # fuzzing (scripts/fuzz.sh): clang, and libFuzzer with the sanitizer runtimes (only
          # recommended by clang, and recommends are not installed here)
          clang libclang-rt-14-dev
          # elevation map files: GeoTIFF writer/reader (drivers/files/dem_files.cpp)
          libgdal-dev
          # loop closing back end: pose-graph optimisation (src/loop/pose_graph.cpp, Ceres >= 2.1;
          # optional: without it svslam_graph and its test and benchmark are not built)
          libceres-dev
          # real-time pipeline and service: SPSC queues, LCM (lcm-gen, glib for lcm.pc),
          # sd_notify, cameras (libcamera, v4l-utils for real hardware), iproute2 + util-linux
          # for the multicast test in a private network namespace
          libreaderwriterqueue-dev liblcm-dev liblcm-bin libglib2.0-dev libsystemd-dev
          libcamera-dev v4l-utils iproute2 util-linux systemd
          # LCM types for Java (svslam_lcm_types.jar, lcm-spy; optional: without a JDK or lcm.jar
          # the jar is not built and its test skips): JDK, LCM's Java library, lcm-spy's charts
          default-jdk-headless liblcm-java libjchart2d-java
          # cross step of .ci/run (scripts/cross_test_arm.sh): ARM cross compilers, qemu-user
          # and GoogleTest's sources to build for the target
          g++-aarch64-linux-gnu g++-arm-linux-gnueabihf qemu-user-static googletest)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  $APT update
  $APT install --no-install-recommends "${missing[@]}"
fi
