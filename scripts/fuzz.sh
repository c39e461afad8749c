#!/usr/bin/env bash
# Runs one libFuzzer harness of tests/fuzz for real (docs/pipeline.md "Fuzzing").
#
#   scripts/fuzz.sh list                  the harnesses
#   scripts/fuzz.sh NAME SECONDS [-merge] [LIBFUZZER_FLAG...]
#
# Configures build-fuzz/ with clang (SVSLAM_FUZZ=ON: libraries with the fuzzer's coverage, ASan
# and UBSan), builds fuzz_NAME and runs it for SECONDS on a scratch copy of the seed corpus
# tests/fuzz/corpus/NAME (build-fuzz/work/NAME), -timeout=10 s per input. Crash, timeout and
# leak inputs go to build-fuzz/crashes/NAME/. -merge merges the new interesting inputs of the
# run back into tests/fuzz/corpus/NAME (libFuzzer -merge=1: only inputs that add coverage).
# Prints one summary line (name, seconds, execs, execs/s, corpus size, crashes) and exits
# non-zero when an input crashed, hung or leaked. JOBS (default 2) sets the build parallelism.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
harnesses() {
  sed -n 's/^ *\([a-z_0-9]*\):svslam_[a-z]*)\{0,1\}$/\1/p' tests/fuzz/CMakeLists.txt
}
if [ "${1:-}" = "list" ]; then
  harnesses
  exit 0
fi
if [ $# -lt 2 ] || ! [[ $2 =~ ^[0-9]+$ ]]; then
  echo "usage: scripts/fuzz.sh list | NAME SECONDS [-merge] [LIBFUZZER_FLAG...]" >&2
  exit 2
fi
name=$1
seconds=$2
shift 2
merge=0
if [ "${1:-}" = "-merge" ]; then
  merge=1
  shift
fi
if ! harnesses | grep -qx "$name"; then
  echo "fuzz.sh: no harness '$name' (scripts/fuzz.sh list)" >&2
  exit 2
fi
if ! ls /usr/lib/llvm-*/lib/clang/*/lib/linux/libclang_rt.fuzzer-x86_64.a > /dev/null 2>&1 ||
   ! command -v clang++ > /dev/null; then
  echo "fuzz.sh: clang with libFuzzer is needed (apt-get install clang; scripts/install_deps.sh)" >&2
  exit 2
fi

build=build-fuzz
# shellcheck source=scripts/ccache_env.sh
source scripts/ccache_env.sh
CC=clang CXX=clang++ cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -DNDEBUG" -DSVSLAM_FUZZ=ON \
  -DSVSLAM_BUILD_TESTS=OFF -DSVSLAM_BUILD_BENCH=OFF "${ccache_args[@]}" > "$build.configure.log" ||
  { cat "$build.configure.log"; exit 1; }
cmake --build "$build" -j "${JOBS:-2}" --target "fuzz_$name"

work="$root/$build/work/$name"
crashes="$root/$build/crashes/$name"
rm -rf "$work"
mkdir -p "$work" "$crashes"
cp "tests/fuzz/corpus/$name"/* "$work"/
log="$root/$build/fuzz_$name.log"
marker="$root/$build/fuzz_$name.start"
touch "$marker"
set +e
"$build/tests/fuzz/fuzz_$name" "$work" -max_total_time="$seconds" -timeout=10 \
  -artifact_prefix="$crashes/" -print_final_stats=1 "$@" > "$log" 2>&1
rc=$?
set -e
if [ "$merge" = "1" ] && [ "$rc" = "0" ]; then
  "$build/tests/fuzz/fuzz_$name" -merge=1 "tests/fuzz/corpus/$name" "$work" >> "$log" 2>&1
fi
execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
secs=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
ncrash=$(find "$crashes" -type f -newer "$marker" | wc -l)
corpus=$(find "$work" -type f | wc -l)
echo "fuzz $name: ${seconds} s, ${execs:-0} execs, ${secs:-0} execs/s, corpus $corpus files," \
     "crashes $ncrash (exit $rc; log $log)"
exit "$rc"
