#!/usr/bin/env bash
# The yardstick: retarget 8 clips onto a database, score each with `eval`, and
# print one row per clip (head-to-torso p95 and its line, joint velocity error,
# ground penetration max, floating median, foot sliding in contact and while
# touching (cm/frame), knee hyper-extension max (degrees), the warnings). The table checked on
# every merge of retargeting work (README, "Retargeting: what is matched and why").
#
#   scripts/yardstick.sh [-b BIN] DB [OUTDIR]
#
# BIN defaults to target/release/surfmotion (of this repository; `cargo build
# --release` first), the data to $SURFMOTION_DATA or ../shared/data beside the
# repository, OUTDIR to a new temporary folder (the results and the JSON
# reports stay there). Clips: CMU 131_01, 131_02 (BVH), 02_02, 03_01, 03_02,
# 02_03 (AMC), Bandai Namco walk_happy and run_normal. Needs python3 (no
# packages) to read the reports. Exit status 1 if any clip failed. The
# retargeting options of the environment apply (e.g. SURFMOTION_PLACEMENT).
set -u
here=$(cd "$(dirname "$0")/.." && pwd)
BIN=$here/target/release/surfmotion
if [ "${1:-}" = "-b" ]; then BIN=$2; shift 2; fi
if [ $# -lt 1 ] || [ $# -gt 2 ]; then
  echo "usage: $0 [-b BIN] DB [OUTDIR]" >&2; exit 2
fi
DB=$1
OUT=${2:-$(mktemp -d "${TMPDIR:-/tmp}/yardstick.XXXXXX")}
S=${SURFMOTION_DATA:-$here/../shared/data}
[ -x "$BIN" ] || { echo "no binary at $BIN (cargo build --release, or -b BIN)" >&2; exit 2; }
[ -d "$S/mocap" ] || { echo "no data at $S (set SURFMOTION_DATA)" >&2; exit 2; }
[ -d "$DB" ] || { echo "no database at $DB" >&2; exit 2; }
mkdir -p "$OUT"
echo "# $BIN on $DB; results in $OUT"
CLIPS="$S/mocap/cmu-bvh/131_01.bvh $S/mocap/cmu-bvh/131_02.bvh $S/mocap/cmu-amc/02/02_02.amc $S/mocap/cmu-amc/03/03_01.amc $S/mocap/cmu-amc/03/03_02.amc $S/mocap/cmu-amc/02/02_03.amc $S/mocap/bandai-namco/dataset-1_walk_happy_001.bvh $S/mocap/bandai-namco/dataset-1_run_normal_001.bvh"
printf "%-32s %6s %6s %7s %7s %7s %6s %6s %5s  %s\n" clip headp95 line vel pen_max float_md slide glide knee warnings
failed=0
for c in $CLIPS; do
  n=$(basename "$c"); n=${n%.*}
  if ! "$BIN" retarget --db "$DB" --mocap "$c" -o "$OUT/$n.pc2" --json > "$OUT/$n.r.json" 2> "$OUT/$n.r.err"; then
    echo "$n: retarget FAILED: $(tail -1 "$OUT/$n.r.err")"; failed=1; continue; fi
  if ! "$BIN" eval --db "$DB" --mocap "$c" --result "$OUT/$n.pc2" --json > "$OUT/$n.e.json" 2> "$OUT/$n.e.err"; then
    echo "$n: eval FAILED: $(tail -1 "$OUT/$n.e.err")"; failed=1; continue; fi
  python3 - "$OUT/$n.e.json" "$n" <<'PY'
import json, sys
d = json.load(open(sys.argv[1])); p = d['plausibility']
ref = (p.get('reference') or {}).get('head_torso_deg', {}).get('p95', float('nan'))
clip = (p.get('clip_head_torso_deg') or {}).get('p95', float('nan'))
line = max(x for x in (ref, clip) if x == x) + 3
w = [x[:60] for x in p['warnings'] if 'turned over' not in x]
t = [x.split(' in frame')[0] for x in p['warnings'] if 'turned over' in x]
s = p['foot_sliding']
print("%-32s %6.1f %6.1f %7.3f %7.2f %7.2f %6.3f %6.3f %5.1f  %s" % (sys.argv[2], p['head_torso_deg']['p95'], line,
      d['velocity_error_cm_per_frame'], p['ground']['penetration_cm']['max'],
      p['ground']['floating_cm']['median'], s['mean_cm_per_frame'],
      s['touching_mean_cm_per_frame'], p['knee_hyperextension_deg']['max'], '; '.join(w + t)))
PY
done
exit $failed
