// Writes synthetic report directories, as the C++ side writes them, for developing and testing
// the viewer:  node test/make-fixture.mjs OUTDIR [--bundle dist/snh-report.js]
//   OUTDIR/stretch       a hex box (res 4) stretched along y over 6 frames, with stats.json
//   OUTDIR/lab           a lab report: 2 tables, 3 plots, no mesh (bundle at a relative path)
//   OUTDIR/nomesh        the stretch run without frames (mesh null)
//   OUTDIR/broken-frame  the stretch run with frame 3's file missing
import { copyFileSync, cpSync, mkdirSync, rmSync, writeFileSync } from 'node:fs';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const args = process.argv.slice(2);
const out = resolve(args.find((a) => !a.startsWith('--')) || '/tmp/snh-fixture');
const bi = args.indexOf('--bundle');
const bundle = resolve(bi >= 0 ? args[bi + 1] : join(here, '..', 'dist', 'snh-report.js'));

const b64 = (a) => Buffer.from(a.buffer, a.byteOffset, a.byteLength).toString('base64');
const indexHtml = (title, bundlePath) => `<!doctype html>
<html lang="en"><head><meta charset="utf-8"><meta name="viewport" content="width=device-width, initial-scale=1">
<title>snh report: ${title}</title></head>
<body><div id="snh-report"></div>
<noscript>This report needs JavaScript.</noscript>
<script src="report/data.js"></script>
<script src="${bundlePath}"></script>
</body></html>
`;
function writeReport(dir, data, bundlePath = 'report/snh-report.js') {
  mkdirSync(join(dir, 'report'), { recursive: true });
  writeFileSync(join(dir, 'index.html'), indexHtml(data.title, bundlePath));
  writeFileSync(join(dir, 'report', 'data.js'), `window.SNH_REPORT = ${JSON.stringify(data)};\n`);
}

// ---- the stretch run: a box of res^3 hexes on [0,1]^3, y stretched by λ, ends pinned ----
const res = 4;
const N = res + 1;
const vid = (i, j, k) => i + N * (j + N * k);
const cid = (i, j, k) => i + res * (j + res * k);
const X = [];
for (let k = 0; k < N; k++) for (let j = 0; j < N; j++) for (let i = 0; i < N; i++) X.push([i / res, j / res, k / res]);

// Boundary faces: for each hex face on the box's boundary, its corners counter-clockwise from outside.
const faces = []; // {cell, v: [a, b, c, d]}
for (let k = 0; k < res; k++) for (let j = 0; j < res; j++) for (let i = 0; i < res; i++) {
  const c = cid(i, j, k);
  const v = (a, b, d) => vid(i + a, j + b, k + d);
  if (i === 0) faces.push({ cell: c, v: [v(0, 0, 0), v(0, 0, 1), v(0, 1, 1), v(0, 1, 0)] });
  if (i === res - 1) faces.push({ cell: c, v: [v(1, 0, 0), v(1, 1, 0), v(1, 1, 1), v(1, 0, 1)] });
  if (j === 0) faces.push({ cell: c, v: [v(0, 0, 0), v(1, 0, 0), v(1, 0, 1), v(0, 0, 1)] });
  if (j === res - 1) faces.push({ cell: c, v: [v(0, 1, 0), v(0, 1, 1), v(1, 1, 1), v(1, 1, 0)] });
  if (k === 0) faces.push({ cell: c, v: [v(0, 0, 0), v(0, 1, 0), v(1, 1, 0), v(1, 0, 0)] });
  if (k === res - 1) faces.push({ cell: c, v: [v(0, 0, 1), v(1, 0, 1), v(1, 1, 1), v(0, 1, 1)] });
}
const surfV = [...new Set(faces.flatMap((f) => f.v))].sort((a, b) => a - b);
const surfC = [...new Set(faces.map((f) => f.cell))].sort((a, b) => a - b);
const vLocal = new Map(surfV.map((v, i) => [v, i]));
const cLocal = new Map(surfC.map((c, i) => [c, i]));
const triangles = new Uint32Array(faces.flatMap((f) => {
  const [a, b, c, d] = f.v.map((v) => vLocal.get(v));
  return [a, b, c, a, c, d];
}));
const triangleCells = new Uint32Array(faces.flatMap((f) => [cLocal.get(f.cell), cLocal.get(f.cell)]));
const n = surfV.length;
const m = surfC.length;
const rest = new Float32Array(surfV.flatMap((v) => X[v]));
const pinned = new Uint8Array(surfV.map((v) => (X[v][1] === 0 || X[v][1] === 1 ? 1 : 0)));

