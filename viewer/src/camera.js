// Framing: where the camera goes for a named view so that a set of points fills the picture, and the joints
// of a flesh run's bones for a close-up. Plain arrays, no three.js, so that node's tests can check the
// framing by projecting the points themselves.

/** The views a picture can take, as animators name them. */
export const VIEWS = ['three-quarter', 'front', 'back', 'left', 'right', 'top'];

const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const scale = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const unit = (a) => scale(a, 1 / Math.hypot(a[0], a[1], a[2]));

/**
 * The model's up, front and right from its up axis ("+Y", as glTF has it, "+Z", as Blender and many FBX
 * files have it, or any signed axis): front is +Z for a Y-up model and -Y for a Z-up one (where a character
 * made in each faces), right is up × front (the side a viewer facing the character sees on the right).
 */
export function modelAxes(upAxis = '+Y') {
  const m = /^([+-]?)([XYZ])$/i.exec(String(upAxis || '+Y').trim());
  if (!m) throw new Error(`unknown up axis "${upAxis}" (expected +X, +Y, +Z, -X, -Y or -Z)`);
  const k = 'XYZ'.indexOf(m[2].toUpperCase());
  const s = m[1] === '-' ? -1 : 1;
  const up = [0, 0, 0];
  up[k] = s;
  // Y-up (either sign) and X-up face +Z; Z-up faces -Y (for +Z; +Y for -Z, keeping right = up × front).
  const front = k === 2 ? [0, -s, 0] : [0, 0, 1];
  return { up, front, right: cross(up, front) };
}

/**
 * The camera's direction (from the target towards the camera, unit) and its up for a named view:
 * front, back, left, right, top, or three-quarter (35° round from the front towards the right, 20° above).
 */
export function viewBasis(name, upAxis = '+Y') {
  const { up, front, right } = modelAxes(upAxis);
  switch (name) {
    case 'front': return { dir: front, up };
    case 'back': return { dir: scale(front, -1), up };
    case 'right': return { dir: right, up };
    case 'left': return { dir: scale(right, -1), up };
    case 'top': return { dir: up, up: scale(front, -1) };
    case 'three-quarter':
    case undefined:
    case null:
    case '': {
      const az = (35 * Math.PI) / 180;
      const el = (20 * Math.PI) / 180;
      const level = add(scale(front, Math.cos(az)), scale(right, Math.sin(az)));
      return { dir: unit(add(scale(level, Math.cos(el)), scale(up, Math.sin(el)))), up };
    }
    default: throw new Error(`unknown view "${name}" (expected ${VIEWS.join(', ')})`);
  }
}

/**
 * Where a perspective camera looking along -basis.dir goes so that every point (a flat array x, y, z, …)
 * projects inside `box` of normalized device coordinates ({left, right, bottom, top} in -1..1), as large as
 * it fits: {position, target, up, distance, shift, near, far}. The vertical field of view is `fovDeg`,
 * `aspect` is width / height. The view is shifted (a lens shift, as three.js's setViewOffset makes) by
 * `shift`, the box's centre, so that the frustum is symmetric about the camera's axis.
 *
 * With camera coordinates x, y (along right and up) and depth w of a point, the point is inside when
 * |x| <= a w and |y| <= b w (a, b the box's half-widths times the tangents of the half fields of view).
 * In world coordinates X, Y, Z (along right, up, dir) and the camera's (Xc, Yc, Zc) that is X + aZ <= Xc + aZc
 * and -X + aZ <= -Xc + aZc, so the frustum's four sides are planes each pushed against the points: the
 * camera where the left and right sides both touch is Xc = (R - L) / 2, Zc = (R + L) / (2a) with
 * R = max(X + aZ), L = max(-X + aZ), and likewise up and down. It takes the farther of the two depths, so
 * the points touch both sides of one axis and have room on the other, shared equally between its two sides.
 */
export function fitView(points, basis, fovDeg, aspect, box = { left: -0.9, right: 0.9, bottom: -0.9, top: 0.9 }) {
  const n = Math.floor(points.length / 3);
  const dir = unit(basis.dir);
  const right = unit(cross(basis.up, dir));
  const up = cross(dir, right);
  const tv = Math.tan((fovDeg * Math.PI) / 360);
  const shift = [(box.left + box.right) / 2, (box.bottom + box.top) / 2];
  if (n === 0) return { target: [0, 0, 0], position: dir, distance: 1, up, shift, near: 0.01, far: 100 };
  const a = ((box.right - box.left) / 2) * tv * aspect;
  const b = ((box.top - box.bottom) / 2) * tv;
  let R = -Infinity; let L = -Infinity; let T = -Infinity; let B = -Infinity;
  let zlo = Infinity; let zhi = -Infinity;
  for (let i = 0; i < n; i++) {
    const p = [points[3 * i], points[3 * i + 1], points[3 * i + 2]];
    const X = dot(p, right);
    const Y = dot(p, up);
    const Z = dot(p, dir);
    R = Math.max(R, X + a * Z); L = Math.max(L, -X + a * Z);
    T = Math.max(T, Y + b * Z); B = Math.max(B, -Y + b * Z);
    zlo = Math.min(zlo, Z); zhi = Math.max(zhi, Z);
  }
  const Xc = (R - L) / 2;
  const Yc = (T - B) / 2;
  // Both depths put every point in front of the camera (a point with Z = Zc would need x = y = 0); a hair
  // farther keeps a point on the axis off the camera itself.
  const Zc = Math.max((R + L) / (2 * a), (T + B) / (2 * b), zhi + 1e-6 * Math.max(zhi - zlo, 1e-9));
  const position = add(add(scale(right, Xc), scale(up, Yc)), scale(dir, Zc));
  const distance = Zc - (zlo + zhi) / 2;  // to the target: the points' middle depth, on the axis
  const target = add(position, scale(dir, -distance));
  const nearest = Zc - zhi;
  const deepest = Zc - zlo;
  return { target, position, distance, up, shift, near: Math.max(nearest * 0.5, deepest * 1e-4), far: deepest * 2 };
}

