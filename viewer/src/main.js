// Entry point of the report page: reads window.SNH_REPORT (report/data.js) and builds the page,
// or with #render... only the 3D view for a screenshot. Test hooks live in window.snhReport.
import uplotCss from 'uplot/dist/uPlot.min.css';
import css from './style.css';
import { FrameStore } from './frames.js';
import { header, tablesSection } from './page.js';
import { legendElement, Player } from './player.js';
import { plotsSection } from './plots.js';
import { el, message } from './util.js';
import { decisivePoints, viewBasis } from './camera.js';
import { BACKGROUND, FOV, MeshView } from './view3d.js';

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
 * run also show=flesh|lbs|difference|volume (render mode: up to four, comma-separated, side by side) and
 * bones=0|1 (on in the report, off in render mode); a run with muscles fibres=0. The framing: view= (camera.js
 * VIEWS), fit=frame|animation, focus=JOINT; and the difference's colours range=run|frame|LO:HI (mm).
 */
function hashSettings() {
  const h = location.hash.replace(/^#/, '');
  const q = new URLSearchParams(h);
  const flag = (k, dflt) => (q.has(k) ? !['0', 'false', 'no', 'off'].includes(q.get(k)) : dflt);
  const render = h.startsWith('render');
  return {
    render,
    frame: q.get('frame'),
    field: q.get('field'),
    wireframe: flag('wireframe', false),
    pins: flag('pins', true),
    show: q.get('show'),
    bones: flag('bones', !render),
    fibres: flag('fibres', true),
    view: q.get('view') || 'three-quarter',
    fit: q.get('fit') || (render ? 'frame' : 'animation'),
    focus: q.get('focus') || '',
    range: q.get('range') || 'run',
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

/** What a flesh run shows first: the hash's choice, else the flesh (the volume for other runs); a list. */
function showFromHash(value, render) {
  if (!render) return null;
  if (value === null || value === '') return ['flesh'];
  const list = value.split(',');
  for (const v of list) if (!['flesh', 'lbs', 'difference', 'volume'].includes(v)) throw new Error(`no "${v}" to show (flesh, lbs, difference or volume)`);
  if (list.length > 4) throw new Error(`show=${value}: at most four side by side`);
  return list;
}

/** The part of the picture the framing fills (NDC): below the caption and the panels' labels, above the legend. */
function framingBox(box, parts) {
  const height = Math.max(box.clientHeight, 1);
  const view = box.getBoundingClientRect();
  let top = 0;
  let bottom = height;
  for (const e of [parts.caption, ...(parts.labels || [])]) {
    if (e && !e.hidden) top = Math.max(top, e.getBoundingClientRect().bottom - view.top);
  }
  if (parts.legend && !parts.legend.hidden) bottom = Math.min(bottom, parts.legend.getBoundingClientRect().top - view.top);
  const margin = 0.05 * height;
  const ndc = (y) => 1 - (2 * y) / height;
  const box2 = { left: -0.94, right: 0.94, top: Math.min(0.94, ndc(top + margin)), bottom: Math.max(-0.94, ndc(bottom - margin)) };
  // A shape in a narrow strip would be tiny: give the overlays' room back where too little is left.
  if (box2.top - box2.bottom < 0.8) { box2.top = 0.94; box2.bottom = -0.94; }
  return box2;
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
    const panels = showFromHash(s.show, render);
    const view = new MeshView(box, mesh, render);
    view.setWireframe(s.wireframe);
    view.setPinsVisible(s.pins);
    view.setBonesVisible(s.bones);
    view.setFibresVisible(s.fibres);
    const store = new FrameStore(mesh, render);
    const player = new Player({ mesh, store, view, hooks, parts, onError: record });
    const field = s.field || mesh.default_field || (mesh.fields[0] && mesh.fields[0].name);
    if (field) await player.setField(field);
    if (panels) {
      player.setPanels(panels);
      if (panels.length > 1) {
        parts.labels = panels.map((p, i) => {
          const label = el('div', { class: 'snh-panel-label' }, view.showLabel(p));
          label.style.left = `${((i + 0.5) * 100) / panels.length}%`;
          box.append(label);
          return label;
        });
      }
    }
    // The difference's colour range: the run's, the frame's, or LO:HI millimetres.
    if (render && s.range !== 'run') {
      const m = /^(-?[\d.e+-]+):(-?[\d.e+-]+)$/.exec(s.range);
      view.setDistanceRange(m ? [Number(m[1]), Number(m[2])] : s.range);
      player.updateLegend();
    }
    // The framing: the frame's own shape, or the whole animation's (the decisive points of every frame).
    view.framing.view = s.view;
    view.framing.fit = s.fit;
    if (s.fit !== 'frame' && s.fit !== 'animation') throw new Error(`fit=${s.fit}: expected frame or animation`);
    const framingFor = () => ({ box: framingBox(box, parts) });
    if (s.fit === 'animation' && !s.focus) {
      const { w, h } = view.panelSize();
      const f = framingFor();
      const basis = viewBasis(s.view, view.framing.up);
      const points = [];
      for (let i = 0; i < store.count; i++) {
        await player.setFrame(i);
        points.push(...decisivePoints(view.shownPoints(), basis, FOV, w / h, f.box));
      }
      f.points = points;
      view.setFraming(f);
    }
    await player.setFrame(frame);
    view.setFraming({ ...framingFor(), focus: s.focus });
    player.draw(await store.get(frame)); // the framing as it stands for this frame
    hooks.setFrame = async (i) => {
      await player.setFrame(i);
      await new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)));
    };
    hooks.framingBox = () => view.framing.box;
    hooks.projectedExtent = () => view.projectedExtent();
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
      const shows = pick(() => showFromHash(s.show, render));
      const show = shows ? shows[0] : render ? 'flesh' : null; // one at a time here
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
