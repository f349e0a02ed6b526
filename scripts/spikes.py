#!/usr/bin/env python3
"""The largest one-frame vertex jump of a point cache: per file, the largest
distance of a vertex from the mean of its positions in the frames before
and after (a vertex shot off for one frame), with its frame and vertex, and
how many vertex-frames exceed 0.1 m. Needs numpy.

usage: scripts/spikes.py FILE.pc2...
"""
import struct
import sys

import numpy as np

if len(sys.argv) < 2:
    sys.exit(__doc__)
for p in sys.argv[1:]:
    d = open(p, 'rb').read()
    (n,) = struct.unpack('<i', d[16:20])
    (f,) = struct.unpack('<i', d[28:32])
    a = np.frombuffer(d[32:32 + f * n * 12], dtype='<f4').reshape(f, n, 3)
    dd = np.linalg.norm(a[1:-1] - (a[:-2] + a[2:]) / 2, axis=2)
    k = np.unravel_index(dd.argmax(), dd.shape)
    big = (dd > 0.1).sum()
    print("%-50s max %.3f m (frame %d, vertex %d); %d vertex-frames > 0.1 m"
          % (p[-50:], dd.max(), k[0] + 1, k[1], big))
