// The page of `umbra view` in headless Chromium (Debian's /usr/bin/chromium,
// driven by playwright-core, pinned in package-lock.json beside this file).
//
// It maps the built-in building (`umbra demo --res 0.2`), writes two pages
// (the default budget, and a budget small enough that depth 0 does not fit)
// and checks that each page loads without console errors or page errors;
// that at every depth the page offers, the boxes it draws per state, and
// their volume, equal what the library counts for the same depth and state;
// that the budget picks the finest depth that fits and the page says so;
// that a screenshot shows a drawn map; that the page starts cut below the
// ceiling `umbra render --view top` finds and that a height cut draws exactly
// the nodes whose bottom lies below it; that the panel lies beside the
// picture, never over it, and folds; and that `umbra view --serve` serves
// the same page. The expected numbers come from the library through the
// CLI: `umbra query MAP nodes --state S --depth D --count` for the counts,
// and the same query's node list (centre, size) for the volumes; unknown
// nodes are limited, as on the page, to those meeting the box around the
// known space (`umbra info --json`) shrunk by half a voxel, and their volume
// to the part inside it; a height cut (at the middle of a voxel layer) is
// the same box ending at the cut.
//
//   node viewer_test.mjs --umbra PATH --modules NODE_MODULES --work DIR
// Exit codes: 0 passed, 1 failed, 77 skipped (no Chromium).
import { execFileSync, spawn } from 'node:child_process';
import { existsSync, mkdirSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { pathToFileURL } from 'node:url';
import { parseArgs } from 'node:util';

const { values: args } = parseArgs({
  options: { umbra: { type: 'string' }, modules: { type: 'string' }, work: { type: 'string' } },
});
for (const name of ['umbra', 'modules', 'work']) {
  if (!args[name]) {
    console.error('usage: node viewer_test.mjs --umbra PATH --modules NODE_MODULES --work DIR');
    process.exit(2);
  }
}
const chromiumPath = process.env.UMBRA_CHROMIUM || '/usr/bin/chromium';
if (!existsSync(chromiumPath)) {
  console.log(`SKIPPED: no Chromium at ${chromiumPath} (Debian: apt-get install chromium, or set UMBRA_CHROMIUM): ` +
    'the page of `umbra view` was not tested in a browser');
  process.exit(77);
}

const started = Date.now();
const note = (what) => console.log(`${((Date.now() - started) / 1000).toFixed(1)} s: ${what}`);
let passed = 0;
let failed = 0;
function check(condition, message) {
  if (condition) {
    passed += 1;
  } else {
    failed += 1;
    console.log('FAILED: ' + message);
  }
}

const umbra = (...command) => execFileSync(args.umbra, command, { encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'] });
const expectedAt = new Map();
/// What the library reports for a depth (and a height cut, in map metres):
/// per state, the node count and volume.
function expected(map, depth, cut = Infinity) {
  const key = map + '@' + depth + '@' + cut;
  if (expectedAt.has(key)) return expectedAt.get(key);
  const info = JSON.parse(umbra('info', map, '--json'));
  const half = info.resolution / 2;
  const box = [...info.known_min.map((v) => v + half), ...info.known_max.map((v) => v - half)];
  const cutBox = [...info.known_min, info.known_max[0], info.known_max[1], Math.min(cut, info.known_max[2])];
  const result = {};
  for (const state of ['occupied', 'free', 'unknown']) {
    const query = ['query', map, 'nodes', '--state', state, '--depth', String(depth)];
    if (state === 'unknown') {
      const clipped = [...box];
      clipped[5] = Math.min(clipped[5], cut);
      query.push('--box=' + clipped.map((v) => v.toPrecision(17)).join(','));
    } else if (cut < Infinity) {
      query.push('--box=' + cutBox.map((v) => v.toPrecision(17)).join(','));
    }
    const count = Number(umbra(...query, '--count').trim());
    let volume = 0;
    for (const line of umbra(...query).split('\n')) {
      if (!line.trim()) continue;
      const [x, y, z, size] = line.split(' ').map(Number);
      let inside = 1;
      for (const [axis, centre] of [x, y, z].entries()) {
        inside *= Math.min(centre + size / 2, info.known_max[axis]) - Math.max(centre - size / 2, info.known_min[axis]);
      }
      volume += inside;
    }
    result[state] = { count, volume };
  }
  expectedAt.set(key, result);
  return result;
}
const close = (a, b) => Math.abs(a - b) <= 1e-6 * Math.max(1, Math.abs(b));

rmSync(args.work, { recursive: true, force: true });
mkdirSync(args.work, { recursive: true });
umbra('demo', '-o', args.work, '--res', '0.2');
const map = join(args.work, 'demo.umb');
const smallBudget = 1000;
umbra('view', map, '-o', join(args.work, 'demo.html'));
umbra('view', map, '-o', join(args.work, 'budget.html'), '--budget', String(smallBudget));

note('maps and pages written');
const { chromium } = await import(pathToFileURL(join(args.modules, 'playwright-core', 'index.mjs')).href);
const browser = await chromium.launch({
  executablePath: chromiumPath,
  args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
    '--disable-component-update', '--disable-sync'],
});

/// Opens a page and waits until it has drawn; collects its errors.
async function open(file) {
  const page = await browser.newPage({ viewport: { width: 800, height: 500 } });
  const errors = [];
  page.on('console', (message) => {
    if (message.type() === 'error') errors.push('console: ' + message.text());
  });
  page.on('pageerror', (error) => errors.push('page: ' + error.message));
  page.on('request', (request) => {
    const url = request.url();
    if (!url.startsWith('file:') && !url.startsWith('data:')) errors.push('network request: ' + url);
  });
  await page.goto(pathToFileURL(file).href);
  await page.waitForFunction(() => window.umbraStats && window.umbraStats.ready, null, { timeout: 60000 });
  note(`${file} drawn`);
  return { page, errors };
}

/// Share of the screenshot's pixels on the canvas that differ from the background.
async function drawnShare(page, file) {
  const png = await page.screenshot();
  writeFileSync(file, png);
  return page.evaluate(async (base64) => {
    const image = new Image();
    image.src = 'data:image/png;base64,' + base64;
    await image.decode();
    const canvas = document.createElement('canvas');
    canvas.width = image.width;
    canvas.height = image.height;
    const context = canvas.getContext('2d');
    context.drawImage(image, 0, 0);
    const pixels = context.getImageData(0, 0, canvas.width, canvas.height).data;
    const view = document.getElementById('view').getBoundingClientRect();
    let drawn = 0;
    let total = 0;
    for (let y = Math.ceil(view.top); y < Math.floor(view.bottom); ++y) {
      for (let x = Math.ceil(view.left); x < Math.floor(view.right); ++x) {
        const i = 4 * (y * canvas.width + x);
        total += 1;
        // The page's background is #15161c.
        if (Math.abs(pixels[i] - 0x15) + Math.abs(pixels[i + 1] - 0x16) + Math.abs(pixels[i + 2] - 0x1c) > 30) drawn += 1;
      }
    }
    return drawn / total;
  }, png.toString('base64'));
}

/// The panel's and the canvas's boxes on the page.
async function boxes(page) {
  return page.evaluate(() => {
    const box = (id) => {
      const r = document.getElementById(id).getBoundingClientRect();
      return { left: r.left, right: r.right, top: r.top, bottom: r.bottom, width: r.width };
    };
    return { panel: box('panel'), view: box('view') };
  });
}
const overlap = (a, b) => a.left < b.right && b.left < a.right && a.top < b.bottom && b.top < a.bottom;

note('Chromium started');
const stateNames = ['occupied', 'free', 'unknown'];

// --- the default budget: every depth, every state --------------------------------
{
  const { page, errors } = await open(join(args.work, 'demo.html'));
  const first = await page.evaluate(() => window.umbraStats);
  // The page starts cut half a voxel below the ceiling that `umbra render` finds.
  const ceiling = /ceiling found at ([-\d.]+) m/.exec(umbra('render', map, '-o', join(args.work, 'top.png'), '--view', 'top'));
  check(ceiling !== null, 'umbra render finds the demo building\'s ceiling');
  const ceilingCut = ceiling ? Number(ceiling[1]) - 0.1 : NaN;  // --res 0.2: half a voxel
  check(close(first.cut, ceilingCut), `the page starts cut at z ${first.cut}, below the ceiling at ${ceiling[1]}`);
  const depth0cut = expected(map, 0, first.cut);
  check(first.depth === 0 && first.finestDepth === 0, `the page starts at depth 0 (got ${first.depth})`);
  check(first.drawn.occupied === depth0cut.occupied.count,
    `depth 0 below the cut draws ${first.drawn.occupied} occupied boxes, the library counts ${depth0cut.occupied.count}`);
  check(first.drawn.occupied < expected(map, 0).occupied.count, 'the cut hides the ceiling\'s boxes');
  check(first.drawn.free === 0 && first.drawn.unknown === 0, 'free and unknown space start hidden');
  const share = await drawnShare(page, join(args.work, 'demo-screenshot.png'));
  check(share > 0.02, `the screenshot shows a map (${(100 * share).toFixed(1)}% of the pixels drawn, want > 2%)`);
  const numbers = await page.textContent('#numbers');
  check(numbers.includes('0.2 m') && numbers.includes('memory'), `the corner shows the map's numbers: ${numbers}`);

  // The panel is beside the picture, never over it; folded it leaves the picture more room.
  const open_ = await boxes(page);
  check(!overlap(open_.panel, open_.view), `the panel (${JSON.stringify(open_.panel)}) does not cover the picture (${JSON.stringify(open_.view)})`);
  await page.evaluate(() => window.umbraViewer.fold());
  const folded = await boxes(page);
  check(!overlap(folded.panel, folded.view) && folded.panel.width <= 48 && folded.view.width > open_.view.width + 200,
    `folded, the panel is a strip (${folded.panel.width} px) and the picture wider (${open_.view.width} -> ${folded.view.width} px)`);
  const foldedShare = await drawnShare(page, join(args.work, 'demo-folded.png'));
  check(foldedShare > 0.02, `folded, the picture still shows the map (${(100 * foldedShare).toFixed(1)}%)`);
  await page.evaluate(() => window.umbraViewer.fold());

  // No cut: every node, as before the cut existed.
  await page.evaluate(async () => window.umbraViewer.setCut(Infinity));
  const depths = await page.evaluate(() => window.umbraViewer.depths);
  check(depths.length === 8 && depths[0] === 0, `the slider offers depths 0..7 (got ${depths})`);
  await page.evaluate(async () => {
    await window.umbraViewer.setVisible('free', true);
    await window.umbraViewer.setVisible('unknown', true);
  });
  note('demo.html loaded, screenshot taken');
  for (const depth of depths) {
    const stats = await page.evaluate(async (d) => {
      await window.umbraViewer.show(d);
      return window.umbraStats;
    }, depth);
    const library = expected(map, depth);
    check(stats.depth === depth, `show(${depth}) shows depth ${stats.depth}`);
    for (const state of stateNames) {
      check(stats.drawn[state] === library[state].count,
        `depth ${depth}: ${stats.drawn[state]} ${state} boxes drawn, the library counts ${library[state].count}`);
      check(close(stats.volume[state], library[state].volume),
        `depth ${depth}: ${state} boxes hold ${stats.volume[state]} m^3, the library's nodes ${library[state].volume}`);
    }
    note(`depth ${depth}: ${stats.instances} boxes`);
    check(stats.instances === stateNames.reduce((sum, s) => sum + library[s].count, 0), `depth ${depth}: instance total`);
  }
  // A cut at z = 1.1 m (the middle of a voxel layer): the boxes whose bottom lies below it.
  for (const depth of [0, 2]) {
    const stats = await page.evaluate(async (d) => {
      await window.umbraViewer.show(d);
      await window.umbraViewer.setCut(1.1);
      return window.umbraStats;
    }, depth);
    const library = expected(map, depth, 1.1);
    for (const state of stateNames) {
      check(stats.drawn[state] === library[state].count,
        `depth ${depth} cut at 1.1 m: ${stats.drawn[state]} ${state} boxes drawn, the library counts ${library[state].count}`);
      check(close(stats.volume[state], library[state].volume),
        `depth ${depth} cut at 1.1 m: ${state} boxes hold ${stats.volume[state]} m^3, the library's nodes ${library[state].volume}`);
    }
  }
  const cutText = await page.textContent('#status');
  check(cutText.includes('below the cut at z 1.10 m'), `the status says where the cut is: "${cutText}"`);
  check(errors.length === 0, 'no errors in demo.html: ' + errors.join('; '));
  await page.close();
}

// --- a budget that depth 0 does not fit ----------------------------------------------
{
  const { page, errors } = await open(join(args.work, 'budget.html'));
  const stats = await page.evaluate(async () => {
    await window.umbraViewer.setCut(Infinity);  // every node, as the budget counts them
    return window.umbraStats;
  });
  const finest = stats.finestDepth;
  check(finest > 0 && stats.depth === finest, `a budget of ${smallBudget} starts the page at depth ${finest} > 0`);
  check(expected(map, finest).occupied.count <= smallBudget && expected(map, finest - 1).occupied.count > smallBudget,
    `depth ${finest} is the finest whose occupied nodes fit the budget (library: ${expected(map, finest - 1).occupied.count} at ` +
    `depth ${finest - 1}, ${expected(map, finest).occupied.count} at depth ${finest})`);
  check(stats.drawn.occupied === expected(map, finest).occupied.count,
    `depth ${finest}: ${stats.drawn.occupied} occupied boxes drawn, the library counts ${expected(map, finest).occupied.count}`);
  const status = await page.textContent('#status');
  check(status.includes('more than the budget') && status.includes(`finest depth drawn is ${finest}`),
    `the page says why it starts at depth ${finest}: "${status}"`);
  // A free or unknown layer over the budget is left out, and its box says so.
  const after = await page.evaluate(async () => {
    await window.umbraViewer.setVisible('free', true);
    await window.umbraViewer.setVisible('unknown', true);
    return window.umbraStats;
  });
  for (const state of ['free', 'unknown']) {
    const count = expected(map, finest)[state].count;
    const disabled = await page.isDisabled('#show-' + state);
    if (count > smallBudget) {
      check(after.drawn[state] === 0 && disabled, `depth ${finest}: ${count} ${state} nodes are over the budget and left out`);
    } else {
      check(after.drawn[state] === count && !disabled, `depth ${finest}: ${after.drawn[state]} ${state} boxes, library ${count}`);
    }
  }
  check(errors.length === 0, 'no errors in budget.html: ' + errors.join('; '));
  await page.close();
}
await browser.close();

note('budget.html checked');

// --- --serve: the same page over HTTP on the loopback address -------------------------
{
  const server = spawn(args.umbra, ['view', map, '--budget', String(smallBudget), '--serve', '--port', '0']);
  let output = '';
  const url = await new Promise((resolve, reject) => {
    const timer = setTimeout(() => reject(new Error('no "serving" line within 30 s: ' + output)), 30000);
    server.stdout.on('data', (chunk) => {
      output += chunk;
      const found = /serving (http:\/\/127\.0\.0\.1:\d+\/)/.exec(output);
      if (found) {
        clearTimeout(timer);
        resolve(found[1]);
      }
    });
    server.on('exit', (code) => reject(new Error(`umbra view --serve exited with ${code}: ${output}`)));
  });
  const page = await (await fetch(url)).text();
  check(page === readFileSync(join(args.work, 'budget.html'), 'utf8'), `${url} serves the page that -o writes`);
  const missing = await fetch(url + 'other');
  check(missing.status === 404, `${url}other answers 404 (got ${missing.status})`);
  const exited = new Promise((resolve) => server.on('exit', (code) => resolve(code)));
  server.kill('SIGINT');
  const code = await exited;
  check(code === 0 && output.includes('stopped'), `Ctrl-C stops the server cleanly (exit ${code}): ${output}`);
}

console.log(`${passed} passed, ${failed} failed`);
process.exit(failed === 0 ? 0 : 1);
