// Writes an OUTDIR as `chokeloops analyze` would (surface.ply + loops.json) for developing and testing the viewer.
//   node make-fixture.mjs torus OUTDIR [--binary]   one torus with a thin side: 4 loops (one of each colour)
//   node make-fixture.mjs large OUTDIR              three tori, 720K faces (binary PLY), 12 loops: decimation
import fs from 'node:fs';
import path from 'node:path';

const [kind, outdir, ...flags] = process.argv.slice(2);
if (!['torus', 'large'].includes(kind) || !outdir) {
  console.error('usage: node make-fixture.mjs torus|large OUTDIR [--binary]');
  process.exit(2);
}
const binary = kind === 'large' || flags.includes('--binary');
const round = (x) => Math.round(x * 1e6) / 1e6;

// Torus around the z axis with tube radius r(u) = r0 + dr*cos(u): thickest at u=0, thinnest at u=pi.
function torus(R, r0, dr, nu, nv, place) {
  const rr = (u) => r0 + dr * Math.cos(u);
  const at = (u, v, grow = 1) => {
    const r = rr(u) * grow;
    return place([(R + r * Math.cos(v)) * Math.cos(u), (R + r * Math.cos(v)) * Math.sin(u), r * Math.sin(v)]);
  };
  const verts = [], faces = [];
  for (let i = 0; i < nu; i++) for (let j = 0; j < nv; j++) verts.push(at((2 * Math.PI * i) / nu, (2 * Math.PI * j) / nv));
  const id = (i, j) => (i % nu) * nv + (j % nv);
  for (let i = 0; i < nu; i++) for (let j = 0; j < nv; j++) {
    faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)], [id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
  }
  const circle = (n, f) => Array.from({ length: n }, (_, k) => f((2 * Math.PI * k) / n).map(round));
  const grow = 1.01;  // loops sit just outside the faceted surface
  const loops = [
    { side: 'handle', kind: 'generator', pts: circle(96, (v) => at(0, v, grow)), depth: r0 + dr, r: r0 + dr },
    { side: 'handle', kind: 'choke', pts: circle(96, (v) => at(Math.PI, v, grow)), depth: r0 - dr, r: r0 - dr },
    { side: 'tunnel', kind: 'generator', pts: circle(240, (u) => at(u, Math.PI / 2, grow)), depth: R - r0 + dr, r: R },
    { side: 'tunnel', kind: 'choke', pts: circle(240, (u) => at(u, Math.PI, grow)), depth: R - r0 - dr, r: R - r0 },
  ];
  return { verts, faces, loops };
}

function writePly(file, verts, faces) {
  const header = `ply\nformat ${binary ? 'binary_little_endian' : 'ascii'} 1.0\ncomment chokeloops viewer fixture\n` +
    `element vertex ${verts.length}\nproperty float x\nproperty float y\nproperty float z\n` +
    `element face ${faces.length}\nproperty list uchar int vertex_indices\nend_header\n`;
  if (!binary) {
    const lines = [header.trimEnd()];
    for (const v of verts) lines.push(v.map((x) => round(x)).join(' '));
    for (const f of faces) lines.push(`3 ${f.join(' ')}`);
    fs.writeFileSync(file, lines.join('\n') + '\n');
    return;
  }
  const buf = Buffer.alloc(verts.length * 12 + faces.length * 13);
  let o = 0;
  for (const v of verts) for (const x of v) { buf.writeFloatLE(x, o); o += 4; }
  for (const f of faces) { buf.writeUInt8(3, o); o += 1; for (const x of f) { buf.writeInt32LE(x, o); o += 4; } }
  fs.writeFileSync(file, Buffer.concat([Buffer.from(header, 'ascii'), buf]));
}

const parts = kind === 'torus'
  ? [torus(1, 0.35, 0.1, 48, 24, (p) => p)]
  : [
      torus(1, 0.35, 0.1, 600, 200, (p) => p),
      torus(0.8, 0.25, 0.08, 600, 200, ([x, y, z]) => [x + 3, z, y]),            // stands up in the xz plane
      torus(1.2, 0.3, 0.12, 600, 200, ([x, y, z]) => [x + 6.5, y + 0.5, z + 0.4]),
    ];
const verts = [], faces = [], loops = [];
const diagram = { handle: [], tunnel: [] };
let seed = 7;
const rand = () => ((seed = (seed * 16807) % 2147483647) / 2147483647);
for (const part of parts) {
  const base = verts.length;
  for (const v of part.verts) verts.push(v);
  for (const f of part.faces) faces.push(f.map((i) => i + base));
  for (const l of part.loops) {
    const persistence = round(l.side === 'handle' ? 0.8 * l.r : 0.6 * l.r);
    let length = 0;
    for (let k = 0; k < l.pts.length; k++) {
      const a = l.pts[k], b = l.pts[(k + 1) % l.pts.length];
      length += Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
    }
    const centroid = [0, 1, 2].map((a) => round(l.pts.reduce((s, p) => s + p[a], 0) / l.pts.length));
    const choke = l.pts[0];
    const depth = round(l.depth);
    loops.push({ id: loops.length, side: l.side, kind: l.kind, depth, persistence, birth: round(-depth), death: round(-depth + persistence),
      length: round(length), choke_point: choke, centroid, points: l.pts });
    diagram[l.side].push([depth, persistence]);
  }
  for (let k = 0; k < 6; k++) {
    diagram.handle.push([round(0.02 + 0.5 * rand()), round(0.03 * rand())]);
    diagram.tunnel.push([round(0.02 + 0.9 * rand()), round(0.03 * rand())]);
  }
}
diagram.handle.push([0.95, 0.12]);  // persistent but too deep: beyond d_max
const report = {
  input: kind === 'torus' ? 'thin-torus.obj' : 'three-tori.obj', units: 'input', voxel_size: 0.01,
  grid: { dims: [260, 260, 100], origin: [-1.5, -1.5, -0.5] },
  surface: { vertices: verts.length, faces: faces.length, components: parts.length, genus: parts.length },
  scales: { R_in: 0.45, R_out: 1.3 },
  parameters: { d_max: '50%', min_persistence: '10%', d_max_abs: 0.9, min_persistence_abs_handle: 0.045, min_persistence_abs_tunnel: 0.05 },
  loops, diagram,
  timings_ms: { levelset: 120, persistence: 80, loops: 40, total: 260 },
};
fs.mkdirSync(outdir, { recursive: true });
writePly(path.join(outdir, 'surface.ply'), verts, faces);
fs.writeFileSync(path.join(outdir, 'loops.json'), JSON.stringify(report, null, kind === 'torus' ? 1 : 0) + '\n');
console.log(`${outdir}: ${verts.length} vertices, ${faces.length} faces, ${loops.length} loops`);
