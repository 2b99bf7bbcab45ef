// Entry point of the report page: reads window.SNH_REPORT (report/data.js) and builds the page,
// or with #render... only the 3D view for a screenshot. Test hooks live in window.snhReport.
import uplotCss from 'uplot/dist/uPlot.min.css';
import css from './style.css';
import { FrameStore } from './frames.js';
import { header, tablesSection } from './page.js';
import { legendElement, Player } from './player.js';
import { plotsSection } from './plots.js';
import { el, message } from './util.js';
import { BACKGROUND, MeshView } from './view3d.js';

const noMesh = () => Promise.reject(new Error('the report has no mesh'));
const hooks = {
  ready: false, errors: [], frameCount: 0, frame: -1, setFrame: noMesh, field: null, setField: noMesh,
  legend: null, plots: [], background: BACKGROUND.slice(), show: null, setShow: noMesh,
};
window.snhReport = hooks;

function record(e) {
  const m = message(e);
  hooks.errors.push(m);
  console.error(`snh report: ${m}`);
}
window.addEventListener('error', (e) => record(e.error || e.message));
window.addEventListener('unhandledrejection', (e) => record(e.reason));

/**
 * Settings from the location hash: #render&frame=5&field=psi&wireframe=1, or #frame=N&field=NAME; a flesh
 * run also show=flesh|lbs|volume and bones=0; a run with muscles fibres=0.
 */
function hashSettings() {
  const h = location.hash.replace(/^#/, '');
  const q = new URLSearchParams(h);
  const flag = (k, dflt) => (q.has(k) ? !['0', 'false', 'no', 'off'].includes(q.get(k)) : dflt);
  return {
    render: h.startsWith('render'),
    frame: q.get('frame'),
    field: q.get('field'),
    wireframe: flag('wireframe', false),
    pins: flag('pins', true),
    show: q.get('show'),
    bones: flag('bones', true),
    fibres: flag('fibres', true),
  };
}

/** The index of a frame named in the hash ("3", or "last"); null when none is named. */
function frameFromHash(value, count) {
  if (value === null || value === '') return null;
  const i = value === 'last' ? count - 1 : Number(value);
  if (!Number.isInteger(i) || i < 0 || i >= count) throw new Error(`no frame "${value}" (the report has frames 0 to ${count - 1})`);
  return i;
}

/** The 3D view's box with its overlays (legend, message, and in render mode a caption). */
function viewBox(data, withCaption) {
  const parts = {
    legend: legendElement(),
    message: el('div', { class: 'snh-view-message', hidden: true }),
    caption: withCaption ? el('div', { class: 'snh-caption' }, el('div', { class: 'snh-caption-title' }, data.title || ''), el('div', {})) : null,
  };
  const box = el('div', { class: 'snh-view' }, parts.caption, parts.legend, parts.message);
  return { box, parts };
}

function meshInfo(m, r) {
  const s = m.surface || {};
  const render = r ? ` — render surface: ${r.vertex_count} vertices, ${r.triangle_count} triangles` +
    (Array.isArray(r.bones) ? ` · ${r.bones.length} bones` : '') : '';
  return `${m.element || ''} mesh · ${m.vertex_count} vertices · ${m.cell_count} cells · ${m.pinned_count} pinned` +
    ` — surface: ${s.vertex_count} vertices, ${s.triangle_count} triangles${render} · ${m.frames.length} frames`;
}

/** What a flesh run shows first: the hash's choice, else the flesh (the volume for other runs). */
function showFromHash(value, render) {
  if (!render) return null;
  if (value === null || value === '') return 'flesh';
  if (!['flesh', 'lbs', 'volume'].includes(value)) throw new Error(`no "${value}" to show (flesh, lbs or volume)`);
  return value;
}

async function renderMode(root, data, s) {
  document.documentElement.classList.add('snh-render-mode');
  const { box, parts } = viewBox(data, true);
  root.append(box);
  try {
    const mesh = data.mesh;
    if (!mesh) throw new Error('the report has no mesh (the run wrote no frames)');
    if (!mesh.frames || !mesh.frames.length) throw new Error('the report has no frames');
    const frame = frameFromHash(s.frame, mesh.frames.length) ?? 0;
    const render = data.render || null;
    const show = showFromHash(s.show, render);
    const view = new MeshView(box, mesh, render);
    view.setWireframe(s.wireframe);
    view.setPinsVisible(s.pins);
    view.setBonesVisible(s.bones);
    view.setFibresVisible(s.fibres);
    const player = new Player({ mesh, store: new FrameStore(mesh, render), view, hooks, parts, onError: record });
    const field = s.field || mesh.default_field || (mesh.fields[0] && mesh.fields[0].name);
    if (field) await player.setField(field);
    if (show) player.setShow(show);
    await player.setFrame(frame);
    await new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)));
    hooks.ready = true;
    document.title = 'snh-render-ready';
  } catch (e) {
    record(e);
    parts.message.textContent = message(e);
    parts.message.hidden = false;
    document.title = `snh-render-error: ${message(e)}`;
  }
}

