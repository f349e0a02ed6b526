// A classic script (pages opened from disk refuse modules): its names
// are in `self.SurfDecode`.
self.SurfDecode = (() => {
'use strict';
// Decoder of the surfmotion compact 4D geometry (.sm4d, version 1); the
// layout is documented in src/web/codec.rs. Raw DEFLATE blocks are inflated
// by the browser (DecompressionStream "deflate-raw"); the varint residuals
// are undone here into quantised u16 positions, which the vertex shader
// turns into metres (origin + step * q).

const VERSION = 1;
const HEADER = 64;

function fail(offset, msg) {
  return new Error(`corrupt 4D geometry at byte ${offset}: ${msg}`);
}

async function inflate(bytes, offset) {
  try {
    const ds = new DecompressionStream('deflate-raw');
    const s = new Blob([bytes]).stream().pipeThrough(ds);
    return new Uint8Array(await new Response(s).arrayBuffer());
  } catch (e) {
    throw fail(offset, `the block does not inflate (${e.message || e})`);
  }
}

// Reads `count` zigzag LEB128 varints into an Int32Array.
function varints(raw, count, offset) {
  if (count > raw.length) throw fail(offset, `the block holds ${raw.length} bytes, too few for ${count} values`);
  const out = new Int32Array(count);
  let k = 0, z = 0, shift = 0;
  for (let i = 0; i < raw.length; i++) {
    const b = raw[i];
    if (shift > 28) throw fail(offset, 'a varint longer than 5 bytes');
    z |= (b & 0x7f) << shift;
    if (b & 0x80) { shift += 7; continue; }
    if (k >= count) throw fail(offset, `the block holds more than ${count} values`);
    z >>>= 0;
    out[k++] = (z >>> 1) ^ -(z & 1);
    z = 0; shift = 0;
  }
  if (k !== count || shift !== 0) throw fail(offset, `the block holds ${k} values, expected ${count}`);
  return out;
}

// parent[v]: the smallest index sharing a triangle with v when smaller than v, else v.
function parents(n, tris) {
  const p = new Uint32Array(n);
  for (let v = 0; v < n; v++) p[v] = v;
  for (let i = 0; i < tris.length; i += 3) {
    for (let a = 0; a < 3; a++) for (let b = 0; b < 3; b++) {
      const va = tris[i + a], vb = tris[i + b];
      if (vb < p[va]) p[va] = vb;
    }
  }
  return p;
}

// Undoes the prediction of one sequence while reading its zigzag varints
// (one pass, no intermediate array): for every frame t, axis c, vertex v,
// q = pred + residual, pred as in src/web/codec.rs.
function reconstruct(raw, frames, n, parent, predictor, levels, offset, s) {
  const count = frames * n * 3;
  if (count > raw.length) throw fail(offset, `the block holds ${raw.length} bytes, too few for ${count} values`);
  const q = new Uint16Array(count);
  const len = raw.length;
  const spatial = predictor === 1;
  let i = 0;
  for (let t = 0; t < frames; t++) {
    const cur = t * n * 3, prev = cur - n * 3;
    for (let c = 0; c < 3; c++) {
      const lim = levels[c];
      for (let v = 0; v < n; v++) {
        if (i >= len) throw fail(offset, `the block holds ${(t * 3 + c) * n + v} values, expected ${count}`);
        let b = raw[i++];
        let z = b & 0x7f;
        if (b & 0x80) {
          let shift = 7;
          do {
            if (i >= len) throw fail(offset, `the block holds ${(t * 3 + c) * n + v} values, expected ${count}`);
            if (shift > 28) throw fail(offset, 'a varint longer than 5 bytes');
            b = raw[i++];
            z |= (b & 0x7f) << shift;
            shift += 7;
          } while (b & 0x80);
          z >>>= 0;
        }
        const u = parent[v];
        const o = v * 3 + c;
        let pred;
        if (t === 0) pred = u !== v ? q[cur + u * 3 + c] : 0;
        else if (spatial && u !== v) pred = q[prev + o] + q[cur + u * 3 + c] - q[prev + u * 3 + c];
        else pred = q[prev + o];
        const x = pred + ((z >>> 1) ^ -(z & 1));
        if (x < 0 || x >= lim) throw fail(offset, `sequence ${s}, frame ${t}, vertex ${v}: position ${x} outside 0..${lim}`);
        q[cur + o] = x;
      }
    }
  }
  if (i !== len) throw fail(offset, `the block holds more than ${count} values`);
  return q;
}

async function decodeSm4d(buffer) {
  const b = new Uint8Array(buffer);
  const magic = 'SM4DGEO\0';
  if (b.length < 8 || [...magic].some((c, i) => b[i] !== c.charCodeAt(0)))
    throw fail(0, 'not a surfmotion 4D geometry file (bad magic)');
  if (b.length < HEADER) throw fail(b.length, `the file ends in its header (${b.length} bytes)`);
  const dv = new DataView(buffer);
  const u32 = (o) => dv.getUint32(o, true);
  const f32 = (o) => dv.getFloat32(o, true);
  const version = u32(8);
  if (version !== VERSION) throw fail(8, `version ${version}, this reader knows ${VERSION}`);
  const predictor = u32(12);
  if (predictor > 1) throw fail(12, `unknown predictor ${predictor}`);
  const n = u32(16), nt = u32(20), ns = u32(24);
  const step = f32(28);
  const origin = [f32(32), f32(36), f32(40)];
  const levels = [u32(44), u32(48), u32(52)];
  const maxError = f32(56);
  const topoBytes = u32(60);
  if (!(n > 0) || n > Math.min(1 << 26, b.length * 1100) || !(step > 0) || !isFinite(step) || origin.some((x) => !isFinite(x)) || levels.some((l) => l > 65536))
    throw fail(16, `${n} vertices, step ${step}, levels ${levels}`);
  if (HEADER + 8 * ns > b.length) throw fail(24, `${ns} sequences do not fit the file`);
  const table = [];
  for (let s = 0; s < ns; s++) table.push([u32(HEADER + 8 * s), u32(HEADER + 8 * s + 4)]);
  let at = HEADER + 8 * ns;
  const block = (len) => {
    if (at + len > b.length) throw fail(at, `a block of ${len} bytes runs past the end of the file (${b.length} bytes): truncated?`);
    return b.subarray(at, at + len);
  };
  const idx = varints(await inflate(block(topoBytes), at), nt * 3, at);
  const tris = new Uint32Array(nt * 3);
  let last = 0;
  for (let i = 0; i < idx.length; i++) {
    last += idx[i];
    if (last < 0 || last >= n) throw fail(at, `triangle ${Math.floor(i / 3)} names vertex ${last} of ${n}`);
    tris[i] = last;
  }
  at += topoBytes;
  const parent = parents(n, tris);
  // Every block's inflation starts at once (the browser inflates off the
  // script's thread); each sequence is rebuilt as its block arrives.
  const inflating = [];
  const starts = [];
  for (let s = 0; s < ns; s++) {
    const [frames, len] = table[s];
    if (frames * n * 3 > len * 1100) throw fail(HEADER + 8 * s, `sequence ${s}: ${frames} frames cannot come from ${len} bytes`);
    const p = inflate(block(len), at);
    p.catch(() => {});
    inflating.push(p);
    starts.push(at);
    at += len;
  }
  const sequences = [];
  for (let s = 0; s < ns; s++) {
    const frames = table[s][0];
    const q = reconstruct(await inflating[s], frames, n, parent, predictor, levels, starts[s], s);
    sequences.push({ frames, q });
  }
  if (at !== b.length) throw fail(at, `${b.length - at} bytes after the last block`);
  return { vertices: n, triangles: tris, step, origin, levels, maxError, sequences };
}

// Per-frame centre (metres) of every sequence: the camera follows it.
function centres(g) {
  const n = g.vertices;
  return g.sequences.map(({ frames, q }) => {
    const out = new Float32Array(frames * 3);
    for (let t = 0; t < frames; t++) {
      let x = 0, y = 0, z = 0;
      const o = t * n * 3;
      for (let v = 0; v < n; v++) { x += q[o + 3 * v]; y += q[o + 3 * v + 1]; z += q[o + 3 * v + 2]; }
      out[3 * t] = g.origin[0] + g.step * x / n;
      out[3 * t + 1] = g.origin[1] + g.step * y / n;
      out[3 * t + 2] = g.origin[2] + g.step * z / n;
    }
    return out;
  });
}
return { VERSION, parents, decodeSm4d, centres };
})();
