// Loop closures in the web viewer: two simulated 2D-laser robots (rmap-sim) map one building
// and rmapd finds loop closures between their places; the viewer lists them (with each one's
// measured relative pose as distance and turn) and draws each as a line between its two poses
// in its source's colour (web/app/colors.js LOOP_COLORS), and the lines show in a screenshot.
// rmapd runs with a wide ambiguity margin and keeps ambiguous matches, so that some geometry
// closures carry an `ambiguous_direction` (the simulated buildings have no long corridor), which
// the list marks with "↔".
//
//   node --test tests/browser/loop_closures.test.mjs      (env: RMAPD, RMAP_SIM, RMAP_TEST_ARTIFACTS)

import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { after, before, describe, test } from 'node:test';

import {
  artifactPath, getJson, launchBrowser, log, openViewerPage, startRmapd, startSim, waitFor,
} from './lib/harness.mjs';
import { decodePng } from './lib/png.mjs';

// web/app/colors.js LOOP_COLORS, as the test expects them on screen.
const LOOP_COLORS = { camera: '#ffd54a', laser_intensity: '#ff4df0', geometry: '#4dd0ff' };

let server;
let sim;
let browser;
let configDir;

/** Pixels of a screenshot inside `rect` within `tolerance` of a CSS colour. */
function pixelsOf(png, rect, css, tolerance = 40) {
  const rgb = [1, 3, 5].map((i) => parseInt(css.slice(i, i + 2), 16));
  let n = 0;
  for (let y = Math.max(0, Math.floor(rect.y)); y < Math.min(png.height, rect.y + rect.height); y++) {
    for (let x = Math.max(0, Math.floor(rect.x)); x < Math.min(png.width, rect.x + rect.width); x++) {
      const o = 4 * (y * png.width + x);
      if (Math.abs(png.rgba[o] - rgb[0]) <= tolerance && Math.abs(png.rgba[o + 1] - rgb[1]) <= tolerance
          && Math.abs(png.rgba[o + 2] - rgb[2]) <= tolerance) n++;
    }
  }
  return n;
}