/**
 * The few points of a set that decide fitView's camera for the same basis, field of view, aspect and box:
 * those farthest out along each of the frustum's four sides and nearest and farthest in depth (a flat
 * array). Gathering them frame by frame frames a whole animation without keeping every frame's points.
 */
export function decisivePoints(points, basis, fovDeg, aspect, box = { left: -0.9, right: 0.9, bottom: -0.9, top: 0.9 }) {
  const n = Math.floor(points.length / 3);
  if (n === 0) return [];
  const dir = unit(basis.dir);
  const right = unit(cross(basis.up, dir));
  const up = cross(dir, right);
  const tv = Math.tan((fovDeg * Math.PI) / 360);
  const a = ((box.right - box.left) / 2) * tv * aspect;
  const b = ((box.top - box.bottom) / 2) * tv;
  const measures = [
    (X, Y, Z) => X + a * Z, (X, Y, Z) => -X + a * Z, (X, Y, Z) => Y + b * Z, (X, Y, Z) => -Y + b * Z,
    (X, Y, Z) => Z, (X, Y, Z) => -Z,
  ];
  const best = measures.map(() => [-Infinity, 0]);
  for (let i = 0; i < n; i++) {
    const p = [points[3 * i], points[3 * i + 1], points[3 * i + 2]];
    const X = dot(p, right);
    const Y = dot(p, up);
    const Z = dot(p, dir);
    measures.forEach((m, k) => {
      const v = m(X, Y, Z);
      if (v > best[k][0]) best[k] = [v, i];
    });
  }
  const out = [];
  for (const [, i] of best) out.push(points[3 * i], points[3 * i + 1], points[3 * i + 2]);
  return out;
}

/** A flesh run's joints, from its bones' names ("head>tail", or one name for an end): each name once, in order. */
export function jointNames(boneNames) {
  const out = [];
  for (const b of boneNames || []) for (const j of String(b).split('>')) if (j && !out.includes(j)) out.push(j);
  return out;
}

/**
 * Where joint `name` is in a frame's bone segments (6 values per bone: head then tail) and how far round it
 * a close-up reaches (the shortest bone that starts or ends there, so that a knuckle's close-up is the
 * finger's, not the hand's; at least a twentieth of the skeleton's size): {position, reach}; null when no
 * bone names it.
 */
export function jointAt(boneNames, segments, name) {
  let position = null;
  let reach = Infinity;
  let lo = [Infinity, Infinity, Infinity];
  let hi = [-Infinity, -Infinity, -Infinity];
  (boneNames || []).forEach((b, k) => {
    const head = [segments[6 * k], segments[6 * k + 1], segments[6 * k + 2]];
    const tail = [segments[6 * k + 3], segments[6 * k + 4], segments[6 * k + 5]];
    for (const p of [head, tail]) for (let a = 0; a < 3; a++) { lo[a] = Math.min(lo[a], p[a]); hi[a] = Math.max(hi[a], p[a]); }
    const parts = String(b).split('>');
    const length = Math.hypot(...sub(tail, head));
    if (parts[0] === name || (parts.length > 1 && parts[1] === name)) {
      position = position || (parts[0] === name ? head : tail);
      if (length > 0) reach = Math.min(reach, length);
    }
  });
  if (!position) return null;
  const skeleton = Number.isFinite(lo[0]) ? Math.hypot(...sub(hi, lo)) : 0;
  return { position, reach: Math.max(Number.isFinite(reach) ? reach : 0, 0.05 * skeleton) };
}

/** The points (flat x, y, z, …) within `radius` of `centre`, and the centre itself. */
export function pointsNear(points, centre, radius) {
  const out = [...centre];
  const r2 = radius * radius;
  for (let i = 0; i + 2 < points.length; i += 3) {
    const dx = points[i] - centre[0];
    const dy = points[i + 1] - centre[1];
    const dz = points[i + 2] - centre[2];
    if (dx * dx + dy * dy + dz * dz <= r2) out.push(points[i], points[i + 1], points[i + 2]);
  }
  return out;
}

/** The NDC of point p seen by the camera {position, target, up} of `fitView` (for tests): [x, y, depth]. */
export function project(p, cam, fovDeg, aspect) {
  const dir = unit(sub(cam.position, cam.target));
  const right = unit(cross(cam.up, dir));
  const up = cross(dir, right);
  const q = sub(p, cam.position);
  const w = -dot(q, dir);
  const tv = Math.tan((fovDeg * Math.PI) / 360);
  return [dot(q, right) / (w * tv * aspect) + cam.shift[0], dot(q, up) / (w * tv) + cam.shift[1], w];
}
