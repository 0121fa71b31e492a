// The browser page end to end (playwright-core driving Debian's chromium, headless, WebGL2 through
// SwiftShader), served by `medspring view`:
//   the page loads and the canvas is not blank; the default left-drag presses a rigid sphere (the probe)
//   into the kidney and slides it: every surface node stays outside the sphere (>= 0.95 R from its
//   centre), the reaction on the probe points back at the user (against the press), and the tissue
//   returns to rest after release; the grasp mode closes two jaws on the kidney, holds surface points and
//   pulls them out with the cursor; in the pull mode a scripted mouse drag on the kidney moves the nodes under
//   the cursor in the drag direction and gives a non-zero reaction force; after release the surface
//   returns to rest within 1e-3 mm; a drag outside the surface does nothing; switching to the vessel works;
//   a broken model file shows an error message (the canvas stays drawn); a diverged state is reset with
//   a visible message; a parameter slider rebuilds the model.
// Screenshots (rest, probe, grasp, pulled, released, vessel, broken) go to OUT_DIR as test artifacts.
//
// Usage: node web/test/page_test.mjs --medspring PATH/TO/medspring --out OUT_DIR [--chromium /usr/bin/chromium]
//                                    [--models DIR]   (default: medspring export --web into OUT_DIR/models)
import { spawn, spawnSync } from 'node:child_process';
import { mkdirSync, readFileSync, writeFileSync, existsSync, rmSync } from 'node:fs';
import path from 'node:path';
import assert from 'node:assert/strict';
import { chromium } from 'playwright-core';

export const CHROMIUM_FLAGS = ['--headless', '--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
  '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run'];

const args = { chromium: '/usr/bin/chromium' };
for (let i = 2; i < process.argv.length; i += 2) args[process.argv[i].replace(/^--/, '')] = process.argv[i + 1];
if (!args.medspring || !args.out) {
  console.error('usage: node page_test.mjs --medspring EXE --out DIR [--chromium PATH] [--models DIR]');
  process.exit(2);
}
mkdirSync(args.out, { recursive: true });

// ---- the models folder: the exported packages plus a broken file listed in models.json
function prepareModels() {
  const dir = path.join(args.out, 'models');
  if (args.models) {
    rmSync(dir, { recursive: true, force: true });
    mkdirSync(dir, { recursive: true });
    spawnSync('cp', ['-r', `${args.models}/.`, dir]);
  } else {
    const t0 = Date.now();
    const r = spawnSync(args.medspring, ['export', '--web', '--out', dir, '--force', '--quiet'], { encoding: 'utf8' });
    if (r.status !== 0) {
      console.log(`# medspring export --web failed (${(r.stderr || r.error || '').toString().trim()}): built-in models only`);
      rmSync(dir, { recursive: true, force: true });
      mkdirSync(dir, { recursive: true });
    } else {
      console.log(`# medspring export --web: ${((Date.now() - t0) / 1000).toFixed(1)} s`);
    }
  }
  const listFile = path.join(dir, 'models.json');
  const json = existsSync(listFile) ? JSON.parse(readFileSync(listFile, 'utf8')) : { models: [] };
  const models = Array.isArray(json) ? json : json.models;
  writeFileSync(path.join(dir, 'broken.msm'), Buffer.concat([Buffer.from('MSPRMODL'), Buffer.alloc(40, 7)]));
  models.push({ file: 'broken.msm', name: 'Broken model (test)', kind: 'hybrid', description: 'not a model package' });
  writeFileSync(listFile, JSON.stringify(Array.isArray(json) ? models : { ...json, models }, null, 2));
  return { dir, models };
}

