// The 3D view: the run's boundary surface, coloured by a field, with orbit controls.
// The geometry is non-indexed (3 vertices per triangle) so that cell colours and normals stay flat.
// A flesh run adds its render surface (smooth, indexed), simulated or posed by linear blend skinning, and
// its bones as lines drawn over everything: one of flesh, lbs or the volume is shown at a time. A run with
// muscles draws their fibres over everything too, coloured by their muscle's activation.
import {
  AmbientLight, BufferAttribute, BufferGeometry, Color, DirectionalLight, DoubleSide, HemisphereLight, LineBasicMaterial,
  LineSegments, Mesh, MeshBasicMaterial, MeshLambertMaterial, MeshStandardMaterial, Object3D, PerspectiveCamera, Points,
  PointsMaterial, Scene, Vector3, WebGLRenderer,
} from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import { LineMaterial } from 'three/examples/jsm/lines/LineMaterial.js';
import { LineSegments2 } from 'three/examples/jsm/lines/LineSegments2.js';
import { LineSegmentsGeometry } from 'three/examples/jsm/lines/LineSegmentsGeometry.js';
import { fitView, jointAt, modelAxes, pointsNear, viewBasis } from './camera.js';
import { fieldColors } from './colormap.js';
import { decodeBase64 } from './util.js';

/** The background colour (sRGB 0-255); tests compare pixels against it. */
export const BACKGROUND = [224, 228, 233];
export const FOV = 30; // degrees, vertical
/** How much of the picture the framing leaves round the shape, in NDC (1 = the edge). */
const FRAME_MARGIN = 0.92;
/** A close-up on a joint takes in the surface within this many times its longest bone. */
const FOCUS_REACH = 0.9;
const CREASE_COS = Math.cos((35 * Math.PI) / 180); // feature edges: where the surface bends more
/** What a flesh run's view can show, with the labels of its switch. */
export const SHOWS = [['flesh', 'flesh'], ['lbs', 'skinning (LBS)'], ['difference', 'flesh − LBS distance'], ['volume', 'volume']];
const SKIN_SRGB = { flesh: [226, 168, 142], lbs: [146, 170, 206] }; // warm for the flesh, cool for the comparison
const BONE_COLOR = 0x16233f;
const BONE_WIDTH = 3; // CSS pixels
const FIBRE_WIDTH = 2; // CSS pixels
/** A fibre's colour: its muscle's activation, 0 to 1, on the sequential map. */
const ACTIVATION_COLORS = fieldColors({ colormap: 'sequential', min: 0, max: 1 });

/** The surface's edges as [a, b, t1, t2] (vertices, triangles; t2 = -1 on an open edge). */
function surfaceEdges(tris, n) {
  const seen = new Map();
  const edges = [];
  for (let t = 0; t < tris.length / 3; t++) {
    for (let k = 0; k < 3; k++) {
      const a = tris[3 * t + k];
      const b = tris[3 * t + ((k + 1) % 3)];
      const key = Math.min(a, b) * n + Math.max(a, b);
      const e = seen.get(key);
      if (e === undefined) {
        seen.set(key, edges.length);
        edges.push([a, b, t, -1]);
      } else edges[e][3] = t;
    }
  }
  return edges;
}

