// The page of `rig embed --pick` / `db init --pick` (src/web/pick/): the
// rest mesh coloured by body part (WebGL2), the skeleton and the landmarks
// drawn over it (a 2D canvas), landmarks dragged over the surface, the rig
// embedded again by the server after each move, Save.
//
// Query: ?view=front|side|back (the first camera), ?overlay=0 (no
// skeleton or handles: the part colours alone), ?move=NAME:x,y,z (move a
// landmark once loaded, as a drag ending there would: snapped to the
// surface). Script API: window.pick (ready, state, move, save, project,
// setView, setOverlay, drawn).
'use strict';
(() => {
const $ = (id) => document.getElementById(id);
const q = new URLSearchParams(location.search);
const pick = { ready: false, error: null, state: null, mesh: null, drawn: 0, busy: 0 };
window.pick = pick;

// --- small vector and matrix helpers (column-major 4x4) ---
const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
const mul = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const norm = (a) => { const l = Math.hypot(a[0], a[1], a[2]) || 1; return [a[0] / l, a[1] / l, a[2] / l]; };

// The part colours of `rig embed --png` (tools::render::label_colour).
function partColour(k) {
  const h = (k * 137.508) % 360, s = 0.65, v = 0.95, c = v * s;
  const x = c * (1 - Math.abs((h / 60) % 2 - 1));
  const t = [[c, x, 0], [x, c, 0], [0, c, x], [0, x, c], [x, 0, c], [c, 0, x]][Math.min(5, Math.floor(h / 60))];
  const m = v - c;
  return t.map((u) => Math.round((u + m) * 255) / 255);
}

const VS = `#version 300 es
in vec3 aP; in vec3 aC;
uniform mat4 uVP;
out vec3 vPos; flat out vec3 vCol;
void main() { vPos = aP; vCol = aC; gl_Position = uVP * vec4(aP, 1.0); }`;
const FS = `#version 300 es
precision highp float;
in vec3 vPos; flat in vec3 vCol;
uniform vec3 uEye; uniform vec3 uUp;
out vec4 o;
void main() {
  vec3 n = normalize(cross(dFdx(vPos), dFdy(vPos)));
  vec3 e = normalize(uEye - vPos);
  if (dot(n, e) < 0.0) n = -n;
  float d = max(dot(n, e), 0.0);
  float hemi = 0.5 + 0.5 * dot(n, uUp);
  vec3 c = vCol * (0.25 + 0.25 * hemi + 0.6 * d);
  o = vec4(pow(c, vec3(1.0 / 2.2)), 1.0);
}`;

let gl, prog, buf = {}, nIdx = 0;
let cam = null; // {centre, dist, yaw, pitch, U, F, L}
let overlay = q.get('overlay') !== '0';
let drag = null; // {name, point, moved} or {orbit: [x, y]}
let dirty = true;

function status(text, error) {
  const s = $('status');
  s.textContent = text;
  s.className = error ? 'error' : '';
}

async function api(path, body) {
  const init = body === undefined ? {} : { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(body) };
  const r = await fetch(path, init);
  let v = null;
  try { v = await r.json(); } catch (e) { v = { error: `${path}: ${r.status}, not JSON` }; }
  return { status: r.status, body: v };
}

function setupGL() {
  const c = $('gl');
  gl = c.getContext('webgl2', { antialias: true, preserveDrawingBuffer: true });
  if (!gl) throw new Error('this browser has no WebGL2');
  prog = gl.createProgram();
  for (const [t, src] of [[gl.VERTEX_SHADER, VS], [gl.FRAGMENT_SHADER, FS]]) {
    const s = gl.createShader(t);
    gl.shaderSource(s, src); gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error('shader: ' + gl.getShaderInfoLog(s));
    gl.attachShader(prog, s);
  }
  gl.bindAttribLocation(prog, 0, 'aP');
  gl.bindAttribLocation(prog, 1, 'aC');
  gl.linkProgram(prog);
  if (!gl.getProgramParameter(prog, gl.LINK_STATUS)) throw new Error('link: ' + gl.getProgramInfoLog(prog));
  const m = pick.mesh;
  buf.vao = gl.createVertexArray();
  gl.bindVertexArray(buf.vao);
  buf.pos = gl.createBuffer();
  gl.bindBuffer(gl.ARRAY_BUFFER, buf.pos);
  gl.bufferData(gl.ARRAY_BUFFER, new Float32Array(m.positions), gl.STATIC_DRAW);
  gl.enableVertexAttribArray(0);
  gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 0, 0);
  buf.col = gl.createBuffer();
  gl.bindBuffer(gl.ARRAY_BUFFER, buf.col);
  gl.bufferData(gl.ARRAY_BUFFER, new Float32Array(m.positions.length).fill(0.7), gl.DYNAMIC_DRAW);
  gl.enableVertexAttribArray(1);
  gl.vertexAttribPointer(1, 3, gl.FLOAT, false, 0, 0);
  buf.idx = gl.createBuffer();
  gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, buf.idx);
  gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, new Uint32Array(m.triangles), gl.STATIC_DRAW);
  nIdx = m.triangles.length;
}