// ---- `medspring view --port 0`: read the URL it prints
function startServer(modelsDir) {
  return new Promise((resolve, reject) => {
    const proc = spawn(args.medspring, ['view', '--port', '0', '--models', modelsDir, '--quiet', '--exit-after', '900'],
      { stdio: ['ignore', 'pipe', 'inherit'] });
    let out = '';
    const timer = setTimeout(() => reject(new Error(`medspring view printed no URL: ${out}`)), 20000);
    proc.stdout.on('data', (d) => {
      out += d;
      const m = out.match(/http:\/\/127\.0\.0\.1:\d+\//);
      if (m) { clearTimeout(timer); resolve({ proc, url: m[0] }); }
    });
    proc.on('exit', (code) => reject(new Error(`medspring view exited (${code}): ${out}`)));
  });
}

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
let step = 0;
const ok = (what) => console.log(`ok ${++step} - ${what}`);

const { dir: modelsDir, models } = prepareModels();
const { proc: server, url } = await startServer(modelsDir);
const browser = await chromium.launch({ executablePath: args.chromium, args: CHROMIUM_FLAGS, headless: true });
let failed = false;
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
  const pageErrors = [];
  page.on('pageerror', (e) => pageErrors.push(String(e)));
  page.on('console', (m) => { if (m.type() === 'error') console.log(`# console: ${m.text()}`); });

  // Prefer the real kidney / aorta, else the phantoms' packages, else the built-ins.
  const have = (f) => models.some((m) => m.file === f);
  const kidneyId = have('kidney.msm') ? 'kidney.msm' : have('kidney_phantom.msm') ? 'kidney_phantom.msm' : 'builtin:kidney_phantom';
  const vesselId = have('aorta.msm') ? 'aorta.msm' : have('vessel_phantom.msm') ? 'vessel_phantom.msm' : 'builtin:vessel_phantom';

  await page.goto(`${url}?model=${encodeURIComponent(kidneyId)}`);
  await page.waitForFunction(() => window.medspring && window.medspring.ready, null, { timeout: 60000 });
  await sleep(500);
  const info = await page.evaluate(() => ({ model: window.medspring.model.id, error: window.medspring.error,
    kind: window.medspring.engine.kind(), isolated: self.crossOriginIsolated }));
  assert.equal(info.model, kidneyId, JSON.stringify(info));
  assert.equal(info.kind, 'hybrid');
  assert.equal(info.error, '');
  ok(`page loaded ${info.model} (cross-origin isolated: ${info.isolated})`);

  const canvas = await page.evaluate(() => window.medspring.canvasStats());
  assert.ok(canvas.foreground > 0.02 && canvas.colours > 5, `canvas looks blank: ${JSON.stringify(canvas)}`);
  await page.screenshot({ path: path.join(args.out, 'rest.png') });
  ok(`canvas not blank: ${(100 * canvas.foreground).toFixed(1)} % foreground, ${canvas.colours} colours`);

  const box = await page.locator('#view canvas').boundingBox();
  const start = await page.evaluate(({ x0, y0, w, h }) => {
    for (let r = 0; r < 200; r += 10)
      for (const [dx, dy] of [[0, 0], [r, 0], [-r, 0], [0, r], [0, -r]]) {
        const hit = window.medspring.pickAt(x0 + dx, y0 + dy);
        if (hit) return { x: x0 + dx, y: y0 + dy, node: hit.node };
      }
    return null;
  }, { x0: box.x + box.width / 2, y0: box.y + box.height / 2, w: box.width, h: box.height });
  assert.ok(start, 'no surface under the middle of the canvas');

  // ---- the probe (default mode): press the kidney, slide, hold; the surface stays outside the sphere and
  // the reaction on the probe points back at the user
  assert.equal(await page.evaluate(() => window.medspring.mode), 'probe');
  const probeState = () => page.evaluate(() => {
    const ms = window.medspring, e = ms.engine, ts = e.toolState();
    if (!ts) return { tool: null, reaction: e.reaction(), max: e.maxDisplacement() };
    const P = e.positions(), c = ts.position;
    let closest = Infinity;
    for (let i = 0; i < P.length; i += 3) closest = Math.min(closest, Math.hypot(P[i] - c[0], P[i + 1] - c[1], P[i + 2] - c[2]));
    const cam = ms.camera.position, dir = [c[0] - cam.x, c[1] - cam.y, c[2] - cam.z];
    const dn = Math.hypot(...dir), r = e.reaction(), rn = Math.hypot(...r);
    const cosine = rn > 0 ? (r[0] * dir[0] + r[1] * dir[1] + r[2] * dir[2]) / (rn * dn) : 0;
    return { tool: ts, closest, cosine, reaction: r, max: e.maxDisplacement(), size: ms.toolSizes() };
  });
  await page.mouse.move(start.x, start.y);
  await page.mouse.down();
  await sleep(1200);
  const pressed = await probeState();
  for (let k = 1; k <= 10; ++k) {
    await page.mouse.move(start.x + 3 * k, start.y);
    await sleep(15);
  }
  await sleep(1200);
  const slid = await probeState();
  await page.screenshot({ path: path.join(args.out, 'probe.png') });
  for (const [what, st] of [['pressed', pressed], ['slid', slid]]) {
    assert.ok(st.tool && st.tool.kind === 'sphere', `${what}: no probe ${JSON.stringify(st)}`);
    const R = st.tool.radius;
    assert.ok(st.tool.contacts > 0 && st.max > 0.25 * st.size.depth, `${what}: the probe does not press: ${JSON.stringify(st)}`);
    assert.ok(st.closest >= 0.95 * R, `${what}: a surface node ${st.closest} mm from the centre of the ${R} mm probe`);
    assert.ok(Math.hypot(...st.reaction) > 1e-3 && st.cosine < -0.3,
      `${what}: the reaction ${st.reaction} does not point back at the user (cosine with the press ${st.cosine})`);
  }
  const slide = Math.hypot(...[0, 1, 2].map((c) => slid.tool.position[c] - pressed.tool.position[c]));
  assert.ok(slide > 0.5, `the probe did not slide with the cursor (${slide} mm)`);
  ok(`probe r = ${pressed.tool.radius.toFixed(2)} mm pressed ${pressed.size.depth.toFixed(2)} mm and slid ${slide.toFixed(2)} mm: ` +
    `closest surface node ${(pressed.closest / pressed.tool.radius).toFixed(3)} R / ${(slid.closest / slid.tool.radius).toFixed(3)} R ` +
    `from the centre, reaction ${Math.hypot(...pressed.reaction).toFixed(3)} / ${Math.hypot(...slid.reaction).toFixed(3)} N at ` +
    `cosine ${pressed.cosine.toFixed(3)} / ${slid.cosine.toFixed(3)} with the press, ${slid.tool.contacts} contacts`);
  await page.mouse.up();
  await page.waitForFunction(() => window.medspring.engine.maxDisplacement() <= 1e-3, null, { timeout: 30000, polling: 50 });
  const probeOff = await probeState();
  assert.equal(probeOff.tool, null);
  assert.deepEqual(probeOff.reaction, [0, 0, 0]);
  ok('probe released: no tool, zero reaction, back to rest within 1e-3 mm');

  // ---- grasp: the jaws close on the surface, hold points and pull them towards the cursor
  await page.selectOption('#mode', 'grasp');
  await page.mouse.move(start.x, start.y);
  await page.mouse.down();
  await page.waitForFunction(() => { const t = window.medspring.engine.toolState(); return t && t.grasping; }, null,
    { timeout: 10000, polling: 20 });
  const held = await page.evaluate(() => ({ ...window.medspring.engine.toolState(), max: window.medspring.engine.maxDisplacement() }));
  await page.mouse.move(start.x, start.y - 60, { steps: 10 });
  await sleep(1200);
  const pulledOut = await page.evaluate(() => ({ ...window.medspring.engine.toolState(), max: window.medspring.engine.maxDisplacement() }));
  await page.screenshot({ path: path.join(args.out, 'grasp.png') });
  assert.ok(held.attached > 0, JSON.stringify(held));
  assert.ok(pulledOut.grasping && pulledOut.attached > 0 && pulledOut.graspForce > 1e-3, JSON.stringify(pulledOut));
  assert.ok(pulledOut.max > held.max + 0.5, `the grasp did not pull the tissue: ${held.max} -> ${pulledOut.max} mm`);
  ok(`grasp: ${held.attached} points held, pulled: max displacement ${pulledOut.max.toFixed(2)} mm, grasp force ` +
    `${pulledOut.graspForce.toFixed(3)} N`);
  await page.mouse.up();
  await page.waitForFunction(() => window.medspring.engine.maxDisplacement() <= 1e-3, null, { timeout: 30000, polling: 50 });
  ok('grasp released: back to rest');

  // ---- the node pull (the pull mode): pick near the middle of the canvas, pull right and up
  await page.selectOption('#mode', 'pull');
  // The nodes under the cursor: the picked node and its neighbours on screen (within 25 px).
  const before = await page.evaluate(({ node }) => {
    const ms = window.medspring, n = ms.engine.numSurfaceNodes(), c = ms.project(node), near = [];
    for (let i = 0; i < n; ++i) {
      const p = ms.project(i);
      if (Math.hypot(p.x - c.x, p.y - c.y) < 25 && p.depth <= c.depth + 0.002) near.push({ i, ...p });
    }
    return { c, near };
  }, start);
  const drag = { x: 140, y: -70 };
  await page.mouse.move(start.x, start.y);
  await page.mouse.down();
  for (let k = 1; k <= 20; ++k) {
    await page.mouse.move(start.x + (drag.x * k) / 20, start.y + (drag.y * k) / 20);
    await sleep(15);
  }
  await sleep(1500);
  const pulled = await page.evaluate(({ near }) => {
    const ms = window.medspring, e = ms.engine;
    return { grabbed: e.grabbed(), contact: e.contact(), reaction: e.reaction(), stats: ms.stats(),
      moved: near.map((q) => { const p = ms.project(q.i); return { i: q.i, dx: p.x - q.x, dy: p.y - q.y }; }) };
  }, before);
  assert.equal(pulled.grabbed, true);
  assert.equal(pulled.contact, start.node);
  const fmag = Math.hypot(...pulled.reaction);
  assert.ok(fmag > 1e-3, `reaction ${pulled.reaction} N during the drag`);
  const unit = [drag.x / Math.hypot(drag.x, drag.y), drag.y / Math.hypot(drag.x, drag.y)];
  const along = pulled.moved.map((m) => m.dx * unit[0] + m.dy * unit[1]);
  const across = pulled.moved.map((m) => Math.abs(-m.dx * unit[1] + m.dy * unit[0]));
  const contactAlong = along[pulled.moved.findIndex((m) => m.i === start.node)];
  assert.ok(contactAlong > 10, `the picked node moved ${contactAlong} px along the drag`);
  assert.ok(along.every((a) => a > 0), `every node under the cursor moves along the drag: ${along.map((a) => a.toFixed(1))}`);
  assert.ok(contactAlong > Math.max(...across), 'the picked node moves mostly along the drag');
  await page.screenshot({ path: path.join(args.out, 'pulled.png') });
  ok(`drag on node ${start.node}: it moved ${contactAlong.toFixed(1)} px along the ${Math.hypot(drag.x, drag.y).toFixed(0)} px ` +
    `drag (${pulled.moved.length} nodes under the cursor, all along it); reaction ${fmag.toFixed(3)} N; ` +
    `${pulled.stats.ticksPerSecond.toFixed(0)} ticks/s, ${pulled.stats.fps.toFixed(0)} fps, median tick ` +
    `${pulled.stats.medianTickUs.toFixed(1)} us`);

  // ---- release: back to rest within 1e-3 mm
  await page.mouse.up();
  const t0 = Date.now();
  await page.waitForFunction(() => window.medspring.engine.maxDisplacement() <= 1e-3, null, { timeout: 30000, polling: 50 });
  const released = await page.evaluate(() => {
    const e = window.medspring.engine, P = e.positions(), R = e.restPositions();
    let worst = 0;
    for (let i = 0; i < P.length; i += 3) worst = Math.max(worst, Math.hypot(P[i] - R[i], P[i + 1] - R[i + 1], P[i + 2] - R[i + 2]));
    return { grabbed: e.grabbed(), reaction: e.reaction(), max: e.maxDisplacement(), worstFloat: worst };
  });
  assert.equal(released.grabbed, false);
  assert.deepEqual(released.reaction, [0, 0, 0]);
  assert.ok(released.max <= 1e-3 && released.worstFloat <= 1e-3 + 1e-4, JSON.stringify(released));
  await page.screenshot({ path: path.join(args.out, 'released.png') });
  ok(`released: back to rest within 1e-3 mm (max ${released.max.toExponential(2)} mm) after ${((Date.now() - t0) / 1000).toFixed(2)} s`);

  // ---- a drag outside the surface does nothing
  const corner = { x: box.x + 15, y: box.y + box.height - 15 };
  assert.equal(await page.evaluate(({ x, y }) => window.medspring.pickAt(x, y), corner), null);
  await page.mouse.move(corner.x, corner.y);
  await page.mouse.down();
  await page.mouse.move(corner.x + 200, corner.y - 150, { steps: 10 });
  await sleep(300);
  const outside = await page.evaluate(() => ({ grabbed: window.medspring.engine.grabbed(),
    max: window.medspring.engine.maxDisplacement(), reaction: window.medspring.engine.reaction() }));
  await page.mouse.up();
  assert.equal(outside.grabbed, false);
  assert.deepEqual(outside.reaction, [0, 0, 0]);
  assert.ok(outside.max <= 1e-3, `drag outside moved the tissue: ${outside.max}`);
  ok('a drag outside the surface does nothing');

  // ---- a parameter slider rebuilds the model
  const k0 = await page.evaluate(() => window.medspring.engine.params().k);
  await page.locator('#k').fill('0.5');
  await page.waitForFunction((k) => Math.abs(window.medspring.engine.params().k - k * Math.pow(10, 0.5)) < 1e-9 * k, k0, { timeout: 5000 });
  await page.locator('#nonlinear').uncheck();
  await page.waitForFunction(() => window.medspring.engine.params().nonlinear === false, null, { timeout: 5000 });
  await page.locator('#local').check();
  assert.equal(await page.evaluate(() => window.medspring.engine.local()), true);
  ok(`sliders: k ${k0} -> ${(k0 * Math.sqrt(10)).toPrecision(4)} N/mm, linear springs, local deformation on`);

  // ---- a diverged state is reset with a visible message
  await page.evaluate(() => window.medspring.engine.injectNaN());
  await page.waitForFunction(() => !document.getElementById('message').hidden, null, { timeout: 5000 });
  const msg = await page.locator('#message').textContent();
  assert.match(msg, /diverged.*reset/);
  assert.equal(await page.evaluate(() => window.medspring.engine.finite()), true);
  ok(`divergence: "${msg}"`);

  // ---- switch to the vessel with the model menu
  await page.selectOption('#model', vesselId);
  await page.waitForFunction((id) => window.medspring.ready && window.medspring.model.id === id, vesselId, { timeout: 30000 });
  await sleep(500);
  const vessel = await page.evaluate(() => ({ kind: window.medspring.engine.kind(), n: window.medspring.engine.numSurfaceNodes(),
    atoms: window.medspring.engine.numAtoms(), error: window.medspring.error, canvas: window.medspring.canvasStats() }));
  assert.equal(vessel.kind, 'smrm');
  assert.equal(vessel.error, '');
  // the kidney's divergence notice is not shown over the vessel
  assert.equal(await page.evaluate(() => document.getElementById('message').hidden), true);
  assert.ok(vessel.canvas.foreground > 0.01, JSON.stringify(vessel.canvas));
  await page.locator('#show-spokes').check();
  await page.locator('#show-atoms').check();
  const vstart = await page.evaluate(({ x0, y0 }) => {
    for (let r = 0; r < 300; r += 10)
      for (const [dx, dy] of [[0, 0], [r, 0], [-r, 0], [0, r], [0, -r]]) {
        const hit = window.medspring.pickAt(x0 + dx, y0 + dy);
        if (hit) return { x: x0 + dx, y: y0 + dy, node: hit.node };
      }
    return null;
  }, { x0: box.x + box.width / 2, y0: box.y + box.height / 2 });
  assert.ok(vstart, 'no vessel surface near the middle of the canvas');
  await page.mouse.move(vstart.x, vstart.y);
  await page.mouse.down();
  await page.mouse.move(vstart.x, vstart.y - 80, { steps: 10 });
  await sleep(800);
  const vr = await page.evaluate(() => ({ r: window.medspring.engine.reaction(), u: window.medspring.engine.maxDisplacement() }));
  await page.screenshot({ path: path.join(args.out, 'vessel.png') });
  await page.mouse.up();
  assert.ok(Math.hypot(...vr.r) > 1e-4 && vr.u > 1e-3, JSON.stringify(vr));
  ok(`switched to ${vesselId}: ${vessel.n} surface nodes, ${vessel.atoms} atoms; pulled: reaction ` +
    `${Math.hypot(...vr.r).toFixed(3)} N, max displacement ${vr.u.toFixed(2)} mm`);

  // ---- a broken model file: the error is shown, the canvas keeps the last model
  await page.selectOption('#model', 'broken.msm');
  await page.waitForFunction(() => !document.getElementById('error').hidden, null, { timeout: 15000 });
  const err = await page.locator('#error').textContent();
  assert.match(err, /broken\.msm/);
  assert.match(err, /model package/i);
  const after = await page.evaluate(() => ({ model: window.medspring.model.id, canvas: window.medspring.canvasStats(),
    selected: document.getElementById('model').value }));
  assert.equal(after.model, vesselId);
  assert.equal(after.selected, vesselId);
  assert.ok(after.canvas.foreground > 0.01, 'blank canvas after a failed load');
  await page.screenshot({ path: path.join(args.out, 'broken.png') });
  ok(`broken model file: "${err}"`);

  // ---- a broken model as the first page: the error is shown over a working fallback model
  const page2 = await browser.newPage({ viewport: { width: 1024, height: 700 } });
  await page2.goto(`${url}?model=broken.msm`);
  await page2.waitForFunction(() => window.medspring && window.medspring.ready && window.medspring.error, null, { timeout: 60000 });
  const p2 = await page2.evaluate(() => ({ error: window.medspring.error, model: window.medspring.model.id,
    canvas: window.medspring.canvasStats() }));
  assert.match(p2.error, /broken\.msm/);
  assert.equal(p2.model, 'builtin:kidney_phantom');
  assert.ok(p2.canvas.foreground > 0.02);
  await page2.close();
  ok('a broken model as the first model: error shown over the built-in kidney phantom');

  assert.deepEqual(pageErrors, [], 'uncaught page errors');
  console.log(`PASS (${step} checks; screenshots in ${args.out})`);
} catch (err) {
  failed = true;
  console.error(`FAIL: ${err && err.stack ? err.stack : err}`);
} finally {
  await browser.close();
  server.kill('SIGTERM');
}
process.exit(failed ? 1 : 0);
