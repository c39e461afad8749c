#!/usr/bin/env bash
# Installs dependencies, builds and runs every test (ctest), then a 60-second soak (memory). SANITIZE=1 builds into
# build-asan/ with AddressSanitizer + UndefinedBehaviorSanitizer instead; TSAN=1 builds the
# threaded tests into build-tsan/ with ThreadSanitizer and runs those.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
if [ "${TSAN:-0}" = "1" ]; then
  # ThreadSanitizer over the tests that run threads: the pipeline (edges, runner, svslam run
  # threaded vs sequential, service, LCM between processes, loop closing's back-end thread), the
  # executor and the LCM transport.
  BUILD_DIR=${BUILD_DIR:-build-tsan}
  source scripts/ccache_env.sh
  targets=(svslam pipeline_realtime_pipeline_test pipeline_executor_test pipeline_service_test
           pipeline_lcm_pipeline_test drivers_lcm_transport_test drivers_lcm_source_test
           pipeline_cli_loop_test)
  # No precompiled headers here: eight targets gain little from them.
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" \
        -DSVSLAM_WERROR=ON -DSVSLAM_TSAN=ON \
        -DSVSLAM_BUILD_BENCH=OFF -DSVSLAM_PCH=OFF "${ccache_args[@]}"
  cmake --build "$BUILD_DIR" -j "$(nproc)" --target "${targets[@]}"
  export TSAN_OPTIONS=${TSAN_OPTIONS:-halt_on_error=1:second_deadlock_stack=1:suppressions=$PWD/tests/tsan.supp}
  regex="^($(IFS='|'; echo "${targets[*]:1}"))\\."
  ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$(nproc)" -R "$regex"
  exit 0
fi
if [ "${SANITIZE:-0}" = "1" ]; then export BUILD_DIR=${BUILD_DIR:-build-asan}; fi
BUILD_DIR=${BUILD_DIR:-build}
export BUILD_DIR
bash scripts/build.sh
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
exclude=()
if [ "${SANITIZE:-0}" = "1" ]; then
  # Under the sanitizers, not the slowest flights whose code other tests take through ASan +
  # UBSan (100-200 s each there; the release run above checks every one of them): the two
  # mono bit-identity checks that fly the same flight twice (MonoStart.FlightUpToScale... keeps
  # the mono start, camera loss the bearing-only flight), the altimeter-scaled mono start, the
  # left-camera-only mono flight, the frozen right camera (the black one stays) and the CLI's
  # two-lap loop (ThreadSanitizer runs it below; loop_closer_test keeps the back end).
  slow=(slam_mono_start_test.MonoStart.RightImageIsNeverUsed
        slam_mono_start_test.MonoStartAltitude.MetricMapFromTheAltimeterWithoutAStereoPair
        slam_mono_mode_test.MonoMode.RightImageAfterTheFirstPairIsNotUsed
        slam_mono_mode_test.MonoMode.FlightFromTheLeftCameraWithinOnePercentAfterSim3
        slam_camera_loss_test.CameraLoss.RightCameraFrozenFrom40To60ThenBack
        pipeline_cli_loop_test.CliLoop.TwoLapsCloseLoopsAndWriteTheOptimisedTrajectory)
  exclude=(-E "^($(IFS='|'; echo "${slow[*]//./\.}"))$")
fi
ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$(nproc)" "${exclude[@]}"
if [ "${SANITIZE:-0}" != "1" ]; then
  # A one-minute soak as fast as possible: resident memory flat within 5 % after the warm-up
  # (docs/pipeline.md "Soak"; the hour-long runs are scripts/soak.sh 3600).
  SVSLAM_BIN="$BUILD_DIR/pipeline/svslam" bash scripts/soak.sh 60 fast
fi
