// The JavaScript API of the wasm engine (web/src/bindings.cpp) under node: construction from names and
// model packages, views, atoms/spokes, setParams keeping the state, errors as JS exceptions carrying
// the C++ message, and the automatic reset of a diverged state.
// Usage: node web/test/engine_api_test.mjs [MODELS_DIR]   (MODELS_DIR: output of medspring export --web)
import { readFileSync, existsSync } from 'node:fs';
import path from 'node:path';
import assert from 'node:assert/strict';
import { loadMedSpring } from './load_engine.mjs';

const modelsDir = process.argv[2];
const ms = await loadMedSpring();
let checks = 0;
const check = (name, fn) => { fn(); ++checks; console.log(`ok ${checks} - ${name}`); };
const throwsWith = (fn, re) => {
  try { fn(); } catch (err) {
    assert.ok(err instanceof Error, `expected an Error, got ${typeof err}: ${err}`);
    assert.match(err.message, re);
    return err.message;
  }
  assert.fail(`expected an exception matching ${re}`);
};

check('built-in models: sizes, zero-copy views, atoms and spokes', () => {
  const k = new ms.Engine('kidney_phantom', true, false);
  assert.equal(k.kind(), 'hybrid');
  assert.equal(k.numSurfaceNodes(), 458);
  assert.equal(k.numAtoms(), 42);
  assert.equal(k.numMasses(), 500);
  assert.ok(k.positions() instanceof Float32Array && k.positions().length === 458 * 3);
  assert.ok(k.faces() instanceof Uint32Array && k.faces().length % 3 === 0);
  assert.equal(k.atoms().length, 42 * 3);
  const sp = k.spokes();
  assert.ok(sp.length > 0 && sp.length % 2 === 0);
  for (let i = 0; i < sp.length; i += 2) assert.ok(sp[i] < 458 && sp[i + 1] < 42);
  assert.deepEqual(Array.from(k.positions()), Array.from(k.restPositions()));
  const v = new ms.Engine('vessel_phantom', false, true);
  assert.equal(v.kind(), 'smrm');
  assert.equal(v.numSurfaceNodes(), 1200);
  assert.equal(v.numAtoms(), 40);
  assert.equal(v.spokes().length, 2 * 1200);
  assert.equal(v.params().nonlinear, false);
  assert.equal(v.local(), true);
  const t = new ms.Engine('tube');
  assert.equal(t.kind(), 'surface');
  assert.equal(t.numAtoms(), 0);
  assert.equal(t.spokes().length, 0);
  for (const e of [k, v, t]) e.delete();
});

check('grab, pull, reaction, release back to rest within 1e-3 mm', () => {
  const e = new ms.Engine('kidney_phantom', true, false);
  e.grab(223, 0.1, 0.01, 3);
  const x0 = e.node(223);
  e.moveTool(x0[0], x0[1], x0[2] + 5);
  e.ticks(300);
  const x1 = e.node(223);
  assert.ok(x1[2] - x0[2] > 0.5, `node moved ${x1[2] - x0[2]} mm towards the tool`);
  const r = e.reaction();
  assert.ok(r[2] < -0.01, `reaction ${r} opposes the pull`);
  assert.ok(e.tickStats().count === 300 && e.tickStats().median > 0);
  e.release();
  assert.deepEqual(e.reaction(), [0, 0, 0]);
  let t = 0;
  while (e.maxDisplacement() > 1e-3 && t < 5000) { e.ticks(10); t += 10; }
  assert.ok(e.maxDisplacement() <= 1e-3, `back to rest after ${t} ms: ${e.maxDisplacement()}`);
  e.delete();
});