/** The mesh section; returns {section, start()} where start() shows the first frame. */
function meshSection(data, s) {
  const mesh = data.mesh;
  const { box, parts } = viewBox(data, false);
  const section = el('section', { class: 'snh-section snh-viewer' },
    el('div', { class: 'snh-section-head' }, el('h2', {}, 'Deformation'),
      el('p', { class: 'snh-mesh-info' }, meshInfo(mesh, data.render))),
    box);
  const fail = (e) => {
    record(e);
    parts.message.textContent = message(e);
    parts.message.hidden = false;
  };
  async function start() {
    try {
      if (!mesh.frames || !mesh.frames.length) throw new Error('the report has no frames');
      const render = data.render || null;
      const store = new FrameStore(mesh, render);
      const view = new MeshView(box, mesh, render);
      const player = new Player({ mesh, store, view, hooks, parts, onError: record });
      // A bad frame or field in the hash is reported, and the default used.
      const bad = [];
      const pick = (get) => { try { return get(); } catch (e) { bad.push(message(e)); return null; } };
      const frame = pick(() => frameFromHash(s.frame, store.count)) ?? 0;
      const field = (s.field && pick(() => player.fieldByName(s.field).name)) ||
        mesh.default_field || (mesh.fields[0] && mesh.fields[0].name);
      const show = pick(() => showFromHash(s.show, render)) || (render ? 'flesh' : null);
      view.setWireframe(s.wireframe);
      view.setPinsVisible(s.pins);
      view.setBonesVisible(s.bones);
      view.setFibresVisible(s.fibres);
      section.append(player.buildControls({ frame, wireframe: s.wireframe, pins: s.pins, bones: s.bones, fibres: s.fibres }));
      if (field) await player.setField(field);
      if (show) player.setShow(show);
      try {
        await player.setFrame(frame);
      } catch (e) {
        record(e); // shown in the view by the player
      }
      if (bad.length) fail(bad.join('; '));
      store.prefetch(frame, record); // the rest in the background, one by one
    } catch (e) {
      fail(e);
    }
  }
  return { section, start };
}

async function main() {
  const s = hashSettings();
  let root = document.getElementById('snh-report');
  if (!root) root = document.body.appendChild(el('div', { id: 'snh-report' }));
  document.head.append(el('style', {}, uplotCss), el('style', {}, css));
  const data = window.SNH_REPORT;
  if (!data || typeof data !== 'object') {
    const m = 'report/data.js did not load, or did not set window.SNH_REPORT';
    record(m);
    root.append(el('p', { class: 'snh-error' }, m));
    if (s.render) document.title = `snh-render-error: ${m}`;
    return;
  }
  if (s.render) return renderMode(root, data, s);

  root.classList.add('snh-page');
  root.append(header(data));
  const tables = Array.isArray(data.tables) && data.tables.length ? tablesSection(data.tables) : null;
  const plots = plotsSection(data.plots, hooks, record);
  const mesh = data.mesh ? meshSection(data, s) : null;
  if (!data.mesh && data.kind !== 'lab') {
    root.append(el('p', { class: 'snh-note' }, 'This run wrote no frames, so there is no 3D view.'));
  }
  // With a mesh: view, plots, tables; a lab (no mesh) leads with its tables.
  const order = mesh ? [mesh.section, plots.section, tables] : [tables, plots.section];
  for (const part of order) if (part) root.append(part);
  plots.draw();
  if (mesh) await mesh.start();
  hooks.ready = true;
}

main().catch(record);
