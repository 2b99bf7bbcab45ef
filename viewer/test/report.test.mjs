// Checks a report directory written by the C++ side (or by test/make-fixture.mjs) in Chromium.
// Each part runs only when its variable is set:
//   SNH_TEST_RUN_DIR        a stretch (or scene) run's directory: page, 3D view, slider, plots, legend
//   SNH_TEST_CHECK_MIN_J=1  also: the legend's min for J = min over stats.json of min_J (and 1)
//   SNH_TEST_LAB_DIR        a lab report's directory: tables and plots
//   SNH_TEST_FLESH_DIR      a flesh run's directory (or one made by test/make-flesh-run.mjs): the switch among
//                           flesh, skinning and volume, the bones and their frames, the render volume plot
//   SNH_TEST_MUSCLE_DIR     a run with muscles (muscles.json): the fibres drawn, moved and coloured by each frame's
//                           activation, and their switch
//   SNH_TEST_RENDER_PNG     a PNG taken in render mode, with SNH_TEST_RENDER_SIZE=WxH: size, not blank
//   SNH_TEST_FRAMING_DIR    a flesh run: render mode's framing in six views and layouts (tests/apps/test_pictures.sh
//                           gives it the hand)
// Chromium: /usr/bin/chromium, or SNH_TEST_CHROMIUM.
import assert from 'node:assert/strict';
import { existsSync, readFileSync } from 'node:fs';
import { join } from 'node:path';
import { after, before, test } from 'node:test';
import { pathToFileURL } from 'node:url';
import { chromium } from 'playwright-core';
import { PNG } from 'pngjs';

const env = process.env;
const RUN = env.SNH_TEST_RUN_DIR;
const LAB = env.SNH_TEST_LAB_DIR;
const FLESH = env.SNH_TEST_FLESH_DIR;
const RENDER = env.SNH_TEST_RENDER_PNG;
const MUSCLE = env.SNH_TEST_MUSCLE_DIR;
const FRAMING = env.SNH_TEST_FRAMING_DIR;
const TIMEOUT = 30000;
let browser;

before(async () => {
  if (!RUN && !LAB && !FLESH && !MUSCLE && !FRAMING) return;
  browser = await chromium.launch({
    executablePath: env.SNH_TEST_CHROMIUM || '/usr/bin/chromium',
    headless: true,
    args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
      '--disable-component-update', '--disable-sync'],
  });
});
after(async () => browser && browser.close());

/** Opens DIR/index.html (with `hash`) and waits for the report; `problems` collects console errors and page errors. */
async function open(dir, hash = '') {
  const page = await browser.newPage({ viewport: { width: 1280, height: 900 } });
  const problems = [];
  page.on('console', (m) => m.type() === 'error' && problems.push(`console: ${m.text()}`));
  page.on('pageerror', (e) => problems.push(`page error: ${e.message}`));
  await page.goto(pathToFileURL(join(dir, 'index.html')).href + hash);
  await page.waitForFunction(() => window.snhReport && window.snhReport.ready, null, { timeout: TIMEOUT });
  return { page, problems };
}

async function assertNoErrors(page, problems) {
  const errors = await page.evaluate(() => window.snhReport.errors);
  assert.deepEqual([...problems, ...errors.map((e) => `snhReport: ${e}`)], []);
}

const pixel = (png, x, y) => png.data.subarray(4 * (y * png.width + x), 4 * (y * png.width + x) + 3);
const differs = (a, b) => Math.max(Math.abs(a[0] - b[0]), Math.abs(a[1] - b[1]), Math.abs(a[2] - b[2])) > 12;

/** The fraction of pixels in [x0,x1)×[y0,y1) for which test(pixel) holds. */
function fraction(png, test, [x0, y0, x1, y1] = [0, 0, png.width, png.height]) {
  let hit = 0;
  for (let y = y0; y < y1; y++) for (let x = x0; x < x1; x++) if (test(pixel(png, x, y), x, y)) hit++;
  return hit / Math.max(1, (x1 - x0) * (y1 - y0));
}

