// surfmotion live: the character and the incoming skeleton, side by side,
// as frames arrive over the WebSocket at /live (see src/live/page.rs for
// the messages). `window.live` exposes the counters the browser test reads.
"use strict";
(function () {
  const stats = document.getElementById("stats");
  const live = (window.live = {
    meta: null, frames: 0, drawn: 0, skipped: 0, index: -1,
    latencyMs: 0, deliveryMs: 0, outputFps: 0, error: null,
    arrivals: [], draws: [],
  });
  // Frames per second over the last two seconds of timestamps.
  const rate = (ts) => {
    const now = performance.now();
    while (ts.length && now - ts[0] > 2000) ts.shift();
    return ts.length < 2 ? 0 : (ts.length - 1) / ((ts[ts.length - 1] - ts[0]) / 1000);
  };
  live.receiveRate = () => rate(live.arrivals);
  live.drawRate = () => rate(live.draws);

  // ---- the character: WebGL, each triangle lit by its own facet ----
  // Positions arrive quantised (u16, origin + step · q) and are uploaded as
  // they are; the vertex shader dequantises, the fragment shader takes the
  // facet's normal from the derivatives of the position: no per-vertex
  // work in JavaScript, no normals sent.
  const cv = document.getElementById("character");
  const gl = cv.getContext("webgl", { antialias: true, preserveDrawingBuffer: true });
  const sk = document.getElementById("skeleton");
  const ctx = sk.getContext("2d");
  const derivatives = !!gl.getExtension("OES_standard_derivatives");
  const prog = (() => {
    const vs = `attribute vec3 q; uniform vec3 o; uniform float s; uniform mat4 m; varying vec3 wp;
      void main() { wp = o + q * s; gl_Position = m * vec4(wp, 1.0); }`;
    const fs = (derivatives ? "#extension GL_OES_standard_derivatives : enable\n" : "") +
      `precision mediump float; varying vec3 wp;
      void main() {
        ${derivatives ? "vec3 n = normalize(cross(dFdx(wp), dFdy(wp)));" : "vec3 n = vec3(0.0, 0.0, 1.0);"}
        float l = 0.25 + 0.6 * max(dot(n, normalize(vec3(0.4, 0.7, 0.6))), 0.0)
                + 0.25 * max(dot(n, normalize(vec3(-0.6, 0.2, -0.5))), 0.0);
        gl_FragColor = vec4(vec3(0.80, 0.74, 0.68) * l, 1.0); }`;
    const sh = (t, src) => {
      const x = gl.createShader(t); gl.shaderSource(x, src); gl.compileShader(x);
      if (!gl.getShaderParameter(x, gl.COMPILE_STATUS)) live.error = "shader: " + gl.getShaderInfoLog(x);
      return x;
    };
    const p = gl.createProgram();
    gl.attachShader(p, sh(gl.VERTEX_SHADER, vs));
    gl.attachShader(p, sh(gl.FRAGMENT_SHADER, fs));
    gl.linkProgram(p);
    return p;
  })();
  const loc = {
    q: gl.getAttribLocation(prog, "q"), o: gl.getUniformLocation(prog, "o"),
    s: gl.getUniformLocation(prog, "s"), m: gl.getUniformLocation(prog, "m"),
  };
  const pbuf = gl.createBuffer(), ibuf = gl.createBuffer();
  let joints = null, pending = null, triCount = 0, useUint32 = false;

  function setMeta(m) {
    live.meta = { vertices: m.vertices, triangles: m.triangles.length / 3, fps: m.fps, lag: m.lag };
    live.parents = m.parents;
    useUint32 = m.vertices > 65535 && !!gl.getExtension("OES_element_index_uint");
    const tris = useUint32 ? new Uint32Array(m.triangles) : new Uint16Array(m.triangles);
    triCount = m.triangles.length;
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, ibuf);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, tris, gl.STATIC_DRAW);
    gl.bindBuffer(gl.ARRAY_BUFFER, pbuf);
    gl.bufferData(gl.ARRAY_BUFFER, 6 * m.vertices, gl.DYNAMIC_DRAW);
  }

  // A camera in front of the body (+Z), following it over the floor.
  function camera(cx, cz, aspect) {
    const f = 1 / Math.tan((30 * Math.PI) / 180 / 2), near = 0.1, far = 20;
    const ex = cx + 0.9, ey = 1.1, ez = cz + 3.6, tx = cx, ty = 0.9, tz = cz;
    let zx = ex - tx, zy = ey - ty, zz = ez - tz;
    const zl = Math.hypot(zx, zy, zz); zx /= zl; zy /= zl; zz /= zl;
    let xx = zz, xy = 0, xz = -zx; const xl = Math.hypot(xx, xz); xx /= xl; xz /= xl;
    const yx = zy * xz - zz * xy, yy = zz * xx - zx * xz, yz = zx * xy - zy * xx;
    const v = [xx, yx, zx, 0, xy, yy, zy, 0, xz, yz, zz, 0,
      -(xx * ex + xy * ey + xz * ez), -(yx * ex + yy * ey + yz * ez), -(zx * ex + zy * ey + zz * ez), 1];
    const p = [f / aspect, 0, 0, 0, 0, f, 0, 0, 0, 0, (far + near) / (near - far), -1, 0, 0, (2 * far * near) / (near - far), 0];
    const m = new Array(16).fill(0);
    for (let c = 0; c < 4; c++) for (let r = 0; r < 4; r++) for (let k = 0; k < 4; k++) m[c * 4 + r] += p[k * 4 + r] * v[c * 4 + k];
    return new Float32Array(m);
  }

  function fit(c) {
    const w = c.clientWidth * devicePixelRatio, h = c.clientHeight * devicePixelRatio;
    if (c.width !== w || c.height !== h) { c.width = w; c.height = h; }
  }

  function drawCharacter(f) {
    fit(cv);
    gl.viewport(0, 0, cv.width, cv.height);
    gl.clearColor(0.16, 0.17, 0.19, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    gl.useProgram(prog);
    gl.uniformMatrix4fv(loc.m, false, camera(f.centre[0], f.centre[2], cv.width / cv.height));
    gl.uniform3f(loc.o, f.origin[0], f.origin[1], f.origin[2]);
    gl.uniform1f(loc.s, f.step * 65535);
    gl.bindBuffer(gl.ARRAY_BUFFER, pbuf);
    gl.bufferSubData(gl.ARRAY_BUFFER, 0, f.q);
    gl.enableVertexAttribArray(loc.q);
    gl.vertexAttribPointer(loc.q, 3, gl.UNSIGNED_SHORT, true, 0, 0);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, ibuf);
    gl.drawElements(gl.TRIANGLES, triCount, useUint32 ? gl.UNSIGNED_INT : gl.UNSIGNED_SHORT, 0);
  }

  // The incoming skeleton from the same side, 2D, centred on its pelvis.
  function drawSkeleton() {
    fit(sk);
    const w = sk.width, h = sk.height, s = h / 2.3;
    ctx.fillStyle = "#202328"; ctx.fillRect(0, 0, w, h);
    ctx.strokeStyle = "#3a3f46"; ctx.beginPath(); ctx.moveTo(0, h * 0.92); ctx.lineTo(w, h * 0.92); ctx.stroke();
    const px = joints[0], pz = joints[2];
    // The same oblique view as the character's camera.
    const proj = (i) => {
      const x = joints[3 * i] - px, y = joints[3 * i + 1], z = joints[3 * i + 2] - pz;
      return [w / 2 + s * (0.97 * x - 0.24 * z), h * 0.92 - s * y];
    };
    ctx.lineWidth = 3 * devicePixelRatio; ctx.lineCap = "round";
    live.parents.forEach((p, i) => {
      if (p < 0) return;
      const [ax, ay] = proj(p), [bx, by] = proj(i);
      const left = [5, 6, 7, 11, 12, 13, 14].includes(i), right = [8, 9, 10, 15, 16, 17, 18].includes(i);
      ctx.strokeStyle = left ? "#e0a050" : right ? "#50a0e0" : "#d8d8d8";
      ctx.beginPath(); ctx.moveTo(ax, ay); ctx.lineTo(bx, by); ctx.stroke();
    });
    ctx.fillStyle = "#fff";
    for (let i = 0; i < 19; i++) { const [x, y] = proj(i); ctx.beginPath(); ctx.arc(x, y, 2.5 * devicePixelRatio, 0, 7); ctx.fill(); }
  }

  // The frame message (src/live/page.rs): 52 header bytes, the skeleton
  // (19 × 3 f32), the vertices (n × 3 u16). Newest wins: a frame that
  // arrives before the previous one was drawn replaces it (counted).
  const HEADER = 52 + 12 * 19;
  function onFrame(buf) {
    const dv = new DataView(buf);
    if (dv.getUint32(0, true) !== 2 || !live.meta) return;
    const n = live.meta.vertices;
    if (buf.byteLength !== HEADER + 6 * n) { live.error = "frame of " + buf.byteLength + " bytes"; return; }
    if (pending) live.skipped++;
    const f32 = (at) => dv.getFloat32(at, true);
    pending = {
      index: dv.getUint32(4, true), latency: f32(8), fps: f32(12),
      delivery: Date.now() - dv.getFloat64(16, true),
      origin: [f32(24), f32(28), f32(32)], step: f32(36), centre: [f32(40), f32(44), f32(48)],
      joints: new Float32Array(buf, 52, 57), q: new Uint16Array(buf, HEADER, 3 * n),
    };
    live.frames++;
    live.bytes = buf.byteLength;
    const now = performance.now();
    live.arrivals.push(now);
    if (live.firstFrameAt === undefined) live.firstFrameAt = now;
    live.lastFrameAt = now;
    pending.received = now;
  }

  function draw() {
    requestAnimationFrame(draw);
    if (!pending) return;
    const f = pending; pending = null;
    joints = f.joints;
    live.index = f.index; live.latencyMs = f.latency; live.deliveryMs = f.delivery; live.outputFps = f.fps;
    const t0 = performance.now();
    drawCharacter(f);
    drawSkeleton();
    live.drawn++;
    const now = performance.now();
    live.drawMs = now - t0;
    live.draws.push(now);
    if (live.firstDrawAt === undefined) live.firstDrawAt = now;
    live.lastDrawAt = now;
    // Arrival at the server → drawn here: the session's latency plus the
    // delivery and the wait for this draw.
    live.shownMs = f.latency + f.delivery + (now - f.received);
    stats.innerHTML = `frame <b>${f.index}</b> · ${live.meta.vertices} vertices · lag ${live.meta.lag}` +
      ` · in <b>${live.receiveRate().toFixed(1)}</b> frames/s · drawn <b>${live.drawRate().toFixed(1)}</b> frames/s` +
      ` · skipped <b>${live.skipped}</b> of ${live.frames}` +
      ` · arrival→mesh <b>${f.latency.toFixed(1)}</b> ms · delivery <b>${f.delivery.toFixed(1)}</b> ms` +
      ` · shown <b>${live.shownMs.toFixed(1)}</b> ms`;
  }

  if (location.protocol === "file:") {
    // Opened from disk: the frames come from the live session's server.
    stats.innerHTML = "<b>This page needs the live server.</b> Run <code>surfmotion live --db DIR " +
      "--replay CLIP --serve</code> (or --vmc/--rokoko/--bvh-tcp) and open the URL it prints.";
    live.error = "opened from disk: no live server";
    return;
  }
  const ws = new WebSocket(`ws://${location.host}/live`);
  ws.binaryType = "arraybuffer";
  ws.onmessage = (e) => {
    if (typeof e.data === "string") { setMeta(JSON.parse(e.data)); stats.textContent = "waiting for frames…"; }
    else onFrame(e.data);
  };
  ws.onclose = () => { live.closed = true; stats.innerHTML += " · stream ended"; };
  ws.onerror = () => { live.error = "websocket error"; };
  requestAnimationFrame(draw);
})();
