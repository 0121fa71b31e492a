// The wasm engine replays a tool trajectory through the haptic loop and must reproduce the native
// `medspring haptics` force trace (contact positions and reactions) to 1e-9 relative.
// Usage: node web/test/wasm_matches_native.mjs TRAJECTORY.csv NATIVE_TRACE.csv CONTACT_NODE [MODEL]
import { readFileSync } from 'node:fs';
import { fileURLToPath } from 'node:url';
import path from 'node:path';

const [trajFile, traceFile, contactArg, model = 'kidney_phantom'] = process.argv.slice(2);
if (!trajFile || !traceFile || contactArg === undefined) {
  console.error('usage: node wasm_matches_native.mjs TRAJECTORY.csv NATIVE_TRACE.csv CONTACT_NODE [MODEL]');
  process.exit(2);
}
const here = path.dirname(fileURLToPath(import.meta.url));
// emscripten 3.1.6's ES module expects CommonJS globals under node
globalThis.__dirname = path.join(here, '..', 'dist');
globalThis.require = (await import('node:module')).createRequire(import.meta.url);
const { default: createMedSpring } = await import(path.join(here, '..', 'dist', 'medspring.mjs'));
const ms = await createMedSpring();
const engine = new ms.Engine(model, true, false);
const wasm = engine.runTrajectory(readFileSync(trajFile, 'utf8'), Number(contactArg));

const rows = readFileSync(traceFile, 'utf8').trim().split('\n').slice(1).map((l) => l.split(',').map(Number));
if (wasm.length !== rows.length * 7) {
  console.error(`FAIL: wasm gave ${wasm.length / 7} ticks, native ${rows.length}`);
  process.exit(1);
}
// native columns: time, tool xyz, contact xyz, reaction xyz, saturated, compute_us
let scaleX = 0, scaleF = 0;
for (const r of rows) {
  for (let c = 0; c < 3; ++c) { scaleX = Math.max(scaleX, Math.abs(r[4 + c])); scaleF = Math.max(scaleF, Math.abs(r[7 + c])); }
}
let worstX = 0, worstF = 0;
rows.forEach((r, k) => {
  if (Math.abs(wasm[7 * k] - r[0]) > 1e-9) { console.error(`FAIL: tick ${k} time ${wasm[7 * k]} vs ${r[0]}`); process.exit(1); }
  for (let c = 0; c < 3; ++c) {
    worstX = Math.max(worstX, Math.abs(wasm[7 * k + 1 + c] - r[4 + c]) / scaleX);
    worstF = Math.max(worstF, Math.abs(wasm[7 * k + 4 + c] - r[7 + c]) / scaleF);
  }
});
console.log(`${rows.length} ticks: max relative difference contact ${worstX.toExponential(2)}, reaction ${worstF.toExponential(2)} (tolerance 1e-9)`);
if (!(worstX <= 1e-9 && worstF <= 1e-9) || scaleF === 0) { console.error('FAIL'); process.exit(1); }
console.log('PASS');