function readReport(dir) {
  const text = readFileSync(join(dir, 'report', 'data.js'), 'utf8').trim();
  const prefix = 'window.SNH_REPORT = ';
  assert.ok(text.startsWith(prefix), 'data.js starts with "window.SNH_REPORT = "');
  return JSON.parse(text.slice(prefix.length).replace(/;$/, ''));
}

function readSteps(dir) {
  const stats = JSON.parse(readFileSync(join(dir, 'stats.json'), 'utf8'));
  const steps = stats.steps || stats.frames;
  assert.ok(Array.isArray(steps), 'stats.json has "steps" or "frames"');
  return steps;
}

test('stretch run report', { skip: !RUN && 'SNH_TEST_RUN_DIR is not set', timeout: 60000 }, async () => {
  const report = readReport(RUN);
  const steps = readSteps(RUN);
  const { page, problems } = await open(RUN);
  const canvasShot = async () => PNG.sync.read(await page.locator('.snh-view canvas').screenshot());

  // The mesh is drawn: the middle third of the canvas is not all background. (The view is framed on every
  // frame's bounds, so a first frame can be small: a bar at rest that later swings down covers ~6 %.)
  const bg = await page.evaluate(() => window.snhReport.background);
  const first = await canvasShot();
  const w = first.width;
  const h = first.height;
  const middle = [Math.floor(w / 3), Math.floor(h / 3), Math.floor((2 * w) / 3), Math.floor((2 * h) / 3)];
  const covered = fraction(first, (p) => differs(p, bg), middle);
  assert.ok(covered > 0.03, `the mesh covers ${(100 * covered).toFixed(1)}% of the canvas' middle third`);
  // Only a flesh run has the switch among flesh, skinning and volume.
  assert.equal(await page.locator('#snh-show-flesh').count(), report.render ? 1 : 0);
  // The status: a plain tick for a run that finished clean, a warning sign and the list where it warned.
  const warnings = report.status.warnings || [];
  if (report.status.ok !== false) assert.equal(await page.locator(warnings.length ? '.snh-status-warn' : '.snh-status-ok').count(), 1);
  assert.deepEqual(await page.$$eval('.snh-warnings li', (ls) => ls.map((l) => l.textContent)), warnings);

  // The slider to the last frame: the frame and the picture change.
  const count = await page.evaluate(() => window.snhReport.frameCount);
  assert.equal(count, report.mesh.frames.length);
  if (count > 1) {
    await page.$eval('#snh-frame-slider', (el, v) => {
      el.value = String(v);
      el.dispatchEvent(new Event('input', { bubbles: true }));
    }, count - 1);
    await page.waitForFunction((last) => window.snhReport.frame === last, count - 1, { timeout: TIMEOUT });
    const last = await canvasShot();
    const changed = fraction(last, (p, x, y) => differs(p, pixel(first, x, y)));
    assert.ok(changed > 0.005, `the last frame changes ${(100 * changed).toFixed(2)}% of the pixels`);
  }

  // Step keys: Home, then → (the body has the focus); play runs to the last frame and stops there.
  if (count > 2) {
    await page.keyboard.press('Home');
    await page.waitForFunction(() => window.snhReport.frame === 0, null, { timeout: TIMEOUT });
    await page.keyboard.press('ArrowRight');
    await page.waitForFunction(() => window.snhReport.frame === 1, null, { timeout: TIMEOUT });
    await page.click('#snh-play');
    await page.waitForFunction((last) => window.snhReport.frame === last, count - 1, { timeout: TIMEOUT });
    await page.waitForFunction(() => document.querySelector('#snh-play').getAttribute('aria-pressed') === 'false',
      null, { timeout: TIMEOUT });
    assert.equal(await page.$eval('#snh-frame-slider', (e) => Number(e.value)), count - 1);
  }

  // Another field and the wireframe each change the picture; the legend follows the field.
  const names = report.mesh.fields.map((f) => f.name);
  const before = await canvasShot();
  const current = await page.evaluate(() => window.snhReport.field);
  const other = names.find((n) => n !== current);
  if (other) {
    await page.selectOption('#snh-field', other);
    await page.waitForFunction((n) => window.snhReport.field === n, other, { timeout: TIMEOUT });
    assert.equal(await page.$eval('#snh-legend', (e) => e.dataset.field), other);
    const recoloured = await canvasShot();
    const changed = fraction(recoloured, (p, x, y) => differs(p, pixel(before, x, y)));
    assert.ok(changed > 0.005, `colouring by ${other} changes ${(100 * changed).toFixed(2)}% of the pixels`);
  }
  const plain = await canvasShot();
  await page.check('#snh-wireframe');
  const wired = await canvasShot();
  const wireChange = fraction(wired, (p, x, y) => differs(p, pixel(plain, x, y)));
  assert.ok(wireChange > 0.001, `the wireframe changes ${(100 * wireChange).toFixed(2)}% of the pixels`);
  await page.uncheck('#snh-wireframe');

  // One point per step in every plot.
  const points = await page.$$eval('.snh-plot', (els) => els.map((e) => [e.dataset.plotId, Number(e.dataset.points)]));
  assert.ok(points.length > 0, 'the page has plots');
  for (const [id, n] of points) assert.equal(n, steps.length, `plot "${id}" has one point per step`);

  // The legend shows the current field's range, exactly as in data.js.
  const legend = async () => page.$eval('#snh-legend', (e) => ({ field: e.dataset.field, min: Number(e.dataset.min), max: Number(e.dataset.max) }));
  const shown = await legend();
  const field = report.mesh.fields.find((f) => f.name === shown.field);
  assert.ok(field, `the legend's field "${shown.field}" is in data.js`);
  assert.equal(shown.field, await page.evaluate(() => window.snhReport.field));
  assert.equal(shown.min, field.min);
  assert.equal(shown.max, field.max);

  if (env.SNH_TEST_CHECK_MIN_J === '1') {
    await page.evaluate(() => window.snhReport.setField('J'));
    const j = await legend();
    const expected = Math.min(1, ...steps.map((s) => s.min_J));
    assert.equal(j.field, 'J');
    assert.ok(Math.abs(j.min - expected) <= 1e-6 * Math.max(1, Math.abs(expected)),
      `the legend's min J ${j.min} = min over stats.json of min_J (and 1) ${expected}`);
  }
  await assertNoErrors(page, problems);
  await page.close();
});