function uploadColours() {
  const s = pick.state, n = pick.mesh.positions.length / 3;
  const c = new Float32Array(3 * n);
  const pal = pick.mesh.parts.map((_, k) => partColour(k));
  for (let v = 0; v < n; v++) {
    const col = s.labels ? pal[s.labels[v]] : [0.7, 0.7, 0.7];
    c[3 * v] = col[0]; c[3 * v + 1] = col[1]; c[3 * v + 2] = col[2];
  }
  gl.bindBuffer(gl.ARRAY_BUFFER, buf.col);
  gl.bufferData(gl.ARRAY_BUFFER, c, gl.DYNAMIC_DRAW);
}

// --- camera ---
function initCamera() {
  const s = pick.state, p = pick.mesh.positions;
  const U = norm(s.up || [0, 1, 0]);
  let F = s.facing || [0, 0, 1];
  F = norm(sub(F, mul(U, dot(F, U))));
  const L = cross(U, F);
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < p.length; i += 3) for (let k = 0; k < 3; k++) { lo[k] = Math.min(lo[k], p[i + k]); hi[k] = Math.max(hi[k], p[i + k]); }
  const centre = mul(add(lo, hi), 0.5);
  const size = Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  cam = { centre, dist: 1.5 * size, size, yaw: 0, pitch: 0.08, U, F, L };
  setView(q.get('view') || 'front');
}

function setView(v) {
  cam.yaw = { front: 0, side: Math.PI / 2, back: Math.PI, left: Math.PI / 2, right: -Math.PI / 2 }[v] ?? 0;
  cam.pitch = 0.08;
  dirty = true;
}

function camera() {
  const c = $('gl'), w = c.clientWidth, h = c.clientHeight;
  const { U, F, L } = cam;
  const dir = add(mul(add(mul(F, Math.cos(cam.yaw)), mul(L, Math.sin(cam.yaw))), Math.cos(cam.pitch)), mul(U, Math.sin(cam.pitch)));
  const eye = add(cam.centre, mul(dir, cam.dist));
  const f = norm(sub(cam.centre, eye)), s = norm(cross(f, U)), u = cross(s, f);
  const fov = 35 * Math.PI / 180, t = Math.tan(fov / 2), aspect = w / Math.max(1, h);
  const n = cam.dist * 0.05, fa = cam.dist * 4;
  const view = [s[0], u[0], -f[0], 0, s[1], u[1], -f[1], 0, s[2], u[2], -f[2], 0, -dot(s, eye), -dot(u, eye), dot(f, eye), 1];
  const proj = [1 / (t * aspect), 0, 0, 0, 0, 1 / t, 0, 0, 0, 0, (fa + n) / (n - fa), -1, 0, 0, 2 * fa * n / (n - fa), 0];
  const vp = new Array(16).fill(0);
  for (let i = 0; i < 4; i++) for (let j = 0; j < 4; j++) for (let k = 0; k < 4; k++) vp[j * 4 + i] += proj[k * 4 + i] * view[j * 4 + k];
  return { eye, f, s, u, t, aspect, w, h, vp };
}