export class MeshView {
  /** mesh: the report's mesh; render: its flesh run's render surface (data.render), or null. */
  constructor(container, mesh, render = null) {
    const s = mesh.surface;
    const n = s.vertex_count;
    this.tris = decodeBase64(s.triangles, Uint32Array, 'surface triangles');
    this.triCells = decodeBase64(s.triangle_cells, Uint32Array, 'surface triangle_cells');
    const pinned = decodeBase64(s.pinned, Uint8Array, 'surface pinned');
    const rest = decodeBase64(s.rest, Float32Array, 'surface rest');
    const F = this.tris.length / 3;
    if (F !== s.triangle_count || this.triCells.length !== F) throw new Error('surface: triangle counts do not match');
    if (rest.length !== 3 * n || pinned.length !== n) throw new Error('surface: vertex counts do not match');
    if (this.tris.some((v) => v >= n)) throw new Error('surface: a triangle refers to a vertex past the surface');
    if (this.triCells.some((c) => c >= s.cell_count)) throw new Error('surface: a triangle refers to a cell past the surface');
    this.pinIndex = [];
    pinned.forEach((p, i) => p && this.pinIndex.push(i));

    this.container = container;
    this.renderer = new WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    container.append(this.renderer.domElement);

    this.scene = new Scene();
    this.scene.background = new Color().setRGB(...BACKGROUND.map((c) => c / 255), 'srgb');
    this.camera = new PerspectiveCamera(FOV, 1, 0.01, 100);
    this.scene.add(this.camera);
    // Soft light: an even base, a sky above and a warm floor below (the model's up), and a key light that
    // moves with the camera from its upper left, so that the side in view is always lit and shaped.
    this.scene.add(new AmbientLight(0xffffff, 1.1));
    this.hemisphere = new HemisphereLight(0xffffff, 0x8a7d74, 1.1);
    this.scene.add(this.hemisphere);
    const light = new DirectionalLight(0xffffff, 1.5);
    light.position.set(-0.5, 0.8, 0.6);
    light.target = new Object3D();
    light.target.position.set(0, 0, -1);
    this.camera.add(light, light.target);

    // The surface and its wireframe, sharing one geometry.
    this.geometry = new BufferGeometry();
    this.geometry.setAttribute('position', new BufferAttribute(new Float32Array(9 * F), 3));
    this.geometry.setAttribute('normal', new BufferAttribute(new Float32Array(9 * F), 3));
    this.geometry.setAttribute('color', new BufferAttribute(new Float32Array(9 * F).fill(0.7), 3));
    this.solid = new Mesh(this.geometry, new MeshLambertMaterial({
      vertexColors: true, side: DoubleSide, polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1,
    }));
    this.wire = new Mesh(this.geometry, new MeshBasicMaterial({
      color: 0x202020, wireframe: true, transparent: true, opacity: 0.35,
    }));
    this.wire.visible = false;
    // Feature edges, so that shapes read clearly even where a face is as light as the background.
    this.edges = surfaceEdges(this.tris, n);
    this.edgeGeometry = new BufferGeometry();
    this.edgeGeometry.setAttribute('position', new BufferAttribute(new Float32Array(3 * n), 3));
    this.edgeGeometry.setIndex(new BufferAttribute(new Uint32Array(2 * this.edges.length), 1));
    this.creases = new LineSegments(this.edgeGeometry, new LineBasicMaterial({ color: 0x303030, transparent: true, opacity: 0.55 }));
    this.pinGeometry = new BufferGeometry();
    this.pinGeometry.setAttribute('position', new BufferAttribute(new Float32Array(3 * this.pinIndex.length), 3));
    this.pins = new Points(this.pinGeometry, new PointsMaterial({ color: 0xe0158a, size: 5, sizeAttenuation: false }));
    for (const o of [this.solid, this.wire, this.creases, this.pins]) {
      o.frustumCulled = false; // the positions change every frame
      this.scene.add(o);
    }
    this.setPositions(rest);
    this.show = 'volume';
    this.panels = ['volume'];
    this.framing = { view: 'three-quarter', up: '+Y', fit: 'animation', focus: '', box: null, points: null };
    this.wireOn = false;
    this.pinsOn = true;
    this.bonesOn = true;
    this.renderData = null; // the render part of the frame drawn
    this.renderFrame = 0; // counts the frames given, so that a surface shown again is filled only if stale
    this.skins = null;
    this.fibresOn = true;
    this.fibreLines = null;
    if (render) this.addRender(render);
    if (mesh.fibres) this.addFibres(mesh.fibres);

    this.camera.up.set(...modelAxes(this.framing.up).up); // before the controls, which orbit about it
    this.hemisphere.position.set(...modelAxes(this.framing.up).up);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.addEventListener('change', () => this.render());
    this.controls.addEventListener('start', () => { this.userMoved = true; });
    this.bounds = unionBounds(mesh.bounds, render && render.bounds);
    this.userMoved = false;
    this.resize();
    new ResizeObserver(() => requestAnimationFrame(() => this.resize())).observe(container);
  }