test('flesh run report', { skip: !FLESH && 'SNH_TEST_FLESH_DIR is not set', timeout: 90000 }, async () => {
  const report = readReport(FLESH);
  assert.ok(report.render, 'data.js has a "render" part');
  const bones = JSON.parse(readFileSync(join(FLESH, 'bones.json'), 'utf8'));
  const { page, problems } = await open(FLESH);
  const canvasShot = async () => PNG.sync.read(await page.locator('.snh-view canvas').screenshot());
  const changedBetween = (a, b) => fraction(b, (p, x, y) => differs(p, pixel(a, x, y)));
  const visible = () => page.evaluate(() => window.snhReport.visible());
  const pressed = () => page.$$eval('.snh-seg', (bs) => bs.filter((b) => b.getAttribute('aria-pressed') === 'true').map((b) => b.dataset.show));

  // Its warnings: the status is no plain tick, and lists each one.
  assert.equal(await page.locator('.snh-status-warn').count(), 1);
  assert.match(await page.locator('.snh-status').textContent(), /finished with 2 warnings/);
  assert.deepEqual(await page.$$eval('.snh-warnings li', (ls) => ls.map((l) => l.textContent)), report.status.warnings);
  assert.equal(report.status.warnings.length, 2);

  // The flesh first, with its bones; the volume's colours (legend, field) are not in use.
  assert.deepEqual(await page.$$eval('.snh-seg', (bs) => bs.map((b) => b.textContent)), ['flesh', 'skinning (LBS)', 'flesh − LBS distance', 'volume']);
  assert.deepEqual(await pressed(), ['flesh']);
  assert.deepEqual(await visible(), { flesh: true, lbs: false, difference: false, volume: false, bones: true, fibres: false });
  assert.ok(await page.$eval('#snh-legend', (e) => e.hidden), 'no legend over the flesh');
  assert.ok(await page.$eval('#snh-field', (e) => e.disabled), 'the field select is off over the flesh');
  const bg = await page.evaluate(() => window.snhReport.background);
  const flesh = await canvasShot();
  const covered = fraction(flesh, (p) => differs(p, bg));
  assert.ok(covered > 0.03, `the flesh covers ${(100 * covered).toFixed(1)}% of the canvas`);

  // The switch: each choice shows its mesh alone, and the picture changes.
  await page.click('#snh-show-lbs');
  assert.deepEqual(await pressed(), ['lbs']);
  assert.deepEqual(await visible(), { flesh: false, lbs: true, difference: false, volume: false, bones: true, fibres: false });
  const lbs = await canvasShot();
  assert.ok(changedBetween(flesh, lbs) > 0.01, `skinning changes ${(100 * changedBetween(flesh, lbs)).toFixed(2)}% of the pixels`);
  // The flesh coloured by its distance from the skinned surface, with its legend (millimetres, 0 at the centre).
  await page.click('#snh-show-difference');
  assert.deepEqual(await visible(), { flesh: false, lbs: false, difference: true, volume: false, bones: true, fibres: false });
  assert.ok(!(await page.$eval('#snh-legend', (e) => e.hidden)), 'the distance has a legend');
  const legend = await page.evaluate(() => window.snhReport.legend);
  assert.equal(legend.field, 'distance');
  assert.deepEqual([legend.min, legend.max], [report.render.distance.min, report.render.distance.max]);
  assert.match(await page.$eval('.snh-legend-label', (e) => e.textContent), /\(mm\)/);
  const diff = await canvasShot();
  assert.ok(changedBetween(flesh, diff) > 0.01, `the colours change ${(100 * changedBetween(flesh, diff)).toFixed(2)}% of the pixels`);
  await page.click('#snh-show-volume');
  assert.deepEqual(await visible(), { flesh: false, lbs: false, difference: false, volume: true, bones: true, fibres: false });
  assert.equal(await page.evaluate(() => window.snhReport.show), 'volume');
  assert.ok(!(await page.$eval('#snh-legend', (e) => e.hidden)), 'the legend is back with the volume');
  assert.ok(!(await page.$eval('#snh-field', (e) => e.disabled)), 'the field select is on with the volume');
  const vol = await canvasShot();
  assert.ok(changedBetween(lbs, vol) > 0.01, `the volume changes ${(100 * changedBetween(lbs, vol)).toFixed(2)}% of the pixels`);
  await page.click('#snh-show-flesh');
  assert.deepEqual(await visible(), { flesh: true, lbs: false, difference: false, volume: false, bones: true, fibres: false });

  // The bones follow the frames: at each frame shown, the segments of bones.json.
  const segmentsAt = (k) => bones.frames[k].segments.flat();
  const near = (a, b) => a.length === b.length && a.every((v, i) => Math.abs(v - b[i]) <= 1e-5 * Math.max(1, Math.abs(b[i])));
  const count = report.mesh.frames.length;
  assert.ok(count > 2 && bones.frames.length === count, 'a frame of bones per frame');
  const atFirst = await page.evaluate(() => window.snhReport.bones());
  assert.ok(near(atFirst, segmentsAt(0)), 'frame 0 draws the bones of bones.json\'s frame 0');
  const first = await canvasShot();
  await page.$eval('#snh-frame-slider', (el, v) => {
    el.value = String(v);
    el.dispatchEvent(new Event('input', { bubbles: true }));
  }, count - 1);
  await page.waitForFunction((n) => window.snhReport.frame === n, count - 1, { timeout: TIMEOUT });
  const atLast = await page.evaluate(() => window.snhReport.bones());
  assert.ok(near(atLast, segmentsAt(count - 1)), 'the last frame draws the bones of bones.json\'s last frame');
  const moved = Math.max(...atLast.map((v, i) => Math.abs(v - atFirst[i])));
  assert.ok(moved > 1e-3, `the bones move by ${moved} between the first and the last frame`);
  const lastShot = await canvasShot();
  assert.ok(changedBetween(first, lastShot) > 0.005, 'the last frame changes the picture');

  // The bones' toggle hides them, and the picture shows it.
  await page.uncheck('#snh-bones');
  assert.equal((await visible()).bones, false);
  const noBones = await canvasShot();
  assert.ok(changedBetween(lastShot, noBones) > 0.0005, `hiding the bones changes ${(100 * changedBetween(lastShot, noBones)).toFixed(3)}% of the pixels`);
  await page.check('#snh-bones');
  assert.equal((await visible()).bones, true);

  // The volume inside the render surface: flesh and skinning, one point per frame each.
  const plot = (await page.evaluate(() => window.snhReport.plots)).find((p) => p.id === 'render_volume');
  assert.ok(plot, 'a render_volume plot');
  assert.equal(plot.series.length, 2, `the render_volume plot has 2 series: ${JSON.stringify(plot.series)}`);
  assert.equal(plot.points, readSteps(FLESH).length);
  const legendRows = await page.$$eval('.snh-plot[data-plot-id="render_volume"] .u-legend .u-series', (rows) => rows.length);
  assert.equal(legendRows, 3, 'the chart\'s legend: x, flesh, skinning');
  // The USD stage is linked among the settings.
  assert.equal(await page.locator('.snh-meta a[href="flesh.usda"]').count(), existsSync(join(FLESH, 'flesh.usda')) ? 1 : 0);
  await assertNoErrors(page, problems);
  await page.close();

  // The hash picks what is shown first and hides the bones.
  const again = await open(FLESH, '#show=lbs&bones=0');
  assert.deepEqual(await again.page.evaluate(() => window.snhReport.visible()), { flesh: false, lbs: true, difference: false, volume: false, bones: false, fibres: false });
  assert.equal(await again.page.$eval('#snh-bones', (e) => e.checked), false);
  await assertNoErrors(again.page, again.problems);
  await again.page.close();
});

