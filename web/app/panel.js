// The side panel and the overlay (docs/web.md): tissue parameter sliders (applied by the physics pump),
// tool sizes, the model list, and the overlay's timings and force plot.
import { $, S, errorText, showError } from './state.js';
import { toolSizes } from './interaction.js';

// ---------------------------------------------------------------- panel
export const logSlider = (id, base) => base * Math.pow(10, Number($(id).value));
export function sliderParams() {
  const d = S.defaults;
  return {
    k: logSlider('k', d.k),
    eta: Number($('eta').value),
    kr: logSlider('kr', d.kr > 0 ? d.kr : 0.02),
    beta: logSlider('beta', d.beta > 0 ? d.beta : 0.5),
    nonlinear: $('nonlinear').checked,
  };
}
export function showParamValues(p) {
  $('k-val').textContent = `${p.k.toPrecision(3)} N/mm`;
  $('eta-val').textContent = p.eta.toFixed(2);
  $('kr-val').textContent = `${p.kr.toPrecision(3)} N/mm`;
  $('beta-val').textContent = `${p.beta.toPrecision(3)} /ms`;
  $('kvc-val').textContent = `${S.kvc.toPrecision(3)} N/mm`;
}
export function setSlidersTo(p) {
  const d = S.defaults;
  $('k').value = Math.log10(p.k / d.k);
  $('eta').value = p.eta;
  $('kr').value = Math.log10(p.kr / (d.kr > 0 ? d.kr : 0.02)) || 0;
  $('beta').value = Math.log10(p.beta / (d.beta > 0 ? d.beta : 0.5)) || 0;
  $('nonlinear').checked = p.nonlinear;
  showParamValues(p);
}

export function onParamInput() {
  if (!S.engine) return;
  S.pendingParams = sliderParams();
  showParamValues(S.pendingParams);
}

export function applyPendingParams() {
  if (!S.pendingParams) return;
  const p = S.pendingParams;
  S.pendingParams = null;
  try {
    S.engine.setParams(p);
    if (S.drag && S.drag.mode !== 'pull') S.drag = null;  // the rebuilt engine removed the rigid tool
    if (S.error.startsWith('Parameters:')) showError('');
  } catch (err) {
    showError(`Parameters: ${errorText(err)}`);
  }
}

export function fillModelSelect() {
  const sel = $('model');
  sel.innerHTML = '';
  const groups = new Map();
  for (const m of S.models) {
    const g = m.builtin ? 'built-in' : 'model files';
    if (!groups.has(g)) {
      const og = document.createElement('optgroup');
      og.label = g;
      groups.set(g, og);
      sel.appendChild(og);
    }
    const o = document.createElement('option');
    o.value = m.id;
    o.textContent = m.name;
    groups.get(g).appendChild(o);
  }
}
export function showToolValues() {
  if (!S.size) return;
  const sz = toolSizes();
  $('radius-val').textContent = `${sz.radius.toFixed(1)} mm`;
  $('depth-val').textContent = `${sz.depth.toFixed(1)} mm`;
  $('friction-val').textContent = Number($('friction').value).toFixed(2);
}

// ---------------------------------------------------------------- overlay
export function stats() {
  const e = S.engine;
  const b = S.batches;
  const span = b.length > 1 ? b[b.length - 1][0] - b[0][0] : 0;
  const ticksInWindow = b.slice(1).reduce((s, [, n]) => s + n, 0);
  const ticksAll = b.reduce((s, [, n]) => s + n, 0), wallAll = b.reduce((s, [, , w]) => s + w, 0);
  const ts = e ? e.tickStats() : {};
  const isolated = !!self.crossOriginIsolated;
  return {
    model: S.model ? S.model.id : null,
    ticks: S.ticks,
    dropped: S.dropped,
    ticksPerSecond: span > 0 ? (1000 * ticksInWindow) / span : 0,
    fps: S.frameTimes.length > 1 ? (1000 * (S.frameTimes.length - 1)) / (S.frameTimes[S.frameTimes.length - 1] - S.frameTimes[0]) : 0,
    // C++ compute time per tick (steady_clock = performance.now: 5 us resolution when cross-origin
    // isolated, as `medspring view` serves the page; 100 us otherwise)
    medianTickUs: ts.median ?? NaN,
    p99TickUs: ts.p99 ?? NaN,
    meanTickUs: ts.mean ?? NaN,
    wallTickUs: ticksAll > 0 ? (1000 * wallAll) / ticksAll : NaN,  // JS wall time per tick over the last second
    crossOriginIsolated: isolated,
    renderMs: S.renderMs.length ? [...S.renderMs].sort((a, b) => a - b)[S.renderMs.length >> 1] : NaN,
    reaction: e ? e.reaction() : [0, 0, 0],
    grabbed: e ? e.grabbed() : false,
    mode: S.mode,
    tool: e ? e.toolState() : null,
    maxDisplacement: e ? e.maxDisplacement() : 0,
  };
}

export function drawOverlay() {
  const st = stats();
  const f = st.reaction;
  const fm = Math.hypot(f[0], f[1], f[2]);
  const o = $('overlay');
  if (!o.querySelector('canvas')) {
    o.innerHTML = '<div id="ov-text"></div><canvas id="plot" width="250" height="60"></canvas>';
  }
  const tick = st.crossOriginIsolated ? `median <b>${st.medianTickUs.toFixed(1)} µs</b> · wall ${st.wallTickUs.toFixed(1)} µs`
    : `wall <b>${st.wallTickUs.toFixed(1)} µs</b>`;
  $('ov-text').innerHTML =
    `tick (1 ms) ${tick}<br>` +
    `physics <b>${st.ticksPerSecond.toFixed(0)} ticks/s</b> · ${st.fps.toFixed(0)} fps` +
    (st.dropped ? ` · ${st.dropped} ticks dropped` : '') + '<br>' +
    `reaction <b>${fm.toFixed(3)} N</b> (${f.map((v) => v.toFixed(3)).join(', ')})<br>` +
    `max |u| ${st.maxDisplacement.toFixed(3)} mm · t ${(S.engine.time() / 1000).toFixed(1)} s`;
  const c = $('plot'), g = c.getContext('2d');
  g.clearRect(0, 0, c.width, c.height);
  g.fillStyle = 'rgba(255,255,255,0.06)';
  g.fillRect(0, 0, c.width, c.height);
  const top = Math.max(0.05, ...S.forces.map(([, v]) => v)) * 1.1;
  const now = performance.now();
  g.strokeStyle = '#ffd24a';
  g.beginPath();
  S.forces.forEach(([t, v], i) => {
    const x = (1 - (now - t) / 5000) * (c.width - 1), y = c.height - 1 - (v / top) * (c.height - 2);
    if (i) g.lineTo(x, y); else g.moveTo(x, y);
  });
  g.stroke();
  g.fillStyle = '#9aa5b4';
  g.font = '10px monospace';
  g.fillText(`|F| (N), last 5 s, max ${top.toFixed(2)}`, 4, 10);
}
