// MedSpring in the browser (docs/web.md): the C++ engine as WebAssembly (dist/medspring.mjs), a three.js
// view, and a fixed 1 ms physics tick caught up against the wall clock; every animation frame renders the
// surface of the last tick. Left-drag on the surface presses and slides a rigid spherical probe (the
// default; docs/tools.md), closes a grasper's jaws on the surface and pulls, or pulls the picked node
// through a virtual-coupling spring (docs/haptics.md); the arrow is the force on the tissue. Tests drive
// the page through window.medspring.
// The page's modules (web/app/): state.js (constants, state, banners), scene.js (three.js view),
// interaction.js (picking, probe, grasp, node pull), panel.js (sliders, model list, overlay), models.js
// (model loading); this file runs the physics loop and starts the page.
import * as THREE from 'three';
import { $, S, TICK_MS, MAX_CATCHUP_TICKS, F_MAX, B_VC, K_VC0, errorText, showError, showMessage } from './app/state.js';
import { renderer, scene, camera, controls, makeScene, refreshGeometry, canvasStats, project } from './app/scene.js';
import { pickAt, toolSizes, onPointerDown, onPointerMove, onPointerUp, updateGrasp, setMode } from './app/interaction.js';
import { logSlider, sliderParams, showParamValues, setSlidersTo, onParamInput, applyPendingParams, showToolValues, stats, drawOverlay } from './app/panel.js';
import { loadModelList, loadModel } from './app/models.js';

// ---------------------------------------------------------------- the loop
// Physics: fixed 1 ms ticks caught up against the wall clock by a pump that runs every millisecond or so
// (setInterval; the browser clamps it to ~1-4 ms) and before every frame, independently of the frame
// rate; a lag of more than MAX_CATCHUP_TICKS (a stalled tab, a slow frame) is dropped, not replayed.
// Rendering: every animation frame draws the surface after the last tick.
function pump() {
  const now = performance.now();
  if (!S.engine || S.loading || S.paused) { S.last = now; return; }
  applyPendingParams();
  S.pending += Math.max(0, now - (S.last ?? now));
  S.last = now;
  let n = Math.floor(S.pending / TICK_MS);
  if (n > MAX_CATCHUP_TICKS) {
    S.dropped += n - MAX_CATCHUP_TICKS;
    n = MAX_CATCHUP_TICKS;
    S.pending = 0;
  } else {
    S.pending -= n * TICK_MS;
  }
  if (n <= 0) return;
  const e = S.engine;
  updateGrasp(now);
  const t0 = performance.now();
  e.ticks(n);
  const wall = performance.now() - t0;
  S.ticks += n;
  S.batches.push([now, n, wall]);
  while (S.batches.length && now - S.batches[0][0] > 1000) S.batches.shift();
  const msg = e.message();
  if (msg) {
    e.clearMessage();
    if (S.drag) S.drag = null;
    showMessage(`${msg} (${e.autoResets()} automatic reset${e.autoResets() === 1 ? '' : 's'})`);
  }
}

function frame(now) {
  requestAnimationFrame(frame);
  if (!S.engine || S.loading) return;
  pump();
  if (S.messageUntil && now > S.messageUntil) { $('message').hidden = true; S.messageUntil = 0; }
  S.frameTimes.push(now);
  while (S.frameTimes.length && now - S.frameTimes[0] > 1000) S.frameTimes.shift();
  const F = S.engine.reaction();
  S.forces.push([now, Math.hypot(F[0], F[1], F[2])]);
  while (S.forces.length && now - S.forces[0][0] > 5000) S.forces.shift();
  const r0 = performance.now();
  refreshGeometry();
  controls.update();
  renderer.render(scene, camera);
  S.renderMs.push(performance.now() - r0);
  if (S.renderMs.length > 60) S.renderMs.shift();
  if (now - (S.overlayAt || 0) > 100) { S.overlayAt = now; drawOverlay(); }
}