test('render mode frames the surface it shows', { skip: !FRAMING && 'SNH_TEST_FRAMING_DIR is not set', timeout: 120000 }, async () => {
  const report = readReport(FRAMING);
  const last = report.mesh.frames.length - 1;
  // A joint in the middle of the skeleton's list (make-flesh-run.mjs's "middle"; a hand's finger joint).
  const joints = [...new Set(report.render.bones.flatMap((b) => b.split('>')))];
  const joint = joints[Math.floor(joints.length / 2)];
  const cases = [
    ['#render&show=flesh', 1200, 900], ['#render&show=lbs&view=front', 640, 900], ['#render&show=difference&view=top', 1200, 500],
    ['#render&show=flesh,lbs&view=left', 1200, 600], [`#render&show=volume&frame=${last}&fit=animation`, 800, 800],
    [`#render&show=flesh&bones=1&focus=${encodeURIComponent(joint)}`, 900, 900],
  ];
  for (const [hash, width, height] of cases) {
    const page = await browser.newPage({ viewport: { width, height } });
    const problems = [];
    page.on('pageerror', (e) => problems.push(`page error: ${e.message}`));
    await page.goto(pathToFileURL(join(FRAMING, 'index.html')).href + hash);
    await page.waitForFunction(() => document.title.startsWith('snh-render'), null, { timeout: TIMEOUT });
    assert.equal(await page.title(), 'snh-render-ready', `${hash}: ${await page.title()}`);
    // Every point shown projects inside the box the framing fills, which leaves the caption and legend clear;
    // and the shape reaches both sides of that box along one axis (the frame shown fills it; a close-up and
    // the whole animation's framing fill it less).
    const box = await page.evaluate(() => window.snhReport.framingBox());
    const e = await page.evaluate(() => window.snhReport.projectedExtent());
    const eps = 1e-4;
    assert.ok(e.points > 0, hash);
    if (!hash.includes('focus')) {
      assert.ok(e.left >= box.left - eps && e.right <= box.right + eps && e.bottom >= box.bottom - eps && e.top <= box.top + eps,
        `${hash}: the shape spans x ${e.left}..${e.right}, y ${e.bottom}..${e.top}, outside the box ${JSON.stringify(box)}`);
    }
    if (!hash.includes('fit=animation') && !hash.includes('focus')) {
      const touch = (a, b) => Math.abs(a - b) < 2e-3;
      assert.ok((touch(e.left, box.left) && touch(e.right, box.right)) || (touch(e.bottom, box.bottom) && touch(e.top, box.top)),
        `${hash}: the shape x ${e.left}..${e.right}, y ${e.bottom}..${e.top} does not fill the box ${JSON.stringify(box)}`);
    }
    assert.ok(box.top - box.bottom > 1 && box.top <= 0.94 && box.bottom >= -0.94, `${hash}: a margin all round: ${JSON.stringify(box)}`);
    // In the picture: the margins are background, and the shape is there.
    const png = PNG.sync.read(await page.screenshot());
    const bg = BACKGROUND_OF(png);
    const rim = 8; // pixels (the caption and the legend sit 10 to 12 in)
    const edge = (p, x, y) => (x < rim || y < rim || x >= width - rim || y >= height - rim) && differs(p, bg);
    if (!hash.includes('focus')) assert.equal(fraction(png, edge), 0, `${hash}: something is drawn on the picture's rim`);
    assert.ok(fraction(png, (p) => differs(p, bg)) > 0.02, `${hash}: the picture is blank`);
    assert.deepEqual(problems, []);
    await page.close();
  }
});

