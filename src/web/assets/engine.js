// A classic script (pages opened from disk refuse modules): its names
// are in `self.SurfEngine`.
self.SurfEngine = (() => {
'use strict';
// The character animation engine (Volino, Huang & Hilton 2015, Sec. 5):
// it walks the Surface Motion Graph exported by `surfmotion web export`.
// A motion request joins a queue; the engine plans the shortest path in
// frames (Dijkstra over the frame graph: t -> t+1 inside a sequence, and
// each transition (i, m) -> (j, n) with half-window L taken from frame m-L
// of i to frame n+L+1 of j after 2L+1 blended frames), plays it, and blends
// linearly over each transition's window on the GPU. A motion with nothing
// queued loops through its latest self-transition ahead, else restarts.
// Each transition carries a ground-plane rigid alignment, so the character
// moves on instead of jumping back. Where the export precomputed a
// transition's window blended non-linearly (Huang et al. 2015, Sec. 4.4),
// those frames are played instead of the linear blend.
//
// Parametric spaces (Casas et al. 2013, Sec. 3): in a space the character
// is the hybrid blend (Eq. 3) of the stored reference frames: the two
// references bracketing the weight u, each at the two phase samples around
// the phase (four frames, blended on the GPU), placed at the integrated
// root. The speed slider sets u = h^-1(speed) (Sec. 3.1.4), u moves there
// at most 1.5 per second; a later `turn` parameter steers the heading.
// Entering or leaving a space cross-fades over FADE frames. This mirrors
// src/parametric/controller.rs.

// Ground-plane rigid motions [c, s, tx, tz]: x' = c x + s z + tx, z' = -s x + c z + tz.
const IDENTITY = [1, 0, 0, 0];
function compose(w, t) {
  const [a, b, ex, ez] = w, [c, s, tx, tz] = t;
  return [a * c - b * s, a * s + b * c, a * tx + b * tz + ex, -b * tx + a * tz + ez];
}
function apply(w, x, z) {
  return [w[0] * x + w[1] * z + w[2], -w[1] * x + w[0] * z + w[3]];
}
function mat4(w) {
  const [c, s, tx, tz] = w;
  return new Float32Array([c, 0, -s, 0, 0, 1, 0, 0, s, 0, c, 0, tx, 0, tz, 1]);
}

const RESTART_PENALTY = 60;
// Largest change of the weight coordinate per second (controller.rs).
const WEIGHT_RATE = 1.5;
// Frames of the cross-fade into and out of a space.
const FADE = 8;
// Steering range of a later `turn` parameter around the blend's own, deg/s.
const STEER = 90;

// The blended root step k at weight u: [x, z, dheading, duration] (params.rs).
function blendedStep(steps, u, k) {
  const last = steps.length - 1;
  u = Math.max(0, Math.min(last, u));
  const a = Math.min(Math.floor(u), Math.max(0, last - 1));
  const s = last === 0 ? 0 : u - a;
  const b = Math.min(a + 1, last);
  const x = steps[a][k], y = steps[b][k];
  return [0, 1, 2, 3].map((c) => x[c] + (y[c] - x[c]) * s);
}

// Plays `frames` frames from `phase` at weight u: [new phase, [x, z, dheading]] (space.rs).
function playPhase(sp, u, phase, frames) {
  const K = sp.grid;
  let p = ((phase % K) + K) % K, left = frames;
  const acc = [0, 0, 0];
  for (let it = 0; it < 4 * K + 4 && left > 1e-12; it++) {
    const i = Math.min(Math.floor(p), K - 1);
    const [x, z, dh, d] = blendedStep(sp.steps, u, i);
    const rest = i + 1 - p, need = rest * d;
    let take, dp;
    if (need <= left) { take = rest; dp = need; } else { take = left / Math.max(d, 1e-12); dp = left; }
    take = Math.min(take, rest);
    acc[0] += x * take; acc[1] += z * take; acc[2] += dh * take;
    left -= dp; p += take;
    if (p >= i + 1 - 1e-12) p = (i + 1) % K;
  }
  return [p, acc];
}

// The measured [speed, turn] at u (interpolated, space.rs).
function measuredAt(sp, u) {
  const s = sp.measured;
  if (s.length < 2) return s.length ? [s[0][1], s[0][2]] : [0, 0];
  const x = Math.max(0, Math.min(s.length - 1, u / 0.05));
  const k = Math.min(Math.floor(x), s.length - 2), t = x - k;
  return [s[k][1] + (s[k + 1][1] - s[k][1]) * t, s[k][2] + (s[k + 1][2] - s[k][2]) * t];
}

// u = h^-1(p), clamped to the valid range (params.rs).
function inverse(map, p) {
  const [lo, hi] = map.range;
  p = Math.max(lo, Math.min(hi, isFinite(p) ? p : lo));
  const S = map.samples;
  if (S.length < 2) return 0;
  const umax = S[S.length - 1][0];
  let u;
  if (map.fit === 'quadratic') {
    const x = (p - 0.5 * (lo + hi)) / Math.max(0.5 * (hi - lo), 1e-12);
    const [a, b, c] = map.quadratic;
    u = a + b * x + c * x * x;
  } else {
    const inc = S[S.length - 1][1] > S[0][1];
    const key = (s) => (inc ? s[1] : -s[1]), q = inc ? p : -p;
    let j = 0;
    while (j < S.length && key(S[j]) <= q) j++;
    j = Math.max(1, Math.min(S.length - 1, j));
    const a = S[j - 1], b = S[j], ka = key(a), kb = key(b);
    const t = kb > ka ? Math.max(0, Math.min(1, (q - ka) / (kb - ka))) : 0;
    u = a[0] + (b[0] - a[0]) * t;
  }
  return Math.max(0, Math.min(umax, u));
}

// [block0, block1, t]: the references bracketing u (geometry sequences; hybrid.rs).
function bracket(sp, u) {
  if (sp.pairs.length === 0) return [sp.first_block, sp.first_block, 0];
  u = Math.max(0, Math.min(sp.pairs.length, u));
  const a = Math.min(Math.floor(u), sp.pairs.length - 1), s = u - a, p = sp.pairs[a];
  let j = 0;
  while (j < p.weights.length && p.weights[j] <= s) j++;
  j = Math.max(1, Math.min(p.weights.length - 1, j));
  const w0 = p.weights[j - 1], w1 = p.weights[j];
  const t = w1 > w0 ? Math.max(0, Math.min(1, (s - w0) / (w1 - w0))) : 0;
  return [p.blocks[j - 1], p.blocks[j], t];
}

// Ground-plane placement of heading h at root (x, z).
const placement = (h, x, z) => [Math.cos(h), Math.sin(h), x, z];

class Engine {
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
    this.spaces = manifest.spaces || [];
    this.space = null; this.fade = null; this.centres = null;
  }

  // Per-frame centres (metres, per geometry sequence) for placing the
  // character when it enters or leaves a space.
  setCentres(c) { this.centres = c; }
  centre(s, f) { const c = this.centres && this.centres[s]; return c ? [c[3 * f], c[3 * f + 2]] : [0, 0]; }
  // Travel heading of sequence s around frame f in its own coordinates
  // (+Z is heading 0), or null when it barely moves.
  travel(s, f) {
    const g = Math.min(this.len(s) - 1, f + 10), a = Math.max(0, g - 10);
    const p = this.centre(s, a), q = this.centre(s, g);
    const dx = q[0] - p[0], dz = q[1] - p[1];
    return Math.hypot(dx, dz) > 0.05 ? Math.atan2(dx, dz) : null;
  }

  // The parts of the space's frame at its state (four, or two at the
  // nearest phase sample when `nearest`), placed, with total weight w.
  spaceParts(st, w, nearest) {
    const sp = this.spaces[st.index];
    const [b0, b1, t] = bracket(sp, st.u);
    const K = sp.grid, p = ((st.phase % K) + K) % K;
    const W = placement(st.heading, st.root[0], st.root[1]);
    if (nearest) {
      const k = Math.round(p) % K;
      return [{ s: b0, f: k, W, w: w * (1 - t) }, { s: b1, f: k, W, w: w * t }];
    }
    const k0 = Math.min(Math.floor(p), K - 1), k1 = (k0 + 1) % K, f = p - k0;
    return [
      { s: b0, f: k0, W, w: w * (1 - f) * (1 - t) }, { s: b0, f: k1, W, w: w * f * (1 - t) },
      { s: b1, f: k0, W, w: w * (1 - f) * t }, { s: b1, f: k1, W, w: w * f * t },
    ];
  }

  // Enters space i (or changes space) with a cross-fade from what is shown.
  enterSpace(i) {
    if (!(i >= 0 && i < this.spaces.length)) return;
    const sp = this.spaces[i];
    const v = this.view();
    const top = v.parts.reduce((a, b) => (b.w > a.w ? b : a));
    let root, heading;
    if (this.space) { root = this.space.root.slice(); heading = this.space.heading; }
    else {
      const c = this.centre(top.s, top.f);
      root = apply(top.W, c[0], c[1]);
      const h = top.s < this.seqs.length ? this.travel(top.s, top.f) : null;
      heading = (h === null ? 0 : h) + Math.atan2(top.W[1], top.W[0]);
    }
    const from = this.space ? this.spaceParts(this.space, 1, true) : [top];
    const u0 = this.space && this.space.index === i ? this.space.u : 0;
    const old = this.space || {};
    this.space = { index: i, u: u0, uTarget: u0, phase: 0, root, heading, speed: old.speed ?? null, turn: old.turn ?? null, path: [], turned: [] };
    this.applyControl();
    this.fade = { from, i: 0 };
    this.blend = null; this.plan = []; this.queue = [];
    this.last = { kind: 'space', to: sp.name };
  }

  // Leaves the space for sequence `seq`, frame 0, placed at the root facing the heading.
  leaveSpace(seq) {
    const st = this.space;
    const from = this.spaceParts(st, 1, true);
    const c = this.centre(seq, 0), h = this.travel(seq, 0);
    const th = st.heading - (h === null ? 0 : h);
    const R = [Math.cos(th), Math.sin(th), 0, 0];
    const p = apply(R, c[0], c[1]);
    this.W = [R[0], R[1], st.root[0] - p[0], st.root[1] - p[1]];
    this.seq = seq; this.frame = 0; this.goal = seq; this.plan = [];
    this.space = null;
    this.fade = { from, i: 0 };
    this.last = { kind: 'leave', from: this.spaces[st.index].name, to: this.seqs[seq].name };
  }

  // Slider input: speed (m/s) and turn (deg/s); null keeps the value.
  control(speed, turn) {
    if (!this.space) return;
    if (speed !== null && speed !== undefined) this.space.speed = speed;
    if (turn !== null && turn !== undefined) this.space.turn = turn;
    this.applyControl();
  }

  applyControl() {
    const st = this.space, sp = this.spaces[st.index];
    const first = sp.parameters[0];
    const want = first === 'speed' ? st.speed : first === 'turn' ? st.turn : null;
    if (sp.axis && want !== null && want !== undefined) st.uTarget = inverse(sp.axis, want);
  }

  // One frame in the space: the root step of the blended cycle, steering,
  // the weight towards its target (controller.rs, `advance`).
  spaceTick() {
    const st = this.space, sp = this.spaces[st.index], fps = sp.fps;
    const [p, d] = playPhase(sp, st.u, st.phase, 1);
    st.phase = p;
    let steer = 0;
    const ti = sp.parameters.indexOf('turn');
    if (ti > 0 && st.turn !== null) steer = (st.turn - measuredAt(sp, st.u)[1]) * Math.PI / 180 / fps;
    const [dx, dz] = apply([Math.cos(st.heading), Math.sin(st.heading), 0, 0], d[0], d[1]);
    st.root[0] += dx; st.root[1] += dz;
    st.heading += d[2] + steer;
    const du = WEIGHT_RATE / fps;
    st.u += Math.max(-du, Math.min(du, st.uTarget - st.u));
    // The achieved speed and turn: root path and heading change over the last second.
    st.path.push(Math.hypot(dx, dz)); st.turned.push(d[2] + steer);
    const keep = Math.max(1, Math.round(fps));
    if (st.path.length > keep) { st.path.shift(); st.turned.shift(); }
  }
  len(s) { return this.seqs[s].frames; }
  clampF(s, f) { return Math.max(0, Math.min(this.len(s) - 1, f)); }
  startFrame(t) { return this.clampF(t.from, t.m - t.window); }
  endFrame(t) { return t.n + t.window + 1; }

  request(seq) {
    if (seq < 0 || seq >= this.seqs.length) return;
    if (this.space) { this.leaveSpace(seq); return; }
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
    if (this.fade && ++this.fade.i >= FADE) this.fade = null;
    if (this.space) { this.spaceTick(); return; }
    if (this.fade) { this.frame = Math.min(this.frame + 1, this.len(this.seq) - 1); return; }
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

  // What to draw: up to four parts {s: geometry sequence, f: frame,
  // W: placement, w: weight}, weights summing to 1.
  view() {
    let parts;
    if (this.space) parts = this.spaceParts(this.space, 1, !!this.fade);
    else if (this.blend) {
      const t = this.trans[this.blend.k], i = this.blend.i, L = t.window;
      if (t.blended !== undefined && t.blended !== null) parts = [{ s: t.blended, f: i, W: this.W, w: 1 }];
      else {
        const alpha = L === 0 ? 1 : i / (2 * L);
        parts = [
          { s: t.from, f: this.clampF(t.from, t.m - L + i), W: this.W, w: 1 - alpha },
          { s: t.to, f: this.clampF(t.to, t.n - L + i), W: compose(this.W, t.align), w: alpha },
        ];
      }
    } else parts = [{ s: this.seq, f: this.frame, W: this.W, w: 1 }];
    if (this.fade) {
      const a = (this.fade.i + 1) / (FADE + 1);
      const from = this.fade.from.slice(0, 4 - parts.length).map((p) => ({ ...p, w: p.w * (1 - a) }));
      parts = parts.map((p) => ({ ...p, w: p.w * a })).concat(from);
    }
    return { parts };
  }

  state() {
    const v = this.view();
    const top = v.parts[0];
    let space = null;
    if (this.space) {
      const st = this.space, sp = this.spaces[st.index], fps = sp.fps;
      const secs = Math.max(1, st.path.length) / fps;
      space = {
        name: sp.name, u: st.u, uTarget: st.uTarget, phase: st.phase,
        speedAsked: st.speed, turnAsked: st.turn,
        achievedSpeed: st.path.reduce((x, y) => x + y, 0) / secs,
        achievedTurn: st.turned.reduce((x, y) => x + y, 0) * 180 / Math.PI / secs,
        modelSpeed: measuredAt(sp, st.u)[0], root: st.root.slice(), heading: st.heading,
        samples: st.path.length,
      };
    }
    return {
      sequence: this.space ? null : this.seqs[this.seq].name,
      space,
      fading: !!this.fade,
      frame: this.frame,
      shown: { part: top.s, frame: top.f, weights: v.parts.map((p) => p.w) },
      goal: this.space ? null : this.seqs[this.goal].name,
      queue: this.queue.map((s) => this.seqs[s].name),
      plan: this.plan.map((p) => p.k),
      blending: !!this.blend,
      lastTransition: this.last,
      transitions: this.transitions,
      ticks: this.ticks,
    };
  }
}
return { IDENTITY, compose, apply, mat4, WEIGHT_RATE, FADE, STEER, blendedStep, playPhase, measuredAt, inverse, bracket, Engine };
})();
