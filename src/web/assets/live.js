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
  // Multisampling is what a software rasteriser (headless Chromium's
  // SwiftShader, Mesa's llvmpipe) spends most of a draw on: measured in
  // headless Chromium on 2 cores, a 10K-vertex frame drew at 11-14
  // frames/s with it and 21-29 without. So it is on only where the GPU is
  // a real one; `?antialias=1` or `=0` in the page's address decides.
  const software = /swiftshader|llvmpipe|softpipe|software|basic render/i;
  const renderer = (() => {
    const probe = document.createElement("canvas").getContext("webgl");
    const info = probe && probe.getExtension("WEBGL_debug_renderer_info");
    const name = info ? String(probe.getParameter(info.UNMASKED_RENDERER_WEBGL)) : "";
    const lose = probe && probe.getExtension("WEBGL_lose_context");
    if (lose) lose.loseContext();
    return name;
  })();
  const params = new URLSearchParams(location.search), asked = params.get("antialias");
  live.renderer = renderer;
  live.antialias = asked === null ? !software.test(renderer) : asked === "1";
  // One canvas under both views: the character in its left half, the
  // skeleton in its right. A second canvas (a 2D one for the skeleton) cost
  // the page 6-8 of its ~25 draws a second in headless Chromium's software
  // compositing (measured in \`live::page\`).
  const cv = document.getElementById("screen");
  const gl = cv.getContext("webgl", { antialias: live.antialias, preserveDrawingBuffer: false });
  const derivatives = !!gl.getExtension("OES_standard_derivatives");
  // A program of two shaders; a shader that does not compile or a program
  // that does not link is the page's error, named.
  function program(vs, fs, what) {
    const sh = (t, src) => {
      const x = gl.createShader(t); gl.shaderSource(x, src); gl.compileShader(x);
      if (!gl.getShaderParameter(x, gl.COMPILE_STATUS)) live.error = what + " shader: " + gl.getShaderInfoLog(x);
      return x;
    };
    const p = gl.createProgram();
    gl.attachShader(p, sh(gl.VERTEX_SHADER, vs));
    gl.attachShader(p, sh(gl.FRAGMENT_SHADER, fs));
    gl.linkProgram(p);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS)) live.error = what + " program: " + gl.getProgramInfoLog(p);
    return p;
  }
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
    return program(vs, fs, "character");
  })();
  const loc = {
    q: gl.getAttribLocation(prog, "q"), o: gl.getUniformLocation(prog, "o"),
    s: gl.getUniformLocation(prog, "s"), m: gl.getUniformLocation(prog, "m"),
  };
  // The skeleton: flat-coloured triangles given in the half's pixels.
  const flat = (() => {
    const p = program(`attribute vec2 a; attribute vec3 c; uniform vec2 size; varying vec3 v;
      void main() { v = c; gl_Position = vec4(2.0 * a.x / size.x - 1.0, 1.0 - 2.0 * a.y / size.y, 0.0, 1.0); }`,
      "precision mediump float; varying vec3 v; void main() { gl_FragColor = vec4(v, 1.0); }", "skeleton");
    return { p, a: gl.getAttribLocation(p, "a"), c: gl.getAttribLocation(p, "c"), size: gl.getUniformLocation(p, "size") };
  })();
  // 5 floats a vertex (x, y, r, g, b): the floor, 18 bones of 6 vertices,
  // 19 joints of 8 triangles.
  const skv = new Float32Array(5 * (6 + 18 * 6 + 19 * 24)), skbuf = gl.createBuffer();
  gl.bindBuffer(gl.ARRAY_BUFFER, skbuf);
  gl.bufferData(gl.ARRAY_BUFFER, skv.byteLength, gl.DYNAMIC_DRAW);
  const pbuf = gl.createBuffer(), ibuf = gl.createBuffer();
  let joints = null, triCount = 0, useUint32 = false;

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
    const w = Math.round(c.clientWidth * devicePixelRatio), h = Math.round(c.clientHeight * devicePixelRatio);
    if (c.width !== w || c.height !== h) { c.width = w; c.height = h; }
  }

  // One half of the canvas: viewport and scissor on it, cleared.
  function half(x, w, h, r, g, b) {
    gl.viewport(x, 0, w, h);
    gl.scissor(x, 0, w, h);
    gl.clearColor(r, g, b, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
  }

  function drawCharacter(f, w, h) {
    half(0, w, h, 0.16, 0.17, 0.19);
    gl.enable(gl.DEPTH_TEST);
    gl.useProgram(prog);
    gl.uniformMatrix4fv(loc.m, false, camera(f.centre[0], f.centre[2], w / h));
    gl.uniform3f(loc.o, f.origin[0], f.origin[1], f.origin[2]);
    gl.uniform1f(loc.s, f.step * 65535);
    gl.bindBuffer(gl.ARRAY_BUFFER, pbuf);
    gl.bufferSubData(gl.ARRAY_BUFFER, 0, f.q);
    gl.enableVertexAttribArray(loc.q);
    gl.vertexAttribPointer(loc.q, 3, gl.UNSIGNED_SHORT, true, 0, 0);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, ibuf);
    gl.drawElements(gl.TRIANGLES, triCount, useUint32 ? gl.UNSIGNED_INT : gl.UNSIGNED_SHORT, 0);
    gl.disableVertexAttribArray(loc.q);
  }

  const rgb = (hex) => [1, 3, 5].map((k) => parseInt(hex.slice(k, k + 2), 16) / 255);
  const LEFT = [5, 6, 7, 11, 12, 13, 14], RIGHT = [8, 9, 10, 15, 16, 17, 18];
  const COLOUR = { left: rgb("#e0a050"), right: rgb("#50a0e0"), middle: rgb("#d8d8d8"), joint: [1, 1, 1], floor: rgb("#3a3f46") };

  // The incoming skeleton from the same side, centred on its pelvis: bones
  // as bands 3 px wide, joints as discs, on the floor's line.
  function drawSkeleton(x0, w, h) {
    half(x0, w, h, 0x20 / 255, 0x23 / 255, 0x28 / 255);
    gl.disable(gl.DEPTH_TEST);
    const s = h / 2.3, dpr = devicePixelRatio, px = joints[0], pz = joints[2];
    let n = 0;
    const put = (x, y, c) => { skv.set([x, y, c[0], c[1], c[2]], 5 * n); n++; };
    // A band from a to b, `width` across, its ends pushed out by half that.
    const band = (ax, ay, bx, by, width, c) => {
      const len = Math.hypot(bx - ax, by - ay) || 1, dx = (bx - ax) / len * width / 2, dy = (by - ay) / len * width / 2;
      const p = [[ax - dx - dy, ay - dy + dx], [ax - dx + dy, ay - dy - dx], [bx + dx + dy, by + dy - dx], [bx + dx - dy, by + dy + dx]];
      for (const k of [0, 1, 2, 0, 2, 3]) put(p[k][0], p[k][1], c);
    };
    // The same oblique view as the character's camera.
    const proj = (i) => {
      const x = joints[3 * i] - px, y = joints[3 * i + 1], z = joints[3 * i + 2] - pz;
      return [w / 2 + s * (0.97 * x - 0.24 * z), h * 0.92 - s * y];
    };
    band(0, h * 0.92, w, h * 0.92, dpr, COLOUR.floor);
    live.parents.forEach((p, i) => {
      if (p < 0 || n + 6 > skv.length / 5) return;
      const [ax, ay] = proj(p), [bx, by] = proj(i);
      band(ax, ay, bx, by, 3 * dpr, LEFT.includes(i) ? COLOUR.left : RIGHT.includes(i) ? COLOUR.right : COLOUR.middle);
    });
    for (let i = 0; i < 19 && n + 24 <= skv.length / 5; i++) {
      const [x, y] = proj(i), r = 2.5 * dpr;
      for (let k = 0; k < 8; k++) {
        const a = (k * Math.PI) / 4, b = ((k + 1) * Math.PI) / 4;
        put(x, y, COLOUR.joint);
        put(x + r * Math.cos(a), y + r * Math.sin(a), COLOUR.joint);
        put(x + r * Math.cos(b), y + r * Math.sin(b), COLOUR.joint);
      }
    }
    gl.useProgram(flat.p);
    gl.uniform2f(flat.size, w, h);
    gl.bindBuffer(gl.ARRAY_BUFFER, skbuf);
    gl.bufferSubData(gl.ARRAY_BUFFER, 0, skv.subarray(0, 5 * n));
    gl.enableVertexAttribArray(flat.a);
    gl.enableVertexAttribArray(flat.c);
    gl.vertexAttribPointer(flat.a, 2, gl.FLOAT, false, 20, 0);
    gl.vertexAttribPointer(flat.c, 3, gl.FLOAT, false, 20, 8);
    gl.drawArrays(gl.TRIANGLES, 0, n);
    gl.disableVertexAttribArray(flat.a);
    gl.disableVertexAttribArray(flat.c);
  }

  // The frame message (src/live/page.rs): 52 header bytes, the skeleton
  // (19 × 3 f32), the vertices (n × 3 u16). Frames wait in a short queue
  // and are drawn in order at the stream's pace: the session may send two
  // at once (its two-frame overlap deforms a pair together), and drawing
  // only the newest of each pair halves the rate. A frame is drawn once a
  // frame period (less a quarter) has passed since the last draw, or at
  // once when another waits behind it; when the page falls behind, the
  // oldest frames beyond QUEUE are skipped (counted), so the newest still
  // wins and the wait never grows past QUEUE frames.
  const HEADER = 52 + 12 * 19, QUEUE = 2;
  const queue = [];
  function onFrame(buf) {
    const dv = new DataView(buf);
    if (dv.getUint32(0, true) !== 2 || !live.meta) return;
    const n = live.meta.vertices;
    if (buf.byteLength !== HEADER + 6 * n) { live.error = "frame of " + buf.byteLength + " bytes"; return; }
    const f32 = (at) => dv.getFloat32(at, true);
    const f = {
      index: dv.getUint32(4, true), latency: f32(8), fps: f32(12),
      delivery: Date.now() - dv.getFloat64(16, true),
      origin: [f32(24), f32(28), f32(32)], step: f32(36), centre: [f32(40), f32(44), f32(48)],
      joints: new Float32Array(buf, 52, 57), q: new Uint16Array(buf, HEADER, 3 * n),
    };
    live.frames++;
    live.bytes = buf.byteLength;
    const now = performance.now();
    // Frames that came within 8 ms of the one before (sent together).
    if (live.lastFrameAt !== undefined && now - live.lastFrameAt < 8) live.together = (live.together || 0) + 1;
    live.arrivals.push(now);
    if (live.firstFrameAt === undefined) live.firstFrameAt = now;
    live.lastFrameAt = now;
    f.received = now;
    queue.push(f);
    while (queue.length > QUEUE) { queue.shift(); live.skipped++; }
  }

  function draw() {
    requestAnimationFrame(draw);
    if (!queue.length) return;
    const period = 1000 / (live.meta.fps || 30);
    if (queue.length < 2 && performance.now() - (live.lastDrawAt || 0) < 0.75 * period) return;
    const f = queue.shift();
    joints = f.joints;
    live.index = f.index; live.latencyMs = f.latency; live.deliveryMs = f.delivery; live.outputFps = f.fps;
    const t0 = performance.now();
    fit(cv);
    gl.enable(gl.SCISSOR_TEST);
    const w = Math.floor(cv.width / 2);
    drawCharacter(f, w, cv.height);
    drawSkeleton(w, cv.width - w, cv.height);
    live.drawn++;
    const now = performance.now();
    live.drawMs = now - t0;
    live.draws.push(now);
    if (live.firstDrawAt === undefined) live.firstDrawAt = now;
    live.lastDrawAt = now;
    // Arrival at the server → drawn here: the session's latency plus the
    // delivery and the wait for this draw.
    live.shownMs = f.latency + f.delivery + (now - f.received);
    live.last = f;
    // The counters' text is laid out and rasterised again each time it
    // changes: four times a second is enough to read it.
    if (now - (live.statsAt || 0) >= 250) showStats(f);
  }

  function showStats(f) {
    live.statsAt = performance.now();
    stats.innerHTML = `frame <b>${f.index}</b> · ${live.meta.vertices} vertices · lag ${live.meta.lag}` +
      ` · in <b>${live.receiveRate().toFixed(1)}</b> frames/s · drawn <b>${live.drawRate().toFixed(1)}</b> frames/s` +
      ` · skipped <b>${live.skipped}</b> of ${live.frames}` +
      ` · arrival→mesh <b>${f.latency.toFixed(1)}</b> ms · delivery <b>${f.delivery.toFixed(1)}</b> ms` +
      ` · shown <b>${live.shownMs.toFixed(1)}</b> ms`;
    live.shown = f;
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
  ws.onclose = () => {
    live.closed = true;
    if (live.last && live.shown !== live.last) showStats(live.last);
    stats.innerHTML += " · stream ended";
  };
  ws.onerror = () => { live.error = "websocket error"; };
  requestAnimationFrame(draw);
})();
