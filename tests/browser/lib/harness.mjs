// Shared harness of the browser tests: a real rmapd on a free loopback port, rmap-sim feeds,
// Debian Chromium through playwright-core, and helpers to read the API.
//
// Environment:
//   RMAPD, RMAP_SIM          binaries (default <repo>/build/bin/rmapd, …/rmap-sim)
//   RMAP_WEB_ROOT            viewer files (default <repo>/web)
//   RMAP_CHROMIUM            browser (default /usr/bin/chromium)
//   RMAP_TEST_ARTIFACTS      where screenshots and JSON figures go (default <repo>/build/test-artifacts)
//   RMAP_BROWSER_STATIC_PROXY=1  force the development fallback below
//
// rmapd serves the viewer itself with --web-root. Only when the binary does not know that flag
// (older builds) does the harness put a small same-origin static server + API proxy in front of
// it (static_proxy.mjs), so the viewer can still be exercised; the test then says so.

import { spawn, spawnSync } from 'node:child_process';
import { createRequire } from 'node:module';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
export const repoRoot = path.resolve(here, '..', '..', '..');
export const paths = {
  rmapd: process.env.RMAPD || path.join(repoRoot, 'build', 'bin', 'rmapd'),
  sim: process.env.RMAP_SIM || path.join(repoRoot, 'build', 'bin', 'rmap-sim'),
  webRoot: process.env.RMAP_WEB_ROOT || path.join(repoRoot, 'web'),
  chromium: process.env.RMAP_CHROMIUM || '/usr/bin/chromium',
  artifacts: process.env.RMAP_TEST_ARTIFACTS || path.join(repoRoot, 'build', 'test-artifacts'),
};

// The flags the outside checks use; the tests use exactly these.
export const CHROMIUM_ARGS = [
  '--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
  '--disable-component-update', '--disable-sync',
];

export function sleep(ms) {
  return new Promise((resolve) => setTimeout(resolve, ms));
}

export function log(...args) {
  const t = new Date().toISOString().slice(11, 23);
  console.log(`[${t}]`, ...args);
}

/** True when rmapd's --help lists --web-root. */
export function rmapdHasWebRoot() {
  if (process.env.RMAP_BROWSER_STATIC_PROXY === '1') return false;
  const r = spawnSync(paths.rmapd, ['--help'], { encoding: 'utf8', timeout: 10000 });
  return `${r.stdout}${r.stderr}`.includes('--web-root');
}

/** Starts rmapd on 127.0.0.1:0 with a fresh data dir; resolves once it prints its URL. */
export async function startRmapd({ dataDir, config, extraArgs = [] } = {}) {
  dataDir ||= fs.mkdtempSync(path.join(os.tmpdir(), 'rmap-browser-'));
  const webRoot = rmapdHasWebRoot();
  const args = ['--listen', '127.0.0.1:0', '--data-dir', dataDir, ...extraArgs];
  if (config) args.push('--config', config);
  if (webRoot) args.push('--web-root', paths.webRoot);
  const child = spawn(paths.rmapd, args, { stdio: ['ignore', 'pipe', 'pipe'] });
  let stderr = '';
  child.stderr.on('data', (d) => {
    stderr += d;
    if (stderr.length > 200000) stderr = stderr.slice(-100000);
  });
  const url = await new Promise((resolve, reject) => {
    let out = '';
    const timer = setTimeout(() => reject(new Error(`rmapd did not start in 20 s:\n${stderr}`)), 20000);
    child.stdout.on('data', (d) => {
      out += d;
      const m = out.match(/rmapd listening on (http:\/\/[^\s]+?)\/?\s/);
      if (m) {
        clearTimeout(timer);
        resolve(m[1]);
      }
    });
    child.on('exit', (code) => {
      clearTimeout(timer);
      reject(new Error(`rmapd exited with ${code}:\n${stderr}`));
    });
  });
  const server = {
    child, dataDir, apiUrl: url, url, port: Number(new URL(url).port), servesWeb: webRoot, proxy: null,
    stderr: () => stderr,
    async stop() {
      if (server.proxy) await server.proxy.close();
      if (child.exitCode === null && child.signalCode === null) {
        child.kill('SIGTERM');
        let timer;
        await Promise.race([new Promise((r) => child.once('exit', r)), new Promise((r) => { timer = setTimeout(r, 8000); })]);
        clearTimeout(timer);
        if (child.exitCode === null && child.signalCode === null) child.kill('SIGKILL');
      }
      fs.rmSync(dataDir, { recursive: true, force: true });
    },
  };
  if (!webRoot) {
    const { startStaticProxy } = await import('./static_proxy.mjs');
    server.proxy = await startStaticProxy({ webRoot: paths.webRoot, apiPort: server.port });
    server.url = server.proxy.url;
    log(`note: ${paths.rmapd} has no --web-root yet; serving web/ through the harness proxy ${server.url}`);
  }
  return server;
}

