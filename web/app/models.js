// Model loading (docs/web.md): the list from models/models.json (`medspring export --web`) plus the
// built-in phantoms, and one model's engine (a package fetched from models/, or a built-in).
import { $, S, K_VC0, BUILTINS, errorText, showError } from './state.js';
import { buildModelObjects } from './scene.js';
import { setSlidersTo, showToolValues, fillModelSelect } from './panel.js';

// models/models.json from `medspring export --web` (an array, or {models: [...]}); the built-in phantoms
// are always offered too, and are all there is when the list is missing.
export async function loadModelList() {
  let list = [];
  try {
    const res = await fetch('models/models.json', { cache: 'no-store' });
    if (res.ok) {
      const j = await res.json();
      const arr = Array.isArray(j) ? j : j.models;
      if (!Array.isArray(arr)) throw new Error('models.json: expected a list of models');
      list = arr.filter((m) => m && typeof m.file === 'string').map((m) => ({
        id: m.file, file: m.file, name: m.name || m.file, kind: m.kind || '', description: m.description || '',
      }));
    }
  } catch (err) {
    showError(`Could not read models/models.json: ${errorText(err)} (built-in models only)`);
  }
  S.models = [...list, ...BUILTINS];
  fillModelSelect();
}

/// Loads a model by id (a models.json file or builtin:NAME). On failure the page keeps (or falls back
/// to) a working model and shows the error; returns whether the requested model loaded.
export async function loadModel(id) {
  const entry = S.models.find((m) => m.id === id);
  if (!entry) {
    showError(`Unknown model '${id}'`);
    return false;
  }
  S.loading = true;
  let engine = null;
  try {
    if (entry.builtin) {
      engine = new S.ms.Engine(entry.builtin, $('nonlinear').checked, $('local').checked);
    } else {
      const url = `models/${entry.file.split('/').map(encodeURIComponent).join('/')}`;
      const res = await fetch(url, { cache: 'no-store' });
      if (!res.ok) throw new Error(`${url}: HTTP ${res.status} ${res.statusText}`);
      const bytes = new Uint8Array(await res.arrayBuffer());
      engine = new S.ms.Engine(bytes, $('nonlinear').checked, $('local').checked);
    }
  } catch (err) {
    S.loading = false;
    const where = entry.file ? `models/${entry.file}` : entry.builtin;
    const text = `Could not load the model "${entry.name}" (${where}): ${errorText(err)}`;
    // Never a blank canvas: without a running model, fall back to the kidney phantom.
    if (!S.engine && entry.id !== BUILTINS[0].id) await loadModel(BUILTINS[0].id);
    showError(text);
    if (S.model) $('model').value = S.model.id;
    return false;
  }
  if (S.drag) S.drag = null;
  if (S.engine) S.engine.delete();
  S.engine = engine;
  S.model = entry;
  S.defaults = engine.params();
  S.kvc = K_VC0;
  $('kvc').value = 0;
  setSlidersTo(S.defaults);
  $('model').value = entry.id;
  $('model-desc').textContent =
    `${entry.description || engine.description()} — ${engine.numSurfaceNodes()} surface nodes, ` +
    `${engine.numMasses()} masses, ${engine.numSprings()} springs`;
  buildModelObjects();
  showToolValues();
  showError('');
  // a notice about the previous model (a divergence reset) does not carry over to this one
  $('message').hidden = true;
  S.messageUntil = 0;
  S.ticks = 0;
  S.batches = [];
  S.forces = [];
  S.pending = 0;
  S.last = performance.now();
  S.loading = false;
  return true;
}
