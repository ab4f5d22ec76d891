// The ehservo playground. Everything about the servo comes from the wasm
// module (crates/ehservo-web): the scenarios, each controller kind's declared
// tunables and signals, the validation, the run, the metrics and the TOML.
// This file only builds the controls from that catalogue, keeps the state in
// the URL and hands the traces to uPlot.
import init, * as wasm from './pkg/ehservo_web.js';
import uPlot from './vendor/uPlot.esm.js';

const $ = (id) => document.getElementById(id);
const PALETTE = ['#2563eb', '#dc2626', '#059669', '#d97706', '#7c3aed', '#0891b2', '#db2777', '#4b5563'];
const METRICS = [
  ['e_max_deg', 'e_max', '°', 'max |e| after the transient'],
  ['e_final_deg', 'e_final', '°', 'max |e| over the last reference period'],
  ['e_rms_deg', 'e_rms', '°', 'RMS of e after the transient'],
  ['u_max', 'u_max', 'V', 'max |u| over the run'],
  ['u_rms', 'u_rms', 'V', 'RMS of u after the transient'],
  ['chattering', 'chattering', '', 'L2[Δu]/L2[u] after the transient'],
  ['w_norm_max', '‖W‖ max', '', 'largest norm of the network weights'],
];
const DEFAULT_SIGNALS = ['sigma', 'w_norm'];

const state = {
  catalog: null,
  scenario: null, // id
  kind: null,
  base: {}, // key -> number | null, the scenario's own values under `kind`
  fields: {}, // key -> {param, input, slider, error}
  shown: new Set(), // signal keys plotted
  charts: [],
  layoutKey: '',
  lastGood: null,
  pending: false,
};

// ---------- numbers ----------
const fmt = (v) => {
  if (v === null || v === undefined) return '';
  if (v === 0) return '0';
  const a = Math.abs(v);
  if (a >= 1e5 || a < 1e-3) return v.toExponential(3).replace(/\.?0+e/, 'e');
  return String(Number(v.toPrecision(4)));
};
const metricText = (v) => (v === null || v === undefined ? '–' : Number(v.toPrecision(4)).toString());
const SLIDER_STEPS = 1000;
const toSlider = (p, v) => {
  if (v === null || !Number.isFinite(v)) return SLIDER_STEPS / 2;
  const f = p.log
    ? (Math.log10(Math.max(v, p.low)) - Math.log10(p.low)) / (Math.log10(p.high) - Math.log10(p.low))
    : (v - p.low) / (p.high - p.low);
  return Math.round(Math.min(1, Math.max(0, f)) * SLIDER_STEPS);
};
const fromSlider = (p, s) => {
  const f = s / SLIDER_STEPS;
  return p.log ? 10 ** (Math.log10(p.low) + f * (Math.log10(p.high) - Math.log10(p.low))) : p.low + f * (p.high - p.low);
};

// ---------- the URL ----------
function readHash() {
  const q = new URLSearchParams(location.hash.slice(1));
  const out = { scenario: q.get('scenario'), kind: q.get('kind'), values: {}, signals: q.get('signals') };
  for (const [k, v] of q) if (k.includes('.')) out.values[k] = v;
  return out;
}
function writeHash() {
  const q = new URLSearchParams();
  q.set('scenario', state.scenario);
  q.set('kind', state.kind);
  for (const [k, v] of overrides()) if (k !== 'controller.kind') q.set(k, v);
  q.set('signals', [...state.shown].join(','));
  history.replaceState(null, '', '#' + q.toString());
}

// ---------- controls ----------
function overrides() {
  const out = [['controller.kind', state.kind]];
  for (const [key, f] of Object.entries(state.fields)) {
    const text = f.input.value.trim();
    const base = state.base[key];
    if (base === null && text === '') continue; // left to the law's own design
    if (base !== null && text !== '' && Number(text) === base) continue;
    out.push([key, f.input.value]);
  }
  return out;
}

