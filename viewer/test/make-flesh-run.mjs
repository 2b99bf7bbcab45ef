// Turns the output directory of a scene run (snh run: frames.pvd, NNN.vtu, stats.json) into a flesh-like
// run directory, as `snh flesh` writes one, for testing the report of flesh runs:
//   node test/make-flesh-run.mjs RUN_DIR
// The scene must be a box (its volume's vertices on a grid). It adds an "arm" inside the run's volume: a
// capsule along the volume's longest axis (the render surface) and two bones along its centre line, plus a
// point bone at its far end. The volume carries them:
//   surface/NNN.obj  the capsule embedded in the volume (trilinear in its lattice's cells)
//   lbs/NNN.obj      the capsule posed from the bones by linear blend skinning (which loses volume at a bend)
//   bones.json       the bones' segments of every frame
//   flesh.usda       a stage (a stub: the report only links it)
//   stats.json       + per frame surface_volume_ratio and lbs_volume_ratio (their schema columns and the
//                    render_volume plot), + the run-level keys of a flesh run, with two warnings
import { existsSync, mkdirSync, readFileSync, writeFileSync } from 'node:fs';
import { basename, join } from 'node:path';

const dir = process.argv[2];
if (!dir || !existsSync(join(dir, 'frames.pvd'))) {
  console.error('usage: node test/make-flesh-run.mjs RUN_DIR   (a scene run\'s directory, with frames.pvd)');
  process.exit(2);
}

// ---- the volume's frames ----
const pvd = readFileSync(join(dir, 'frames.pvd'), 'utf8');
const frames = [...pvd.matchAll(/<DataSet\b[^>]*>/g)].map(([tag]) => ({
  time: Number(/timestep="([^"]*)"/.exec(tag)[1]),
  file: /file="([^"]*)"/.exec(tag)[1],
}));
/**
 * The numbers of the DataArray whose opening tag matches `re` in a .vtu file's bytes: ASCII, or appended
 * raw (UInt64 length header, Float64 values), as snh writes its frames.
 */
function array(bytes, re) {
  const ad = bytes.indexOf('<AppendedData');
  const xml = bytes.toString('latin1', 0, ad < 0 ? bytes.length : ad);
  const m = re.exec(xml);
  if (!m) return null;
  const tagEnd = xml.indexOf('>', m.index + m[0].length);
  const tag = xml.slice(m.index, tagEnd);
  if (!/format="appended"/.test(tag)) return xml.slice(tagEnd + 1, xml.indexOf('</DataArray>', tagEnd)).trim().split(/\s+/).map(Number);
  if (!/type="Float64"/.test(tag) || !/header_type="UInt64"/.test(xml)) throw new Error(`unexpected DataArray: ${tag}`);
  const at = bytes.indexOf('_', ad) + 1 + Number(/offset="(\d+)"/.exec(tag)[1]);
  const length = Number(bytes.readBigUInt64LE(at));
  return Array.from({ length: length / 8 }, (_, i) => bytes.readDoubleLE(at + 8 + 8 * i));
}
const volume = frames.map((f) => {
  const bytes = readFileSync(join(dir, f.file));
  return { x: array(bytes, /<Points>\s*<DataArray/), u: array(bytes, /<DataArray[^>]*Name="displacement"/) };
});
const nv = volume[0].x.length / 3;
const rest = volume[0].x.map((v, i) => v - (volume[0].u ? volume[0].u[i] : 0));

