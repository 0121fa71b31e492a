// Benchmark of the page (docs/web.md): the kidney phantom's 1 ms haptic tick in headless Chromium vs
// native (`medspring haptics`, same trajectory, same per-tick timer), and the physics rate with rendering
// while a node is held, per model.
// Usage: node web/test/bench.mjs --medspring EXE [--models DIR] [--rounds 3] [--chromium /usr/bin/chromium]
import { spawn, spawnSync } from 'node:child_process';
import { readFileSync, mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import path from 'node:path';
import { chromium } from 'playwright-core';
import { webDir } from './load_engine.mjs';

const FLAGS = ['--headless', '--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
  '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run'];
const args = { chromium: '/usr/bin/chromium', rounds: '3' };
for (let i = 2; i < process.argv.length; i += 2) args[process.argv[i].replace(/^--/, '')] = process.argv[i + 1];
if (!args.medspring) { console.error('usage: node bench.mjs --medspring EXE [--models DIR] [--rounds N]'); process.exit(2); }
const trajectory = path.join(webDir, '..', 'examples', 'haptics', 'kidney_press.csv');
const csv = readFileSync(trajectory, 'utf8');
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const med = (a) => [...a].sort((x, y) => x - y)[a.length >> 1];

// Median over 100-tick windows of the mean tick time: robust to the shared machine's outliers, and
// unbiased by the browser's coarse (5 µs, jittered) timer, unlike a per-tick median.
function windowed(times, w = 100) {
  const means = [];
  for (let k = 0; k + w <= times.length; k += w) means.push(times.slice(k, k + w).reduce((s, v) => s + v, 0) / w);
  return med(means);
}

function native(local) {
  const out = mkdtempSync(path.join(tmpdir(), 'medspring-bench-'));
  const r = spawnSync(args.medspring, ['haptics', 'kidney_phantom', '--trajectory', trajectory, '--json',
    '--out', path.join(out, 'trace'), ...(local ? ['--local'] : [])], { encoding: 'utf8' });
  if (r.status !== 0) throw new Error(r.stderr);
  const j = JSON.parse(r.stdout);
  const rows = readFileSync(path.join(out, 'trace', 'force_trace.csv'), 'utf8').trim().split('\n').slice(1);
  const times = rows.map((l) => Number(l.split(',').pop()));
  rmSync(out, { recursive: true, force: true });
  return { median: j.median_us, p99: j.p99_us, mean: j.mean_us, windowed: windowed(times) };
}

const server = spawn(args.medspring, ['view', '--port', '0', '--quiet', '--exit-after', '1200',
  ...(args.models ? ['--models', args.models] : [])], { stdio: ['ignore', 'pipe', 'inherit'] });
const url = await new Promise((resolve) => {
  let out = '';
  server.stdout.on('data', (d) => { out += d; const m = out.match(/http:\/\/127\.0\.0\.1:\d+\//); if (m) resolve(m[0]); });
});
const browser = await chromium.launch({ executablePath: args.chromium, args: FLAGS });
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
  await page.goto(`${url}?model=builtin:kidney_phantom`);
  await page.waitForFunction(() => window.medspring && window.medspring.ready, null, { timeout: 60000 });
  const isolated = await page.evaluate(() => self.crossOriginIsolated);

  // ---- per-tick cost, browser vs native, alternating rounds (the machine is shared)
  console.log(`# kidney phantom, 1 ms tick, ${trajectory} (1000 ticks); cross-origin isolated: ${isolated}`);
  console.log('| case | native median / windowed µs | Chromium median / windowed µs | ratio (median, windowed) |');
  console.log('|---|---|---|---|');
  for (const local of [false, true]) {
    const nat = [], web = [];
    for (let r = 0; r < Number(args.rounds); ++r) {
      nat.push(native(local));
      await page.evaluate(() => { window.medspring.paused = true; });
      web.push(await page.evaluate(({ csv, local }) => window.medspring.bench({ csv, local, batch: 1000 }), { csv, local }));
      await page.evaluate(() => { window.medspring.paused = false; });
    }
    const n = { median: med(nat.map((x) => x.median)), win: med(nat.map((x) => x.windowed)) };
    const w = { median: med(web.map((x) => x.trajectory.median)),
      win: med(web.map((x) => windowed(x.trajectory.times))) };
    console.log(`| local deformation ${local ? 'on' : 'off'} | ${n.median.toFixed(1)} / ${n.win.toFixed(1)} | ` +
      `${w.median.toFixed(1)} / ${w.win.toFixed(1)} | ${(w.median / n.median).toFixed(2)}×, ${(w.win / n.win).toFixed(2)}× |`);
  }

  // ---- physics rate with rendering, a node held and pulled
  const models = await page.evaluate(() => window.medspring.models.map((m) => m.id));
  console.log('\n| model | ticks/s (target 1000) | fps | wall per tick µs | dropped ticks |');
  console.log('|---|---|---|---|---|');
  for (const id of models) {
    if (id === 'broken.msm') continue;
    await page.evaluate((id) => window.medspring.loadModel(id), id);
    await sleep(500);
    const box = await page.locator('#view canvas').boundingBox();
    const hit = await page.evaluate(({ x, y }) => {
      for (let r = 0; r < 300; r += 10)
        for (const [dx, dy] of [[0, 0], [r, 0], [-r, 0], [0, r], [0, -r]])
          if (window.medspring.pickAt(x + dx, y + dy)) return { x: x + dx, y: y + dy };
      return null;
    }, { x: box.x + box.width / 2, y: box.y + box.height / 2 });
    if (!hit) continue;
    await page.mouse.move(hit.x, hit.y);
    await page.mouse.down();
    await page.mouse.move(hit.x + 60, hit.y - 40, { steps: 5 });
    await sleep(1500);
    const d0 = await page.evaluate(() => window.medspring.stats().dropped);
    const samples = [];
    for (let k = 0; k < 4; ++k) { await sleep(1000); samples.push(await page.evaluate(() => window.medspring.stats())); }
    await page.mouse.up();
    const last = samples[samples.length - 1];
    console.log(`| ${id} | ${med(samples.map((s) => s.ticksPerSecond)).toFixed(0)} | ${med(samples.map((s) => s.fps)).toFixed(1)} | ` +
      `${med(samples.map((s) => s.wallTickUs)).toFixed(1)} | ${last.dropped - d0} in 4 s |`);
  }
} finally {
  await browser.close();
  server.kill('SIGTERM');
}
