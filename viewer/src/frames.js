// Lazy loading of the frame files (report/frames/NNN.js). They are classic scripts that call
// window.snhReportFrame(index, {...}), so they load from file:// where fetch() does not.
import { decodeBase64, message } from './util.js';

const LOAD_TIMEOUT_MS = 60000;

export class FrameStore {
  /** mesh: the report's mesh; render: a flesh run's render surface (data.render), whose frames it also decodes. */
  constructor(mesh, render = null) {
    this.mesh = mesh;
    this.render = render;
    this.loaded = new Map(); // index -> Promise of the decoded frame (kept once loaded)
    this.waiting = new Map(); // index -> {resolve, reject} while its script loads
    window.snhReportFrame = (index, raw) => this.receive(index, raw);
  }

  get count() {
    return this.mesh.frames.length;
  }

  /**
   * The decoded frame {x: Float32Array, fields: {name: Float32Array}, render: {flesh, lbs, bones} (a flesh
   * run: Float32Arrays; bones only with bones) or null, fibres: {segments, activation} (a run with muscles) or
   * null}; loads its file once.
   */
  get(index) {
    if (!Number.isInteger(index) || index < 0 || index >= this.count) {
      return Promise.reject(new Error(`no frame ${index} (the report has ${this.count})`));
    }
    if (!this.loaded.has(index)) this.loaded.set(index, this.load(index));
    return this.loaded.get(index);
  }

  /** Loads every frame not yet loaded, one after another, starting after `first`. */
  async prefetch(first, onError) {
    for (let k = 1; k < this.count; k++) {
      const i = (first + k) % this.count;
      if (this.loaded.has(i)) continue;
      try {
        await this.get(i);
      } catch (e) {
        onError(e);
      }
    }
  }

  load(index) {
    const src = this.mesh.frames[index].src;
    return new Promise((resolve, reject) => {
      const script = document.createElement('script');
      const done = () => {
        clearTimeout(timer);
        script.remove();
        this.waiting.delete(index);
      };
      const fail = (why) => {
        done();
        reject(new Error(`frame ${index} (${src}): ${why}`));
      };
      const timer = setTimeout(() => fail('its file did not load in time'), LOAD_TIMEOUT_MS);
      this.waiting.set(index, {
        resolve: (f) => { done(); resolve(f); },
        reject: (e) => fail(message(e)),
      });
      script.onerror = () => fail('its file could not be loaded');
      // A script runs before its load event, so by then it must have delivered the frame.
      script.onload = () => this.waiting.has(index) && fail('its file did not deliver this frame');
      script.src = src;
      document.head.append(script);
    });
  }

  receive(index, raw) {
    const w = this.waiting.get(index);
    if (!w) return; // a frame nobody asked for (or delivered twice): ignore
    try {
      w.resolve(this.decode(raw));
    } catch (e) {
      w.reject(e);
    }
  }

  decode(raw) {
    const s = this.mesh.surface;
    const counts = { vertex: s.vertex_count, cell: s.cell_count };
    const x = decodeBase64(raw && raw.x, Float32Array, 'positions "x"');
    if (x.length !== 3 * s.vertex_count) throw new Error(`"x" has ${x.length} values, expected ${3 * s.vertex_count}`);
    const fields = {};
    for (const f of this.mesh.fields) {
      const v = decodeBase64(raw[f.name], Float32Array, `field "${f.name}"`);
      const n = counts[f.per];
      if (v.length !== n) throw new Error(`field "${f.name}" has ${v.length} values, expected ${n} (one per ${f.per})`);
      fields[f.name] = v;
    }
    return { x, fields, render: this.render ? this.decodeRender(raw.render) : null, fibres: this.mesh.fibres ? this.decodeFibres(raw.fibres) : null };
  }

  /** A run with muscles: the fibres' segments (6 per fibre) and each muscle's activation at the frame. */
  decodeFibres(raw) {
    const f = this.mesh.fibres;
    if (!raw || typeof raw !== 'object') throw new Error('no "fibres" in the frame, though the report has muscles');
    const segments = decodeBase64(raw.segments, Float32Array, 'fibre segments');
    if (segments.length !== 6 * f.count) throw new Error(`"fibres" has ${segments.length} values, expected ${6 * f.count} (6 per fibre)`);
    const activation = raw.activation;
    if (!Array.isArray(activation) || activation.length !== f.muscles.length || activation.some((a) => typeof a !== 'number')) {
      throw new Error(`the fibres' "activation" must hold one number per muscle (${f.muscles.length})`);
    }
    return { segments, activation };
  }

  decodeRender(raw) {
    const r = this.render;
    if (!raw || typeof raw !== 'object') throw new Error('no render surface "render", though the report has one');
    const out = {};
    for (const name of ['flesh', 'lbs']) {
      out[name] = decodeBase64(raw[name], Float32Array, `render surface "${name}"`);
      if (out[name].length !== 3 * r.vertex_count) {
        throw new Error(`render surface "${name}" has ${out[name].length} values, expected ${3 * r.vertex_count}`);
      }
    }
    if (r.distance) {
      out.distance = decodeBase64(raw.distance, Float32Array, 'render surface "distance"');
      if (out.distance.length !== r.vertex_count) {
        throw new Error(`render surface "distance" has ${out.distance.length} values, expected ${r.vertex_count} (one per vertex)`);
      }
    }
    if (Array.isArray(r.bones)) {
      out.bones = decodeBase64(raw.bones, Float32Array, 'bones');
      if (out.bones.length !== 6 * r.bones.length) {
        throw new Error(`"bones" has ${out.bones.length} values, expected ${6 * r.bones.length} (6 per bone)`);
      }
    }
    return out;
  }
}
