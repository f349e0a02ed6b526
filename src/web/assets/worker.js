// Fetches and decodes the geometry off the main thread.
import { decodeSm4d, centres } from './decode.js';

self.onmessage = async (e) => {
  try {
    const t0 = performance.now();
    const r = await fetch(e.data.url);
    if (!r.ok) throw new Error(`${e.data.url}: HTTP ${r.status}`);
    const buf = await r.arrayBuffer();
    const t1 = performance.now();
    const g = decodeSm4d ? await decodeSm4d(buf) : null;
    const c = centres(g);
    const t2 = performance.now();
    const transfer = [g.triangles.buffer, ...g.sequences.map((s) => s.q.buffer), ...c.map((x) => x.buffer)];
    self.postMessage({ ok: true, g, centres: c, bytes: buf.byteLength, fetchMs: t1 - t0, decodeMs: t2 - t1 }, transfer);
  } catch (err) {
    self.postMessage({ ok: false, error: String(err.message || err) });
  }
};