// The deformation at stretch λ: y scaled, the middle contracts sideways (the ends are held).
const lateral = (lam, y) => 1 - (1 - lam ** -0.7) * 4 * y * (1 - y);
const place = (lam, [x, y, z]) => {
  const s = lateral(lam, y);
  return [0.5 + (x - 0.5) * s, y * lam, 0.5 + (z - 0.5) * s];
};
// min det F over a cell (F = diag(s, λ, s) plus a shear that does not change det): at its y ends
const cellJ = (lam, c) => {
  const j = Math.floor(c / res) % res;
  return Math.min(...[j / res, (j + 1) / res].map((y) => lam * lateral(lam, y) ** 2));
};
const cellPsi = (lam, c) => {
  const J = cellJ(lam, c);
  const s2 = J / lam;
  return 0.5 * (lam * lam + 2 * s2 - 3) - Math.log(J) + 0.6 * (J - 1) ** 2;
};

const frameCount = 6;
const lambdas = [...Array(frameCount)].map((_, f) => 1 + 0.1 * f);
const frames = [];
const stats = [];
const lo = [Infinity, Infinity, Infinity];
const hi = [-Infinity, -Infinity, -Infinity];
const range = { J: [1, 1], psi: [Infinity, -Infinity], displacement: [Infinity, -Infinity] };
const widen = (r, v) => { r[0] = Math.min(r[0], v); r[1] = Math.max(r[1], v); };
lambdas.forEach((lam, f) => {
  const x = new Float32Array(surfV.flatMap((v) => place(lam, X[v])));
  for (let i = 0; i < x.length; i++) { lo[i % 3] = Math.min(lo[i % 3], x[i]); hi[i % 3] = Math.max(hi[i % 3], x[i]); }
  const allJ = [...Array(res ** 3)].map((_, c) => Math.fround(cellJ(lam, c)));
  const J = new Float32Array(surfC.map((c) => allJ[c]));
  const psi = new Float32Array(surfC.map((c) => cellPsi(lam, c)));
  if (f === frameCount - 1) psi[5] = NaN; // an undefined value: drawn grey
  const disp = new Float32Array(n).map((_, i) => Math.hypot(x[3 * i] - rest[3 * i], x[3 * i + 1] - rest[3 * i + 1], x[3 * i + 2] - rest[3 * i + 2]));
  allJ.forEach((v) => widen(range.J, v));
  psi.forEach((v) => Number.isFinite(v) && widen(range.psi, v));
  disp.forEach((v) => widen(range.displacement, v));
  frames.push({ x: b64(x), J: b64(J), psi: b64(psi), displacement: b64(disp) });
  if (f > 0) {
    const energy = psi.reduce((a, v) => a + (Number.isFinite(v) ? v : 0), 0) / 64;
    stats.push({
      step: f, converged: true, newton_iterations: 3 + (f % 3), residual: f === 3 ? 0 : 10 ** (-6 - f / 2),
      energy, min_J: Math.min(...allJ), volume_ratio: lam * (1 - (1 - 1 / Math.sqrt(lam)) * 0.9), wall_seconds: 0.01 * f,
    });
  }
});

const steps = stats.map((s) => s.step);
const stretch = {
  format: 1, kind: 'stretch', title: 'tetcli 4 stable_neo_hookean 1.0 10.0 fixture', generated_by: 'snh 0.1.0 (fixture)',
  status: { ok: true, text: 'converged every step' },
  meta: [['command line', 'snh stretch --res 4 --element hex --material stable_neo_hookean --mu 1 --lambda 10 --steps 5 fixture'],
    ['material', 'stable_neo_hookean'], ['mu', '1'], ['lambda', '10'], ['element', 'hex'], ['resolution', '4'],
    ['steps', String(steps.length)], ['final stretch', '1.5'], ['wall time', '0.15 s']],
  tables: [{ title: 'Summary', note: 'totals over all steps', columns: ['quantity', 'value'],
    rows: [['Newton iterations', stats.reduce((a, s) => a + s.newton_iterations, 0)], ['min J', Math.min(...stats.map((s) => s.min_J)).toFixed(4)],
      ['final volume ratio', stats.at(-1).volume_ratio.toFixed(4)], ['failures', null]] }],
  plots: [
    { id: 'residual', group: 'Per step', title: 'Residual |f|', x_label: 'step', y_label: '|f|', log_y: true, x: steps,
      series: [{ label: '|f|', y: stats.map((s, i) => (i === 1 ? null : s.residual)) }] },
    { id: 'energy', group: 'Per step', title: 'Energy', x_label: 'step', y_label: 'E', x: steps, series: [{ label: 'energy', y: stats.map((s) => s.energy) }] },
    { id: 'volume', group: 'Per step', title: 'Volume', x_label: 'step', y_label: 'ratio', x: steps,
      series: [{ label: 'min J', y: stats.map((s) => s.min_J) }, { label: 'V / V₀', y: stats.map((s) => s.volume_ratio) }] },
    { id: 'newton', group: 'Solver', title: 'Newton iterations', x_label: 'step', y_label: 'iterations', points_only: true, x: steps,
      series: [{ label: 'iterations', y: stats.map((s) => s.newton_iterations) }] },
    { id: 'wall', group: 'Solver', title: 'Wall time per step', x_label: 'step', y_label: 's', x: steps, series: [{ label: 'wall', y: stats.map((s) => s.wall_seconds) }] },
  ],
  mesh: {
    element: 'hex', vertex_count: N ** 3, cell_count: res ** 3, pinned_count: 2 * N * N,
    surface: { vertex_count: n, cell_count: m, triangle_count: triangles.length / 3, triangles: b64(triangles),
      triangle_cells: b64(triangleCells), rest: b64(rest), pinned: b64(pinned) },
    bounds: { min: lo, max: hi },
    fields: [
      { name: 'J', label: 'volume change J (min det F per element)', per: 'cell', min: range.J[0], max: range.J[1], colormap: 'diverging', center: 1.0 },
      { name: 'psi', label: 'energy density ψ', per: 'cell', min: range.psi[0], max: range.psi[1], colormap: 'sequential' },
      { name: 'displacement', label: 'displacement magnitude |x − X|', per: 'vertex', min: range.displacement[0], max: range.displacement[1], colormap: 'sequential' },
    ],
    default_field: 'J',
    frames: lambdas.map((_, f) => ({ index: f, time: f, label: `step ${f}`, src: `report/frames/${String(f).padStart(3, '0')}.js` })),
  },
};

