#!/usr/bin/env bash
# The Java types jar against messages encoded by svslam's C++ code: `svslam run` writes an LCM
# log; DecodeLog.java reads it with CLASSPATH=lcm.jar:svslam_lcm_types.jar, the way lcm-spy is
# run (docs/lcm.md), and picks each message's class by its type hash. Every message must be
# decoded, and the first pose must carry the seq, utime and position `svslam listen` prints.
# Usage: lcm_java_test.sh SVSLAM TYPES_JAR LCM_JAR. Exit 77 (skip) without java, javac or the jars.
set -euo pipefail
svslam=$1 types_jar=$2 lcm_jar=$3
here=$(cd "$(dirname "$0")" && pwd)
for tool in java javac; do
  command -v "$tool" > /dev/null || { echo "skip: no $tool (install default-jdk-headless)"; exit 77; }
done
[ -n "$types_jar" ] && [ -f "$types_jar" ] || { echo "skip: svslam_lcm_types.jar not built"; exit 77; }
[ -n "$lcm_jar" ] && [ -f "$lcm_jar" ] || { echo "skip: no lcm.jar (install liblcm-java)"; exit 77; }

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$svslam" run --source synthetic:width=320,height=240,frames=5 \
  --lcm-url "file://$tmp/run.lcmlog?mode=w" --out "$tmp/out" > "$tmp/run.txt" 2>&1 ||
  { cat "$tmp/run.txt"; echo "FAIL: svslam run"; exit 1; }

javac -nowarn -cp "$lcm_jar" -d "$tmp/classes" "$here/DecodeLog.java"
# lcm-spy's class path (docs/lcm.md); jchart2d only lets the type database load lcm-spy's own
# classes while it scans lcm.jar.
chart=/usr/share/java/jchart2d.jar
classpath="$lcm_jar:$types_jar:$tmp/classes"
[ -f "$chart" ] && classpath="$lcm_jar:$chart:$types_jar:$tmp/classes"
CLASSPATH="$classpath" java DecodeLog "$tmp/run.lcmlog" > "$tmp/all.txt"
grep "^msg " "$tmp/all.txt" | sed 's/^msg //' > "$tmp/java.txt"
sed 's/ seq.*//' "$tmp/java.txt" | sort | uniq -c

if grep -q " unknown$" "$tmp/java.txt"; then
  echo "FAIL: messages without a class in $types_jar:"; grep " unknown$" "$tmp/java.txt"; exit 1
fi
java_pose=$(grep -m1 "^SVSLAM_POSE svslam_lcm.pose_t " "$tmp/java.txt" || true)
[ -n "$java_pose" ] || { echo "FAIL: no pose decoded by Java"; exit 1; }
grep -q "^SVSLAM_STATS svslam_lcm.stats_t" "$tmp/java.txt" || { echo "FAIL: no stats decoded"; exit 1; }

# The same pose through svslam's own decoder.
"$svslam" listen --url "file://$tmp/run.lcmlog?speed=0" --count 1 --types pose \
  > "$tmp/listen.txt"
read -r seq utime x y z < <(python3 -c '
import json, sys
p = json.loads(open(sys.argv[1]).readline())
print(p["seq"], p["utime"], *("%.6f" % v for v in p["position"]))' "$tmp/listen.txt")
expected="SVSLAM_POSE svslam_lcm.pose_t seq $seq utime $utime position $x $y $z"
if [ "$java_pose" != "$expected" ]; then
  echo "FAIL: Java decoded '$java_pose', svslam listen '$expected'"; exit 1
fi
echo "OK: $java_pose"
