// Small DOM and data helpers shared by the page's parts.

/** Creates an element: el('div', {class: 'x', 'data-id': 3}, child, 'text', ...). */
export function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (v === undefined || v === null || v === false) continue;
    if (k === 'class') e.className = v;
    else if (k === 'text') e.textContent = v;
    else if (k.startsWith('on')) e.addEventListener(k.slice(2), v);
    else e.setAttribute(k, v === true ? '' : String(v));
  }
  for (const c of children.flat(Infinity)) {
    if (c !== null && c !== undefined && c !== false) e.append(c instanceof Node ? c : String(c));
  }
  return e;
}

/** Decodes base64 into a typed array of the given type (little-endian, as the report is written). */
export function decodeBase64(b64, Type, what) {
  if (typeof b64 !== 'string') throw new Error(`${what}: missing`);
  const bin = atob(b64);
  if (bin.length % Type.BYTES_PER_ELEMENT) throw new Error(`${what}: ${bin.length} bytes is not a whole number of values`);
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
  return new Type(bytes.buffer);
}

/** A number with 4 significant digits, without trailing noise ("1", "0.6123", "2.5e-7"). */
export function fmt4(v) {
  if (v === null || v === undefined || !Number.isFinite(v)) return '–';
  if (v === 0) return '0';
  const a = Math.abs(v);
  if (a >= 1e-3 && a < 1e6) return String(Number(v.toPrecision(4)));
  return v.toExponential(3).replace(/\.?0+e/, 'e');
}

/** A time value, short but not rounded away ("12", "0.03333"). */
export function fmtTime(t) {
  return typeof t === 'number' && Number.isFinite(t) ? String(Number(t.toPrecision(6))) : String(t ?? '');
}

/** The message of anything thrown. */
export function message(e) {
  return e && e.message ? e.message : String(e);
}