  /** Surface vertex positions (Float32Array of 3n). */
  setPositions(x) {
    const pos = this.geometry.attributes.position.array;
    const t = this.tris;
    for (let i = 0; i < t.length; i++) {
      const v = 3 * t[i];
      pos[3 * i] = x[v];
      pos[3 * i + 1] = x[v + 1];
      pos[3 * i + 2] = x[v + 2];
    }
    this.geometry.attributes.position.needsUpdate = true;
    this.geometry.computeVertexNormals(); // non-indexed: one normal per triangle
    this.updateCreases(x);
    const pp = this.pinGeometry.attributes.position.array;
    this.pinIndex.forEach((v, k) => pp.set(x.subarray(3 * v, 3 * v + 3), 3 * k));
    this.pinGeometry.attributes.position.needsUpdate = true;
  }

  /** The feature edges of the current shape: open edges and those between triangles at an angle. */
  updateCreases(x) {
    this.edgeGeometry.attributes.position.array.set(x);
    this.edgeGeometry.attributes.position.needsUpdate = true;
    const nrm = this.geometry.attributes.normal.array;
    const index = this.edgeGeometry.index;
    let count = 0;
    for (const [a, b, t1, t2] of this.edges) {
      const dot = t2 < 0 ? -1 : nrm[9 * t1] * nrm[9 * t2] + nrm[9 * t1 + 1] * nrm[9 * t2 + 1] + nrm[9 * t1 + 2] * nrm[9 * t2 + 2];
      if (dot < CREASE_COS) {
        index.array[count++] = a;
        index.array[count++] = b;
      }
    }
    index.needsUpdate = true;
    this.edgeGeometry.setDrawRange(0, count);
  }

  /** Colours from a field's values: one per surface cell or one per surface vertex. */
  setColors(field, values, colors) {
    const col = this.geometry.attributes.color.array;
    const t = this.tris;
    if (field.per === 'cell') {
      for (let f = 0; f < this.triCells.length; f++) {
        const v = values[this.triCells[f]];
        colors.fill(col, 9 * f, v);
        col.copyWithin(9 * f + 3, 9 * f, 9 * f + 3);
        col.copyWithin(9 * f + 6, 9 * f, 9 * f + 3);
      }
    } else {
      for (let i = 0; i < t.length; i++) colors.fill(col, 3 * i, values[t[i]]);
    }
    this.geometry.attributes.color.needsUpdate = true;
  }

  /** The render surfaces (flesh and lbs, sharing the triangles) and the bones of a flesh run. */
  addRender(r) {
    const n = r.vertex_count;
    const tris = decodeBase64(r.triangles, Uint32Array, 'render triangles');
    if (tris.length !== 3 * r.triangle_count) throw new Error('render: the triangle count does not match');
    if (tris.some((v) => v >= n)) throw new Error('render: a triangle refers to a vertex past the surface');
    this.renderTris = tris;
    this.labels = r.labels && typeof r.labels === 'object' ? r.labels : {}; // two runs compared: their names
    // Smooth shading: one normal per group of vertices (a seam's copies share one, a hard edge's do not).
    this.normalGroups = r.normal_groups ? decodeBase64(r.normal_groups, Uint32Array, 'render normal_groups') : null;
    if (this.normalGroups && this.normalGroups.length !== n) throw new Error('render: normal_groups does not have one group per vertex');
    this.distanceField = r.distance ? {
      name: 'distance', label: r.distance.label, per: 'vertex', colormap: 'diverging', center: 0,
      min: r.distance.min, max: r.distance.max, unit: r.distance.unit,
    } : null;
    this.distanceColors = this.distanceField ? fieldColors(this.distanceField) : null;
    this.distanceRun = this.distanceField ? [this.distanceField.min, this.distanceField.max] : null;
    this.distanceRange = 'run';
    this.skins = {};
    for (const name of ['flesh', 'lbs', 'difference']) {
      if (name === 'difference' && !this.distanceField) continue;
      const geometry = new BufferGeometry();
      geometry.setAttribute('position', new BufferAttribute(new Float32Array(3 * n), 3));
      geometry.setAttribute('normal', new BufferAttribute(new Float32Array(3 * n), 3));
      if (name === 'difference') geometry.setAttribute('color', new BufferAttribute(new Float32Array(3 * n), 3));
      geometry.setIndex(new BufferAttribute(tris, 1));
      const solid = new Mesh(geometry, name === 'difference'
        ? new MeshStandardMaterial({ vertexColors: true, roughness: 0.7, metalness: 0, side: DoubleSide, polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 })
        : new MeshStandardMaterial({
          color: new Color().setRGB(...SKIN_SRGB[name].map((c) => c / 255), 'srgb'), roughness: 0.62, metalness: 0,
          side: DoubleSide, polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1,
        }));
      const wire = new Mesh(geometry, new MeshBasicMaterial({
        color: 0x202020, wireframe: true, transparent: true, opacity: 0.3,
      }));
      for (const o of [solid, wire]) {
        o.frustumCulled = false;
        this.scene.add(o);
      }
      this.skins[name] = { geometry, solid, wire, filled: -1 };
    }
    // Bones: segments drawn over the surfaces (they lie inside them), their ends as dots.
    this.boneNames = Array.isArray(r.bones) ? r.bones : [];
    this.bonePositions = new Float32Array(6 * this.boneNames.length);
    this.boneGeometry = new LineSegmentsGeometry();
    this.boneMaterial = new LineMaterial({ color: BONE_COLOR, linewidth: BONE_WIDTH, depthTest: false, transparent: true });
    this.boneLines = new LineSegments2(this.boneGeometry, this.boneMaterial);
    this.boneEndGeometry = new BufferGeometry();
    this.boneEndGeometry.setAttribute('position', new BufferAttribute(this.bonePositions, 3));
    this.boneEnds = new Points(this.boneEndGeometry, new PointsMaterial({
      color: BONE_COLOR, size: 7, sizeAttenuation: false, depthTest: false, transparent: true,
    }));
    if (this.bonePositions.length) this.boneGeometry.setPositions(this.bonePositions);
    for (const o of [this.boneLines, this.boneEnds]) {
      o.frustumCulled = false;
      o.renderOrder = 10;
      this.scene.add(o);
    }
    this.show = 'flesh';
    this.panels = ['flesh'];
    if (typeof r.up_axis === 'string') this.framing.up = r.up_axis;
    this.applyVisibility();
  }

