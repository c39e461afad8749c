#!/usr/bin/env bash
# The loop-closing figures of docs/loop_closing.md: synthetic blimp flights at 25-30 m over
# terrain seed 1 (vocabularies trained on terrain seed 99 at the same resolution), each run
# without loop closing, with loop closing and no feedback (loop.feedback: false: only the outputs
# are corrected) and with feedback (the default). Prints one line per run: the online trajectory
# (trajectory_kitti.txt: what was published) and the optimised one (trajectory_optimized_kitti.txt),
# ATE and final position error against ground truth with --align none, loops accepted, loops
# between camera centres more than 25 m apart (false), feedback moves; then the elevation map's
# height RMSE and coverage against groundtruth_dem.tif (svslam eval-dem): dem.tif (online) and
# dem_optimized.tif (re-placed with the corrected trajectory).
# Usage: scripts/loop_figures.sh [--quick] [BUILD_DIR]   (--quick: the 270 m loop at 512x384 only)
set -euo pipefail
quick=0
if [[ "${1:-}" == "--quick" ]]; then quick=1; shift; fi
build=${1:-build}
svslam="$build/pipeline/svslam"
work=${LOOP_FIGURES_DIR:-/tmp/svslam_loop_figures}
mkdir -p "$work"

vocabulary() {  # WIDTH HEIGHT -> path
  local f="$work/voc_$1.svvoc"
  if [[ ! -s "$f" ]]; then
    "$svslam" train-vocabulary --source \
      "synthetic:seed=99,frames=100,loop_length_m=300,width=$1,height=$2" --frames 100 \
      --out "$f" >/dev/null
  fi
  echo "$f"
}


score() {  # RUN_DIR TRAJECTORY -> "ate final"
  "$svslam" eval-trajectory --align none --gt "$1/groundtruth_kitti.txt" --est "$1/$2" \
    > "$1/eval_$2.json"
  python3 - "$1/eval_$2.json" <<'EOF'
import json, sys
d = json.load(open(sys.argv[1]))
print("%.4f %.4f" % (d["ate_rmse_m"], d["final_pos_err_m"]))
EOF
}

dem_score() {  # RUN_DIR DEM_FILE -> "rmse coverage" ("- -" when the file is absent)
  if [[ ! -s "$1/$2" ]]; then echo "- -"; return; fi
  "$svslam" eval-dem --dem "$1/$2" --gt "$1/groundtruth_dem.tif" > "$1/eval_$2.json"
  python3 - "$1/eval_$2.json" <<'EOF'
import json, sys
d = json.load(open(sys.argv[1]))
print("%.4f %.4f" % (d["rmse_m"], d["coverage"]))
EOF
}

false_loops() {  # RUN_DIR -> loops whose ground-truth camera centres are > 25 m apart
  python3 - "$1" <<'EOF'
import json, sys
d = sys.argv[1]
gt = [list(map(float, l.split())) for l in open(d + "/groundtruth_kitti.txt")]
loop = json.load(open(d + "/stats.json")).get("loop", {})
bad = 0
for a in loop.get("accepted", []):
    p, q = gt[a["query_frame"]], gt[a["candidate_frame"]]
    dist = sum((p[i] - q[i]) ** 2 for i in (3, 7, 11)) ** 0.5
    bad += dist > 25.0
print(len(loop.get("accepted", [])), bad, loop.get("feedback_moves", 0))
EOF
}

flight() {  # NAME WIDTH HEIGHT SOURCE_EXTRA
  local name=$1 w=$2 h=$3 extra=$4
  # LOOP_FIGURES_ONLY=NAME runs that flight alone; LOOP_FIGURES_MODES the modes (default all).
  if [[ -n "${LOOP_FIGURES_ONLY:-}" && "$LOOP_FIGURES_ONLY" != "$name" ]]; then return; fi
  local voc; voc=$(vocabulary "$w" "$h")
  local src="synthetic:width=$w,height=$h,$extra"
  for mode in ${LOOP_FIGURES_MODES:-off nofeedback feedback}; do
    local out="$work/$name-$mode" cfg="$work/$name-$mode.yaml"
    case $mode in
      off) printf 'loop:\n  enabled: false\n' > "$cfg" ;;
      nofeedback) printf 'loop:\n  enabled: true\n  vocabulary: %s\n  feedback: false\n' "$voc" > "$cfg" ;;
      feedback) printf 'loop:\n  enabled: true\n  vocabulary: %s\n' "$voc" > "$cfg" ;;
    esac
    "$svslam" run --config "$cfg" --source "$src" --out "$out" >/dev/null 2>"$out.err" ||
      { echo "$name $mode: svslam run failed"; cat "$out.err"; exit 1; }
    local online optimised="- -" loops="0 0 0"
    online=$(score "$out" trajectory_kitti.txt)
    if [[ $mode != off ]]; then
      optimised=$(score "$out" trajectory_optimized_kitti.txt)
      loops=$(false_loops "$out")
    fi
    local dem dem_opt
    dem=$(dem_score "$out" dem.tif)
    dem_opt=$(dem_score "$out" dem_optimized.tif)
    printf '%-14s %-10s online ATE/final %s  optimised ATE/final %s  loops/false/moves %s  DEM rmse/coverage %s  optimised %s\n' \
      "$name" "$mode" "$online" "$optimised" "$loops" "$dem" "$dem_opt"
  done
}

flight loop270_512 512 384 "frames=400,loop_length_m=270"
if [[ $quick == 0 ]]; then
  flight laps3_512 512 384 "frames=1200,loop_frames=400,loop_length_m=333"
  # Three and a half laps: the flight ends half a lap from the start, where the filter's drift is
  # not already closed by the first frame's anchors.
  flight laps3half_512 512 384 "frames=1400,loop_frames=400,loop_length_m=333"
  flight loop270_1024 1024 768 "frames=400,loop_length_m=270"
  flight lookalike_512 512 384 "frames=800,loop_frames=400,loop_length_m=270,texture_period_m=40"
fi