// ---- the arm at rest: a capsule along the volume's longest axis ----
const lo = [0, 1, 2].map((a) => Math.min(...rest.filter((_, i) => i % 3 === a)));
const hi = [0, 1, 2].map((a) => Math.max(...rest.filter((_, i) => i % 3 === a)));
const axis = [0, 1, 2].reduce((b, a) => (hi[a] - lo[a] > hi[b] - lo[b] ? a : b), 0);
const [u, w] = [0, 1, 2].filter((a) => a !== axis);
const center = lo.map((v, a) => (v + hi[a]) / 2);
const radius = 0.7 * Math.min(hi[u] - lo[u], hi[w] - lo[w]) / 2;
const start = lo[axis] + 0.05 * (hi[axis] - lo[axis]);
const length = 0.9 * (hi[axis] - lo[axis]);
const point = (along, cu, cw) => {
  const p = center.slice();
  p[axis] = along;
  p[u] += cu;
  p[w] += cw;
  return p;
};
const SEG = 24; // around
const BODY = 36; // rings along the body
const CAP = 8; // rings on each cap
const rings = []; // [along, ring radius]
for (let k = 1; k < CAP; k++) {
  const t = (Math.PI / 2) * (1 - k / CAP);
  rings.push([start + radius - radius * Math.sin(t), radius * Math.cos(t)]);
}
for (let k = 0; k <= BODY; k++) rings.push([start + radius + ((length - 2 * radius) * k) / BODY, radius]);
for (let k = CAP - 1; k >= 1; k--) {
  const t = (Math.PI / 2) * (1 - k / CAP);
  rings.push([start + length - radius + radius * Math.sin(t), radius * Math.cos(t)]);
}
const X = [point(start, 0, 0)]; // the first pole, the rings, the last pole
for (const [along, r] of rings) {
  for (let s = 0; s < SEG; s++) {
    const angle = (2 * Math.PI * s) / SEG;
    X.push(point(along, r * Math.cos(angle), r * Math.sin(angle)));
  }
}
X.push(point(start + length, 0, 0));
const last = X.length - 1;
const ring = (k, s) => 1 + k * SEG + (s % SEG);
const T = []; // triangles, 0-based: the same in every frame (their orientation does not matter here)
for (let s = 0; s < SEG; s++) T.push([0, ring(0, s + 1), ring(0, s)]);
for (let k = 0; k + 1 < rings.length; k++) {
  for (let s = 0; s < SEG; s++) {
    T.push([ring(k, s), ring(k, s + 1), ring(k + 1, s + 1)], [ring(k, s), ring(k + 1, s + 1), ring(k + 1, s)]);
  }
}
for (let s = 0; s < SEG; s++) T.push([last, ring(rings.length - 1, s), ring(rings.length - 1, s + 1)]);

// ---- the embedding: trilinear in the volume's lattice (a scene run on a box: its vertices on a grid) ----
const planes = (a) => new Set(rest.filter((_, i) => i % 3 === a).map((v) => Number(v.toPrecision(9))));
const grid = [0, 1, 2].map((a) => [...planes(a)].sort((p, q) => p - q));
const at = new Map(); // "i,j,k" -> vertex
for (let v = 0; v < nv; v++) at.set([0, 1, 2].map((a) => grid[a].indexOf(Number(rest[3 * v + a].toPrecision(9)))).join(), v);
if (grid[0].length * grid[1].length * grid[2].length !== nv || at.size !== nv) {
  console.error(`make-flesh-run: ${dir}: the volume's vertices are not a grid (run a scene on a box)`);
  process.exit(1);
}
/** The 8 vertices around p and their trilinear weights. */
function embed(p) {
  const cell = [0, 1, 2].map((a) => {
    const g = grid[a];
    const above = g.findIndex((v) => v > p[a]); // -1 past the last plane
    const c = above < 0 ? g.length - 2 : Math.min(Math.max(above - 1, 0), g.length - 2);
    return [c, (p[a] - g[c]) / (g[c + 1] - g[c])];
  });
  const out = [];
  for (let corner = 0; corner < 8; corner++) {
    const bits = [corner & 1, (corner >> 1) & 1, (corner >> 2) & 1];
    const weight = bits.reduce((acc, b, a) => acc * (b ? cell[a][1] : 1 - cell[a][1]), 1);
    out.push([at.get(bits.map((b, a) => cell[a][0] + b).join()), weight]);
  }
  return out;
}
const carried = (weights, x) => [0, 1, 2].map((a) => weights.reduce((acc, [v, wt]) => acc + wt * x[3 * v + a], 0));

// ---- the bones: root>middle, middle>tip, and the point bone "tip" ----
const joints = [start + 0.08 * length, start + 0.5 * length, start + 0.92 * length].map((along) => point(along, 0, 0));
const bones = [['root>middle', 0, 1], ['middle>tip', 1, 2], ['tip', 2, 2]];
const jointWeights = joints.map(embed);
const sub = (a, b) => a.map((v, k) => v - b[k]);
const add = (a, b) => a.map((v, k) => v + b[k]);
const scale = (a, s) => a.map((v) => v * s);
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const unit = (a) => scale(a, 1 / Math.hypot(...a));
/** The smallest rotation taking unit vector a to unit vector b, applied to p (Rodrigues). */
function rotate(a, b, p) {
  const k = cross(a, b);
  const s = Math.hypot(...k);
  const c = dot(a, b);
  if (s < 1e-12) return p.slice();
  const n = scale(k, 1 / s);
  return add(add(scale(p, c), scale(cross(n, p), s)), scale(n, dot(n, p) * (1 - c)));
}
// Skinning weights of the two segment bones: a smooth blend across the middle joint.
const smooth = (t) => (t <= 0 ? 0 : t >= 1 ? 1 : t * t * (3 - 2 * t));
const skinWeight = X.map((p) => smooth((p[axis] - joints[1][axis]) / (0.3 * length) + 0.5)); // of middle>tip

