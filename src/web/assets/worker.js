// Fetches and decodes the geometry off the main thread (a classic worker).
importScripts('decode.js');
const { decodeSm4d, centres } = self.SurfDecode;

self.onmessage = async (e) => {
  try {
    const t0 = performance.now();
    const fetching = fetch(e.data.url);
    // The page creates its WebGL2 context (blocking its thread) only once
    // this worker runs: a worker starts through the page's thread.
    self.postMessage({ started: true });
    const r = await fetching;
    if (!r.ok) throw new Error(`${e.data.url}: HTTP ${r.status}`);
    const buf = await r.arrayBuffer();
    const t1 = performance.now();
    const g = decodeSm4d ? await decodeSm4d(buf) : null;
    const c = centres(g);
    const t2 = performance.now();
    const transfer = [g.triangles.buffer, ...g.sequences.map((s) => s.q.buffer), ...c.map((x) => x.buffer)];
    // Absolute times (ms since the epoch): the page turns them into its stages.
    const abs = (t) => performance.timeOrigin + t;
    self.postMessage({ ok: true, g, centres: c, bytes: buf.byteLength, fetchMs: t1 - t0, decodeMs: t2 - t1, at: { worker: abs(t0), fetched: abs(t1), decoded: abs(t2) } }, transfer);
  } catch (err) {
    self.postMessage({ ok: false, error: String(err.message || err) });
  }
};
