#!/usr/bin/env bash
# Synthetic 4D databases of a chosen size for the scale figures of issue 43:
# every CMU (AMC and BVH) and Bandai Namco clip of the shared mocap, driven
# onto the samba mesh (9,971 vertices) by `surfmotion synth`, and re-timed
# variants of the whole set (the clips read at other frame rates: slower and
# faster versions of each motion) until the pool holds enough frames.
#
#   scripts/scale-db.sh OUT FRAMES...        e.g. scripts/scale-db.sh /work/scale-data 1000 3000 10000
#
# The pool is made once in OUT/pool/vK (one `synth` per variant, source
# frame rate and CMU subject; what is already there is reused; the pool
# stops growing as soon as it holds FRAMES, so the largest size makes only
# the part of a variant it needs: the manifests take the pool's sequences
# in the order they are made), then each size gets
# OUT/dbFRAMES/character.toml listing the pool's sequences in order until
# FRAMES frames are reached (whole sequences, so the count is at least
# FRAMES; the last sequence may overshoot). The sequences are not copied:
# the manifests name the pool's files. BIN (default target/release/surfmotion)
# and SURFMOTION_DATA (default ../shared/data) as elsewhere.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
[ $# -ge 2 ] || { echo "usage: $0 OUT FRAMES..." >&2; exit 2; }
OUT=$(realpath -m "$1"); shift
BIN=$(realpath "${BIN:-$repo/target/release/surfmotion}")
S=$(realpath "${SURFMOTION_DATA:-$repo/../shared/data}")
F=$repo/tests/fixtures
[ -x "$BIN" ] || { echo "$BIN: no binary (cargo build --release)" >&2; exit 2; }
max=0
for n in "$@"; do [ "$n" -gt "$max" ] && max=$n; done
mkdir -p "$OUT/pool"
# Speed factors of the variants: the clips read at factor × their own rate
# (1.25: the motion plays 1.25× faster, so it has 0.8× the frames).
FACTORS="1.0 0.8 1.25 0.9 1.1 0.7 1.4 0.85 1.15 0.75 1.3 0.95 1.05 0.65"
amc=$(ls "$S"/mocap/cmu-amc/0[1-3]/*.amc)
bvh120="$S/mocap/cmu-bvh/131_01.bvh $S/mocap/cmu-bvh/131_02.bvh $S/mocap/cmu-bvh/131_03.bvh"
bvh30=$(ls "$S"/mocap/bandai-namco/*.bvh)
pool_frames() {
  local total=0
  # PC2: 12-byte magic, version, points, start, rate, samples (i32 at 28).
  for p in $(find "$OUT/pool" -name '*.pc2'); do
    total=$((total + $(od -An -t d4 -j 28 -N 4 "$p")))
  done
  echo $total
}
enough() { [ "$(pool_frames)" -ge "$max" ]; }
k=0
for f in $FACTORS; do
  enough && break
  v=$OUT/pool/v$k
  for group in amc bvh120 bvh30; do
    d=$v/$group
    [ -f "$d/character.toml" ] && continue
    enough && break
    case $group in
      amc) clips=$amc; rate=120 ;;
      bvh120) clips=$bvh120; rate=120 ;;
      bvh30) clips=$bvh30; rate=30 ;;
    esac
    fps=$(python3 -c "print($rate * $f)")
    # Each AMC needs its own ASF (subjects 01, 02, 03): one call per subject.
    if [ $group = amc ]; then
      for subj in 01 02 03; do
        [ -f "$d/$subj/character.toml" ] && continue
        enough && break
        "$BIN" synth --mesh "$S/4d/samba/samba.obj" --landmarks "$F/samba.landmarks.json" \
          --input-fps "$fps" --mocap "$S"/mocap/cmu-amc/$subj/*.amc -o "$d/$subj" --force >/dev/null
      done
      mkdir -p "$d"
      # A marker so the group counts as done (the sequences are in the
      # subfolders); none while a subject is left out (the pool was enough).
      if [ -f "$d/01/character.toml" ] && [ -f "$d/02/character.toml" ] && [ -f "$d/03/character.toml" ]; then
        : > "$d/character.toml"
      fi
    else
      # shellcheck disable=SC2086
      "$BIN" synth --mesh "$S/4d/samba/samba.obj" --landmarks "$F/samba.landmarks.json" \
        --input-fps "$fps" --mocap $clips -o "$d" --force >/dev/null
    fi
    echo "pool: v$k $group at ${fps} fps: $(pool_frames) frames so far"
  done
  k=$((k + 1))
done
have=$(pool_frames)
echo "pool: $have frames in $OUT/pool"
# One manifest per size: the pool's sequences in order until FRAMES.
for n in "$@"; do
  db=$OUT/db$n
  mkdir -p "$db"
  python3 - "$OUT" "$db" "$n" "$S" "$F" <<'PY'
import os, struct, sys, glob
out, db, want, S, F = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4], sys.argv[5]
seqs = []
for v in sorted(glob.glob(f"{out}/pool/v*"), key=lambda p: int(p.rsplit("v", 1)[1])):
    for pc2 in sorted(glob.glob(f"{v}/**/*.pc2", recursive=True)):
        with open(pc2, "rb") as f:
            head = f.read(32)
        frames = struct.unpack("<i", head[28:32])[0]
        rel = os.path.relpath(pc2, out).replace("pool/", "").replace("/", "_")[:-4]
        seqs.append((rel, os.path.relpath(pc2, db), frames))
total, lines = 0, []
for name, path, frames in seqs:
    if total >= want:
        break
    lines.append(f'[[sequence]]\nname = "{name}"\npath = "{path}"\n')
    total += frames
if total < want:
    sys.exit(f"only {total} frames in the pool for {want}")
topo = os.path.relpath(f"{out}/pool/v0/bvh120/topology.obj", db)
marks = os.path.relpath(f"{out}/pool/v0/bvh120/landmarks.json", db)
with open(f"{db}/character.toml", "w") as f:
    f.write(f'name = "db{want}"\ntopology = "{topo}"\nfps = 30.0\nunits = "m"\nup = "y"\n\n')
    f.write("\n".join(lines))
    f.write(f'\n[rig]\nlandmarks = "{marks}"\n')
print(f"{db}: {len(lines)} sequences, {total} frames")
PY
done
