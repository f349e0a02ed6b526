// The character animation engine (Volino, Huang & Hilton 2015, Sec. 5):
// it walks the Surface Motion Graph exported by `surfmotion web export`.
// A motion request joins a queue; the engine plans the shortest path in
// frames (Dijkstra over the frame graph: t -> t+1 inside a sequence, and
// each transition (i, m) -> (j, n) with half-window L taken from frame m-L
// of i to frame n+L+1 of j after 2L+1 blended frames), plays it, and blends
// linearly over each transition's window on the GPU. A motion with nothing
// queued loops through its latest self-transition ahead, else restarts.
// Each transition carries a ground-plane rigid alignment, so the character
// moves on instead of jumping back.

// Ground-plane rigid motions [c, s, tx, tz]: x' = c x + s z + tx, z' = -s x + c z + tz.
export const IDENTITY = [1, 0, 0, 0];
export function compose(w, t) {
  const [a, b, ex, ez] = w, [c, s, tx, tz] = t;
  return [a * c - b * s, a * s + b * c, a * tx + b * tz + ex, -b * tx + a * tz + ez];
}
export function apply(w, x, z) {
  return [w[0] * x + w[1] * z + w[2], -w[1] * x + w[0] * z + w[3]];
}
export function mat4(w) {
  const [c, s, tx, tz] = w;
  return new Float32Array([c, 0, -s, 0, 0, 1, 0, 0, s, 0, c, 0, tx, 0, tz, 1]);
}

const RESTART_PENALTY = 60;

export class Engine {
  constructor(manifest) {
    this.seqs = manifest.sequences;
    this.trans = manifest.transitions;
    this.start = [];
    let acc = 0;
    for (const s of this.seqs) { this.start.push(acc); acc += s.frames; }
    this.total = acc;
    this.out = Array.from({ length: this.seqs.length }, () => []);
    this.trans.forEach((t, k) => this.out[t.from].push(k));
    this.seq = 0; this.frame = 0; this.W = IDENTITY.slice();
    this.blend = null; this.plan = []; this.queue = []; this.goal = 0;
    this.last = null; this.ticks = 0; this.transitions = 0;
  }
  len(s) { return this.seqs[s].frames; }
  clampF(s, f) { return Math.max(0, Math.min(this.len(s) - 1, f)); }
  startFrame(t) { return this.clampF(t.from, t.m - t.window); }
  endFrame(t) { return t.n + t.window + 1; }

  request(seq) {
    if (seq < 0 || seq >= this.seqs.length) return;
    this.queue.push(seq);
  }

  // Shortest path in frames from (s, f) to any frame of `target`: a list
  // of {k, s, f} transitions to start at (s, f).
  route(s0, f0, target) {
    const N = this.total;
    const dist = new Float64Array(N).fill(Infinity);
    const prev = new Int32Array(N).fill(-1);
    const via = new Int32Array(N).fill(-1);
    const heap = [];
    const push = (d, g) => {
      heap.push([d, g]);
      let i = heap.length - 1;
      while (i > 0) { const p = (i - 1) >> 1; if (heap[p][0] <= heap[i][0]) break; [heap[p], heap[i]] = [heap[i], heap[p]]; i = p; }
    };
    const pop = () => {
      const top = heap[0], lastE = heap.pop();
      if (heap.length) {
        heap[0] = lastE; let i = 0;
        for (;;) { const l = 2 * i + 1, r = l + 1; let m = i;
          if (l < heap.length && heap[l][0] < heap[m][0]) m = l;
          if (r < heap.length && heap[r][0] < heap[m][0]) m = r;
          if (m === i) break; [heap[m], heap[i]] = [heap[i], heap[m]]; i = m; }
      }
      return top;
    };
    const g0 = this.start[s0] + f0;
    dist[g0] = 0; push(0, g0);
    const seqOf = (g) => { let s = 0; while (s + 1 < this.start.length && this.start[s + 1] <= g) s++; return s; };
    let found = -1;
    while (heap.length) {
      const [d, g] = pop();
      if (d > dist[g]) continue;
      const s = seqOf(g), f = g - this.start[s];
      if (s === target && g !== g0) { found = g; break; }
      const relax = (h, c, k) => { if (d + c < dist[h]) { dist[h] = d + c; prev[h] = g; via[h] = k; push(d + c, h); } };
      if (f + 1 < this.len(s)) relax(g + 1, 1, -1);
      else relax(this.start[s], RESTART_PENALTY, -2);
      for (const k of this.out[s]) {
        const t = this.trans[k];
        if (this.startFrame(t) !== f) continue;
        relax(this.start[t.to] + this.clampF(t.to, this.endFrame(t)), 2 * t.window + 1, k);
      }
    }
    if (found < 0) return null;
    const path = [];
    for (let g = found; prev[g] >= 0; g = prev[g]) {
      if (via[g] >= 0) { const p = prev[g], s = seqOf(p); path.push({ k: via[g], s, f: p - this.start[s] }); }
    }
    return path.reverse();
  }