/** The background colour of a render: the most common one. */
function BACKGROUND_OF(png) {
  const counts = new Map();
  for (let i = 0; i < png.data.length; i += 4) {
    const key = (png.data[i] << 16) | (png.data[i + 1] << 8) | png.data[i + 2];
    counts.set(key, (counts.get(key) || 0) + 1);
  }
  const [key] = [...counts].reduce((a, b) => (b[1] > a[1] ? b : a));
  return [key >> 16, (key >> 8) & 255, key & 255];
}

test('lab report', { skip: !LAB && 'SNH_TEST_LAB_DIR is not set', timeout: 60000 }, async () => {
  const { page, problems } = await open(LAB);
  const rows = await page.$$eval('table.snh-table', (ts) => ts.map((t) => t.querySelectorAll('tbody tr').length));
  assert.ok(rows.length >= 1 && rows.some((n) => n > 0), `tables with rows: ${JSON.stringify(rows)}`);
  const points = await page.$$eval('.snh-plot', (els) => els.map((e) => Number(e.dataset.points)));
  assert.ok(points.length >= 3, `${points.length} plots`);
  assert.ok(points.every((n) => n > 0), `every plot has points: ${JSON.stringify(points)}`);
  await assertNoErrors(page, problems);
  await page.close();
});

test('render-mode PNG', { skip: !RENDER && 'SNH_TEST_RENDER_PNG is not set' }, () => {
  const png = PNG.sync.read(readFileSync(RENDER));
  const size = env.SNH_TEST_RENDER_SIZE;
  assert.ok(/^\d+x\d+$/.test(size || ''), 'SNH_TEST_RENDER_SIZE is WxH');
  assert.equal(`${png.width}x${png.height}`, size);
  // The most common colour is the background; a clear part of the picture's middle third (where the mesh
  // is: the caption and the legend sit in the corners) is something else.
  const counts = new Map();
  for (let i = 0; i < png.data.length; i += 4) {
    const key = (png.data[i] << 16) | (png.data[i + 1] << 8) | png.data[i + 2];
    counts.set(key, (counts.get(key) || 0) + 1);
  }
  const [key] = [...counts].reduce((a, b) => (b[1] > a[1] ? b : a));
  const common = [key >> 16, (key >> 8) & 255, key & 255];
  const middle = [Math.floor(png.width / 3), Math.floor(png.height / 3), Math.floor((2 * png.width) / 3), Math.floor((2 * png.height) / 3)];
  const other = fraction(png, (p) => differs(p, common), middle);
  assert.ok(other > 0.05, `${(100 * other).toFixed(1)}% of the middle third differs from the most common colour ${common}`);
});