// ---- every frame ----
const vertexWeights = X.map(embed);
const obj = (P) => `${P.map((p) => `v ${p.map((v) => Number(v.toPrecision(9))).join(' ')}`).join('\n')}\n` +
  `${T.map((t) => `f ${t.map((i) => i + 1).join(' ')}`).join('\n')}\n`;
/** The signed volume inside a closed surface (divergence theorem), made positive. */
const enclosed = (P) => Math.abs(T.reduce((acc, [a, b, c]) => acc + dot(P[a], cross(P[b], P[c])), 0) / 6);
mkdirSync(join(dir, 'surface'), { recursive: true });
mkdirSync(join(dir, 'lbs'), { recursive: true });
const restVolume = enclosed(X);
const boneFrames = [];
const ratios = [];
frames.forEach((f, i) => {
  const x = volume[i].x;
  const J = jointWeights.map((wt) => carried(wt, x));
  const flesh = vertexWeights.map((wt) => carried(wt, x));
  const pose = [0, 1].map((b) => {
    const [, a0, b0] = bones[b];
    return { from: unit(sub(joints[b0], joints[a0])), to: unit(sub(J[b0], J[a0])), a0: joints[a0], a: J[a0] };
  });
  const lbs = X.map((p, v) => {
    const [p0, p1] = pose.map((m) => add(m.a, rotate(m.from, m.to, sub(p, m.a0))));
    return add(scale(p0, 1 - skinWeight[v]), scale(p1, skinWeight[v]));
  });
  const name = `${basename(f.file).replace(/\.vtu$/, '')}.obj`;
  writeFileSync(join(dir, 'surface', name), obj(flesh));
  writeFileSync(join(dir, 'lbs', name), obj(lbs));
  boneFrames.push({ time: f.time, segments: bones.map(([, a, b]) => [...J[a], ...J[b]]) });
  ratios.push([enclosed(flesh) / restVolume, enclosed(lbs) / restVolume]);
});
writeFileSync(join(dir, 'bones.json'), `${JSON.stringify({ bones: bones.map(([n]) => n), frames: boneFrames })}\n`);
writeFileSync(join(dir, 'flesh.usda'),
  '#usda 1.0\n(\n    doc = "make-flesh-run.mjs: a stub stage"\n    defaultPrim = "character"\n)\n\ndef Xform "character"\n{\n}\n');

// ---- stats.json: the records' two volumes, their schema, and a flesh run's settings ----
const stats = JSON.parse(readFileSync(join(dir, 'stats.json'), 'utf8'));
stats.frames.forEach((r, i) => {
  const k = Number.isInteger(r.frame) ? r.frame : i;
  if (ratios[k]) [r.surface_volume_ratio, r.lbs_volume_ratio] = ratios[k];
});
stats.schema.columns.push({ key: 'surface_volume_ratio', label: 'flesh', plot: 'render_volume' },
  { key: 'lbs_volume_ratio', label: 'linear blend skinning', plot: 'render_volume' });
stats.schema.plots.push({
  id: 'render_volume', title: 'Volume inside the render surface (posed / rest)', y_label: 'ratio', log_y: false,
});
// The volume vertices each bone binds: those within `radius` of its segment.
const boundBy = bones.map(([, a, b]) => {
  const ab = sub(joints[b], joints[a]);
  const within = new Set();
  for (let v = 0; v < nv; v++) {
    const p = rest.slice(3 * v, 3 * v + 3);
    const t = dot(ab, ab) > 0 ? Math.min(Math.max(dot(sub(p, joints[a]), ab) / dot(ab, ab), 0), 1) : 0;
    if (Math.hypot(...sub(p, add(joints[a], scale(ab, t)))) <= radius) within.add(v);
  }
  return within;
});
const bound = boundBy.map((s) => s.size);
Object.assign(stats, {
  model: 'fixture-arm.glb', volume: 'lattice', animation: 'the scene\'s motion', model_vertices: X.length,
  model_triangles: T.length, joints: joints.length, bound_vertices: new Set(boundBy.flatMap((s) => [...s])).size,
  bones: bones.map(([name], b) => ({ name, radius, bound: bound[b] })), usd: 'flesh.usda',
  // What a flesh run warns of (the report's status lists them): two, as a pressed run's would read.
  warnings: ['the bones press flesh inside out in 2 frames: in frame 4 (t = 0.4) upper and lower carry bound vertices 0.5 apart at rest to 0.01 (2 %)',
    '2 frames converged with elements turned inside out (at most 3, in frame 4)'],
});
writeFileSync(join(dir, 'stats.json'), `${JSON.stringify(stats, null, 2)}\n`);
console.log(`make-flesh-run: ${dir}: ${frames.length} frames of a render surface of ${X.length} vertices, ` +
  `${T.length} triangles, ${bones.length} bones`);