  /** The fibres of a run with muscles (data.mesh.fibres): segments coloured by activation, drawn over everything. */
  addFibres(f) {
    this.fibreMuscle = decodeBase64(f.muscle, Uint32Array, 'fibres muscle');
    if (!Array.isArray(f.muscles) || this.fibreMuscle.length !== f.count) throw new Error('fibres: the fibre count does not match');
    if (this.fibreMuscle.some((m) => m >= f.muscles.length)) throw new Error('fibres: a fibre refers to a muscle past the list');
    this.fibreNames = f.muscles;
    this.fibrePositions = new Float32Array(6 * f.count);
    this.fibreColors = new Float32Array(6 * f.count);
    this.fibreActivation = [];
    this.fibreGeometry = new LineSegmentsGeometry();
    this.fibreMaterial = new LineMaterial({ vertexColors: true, linewidth: FIBRE_WIDTH, depthTest: false, transparent: true });
    this.fibreLines = new LineSegments2(this.fibreGeometry, this.fibreMaterial);
    this.fibreLines.frustumCulled = false;
    this.fibreLines.renderOrder = 9;
    this.fibreLines.visible = false; // until a frame gives the segments
    this.scene.add(this.fibreLines);
  }

  /** A frame's fibres ({segments, activation}). */
  setFibres(fr) {
    if (!this.fibreLines || !fr) return;
    this.fibrePositions.set(fr.segments);
    this.fibreActivation = fr.activation.slice();
    for (let k = 0; k < this.fibreMuscle.length; k++) {
      ACTIVATION_COLORS.fill(this.fibreColors, 6 * k, fr.activation[this.fibreMuscle[k]]);
      this.fibreColors.copyWithin(6 * k + 3, 6 * k, 6 * k + 3);
    }
    if (this.fibrePositions.length) {
      this.fibreGeometry.setPositions(this.fibrePositions);
      this.fibreGeometry.setColors(this.fibreColors);
    }
    this.fibreLines.visible = this.fibresOn && this.fibrePositions.length > 0;
  }

  setFibresVisible(on) {
    this.fibresOn = !!on;
    if (this.fibreLines) this.fibreLines.visible = this.fibresOn && this.fibreActivation.length > 0 && this.fibrePositions.length > 0;
  }