function paramRow(p, container) {
  const row = document.createElement('div');
  row.className = 'param';
  row.dataset.key = p.key;
  const label = document.createElement('label');
  label.textContent = p.name;
  label.title = `${p.key}: ${p.log ? 'log' : 'linear'} slider over [${p.low}, ${p.high}]`;
  const range = document.createElement('span');
  range.className = 'range';
  range.textContent = `${fmt(p.low)} – ${fmt(p.high)}${p.log ? ' (log)' : ''}`;
  const slider = document.createElement('input');
  slider.type = 'range';
  slider.min = 0;
  slider.max = SLIDER_STEPS;
  slider.step = 1;
  slider.setAttribute('aria-label', `${p.key} slider`);
  const input = document.createElement('input');
  input.type = 'text';
  input.inputMode = 'decimal';
  input.spellcheck = false;
  input.setAttribute('aria-label', p.key);
  const error = document.createElement('div');
  error.className = 'error';
  error.setAttribute('role', 'alert');
  label.htmlFor = input.id = 'f-' + p.key.replace('.', '-');
  const head = document.createElement('div');
  head.className = 'param-head';
  head.append(label, range);
  const line = document.createElement('div');
  line.className = 'param-line';
  line.append(slider, input);
  row.append(head, line, error);
  container.append(row);
  slider.addEventListener('input', () => {
    input.value = fmt(fromSlider(p, Number(slider.value)));
    schedule();
  });
  input.addEventListener('input', () => {
    const v = Number(input.value.trim());
    if (input.value.trim() !== '' && Number.isFinite(v)) slider.value = toSlider(p, v);
    schedule();
  });
  state.fields[p.key] = { param: p, input, slider, error, row };
}

function setValues(values) {
  for (const [key, f] of Object.entries(state.fields)) {
    const v = key in values ? values[key] : null;
    // A number is shown exactly (String, the shortest round trip), so that
    // a scenario's own value is not sent back rounded as a change.
    const text = typeof v === 'string' ? v : v === null || v === undefined ? '' : String(v);
    f.input.value = text;
    const n = Number(text);
    f.slider.value = toSlider(f.param, text === '' || !Number.isFinite(n) ? null : n);
    f.input.placeholder = state.base[key] === null ? 'auto (designed)' : '';
  }
}

function call(fn, ...args) {
  return JSON.parse(fn(...args));
}

function loadKind(kind, given = {}) {
  state.kind = kind;
  $('kind').value = kind;
  const r = call(wasm.base_values, state.scenario, kind);
  state.base = r.ok ? r.value : {};
  const info = state.catalog.kinds.find((k) => k.kind === kind);
  state.fields = {};
  $('controller-params').replaceChildren();
  $('uncertainty-params').replaceChildren();
  if (info.params.length === 0) $('controller-params').innerHTML = '<p class="desc">No declared tunables.</p>';
  // A declared range is where the slider explores; it is widened to hold
  // the scenario's own value (as the validator does: playground.rs
  // `Param::including`), e.g. a cylinder's P gain beyond the paper's scale.
  const including = (p) => {
    const b = state.base[p.key];
    if (typeof b !== 'number' || !Number.isFinite(b) || (p.log && b <= 0)) return p;
    return { ...p, low: Math.min(p.low, b), high: Math.max(p.high, b) };
  };
  for (const p of info.params) paramRow(including(p), $('controller-params'));
  for (const p of state.catalog.uncertainty) paramRow(including(p), $('uncertainty-params'));
  setValues({ ...state.base, ...given });
  // Signals: what the kind writes; σ and ‖W‖ first when it has them.
  const keys = info.signals.map((s) => s.key);
  if (![...state.shown].some((k) => keys.includes(k))) {
    state.shown = new Set(DEFAULT_SIGNALS.filter((k) => keys.includes(k)));
    if (state.shown.size === 0) keys.slice(0, 2).forEach((k) => state.shown.add(k));
  }
  const picker = $('signal-picker');
  picker.replaceChildren();
  const lead = document.createElement('span');
  lead.className = 'picker-lead';
  lead.textContent = `${kind} signals:`;
  picker.append(lead);
  for (const s of info.signals) {
    const b = document.createElement('button');
    b.type = 'button';
    b.className = 'chip' + (state.shown.has(s.key) ? ' on' : '');
    b.textContent = s.key;
    b.title = `${s.doc}${s.unit ? ' (' + s.unit + ')' : ''}`;
    b.dataset.signal = s.key;
    b.addEventListener('click', () => {
      if (state.shown.has(s.key)) state.shown.delete(s.key);
      else state.shown.add(s.key);
      b.classList.toggle('on');
      if (state.lastGood) draw(state.lastGood, true);
      writeHash();
    });
    picker.append(b);
  }
}

