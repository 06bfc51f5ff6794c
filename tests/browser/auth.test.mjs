// The viewer against an rmapd with tokens: the page asks for a token on 401, refuses a wrong
// one, and with a viewer token loads the map over HTTP (Authorization: Bearer) and the viewer
// stream (subprotocols rmap.v1 + bearer.<token>); the token survives a reload (sessionStorage).
//
//   node --test tests/browser/auth.test.mjs       (env: RMAPD, RMAP_SIM, RMAP_TEST_ARTIFACTS)

import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { after, before, describe, test } from 'node:test';

import { artifactPath, getJson, launchBrowser, log, openViewerPage, startRmapd, startSim, waitFor } from './lib/harness.mjs';

const ADMIN = 'admin-secret-01';
const VIEWER = 'viewer-secret-1';

let server;
let sim;
let browser;
let dir;

describe('web viewer with tokens', { timeout: 120000 }, () => {
  before(async () => {
    dir = fs.mkdtempSync(path.join(os.tmpdir(), 'rmap-browser-auth-'));
    const config = path.join(dir, 'rmapd.yaml');
    fs.writeFileSync(config, `auth:\n  tokens:\n    - {token: ${ADMIN}, role: admin}\n    - {token: ${VIEWER}, role: viewer}\n`);
    server = await startRmapd({ config });
    sim = startSim(server, { robots: 1, duration: 30, rate: 10, extra: ['--token', ADMIN] });
    await waitFor('map sim', async () => {
      const maps = await getJson(server, '/v1/maps', { Authorization: `Bearer ${VIEWER}` });
      return maps.maps.some((m) => m.name === 'sim' && m.cuboids > 0);
    }, { timeout: 20000 });
    browser = await launchBrowser();
  });

  after(async () => {
    if (browser) await browser.close().catch(() => {});
    if (sim) await sim.stop();
    if (server) await server.stop();
    if (dir) fs.rmSync(dir, { recursive: true, force: true });
  });

  test('token prompt on 401, wrong token refused, viewer token works and is kept', async () => {
    const r = await fetch(`${server.apiUrl}/v1/maps`);
    assert.equal(r.status, 401);
    const { page, record } = await openViewerPage(browser, `${server.url}/`);
    await page.waitForSelector('#token-dialog[open]', { timeout: 15000 });
    log('token dialog shown');

    await page.fill('#token-input', 'not-a-token-at-all');
    await page.click('#token-dialog button[type="submit"]');
    await page.waitForFunction(() => document.querySelector('#token-dialog').open
      && /refused/.test(document.querySelector('#token-reason').textContent), null, { timeout: 15000 });
    log(`wrong token: ${await page.textContent('#token-reason')}`);

    await page.fill('#token-input', VIEWER);
    await page.click('#token-dialog button[type="submit"]');
    await waitFor('cuboids drawn', () => page.evaluate(() => window.rmapViewer.cuboidCount() > 0), { timeout: 30000 });
    await waitFor('the viewer stream', () => page.evaluate(() => window.rmapViewer.streamState() === 'live'), { timeout: 20000 });
    const stored = await page.evaluate(() => sessionStorage.getItem('rmap.token'));
    assert.equal(stored, VIEWER);
    assert.equal(await page.evaluate(() => document.querySelector('#token-dialog').open), false);
    await page.screenshot({ path: artifactPath('viewer-auth.png') });

    // A reload keeps the token: no prompt, the map comes back.
    await page.reload({ waitUntil: 'load' });
    await waitFor('cuboids drawn after reload', () => page.evaluate(() => window.rmapViewer.cuboidCount() > 0), { timeout: 30000 });
    assert.equal(await page.evaluate(() => document.querySelector('#token-dialog').open), false);
    assert.deepEqual(record.foreign, []);
    assert.deepEqual(record.pageErrors, []);
    await page.context().close();
  });
});
