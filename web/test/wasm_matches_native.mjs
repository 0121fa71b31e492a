// The wasm engine replays a tool trajectory through the haptic loop and must reproduce the native force
// trace (contact positions and reactions of every tick) to 1e-9 relative. The native trace comes from
// `medspring haptics --out DIR` (force_trace.csv) or tests/web/web_reference.cpp (same columns).
//
// Usage: node web/test/wasm_matches_native.mjs TRAJECTORY.csv NATIVE_TRACE.csv CONTACT_NODE [MODEL|PACKAGE.msm]
//                                              [--linear] [--local] [--params k,eta,kr,beta]
import { readFileSync } from 'node:fs';
import { loadMedSpring } from './load_engine.mjs';

const positional = [];
const opts = { linear: false, local: false, params: null };
const argv = process.argv.slice(2);
for (let i = 0; i < argv.length; ++i) {
  if (argv[i] === '--linear') opts.linear = true;
  else if (argv[i] === '--local') opts.local = true;
  else if (argv[i] === '--params') opts.params = argv[++i];
  else positional.push(argv[i]);
}
const [trajFile, traceFile, contactArg, model = 'kidney_phantom'] = positional;
if (!trajFile || !traceFile || contactArg === undefined) {
  console.error('usage: node wasm_matches_native.mjs TRAJECTORY.csv NATIVE_TRACE.csv CONTACT_NODE [MODEL|PACKAGE.msm] ' +
    '[--linear] [--local] [--params k,eta,kr,beta]');
  process.exit(2);
}
const ms = await loadMedSpring();
const source = model.endsWith('.msm') ? new Uint8Array(readFileSync(model)) : model;
const engine = new ms.Engine(source, !opts.linear, opts.local);
if (opts.params) {
  const [k, eta, kr, beta] = opts.params.split(',').map(Number);
  engine.setParams({ k, eta, kr, beta });
}
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
const what = `${model}${opts.linear ? ' linear' : ''}${opts.local ? ' local' : ''}${opts.params ? ` params ${opts.params}` : ''}`;
console.log(`${what}: ${rows.length} ticks, peak reaction ${scaleF.toExponential(3)} N: max relative difference ` +
  `contact ${worstX.toExponential(2)}, reaction ${worstF.toExponential(2)} (tolerance 1e-9)`);
if (!(worstX <= 1e-9 && worstF <= 1e-9) || scaleF === 0) { console.error('FAIL'); process.exit(1); }
console.log('PASS');
