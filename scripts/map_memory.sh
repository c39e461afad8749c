#!/usr/bin/env bash
# Resident memory of `svslam run` while the map grows over a flight that repeats its loop:
# RSS (VmRSS) when the progress line first reports >= 300 poses and when it first reports >= 1000.
# The flight is longer than 1000 frames so that the second reading is taken while frames still
# flow: after its last frame a run builds and writes the map files, a transient that is not the
# map's footprint. The map only grows where new ground is seen, so after the first loop the
# memory should stay flat (issue: within 5 %).
#   scripts/map_memory.sh [SVSLAM_BINARY] [SOURCE]
# Default source: the 512x384 synthetic blimp flight, 1100 frames, a loop every 100 frames.
# Extra `svslam run` options: SVSLAM_RUN_ARGS (e.g. "--mode vo": no landmark map, so the
# growth left is the elevation map's and the rest of the pipeline's).
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-./build/pipeline/svslam}
src=${2:-synthetic:width=512,height=384,frames=1100,loop_frames=100}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf 'pipeline:\n  progress_period_s: 0.5\n' > "$tmp/cfg.yaml"
"$bin" run --source "$src" --config "$tmp/cfg.yaml" --out "$tmp/o" ${SVSLAM_RUN_ARGS:-} \
  > "$tmp/out.json" 2> "$tmp/err" &
pid=$!
rss300="" last_rss="" last_n=0 n300=0
while kill -0 "$pid" 2> /dev/null; do
  rss=$(awk '/VmRSS/ {print $2}' "/proc/$pid/status" 2> /dev/null || true)
  n=$(grep -o 'progress: [0-9]*' "$tmp/err" | tail -1 | awk '{print $2}' || true)
  n=${n:-0}
  if [ -n "$rss" ]; then
    if [ -z "$rss300" ] && [ "$n" -ge 300 ]; then rss300=$rss; n300=$n; fi
    if [ -z "$last_rss" ] && [ "$n" -ge 1000 ]; then last_rss=$rss; last_n=$n; fi
  fi
  sleep 0.2
done
wait "$pid"
if [ -z "$rss300" ] || [ -z "$last_rss" ]; then
  echo "map_memory.sh: the run ended before 1000 poses (see $tmp/err)" >&2
  trap - EXIT
  exit 1
fi
python3 - "$rss300" "$n300" "$last_rss" "$last_n" "$tmp/o/stats.json" <<'PY'
import json, sys
r300, n300, rl, nl = (int(x) for x in sys.argv[1:5])
stats = json.load(open(sys.argv[5]))
print(json.dumps({"poses_at_first": n300, "rss_first_kib": r300, "poses_at_last": nl,
                  "rss_last_kib": rl, "growth_pct": round(100.0 * (rl - r300) / r300, 2),
                  "map_tiles": stats["map"]["tiles"], "map_cell_bytes": stats["map"]["cell_bytes"],
                  "landmarks_in_map": stats.get("landmarks_in_map")}))
PY
