// The dashboard as a person sees it: a real bench (driver, controller, polarimeter on loopback),
// `dpc dashboard`, and the page in Debian's headless Chromium (playwright-core, executablePath;
// WebGL through SwiftShader). Checks that the sphere is drawn, S_out moves, the error plot
// updates, LOCKED appears, a target set from the page reaches the driver (the revision grows and
// S_out follows), a bad target is refused with its reason; keeps a screenshot; prints the page's
// frame rate.
//
//   node dashboard_page_test.mjs --dpc DPC --driver DPC_DRIVER --controller DPC_CONTROLLER
//        --polarimeter DPC_POLARIMETER --modules NODE_MODULES_DIR --artifacts DIR
//        [--domain 89] [--chromium /usr/bin/chromium]
//
// Exit 0 pass, 1 fail, 77 skipped (no chromium, no playwright-core) with the reason.
import { spawn } from 'node:child_process';
import { createRequire } from 'node:module';
import fs from 'node:fs';
import path from 'node:path';
import readline from 'node:readline';

const args = Object.fromEntries(process.argv.slice(2).reduce((pairs, a, i, all) => {
  if (a.startsWith('--')) pairs.push([a.slice(2), all[i + 1]]);
  return pairs;
}, []));
const domain = args.domain ?? '89';
const chromiumPath = args.chromium ?? '/usr/bin/chromium';
const artifacts = args.artifacts;

function skip(reason) { console.log(`SKIP: ${reason}`); process.exit(77); }
if (!fs.existsSync(chromiumPath)) skip(`${chromiumPath} not found (apt-get install chromium)`);
let chromium;
try {
  chromium = createRequire(path.resolve(args.modules, 'package.json'))('playwright-core').chromium;
} catch (e) {
  skip(`playwright-core not installed in ${args.modules} (the dpc_dashboard_test_deps target runs npm ci): ${e.message}`);
}

const children = [];
function start(name, binary, argv) {
  const logPath = path.join(artifacts, `dashboard-test-${name}.log`);
  const log = fs.openSync(logPath, 'w');
  const child = spawn(binary, argv, { stdio: ['ignore', name === 'dashboard' ? 'pipe' : log, log] });
  child.logPath = logPath;
  children.push(child);
  return child;
}
function stopAll() {
  for (const child of children) {
    if (child.exitCode === null && child.signalCode === null) child.kill('SIGTERM');
  }
}
process.on('exit', stopAll);

const checks = [];
function check(ok, what) {
  checks.push({ ok, what });
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
  if (!ok) throw new Error(what);
}
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
async function until(page, predicate, timeoutMs, what, arg) {
  const deadline = Date.now() + timeoutMs;
  for (;;) {
    const value = await page.evaluate(predicate, arg);
    if (value) return value;
    if (Date.now() > deadline) check(false, `${what} (within ${timeoutMs / 1000} s)`);
    await sleep(100);
  }
}

