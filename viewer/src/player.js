// Playback of the mesh frames: the controls (play, slider, field, wireframe, pins; for a flesh run what is
// shown and the bones), the keys, the legend, and the frame/field state that the test hooks expose.
import { fieldColors } from './colormap.js';
import { el, fmt4, fmtTime, message } from './util.js';
import { SHOWS } from './view3d.js';

const FRAME_MS = 100; // ~10 frames per second
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

export class Player {
  /**
   * mesh: the report's mesh; store: FrameStore; view: MeshView; hooks: window.snhReport;
   * parts: {legend, caption, message} elements in the view; onError(e) records an error.
   */
  constructor({ mesh, store, view, hooks, parts, onError }) {
    Object.assign(this, { mesh, store, view, hooks, parts, onError });
    this.frame = -1; // the frame drawn
    this.target = -1; // the frame last asked for
    this.field = null;
    this.request = 0; // the latest setFrame/setField call; older ones do not draw
    this.playing = null; // a token while playing
    this.ui = null;
    hooks.frameCount = store.count;
    hooks.setFrame = (i) => this.setFrame(i);
    hooks.setField = (name) => this.setField(name);
    hooks.show = view.show;
    hooks.setShow = (what) => this.setShow(what);
    hooks.setBones = (on) => this.setBonesVisible(on);
    hooks.visible = () => view.visibility();
    hooks.bones = () => Array.from(view.bonePositions || []);
    hooks.setFibres = (on) => this.setFibresVisible(on);
    hooks.fibres = () => Array.from(view.fibrePositions || []);
    hooks.fibreColors = () => Array.from(view.fibreColors || []);
    hooks.activation = () => (view.fibreActivation || []).slice();
  }

  fieldByName(name) {
    const f = this.mesh.fields.find((x) => x.name === name);
    if (!f) throw new Error(`unknown field "${name}" (the report has ${this.mesh.fields.map((x) => x.name).join(', ') || 'none'})`);
    return f;
  }

  /** Shows frame i with the current field; resolves once it is drawn. */
  async setFrame(i) {
    const req = ++this.request;
    this.target = i;
    if (this.ui) this.ui.slider.value = String(i);
    let data;
    try {
      data = await this.store.get(i);
    } catch (e) {
      if (req === this.request) this.showMessage(message(e));
      throw e;
    }
    if (req !== this.request) return; // a later request wins
    this.frame = i;
    this.draw(data);
    this.hooks.frame = i;
  }

  /** Colours the surface by the named field; resolves once it is drawn. */
  async setField(name) {
    const field = this.fieldByName(name);
    this.field = field;
    this.colors = fieldColors(field);
    this.hooks.field = field.name;
    this.updateLegend();
    if (this.ui) this.ui.field.value = field.name;
    if (this.target >= 0) await this.setFrame(this.target);
  }

  draw(data) {
    this.view.setPositions(data.x);
    if (this.field) this.view.setColors(this.field, data.fields[this.field.name], this.colors);
    if (data.render) this.view.setRender(data.render);
    if (data.fibres) this.view.setFibres(data.fibres);
    if (this.view.distanceRange === 'frame') this.updateLegend(); // the frame's own range
    this.view.refit();
    this.view.render();
    this.showMessage('');
    const label = this.frameLabel(this.frame);
    if (this.ui) {
      this.ui.slider.value = String(this.frame);
      this.ui.label.textContent = label;
    }
    this.updateCaption();
  }

  /** Render mode's caption: the frame, and for a flesh run what is shown. */
  updateCaption() {
    if (!this.parts.caption || this.frame < 0) return;
    const shown = this.view.skins && this.view.panels.length === 1 ? ` · ${this.view.showLabel(this.view.show)}` : '';
    this.parts.caption.lastChild.textContent = this.frameLabel(this.frame) + shown;
  }

  /** A flesh run: shows 'flesh' or 'lbs' (the render surface, simulated or skinned) or 'volume' (coloured by the field). */
  setShow(what) {
    this.setPanels([what]);
  }

  /** Render mode: one to four of those side by side. */
  setPanels(list) {
    this.view.setPanels(list);
    const what = list[0];
    this.hooks.show = list.join(',');
    if (this.ui) {
      for (const b of this.ui.shows) b.setAttribute('aria-pressed', b.dataset.show === what ? 'true' : 'false');
      this.ui.field.disabled = what !== 'volume';
    }
    this.updateLegend();
    this.updateCaption();
    this.view.render();
  }

  setBonesVisible(on) {
    this.view.setBonesVisible(on);
    if (this.ui && this.ui.bones) this.ui.bones.checked = !!on;
    this.view.render();
  }