// A point's position on the page (CSS pixels, from the view's corner).
function project(p, cm) {
  const c = cm || camera(), m = c.vp;
  const x = m[0] * p[0] + m[4] * p[1] + m[8] * p[2] + m[12];
  const y = m[1] * p[0] + m[5] * p[1] + m[9] * p[2] + m[13];
  const w = m[3] * p[0] + m[7] * p[1] + m[11] * p[2] + m[15];
  return [(x / w + 1) / 2 * c.w, (1 - y / w) / 2 * c.h];
}

// The nearest surface point under a page position, or null.
function raycast(px, py) {
  const c = camera();
  const nx = 2 * px / c.w - 1, ny = 1 - 2 * py / c.h;
  const d = norm(add(c.f, add(mul(c.s, nx * c.t * c.aspect), mul(c.u, ny * c.t))));
  const o = c.eye, P = pick.mesh.positions, T = pick.mesh.triangles;
  let best = Infinity;
  for (let i = 0; i < T.length; i += 3) {
    const a = 3 * T[i], b = 3 * T[i + 1], cc = 3 * T[i + 2];
    const e1 = [P[b] - P[a], P[b + 1] - P[a + 1], P[b + 2] - P[a + 2]];
    const e2 = [P[cc] - P[a], P[cc + 1] - P[a + 1], P[cc + 2] - P[a + 2]];
    const pv = cross(d, e2), det = dot(e1, pv);
    if (Math.abs(det) < 1e-12) continue;
    const tv = [o[0] - P[a], o[1] - P[a + 1], o[2] - P[a + 2]];
    const uu = dot(tv, pv) / det;
    if (uu < 0 || uu > 1) continue;
    const qv = cross(tv, e1), vv = dot(d, qv) / det;
    if (vv < 0 || uu + vv > 1) continue;
    const tt = dot(e2, qv) / det;
    if (tt > 0 && tt < best) best = tt;
  }
  return best < Infinity ? add(o, mul(d, best)) : null;
}

// --- drawing ---
function resize() {
  const dpr = window.devicePixelRatio || 1;
  for (const id of ['gl', 'overlay']) {
    const c = $(id), w = Math.round(c.clientWidth * dpr), h = Math.round(c.clientHeight * dpr);
    if (c.width !== w || c.height !== h) { c.width = w; c.height = h; dirty = true; }
  }
}

function draw() {
  requestAnimationFrame(draw);
  if (!pick.mesh || !cam) return;
  resize();
  if (!dirty) return;
  dirty = false;
  const c = camera();
  gl.viewport(0, 0, gl.drawingBufferWidth, gl.drawingBufferHeight);
  gl.clearColor(0.78, 0.82, 0.87, 1);
  gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
  gl.enable(gl.DEPTH_TEST);
  gl.useProgram(prog);
  gl.uniformMatrix4fv(gl.getUniformLocation(prog, 'uVP'), false, new Float32Array(c.vp));
  gl.uniform3fv(gl.getUniformLocation(prog, 'uEye'), c.eye);
  gl.uniform3fv(gl.getUniformLocation(prog, 'uUp'), cam.U);
  gl.bindVertexArray(buf.vao);
  gl.drawElements(gl.TRIANGLES, nIdx, gl.UNSIGNED_INT, 0);
  drawOverlay(c);
  pick.drawn++;
}

function landmarkPoints() {
  const out = Object.assign({}, pick.state.landmarks);
  if (drag && drag.name && drag.point) out[drag.name] = drag.point;
  return out;
}