// ---------------------------------------------------------------- bench hook
/// Benchmark: a trajectory replay (per-tick compute, as `medspring haptics`) and a pressed batch.
function bench({ model = 'kidney_phantom', csv, contact = 223, local = false, batch = 2000 } = {}) {
  const out = {};
  if (csv) {
    const e = new S.ms.Engine(model, true, local);
    e.benchTrajectory(csv, contact);  // warm-up
    e.reset();
    out.trajectory = e.benchTrajectory(csv, contact);
    out.trajectory.times = Array.from(out.trajectory.times);
    e.delete();
  }
  const e = new S.ms.Engine(model, true, local);
  e.grab(contact, K_VC0, B_VC, F_MAX);
  const t = e.tool();
  e.moveTool(t[0], t[1], t[2] - 3);
  e.ticks(200);
  const t0 = performance.now();
  e.ticks(batch);
  out.batch = { ticks: batch, meanUs: (1000 * (performance.now() - t0)) / batch, stats: e.tickStats() };
  e.delete();
  out.crossOriginIsolated = self.crossOriginIsolated;
  return out;
}

// ---------------------------------------------------------------- start
export async function start() {
  const api = {
    THREE,
    get module() { return S.ms; },
    get engine() { return S.engine; },
    get model() { return S.model; },
    get models() { return S.models; },
    get camera() { return camera; },
    get renderer() { return renderer; },
    get error() { return S.error; },
    get message() { return S.message; },
    get ready() { return !!S.engine && !S.loading; },
    set paused(v) { S.paused = !!v; },
    get mode() { return S.mode; },
    loadModel, pickAt, project, stats, canvasStats, bench, setMode, toolSizes,
  };
  window.medspring = api;
  makeScene();
  let createMedSpring;
  try {
    ({ default: createMedSpring } = await import('./dist/medspring.mjs'));
    S.ms = await createMedSpring();
  } catch (err) {
    showError(`Could not load the engine (dist/medspring.mjs — build it with web/build.sh): ${errorText(err)}`);
    renderer.render(scene, camera);
    return;
  }
  api.failed = undefined;

  const canvas = renderer.domElement;
  canvas.addEventListener('pointerdown', onPointerDown);
  canvas.addEventListener('pointermove', onPointerMove);
  canvas.addEventListener('pointerup', onPointerUp);
  canvas.addEventListener('pointercancel', onPointerUp);
  canvas.addEventListener('lostpointercapture', onPointerUp);
  $('model').addEventListener('change', (ev) => loadModel(ev.target.value));
  $('error').addEventListener('click', () => showError(''));  // dismiss
  $('local').addEventListener('change', (ev) => {
    try { S.engine.setLocal(ev.target.checked); } catch (err) { showError(errorText(err)); }
  });
  for (const id of ['k', 'eta', 'kr', 'beta']) $(id).addEventListener('input', onParamInput);
  $('nonlinear').addEventListener('change', onParamInput);
  $('defaults').addEventListener('click', () => {
    setSlidersTo({ ...S.defaults, nonlinear: $('nonlinear').checked });
    onParamInput();
  });
  $('kvc').addEventListener('input', () => { S.kvc = logSlider('kvc', K_VC0); showParamValues(sliderParams()); });
  $('reset').addEventListener('click', () => { S.drag = null; S.engine.reset(); });
  $('mode').addEventListener('change', (ev) => setMode(ev.target.value));
  for (const id of ['radius', 'depth', 'friction']) $(id).addEventListener('input', showToolValues);
  const m = new URLSearchParams(location.search).get('mode');
  if (m) setMode(m);

  await loadModelList();
  const wanted = new URLSearchParams(location.search).get('model');
  const first = S.models.find((m) => m.id === wanted) || S.models[0];
  await loadModel(first.id);
  setInterval(pump, 1);
  requestAnimationFrame(frame);
}
