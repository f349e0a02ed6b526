// Decodes the vertex positions of every frame of a surfmotion GLB (a morph-target
// sequence with a weights animation) with glTF Transform, a reader independent
// of the project's: world position = node matrix · (base + Σ w_t · target_t) at
// each animation key. Prints one JSON object per file:
// {"file", "frames", "vertices", "scale", "extensions", "positions": [[x,y,z,...] per frame]}.
import { NodeIO } from '@gltf-transform/core';
import { ALL_EXTENSIONS } from '@gltf-transform/extensions';

const io = new NodeIO().registerExtensions(ALL_EXTENSIONS);
for (const file of process.argv.slice(2)) {
  const doc = await io.read(file);
  const root = doc.getRoot();
  const node = root.listNodes().find((n) => n.getMesh());
  const prim = node.getMesh().listPrimitives()[0];
  const m = node.getWorldMatrix();
  const base = prim.getAttribute('POSITION');
  const nv = base.getCount();
  const targets = prim.listTargets().map((t) => t.getAttribute('POSITION'));
  const el = (acc, i) => acc.getElement(i, [0, 0, 0]);
  const world = (p) => [0, 1, 2].map((r) => m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r]);
  // Weights per key: the animation's output, T values per key.
  let keys = [new Array(targets.length).fill(0)];
  const anim = root.listAnimations()[0];
  if (anim) {
    const s = anim.listChannels().find((c) => c.getTargetPath() === 'weights').getSampler();
    const out = s.getOutput();
    const k = s.getInput().getCount();
    const t = targets.length;
    keys = [];
    for (let f = 0; f < k; f++) {
      keys.push(Array.from({ length: t }, (_, j) => out.getScalar(f * t + j)));
    }
  }
  const positions = keys.map((w) => {
    const frame = [];
    for (let i = 0; i < nv; i++) {
      const p = el(base, i).slice();
      w.forEach((wt, j) => {
        if (wt !== 0) {
          const d = el(targets[j], i);
          for (let c = 0; c < 3; c++) p[c] += wt * d[c];
        }
      });
      frame.push(...world(p));
    }
    return frame;
  });
  console.log(JSON.stringify({
    file,
    frames: positions.length,
    vertices: nv,
    scale: Math.cbrt(Math.abs(m[0] * (m[5] * m[10] - m[9] * m[6]) - m[4] * (m[1] * m[10] - m[9] * m[2]) + m[8] * (m[1] * m[6] - m[5] * m[2]))),
    extensions: root.listExtensionsUsed().map((e) => e.extensionName),
    positions,
  }));
}