check('setParams keeps the state when the DOF count is unchanged (same parameters: bit-identical run)', () => {
  const run = (withParams) => {
    const e = new ms.Engine('kidney_phantom', true, false);
    e.grab(100, 0.1, 0, 3);  // no coupling damping: a re-created coupling gives the same force
    const x = e.node(100);
    e.moveTool(x[0] + 2, x[1], x[2]);
    e.ticks(150);
    if (withParams) e.setParams(e.params());
    e.ticks(150);
    const out = Array.from(e.positions());
    e.delete();
    return out;
  };
  assert.deepEqual(run(true), run(false));
  const e = new ms.Engine('kidney_phantom', true, false);
  e.grab(100, 0.1, 0.01, 3);
  e.moveTool(0, 0, 0);
  e.ticks(50);
  const before = Array.from(e.positions()), t = e.time();
  e.setParams({ k: 0.2, eta: 2, nonlinear: false });
  assert.deepEqual(Array.from(e.positions()), before);
  assert.equal(e.time(), t);
  assert.equal(e.grabbed(), true);
  assert.deepEqual(e.params(), { k: 0.2, eta: 2, kr: 0.02, beta: 0.5, nonlinear: false });
  e.delete();
});

check('errors are JS exceptions with the C++ message', () => {
  throwsWith(() => new ms.Engine('liver', true, false), /unknown model 'liver'/);
  throwsWith(() => new ms.Engine(new Uint8Array([1, 2, 3]), true, false), /model package/);
  throwsWith(() => new ms.Engine(42, true, false), /expected a model name or the bytes/);
  const e = new ms.Engine('tube', true, false);
  const before = e.params();
  throwsWith(() => e.setParams({ k: -1 }), /\bk\b.*must be > 0/);
  throwsWith(() => e.setParams({ beta: Number.NaN }), /beta/);
  throwsWith(() => e.setParams({ eta: 'x' }), /eta must be a number/);
  assert.deepEqual(e.params(), before);  // nothing changed
  throwsWith(() => e.grab(5000, 0.1, 0.01, 3), /surface node 5000 out of range/);
  throwsWith(() => e.grab(0, 0.1, 0.01, 0), /f_max/);
  throwsWith(() => e.node(-1), /out of range/);
  throwsWith(() => e.runTrajectory('time,x,y,z\n0,1,2\n', 0), /trajectory:2/);
  e.delete();
});

check('a diverged state is reset to rest with a message', () => {
  const e = new ms.Engine('kidney_phantom', true, false);
  e.grab(223, 0.1, 0.01, 3);
  e.moveTool(0, 0, 30);
  e.ticks(20);
  e.injectNaN();
  assert.equal(e.finite(), false);
  e.tick();
  assert.equal(e.finite(), true);
  assert.match(e.message(), /diverged.*reset/);
  assert.equal(e.autoResets(), 1);
  assert.equal(e.grabbed(), false);
  assert.equal(e.maxDisplacement(), 0);
  e.clearMessage();
  assert.equal(e.message(), '');
  e.delete();
});

check('a rigid probe: press, the surface outside the sphere, the reaction against the press, release', () => {
  const e = new ms.Engine('kidney_phantom', true, false);
  throwsWith(() => e.placeTool('sphere:8', 0, 0, 0, 0, 0, -1, 0, 3, 0), /inside/);
  throwsWith(() => e.placeTool('sphere:-1', 0, 0, 40, 0, 0, -1, 0, 3, 0), /radius/);
  throwsWith(() => e.placeTool('sphere:8', 0, 0, 40, 0, 0, 0, 0, 3, 0), /direction/);
  assert.equal(e.hasTool(), false);
  assert.equal(e.toolState(), null);
  // examples/tools/probe_press_slide.csv: r = 8 mm from z = 27 to 23 on the broad +z face
  e.placeTool('sphere:8', 0, 0, 27, 0, 0, -1, 0.2, 10, 0.4);
  e.moveTool(0, 0, 23);
  e.ticks(300);
  const ts = e.toolState(), P = e.positions(), c = ts.position;
  assert.equal(ts.kind, 'sphere');
  assert.ok(Math.abs(c[2] - 23) < 1e-12, `probe at ${c}`);
  let closest = Infinity;
  for (let i = 0; i < P.length; i += 3) closest = Math.min(closest, Math.hypot(P[i] - c[0], P[i + 1] - c[1], P[i + 2] - c[2]));
  assert.ok(closest >= 0.95 * 8, `a node ${closest} mm from the centre`);
  assert.ok(ts.contacts > 0 && ts.penetration <= 0.05 * 8, JSON.stringify(ts));
  const r = e.reaction();
  assert.ok(r[2] > 0.05 && Math.hypot(r[0], r[1]) < 0.2 * r[2], `reaction ${r} (the press is along -z)`);
  e.release();
  assert.equal(e.hasTool(), false);
  assert.deepEqual(e.reaction(), [0, 0, 0]);
  const pressed = e.maxDisplacement();
  e.ticks(2000);
  assert.ok(e.maxDisplacement() < 0.01 * pressed, `${pressed} -> ${e.maxDisplacement()} mm after release`);
  e.delete();
});