let browser;
let exitCode = 0;
try {
  fs.mkdirSync(artifacts, { recursive: true });
  const common = ['--domain', domain];
  start('driver', args.driver, [...common, '--device-record', 'none']);  // nothing left in /dev/shm
  start('controller', args.controller, [...common, '--id', 'main', '--priority', '10']);
  start('polarimeter', args.polarimeter, [...common, '--rate-hz', '500']);
  const dashboard = start('dashboard', args.dpc,
    ['dashboard', ...common, '--port', '0', '--push-hz', '20']);
  const url = await new Promise((resolve, reject) => {
    const timer = setTimeout(() => reject(new Error('dpc dashboard printed no URL within 15 s')), 15000);
    readline.createInterface({ input: dashboard.stdout }).on('line', (line) => {
      const m = line.match(/^dpc dashboard: (http:\/\/\S+)$/);
      if (m) { clearTimeout(timer); resolve(m[1]); }
    });
    dashboard.on('exit', (code) => reject(new Error(`dpc dashboard exited with ${code}: ${fs.readFileSync(dashboard.logPath, 'utf8')}`)));
  });
  console.log(`dashboard at ${url}`);

  browser = await chromium.launch({
    executablePath: chromiumPath,
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--disable-background-networking',
      '--disable-component-update', '--disable-sync', '--no-first-run', '--disable-quic'],
  });
  const page = await browser.newPage({ viewport: { width: 1400, height: 900 } });
  const pageErrors = [];
  page.on('pageerror', (e) => pageErrors.push(e.message));
  page.on('console', (m) => { if (m.type() === 'error') pageErrors.push(m.text()); });
  await page.goto(url);

  await until(page, () => window.dpcDashboard && window.dpcDashboard.connected, 10000, 'the page connects to /ws');
  check(true, 'the page connected to the dashboard\'s WebSocket');
  await until(page, () => window.dpcDashboard.snapshots > 10 && window.dpcDashboard.sOut, 15000, 'snapshots with S_out arrive');

  // The sphere's canvas is drawn: many pixels differ from the panel's background.
  const readSphere = () => page.evaluate(() => {
    const c = document.getElementById('sphere');
    const copy = document.createElement('canvas');
    copy.width = c.width; copy.height = c.height;
    const g = copy.getContext('2d');
    g.drawImage(c, 0, 0);
    const data = g.getImageData(0, 0, copy.width, copy.height).data;
    const [r0, g0, b0] = [data[0], data[1], data[2]];
    let differ = 0, orange = 0;
    for (let i = 0; i < data.length; i += 4) {
      const d = Math.abs(data[i] - r0) + Math.abs(data[i + 1] - g0) + Math.abs(data[i + 2] - b0);
      if (d > 20) differ++;
      if (data[i] > 180 && data[i] > data[i + 1] + 50 && data[i + 1] > data[i + 2] + 40) orange++;  // S_out's orange
    }
    return { pixels: data.length / 4, differ, orange, webglLost: window.dpcDashboard.webglLost };
  });
  // The page draws at its own pace (a loaded machine gives it few frames): read until a frame
  // drawn after the data arrived shows S_out, for at most 15 s.
  let drawn = await readSphere();
  for (const deadline = Date.now() + 15000; drawn.orange <= 20 && Date.now() < deadline;) {
    await sleep(250);
    drawn = await readSphere();
  }
  await page.locator('#sphere').screenshot({ path: path.join(artifacts, 'dashboard-sphere.png') });
  check(!drawn.webglLost, 'WebGL context alive');
  check(drawn.differ > 0.02 * drawn.pixels, `the sphere is drawn (${drawn.differ} of ${drawn.pixels} pixels not background)`);
  check(drawn.orange > 20, `the S_out marker and trail are on it (${drawn.orange} S_out-coloured pixels)`);

  const badge = await until(page, () => document.getElementById('badge').dataset.condition === 'LOCKED' &&
    document.getElementById('badge').textContent, 30000, 'the LOCKED badge appears');
  check(badge === 'LOCKED', 'the LOCKED badge appears');

  const before = await page.evaluate(() => ({ sOut: window.dpcDashboard.sOut, points: window.dpcDashboard.errorPoints }));
  await sleep(1500);
  const after = await page.evaluate(() => ({ sOut: window.dpcDashboard.sOut, points: window.dpcDashboard.errorPoints }));
  const moved = Math.hypot(...after.sOut.map((x, i) => x - before.sOut[i]));
  check(moved > 1e-6, `S_out moves while the input turns (|Δ| = ${moved.toExponential(2)} in 1.5 s)`);
  check(after.points > before.points, `the error plot updates (${before.points} → ${after.points} points)`);
  const fps = await page.evaluate(() => window.dpcDashboard.fps);
  const draws = await page.evaluate(() => window.dpcDashboard.drawsPerS);
  console.log(`figure: page ${fps.toFixed(1)} frames/s, sphere ${draws.toFixed(1)} draws/s (headless Chromium, SwiftShader WebGL, 500-Hz bench)`);

  // A bad target from the page is refused with its reason; nothing changes.
  const revision0 = await page.evaluate(() => window.dpcDashboard.targetRevisionCount);
  await page.fill('#p1', '1'); await page.fill('#p2', '1'); await page.fill('#p3', '0');
  await page.click('#target-send');
  const refused = await until(page, () => document.getElementById('target-answer').className === 'refused' &&
    document.getElementById('target-answer').textContent, 10000, 'a non-unit target is refused');
  check(/point/.test(refused), `a non-unit target is refused, naming the field: "${refused}"`);
  check(await page.evaluate(() => window.dpcDashboard.targetRevisionCount) === revision0, 'the refused target changed nothing');

  // A good one reaches the driver: the revision grows and S_out follows it.
  await page.fill('#p1', '0.6'); await page.fill('#p2', '0'); await page.fill('#p3', '0.8');
  await page.click('#target-send');
  const accepted = await until(page, () => document.getElementById('target-answer').className === 'accepted' &&
    document.getElementById('target-answer').textContent, 10000, 'the driver accepts the target set from the page');
  check(true, `the driver answers the page: "${accepted}"`);
  await until(page, (r0) => window.dpcDashboard.targetRevisionCount > r0, 5000, 'the target revision grows', revision0);
  const revision1 = await page.evaluate(() => window.dpcDashboard.targetRevisionCount);
  check(revision1 > revision0, `the target's revision count grew (${revision0} → ${revision1})`);
  await until(page, () => {
    const s = window.dpcDashboard.sOut;
    return s && Math.hypot(s[0] - 0.6, s[1], s[2] - 0.8) < 0.1 && window.dpcDashboard.condition === 'LOCKED';
  }, 20000, 'S_out reaches the new target and the bench is LOCKED again');
  check(true, 'S_out reached the new target [0.6, 0, 0.8], LOCKED again');
  await sleep(1000);

  const shot = path.join(artifacts, 'dashboard.png');
  await page.screenshot({ path: shot });
  check(fs.statSync(shot).size > 20000, `screenshot kept: ${shot}`);
  check(pageErrors.length === 0, `no error in the page's console${pageErrors.length ? ': ' + pageErrors.join(' | ') : ''}`);
} catch (e) {
  if (!checks.length || checks[checks.length - 1].ok) console.log(`FAIL ${e.message}`);
  exitCode = 1;
} finally {
  if (browser) await browser.close();
  stopAll();
}
console.log(exitCode === 0 ? `PASS (${checks.length} checks)` : 'FAILED');
process.exit(exitCode);
