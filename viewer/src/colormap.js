// Colormaps for the mesh fields: value -> colour, as a lookup table for the vertex colours
// (linear RGB, which three.js expects) and as a CSS gradient for the legend (sRGB).

// Control points in sRGB 0-255, evenly spaced over [0, 1].
const STOPS = {
  // viridis-like: dark violet -> blue -> green -> yellow
  sequential: [[68, 1, 84], [72, 40, 120], [62, 73, 137], [49, 104, 142], [38, 130, 142],
               [31, 158, 137], [53, 183, 121], [110, 206, 88], [253, 231, 37]],
  // blue -> white -> red, white in the middle
  diverging: [[33, 72, 150], [67, 147, 195], [171, 210, 229], [250, 250, 250],
              [244, 175, 145], [214, 96, 77], [140, 20, 40]],
};
const NAN_SRGB = [0.62, 0.62, 0.62]; // undefined values (NaN) are grey
const LUT_SIZE = 256;

function stopsFor(name) {
  return STOPS[name] || STOPS.sequential;
}

/** sRGB colour (components 0..1) at t in [0, 1]. */
export function srgbAt(name, t) {
  const s = stopsFor(name);
  const x = Math.min(Math.max(t, 0), 1) * (s.length - 1);
  const i = Math.min(Math.floor(x), s.length - 2);
  const f = x - i;
  return [0, 1, 2].map((k) => (s[i][k] + (s[i + 1][k] - s[i][k]) * f) / 255);
}

const toLinear = (c) => (c <= 0.04045 ? c / 12.92 : Math.pow((c + 0.055) / 1.055, 2.4));

/**
 * The mapping of one field: `toT(v)` gives the position in the colormap, `fill(out, o, v)`
 * writes the linear RGB colour of value v at out[o..o+2].
 * Sequential maps min..max; diverging puts white at `center` with a symmetric span that covers min..max.
 */
export function fieldColors(field) {
  const name = field.colormap === 'diverging' ? 'diverging' : 'sequential';
  let lo = field.min;
  let hi = field.max;
  if (name === 'diverging') {
    const c = Number.isFinite(field.center) ? field.center : (lo + hi) / 2;
    const span = Math.max(Math.abs(hi - c), Math.abs(c - lo));
    lo = c - span;
    hi = c + span;
  }
  const width = hi - lo;
  // A range within rounding of zero (ψ of a run that only rests: ±1e-16) is drawn as constant, not as noise.
  const flat = !(width > 1e-12 * Math.max(1, Math.abs(lo), Math.abs(hi)));
  const toT = (v) => (flat ? (name === 'diverging' ? 0.5 : 0) : (v - lo) / width);

  const lut = new Float32Array(LUT_SIZE * 3);
  for (let i = 0; i < LUT_SIZE; i++) {
    const c = srgbAt(name, i / (LUT_SIZE - 1));
    for (let k = 0; k < 3; k++) lut[3 * i + k] = toLinear(c[k]);
  }
  const nan = NAN_SRGB.map(toLinear);

  function fill(out, o, v) {
    if (!Number.isFinite(v)) {
      out[o] = nan[0]; out[o + 1] = nan[1]; out[o + 2] = nan[2];
      return;
    }
    const t = Math.min(Math.max(toT(v), 0), 1);
    const j = 3 * Math.round(t * (LUT_SIZE - 1));
    out[o] = lut[j]; out[o + 1] = lut[j + 1]; out[o + 2] = lut[j + 2];
  }

  /** A CSS gradient (left to right) of the colours from field.min to field.max. */
  function gradient() {
    const t0 = toT(field.min);
    const t1 = toT(field.max);
    const parts = [];
    for (let i = 0; i <= 16; i++) {
      const c = srgbAt(name, t0 + ((t1 - t0) * i) / 16).map((x) => Math.round(x * 255));
      parts.push(`rgb(${c.join(',')}) ${((i / 16) * 100).toFixed(2)}%`);
    }
    return `linear-gradient(to right, ${parts.join(', ')})`;
  }

  return { name, lo, hi, toT, fill, gradient };
}
