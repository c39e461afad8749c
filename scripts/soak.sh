#!/usr/bin/env bash
# Soak test: replays a preloaded synthetic flight in a loop (`svslam run --preload --loops`)
# through the threaded pipeline for DURATION seconds, paced at 10 Hz as a camera and/or as fast as
# possible, sampling the resident memory (VmRSS) every SOAK_SAMPLE_S seconds, and reading every
# published frame's capture-to-publish latency (latency.txt) and the drops (stats.json).
#   scripts/soak.sh DURATION_S [paced|fast|both] [SOURCE]
# Default source: the 512x384 synthetic blimp flight of 100 frames with loop_frames=100 (its frame
# 100 would be its frame 0, so the replays run on without a jump).
# Prints one JSON line per mode:
#   rss_warm_kib  RSS at the end of the warm-up (the first max(10 s, DURATION / 10));
#   rss_min_kib, rss_max_kib, rss_last_kib  over the samples after the warm-up;
#   rss_growth_pct  the largest deviation of a later sample from rss_warm_kib, percent;
#   latency first/last: p50 and p99 (ms) of the first and the last sixth of the published frames
#   (10 minutes each in an hour's run); frames published and dropped.
# Exit 1 when a mode's rss_growth_pct exceeds SOAK_MAX_GROWTH_PCT (default 5); with
# SOAK_CHECK=all also when the paced mode drops a frame or its last p99 exceeds the first by more
# than 20 %. CI runs `scripts/soak.sh 60 fast` (memory only).
set -euo pipefail
cd "$(dirname "$0")/.."
duration=${1:?usage: scripts/soak.sh DURATION_S [paced|fast|both] [SOURCE]}
modes=${2:-both}
src=${3:-synthetic:width=512,height=384,frames=100,loop_frames=100}
bin=${SVSLAM_BIN:-./build/pipeline/svslam}
sample_s=${SOAK_SAMPLE_S:-5}
max_growth=${SOAK_MAX_GROWTH_PCT:-5}
case "$modes" in both) modes="paced fast" ;; paced | fast) ;; *)
  echo "soak.sh: mode must be paced, fast or both" >&2
  exit 2
  ;;
esac
if ! [[ "$duration" =~ ^[0-9]+$ ]] || [ "$duration" -lt 20 ]; then
  echo "soak.sh: DURATION_S must be a whole number of seconds >= 20" >&2
  exit 2
fi
[ -x "$bin" ] || {
  echo "soak.sh: $bin not found (build first, or set SVSLAM_BIN)" >&2
  exit 2
}
tmp=$(mktemp -d)
pid=""
trap '[ -n "$pid" ] && kill "$pid" 2> /dev/null; rm -rf "$tmp"' EXIT
warm=$((duration / 10 > 10 ? duration / 10 : 10))
status=0

# p50 and p99 (nearest rank) of the numbers on stdin: "p50 p99".
percentiles() {
  sort -g | awk '{v[NR] = $1} END {
    if (NR == 0) { print "null null"; exit }
    i50 = int((NR * 50 + 99) / 100); i99 = int((NR * 99 + 99) / 100)
    print v[i50 < 1 ? 1 : i50], v[i99 < 1 ? 1 : i99] }'
}

for mode in $modes; do
  out="$tmp/$mode"
  printf 'pipeline:\n  progress_period_s: 1\n  latency_log: true\n' > "$tmp/cfg.yaml"
  rate=()
  loops=1000000
  if [ "$mode" = paced ]; then
    rate=(--rate 10)
    loops=$((duration / 10 + 10))  # 100-frame replays at 10 Hz, with room to spare
  fi
  "$bin" run --source "$src" --config "$tmp/cfg.yaml" --preload --loops "$loops" "${rate[@]}" \
    --threads 2 --out "$out" > "$tmp/$mode.json" 2> "$tmp/$mode.err" &
  pid=$!
  # The clock starts with the first progress line (the flight is in memory, frames flow).
  while kill -0 "$pid" 2> /dev/null && ! grep -q 'progress:' "$tmp/$mode.err"; do sleep 0.5; done
  start=$(date +%s)
  : > "$tmp/$mode.rss"
  while kill -0 "$pid" 2> /dev/null; do
    now=$(date +%s)
    [ $((now - start)) -ge "$duration" ] && break
    rss=$(awk '/VmRSS/ {print $2}' "/proc/$pid/status" 2> /dev/null || true)
    [ -n "$rss" ] && echo "$((now - start)) $rss" >> "$tmp/$mode.rss"
    sleep "$sample_s"
  done
  kill -TERM "$pid" 2> /dev/null || true
  code=0
  wait "$pid" || code=$?
  pid=""
  if [ "$code" -ne 0 ]; then
    echo "soak.sh: svslam run ($mode) exited $code:" >&2
    tail -5 "$tmp/$mode.err" >&2
    exit 1
  fi
  read -r rss_warm rss_min rss_max rss_last growth < <(awk -v w="$warm" '
    $1 < w {warm = $2; next}
    { if (warm == "") warm = $2
      if (min == "" || $2 < min) min = $2
      if ($2 > max) max = $2
      last = $2
      d = ($2 - warm) / warm * 100; if (d < 0) d = -d; if (d > g) g = d }
    END { if (warm == "" || last == "") print "null null null null null";
          else printf "%d %d %d %d %.2f\n", warm, min, max, last, g }' "$tmp/$mode.rss")
  n=$(wc -l < "$out/latency.txt")
  sixth=$((n / 6 > 1 ? n / 6 : 1))
  read -r first50 first99 < <(head -n "$sixth" "$out/latency.txt" | awk '{print $2}' | percentiles)
  read -r last50 last99 < <(tail -n "$sixth" "$out/latency.txt" | awk '{print $2}' | percentiles)
  dropped=$(grep -o '"frames_dropped": [0-9]*' "$out/stats.json" | head -1 | awk '{print $2}' || true)
  echo "{\"mode\": \"$mode\", \"duration_s\": $duration, \"source\": \"$src\"," \
    "\"rss_warm_kib\": $rss_warm, \"rss_min_kib\": $rss_min, \"rss_max_kib\": $rss_max," \
    "\"rss_last_kib\": $rss_last, \"rss_growth_pct\": $growth, \"frames\": $n," \
    "\"dropped\": ${dropped:-null}, \"latency_first_p50_ms\": $first50," \
    "\"latency_first_p99_ms\": $first99, \"latency_last_p50_ms\": $last50," \
    "\"latency_last_p99_ms\": $last99}"
  if [ "$growth" = null ] || awk -v g="$growth" -v m="$max_growth" 'BEGIN {exit !(g > m)}'; then
    echo "soak.sh: $mode: resident memory moved ${growth} % after the warm-up (limit $max_growth %)" >&2
    status=1
  fi
  if [ "${SOAK_CHECK:-memory}" = all ] && [ "$mode" = paced ]; then
    if [ "${dropped:-1}" != 0 ] ||
      awk -v a="$first99" -v b="$last99" 'BEGIN {exit !(b > 1.2 * a)}'; then
      echo "soak.sh: paced: dropped ${dropped:-?} frames, p99 $first99 -> $last99 ms" >&2
      status=1
    fi
  fi
done
exit $status
