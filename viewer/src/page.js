// The static parts of the page: header (title, status, meta) and the tables.
import { el } from './util.js';

const KIND_NAMES = { stretch: 'stretch run', scene: 'scene run', lab: 'lab report' };

/** A meta value: text, or a link ({text, href}: a file of the run, such as its USD stage). */
function metaValue(v) {
  if (v === null || v === undefined) return '–';
  if (typeof v === 'object' && v.href) return el('a', { href: v.href }, v.text ?? v.href);
  return String(v);
}

export function header(data) {
  const status = data.status || {};
  const ok = status.ok !== false;
  // A run that finished but warned (bones pressing flesh, frames converged inside out): not a plain tick.
  const warnings = Array.isArray(status.warnings) ? status.warnings.filter((w) => typeof w === 'string') : [];
  const warned = ok && warnings.length > 0;
  const meta = Array.isArray(data.meta) ? data.meta : [];
  return el('header', { class: 'snh-header' },
    el('div', { class: 'snh-kicker' }, data.render ? 'flesh run' : KIND_NAMES[data.kind] || data.kind || 'report',
      data.generated_by ? el('span', { class: 'snh-generated' }, ` · ${data.generated_by}`) : null),
    el('h1', { class: 'snh-title' }, data.title || 'snh report'),
    el('div', { class: `snh-status ${warned ? 'snh-status-warn' : ok ? 'snh-status-ok' : 'snh-status-fail'}`, role: 'status' },
      el('span', { class: 'snh-status-icon', 'aria-hidden': 'true' }, warned ? '⚠' : ok ? '✓' : '✗'),
      el('span', {}, status.text || (ok ? 'ok' : 'failed'))),
    warnings.length ? el('ul', { class: 'snh-warnings' }, warnings.map((w) => el('li', {}, w))) : null,
    meta.length
      ? el('dl', { class: 'snh-meta' }, meta.map(([k, v]) => el('div', {}, el('dt', {}, k), el('dd', {}, metaValue(v)))))
      : null);
}

const NUMERIC = /^[-+−]?(\d[\d,]*\.?\d*|\.\d+)([eE][-+]?\d+)?\s*(%|×|x|s|ms)?$/;

function cell(v, tag) {
  if (v === null || v === undefined) return el(tag, { class: 'snh-empty' }, '–');
  if (typeof v === 'object') {
    return el(tag, {}, v.href ? el('a', { href: v.href }, v.text ?? v.href) : String(v.text ?? ''));
  }
  const text = String(v);
  return el(tag, { class: typeof v === 'number' || NUMERIC.test(text.trim()) ? 'snh-num' : null }, text);
}

export function table(t) {
  const columns = t.columns || [];
  const rows = t.rows || [];
  return el('div', { class: 'snh-table-wrap' },
    el('table', { class: 'snh-table' },
      el('caption', {},
        el('span', { class: 'snh-table-title' }, t.title || ''),
        t.note ? el('span', { class: 'snh-table-note' }, t.note) : null),
      columns.length ? el('thead', {}, el('tr', {}, columns.map((c) => el('th', { scope: 'col' }, c)))) : null,
      el('tbody', {}, rows.map((r) => el('tr', {}, (Array.isArray(r) ? r : [r]).map((c) => cell(c, 'td')))))));
}

export function tablesSection(tables) {
  return el('section', { class: 'snh-section snh-tables' }, el('h2', {}, 'Tables'), tables.map(table));
}