function loadScenario(id, kind, given) {
  state.scenario = id;
  $('scenario').value = id;
  const s = state.catalog.scenarios.find((x) => x.id === id);
  $('scenario-desc').textContent = s.description || s.path;
  $('scenario-desc').title = s.path;
  loadKind(kind || s.kind, given);
}

// ---------- running ----------
// The trace's numbers come as one Float64Array, series after series.
function unpack(run, flat) {
  const n = run.points;
  const at = (i) => flat.subarray(i * n, (i + 1) * n);
  const idx = (k) => run.series.indexOf(k);
  run.trace = { t: at(0), theta_d: at(1), theta: at(2), e: at(3), u: at(4),
    signals: run.trace.signals.map((s) => ({ ...s, values: at(idx(s.key)) })) };
  return run;
}

// One run per frame, however many input events came in it. body's
// data-pending is "true" from the first event until that run is shown, so a
// test (or a script) can wait for the page to settle on its inputs.
function schedule() {
  if (state.pending) return;
  state.pending = true;
  document.body.dataset.pending = 'true';
  requestAnimationFrame(() => {
    state.pending = false;
    try {
      rerun();
    } finally {
      document.body.dataset.pending = 'false';
    }
  });
}

function showErrors(errors) {
  for (const f of Object.values(state.fields)) {
    f.error.textContent = '';
    f.row.classList.remove('bad');
  }
  const general = [];
  for (const e of errors) {
    const f = state.fields[e.key];
    if (f) {
      f.error.textContent = e.reason;
      f.row.classList.add('bad');
    } else general.push(e.key ? `${e.key}: ${e.reason}` : e.reason);
  }
  return general;
}

function rerun() {
  writeHash();
  const ov = JSON.stringify(overrides());
  const t0 = performance.now();
  const r = call(wasm.simulate, state.scenario, ov);
  if (r.ok) unpack(r.value, wasm.last_trace());
  const t1 = performance.now();
  if (!r.ok) {
    const general = showErrors(r.errors);
    setStatus('bad', general.length ? general.join('; ') : 'invalid input: the last good run is shown');
    document.body.dataset.state = 'invalid';
    return;
  }
  showErrors([]);
  const run = r.value;
  state.lastGood = run;
  draw(run, false);
  const t2 = performance.now();
  $('t-sim').textContent = `${(t1 - t0).toFixed(2)} ms`;
  $('t-sim').dataset.ms = String(t1 - t0);
  $('t-draw').textContent = `${(t2 - t1).toFixed(1)} ms`;
  if (run.divergence) setStatus('diverged', run.divergence);
  else setStatus('ok', `bounded · ${run.steps} steps · ${run.kind}`);
  document.body.dataset.state = 'ok';
}

function setStatus(kind, text) {
  const s = $('status');
  s.className = 'status ' + kind;
  s.textContent = text;
}

