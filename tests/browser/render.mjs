// Renders a glTF binary with three.js in headless Chromium and saves a screenshot.
//
//   node tests/browser/render.mjs FILE.glb OUT.png [--time T] [--width W] [--height H]
//
// Serves page.html, three.js (from node_modules/three) and the file on
// 127.0.0.1 (a port the system picks; nothing else is reached), opens the page
// in Debian's Chromium through playwright-core (WAGASHI_CHROMIUM overrides
// /usr/bin/chromium) with a fresh profile and software WebGL (SwiftShader), and
// waits for the page to render. Prints one JSON object on stdout: what the page
// reports (WebGL renderer, animation time, nodes, morph targets, colour scale)
// plus `screenshot`. Exit status 0 on success; 1 when the page fails; 2 on usage.
import http from 'node:http';
import { mkdtemp, readFile, rm } from 'node:fs/promises';
import { tmpdir } from 'node:os';
import { dirname, extname, join, normalize, resolve, sep } from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';

const here = dirname(fileURLToPath(import.meta.url));
const threeRoot = join(here, 'node_modules', 'three');

function usage(message) {
  if (message) console.error(message);
  console.error('usage: node render.mjs FILE.glb OUT.png [--time T] [--width W] [--height H]');
  process.exit(2);
}

const positional = [];
const query = new URLSearchParams();
const args = process.argv.slice(2);
for (let i = 0; i < args.length; i++) {
  const a = args[i];
  if (a === '--time' || a === '--width' || a === '--height') {
    const v = args[++i];
    if (v === undefined || !Number.isFinite(Number(v))) usage(`${a} needs a number`);
    query.set(a.slice(2), v);
  } else if (a.startsWith('--')) {
    usage(`unknown option ${a}`);
  } else {
    positional.push(a);
  }
}
if (positional.length !== 2) usage();
const [glbPath, pngPath] = positional.map((p) => resolve(p));
const width = Number(query.get('width') ?? 800);
const height = Number(query.get('height') ?? 600);
query.set('width', String(width));
query.set('height', String(height));

// Everything ends within two minutes, whatever happens.
const watchdog = setTimeout(() => {
  console.error('render.mjs: timed out after 120 s');
  process.exit(1);
}, 120_000);

const types = { '.html': 'text/html', '.js': 'text/javascript', '.glb': 'model/gltf-binary' };
const glb = await readFile(glbPath).catch((e) => usage(`${glbPath}: ${e.message}`));
const page = await readFile(join(here, 'page.html'));

// GET /, /model.glb and /three/... (inside node_modules/three only).
const server = http.createServer(async (req, res) => {
  const path = decodeURIComponent(new URL(req.url, 'http://localhost').pathname);
  let body = null;
  let type = 'application/octet-stream';
  if (path === '/' || path === '/index.html') {
    [body, type] = [page, types['.html']];
  } else if (path === '/model.glb') {
    [body, type] = [glb, types['.glb']];
  } else if (path.startsWith('/three/')) {
    const file = normalize(join(threeRoot, path.slice('/three/'.length)));
    if (file.startsWith(threeRoot + sep)) {
      body = await readFile(file).catch(() => null);
      type = types[extname(file)] ?? type;
    }
  }
  if (path === '/favicon.ico') {
    res.writeHead(204).end();
    return;
  }
  if (body === null) {
    res.writeHead(404).end();
  } else {
    res.writeHead(200, { 'content-type': type, 'cache-control': 'no-store' }).end(body);
  }
});
await new Promise((ok) => server.listen(0, '127.0.0.1', ok));
const url = `http://127.0.0.1:${server.address().port}/?${query}`;

const profile = await mkdtemp(join(tmpdir(), 'wagashi-chromium-'));
let context;
let status = 0;
try {
  // A persistent context is how playwright takes a --user-data-dir: a fresh one.
  context = await chromium.launchPersistentContext(profile, {
    executablePath: process.env.WAGASHI_CHROMIUM || '/usr/bin/chromium',
    headless: true,
    viewport: { width, height },
    deviceScaleFactor: 1,
    args: [
      '--headless',
      '--no-sandbox',
      '--disable-gpu',
      '--disable-quic',
      '--no-first-run',
      '--disable-background-networking',
      '--disable-component-update',
      '--disable-sync',
      // WebGL without a GPU: ANGLE on SwiftShader (software).
      '--use-angle=swiftshader',
      '--enable-unsafe-swiftshader',
    ],
  });
  const tab = context.pages()[0] ?? (await context.newPage());
  const console_ = [];
  tab.on('console', (m) => console_.push(`${m.type()}: ${m.text()}`));
  tab.on('pageerror', (e) => console_.push(`pageerror: ${e.message}`));
  await tab.goto(url);
  await tab.waitForFunction(() => window.renderResult || window.renderError, null, { timeout: 90_000 });
  const error = await tab.evaluate(() => window.renderError ?? null);
  if (error) {
    console.error(`page failed: ${error}\n${console_.join('\n')}`);
    status = 1;
  } else {
    const result = await tab.evaluate(() => window.renderResult);
    await tab.screenshot({ path: pngPath, clip: { x: 0, y: 0, width, height } });
    console.log(JSON.stringify({ ...result, screenshot: pngPath, console: console_ }, null, 1));
  }
} catch (error) {
  console.error(`render.mjs: ${error.stack ?? error}`);
  status = 1;
} finally {
  await context?.close().catch(() => {});
  server.close();
  await rm(profile, { recursive: true, force: true });
  clearTimeout(watchdog);
}
process.exit(status);