  /** A frame's render part ({flesh, lbs, bones}: Float32Arrays); only the surface in view is updated now. */
  setRender(r) {
    if (!this.skins || !r) return;
    this.renderData = r;
    this.renderFrame++;
    if (this.distanceRange === 'frame' && r.distance) this.setDistanceRange('frame');
    this.updateSkin();
    if (r.bones) {
      this.bonePositions.set(r.bones);
      this.boneEndGeometry.attributes.position.needsUpdate = true;
      if (this.bonePositions.length) this.boneGeometry.setPositions(this.bonePositions);
    }
  }

  /**
   * The range of the difference's colours: 'run' (the whole run's, as data.js has it: the same colour means the
   * same distance in every frame), 'frame' (the frame shown's own) or [lo, hi] in millimetres.
   */
  setDistanceRange(range) {
    if (!this.distanceField) return;
    let lo = this.distanceRun[0];
    let hi = this.distanceRun[1];
    if (Array.isArray(range)) [lo, hi] = range;
    else if (range === 'frame' && this.renderData && this.renderData.distance) {
      lo = Infinity;
      hi = -Infinity;
      for (const d of this.renderData.distance) if (Number.isFinite(d)) { lo = Math.min(lo, d); hi = Math.max(hi, d); }
      if (!(lo <= hi)) [lo, hi] = [0, 0];
    } else if (range !== 'run' && range !== 'frame') throw new Error(`range=${range}: expected run, frame or LO:HI`);
    this.distanceRange = range;
    this.distanceField.min = lo;
    this.distanceField.max = hi;
    this.distanceColors = fieldColors(this.distanceField);
    if (this.skins && this.skins.difference) this.skins.difference.filled = -1; // its colours again
    this.updateSkin();
  }

  /** Fills the skins shown (their positions, normals and, for the difference, colours) from the frame given. */
  updateSkin() {
    if (!this.skins || !this.renderData) return;
    for (const show of this.panels) {
      const skin = this.skins[show];
      if (!skin || skin.filled === this.renderFrame) continue;
      const source = show === 'lbs' ? this.renderData.lbs : this.renderData.flesh;
      skin.geometry.attributes.position.array.set(source);
      skin.geometry.attributes.position.needsUpdate = true;
      groupNormals(source, this.renderTris, this.normalGroups, skin.geometry.attributes.normal.array);
      skin.geometry.attributes.normal.needsUpdate = true;
      if (show === 'difference') {
        const col = skin.geometry.attributes.color.array;
        const d = this.renderData.distance;
        for (let v = 0; v < d.length; v++) this.distanceColors.fill(col, 3 * v, d[v]);
        skin.geometry.attributes.color.needsUpdate = true;
      }
      skin.filled = this.renderFrame;
    }
  }

  /** Shows 'flesh', 'lbs' or 'difference' (a flesh run's render surface: simulated, skinned, or simulated and
   * coloured by its distance from the skinned one) or 'volume' (the boundary, coloured by a field). */
  setShow(what) {
    this.setPanels([what]);
  }

  /** Shows one to four of those side by side, left to right, seen by one camera. */
  setPanels(list) {
    if (!Array.isArray(list) || list.length < 1 || list.length > 4) throw new Error('show one to four surfaces side by side');
    for (const what of list) {
      if (what !== 'volume' && !(this.skins && this.skins[what])) {
        throw new Error(what === 'difference' && this.skins ? 'this report has no flesh–LBS distances (write it again with snh report)'
          : `nothing to show as "${what}"`);
      }
    }
    this.panels = list.slice();
    this.show = list[0];
    this.updateSkin();
    this.applyVisibility();
    this.resize();
  }

  /** What a surface is called: its switch's label, or a compared run's name. */
  showLabel(key) {
    return (this.labels && this.labels[key]) || SHOWS.find(([k]) => k === key)[1];
  }

  /** Makes what panel `show` draws visible (and the rest not). */
  applyVisibility(show = this.show) {
    const volume = show === 'volume';
    this.solid.visible = volume;
    this.creases.visible = volume;
    this.wire.visible = volume && this.wireOn;
    this.pins.visible = volume && this.pinsOn;
    if (!this.skins) return;
    for (const [name, skin] of Object.entries(this.skins)) {
      skin.solid.visible = name === show;
      skin.wire.visible = name === show && this.wireOn;
    }
    const bones = this.bonesOn && this.bonePositions.length > 0;
    this.boneLines.visible = bones;
    this.boneEnds.visible = bones;
  }

