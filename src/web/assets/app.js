// The page: loads manifest.json and the geometry (decoded in a worker),
// runs the engine (character mode) or a timeline (result mode), draws with
// the WebGL2 renderer, and shows any failure as a message on the page.
// `?selftest=1` runs the browser test's draw checks and timings and leaves
// them in `window.surfmotion.selftest`; tests/web.rs drives keys and
// sliders and reads the state through the DevTools protocol.
// A classic script, as are the others: a page opened from disk (file://)
// refuses modules, workers and fetch; there the manifest and geometry come
// from character.sm4d.js and are decoded on this thread.
(() => {
'use strict';
const { Engine, IDENTITY, mat4, apply, STEER } = window.SurfEngine;
const { Renderer } = window.SurfRender;
const FROM_DISK = location.protocol === 'file:';
const SERVE_HINT = 'open the site through a web server instead: `surfmotion web serve --site FOLDER` prints the address';

const $ = (id) => document.getElementById(id);
const params = new URLSearchParams(location.search);
const SELFTEST = params.has('selftest');
// Keys of the parametric spaces' buttons (the motions take 1-9).
const SPACE_KEYS = 'qwertyuio';
const errors = [];
const app = { ready: false, error: null, errors, stats: {} };
window.surfmotion = app;

const origError = console.error.bind(console);
console.error = (...a) => { errors.push(a.map(String).join(' ')); origError(...a); };
window.addEventListener('error', (e) => { errors.push(String(e.message)); showError(e.message); });
window.addEventListener('unhandledrejection', (e) => { errors.push(String(e.reason)); showError(e.reason && e.reason.message || e.reason); });

function showError(msg) {
  if (app.error) return;
  app.error = String(msg);
  $('loading').hidden = true;
  const box = $('error');
  // A missing WebGL2 context is the browser's or its graphics driver's,
  // wherever the page came from: the file:// hint would mislead there.
  const webgl = /WebGL/.test(app.error);
  const hint = webgl
    ? '\n(this browser or its graphics driver gives no WebGL2 context: try another browser, or turn on hardware acceleration)'
    : FROM_DISK ? '\n(opened from disk: ' + SERVE_HINT + ')' : '';
  box.textContent = 'Cannot show this character: ' + app.error + hint;
  box.hidden = false;
  if (SELFTEST) app.selftest = { ok: false, error: app.error, errorVisible: !box.hidden && box.offsetHeight > 0 };
}

function checkManifest(m) {
  const bad = (msg) => { throw new Error('manifest.json: ' + msg); };
  if (!m || m.format !== 'surfmotion-web') bad('not a surfmotion site manifest');
  if (m.version !== 1) bad(`version ${m.version}, this page knows 1`);
  if (!Array.isArray(m.sequences) || m.sequences.length === 0) bad('no sequences');
  for (const s of m.sequences) if (!(s.frames > 0) || !(s.fps > 0)) bad(`sequence ${s.name}: ${s.frames} frames at ${s.fps} fps`);
  for (const [k, t] of (m.transitions || []).entries()) {
    const A = m.sequences[t.from], B = m.sequences[t.to];
    if (!A || !B || !(t.m < A.frames) || !(t.n < B.frames) || !(t.window >= 0) || !Array.isArray(t.align))
      bad(`transition ${k} does not fit its sequences`);
  }
  for (const sp of m.spaces || []) {
    if (!(sp.grid > 0) || !(sp.fps > 0) || !Array.isArray(sp.pairs) || !Array.isArray(sp.steps) || sp.steps.some((s) => s.length !== sp.grid))
      bad(`space ${sp.name}: ${sp.grid} phase samples, ${sp.steps && sp.steps.length} root tracks`);
  }
}

// The geometry holds the manifest's sequences, then the spaces' reference
// blocks and the blended transition windows: every index and length must fit.
function checkGeometry(m, g) {
  const total = m.geometry_sequences || m.sequences.length;
  if (g.sequences.length !== total) throw new Error(`the geometry holds ${g.sequences.length} sequences, the manifest ${total}`);
  m.sequences.forEach((s, i) => { if (g.sequences[i].frames !== s.frames) throw new Error(`sequence ${s.name}: ${g.sequences[i].frames} frames in the geometry, ${s.frames} in the manifest`); });
  const frames = (s) => (Number.isInteger(s) && s >= 0 && s < total ? g.sequences[s].frames : -1);
  for (const [k, t] of (m.transitions || []).entries()) {
    if (t.blended !== undefined && t.blended !== null && frames(t.blended) !== 2 * t.window + 1)
      throw new Error(`transition ${k}: its blended window (geometry sequence ${t.blended}) does not hold ${2 * t.window + 1} frames`);
  }
  for (const sp of m.spaces || []) {
    const blocks = [sp.first_block, ...sp.pairs.flatMap((p) => p.blocks)];
    if (blocks.some((b) => frames(b) !== sp.grid)) throw new Error(`space ${sp.name}: a reference block is missing or not ${sp.grid} frames`);
  }
}

function decodeInWorker(url) {
  return new Promise((resolve, reject) => {
    const w = new Worker('worker.js');
    w.onmessage = (e) => { if (e.data.started) return; w.terminate(); e.data.ok ? resolve(e.data) : reject(new Error(e.data.error)); };
    w.onerror = (e) => { w.terminate(); reject(new Error('the decoder worker failed: ' + (e.message || 'unknown error'))); };
    w.postMessage({ url });
  });
}

// The page opened from disk: the manifest and geometry from
// character.sm4d.js (a classic script; browsers refuse fetch from file://),
// decoded on this thread.
function loadScript(src) {
  return new Promise((resolve, reject) => {
    const el = document.createElement('script');
    el.src = src;
    el.onload = resolve;
    el.onerror = () => reject(new Error(`${src} did not load (is it beside index.html?)`));
    document.head.appendChild(el);
  });
}

async function loadFromDisk() {
  if (!window.surfmotionData) await loadScript('character.sm4d.js');
  const data = window.surfmotionData;
  if (!data || !data.manifest || typeof data.geometry !== 'string') throw new Error('character.sm4d.js: no site data in it');
  const t0 = performance.now();
  let bin;
  try { bin = atob(data.geometry); } catch (e) { throw new Error('character.sm4d.js: the geometry is not base64'); }
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
  const t1 = performance.now();
  if (typeof DecompressionStream === 'undefined') throw new Error('this browser cannot inflate the geometry (no DecompressionStream)');
  const g = await window.SurfDecode.decodeSm4d(bytes.buffer);
  const centres = window.SurfDecode.centres(g);
  return { manifest: data.manifest, d: { g, centres, bytes: bytes.length, fetchMs: t1 - t0, decodeMs: performance.now() - t1 } };
}

async function main() {
  const t0 = performance.now();
  const stages = app.stats.stages = { start: t0 };
  // index.html started the manifest's download and the geometry's decode;
  // the WebGL2 context (0.4-0.5 s under software GL) starts meanwhile.
  const boot = FROM_DISK ? null : window.surfmotionBoot;
  let m, d, renderer;
  if (FROM_DISK) {
    renderer = new Renderer($('view'));
    stages.webgl = performance.now();
    ({ manifest: m, d } = await loadFromDisk());
    checkManifest(m);
    stages.manifest = performance.now();
  } else {
    const fetched = boot ? boot.manifest : fetch('manifest.json');
    // A worker starts through this thread, which creating the context blocks
    // for 0.4-0.5 s: let the decoder start first (at most 300 ms).
    if (boot) await Promise.race([boot.ready, new Promise((r) => setTimeout(r, 300))]);
    stages.workerStarted = performance.now();
    renderer = new Renderer($('view'));
    stages.webgl = performance.now();
    const r = await fetched;
    if (!r.ok) throw new Error(`manifest.json: HTTP ${r.status}`);
    try { m = await r.json(); } catch (e) { throw new Error('manifest.json: not JSON (' + e.message + ')'); }
    checkManifest(m);
    stages.manifest = performance.now();
    const pending = boot && boot.url === m.geometry ? boot.geometry : decodeInWorker(m.geometry);
    d = await pending;
  }
  const g = d.g;
  checkGeometry(m, g);
  stages.decoded = performance.now();
  renderer.load(g);
  stages.uploaded = performance.now();
  if (d.at) for (const k of ['worker', 'fetched', 'decoded']) stages['w_' + k] = d.at[k] - performance.timeOrigin;
  app.stats.fetchMs = d.fetchMs; app.stats.decodeMs = d.decodeMs; app.stats.bytes = d.bytes;
  $('title').textContent = m.name;
  $('loading').hidden = true;

  const result = m.mode === 'result';
  const engine = result ? null : new Engine(m);
  if (engine) engine.setCentres(d.centres);
  app.engine = engine; app.manifest = m;
  let scrubFrame = 0, playing = true;
  const buttons = [], spaceButtons = [];
  if (result) {
    $('timeline').style.display = 'flex';
    const sc = $('scrub'); sc.max = m.sequences[0].frames - 1;
    sc.oninput = () => { scrubFrame = +sc.value; playing = false; $('play').textContent = 'play'; };
    $('play').onclick = () => { playing = !playing; $('play').textContent = playing ? 'pause' : 'play'; };
  } else {
    m.sequences.forEach((s, i) => {
      const b = document.createElement('button');
      b.textContent = (i < 9 ? `${i + 1} ` : '') + s.name;
      b.onclick = () => engine.request(i);
      $('bar').appendChild(b); buttons.push(b);
    });
    (m.spaces || []).forEach((sp, i) => {
      const b = document.createElement('button');
      b.textContent = (i < SPACE_KEYS.length ? `${SPACE_KEYS[i]} ` : '') + sp.name;
      b.className = 'space';
      b.onclick = () => enterSpace(i);
      $('bar').appendChild(b); spaceButtons.push(b);
    });
  }
  // Speed and turn sliders of the current space (Casas et al. 2013,
  // Sec. 3.1.4): the speed sets the blend weight through h^-1, a later
  // `turn` steers.
  function enterSpace(i) {
    engine.enterSpace(i);
    const sp = m.spaces[i];
    const set = (name, el, lab) => {
      const k = sp.parameters.indexOf(name);
      el.parentElement.hidden = k < 0;
      if (k < 0) return null;
      let [lo, hi] = sp.ranges[k];
      if (name === 'turn' && k > 0) { lo = Math.min(lo, -STEER); hi = Math.max(hi, STEER); }
      el.min = lo; el.max = hi; el.step = (hi - lo) / 200 || 0.01;
      const clamp = (x) => Math.max(lo, Math.min(hi, x));
      const v = el.dataset.set ? clamp(+el.value) : clamp(name === 'turn' ? 0 : lo);
      el.dataset.set = '1';
      el.value = v; lab.textContent = v.toFixed(2);
      return +el.value;
    };
    const speed = set('speed', $('speed'), $('speedv'));
    const turn = set('turn', $('turn'), $('turnv'));
    $('sliders').hidden = false;
    engine.control(speed, turn);
  }
  app.enterSpace = enterSpace;
  $('speed').oninput = () => { $('speedv').textContent = (+$('speed').value).toFixed(2); engine.control(+$('speed').value, null); };
  $('turn').oninput = () => { $('turnv').textContent = (+$('turn').value).toFixed(1); engine.control(null, +$('turn').value); };
  window.addEventListener('keydown', (e) => {
    if (result) {
      if (e.key === ' ') { playing = !playing; $('play').textContent = playing ? 'pause' : 'play'; }
      if (e.key === 'ArrowRight') scrubFrame = Math.min(scrubFrame + 1, m.sequences[0].frames - 1);
      if (e.key === 'ArrowLeft') scrubFrame = Math.max(scrubFrame - 1, 0);
      return;
    }
    const k = parseInt(e.key, 10);
    if (k >= 1 && k <= m.sequences.length) { engine.request(k - 1); $('sliders').hidden = !engine.space; }
    const sk = SPACE_KEYS.indexOf(e.key);
    if (sk >= 0 && sk < (m.spaces || []).length) enterSpace(sk);
  });

  // Orbit camera around the character's centre.
  const cam = { yaw: 0.6, pitch: 0.25, dist: 4.5, at: [0, 1, 0] };
  const cv = $('view');
  let drag = null;
  cv.addEventListener('pointerdown', (e) => { drag = [e.clientX, e.clientY]; cv.setPointerCapture(e.pointerId); });
  cv.addEventListener('pointerup', () => { drag = null; });
  cv.addEventListener('pointermove', (e) => {
    if (!drag) return;
    cam.yaw -= (e.clientX - drag[0]) * 0.008;
    cam.pitch = Math.max(-0.2, Math.min(1.4, cam.pitch + (e.clientY - drag[1]) * 0.008));
    drag = [e.clientX, e.clientY];
  });
  cv.addEventListener('wheel', (e) => { cam.dist = Math.max(0.8, Math.min(30, cam.dist * Math.exp(e.deltaY * 0.001))); e.preventDefault(); }, { passive: false });

  const centre = (v) => {
    const c = d.centres[v.s];
    const [x, z] = apply(v.W, c[3 * v.f], c[3 * v.f + 2]);
    return [x, c[3 * v.f + 1], z];
  };
  let first = true;
  const finite = (p) => p.every(Number.isFinite);
  const camAt = (v) => {
    const c = centre(v.parts.reduce((a, b) => (b.w > a.w ? b : a)));
    // A target that is not a number never sticks (a frame index out of
    // range once made it NaN for good: a blank page).
    if (!finite(cam.at)) { cam.at = [0, 1, 0]; first = true; }
    if (finite(c)) {
      // Far off (a restart or a jump while not drawing): look there at once.
      if (first || Math.hypot(c[0] - cam.at[0], c[2] - cam.at[2]) > 3) { cam.at = c.slice(); first = false; }
      for (let i = 0; i < 3; i++) cam.at[i] += (c[i] - cam.at[i]) * 0.15;
    }
    const e = [cam.at[0] + cam.dist * Math.cos(cam.pitch) * Math.sin(cam.yaw), cam.at[1] + cam.dist * Math.sin(cam.pitch), cam.at[2] + cam.dist * Math.cos(cam.pitch) * Math.cos(cam.yaw)];
    return { eye: e, at: cam.at.slice() };
  };

  // What the geometry sequences after the motions are, for the status line:
  // a transition's precomputed window, or a space's reference frames.
  const partNames = new Map();
  (m.transitions || []).forEach((t) => {
    if (t.blended !== undefined && t.blended !== null) partNames.set(t.blended, `transition ${m.sequences[t.from].name} ${t.m} -> ${m.sequences[t.to].name} ${t.n}, window`);
  });
  (m.spaces || []).forEach((sp) => [sp.first_block, ...sp.pairs.flatMap((p) => p.blocks)].forEach((b) => partNames.set(b, `space ${sp.name} reference`)));
  const where = (s) => (s < m.sequences.length ? m.sequences[s].name : partNames.get(s) || `geometry sequence ${s}`);
  app.partName = where;

  const timing = { engine: [], gl: [] };
  let frames = 0;
  // Advances `ticks` frames and draws; returns {engineMs, glMs}.
  const step = (ticks, finish) => {
    const a = performance.now();
    let v;
    if (result) {
      const total = m.sequences[0].frames;
      if (playing && ticks > 0) scrubFrame = (scrubFrame + ticks) % total;
      // Always a frame of the sequence (a negative first tick drew frame -1).
      scrubFrame = Number.isFinite(scrubFrame) ? Math.min(total - 1, Math.max(0, Math.floor(scrubFrame))) : 0;
      $('scrub').value = scrubFrame;
      v = { parts: [{ s: 0, f: scrubFrame, W: IDENTITY, w: 1 }] };
    } else {
      for (let i = 0; i < ticks; i++) engine.tick();
      v = engine.view();
    }
    const mats = v.parts.map((p) => mat4(p.W));
    const c = camAt(v);
    const b = performance.now();
    renderer.draw(v, c, mats);
    if (finish) renderer.gl.finish();
    const e = performance.now();
    frames++;
    app.stats.drawn = frames;
    const st = result ? null : engine.state();
    if (!result) {
      buttons.forEach((bt, i) => bt.classList.toggle('on', m.sequences[i].name === st.goal));
      spaceButtons.forEach((bt, i) => bt.classList.toggle('on', !!st.space && m.spaces[i].name === st.space.name));
    }
    $('status').textContent = result
      ? `frame ${scrubFrame + 1} / ${m.sequences[0].frames}`
      : st.space
        ? `space ${st.space.name}  u ${st.space.u.toFixed(2)}  speed ${st.space.achievedSpeed.toFixed(2)} m/s  turn ${st.space.achievedTurn.toFixed(1)} deg/s${st.fading ? '  (fade)' : ''}  drawn ${frames}`
        : `${where(st.shown.part)} frame ${st.shown.frame}${st.blending ? ' (transition)' : ''}${st.fading ? ' (fade)' : ''}` +
          `  queue [${st.queue.join(', ')}]  transitions ${st.transitions}  drawn ${frames}`;
    return { engineMs: b - a, glMs: e - b, view: v };
  };
  app.step = step;

  const fps = m.sequences[0].fps;
  app.ready = true;
  app.stats.loadMs = performance.now();
  app.stats.setupMs = performance.now() - t0;
  if (SELFTEST) { selftest(app, step, renderer, m); return; }
  let acc = 0, last = performance.now();
  const loop = (now) => {
    // The first callback's time can precede `last` (it is the frame's
    // start): a negative step is no step.
    const dt = (now - last) / 1000; last = Math.max(last, now);
    if (dt > 0) acc += Math.min(0.25, dt);
    const ticks = Math.max(0, Math.floor(acc * fps)); acc -= ticks / fps;
    const t = step(ticks, false);
    timing.engine.push(t.engineMs); if (timing.engine.length > 120) timing.engine.shift();
    app.stats.engineMs = timing.engine.reduce((x, y) => x + y, 0) / timing.engine.length;
    requestAnimationFrame(loop);
  };
  requestAnimationFrame(loop);
}

// Character pixels: the warm skin colour (red well above blue).
function characterMask(gl) {
  const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
  const px = new Uint8Array(w * h * 4);
  gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
  const mask = new Uint8Array(w * h);
  let count = 0;
  for (let i = 0; i < w * h; i++) {
    if (px[4 * i] > px[4 * i + 2] + 40) { mask[i] = 1; count++; }
  }
  return { mask, count };
}

async function selftest(app, step, renderer, m) {
  const gl = renderer.gl;
  const pause = () => new Promise((r) => setTimeout(r, 0));
  const out = { ok: true, webgl2: gl instanceof WebGL2RenderingContext, loadMs: app.stats.loadMs, fetchMs: app.stats.fetchMs, decodeMs: app.stats.decodeMs, mode: m.mode };
  const shots = params.has('shots') ? [] : null;
  const skip = +(params.get('skip') || 0);
  for (let i = 0; i < skip; i++) step(1, false);
  step(0, true);
  app.stats.stages.firstFrame = performance.now();
  out.loadMs = app.stats.stages.firstFrame;
  const a = characterMask(gl);
  if (shots) shots.push(gl.canvas.toDataURL('image/png'));
  const gap = +(params.get('gap') || 10);
  for (let i = 0; i < gap; i++) { step(1, false); if (i % 10 === 0) await pause(); }
  step(1, true);
  const b = characterMask(gl);
  if (shots) shots.push(gl.canvas.toDataURL('image/png'));
  out.shots = shots;
  let diff = 0;
  for (let i = 0; i < a.mask.length; i++) diff += a.mask[i] !== b.mask[i];
  out.characterPixels = [a.count, b.count]; out.diffPixels = diff;
  if (app.engine) out.engineTransitions = app.engine.trans.map((t) => [t.from, t.to, t.m, t.n, t.window]);
  // Keys, sliders and console errors are driven and collected from
  // outside, through the DevTools protocol (tests/web.rs).
  if (app.engine) out.before = app.engine.state();
  // performance.now() is coarse (0.1 ms) in headless Chromium: sum over
  // batches of frames. Engine = ticks + view + matrices + camera; GL = the
  // draw calls and gl.finish() (software GL here).
  let eng = 0, glt = 0, worst = 0;
  const N = 120;
  for (let i = 0; i < N; i++) { const t = step(1, true); eng += t.engineMs; glt += t.glMs; worst = Math.max(worst, t.engineMs); if (i % 20 === 0) await pause(); }
  const e0 = performance.now();
  for (let i = 0; i < 1000; i++) { app.engine ? app.engine.tick() : 0; }
  out.engineTickMs = (performance.now() - e0) / 1000;
  out.engineMsMean = eng / N; out.glMsMean = glt / N; out.engineMsMax = worst;
  out.stages = app.stats.stages;
  out.errors = errors.slice();
  out.errorShown = !!app.error;
  out.canvas = [gl.drawingBufferWidth, gl.drawingBufferHeight];
  app.selftest = out;
  document.title = 'selftest done';
}

main().catch((e) => showError(e.message || e));
})();