// ---------- drawing ----------
function metricsCards(run) {
  const box = $('metrics');
  box.replaceChildren();
  // A linear axis's errors are e_max, e_final, e_rms in mm (run.unit); a
  // rotary one's e_max_deg, ... in degrees.
  const linear = run.unit === 'mm';
  for (const [rotaryKey, label, rotaryUnit, doc] of METRICS) {
    const angle = rotaryKey.endsWith('_deg');
    const key = linear && angle ? rotaryKey.slice(0, -4) : rotaryKey;
    const unit = linear && angle ? 'mm' : rotaryUnit;
    const v = run.metrics[key];
    if ((v === null || v === undefined) && key.startsWith('w_norm')) continue;
    const card = document.createElement('div');
    card.className = 'metric' + (rotaryKey === 'e_max_deg' ? ' headline' : '');
    card.dataset.metric = key;
    card.dataset.value = v === null || v === undefined ? '' : JSON.stringify(v);
    card.title = doc;
    card.innerHTML = `<span class="m-label"></span><span class="m-value"></span>`;
    card.querySelector('.m-label').textContent = label;
    card.querySelector('.m-value').textContent = metricText(v) + (v === null || v === undefined ? '' : unit ? ' ' + unit : '');
    box.append(card);
  }
}

function chartSpecs(run) {
  const tr = run.trace;
  // The position's letter and unit follow the plant's axis.
  const [p, unit] = run.unit === 'mm' ? ['y', 'mm'] : ['θ', 'deg'];
  const specs = [
    { title: `${p}d and ${p}`, unit, series: [
      { label: `${p}d`, data: tr.theta_d, stroke: '#94a3b8', dash: [6, 4] },
      { label: p, data: tr.theta, stroke: PALETTE[0] },
    ] },
    { title: `tracking error e = ${p}d − ${p}`, unit, series: [{ label: 'e', data: tr.e, stroke: PALETTE[1] }] },
    { title: 'control u', unit: 'V', series: [{ label: 'u', data: tr.u, stroke: PALETTE[2] }] },
  ];
  let c = 3;
  for (const s of tr.signals) {
    if (!state.shown.has(s.key)) continue;
    specs.push({ title: `${s.key} — ${s.doc}`, unit: s.unit, series: [{ label: s.key, data: s.values, stroke: PALETTE[c++ % PALETTE.length] }] });
  }
  return specs;
}

// The width of a grid cell of #charts, less the figure's padding.
function chartWidth() {
  const cell = document.querySelector('#charts .chart');
  return Math.max(300, (cell ? cell.clientWidth : $('charts').clientWidth) - 10);
}

function draw(run, force) {
  metricsCards(run);
  const specs = chartSpecs(run);
  const key = specs.map((s) => s.title).join('|');
  const data = (s) => [run.trace.t, ...s.series.map((x) => x.data)];
  if (!force && key === state.layoutKey && state.charts.length === specs.length) {
    state.charts.forEach((ch, i) => ch.setData(data(specs[i])));
    return;
  }
  state.charts.forEach((ch) => ch.destroy());
  state.charts = [];
  state.layoutKey = key;
  const box = $('charts');
  box.replaceChildren();
  const cells = specs.map(() => {
    const cell = document.createElement('figure');
    cell.className = 'chart';
    box.append(cell);
    return cell;
  });
  const width = chartWidth();
  for (const [i, s] of specs.entries()) {
    const cell = cells[i];
    const opts = {
      title: s.title,
      width,
      height: 210,
      cursor: { sync: { key: 'ehservo' } },
      legend: { live: true },
      scales: { x: { time: false } },
      axes: [
        { label: 't (s)', labelSize: 18, size: 36, grid: { stroke: '#eef1f5' } },
        { label: s.unit || '', labelSize: 18, size: 62, grid: { stroke: '#eef1f5' } },
      ],
      series: [{ label: 't', value: (u, v) => (v === null ? '–' : v.toFixed(3) + ' s') },
        ...s.series.map((x) => ({ label: x.label, stroke: x.stroke, width: 1.5, dash: x.dash,
          value: (u, v) => (v === null ? '–' : fmt(v)) }))],
    };
    state.charts.push(new uPlot(opts, data(s), cell));
  }
}

