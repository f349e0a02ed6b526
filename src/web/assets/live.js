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

  // ---- the character: WebGL, flat-lit from two lights ----
  const cv = document.getElementById("character");
  const gl = cv.getContext("webgl", { antialias: true, preserveDrawingBuffer: true });
  const sk = document.getElementById("skeleton");
  const ctx = sk.getContext("2d");
  const prog = (() => {
    const vs = `attribute vec3 p; attribute vec3 n; uniform mat4 m; varying vec3 vn;
      void main() { vn = n; gl_Position = m * vec4(p, 1.0); }`;
    const fs = `precision mediump float; varying vec3 vn;
      void main() { vec3 n = normalize(vn);
        float l = 0.25 + 0.6 * max(dot(n, normalize(vec3(0.4, 0.7, 0.6))), 0.0)
                + 0.25 * max(dot(n, normalize(vec3(-0.6, 0.2, -0.5))), 0.0);
        gl_FragColor = vec4(vec3(0.80, 0.74, 0.68) * l, 1.0); }`;
    const sh = (t, s) => { const x = gl.createShader(t); gl.shaderSource(x, s); gl.compileShader(x); return x; };
    const p = gl.createProgram();
    gl.attachShader(p, sh(gl.VERTEX_SHADER, vs));
    gl.attachShader(p, sh(gl.FRAGMENT_SHADER, fs));
    gl.linkProgram(p);
    return p;
  })();
  const pbuf = gl.createBuffer(), nbuf = gl.createBuffer(), ibuf = gl.createBuffer();
  let tris = null, normals = null, pos = null, joints = null, pending = null, triCount = 0;
  let useUint32 = false;

  function setMeta(m) {
    live.meta = { vertices: m.vertices, triangles: m.triangles.length / 3, fps: m.fps, lag: m.lag };
    live.parents = m.parents;
    useUint32 = m.vertices > 65535 && !!gl.getExtension("OES_element_index_uint");
    tris = useUint32 ? new Uint32Array(m.triangles) : new Uint16Array(m.triangles);
    triCount = m.triangles.length;
    normals = new Float32Array(3 * m.vertices);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, ibuf);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, tris, gl.STATIC_DRAW);
  }

  function computeNormals(p) {
    normals.fill(0);
    for (let t = 0; t < triCount; t += 3) {
      const a = 3 * tris[t], b = 3 * tris[t + 1], c = 3 * tris[t + 2];
      const ux = p[b] - p[a], uy = p[b + 1] - p[a + 1], uz = p[b + 2] - p[a + 2];
      const vx = p[c] - p[a], vy = p[c + 1] - p[a + 1], vz = p[c + 2] - p[a + 2];
      const nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
      for (const i of [a, b, c]) { normals[i] += nx; normals[i + 1] += ny; normals[i + 2] += nz; }
    }
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

  function drawCharacter() {
    fit(cv);
    gl.viewport(0, 0, cv.width, cv.height);
    gl.clearColor(0.16, 0.17, 0.19, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    computeNormals(pos);
    let cx = 0, cz = 0; const n = pos.length / 3;
    for (let i = 0; i < pos.length; i += 3) { cx += pos[i]; cz += pos[i + 2]; }
    gl.useProgram(prog);
    gl.uniformMatrix4fv(gl.getUniformLocation(prog, "m"), false, camera(cx / n, cz / n, cv.width / cv.height));
    for (const [buf, data, name] of [[pbuf, pos, "p"], [nbuf, normals, "n"]]) {
      const loc = gl.getAttribLocation(prog, name);
      gl.bindBuffer(gl.ARRAY_BUFFER, buf);
      gl.bufferData(gl.ARRAY_BUFFER, data, gl.DYNAMIC_DRAW);
      gl.enableVertexAttribArray(loc);
      gl.vertexAttribPointer(loc, 3, gl.FLOAT, false, 0, 0);
    }
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

  function onFrame(buf) {
    const dv = new DataView(buf);
    if (dv.getUint32(0, true) !== 1 || !live.meta) return;
    const n = live.meta.vertices;
    if (buf.byteLength !== 24 + 12 * (n + 19)) { live.error = "frame of " + buf.byteLength + " bytes"; return; }
    if (pending) live.skipped++;
    pending = {
      index: dv.getUint32(4, true), latency: dv.getFloat32(8, true), fps: dv.getFloat32(12, true),
      delivery: Date.now() - dv.getFloat64(16, true),
      pos: new Float32Array(buf, 24, 3 * n), joints: new Float32Array(buf, 24 + 12 * n, 57),
    };
    live.frames++;
    const now = performance.now();
    live.arrivals.push(now);
    if (live.firstFrameAt === undefined) live.firstFrameAt = now;
    live.lastFrameAt = now;
  }

  function draw() {
    requestAnimationFrame(draw);
    if (!pending) return;
    const f = pending; pending = null;
    pos = f.pos; joints = f.joints;
    live.index = f.index; live.latencyMs = f.latency; live.deliveryMs = f.delivery; live.outputFps = f.fps;
    drawCharacter();
    drawSkeleton();
    live.drawn++;
    const now = performance.now();
    live.draws.push(now);
    if (live.firstDrawAt === undefined) live.firstDrawAt = now;
    live.lastDrawAt = now;
    stats.innerHTML = `frame <b>${f.index}</b> · ${live.meta.vertices} vertices · lag ${live.meta.lag}` +
      ` · in <b>${live.receiveRate().toFixed(1)}</b> frames/s · drawn <b>${live.drawRate().toFixed(1)}</b> frames/s` +
      ` · arrival→mesh <b>${f.latency.toFixed(1)}</b> ms · delivery <b>${f.delivery.toFixed(1)}</b> ms`;
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
