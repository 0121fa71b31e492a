// The page's shared state (docs/web.md): constants, the built-in models, the state object S, and the
// error and message banners. Imported by every module of the page (web/app.js and web/app/).

export const TICK_MS = 1;            // physics tick (two 0.5 ms updates of the engine)
export const MAX_CATCHUP_TICKS = 100; // at most this many ticks per pump; a longer lag is dropped
export const F_MAX = 3;              // N, device maximum of the coupling force
export const B_VC = 0.01;            // N ms/mm, coupling damping
export const K_VC0 = 0.1;            // N/mm, default coupling stiffness
export const TOOL_STEP = 0.05;       // a rigid tool moves at most this x its radius per 1 ms tick towards the cursor
export const GRASP_OPEN_DEG = 60;    // grasper: jaws open while approaching
export const GRASP_CLOSE_MS = 250;   // then close over this time once the press is reached
export const BUILTINS = [
  { id: 'builtin:kidney_phantom', builtin: 'kidney_phantom', name: 'Kidney phantom (built-in)', kind: 'hybrid',
    description: 'Procedural kidney (§4.1): hybrid, 458 surface nodes + 42 atoms' },
  { id: 'builtin:vessel_phantom', builtin: 'vessel_phantom', name: 'Vessel phantom (built-in)', kind: 'smrm',
    description: 'Straight procedural vessel: SMRM, 40 atoms x 30 spokes' },
  { id: 'builtin:tube', builtin: 'tube', name: 'Mass-spring tube (built-in)', kind: 'surface',
    description: 'Plain surface mass-spring tube: 40 rings x 30 nodes' },
];

export const $ = (id) => document.getElementById(id);
export const errorText = (err) => (err && err.message ? err.message : String(err));

// ---------------------------------------------------------------- state
export const S = {
  ms: null,           // the wasm module
  engine: null,       // the current ms.Engine
  model: null,        // its entry of S.models
  models: [],         // {id, name, kind, description, file | builtin}
  defaults: null,     // the model's tissue parameters as loaded
  pendingParams: null,
  drag: null,         // {mode, node, plane, hit0, tool0, ...} while the left button holds the tool
  mode: 'probe',      // left-drag: 'probe' (sphere), 'grasp' (grasper), 'pull' (node coupling)
  kvc: K_VC0,
  ticks: 0, dropped: 0,
  pending: 0,         // ms of wall clock not yet simulated
  batches: [],        // [performance.now(), ticks, wall ms] of the pumps of the last second
  frameTimes: [],
  renderMs: [],       // main-thread ms of the recent frames (geometry upload + render calls)
  forces: [],         // [time, |F|] of the frames of the last 5 s
  error: '', message: '', messageUntil: 0,
  dispScale: 1,
  loading: false,
};

export function showError(text) {
  S.error = text;
  const e = $('error');
  e.textContent = text;
  e.hidden = !text;
  if (text) console.error(text);
}

export function showMessage(text, ms = 4000) {
  S.message = text;
  S.messageUntil = performance.now() + ms;
  $('message').textContent = text;
  $('message').hidden = false;
}
