// The plots: one uPlot chart per plot entry, grouped under their headings in a responsive grid.
import uPlot from 'uplot';
import { el, fmt4, message } from './util.js';

const COLORS = ['#1f6fb4', '#d9480f', '#2b8a3e', '#ae3ec9', '#e8590c', '#0c8599', '#c2255c', '#5c7cfa', '#868e96', '#a9a318'];
const HEIGHT = 250;
const FONT = '12px system-ui, -apple-system, "Segoe UI", Roboto, sans-serif';

/** Values a chart can draw: numbers, and null for gaps (also for ≤ 0 on a log axis). */
function clean(y, n, log) {
  const out = new Array(n).fill(null);
  for (let i = 0; i < Math.min(n, y ? y.length : 0); i++) {
    const v = y[i];
    if (typeof v === 'number' && Number.isFinite(v) && (!log || v > 0)) out[i] = v;
  }
  return out;
}

function axis(label, extra = {}) {
  return {
    label: label || '', font: FONT, labelFont: FONT, labelSize: 20, stroke: '#444',
    grid: { stroke: '#e6e6e6', width: 1 }, ticks: { stroke: '#ccc', width: 1, size: 4 }, ...extra,
  };
}

// Tick labels with 4 significant digits (uPlot's default rounds 1e-7 to "0"); null = no label.
const tickValues = (u, splits) => splits.map((v) => (v === null || v === undefined ? '' : fmt4(v)));
// Whole-number steps for an x axis of whole numbers (no tick at step 1.5).
const INT_INCRS = [1, 2, 5, 10, 20, 50, 100, 200, 500, 1e3, 2e3, 5e3, 1e4, 2e4, 5e4, 1e5, 1e6];

// The y axis is as wide as its longest tick label.
const ySize = (u, values) => (values && values.length ? Math.max(...values.map((v) => String(v).length)) * 7 + 18 : 40);

/** A linear y scale: automatic, or clipped where the plot gives y_range [lo, hi] (null = automatic). */
function yScale(p) {
  const r = Array.isArray(p.y_range) ? p.y_range : null;
  if (!r) return { auto: true };
  return {
    auto: false,
    range: (u, lo, hi) => [typeof r[0] === 'number' ? r[0] : lo, typeof r[1] === 'number' ? r[1] : hi],
  };
}

function options(p, width, log) {
  const only = !!p.points_only;
  return {
    width, height: HEIGHT,
    scales: { x: { time: false }, y: log ? { distr: 3, log: 10 } : yScale(p) },
    axes: [
      axis(p.x_label, { values: tickValues, ...(p.x.every(Number.isInteger) ? { incrs: INT_INCRS } : {}) }),
      axis(p.y_label, { values: tickValues, size: ySize }),
    ],
    legend: { show: true, live: true },
    cursor: { points: { size: 7 } },
    series: [
      { label: p.x_label || 'x' },
      ...p.series.map((s, k) => {
        const color = COLORS[k % COLORS.length];
        return {
          label: s.label || `series ${k + 1}`, stroke: color, width: 1.6, spanGaps: false,
          points: only ? { show: true, size: 6, stroke: color, fill: color } : { size: 5, fill: color },
          ...(only ? { paths: () => null } : {}),
        };
      }),
    ],
  };
}

/**
 * The plots section (or null without plots). Charts need their width, so they are drawn by
 * the returned `draw()` once the section is in the document.
 */
export function plotsSection(plots, hooks, onError) {
  if (!plots || !plots.length) return { section: null, draw() {} };
  const groups = new Map(); // heading -> cards, in order of appearance
  const pending = [];
  for (const p of plots) {
    const x = Array.isArray(p.x) ? p.x : [];
    const series = Array.isArray(p.series) ? p.series : [];
    const holder = el('div', { class: 'snh-plot', 'data-plot-id': p.id, 'data-points': x.length });
    const card = el('figure', { class: 'snh-plot-card' }, el('figcaption', {}, p.title || p.id), holder);
    const g = p.group || '';
    if (!groups.has(g)) groups.set(g, []);
    groups.get(g).push(card);
    pending.push({ p: { ...p, x, series }, holder });
    hooks.plots.push({ id: p.id, title: p.title, points: x.length, series: series.map((s) => s.label) });
  }
  const section = el('section', { class: 'snh-section snh-plots' }, el('h2', {}, 'Plots'),
    [...groups].map(([g, cards]) => [g ? el('h3', { class: 'snh-group' }, g) : null, el('div', { class: 'snh-plot-grid' }, cards)]));

  function draw() {
    for (const { p, holder } of pending) {
      try {
        const n = p.x.length;
        const ys = p.series.map((s) => clean(s.y, n, !!p.log_y));
        // A log axis needs at least one positive value; without one, the (empty) axis is linear.
        const log = !!p.log_y && ys.some((y) => y.some((v) => v !== null));
        const data = [p.x.map(Number), ...ys];
        const chart = new uPlot(options(p, Math.max(holder.clientWidth, 200), log), data, holder);
        // Resized in the next frame, not inside the observer (that would loop on the scrollbar).
        new ResizeObserver(() => requestAnimationFrame(() => {
          const w = Math.max(holder.clientWidth, 200);
          if (w !== chart.width) chart.setSize({ width: w, height: HEIGHT });
        })).observe(holder);
      } catch (e) {
        holder.append(el('p', { class: 'snh-error' }, `This plot could not be drawn: ${message(e)}`));
        onError(e);
      }
    }
  }
  return { section, draw };
}
