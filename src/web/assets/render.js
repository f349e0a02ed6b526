// A classic script (pages opened from disk refuse modules): its names
// are in `self.SurfRender`.
self.SurfRender = (() => {
'use strict';
// WebGL2 renderer: the character (quantised positions dequantised and up
// to four placed frames blended in the vertex shader: two across a linear
// transition, four for a parametric space's bilinear blend; faceted normals
// from screen-space derivatives; hemisphere light with a height-based
// occlusion term), a ground plane with a grid, and a planar shadow drawn
// once per pixel through the stencil buffer.

const MESH_VS = `#version 300 es
in vec3 aQ0; in vec3 aQ1; in vec3 aQ2; in vec3 aQ3;
uniform vec3 uOrigin; uniform float uStep; uniform vec4 uW;
uniform mat4 uM[4]; uniform mat4 uVP;
uniform int uShadow; uniform float uGround; uniform vec3 uLight;
out vec3 vPos; out float vH;
vec3 placed(int i, vec3 q) { return (uM[i] * vec4(uOrigin + uStep * q, 1.0)).xyz; }
void main() {
  vec3 p = uW.x * placed(0, aQ0) + uW.y * placed(1, aQ1) + uW.z * placed(2, aQ2) + uW.w * placed(3, aQ3);
  vH = p.y - uGround;
  if (uShadow == 1) {
    p -= uLight * ((p.y - uGround) / uLight.y);
    p.y = uGround + 0.002;
  }
  vPos = p;
  gl_Position = uVP * vec4(p, 1.0);
}`;

const MESH_FS = `#version 300 es
precision highp float; precision highp int;
in vec3 vPos; in float vH;
uniform int uShadow; uniform vec3 uLight; uniform vec3 uEye;
out vec4 outColor;
void main() {
  if (uShadow == 1) { outColor = vec4(0.0, 0.0, 0.0, 0.38); return; }
  vec3 n = normalize(cross(dFdx(vPos), dFdy(vPos)));
  if (dot(n, uEye - vPos) < 0.0) n = -n;
  vec3 base = vec3(0.86, 0.55, 0.36);
  float diff = max(dot(n, normalize(uLight)), 0.0);
  float hemi = 0.5 + 0.5 * n.y;
  float ao = mix(0.55, 1.0, smoothstep(0.0, 0.35, vH));
  vec3 c = base * (0.30 * hemi * ao + 0.75 * diff * mix(0.8, 1.0, ao));
  outColor = vec4(pow(c, vec3(1.0 / 2.2)), 1.0);
}`;

const GROUND_VS = `#version 300 es
in vec2 aP;
uniform mat4 uVP; uniform float uGround; uniform vec2 uCentre;
out vec2 vW;
void main() {
  vW = uCentre + aP * 200.0;
  gl_Position = uVP * vec4(vW.x, uGround, vW.y, 1.0);
}`;

const GROUND_FS = `#version 300 es
precision highp float; precision highp int;
in vec2 vW; uniform vec2 uCentre;
out vec4 outColor;
void main() {
  vec2 g = abs(fract(vW) - 0.5);
  float line = smoothstep(0.48, 0.5, max(g.x, g.y));
  float fade = exp(-length(vW - uCentre) * 0.12);
  vec3 c = mix(vec3(0.30, 0.33, 0.37), vec3(0.62, 0.66, 0.72), fade) - 0.08 * line * fade;
  // Far ground melts into the page's background (#c7d1dd, linear): no
  // hard horizon edge or quad corner.
  c = mix(vec3(0.579, 0.646, 0.730), c, exp(-length(vW - uCentre) * 0.035));
  outColor = vec4(pow(c, vec3(1.0 / 2.2)), 1.0);
}`;

function compile(gl, vs, fs) {
  const p = gl.createProgram();
  for (const [type, src] of [[gl.VERTEX_SHADER, vs], [gl.FRAGMENT_SHADER, fs]]) {
    const s = gl.createShader(type);
    gl.shaderSource(s, src); gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error('shader: ' + gl.getShaderInfoLog(s));
    gl.attachShader(p, s);
  }
  if (vs.includes('in vec2 aP')) gl.bindAttribLocation(p, 0, 'aP');
  else for (let i = 0; i < 4; i++) gl.bindAttribLocation(p, i, 'aQ' + i);
  gl.linkProgram(p);
  if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error('program: ' + gl.getProgramInfoLog(p));
  const u = {};
  const nu = gl.getProgramParameter(p, gl.ACTIVE_UNIFORMS);
  for (let i = 0; i < nu; i++) { const name = gl.getActiveUniform(p, i).name; u[name] = gl.getUniformLocation(p, name); }
  return { p, u };
}

// Column-major 4x4 helpers.
function perspective(fovy, aspect, near, far) {
  const f = 1 / Math.tan(fovy / 2), nf = 1 / (near - far);
  return new Float32Array([f / aspect, 0, 0, 0, 0, f, 0, 0, 0, 0, (far + near) * nf, -1, 0, 0, 2 * far * near * nf, 0]);
}
function lookAt(eye, at, up) {
  const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
  const norm = (a) => { const l = Math.hypot(...a) || 1; return a.map((x) => x / l); };
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const z = norm(sub(eye, at)), x = norm(cross(up, z)), y = cross(z, x);
  return new Float32Array([x[0], y[0], z[0], 0, x[1], y[1], z[1], 0, x[2], y[2], z[2], 0, -dot(x, eye), -dot(y, eye), -dot(z, eye), 1]);
}
function mul(a, b) {
  const o = new Float32Array(16);
  for (let c = 0; c < 4; c++) for (let r = 0; r < 4; r++) {
    let s = 0; for (let k = 0; k < 4; k++) s += a[k * 4 + r] * b[c * 4 + k]; o[c * 4 + r] = s;
  }
  return o;
}

class Renderer {
  constructor(canvas) {
    const gl = canvas.getContext('webgl2', { antialias: true, stencil: true, preserveDrawingBuffer: false });
    if (!gl) throw new Error('this browser has no WebGL2 context');
    this.gl = gl; this.canvas = canvas;
    this.mesh = compile(gl, MESH_VS, MESH_FS);
    this.ground = compile(gl, GROUND_VS, GROUND_FS);
    this.quad = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, this.quad);
    gl.bufferData(gl.ARRAY_BUFFER, new Float32Array([-1, -1, 1, -1, -1, 1, 1, 1]), gl.STATIC_DRAW);
    this.light = [0.45, 1.0, 0.3];
  }

  // Uploads the whole geometry once: one buffer per sequence (u16 x,y,z per
  // vertex, frame-major); a frame is chosen by the attribute offset.
  load(g) {
    const gl = this.gl;
    this.g = g;
    this.n = g.vertices;
    this.count = g.triangles.length;
    this.ibo = gl.createBuffer();
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.ibo);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, g.triangles, gl.STATIC_DRAW);
    this.vbos = g.sequences.map((s) => {
      const b = gl.createBuffer();
      gl.bindBuffer(gl.ARRAY_BUFFER, b);
      gl.bufferData(gl.ARRAY_BUFFER, s.q, gl.STATIC_DRAW);
      return b;
    });
    this.vao = gl.createVertexArray();
    this.ground_y = g.origin[1];
  }

  resize() {
    const c = this.canvas, dpr = Math.min(window.devicePixelRatio || 1, 2);
    const w = Math.floor(c.clientWidth * dpr), h = Math.floor(c.clientHeight * dpr);
    if (c.width !== w || c.height !== h) { c.width = w; c.height = h; }
  }

  // view: {parts: [{s, f, w}, ...]} (at most four); cam: {eye, at};
  // mats: each part's placement as a mat4.
  draw(view, cam, mats) {
    const gl = this.gl, m = this.mesh, n = this.n;
    this.resize();
    gl.viewport(0, 0, this.canvas.width, this.canvas.height);
    gl.clearColor(0.78, 0.82, 0.87, 1); gl.clearStencil(0);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT | gl.STENCIL_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    const vp = mul(perspective(0.8, this.canvas.width / Math.max(1, this.canvas.height), 0.05, 200), lookAt(cam.eye, cam.at, [0, 1, 0]));
    // ground
    gl.useProgram(this.ground.p);
    gl.bindVertexArray(null);
    gl.bindBuffer(gl.ARRAY_BUFFER, this.quad);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 2, gl.FLOAT, false, 0, 0);
    gl.disableVertexAttribArray(1);
    gl.uniformMatrix4fv(this.ground.u.uVP, false, vp);
    gl.uniform1f(this.ground.u.uGround, this.ground_y);
    gl.uniform2f(this.ground.u.uCentre, cam.at[0], cam.at[2]);
    gl.drawArrays(gl.TRIANGLE_STRIP, 0, 4);
    // character
    gl.useProgram(m.p);
    gl.bindVertexArray(this.vao);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.ibo);
    const attrib = (loc, v) => {
      gl.bindBuffer(gl.ARRAY_BUFFER, this.vbos[v.s]);
      gl.enableVertexAttribArray(loc);
      gl.vertexAttribPointer(loc, 3, gl.UNSIGNED_SHORT, false, 6, v.f * n * 6);
    };
    const parts = view.parts, w = [0, 0, 0, 0], M = new Float32Array(64);
    for (let i = 0; i < 4; i++) {
      const k = i < parts.length ? i : 0;
      attrib(i, parts[k]);
      w[i] = i < parts.length ? parts[i].w : 0;
      M.set(mats[k], 16 * i);
    }
    gl.uniform3fv(m.u.uOrigin, this.g.origin);
    gl.uniform1f(m.u.uStep, this.g.step);
    gl.uniform4fv(m.u.uW, w);
    gl.uniformMatrix4fv(m.u['uM[0]'], false, M);
    gl.uniformMatrix4fv(m.u.uVP, false, vp);
    gl.uniform1f(m.u.uGround, this.ground_y);
    gl.uniform3fv(m.u.uLight, this.light);
    gl.uniform3fv(m.u.uEye, cam.eye);
    // shadow first: flattened onto the ground, each pixel darkened once
    gl.uniform1i(m.u.uShadow, 1);
    gl.enable(gl.BLEND); gl.blendFunc(gl.SRC_ALPHA, gl.ONE_MINUS_SRC_ALPHA);
    gl.enable(gl.STENCIL_TEST); gl.stencilFunc(gl.EQUAL, 0, 0xff); gl.stencilOp(gl.KEEP, gl.KEEP, gl.INCR);
    gl.depthMask(false);
    gl.drawElements(gl.TRIANGLES, this.count, gl.UNSIGNED_INT, 0);
    gl.depthMask(true); gl.disable(gl.STENCIL_TEST); gl.disable(gl.BLEND);
    gl.uniform1i(m.u.uShadow, 0);
    gl.drawElements(gl.TRIANGLES, this.count, gl.UNSIGNED_INT, 0);
    gl.bindVertexArray(null);
  }
}
return { perspective, lookAt, mul, Renderer };
})();