  /** Which parts are drawn (for the test hooks). */
  visibility() {
    const s = this.skins;
    return {
      volume: this.solid.visible, flesh: !!s && s.flesh.solid.visible, lbs: !!s && s.lbs.solid.visible,
      difference: !!s && !!s.difference && s.difference.solid.visible,
      bones: !!s && this.boneLines.visible,
      fibres: !!this.fibreLines && this.fibreLines.visible,
    };
  }

  setWireframe(on) {
    this.wireOn = !!on;
    this.applyVisibility();
  }

  setPinsVisible(on) {
    this.pinsOn = !!on;
    this.applyVisibility();
  }

  setBonesVisible(on) {
    this.bonesOn = !!on;
    if (this.skins) this.applyVisibility();
  }

  /**
   * How the camera frames the picture: {view (camera.js VIEWS), fit ('frame': what the frame shown holds,
   * 'animation': the whole run's bounds, or those of `points`, a flat x, y, z array the caller gathered over
   * the frames), focus (a joint's name: a close-up on the surface round it, in the frame shown), box (the
   * part of the picture to fill, in NDC; null: all of it less a margin)}. Framing stops once the user moves
   * the camera.
   */
  setFraming(f) {
    Object.assign(this.framing, f);
    if (this.framing.focus && this.skins && !jointAt(this.boneNames, this.renderData ? this.renderData.bones : this.bonePositions, this.framing.focus)) {
      throw new Error(`no joint "${this.framing.focus}" in this run's bones`);
    }
    viewBasis(this.framing.view, this.framing.up); // a bad name throws here
    if (!this.userMoved) this.frameView();
    this.render();
  }

  /** Frames again if the framing follows the frame (fit 'frame', or a focus); called when a frame is drawn. */
  refit() {
    if (!this.userMoved && (this.framing.fit === 'frame' || this.framing.focus)) this.frameView();
  }

  /** The points of what the panels show in the frame drawn (and the bones when they are drawn). */
  shownPoints() {
    const parts = [];
    for (const show of new Set(this.panels)) {
      if (show === 'volume') parts.push(this.geometry.attributes.position.array);
      else if (this.renderData) parts.push(show === 'lbs' ? this.renderData.lbs : this.renderData.flesh);
    }
    if (this.skins && this.bonesOn && this.bonePositions.length) parts.push(this.bonePositions);
    const out = new Float32Array(parts.reduce((n, p) => n + p.length, 0));
    let at = 0;
    for (const p of parts) {
      out.set(p, at);
      at += p.length;
    }
    return out;
  }

  /** Puts the camera where it frames the picture as setFraming() says. */
  frameView() {
    const f = this.framing;
    let points;
    if (f.focus && this.skins && this.renderData) {
      const joint = jointAt(this.boneNames, this.renderData.bones || this.bonePositions, f.focus);
      points = joint ? pointsNear(this.shownPoints(), joint.position, FOCUS_REACH * joint.reach) : this.shownPoints();
    } else if (f.fit === 'frame') {
      points = this.shownPoints();
    } else if (f.points) {
      points = f.points;
    } else {
      const { min, max } = this.bounds || { min: [-1, -1, -1], max: [1, 1, 1] };
      points = [];
      for (let c = 0; c < 8; c++) points.push(c & 1 ? max[0] : min[0], c & 2 ? max[1] : min[1], c & 4 ? max[2] : min[2]);
    }
    const { w, h } = this.panelSize();
    const box = f.box || { left: -FRAME_MARGIN, right: FRAME_MARGIN, bottom: -FRAME_MARGIN, top: FRAME_MARGIN };
    const cam = fitView(points, viewBasis(f.view, f.up), FOV, w / h, box);
    this.camera.up.set(...cam.up);
    this.camera.position.set(...cam.position);
    this.camera.near = cam.near;
    this.camera.far = cam.far;
    this.camera.aspect = w / h;
    // The lens shift that puts the target at the box's centre (setViewOffset moves the window the other way).
    this.camera.setViewOffset(w, h, (-cam.shift[0] * w) / 2, (cam.shift[1] * h) / 2, w, h);
    this.camera.updateProjectionMatrix();
    this.controls.target.set(...cam.target);
    this.camera.lookAt(this.controls.target);
    this.controls.update();
  }