  setFibresVisible(on) {
    this.view.setFibresVisible(on);
    if (this.ui && this.ui.fibres) this.ui.fibres.checked = !!on;
    this.view.render();
  }

  frameLabel(i) {
    const f = this.mesh.frames[i];
    const t = f.time === undefined || f.time === null ? '' : ` · t = ${fmtTime(f.time)}`;
    return `${f.label || `frame ${i}`}${t}`;
  }

  showMessage(text) {
    this.parts.message.textContent = text;
    this.parts.message.hidden = !text;
  }

  /** The legend of the colours shown: the volume's field, or the flesh's distance from the skinned surface. */
  updateLegend() {
    const panels = this.view.panels || [this.view.show];
    const distance = panels.includes('difference') && !panels.includes('volume');
    const f = distance ? this.view.distanceField : this.field;
    const colors = distance ? this.view.distanceColors : this.colors;
    const lg = this.parts.legend;
    lg.hidden = !f || !(distance || panels.includes('volume')); // the flesh and the LBS surface have no colours
    if (!f) return;
    this.hooks.legend = { field: f.name, min: f.min, max: f.max };
    lg.dataset.field = f.name;
    lg.dataset.min = String(f.min);
    lg.dataset.max = String(f.max);
    lg.querySelector('.snh-legend-label').textContent = f.label || f.name;
    lg.querySelector('.snh-legend-bar').style.background = colors.gradient();
    lg.querySelector('.snh-legend-min').textContent = fmt4(f.min);
    lg.querySelector('.snh-legend-max').textContent = fmt4(f.max);
    // The diverging map's centre (white), when it lies inside min..max.
    const mark = lg.querySelector('.snh-legend-center');
    const c = f.center;
    const inside = colors.name === 'diverging' && Number.isFinite(c) && c > f.min && c < f.max;
    mark.hidden = !inside;
    if (inside) {
      const at = (c - f.min) / (f.max - f.min);
      mark.style.left = `${100 * at}%`;
      // Its number would run into the min's or max's near an end: the tick alone says where it is.
      mark.textContent = at > 0.15 && at < 0.85 ? fmt4(c) : '';
    }
  }

  async play() {
    if (this.playing) return;
    const token = (this.playing = {});
    this.updatePlayButton();
    const last = this.store.count - 1;
    try {
      if (this.frame >= last) {
        await this.setFrame(0); // play again from the start
        await sleep(FRAME_MS);
      }
      while (this.playing === token && this.frame < last) {
        const t0 = performance.now();
        await this.setFrame(this.frame + 1); // waits for the frame's file
        await sleep(Math.max(0, FRAME_MS - (performance.now() - t0)));
      }
    } catch (e) {
      this.onError(e);
    }
    if (this.playing === token) this.pause();
  }

  pause() {
    this.playing = null;
    this.updatePlayButton();
  }

  toggle() {
    if (this.playing) this.pause();
    else this.play();
  }

  updatePlayButton() {
    if (!this.ui) return;
    this.ui.play.textContent = this.playing ? '❚❚ Pause' : '▶ Play';
    this.ui.play.setAttribute('aria-pressed', this.playing ? 'true' : 'false');
  }

  /** Steps to frame i from a control or a key (errors are shown and recorded, not thrown). */
  go(i) {
    const j = Math.min(Math.max(i, 0), this.store.count - 1);
    this.setFrame(j).catch((e) => this.onError(e));
  }