describe('loop closures in the viewer', { timeout: 200000 }, () => {
  before(async () => {
    configDir = fs.mkdtempSync(path.join(os.tmpdir(), 'rmap-loops-'));
    const config = path.join(configDir, 'rmapd.yaml');
    fs.writeFileSync(config, 'slam2d:\n  loop_closure:\n    ambiguity_margin: 0.15\n    ambiguous_min_score: 0\n');
    server = await startRmapd({ config });
    log(`rmapd ${server.apiUrl} (viewer at ${server.url})`);
    sim = startSim(server, { robots: 0, duration: 150, rate: 0, extra: ['--laser2d-robots', '2'] });
    // Until one of them is ambiguous: the first few seldom are (one CI run listed 39, none).
    await waitFor('an ambiguous loop closure of map sim', async () => {
      const json = await getJson(server, '/v1/loop-closures?map=sim&limit=100000');
      return json.loop_closures.some((c) => c.ambiguous_direction);
    }, { timeout: 120000, interval: 500 });
    browser = await launchBrowser();
  });

  after(async () => {
    if (browser) await browser.close().catch(() => {});
    if (sim) await sim.stop();
    if (server) await server.stop();
    if (configDir) fs.rmSync(configDir, { recursive: true, force: true });
  });

  test('each stored loop closure is listed and drawn as a line in its source colour', async () => {
    const stored = (await getJson(server, '/v1/loop-closures?map=sim&limit=100000')).loop_closures;
    const bySource = {};
    for (const c of stored) bySource[c.source] = (bySource[c.source] || 0) + 1;
    log(`loop closures stored: ${JSON.stringify(bySource)}`);
    const { context, page, record } = await openViewerPage(browser, `${server.url}/?map=sim`);
    try {
      const hook = (fn) => page.evaluate(`(${fn.toString()})(window.rmapViewer)`);
      await waitFor('the viewer has read the stored loop closures', async () => {
        const ids = new Set(await hook((v) => v.loopClosures().map((e) => e.id)));
        return stored.every((c) => ids.has(c.id));
      }, { timeout: 30000 });
      const lines = await hook((v) => v.loopLines());
      log(`lines drawn by colour: ${JSON.stringify(lines)}`);
      for (const [source, count] of Object.entries(bySource)) {
        assert.ok(LOOP_COLORS[source], `unknown source ${source}`);
        assert.ok((lines[LOOP_COLORS[source]] || 0) >= count, `${source}: ${count} stored, lines ${JSON.stringify(lines)}`);
      }
      const items = await page.locator('#loops li').count();
      assert.ok(items > 0, 'the loop closure list is empty');
      assert.equal(await page.locator('#loops-empty').isHidden(), true);
      // Each listed closure shows its measured relative pose as distance and turn (none: empty).
      const listed = await page.$$eval('#loops li', (lis) => lis.map((li) => ({
        name: li.querySelector('.name').textContent,
        offset: li.querySelector('.loop-offset').textContent,
        title: li.querySelector('.loop-offset').title,
      })));
      // Read again: the list shows the newest closures, pushed (once stored) since the first read.
      const latest = (await getJson(server, '/v1/loop-closures?map=sim&limit=100000')).loop_closures;
      const byId = new Map(latest.map((c) => [c.id, c]));
      let measured = 0;
      let ambiguous = 0;
      for (const { name, offset, title } of listed) {
        const c = byId.get(Number(/^#(\d+)/.exec(name)[1]));
        assert.ok(c, `listed ${name} is not stored`);
        let expected = '';
        if (c.relative_pose) {
          const [x, y, z] = c.relative_pose.position;
          const turn = (2 * Math.acos(Math.min(1, Math.abs(c.relative_pose.orientation[0]))) * 180) / Math.PI;
          expected = `${Math.hypot(x, y, z).toFixed(2)} m ${turn.toFixed(1)}°`;
          measured += 1;
          // An ambiguous closure is marked, and its tooltip names the direction it leaves open.
          const along = c.ambiguous_direction;
          if (along) {
            expected += ' ↔';
            ambiguous += 1;
            assert.ok(title.includes(`(${along[0].toFixed(2)}, ${along[1].toFixed(2)})`), `closure ${c.id}: ${title}`);
          }
        }
        assert.equal(offset, expected, `closure ${c.id}`);
      }
      log(`listed ${listed.length} closures, ${measured} with a measured relative pose, ${ambiguous} ambiguous`);
      assert.ok(measured > 0, 'no listed closure shows a measured relative pose');
      assert.ok(ambiguous > 0, 'no listed closure is marked ambiguous');
      // The lines are on the map's canvas (not only in the list), in the colours of their sources.
      await waitFor('the map drawn', async () => hook((v) => v.cuboidCount() > 0 && v.tileStats().pending === 0),
        { timeout: 60000 });
      await page.click('#fit-view');
      await page.waitForTimeout(1500);
      const rect = await page.evaluate(() => {
        const r = document.querySelector('canvas.map-canvas').getBoundingClientRect();
        return { x: r.left, y: r.top, width: r.width, height: r.height };
      });
      const shot = decodePng(await page.screenshot({ path: artifactPath('loop-closures.png') }));
      for (const source of Object.keys(bySource)) {
        const n = pixelsOf(shot, rect, LOOP_COLORS[source]);
        log(`${source}: ${n} pixels of ${LOOP_COLORS[source]}`);
        assert.ok(n > 20, `${source} lines not visible (${n} pixels)`);
      }
      assert.deepEqual(record.pageErrors, []);
      assert.deepEqual(record.foreign, []);
    } finally {
      await context.close();
    }
  });

  // rmapd pushes `loop_closure_withdrawn` when the 2D pose graph drops a closure it reported
  // (docs/API.md §6.10, §8; tests/unit/app/mapping_service_test.cc); the simulated run has no
  // such closure, so the test forwards the real stream and adds one frame for a listed closure.
  test('a withdrawn loop closure stays listed, struck through, and is no longer drawn', async () => {
    const streams = [];  // every viewer stream the page opened (it reconnects after errors)
    const { context, page, record } = await openViewerPage(browser, `${server.url}/?map=sim`, {
      beforeGoto: (p) => p.routeWebSocket(/\/v1\/stream\/viewer/, (ws) => {
        ws.connectToServer();  // without handlers both ways are forwarded as they are
        streams.push(ws);
      }),
    });
    try {
      const hook = (fn, arg) => page.evaluate(`(${fn.toString()})(window.rmapViewer, ${JSON.stringify(arg)})`);
      // The viewer's state and its page at one instant: closures arrive several a second, and each
      // one rebuilds the list (the newest 200) and the lines.
      const view = (v, id) => {
        const li = [...document.querySelectorAll('#loops li')]
          .find((l) => l.querySelector('.name').textContent.startsWith(`#${id} `));
        const held = v.loopClosures().filter((e) => e.source === 'geometry' && e.query.position && e.match.position
          && e.withdrawn_ns == null);
        return {
          listed: !!li,
          struck: li ? getComputedStyle(li).textDecorationLine : null,
          title: li ? li.title : null,
          classes: li ? [...li.classList] : [],
          event: v.loopClosures().find((e) => e.id === id) || null,
          heldIds: held.map((e) => e.id),
          lines: v.loopLines()['#4dd0ff'] || 0,  // geometry's colour (LOOP_COLORS)
        };
      };
      let target;
      await waitFor('a listed geometry closure that is drawn', async () => {
        target = await hook((v) => {
          const byId = new Map(v.loopClosures().map((e) => [e.id, e]));
          return [...document.querySelectorAll('#loops li .name')]
            .map((n) => byId.get(Number(/^#(\d+)/.exec(n.textContent)[1])))
            .find((e) => e && e.source === 'geometry' && e.query.position && e.match.position) || null;
        });
        return target !== null;
      }, { timeout: 30000 });
      const before = await hook(view, target.id);
      assert.equal(before.lines, before.heldIds.length, 'every held geometry closure is drawn');
      assert.ok(before.heldIds.includes(target.id));
      assert.ok(streams.length > 0, 'the viewer stream was not routed');
      const withdrawnNs = Date.now() * 1e6;
      const frame = JSON.stringify({ ...target, type: 'loop_closure_withdrawn', withdrawn_ns: withdrawnNs });
      for (const ws of streams) ws.send(frame);
      let after;
      await waitFor(`closure ${target.id} withdrawn in the viewer`, async () => {
        after = await hook(view, target.id);
        return after.event?.withdrawn_ns === withdrawnNs;
      }, { timeout: 20000 });
      // Checked in the same instant as the state: the list was rebuilt when the frame came in.
      assert.ok(after.listed, `closure ${target.id} is no longer among the listed`);
      assert.ok(after.classes.includes('withdrawn'), JSON.stringify(after.classes));
      assert.equal(after.struck, 'line-through');
      assert.match(after.title, /withdrawn/);
      assert.ok(!after.heldIds.includes(target.id));
      assert.equal(after.lines, after.heldIds.length, 'the withdrawn closure is still drawn');
      log(`closure ${target.id} withdrawn: ${before.lines} geometry lines before, ${after.lines} after`);
      assert.deepEqual(record.pageErrors, []);
    } finally {
      await context.close();
    }
  });
});