  /** The NDC extent {left, right, bottom, top} of the shown points through the camera as drawn (for tests). */
  projectedExtent() {
    const p = this.shownPoints();
    const v = new Vector3();
    const e = { left: Infinity, right: -Infinity, bottom: Infinity, top: -Infinity, points: p.length / 3 };
    this.camera.updateMatrixWorld();
    for (let i = 0; i < p.length; i += 3) {
      v.set(p[i], p[i + 1], p[i + 2]).project(this.camera);
      e.left = Math.min(e.left, v.x); e.right = Math.max(e.right, v.x);
      e.bottom = Math.min(e.bottom, v.y); e.top = Math.max(e.top, v.y);
    }
    return e;
  }

  /** The size of one panel in CSS pixels. */
  panelSize() {
    const w = Math.max(this.container.clientWidth, 1);
    const h = Math.max(this.container.clientHeight, 1);
    return { w: w / Math.max(this.panels.length, 1), h };
  }

  resize() {
    const w = Math.max(this.container.clientWidth, 1);
    const h = Math.max(this.container.clientHeight, 1);
    this.renderer.setSize(w, h);
    const panel = this.panelSize();
    this.camera.aspect = panel.w / panel.h;
    this.camera.updateProjectionMatrix();
    if (this.boneMaterial) this.boneMaterial.resolution.set(panel.w, panel.h);
    if (this.fibreMaterial) this.fibreMaterial.resolution.set(panel.w, panel.h);
    if (!this.userMoved) this.frameView();
    this.render();
  }

  /** Draws the panels side by side, each with what it shows, all from one camera. */
  render() {
    const n = this.panels.length;
    const { w, h } = this.panelSize();
    this.renderer.setScissorTest(n > 1);
    for (let i = 0; i < n; i++) {
      this.applyVisibility(this.panels[i]);
      this.renderer.setViewport(i * w, 0, w, h);
      this.renderer.setScissor(i * w, 0, w, h);
      this.renderer.render(this.scene, this.camera);
    }
    this.applyVisibility(this.show);
  }
}

/**
 * Unit normals (into `out`, 3 per vertex) of the surface at positions `x`: each group's sum over its vertices'
 * triangle corners of the face normal times the corner's angle, the same for every vertex of the group
 * (`groups` null: each vertex its own group).
 */
function groupNormals(x, tris, groups, out) {
  const n = x.length / 3;
  let count = n;
  if (groups) {
    count = 0;
    for (let v = 0; v < n; v++) count = Math.max(count, groups[v] + 1);
  }
  const group = (v) => (groups ? groups[v] : v);
  const sum = new Float64Array(3 * count);
  const edge = (from, to) => [x[3 * to] - x[3 * from], x[3 * to + 1] - x[3 * from + 1], x[3 * to + 2] - x[3 * from + 2]];
  for (let t = 0; t < tris.length; t += 3) {
    const i = [tris[t], tris[t + 1], tris[t + 2]];
    const e1 = edge(i[0], i[1]);
    const e2 = edge(i[0], i[2]);
    const nrm = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
    const len = Math.hypot(...nrm);
    if (!(len > 0)) continue;
    for (let c = 0; c < 3; c++) {
      const u = edge(i[c], i[(c + 1) % 3]);
      const w = edge(i[c], i[(c + 2) % 3]);
      const cos = (u[0] * w[0] + u[1] * w[1] + u[2] * w[2]) / (Math.hypot(...u) * Math.hypot(...w) || 1);
      const weight = Math.acos(Math.min(1, Math.max(-1, cos))) / len;
      const G = 3 * group(i[c]);
      for (let k = 0; k < 3; k++) sum[G + k] += weight * nrm[k];
    }
  }
  for (let v = 0; v < n; v++) {
    const G = 3 * group(v);
    const len = Math.hypot(sum[G], sum[G + 1], sum[G + 2]) || 1;
    for (let k = 0; k < 3; k++) out[3 * v + k] = sum[G + k] / len;
  }
}

/** The box around two {min, max} boxes (either may be missing). */
function unionBounds(a, b) {
  if (!a || !b) return a || b;
  return { min: a.min.map((v, k) => Math.min(v, b.min[k])), max: a.max.map((v, k) => Math.max(v, b.max[k])) };
}
