// Opens the dashboard's page in Debian's headless chromium (playwright-core, SwiftShader WebGL)
// for --seconds and prints one JSON line: the page's animation frames and sphere draws per
// second (window.dpcDashboard), the snapshots it received, its JavaScript heap.
//
//   node page_fps.mjs --url http://127.0.0.1:8080/ --seconds 10 --modules NODE_MODULES_DIR
import { createRequire } from 'node:module';
import path from 'node:path';

const args = Object.fromEntries(process.argv.slice(2).reduce((pairs, a, i, all) => {
  if (a.startsWith('--')) pairs.push([a.slice(2), all[i + 1]]);
  return pairs;
}, []));
const { chromium } = createRequire(path.resolve(args.modules, 'package.json'))('playwright-core');
const seconds = Number(args.seconds ?? 10);
const browser = await chromium.launch({
  executablePath: args.chromium ?? '/usr/bin/chromium',
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--disable-background-networking',
    '--disable-component-update', '--disable-sync', '--no-first-run'],
});
try {
  const page = await browser.newPage({ viewport: { width: 1400, height: 900 } });
  await page.goto(args.url);
  await page.waitForFunction(() => window.dpcDashboard && window.dpcDashboard.snapshots > 5, null, { timeout: 20000 });
  const read = () => page.evaluate(() => ({
    frames: window.dpcDashboard.frames, draws: window.dpcDashboard.draws, snapshots: window.dpcDashboard.snapshots,
    t: performance.now(), heap: performance.memory ? performance.memory.usedJSHeapSize : null,
  }));
  const a = await read();
  await new Promise((r) => setTimeout(r, seconds * 1000));
  const b = await read();
  const s = (b.t - a.t) / 1000;
  console.log(JSON.stringify({
    frames_per_s: (b.frames - a.frames) / s, draws_per_s: (b.draws - a.draws) / s,
    snapshots_per_s: (b.snapshots - a.snapshots) / s, heap_mb: b.heap === null ? null : b.heap / 1e6,
  }));
} finally {
  await browser.close();
}