test('muscle fibres', { skip: !MUSCLE && 'SNH_TEST_MUSCLE_DIR is not set', timeout: 90000 }, async () => {
  const report = readReport(MUSCLE);
  const muscles = JSON.parse(readFileSync(join(MUSCLE, 'muscles.json'), 'utf8')).regions.filter((r) => r.kind === 'muscle');
  const cells = muscles.reduce((n, m) => n + m.cells.length, 0);
  assert.ok(report.mesh.fibres, 'data.js has the fibres');
  assert.equal(report.mesh.fibres.count, cells, 'one fibre per muscle cell');
  const { page, problems } = await open(MUSCLE);
  const canvasShot = async () => PNG.sync.read(await page.locator('.snh-view canvas').screenshot());
  const changedBetween = (a, b) => fraction(b, (p, x, y) => differs(p, pixel(a, x, y)));
  const visible = () => page.evaluate(() => window.snhReport.visible());
  const hook = (name) => page.evaluate((n) => window.snhReport[n](), name);
  const lengths = (seg) => Array.from({ length: seg.length / 6 }, (_, k) => Math.hypot(seg[6 * k + 3] - seg[6 * k], seg[6 * k + 4] - seg[6 * k + 1], seg[6 * k + 5] - seg[6 * k + 2]));
  assert.equal((await visible()).fibres, true);
  assert.match(await page.$eval('label:has(#snh-fibres)', (e) => e.textContent), new RegExp(`muscle fibres \\(${cells}\\)`));

  // Frame 0: the activation of muscles.json, and the segments at rest.
  const count = report.mesh.frames.length;
  assert.deepEqual(await hook('activation'), muscles.map((m) => m.activation[0]));
  const first = { seg: await hook('fibres'), colors: await hook('fibreColors'), shot: await canvasShot() };
  assert.equal(first.seg.length, 6 * cells);
  await page.$eval('#snh-frame-slider', (el, v) => {
    el.value = String(v);
    el.dispatchEvent(new Event('input', { bubbles: true }));
  }, count - 1);
  await page.waitForFunction((n) => window.snhReport.frame === n, count - 1, { timeout: TIMEOUT });
  const last = { seg: await hook('fibres'), colors: await hook('fibreColors'), shot: await canvasShot() };
  assert.deepEqual(await hook('activation'), muscles.map((m) => m.activation[count - 1]));
  // The muscle contracted along its fibres: each segment (F a through the cell) is shorter.
  const ratio = lengths(last.seg).reduce((a, b) => a + b) / lengths(first.seg).reduce((a, b) => a + b);
  assert.ok(ratio < 0.95, `the fibres' mean length went from 1 to ${ratio.toFixed(3)} of its rest`);
  assert.ok(first.colors.some((c, i) => Math.abs(c - last.colors[i]) > 0.05), 'the colours follow the activation');
  assert.ok(changedBetween(first.shot, last.shot) > 0.002, 'the last frame changes the picture');

  // The switch hides them, and the picture shows it.
  await page.uncheck('#snh-fibres');
  assert.equal((await visible()).fibres, false);
  const hidden = await canvasShot();
  assert.ok(changedBetween(last.shot, hidden) > 0.0005, `hiding the fibres changes ${(100 * changedBetween(last.shot, hidden)).toFixed(3)}% of the pixels`);
  await page.check('#snh-fibres');
  assert.equal((await visible()).fibres, true);
  await assertNoErrors(page, problems);
  await page.close();
  // The hash turns them off from the start.
  const off = await open(MUSCLE, '#fibres=0');
  assert.equal((await off.page.evaluate(() => window.snhReport.visible())).fibres, false);
  assert.equal(await off.page.$eval('#snh-fibres', (e) => e.checked), false);
  await assertNoErrors(off.page, off.problems);
  await off.page.close();
});