function drawOverlay(c) {
  const o = $('overlay'), g = o.getContext('2d'), dpr = window.devicePixelRatio || 1;
  g.setTransform(dpr, 0, 0, dpr, 0, 0);
  g.clearRect(0, 0, o.width, o.height);
  if (!overlay) return;
  const s = pick.state;
  g.lineCap = 'round';
  for (const [a, b] of s.bones || []) {
    const pa = project(a, c), pb = project(b, c);
    for (const [w, col] of [[5, '#1d2430'], [2.5, '#fff7d6']]) {
      g.strokeStyle = col; g.lineWidth = w;
      g.beginPath(); g.moveTo(pa[0], pa[1]); g.lineTo(pb[0], pb[1]); g.stroke();
    }
  }
  for (const j of Object.values(s.joints || {})) {
    const p = project(j, c);
    g.fillStyle = '#1d2430'; g.beginPath(); g.arc(p[0], p[1], 4, 0, 2 * Math.PI); g.fill();
    g.fillStyle = '#ffd23f'; g.beginPath(); g.arc(p[0], p[1], 2.5, 0, 2 * Math.PI); g.fill();
  }
  g.font = '11px system-ui, sans-serif';
  for (const [name, pt] of Object.entries(landmarkPoints())) {
    const p = project(pt, c), active = drag && drag.name === name;
    g.lineWidth = 2.5;
    g.strokeStyle = '#1d2430'; g.beginPath(); g.arc(p[0], p[1], 8, 0, 2 * Math.PI); g.stroke();
    g.lineWidth = 1.5;
    g.strokeStyle = active ? '#ffd23f' : (s.required.includes(name) ? '#ffffff' : '#b8c2cf');
    g.beginPath(); g.arc(p[0], p[1], 8, 0, 2 * Math.PI); g.stroke();
    g.fillStyle = '#1d2430'; g.fillText(name, p[0] + 10, p[1] - 8);
  }
}

// --- the panel ---
function showState() {
  const s = pick.state;
  $('title').textContent = s.name;
  $('notice').textContent = s.notice
    ? `started from automatic landmarks, refused: ${s.notice}. Move them, then Save.`
    : (s.input ? '' : 'started from automatic landmarks: check them, move any that are wrong, then Save.');
  if (s.error) status(`no rig from these landmarks: ${s.error}`, true);
  else status(`embedded (revision ${s.revision}); height ${(+s.height).toFixed(3)}`, false);
  const lt = $('landmarks');
  lt.innerHTML = '';
  for (const [name, p] of Object.entries(s.landmarks)) {
    const tr = lt.insertRow();
    tr.insertCell().textContent = name;
    for (const x of p) { const td = tr.insertCell(); td.className = 'num'; td.textContent = x.toFixed(3); }
    if (drag && drag.name === name) tr.className = 'sel';
  }
  const pt = $('parts');
  pt.innerHTML = '';
  pick.mesh.parts.forEach((name, k) => {
    const tr = pt.insertRow(), sw = document.createElement('span');
    sw.className = 'sw';
    sw.style.background = `rgb(${partColour(k).map((x) => Math.round(255 * x)).join(',')})`;
    tr.insertCell().appendChild(sw);
    tr.insertCell().textContent = name;
    const td = tr.insertCell(); td.className = 'num';
    td.textContent = s.partSizes ? s.partSizes[k] : '';
  });
  $('notes').textContent = (s.notes || []).join('; ');
  if (!$('path').value) $('path').value = s.defaultSave;
  uploadColours();
  dirty = true;
}

// Moves landmark `name` to `p` (snapped to the surface by the server) and
// embeds again: {status, state}; 422 keeps the landmarks as they were.
async function move(name, p) {
  const marks = {};
  for (const [k, v] of Object.entries(pick.state.landmarks)) marks[k] = (pick.state.vertexIds || {})[k] ?? v;
  marks[name] = p;
  pick.busy++;
  status(`embedding with ${name} moved…`, false);
  try {
    const r = await api('/api/embed', { landmarks: marks, snap: [name] });
    if (r.status === 200 || r.status === 422) {
      pick.state = r.body;
      showState();
      if (r.status === 422) status(`${name} not moved: ${r.body.rejected}`, true);
    } else {
      status(`${name}: ${r.body.error}`, true);
    }
    return { status: r.status, state: r.body };
  } finally {
    pick.busy--;
  }
}

