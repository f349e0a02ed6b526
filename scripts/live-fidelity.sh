#!/usr/bin/env bash
# Live fidelity (issue 45): the joint-velocity error (`eval`, cm/frame) of
# `live --replay CLIP --speed 0 --lossless --lag L --record` against the offline
# `retarget` of the same clip on the same database, for each clip of the
# retargeting yardstick (scripts/yardstick.sh) and each lag.
#
#   scripts/live-fidelity.sh [-b BIN] [-l "0 3 10"] [-c "CLIP..."] [-a "LIVE ARGS"] DB [OUTDIR]
#
# -a adds options to every `live` run (e.g. -a "--lift-settle 0.05").
# Prints one row per clip: the offline error, then each lag's error and its
# ratio to the offline one (targets: ≤ 2× at lag 0, ≤ 1.5× at lag 3).
set -u
here=$(cd "$(dirname "$0")/.." && pwd)
BIN=$here/target/release/surfmotion
LAGS="0 3 10"
ARGS=""
S=${SURFMOTION_DATA:-$here/../shared/data}
CLIPS="$S/mocap/cmu-bvh/131_01.bvh $S/mocap/cmu-bvh/131_02.bvh $S/mocap/cmu-amc/02/02_02.amc $S/mocap/cmu-amc/03/03_01.amc $S/mocap/cmu-amc/03/03_02.amc $S/mocap/cmu-amc/02/02_03.amc $S/mocap/bandai-namco/dataset-1_walk_happy_001.bvh $S/mocap/bandai-namco/dataset-1_run_normal_001.bvh"
while [ $# -gt 0 ]; do
  case $1 in
    -b) BIN=$2; shift 2;;
    -l) LAGS=$2; shift 2;;
    -c) CLIPS=$2; shift 2;;
    -a) ARGS=$2; shift 2;;
    *) break;;
  esac
done
if [ $# -lt 1 ] || [ $# -gt 2 ]; then
  echo "usage: $0 [-b BIN] [-l LAGS] [-c CLIPS] [-a ARGS] DB [OUTDIR]" >&2; exit 2
fi
DB=$1
OUT=${2:-$(mktemp -d "${TMPDIR:-/tmp}/live-fidelity.XXXXXX")}
mkdir -p "$OUT"
vel() { python3 -c 'import json,sys; print("%.3f" % json.load(open(sys.argv[1]))["velocity_error_cm_per_frame"])' "$1" 2>/dev/null || echo nan; }
echo "# $BIN on $DB; lags $LAGS; live options: ${ARGS:-none}; results in $OUT"
echo "# start: $(uptime)"
printf "%-28s %8s" clip offline; for l in $LAGS; do printf " %14s" "lag $l"; done; echo
for c in $CLIPS; do
  n=$(basename "$c"); n=${n%.*}
  if [ ! -f "$OUT/$n.off.e.json" ]; then
    "$BIN" retarget --db "$DB" --mocap "$c" -o "$OUT/$n.off.pc2" > /dev/null 2> "$OUT/$n.off.err" &&
    "$BIN" eval --db "$DB" --mocap "$c" --result "$OUT/$n.off.pc2" --json > "$OUT/$n.off.e.json" 2>> "$OUT/$n.off.err"
  fi
  off=$(vel "$OUT/$n.off.e.json")
  printf "%-28s %8s" "$n" "$off"
  for l in $LAGS; do
    "$BIN" live --db "$DB" --replay "$c" --speed 0 --lossless --lag "$l" $ARGS --record "$OUT/$n.lag$l.pc2" --json > "$OUT/$n.lag$l.json" 2> "$OUT/$n.lag$l.err" &&
    "$BIN" eval --db "$DB" --mocap "$c" --result "$OUT/$n.lag$l.pc2" --json > "$OUT/$n.lag$l.e.json" 2>> "$OUT/$n.lag$l.err"
    v=$(vel "$OUT/$n.lag$l.e.json")
    printf " %7s (%4sx)" "$v" "$(python3 -c "import sys; a,b=sys.argv[1:]; print('%.2f' % (float(a)/float(b)) if b!='nan' and a!='nan' else 'nan')" "$v" "$off")"
  done
  echo
done
echo "# end: $(uptime)"