  // The latest self-transition of the current sequence still ahead.
  loopPlan() {
    let best = null;
    for (const k of this.out[this.seq]) {
      const t = this.trans[k];
      if (t.to !== this.seq) continue;
      const a = this.startFrame(t);
      if (a >= this.frame && (!best || a > best.f)) best = { k, s: this.seq, f: a };
    }
    return best ? [best] : [];
  }

  replan() {
    while (this.queue.length && this.plan.length === 0) {
      const want = this.queue[0];
      if (want === this.seq && this.goal === want) { this.queue.shift(); continue; }
      if (want === this.seq) { this.goal = want; this.queue.shift(); continue; }
      const p = this.route(this.seq, this.frame, want);
      this.queue.shift();
      if (p) { this.plan = p; this.goal = want; }
      break;
    }
    if (this.plan.length === 0 && this.seq === this.goal) this.plan = this.loopPlan();
  }

  // One frame on.
  tick() {
    this.ticks++;
    if (this.blend) {
      const t = this.trans[this.blend.k];
      this.blend.i++;
      if (this.blend.i <= 2 * t.window) return;
      this.W = compose(this.W, t.align);
      this.seq = t.to;
      this.frame = this.endFrame(t);
      this.blend = null;
      this.transitions++;
      this.last = { kind: 'transition', index: this.blend_k, from: this.seqs[t.from].name, to: this.seqs[t.to].name, m: t.m, n: t.n, window: t.window };
      if (this.frame >= this.len(this.seq)) this.restart();
      this.replan();
      return;
    }
    this.replan();
    const next = this.plan[0];
    if (next && next.s === this.seq && next.f === this.frame) {
      this.plan.shift();
      this.blend = { k: next.k, i: 0 };
      this.blend_k = next.k;
      return;
    }
    this.frame++;
    if (this.frame >= this.len(this.seq)) { this.restart(); this.plan = []; this.replan(); }
  }

  restart() {
    const s = this.seqs[this.seq];
    this.W = compose(this.W, s.restart);
    this.frame = 0;
    this.last = { kind: 'restart', from: s.name, to: s.name };
  }

  // What to draw: frames a and b (sequence, frame, transform) and the blend weight.
  view() {
    if (this.blend) {
      const t = this.trans[this.blend.k], i = this.blend.i, L = t.window;
      return {
        a: { s: t.from, f: this.clampF(t.from, t.m - L + i), W: this.W },
        b: { s: t.to, f: this.clampF(t.to, t.n - L + i), W: compose(this.W, t.align) },
        alpha: L === 0 ? 1 : i / (2 * L),
      };
    }
    const a = { s: this.seq, f: this.frame, W: this.W };
    return { a, b: a, alpha: 0 };
  }

  state() {
    const v = this.view();
    return {
      sequence: this.seqs[this.seq].name,
      frame: this.frame,
      shown: { sequence: this.seqs[v.a.s].name, frame: v.a.f, blend: v.alpha },
      goal: this.seqs[this.goal].name,
      queue: this.queue.map((s) => this.seqs[s].name),
      plan: this.plan.map((p) => p.k),
      blending: !!this.blend,
      lastTransition: this.last,
      transitions: this.transitions,
      ticks: this.ticks,
    };
  }
}
