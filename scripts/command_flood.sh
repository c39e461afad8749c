#!/usr/bin/env bash
# The latency cost of an LCM command flood (docs/lcm.md "Command floods"): runs
# build/bench/bench_command_flood (quiet and flooded `svslam run` replays, alternating) inside a
# private network namespace with a loopback multicast route, so that it needs no root and
# touches no host route.
#   scripts/command_flood.sh [frames=150] [rate_hz=10] [repeats=3] [flood_hz=1000] [size=512x384]
# Prints one line per run (end-to-end latency p50/p99/max of stats.json, drops, messages sent)
# and the ratio of the median p99s against the budget (flood <= 1.5 x quiet + 2 ms).
set -euo pipefail
cd "$(dirname "$0")/.."
bench=${BENCH:-./build/bench/bench_command_flood}
[ -x "$bench" ] || { echo "command_flood.sh: build $bench first (cmake --build build --target bench_command_flood)" >&2; exit 2; }
exec unshare -rn sh -c 'ip link set lo up && ip route add 239.0.0.0/8 dev lo && exec "$0" "$@"' \
  "$bench" "$@"
