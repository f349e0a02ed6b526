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
#
# VERTICES=N (e.g. 2600) drives a decimated samba mesh instead: the rest
# mesh cut to N vertices by quadric-error half-edge collapses (Garland &
# Heckbert 1997; the mesh stays closed and manifold, no face turns over,
# the kept vertices keep their positions, the chin landmark's vertex is
# kept), written once to OUT/pool/rest.obj with its landmarks. At 2.6K
# vertices a frame costs about a quarter of the full mesh's in synthesis,
# PC2 (12 B a vertex) and frame cache (24 B): the 10^5-frame pool of
# issue 43 (about 3 GB of PC2). One OUT holds one mesh: the choice is
# recorded in OUT/pool/mesh.txt and another VERTICES for it is refused.
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
MESH=$S/4d/samba/samba.obj
MARKS=$F/samba.landmarks.json
want_mesh="samba ${VERTICES:-full}"
if [ -f "$OUT/pool/mesh.txt" ] && [ "$(cat "$OUT/pool/mesh.txt")" != "$want_mesh" ]; then
  echo "$OUT/pool holds a pool of $(cat "$OUT/pool/mesh.txt"), not $want_mesh (VERTICES): use another OUT" >&2
  exit 2
fi
echo "$want_mesh" > "$OUT/pool/mesh.txt"
if [ -n "${VERTICES:-}" ]; then
  if [ ! -f "$OUT/pool/rest.landmarks.json" ]; then
    python3 - "$MESH" "$VERTICES" "$MARKS" "$OUT/pool/rest.obj" "$OUT/pool/rest.landmarks.json" <<'PY'
# Half-edge-collapse decimation with quadric error metrics (Garland &
# Heckbert 1997): the mesh stays closed and manifold (link condition), no
# face turns over or degenerates, the kept vertices are a subset of the
# input's at their own positions; landmarks given as vertex indices are
# kept and renumbered.
import heapq, json, os, sys
src, want, marks_in, out_obj, marks_out = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4], sys.argv[5]
V, F = [], []
for line in open(src):
    p = line.split()
    if p and p[0] == "v":
        V.append(tuple(float(x) for x in p[1:4]))
    elif p and p[0] == "f":
        idx = [int(t.split("/")[0]) - 1 for t in p[1:]]
        F.extend([idx[0], idx[k], idx[k + 1]] for k in range(1, len(idx) - 1))
if not 4 <= want <= len(V):
    sys.exit(f"VERTICES={want}: between 4 and the mesh's {len(V)}")
marks = json.load(open(marks_in))
keep = {v for v in marks.values() if isinstance(v, int)}
def sub(a, b): return (a[0] - b[0], a[1] - b[1], a[2] - b[2])
def cross(a, b): return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
def dot(a, b): return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
def normal(f):
    a, b, c = V[f[0]], V[f[1]], V[f[2]]
    return cross(sub(b, a), sub(c, a))
Q = [[0.0] * 10 for _ in V]
for f in F:
    n = normal(f)
    l = dot(n, n) ** 0.5
    if l == 0:
        continue
    a, b, c = n[0] / l, n[1] / l, n[2] / l
    d = -dot((a, b, c), V[f[0]])
    q = (a * a, a * b, a * c, a * d, b * b, b * c, b * d, c * c, c * d, d * d)
    for v in f:
        for i in range(10):
            Q[v][i] += l / 2 * q[i]
def err(q, p):
    x, y, z = p
    return (q[0] * x * x + 2 * q[1] * x * y + 2 * q[2] * x * z + 2 * q[3] * x + q[4] * y * y
            + 2 * q[5] * y * z + 2 * q[6] * y + q[7] * z * z + 2 * q[8] * z + q[9])
faces_of = [set() for _ in V]
for i, f in enumerate(F):
    for v in f:
        faces_of[v].add(i)
def nbrs(v):
    s = set()
    for i in faces_of[v]:
        s.update(F[i])
    s.discard(v)
    return s
stamp, heap = [0] * len(V), []
def push(u):  # u's cheapest collapse onto a neighbour (u removed, v kept)
    stamp[u] += 1
    if u in keep:
        return
    best = min(((err([Q[u][i] + Q[v][i] for i in range(10)], V[v]), v) for v in nbrs(u)), default=None)
    if best:
        heapq.heappush(heap, (best[0], u, best[1], stamp[u]))
for u in range(len(V)):
    push(u)
alive, alive_f, removed = len(V), [True] * len(F), [False] * len(V)
while alive > want and heap:
    c, u, v, s = heapq.heappop(heap)
    if removed[u] or removed[v] or s != stamp[u] or v not in nbrs(u):
        continue
    shared = [i for i in faces_of[u] if v in F[i]]
    if len(shared) != 2 or len(nbrs(u) & nbrs(v)) != 2:
        continue
    ok = True
    for i in faces_of[u] - set(shared):
        n0, n1 = normal(F[i]), normal([v if x == u else x for x in F[i]])
        l0, l1 = dot(n0, n0) ** 0.5, dot(n1, n1) ** 0.5
        if l1 < 1e-14 or dot(n0, n1) < 0.3 * l0 * l1:
            ok = False
            break
    if not ok:
        continue
    for i in shared:
        alive_f[i] = False
        for x in F[i]:
            faces_of[x].discard(i)
    for i in faces_of[u]:
        F[i] = [v if x == u else x for x in F[i]]
        faces_of[v].add(i)
    faces_of[u] = set()
    for i in range(10):
        Q[v][i] += Q[u][i]
    removed[u], alive = True, alive - 1
    for w in nbrs(v) | {v}:
        push(w)
if alive > want:
    sys.exit(f"decimation stopped at {alive} vertices (VERTICES={want}): no valid collapse left")
idx = {}
for i in range(len(V)):
    if not removed[i]:
        idx[i] = len(idx)
tmp = out_obj + ".part"
with open(tmp, "w") as f:
    for i in idx:
        f.write("v %.6f %.6f %.6f\n" % V[i])
    tris = [F[i] for i in range(len(F)) if alive_f[i]]
    for t in tris:
        f.write("f %d %d %d\n" % tuple(idx[x] + 1 for x in t))
os.replace(tmp, out_obj)
with open(marks_out + ".part", "w") as f:
    json.dump({k: (idx[v] if isinstance(v, int) else v) for k, v in marks.items()}, f, indent=1)
os.replace(marks_out + ".part", marks_out)
print(f"{out_obj}: {len(V)} -> {len(idx)} vertices, {len(tris)} triangles")
PY
  fi
  MESH=$OUT/pool/rest.obj
  MARKS=$OUT/pool/rest.landmarks.json
fi
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
        "$BIN" synth --mesh "$MESH" --landmarks "$MARKS" \
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
      "$BIN" synth --mesh "$MESH" --landmarks "$MARKS" \
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
