#!/usr/bin/env bash
# Before/after comparison of the CLI (issue 19): run the README's tour and the
# main verbs (inspect, mocap, mesh, blend, repair, db, rig, render, synth,
# graph, retarget, eval, transfer, batch, keyframe, demo) with two binaries,
# each in its own folder, and compare every output file, stdout, stderr and
# exit code.
#
#   scripts/compare_tour.sh OLD_BIN NEW_BIN [OUT_DIR]
#
# Binary outputs (GLB, PC2, PNG, ...) must be byte-identical. Text and JSON
# outputs that differ in bytes are compared token by token: numbers within
# 1e-6 (absolute or relative), everything else (JSON keys and their order
# included) exactly; timing fields (JSON keys naming seconds/timings, text
# lines with a time unit) are ignored. Exit 0 when everything matches, 1
# otherwise, with one line per difference.
#
# Data: ../shared/data beside the repository, or $SURFMOTION_DATA.
# REUSE_OLD=1 keeps OUT_DIR/old from an earlier run of the same OLD_BIN.
set -euo pipefail

if [ $# -lt 2 ]; then
    sed -n '2,18p' "$0" | sed 's/^# \{0,1\}//'
    exit 1
fi
OLD=$(realpath "$1")
NEW=$(realpath "$2")
REPO=$(cd "$(dirname "$0")/.." && pwd)
OUT=$(realpath -m "${3:-$(mktemp -d /tmp/compare_tour.XXXXXX)}")
S=$(realpath "${SURFMOTION_DATA:-$REPO/../shared/data}")
[ -d "$S/4d/samba" ] || { echo "no data at $S (set SURFMOTION_DATA)"; exit 1; }

# One run of the tour with binary $1 in folder $2. Each command's stdout,
# stderr and exit code go to NN.out, NN.err, NN.rc.
run_tour() {
    local bin=$1 dir=$2 n=0
    rm -rf "$dir"
    mkdir -p "$dir"
    ln -s "$REPO/tests" "$dir/tests"
    cd "$dir"
    step() {
        n=$((n + 1))
        local id
        id=$(printf '%02d' "$n")
        local rc=0
        "$bin" "$@" >"$id.out" 2>"$id.err" || rc=$?
        echo "$rc" >"$id.rc"
        printf '%s %s (exit %s)\n' "$id" "$*" "$rc" >>commands.txt
    }
    step inspect "$S/mocap/cmu-bvh-ccrig/002_01.bvh"
    step inspect "$S/4d/samba/samba.pc2" --json
    step mocap positions "$S/mocap/cmu-amc/02/02_01.amc" --frames 0,10 --json
    step mocap positions "$S/mocap/cmu-bvh/01_01.bvh" --frames 100 --output-units metres
    step mocap convert "$S/mocap/cmu-amc/02/02_01.amc" walk.bvh --fps 30 --output-units metres
    step mocap rigmap "$S/mocap/bandai-namco/dataset-1_walk_normal_001.bvh" -o map.json
    step mesh convert "$S/4d/samba/samba.pc2" samba.glb
    step mesh convert "$S/4d/samba/samba.pc2:60" samba_60.obj
    step blend "$S/4d/crane/crane.pc2:0" "$S/4d/crane/crane.pc2:100" --alpha 0.5 -o mid.obj
    step repair "$S/scans/makehuman/base.obj" -o body.obj --keep-largest
    step db init samba_db --mesh "$S/4d/samba/samba.obj" --sequence "dance=$S/4d/samba/samba.pc2"
    step db info samba_db
    step mocap procedural -o clips
    step rig embed "$S/4d/samba/samba.obj" --landmarks tests/fixtures/samba.landmarks.json -o samba.rig.json --png samba_rig.png
    step rig embed "$S/4d/samba/samba.obj" --landmarks tests/fixtures/samba.landmarks.json -o samba2.rig.json --json
    step render "$S/4d/samba/samba.pc2" --frame 90 --rig samba.rig.json -o samba_90.png
    step db init samba_db --mesh "$S/4d/samba/samba.obj" --sequence "dance=$S/4d/samba/samba.pc2" --landmarks tests/fixtures/samba.landmarks.json --force
    step db info samba_db --json
    step db skeleton samba_db
    step db skeleton samba_db --json
    step db skeleton samba_db --kind regressor --json
    step synth --mesh "$S/4d/samba/samba.obj" --landmarks tests/fixtures/samba.landmarks.json \
        --mocap "$S/mocap/cmu-amc/02/02_01.amc" "$S/mocap/cmu-amc/02/02_03.amc" -o samba_synth
    step synth --mesh "$S/4d/samba/samba.obj" --landmarks tests/fixtures/samba.landmarks.json \
        --mocap "$S/mocap/cmu-amc/02/02_01.amc" --seconds 2 -o synth_json --json --preview synth.png
    step db build samba_synth
    step db build samba_synth --json
    step graph samba_synth --matrix samba_synth.png
    step graph samba_synth --dot
    step graph samba_synth --json
    step retarget --db samba_synth --mocap "$S/mocap/cmu-amc/02/02_02.amc" -o walk.glb --report walk.json
    step retarget --db samba_synth --mocap "$S/mocap/cmu-amc/02/02_02.amc" -o walk_lbs.pc2 --deform lbs --json
    step eval --db samba_synth --mocap "$S/mocap/cmu-amc/02/02_02.amc" --result walk.glb
    step eval --db samba_synth --mocap "$S/mocap/cmu-amc/02/02_02.amc" --result walk.glb --json
    step transfer --scan "$S/scans/armadillo/armadillo.obj" --landmarks tests/fixtures/armadillo.landmarks.json \
        --mocap "$S/mocap/cmu-amc/02/02_01.amc" -o arm.pc2
    step transfer --scan "$S/4d/samba/samba.pc2:0" --landmarks tests/fixtures/samba.landmarks.json \
        --template "$S/4d/samba/samba.pc2" --truth "$S/4d/samba/samba.pc2" --marker-count 20 -o s.pc2 --json
    step batch --scan "$S/scans/armadillo/armadillo.obj" --landmarks tests/fixtures/armadillo.landmarks.json \
        --mocap-dir "$S/mocap/cmu-amc/03" -o armadillo_cmu --jobs 2 --format glb
    step db build samba_db
    step batch --db samba_db --mocap-dir "$S/mocap/cmu-amc/03" -o samba_cmu --format pc2
    step keyframe --db samba_synth --from 02_01:0 --to 02_03:30 --distance 6 --time 5 -o kf.pc2 --report kf.json
    step demo -o demo
    cd - >/dev/null
}

t0=$(date +%s)
if [ "${REUSE_OLD:-0}" = 1 ] && [ -f "$OUT/old/commands.txt" ]; then
    echo "old: reusing $OUT/old"
else
    echo "old: $OLD -> $OUT/old"
    run_tour "$OLD" "$OUT/old"
fi
echo "new: $NEW -> $OUT/new ($(($(date +%s) - t0)) s for old)"
run_tour "$NEW" "$OUT/new"
echo "compare ($(($(date +%s) - t0)) s for both)"

python3 - "$OUT/old" "$OUT/new" <<'EOF'
import json, os, re, sys

old, new = sys.argv[1], sys.argv[2]
TOL = 1e-6
# Keys whose values are wall-clock measurements.
TIMING_KEY = re.compile(r"seconds|timings?|elapsed|wall|_ms$|_s$|^ms$|^s$|per_second|ms_per|per_minute")
# batch.html rows: clip, status, frames, seconds, error, output (drop the seconds).
HTML_SECONDS = re.compile(r"(<td>\d+</td>)<td>[0-9.]+</td>")
# Text lines that carry a time measurement.
TIMING_LINE = re.compile(r"\d\s*(ms|s|µs|us|min)\b|\bs\)|frames/s|elapsed|took|timings?")
NUM = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
problems, same, close = [], 0, 0

def num_eq(a, b):
    return abs(a - b) <= TOL or abs(a - b) <= TOL * max(abs(a), abs(b))

def cmp_json(a, b, path):
    if isinstance(a, dict) and isinstance(b, dict):
        ka, kb = list(a.keys()), list(b.keys())
        if ka != kb:
            return f"{path}: keys {ka} != {kb}"
        for k in ka:
            if TIMING_KEY.search(k):
                continue
            r = cmp_json(a[k], b[k], f"{path}.{k}")
            if r:
                return r
        return None
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return f"{path}: length {len(a)} != {len(b)}"
        for i, (x, y) in enumerate(zip(a, b)):
            r = cmp_json(x, y, f"{path}[{i}]")
            if r:
                return r
        return None
    if isinstance(a, bool) or isinstance(b, bool):
        return None if a == b else f"{path}: {a!r} != {b!r}"
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return None if num_eq(a, b) else f"{path}: {a!r} != {b!r}"
    return None if a == b else f"{path}: {a!r} != {b!r}"

def cmp_text(ta, tb):
    ta, tb = HTML_SECONDS.sub(r"\1", ta), HTML_SECONDS.sub(r"\1", tb)
    la, lb = ta.splitlines(), tb.splitlines()
    if len(la) != len(lb):
        return f"{len(la)} lines != {len(lb)} lines"
    for i, (x, y) in enumerate(zip(la, lb)):
        if x == y:
            continue
        if TIMING_LINE.search(x) and TIMING_LINE.search(y) and NUM.sub("#", x) == NUM.sub("#", y):
            continue
        if NUM.sub("#", x) != NUM.sub("#", y):
            return f"line {i + 1}: {x!r} != {y!r}"
        for p, q in zip(NUM.findall(x), NUM.findall(y)):
            if not num_eq(float(p), float(q)):
                return f"line {i + 1}: {x!r} != {y!r}"
    return None

def load_json(t):
    try:
        return json.loads(t, object_pairs_hook=dict)
    except Exception:
        return None

files_a, files_b = set(), set()
for base, acc in ((old, files_a), (new, files_b)):
    for root, dirs, files in os.walk(base):
        dirs[:] = [d for d in dirs if d != "tests"]
        for f in files:
            acc.add(os.path.relpath(os.path.join(root, f), base))
for f in sorted(files_a ^ files_b):
    problems.append(f"{f}: only in {'old' if f in files_a else 'new'}")
for f in sorted(files_a & files_b):
    if f == "commands.txt":
        continue
    a = open(os.path.join(old, f), "rb").read()
    b = open(os.path.join(new, f), "rb").read()
    if a == b:
        same += 1
        continue
    try:
        ta, tb = a.decode(), b.decode()
    except UnicodeDecodeError:
        problems.append(f"{f}: binary files differ ({len(a)} vs {len(b)} bytes)")
        continue
    ja, jb = load_json(ta), load_json(tb)
    r = cmp_json(ja, jb, "$") if ja is not None and jb is not None else cmp_text(ta, tb)
    if r:
        problems.append(f"{f}: {r}")
    else:
        close += 1
print(f"{same} files byte-identical, {close} equal up to timings / 1e-6, {len(problems)} different")
for p in problems:
    print("DIFF", p)
sys.exit(1 if problems else 0)
EOF
