// The framing (src/camera.js) without a browser: for every named view, both up axes and a wide and a tall
// picture, every point of a cloud projects inside the box asked for, the cloud fills the box along one axis
// and sits centred along both; the joints of bone names and a close-up's reach.
import assert from 'node:assert/strict';
import { test } from 'node:test';
import { decisivePoints, fitView, jointAt, jointNames, modelAxes, pointsNear, project, VIEWS, viewBasis } from '../src/camera.js';

/** A cloud shaped like a hand: a flat palm and four long fingers off one side, away from the origin. */
function cloud(seed) {
  let s = seed;
  const rand = () => ((s = (s * 16807) % 2147483647) / 2147483647);
  const p = [];
  for (let i = 0; i < 600; i++) p.push(3 + rand() * 0.8, -1 + rand() * 0.2, 7 + rand() * 0.9);
  for (let f = 0; f < 4; f++) for (let i = 0; i < 100; i++) p.push(3 + f * 0.2 + rand() * 0.1, -1 + rand() * 0.2, 7.9 + rand() * 1.2);
  return p;
}

test('every view fits the points inside the box, touching it along one axis', () => {
  const boxes = [{ left: -0.9, right: 0.9, bottom: -0.9, top: 0.9 }, { left: -0.94, right: 0.94, bottom: -0.94, top: 0.8 }];
  for (const up of ['+Y', '+Z', '-Z', '+X']) {
    for (const view of VIEWS) {
      for (const aspect of [4 / 3, 0.5]) {
        for (const box of boxes) {
          const pts = cloud(7);
          const basis = viewBasis(view, up);
          const cam = fitView(pts, basis, 30, aspect, box);
          let xl = Infinity; let xr = -Infinity; let yb = Infinity; let yt = -Infinity;
          for (let i = 0; i < pts.length; i += 3) {
            const [x, y, w] = project([pts[i], pts[i + 1], pts[i + 2]], cam, 30, aspect);
            assert.ok(w > 0, `${up} ${view}: a point behind the camera`);
            xl = Math.min(xl, x); xr = Math.max(xr, x); yb = Math.min(yb, y); yt = Math.max(yt, y);
          }
          const what = `${up} ${view} aspect ${aspect} box top ${box.top}`;
          const eps = 1e-6;
          assert.ok(xl >= box.left - eps && xr <= box.right + eps && yb >= box.bottom - eps && yt <= box.top + eps,
            `${what}: extent x ${xl}..${xr}, y ${yb}..${yt} outside the box`);
          // Tight: the points touch both sides of the box along one axis.
          const touchX = Math.abs(xl - box.left) < 1e-9 && Math.abs(xr - box.right) < 1e-9;
          const touchY = Math.abs(yb - box.bottom) < 1e-9 && Math.abs(yt - box.top) < 1e-9;
          assert.ok(touchX || touchY, `${what}: extent x ${xl}..${xr}, y ${yb}..${yt} touches neither pair of sides`);
          assert.ok(cam.near > 0 && cam.near < cam.far, `${what}: near ${cam.near}, far ${cam.far}`);
        }
      }
    }
  }
});

test('the decisive points of several sets frame them as all their points do', () => {
  const sets = [cloud(3), cloud(11).map((v, i) => (i % 3 === 1 ? v + 0.7 : v)), cloud(5).map((v) => v * 1.1)];
  const basis = viewBasis('three-quarter', '+Y');
  const box = { left: -0.92, right: 0.92, bottom: -0.8, top: 0.85 };
  const all = fitView(sets.flat(), basis, 30, 1.5, box);
  const few = fitView(sets.flatMap((p) => decisivePoints(p, basis, 30, 1.5, box)), basis, 30, 1.5, box);
  for (const k of ['position', 'target']) for (let a = 0; a < 3; a++) assert.ok(Math.abs(all[k][a] - few[k][a]) < 1e-12, k);
  assert.equal(sets.flatMap((p) => decisivePoints(p, basis, 30, 1.5, box)).length, 3 * 6 * 3);
});

test('views look from where animators expect', () => {
  const dir = (view, up) => viewBasis(view, up).dir.map((x) => x + 0); // -0 as 0
  assert.deepEqual(dir('front', '+Y'), [0, 0, 1]);
  assert.deepEqual(dir('front', '+Z'), [0, -1, 0]);
  assert.deepEqual(dir('right', '+Y'), [1, 0, 0]);
  assert.deepEqual(dir('right', '+Z'), [1, 0, 0]);
  assert.deepEqual(dir('left', '+Y'), [-1, 0, 0]);
  assert.deepEqual(dir('top', '+Z'), [0, 0, 1]);
  const tq = viewBasis('three-quarter', '+Y').dir;
  assert.ok(tq[0] > 0 && tq[1] > 0 && tq[2] > tq[0], `three-quarter from front-right, above: ${tq}`);
  assert.deepEqual(modelAxes('-Y').up, [0, -1, 0]);
  assert.throws(() => viewBasis('sideways'), /unknown view "sideways" \(expected three-quarter, front, back, left, right, top\)/);
  assert.throws(() => modelAxes('Q'), /unknown up axis "Q"/);
});

test('joints come from the bones, a close-up reaches round them', () => {
  const names = ['wrist>index-finger-metacarpal', 'index-finger-metacarpal>index-finger-tip', 'index-finger-tip'];
  assert.deepEqual(jointNames(names), ['wrist', 'index-finger-metacarpal', 'index-finger-tip']);
  const seg = [0, 0, 0, 0, 0, 4, 0, 0, 4, 0, 0, 7, 0, 0, 7, 0, 0, 7];
  const j = jointAt(names, seg, 'index-finger-metacarpal');
  assert.deepEqual(j.position, [0, 0, 4]);
  assert.equal(j.reach, 3); // the shorter of its two bones
  assert.deepEqual(jointAt(names, seg, 'index-finger-tip').position, [0, 0, 7]);
  assert.equal(jointAt(names, seg, 'elbow'), null);
  const near = pointsNear([0, 0, 4.5, 0, 0, 9, 1, 0, 4], [0, 0, 4], 1);
  assert.deepEqual(near, [0, 0, 4, 0, 0, 4.5, 1, 0, 4]);
});