  /** The controls under the view, for the normal page. */
  buildControls(initial) {
    const last = this.store.count - 1;
    const ui = {};
    ui.prev = el('button', { type: 'button', class: 'snh-btn', id: 'snh-prev', title: 'previous frame (←)', onclick: () => this.go(this.target - 1) }, '◀');
    ui.play = el('button', { type: 'button', class: 'snh-btn snh-btn-play', id: 'snh-play', title: 'play / pause (space)', onclick: () => this.toggle() });
    ui.next = el('button', { type: 'button', class: 'snh-btn', id: 'snh-next', title: 'next frame (→)', onclick: () => this.go(this.target + 1) }, '▶');
    ui.slider = el('input', { type: 'range', id: 'snh-frame-slider', min: 0, max: last, step: 1, value: initial.frame, 'aria-label': 'frame' });
    ui.slider.addEventListener('input', () => this.go(Number(ui.slider.value)));
    ui.label = el('span', { id: 'snh-frame-label', class: 'snh-frame-label' }, '…');
    ui.field = el('select', { id: 'snh-field', 'aria-label': 'field' },
      this.mesh.fields.map((f) => el('option', { value: f.name }, f.label || f.name)));
    ui.field.addEventListener('change', () => this.setField(ui.field.value).catch((e) => this.onError(e)));
    ui.wire = el('input', { type: 'checkbox', id: 'snh-wireframe', checked: initial.wireframe });
    ui.wire.addEventListener('change', () => { this.view.setWireframe(ui.wire.checked); this.view.render(); });
    ui.pins = el('input', { type: 'checkbox', id: 'snh-pins', checked: initial.pins, disabled: !this.view.pinIndex.length });
    ui.pins.addEventListener('change', () => { this.view.setPinsVisible(ui.pins.checked); this.view.render(); });
    // A flesh run: what is shown (a switch), and its bones.
    const flesh = !!this.view.skins;
    ui.shows = flesh
      ? SHOWS.filter(([key]) => key === 'volume' || this.view.skins[key]).map(([key]) => el('button', {
        type: 'button', class: 'snh-seg', id: `snh-show-${key}`, 'data-show': key,
        'aria-pressed': key === this.view.show ? 'true' : 'false',
        onclick: () => { try { this.setShow(key); } catch (e) { this.onError(e); } },
      }, this.view.showLabel(key)))
      : [];
    const boneCount = flesh ? this.view.boneNames.length : 0;
    ui.bones = flesh ? el('input', { type: 'checkbox', id: 'snh-bones', checked: initial.bones, disabled: !boneCount }) : null;
    if (ui.bones) ui.bones.addEventListener('change', () => this.setBonesVisible(ui.bones.checked));
    // A run with muscles: their fibres.
    const fibreCount = this.view.fibreMuscle ? this.view.fibreMuscle.length : 0;
    ui.fibres = fibreCount ? el('input', { type: 'checkbox', id: 'snh-fibres', checked: initial.fibres !== false }) : null;
    if (ui.fibres) ui.fibres.addEventListener('change', () => this.setFibresVisible(ui.fibres.checked));
    ui.field.disabled = this.view.show !== 'volume';
    this.ui = ui;
    this.updatePlayButton();
    document.addEventListener('keydown', (e) => this.onKey(e));
    return el('div', { class: 'snh-controls' },
      el('div', { class: 'snh-controls-row' }, ui.prev, ui.play, ui.next, ui.slider, ui.label),
      flesh
        ? el('div', { class: 'snh-controls-row' },
          el('div', { class: 'snh-control snh-show', role: 'group', 'aria-label': 'surface shown' },
            el('span', {}, 'Show'), el('span', { class: 'snh-segs' }, ui.shows)),
          el('label', { class: 'snh-control' }, ui.bones, ` bones (${boneCount})`))
        : null,
      el('div', { class: 'snh-controls-row' },
        el('label', { class: 'snh-control' }, 'Colour by ', ui.field),
        el('label', { class: 'snh-control' }, ui.wire, ' wireframe'),
        el('label', { class: 'snh-control' }, ui.pins, ` pinned vertices (${this.view.pinIndex.length})`),
        ui.fibres ? el('label', { class: 'snh-control' }, ui.fibres, ` muscle fibres (${fibreCount}), coloured by activation`) : null));
  }

  onKey(e) {
    if (e.ctrlKey || e.metaKey || e.altKey) return;
    // Only while the 3D view is on screen: elsewhere the keys scroll the page as usual.
    const box = this.view.container.getBoundingClientRect();
    if (box.bottom <= 0 || box.top >= window.innerHeight) return;
    const t = e.target;
    const onSlider = t === this.ui.slider;
    // Checkboxes (wireframe, pins) do nothing with these keys, so they do not keep them from the player.
    const inInput = !onSlider && t instanceof Element && t.matches('input:not([type=checkbox]), select, textarea, [contenteditable]');
    if (inInput) return;
    if (e.key === ' ') {
      if (t instanceof Element && t.matches('button, a, input[type=checkbox]')) return; // they act on space themselves
      e.preventDefault();
      this.toggle();
      return;
    }
    if (onSlider) return; // the slider steps on arrows, Home and End by itself
    const step = { ArrowLeft: this.target - 1, ArrowRight: this.target + 1, Home: 0, End: this.store.count - 1 }[e.key];
    if (step === undefined) return;
    e.preventDefault();
    this.go(step);
  }
}

/** The legend element (filled by Player.updateLegend). */
export function legendElement() {
  return el('div', { id: 'snh-legend', class: 'snh-legend', hidden: true },
    el('div', { class: 'snh-legend-label' }),
    el('div', { class: 'snh-legend-scale' },
      el('div', { class: 'snh-legend-bar' }),
      el('span', { class: 'snh-legend-center', hidden: true })),
    el('div', { class: 'snh-legend-numbers' },
      el('span', { class: 'snh-legend-min' }), el('span', { class: 'snh-legend-max' })));
}