check('a grasper closes on the surface, holds points and pulls them out', () => {
  const e = new ms.Engine('kidney_phantom', true, false);
  // examples/tools/grasp_pull.json: jaws r = 1.5 mm, 12 mm, opened 60 degrees, hinge at z = 28.4
  e.placeTool('grasper:1.5:12:60', 0, 0, 32, 0, 0, -1, 0, 10, 0.5);
  e.moveTool(0, 0, 28.4);
  e.ticks(50);
  for (let k = 1; k <= 10; ++k) { e.setOpening(60 * (1 - k / 10)); e.ticks(10); }
  const held = e.toolState();
  assert.ok(held.grasping && held.attached > 0, JSON.stringify(held));
  e.moveTool(0, 0, 36.4);
  e.ticks(300);
  const pulled = e.toolState();
  assert.ok(pulled.grasping && pulled.graspForce > 1e-3 && e.maxDisplacement() > 2, JSON.stringify(pulled));
  throwsWith(() => new ms.Engine('kidney_phantom', true, false).setOpening(10), /no tool/);
  e.delete();
});

if (modelsDir && existsSync(path.join(modelsDir, 'models.json'))) {
  const list = JSON.parse(readFileSync(path.join(modelsDir, 'models.json'), 'utf8'));
  const models = Array.isArray(list) ? list : list.models;
  for (const m of models) {
    check(`package ${m.file}: loads, ${m.kind}, ticks, setParams`, () => {
      const bytes = new Uint8Array(readFileSync(path.join(modelsDir, m.file)));
      const info = ms.inspectPackage(bytes);
      assert.equal(info.kind, m.kind);
      const e = new ms.Engine(bytes, true, false);
      assert.equal(e.kind(), m.kind);
      if (m.surface_nodes !== undefined) assert.equal(e.numSurfaceNodes(), m.surface_nodes);
      const node = Math.floor(e.numSurfaceNodes() / 2);
      e.grab(node, 0.1, 0.01, 3);
      const x = e.node(node);
      e.moveTool(x[0], x[1] + 3, x[2]);
      e.ticks(100);
      assert.ok(e.finite() && e.maxDisplacement() > 0);
      const p = e.params();
      e.setParams({ k: 2 * p.k });
      assert.ok(Math.abs(e.params().k - 2 * p.k) < 1e-15);
      e.ticks(10);
      e.delete();
    });
  }
  check('a corrupted package is refused with the reason', () => {
    const first = models[0];
    const bytes = new Uint8Array(readFileSync(path.join(modelsDir, first.file)));
    bytes[bytes.length - 5] ^= 0xff;
    throwsWith(() => new ms.Engine(bytes, true, false), /model package.*(checksum|corrupt)/i);
    throwsWith(() => new ms.Engine(bytes.subarray(0, 20), true, false), /model package/);
  });
} else {
  console.log('# no models folder given (or no models.json in it): package checks skipped');
}
console.log(`PASS (${checks} checks)`);