new ResizeObserver(() => {
  const w = chartWidth();
  state.charts.forEach((ch) => ch.setSize({ width: w, height: 210 }));
}).observe(document.getElementById('charts'));

// ---------- actions ----------
function download() {
  const r = call(wasm.scenario_toml, state.scenario, JSON.stringify(overrides()));
  if (!r.ok) {
    showErrors(r.errors);
    setStatus('bad', 'fix the highlighted fields to download the scenario');
    return;
  }
  const name = (state.lastGood?.name || 'scenario').replace(/[^A-Za-z0-9_.-]/g, '_');
  const blob = new Blob([r.value], { type: 'application/toml' });
  const a = document.createElement('a');
  a.href = URL.createObjectURL(blob);
  a.download = `${name}-playground.toml`;
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 1000);
}

// The median time of `n` Fig. 2 runs (paper/fig2 as it is), each timed
// with performance.now() around the wasm call (validation + run + trace).
function benchmark(n = 50) {
  const times = [];
  const ov = JSON.stringify([]);
  for (let i = 0; i < n; i++) {
    const t0 = performance.now();
    const r = call(wasm.simulate, 'paper/fig2', ov);
    if (r.ok) unpack(r.value, wasm.last_trace());
    times.push(performance.now() - t0);
    if (!r.ok) throw new Error('fig2 failed: ' + JSON.stringify(r.errors));
  }
  times.sort((a, b) => a - b);
  const med = times[Math.floor(n / 2)];
  $('t-bench').textContent = `median ${med.toFixed(2)} ms (min ${times[0].toFixed(2)}, n = ${n})`;
  $('t-bench').dataset.ms = String(med);
  return { median: med, min: times[0], max: times[n - 1], n };
}

async function main() {
  await init();
  state.catalog = JSON.parse(wasm.catalog());
  const sel = $('scenario');
  for (const group of ['paper', 'realistic']) {
    const og = document.createElement('optgroup');
    og.label = group === 'paper' ? "The paper's cases" : 'Realistic loops';
    for (const s of state.catalog.scenarios.filter((x) => x.id.startsWith(group + '/'))) {
      const o = document.createElement('option');
      o.value = s.id;
      o.textContent = `${s.id.split('/')[1]} — ${s.description || s.name}`.slice(0, 80);
      og.append(o);
    }
    sel.append(og);
  }
  for (const k of state.catalog.kinds) {
    const o = document.createElement('option');
    o.value = k.kind;
    o.textContent = k.kind;
    $('kind').append(o);
  }
  const h = readHash();
  const known = state.catalog.scenarios.some((s) => s.id === h.scenario);
  if (h.signals !== null) state.shown = new Set(h.signals.split(',').filter(Boolean));
  const kind = state.catalog.kinds.some((k) => k.kind === h.kind) ? h.kind : null;
  loadScenario(known ? h.scenario : 'paper/fig2', known ? kind : null, known ? h.values : {});
  sel.addEventListener('change', () => { state.shown = new Set(); loadScenario(sel.value); draw(state.lastGood ?? { metrics: {}, trace: { t: [], signals: [] } }, true); rerun(); });
  $('kind').addEventListener('change', () => { loadKind($('kind').value); rerun(); });
  $('reset').addEventListener('click', () => { loadScenario(state.scenario, null, {}); rerun(); });
  $('copy-link').addEventListener('click', async () => {
    writeHash();
    try { await navigator.clipboard.writeText(location.href); setStatus('ok', 'link copied'); } catch { setStatus('ok', 'copy the address bar: it holds the set-up'); }
  });
  $('download').addEventListener('click', download);
  $('bench').addEventListener('click', () => benchmark(50));
  rerun();
  window.playground = { benchmark, overrides, state };
  document.body.dataset.ready = 'true';
}

main().catch((e) => {
  setStatus('bad', 'failed to start: ' + e);
  console.error(e);
});
