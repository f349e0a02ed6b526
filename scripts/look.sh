#!/usr/bin/env bash
# Look at a retargeted result beside the capture: a sheet of four of its
# frames, each beside the database's captured frame nearest to it by shape,
# front and side views, every panel at one scale (issue 42's "Look").
#
#   scripts/look.sh [-b BIN] [-f F1,F2,F3,F4] [-s PX] DB RESULT.pc2 OUT.png
#
# RESULT.pc2 is a `retarget` output onto DB (its `.obj` beside it, as
# `retarget -o X.pc2` writes); the frames default to four evenly spaced
# ones (at 1/8, 3/8, 5/8 and 7/8 of the result). "Nearest by shape" is the
# captured frame, over every `.pc2` sequence of DB's character.toml, with
# the least RMS vertex distance after the best rigid alignment (Kabsch),
# since the result is placed on the clip's path and turned with it. The
# sheet has two rows of two pairs: result frame (front, side), then its
# nearest captured frame (front, side); the frames matched are printed.
# Needs python3 with numpy (a venv in .ci/look-venv is made when it is
# missing) and ImageMagick's `convert`.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
BIN=$here/target/release/surfmotion
FRAMES=""
SIZE=400
while getopts "b:f:s:" o; do
  case $o in
    b) BIN=$OPTARG ;;
    f) FRAMES=$OPTARG ;;
    s) SIZE=$OPTARG ;;
    *) echo "usage: $0 [-b BIN] [-f F1,F2,F3,F4] [-s PX] DB RESULT.pc2 OUT.png" >&2; exit 2 ;;
  esac
done
shift $((OPTIND - 1))
if [ $# -ne 3 ]; then
  echo "usage: $0 [-b BIN] [-f F1,F2,F3,F4] [-s PX] DB RESULT.pc2 OUT.png" >&2; exit 2
fi
DB=$1 RESULT=$2 OUT=$3
[ -x "$BIN" ] || { echo "no binary at $BIN (cargo build --release, or -b BIN)" >&2; exit 2; }
[ -f "$DB/character.toml" ] || { echo "no database at $DB (no character.toml)" >&2; exit 2; }
[ -f "$RESULT" ] || { echo "no result at $RESULT" >&2; exit 2; }
case "$OUT" in *.png) ;; *) echo "OUT must be a .png (got $OUT)" >&2; exit 2 ;; esac
[ "$(realpath -m "$OUT")" != "$(realpath -m "$RESULT")" ] || { echo "OUT is the result itself" >&2; exit 2; }
command -v convert >/dev/null || { echo "needs ImageMagick's convert" >&2; exit 2; }
PY=python3
if ! $PY -c 'import numpy' 2>/dev/null; then
  if [ ! -x "$here/.ci/look-venv/bin/python" ]; then
    python3 -m venv "$here/.ci/look-venv"
    "$here/.ci/look-venv/bin/pip" install --quiet --disable-pip-version-check numpy
  fi
  PY=$here/.ci/look-venv/bin/python
fi
# "result_frame capture.pc2 capture_frame rms_m" per line.
pairs=$($PY - "$DB/character.toml" "$RESULT" "$FRAMES" <<'PY'
import sys, tomllib, numpy as np

def read_pc2(path):
    with open(path, "rb") as f:
        head = f.read(32)
        if head[:12] != b"POINTCACHE2\0":
            sys.exit(f"{path}: not a PC2 file")
        points = int.from_bytes(head[16:20], "little")
        samples = int.from_bytes(head[28:32], "little")
        data = np.frombuffer(f.read(), dtype="<f4")
    if data.size != points * samples * 3:
        sys.exit(f"{path}: {data.size} values for {samples} frames of {points} points")
    return data.reshape(samples, points, 3).astype(np.float64)

def aligned_rms(a, frames):
    """RMS distance of frame `a` to each of `frames` after the best rigid
    motion (Kabsch, no scaling)."""
    a0 = a - a.mean(axis=0)
    out = np.empty(len(frames))
    for i, b in enumerate(frames):
        b0 = b - b.mean(axis=0)
        u, s, vt = np.linalg.svd(a0.T @ b0)
        d = np.sign(np.linalg.det(u @ vt))
        s[-1] *= d
        # |a0 R - b0|^2 = |a0|^2 + |b0|^2 - 2 tr(S) at the optimum.
        e = (a0 * a0).sum() + (b0 * b0).sum() - 2.0 * s.sum()
        out[i] = np.sqrt(max(e, 0.0) / len(a))
    return out

toml, result, frames = sys.argv[1], sys.argv[2], sys.argv[3]
with open(toml, "rb") as f:
    seqs = [s["path"] for s in tomllib.load(f).get("sequence", []) if s["path"].endswith(".pc2")]
if not seqs:
    sys.exit(f"{toml}: no .pc2 sequence to compare with")
res = read_pc2(result)
n = len(res)
picked = [int(x) for x in frames.split(",")] if frames else [n * k // 8 for k in (1, 3, 5, 7)]
for f in picked:
    if not 0 <= f < n:
        sys.exit(f"frame {f} is outside the result's {n} frames")
caps = [(p, read_pc2(p)) for p in seqs]
for f in picked:
    best = min(((aligned_rms(res[f], c).min(), p, int(aligned_rms(res[f], c).argmin())) for p, c in caps))
    print(f, best[1], best[2], "%.4f" % best[0])
PY
)
echo "$pairs" | while read -r f cap g rms; do
  echo "result frame $f ~ $(basename "$cap") frame $g (aligned RMS $rms m)"
done
args=$(echo "$pairs" | while read -r f cap g rms; do printf '%s:%s %s:%s ' "$RESULT" "$f" "$cap" "$g"; done)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# shellcheck disable=SC2086 # one argument per panel
"$BIN" render $args --size "$SIZE" -o "$tmp/row.png" >/dev/null
w=$(identify -format %w "$tmp/row.png")
h=$(identify -format %h "$tmp/row.png")
half=$((w / 2))
convert "$tmp/row.png" -crop "${half}x${h}+0+0" +repage "$tmp/a.png"
convert "$tmp/row.png" -crop "${half}x${h}+${half}+0" +repage "$tmp/b.png"
convert "$tmp/a.png" "$tmp/b.png" -append "$tmp/sheet.png"
mv "$tmp/sheet.png" "$OUT"
echo "wrote $OUT (rows: result, nearest capture frame, result, nearest capture frame; front and side each)"
