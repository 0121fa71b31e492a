// The wasm engine replays a tool path with a rigid tool (Engine.runToolTrajectory) and must reproduce
// the native force trace of `medspring haptics MODEL --trajectory PATH --tool SPEC --friction MU --out DIR`
// (force_trace.csv: tool positions and reactions of every tick) to 1e-9 relative.
//
// Usage: node web/test/wasm_tool_matches_native.mjs PATH.csv NATIVE_TRACE.csv MODEL TOOL_SPEC FRICTION
import { readFileSync } from 'node:fs';
import { loadMedSpring } from './load_engine.mjs';

const [pathFile, traceFile, model, spec, friction] = process.argv.slice(2);
if (!pathFile || !traceFile || !model || !spec || friction === undefined) {
  console.error('usage: node wasm_tool_matches_native.mjs PATH.csv NATIVE_TRACE.csv MODEL TOOL_SPEC FRICTION');
  process.exit(2);
}
const ms = await loadMedSpring();
const engine = new ms.Engine(model.endsWith('.msm') ? new Uint8Array(readFileSync(model)) : model, true, false);
const wasm = engine.runToolTrajectory(readFileSync(pathFile, 'utf8'), spec, Number(friction));

// native columns: time, tool xyz, reaction xyz, torque xyz, area, penetration, grasp, saturated, compute_us
const rows = readFileSync(traceFile, 'utf8').trim().split('\n').slice(1).map((l) => l.split(',').map(Number));
if (wasm.length !== rows.length * 7) {
  console.error(`FAIL: wasm gave ${wasm.length / 7} ticks, native ${rows.length}`);
  process.exit(1);
}
let scaleX = 0, scaleF = 0;
for (const r of rows)
  for (let c = 0; c < 3; ++c) { scaleX = Math.max(scaleX, Math.abs(r[1 + c])); scaleF = Math.max(scaleF, Math.abs(r[4 + c])); }
let worstX = 0, worstF = 0;
rows.forEach((r, k) => {
  if (Math.abs(wasm[7 * k] - r[0]) > 1e-9) { console.error(`FAIL: tick ${k} time ${wasm[7 * k]} vs ${r[0]}`); process.exit(1); }
  for (let c = 0; c < 3; ++c) {
    worstX = Math.max(worstX, Math.abs(wasm[7 * k + 1 + c] - r[1 + c]) / scaleX);
    worstF = Math.max(worstF, Math.abs(wasm[7 * k + 4 + c] - r[4 + c]) / scaleF);
  }
});
console.log(`${model} ${spec} friction ${friction}: ${rows.length} ticks, peak reaction ${scaleF.toExponential(3)} N: max ` +
  `relative difference tool ${worstX.toExponential(2)}, reaction ${worstF.toExponential(2)} (tolerance 1e-9)`);
engine.delete();
if (!(worstX <= 1e-9 && worstF <= 1e-9) || scaleF === 0) { console.error('FAIL'); process.exit(1); }
console.log('PASS');