rmSync(out, { recursive: true, force: true });
const sdir = join(out, 'stretch');
writeReport(sdir, stretch);
mkdirSync(join(sdir, 'report', 'frames'), { recursive: true });
frames.forEach((fr, f) => writeFileSync(join(sdir, 'report', 'frames', `${String(f).padStart(3, '0')}.js`), `snhReportFrame(${f}, ${JSON.stringify(fr)});\n`));
writeFileSync(join(sdir, 'stats.json'), JSON.stringify({ steps: stats }, null, 2));
copyFileSync(bundle, join(sdir, 'report', 'snh-report.js'));

// Variants for robustness checks.
cpSync(sdir, join(out, 'broken-frame'), { recursive: true });
rmSync(join(out, 'broken-frame', 'report', 'frames', '003.js'));
const nodir = join(out, 'nomesh');
writeReport(nodir, { ...stretch, title: 'a run that wrote no frames', status: { ok: false, text: 'step 1 did not converge in 50 iterations' }, mesh: null });
copyFileSync(bundle, join(nodir, 'report', 'snh-report.js'));

// ---- the lab report ----
const mats = ['stable_neo_hookean', 'neo_hookean', 'corotational'];
const stretches = [1, 1.25, 1.5, 1.75, 2, 2.5, 3];
const lab = {
  format: 1, kind: 'lab', title: 'lab: material comparison (fixture)', generated_by: 'snh 0.1.0 (fixture)',
  status: { ok: false, text: '1 of 3 materials inverted an element' },
  meta: [['command line', 'snh lab materials fixture'], ['runs', '3'], ['wall time', '2.4 s']],
  tables: [
    { title: 'Materials under uniaxial stretch', note: 'each run is a box of hexes, res 4, stretched to 3', columns: ['material', 'min J', 'V / V₀', 'inverted', 'run'],
      rows: mats.map((mt, i) => [mt, (0.6 + 0.1 * i).toFixed(4), (1 - 0.02 * i).toFixed(4), i === 2 ? 3 : 0, { text: 'report', href: `rest/free/${mt}/index.html` }]) },
    { title: 'Convergence', columns: ['material', 'Newton its', 'failures'], rows: mats.map((mt, i) => [mt, 40 + 7 * i, i === 2 ? 'step 7' : null]) },
  ],
  plots: [
    { id: 'energy-stretch', group: 'Energy', title: 'Energy vs stretch', x_label: 'stretch', y_label: 'E', x: stretches,
      series: mats.map((mt, i) => ({ label: mt, y: stretches.map((s) => (s - 1) ** 2 * (1 + 0.3 * i)) })) },
    { id: 'poisson', group: 'Energy', title: 'Volume ratio vs stretch', x_label: 'stretch', y_label: 'V / V₀', x: stretches,
      series: mats.map((mt, i) => ({ label: mt, y: stretches.map((s, k) => (i === 2 && k === 4 ? null : 1 - 0.02 * i * (s - 1))) })) },
    { id: 'error', group: 'Convergence', title: 'Error vs resolution', x_label: 'resolution', y_label: 'error', log_y: true, points_only: true,
      x: [2, 4, 8, 16], series: [{ label: 'L2', y: [0.1, 0.026, 0.0064, 0.0016] }, { label: 'max', y: [0.3, 0.09, 0, 0.008] }] },
  ],
  mesh: null,
};
writeReport(join(out, 'lab'), lab, '../stretch/report/snh-report.js');
console.log(`make-fixture: wrote ${out}/{stretch,lab,nomesh,broken-frame}`);
