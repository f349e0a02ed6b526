"""Per-vertex acceleration |x(t+1) - 2x(t) + x(t-1)| * fps^2 of a key-frame
output at its transitions (from the report) against the same statistic
inside the captured sequences (README, Key-frame animation).
usage: transition_accel.py OUT.pc2 REPORT.json DB_SEQ.pc2...
"""
import json, struct, sys
import numpy as np

def pc2(path):
    b = open(path, 'rb').read()
    frames = struct.unpack("<i", b[28:32])[0]
    n = struct.unpack('<i', b[16:20])[0]
    return np.frombuffer(b[32:32 + frames * n * 12], dtype='<f4').reshape(frames, n, 3).astype(np.float64)

def acc(x):
    a = np.linalg.norm(x[2:] - 2 * x[1:-1] + x[:-2], axis=2)  # (frames-2, n), m/frame^2
    return a  # row t is frame t+1

out, rep = pc2(sys.argv[1]), json.load(open(sys.argv[2]))
fps = rep.get('fps', 25.0)
db = [acc(pc2(p)) for p in sys.argv[3:]]
ref_max = np.concatenate([a.max(axis=1) for a in db])
ref_mean = np.concatenate([a.mean(axis=1) for a in db])
ref_p99 = np.concatenate([np.percentile(a, 99, axis=1) for a in db])
ao = acc(out)
omax, omean, op99 = ao.max(axis=1), ao.mean(axis=1), np.percentile(ao, 99, axis=1)
s = fps * fps
print(f"captured sequences ({len(ref_max)} frames): per-frame max vertex acceleration median {np.median(ref_max)*s:.2f}, 99th pct {np.percentile(ref_max,99)*s:.2f}, max {ref_max.max()*s:.2f} m/s^2; per-frame mean {np.median(ref_mean)*s:.2f} (median), 99th-pct vertex {np.median(ref_p99)*s:.2f} (median)")
inw = np.zeros(len(omax), bool)
rows = []
for t in rep['transitions']:
    at, L = t['at'], t['window']
    lo, hi = max(at - L - 1, 0), min(at + L, len(omax))  # rows = frame-1
    inw[lo:hi] = True
    k = lo + int(np.argmax(omax[lo:hi]))
    rows.append((t['from'], t['to'], at, L, t['smoothness'], omax[lo:hi].max() * s, omean[lo:hi].max() * s, k + 1,
                 (ref_max < omax[lo:hi].max()).mean() * 100))
print(f"output ({len(omax)+2} frames): outside transition windows per-frame max median {np.median(omax[~inw])*s:.2f}, max {omax[~inw].max()*s:.2f} m/s^2; inside windows median {np.median(omax[inw])*s:.2f}, max {omax[inw].max()*s:.2f}")
print("transition                               at  L  smooth(m)  max-acc  mean-acc (m/s^2)  worst frame  percentile of captured")
for r in rows:
    print(f"{r[0]:>18} -> {r[1]:<22} {r[2]:4d} {r[3]:2d}  {r[4]:.3f}  {r[5]:7.2f}  {r[6]:6.2f}  {r[7]:5d}  {r[8]:5.1f}")