async function save(path) {
  const r = await api('/api/save', path ? { path } : {});
  if (r.status === 200) {
    pick.state = r.body.state;
    $('saved').textContent = `saved ${r.body.saved}`;
  } else {
    $('saved').textContent = '';
    status(`not saved: ${r.body.error}`, true);
  }
  return r;
}

// --- pointer ---
function pointerAt(e) {
  const r = $('gl').getBoundingClientRect();
  return [e.clientX - r.left, e.clientY - r.top];
}

function setupInput() {
  const v = $('view');
  v.addEventListener('pointerdown', (e) => {
    const [x, y] = pointerAt(e), c = camera();
    let near = null, best = 12;
    if (overlay) for (const [name, p] of Object.entries(pick.state.landmarks)) {
      const s = project(p, c), d = Math.hypot(s[0] - x, s[1] - y);
      if (d < best) { best = d; near = name; }
    }
    drag = near ? { name: near, point: null } : { orbit: [x, y] };
    v.setPointerCapture(e.pointerId);
    e.preventDefault();
  });
  v.addEventListener('pointermove', (e) => {
    if (!drag) return;
    const [x, y] = pointerAt(e);
    if (drag.orbit) {
      cam.yaw -= (x - drag.orbit[0]) * 0.01;
      cam.pitch = Math.max(-1.4, Math.min(1.4, cam.pitch + (y - drag.orbit[1]) * 0.01));
      drag.orbit = [x, y];
    } else {
      const hit = raycast(x, y);
      if (hit) drag.point = hit;
    }
    dirty = true;
  });
  const end = () => {
    const d = drag;
    drag = null;
    dirty = true;
    if (d && d.name && d.point) move(d.name, d.point);
  };
  v.addEventListener('pointerup', end);
  v.addEventListener('pointercancel', () => { drag = null; dirty = true; });
  v.addEventListener('wheel', (e) => {
    cam.dist = Math.max(0.1 * cam.size, Math.min(10 * cam.size, cam.dist * Math.exp(e.deltaY * 0.001)));
    dirty = true;
    e.preventDefault();
  }, { passive: false });
  $('save').onclick = () => save($('path').value.trim());
  $('front').onclick = () => setView('front');
  $('side').onclick = () => setView('side');
  $('back').onclick = () => setView('back');
}

async function main() {
  if (location.protocol === 'file:') {
    // Opened from disk: the mesh, rig and landmarks come from the pick server.
    throw new Error('This page needs the pick server: run `surfmotion rig embed MESH --pick` ' +
      '(or `surfmotion db init DIR … --pick`) and open the URL it prints.');
  }
  const [m, s] = await Promise.all([api('/api/mesh'), api('/api/state')]);
  if (m.status !== 200) throw new Error(m.body.error);
  if (s.status !== 200) throw new Error(s.body.error);
  pick.mesh = m.body;
  pick.state = s.body;
  setupGL();
  initCamera();
  setupInput();
  showState();
  requestAnimationFrame(draw);
  const mv = q.get('move');
  if (mv) {
    const [name, xyz] = mv.split(':');
    const p = (xyz || '').split(',').map(Number);
    if (p.length !== 3 || p.some((x) => !Number.isFinite(x))) throw new Error(`?move=${mv}: expected NAME:x,y,z`);
    pick.moved = await move(name, p);
  }
  pick.ready = true;
}

Object.assign(pick, {
  move, save, setView,
  project: (p) => project(p),
  setOverlay: (on) => { overlay = !!on; dirty = true; },
  // Resolves once the latest change has been drawn.
  frame: () => new Promise((res) => { dirty = true; const n = pick.drawn; const f = () => (pick.drawn > n ? res(pick.drawn) : requestAnimationFrame(f)); f(); }),
});
main().catch((e) => { pick.error = String(e && e.message || e); status(pick.error, true); console.error(e); });
})();