/** Runs rmap-sim against the server; returns {promise, child}. */
export function startSim(server, { robots = 2, duration = 10, rate, map, resolution, precompute, rings, columns,
  extra = [] } = {}) {
  const args = ['--server', `ws://127.0.0.1:${server.port}`, '--robots', String(robots), '--duration', String(duration)];
  if (rate !== undefined) args.push('--rate', String(rate));
  if (map) args.push('--map', map);
  if (resolution) args.push('--resolution', String(resolution));
  if (precompute) args.push('--precompute', String(precompute));
  if (rings) args.push('--lidar-rings', String(rings));
  if (columns) args.push('--lidar-columns', String(columns));
  args.push(...extra);
  const child = spawn(paths.sim, args, { stdio: ['ignore', 'pipe', 'pipe'] });
  let out = '';
  let err = '';
  child.stdout.on('data', (d) => { out += d; });
  child.stderr.on('data', (d) => { err += d; if (err.length > 100000) err = err.slice(-50000); });
  const promise = new Promise((resolve) => {
    child.on('exit', (code) => resolve({ code, stdout: out, stderr: err }));
  });
  return { child, promise, stop() { if (child.exitCode === null) child.kill('SIGTERM'); return promise; } };
}

export async function getJson(server, p, headers = {}) {
  const r = await fetch(server.apiUrl + p, { headers });
  if (!r.ok) throw new Error(`GET ${p}: ${r.status} ${await r.text()}`);
  return r.json();
}

export async function waitFor(what, fn, { timeout = 30000, interval = 200 } = {}) {
  const end = Date.now() + timeout;
  let last;
  for (;;) {
    try {
      last = await fn();
      if (last) return last;
    } catch (e) {
      last = e;
    }
    if (Date.now() > end) throw new Error(`timed out waiting for ${what} (last: ${last instanceof Error ? last.message : JSON.stringify(last)})`);
    await sleep(interval);
  }
}

/**
 * Waits until a map whose robots stopped is done fusing: rmapd fuses an idle map's cuboids
 * about a second after its last message (later on a loaded or sanitized server), so two reads
 * of one point can see different cuboids until its cuboid count holds (2.5 s, as the
 * integration tests' waitForIdleFusion).
 */
export async function waitForIdleFusion(server, map, { timeout = 60000 } = {}) {
  const end = Date.now() + timeout;
  let before = (await getJson(server, `/v1/maps/${map}`)).cuboids;
  while (Date.now() < end) {
    await sleep(2500);
    const now = (await getJson(server, `/v1/maps/${map}`)).cuboids;
    if (now === before) return now;
    before = now;
  }
  throw new Error(`map ${map} still changing after ${timeout} ms`);
}

/** Launches Chromium with the outside checks' flags. */
export async function launchBrowser() {
  // playwright-core lives in web/node_modules (web/package.json), not beside the tests.
  const require = createRequire(path.join(paths.webRoot, 'package.json'));
  const pw = await import(pathToFileURL(require.resolve('playwright-core')).href);
  const chromium = pw.chromium || pw.default.chromium;
  return chromium.launch({ executablePath: paths.chromium, args: CHROMIUM_ARGS });
}

/**
 * Opens a page that may only talk to 127.0.0.1: every other request is aborted and recorded
 * (page.route for HTTP, the websocket event for WebSockets), as are console errors and CSP
 * violations.
 */
export async function openViewerPage(browser, url, { width = 1280, height = 800, beforeGoto = null } = {}) {
  const context = await browser.newContext({ viewport: { width, height } });
  const page = await context.newPage();
  const record = { foreign: [], requests: 0, paths: [], consoleErrors: [], pageErrors: [], websockets: [] };
  await page.route('**/*', (route) => {
    const u = new URL(route.request().url());
    record.requests++;
    record.paths.push(u.pathname);
    if (u.hostname !== '127.0.0.1' && u.protocol !== 'data:' && u.protocol !== 'blob:') {
      record.foreign.push(route.request().url());
      return route.abort();
    }
    return route.continue();
  });
  page.on('websocket', (ws) => {
    record.websockets.push(ws.url());
    if (new URL(ws.url()).hostname !== '127.0.0.1') record.foreign.push(ws.url());
  });
  page.on('console', (msg) => { if (msg.type() === 'error') record.consoleErrors.push(msg.text()); });
  page.on('pageerror', (e) => record.pageErrors.push(String(e)));
  if (beforeGoto) await beforeGoto(page);  // e.g. page.routeWebSocket, which must precede the page's sockets
  await page.goto(url, { waitUntil: 'load' });
  return { context, page, record };
}

export function artifactPath(name) {
  fs.mkdirSync(paths.artifacts, { recursive: true });
  return path.join(paths.artifacts, name);
}

/** Fraction of pixels of a PNG screenshot of the canvas that differ from its background. */
export async function nonBackgroundFraction(page) {
  return page.evaluate(() => window.rmapViewer.nonBackgroundFraction());
}

/** Checks before running: returns a reason to skip, or null. */
export function skipReason() {
  if (!fs.existsSync(paths.chromium)) return `no Chromium at ${paths.chromium} (apt-get install -y chromium)`;
  if (!fs.existsSync(path.join(paths.webRoot, 'node_modules', 'three'))
      || !fs.existsSync(path.join(paths.webRoot, 'node_modules', 'playwright-core'))) {
    return `no ${path.join(paths.webRoot, 'node_modules')} (cd web && npm ci)`;
  }
  return null;
}
