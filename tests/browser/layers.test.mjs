// The 2D layers in the viewer: a robot streams laser scans of a room (hand-encoded protobuf
// over the robot WebSocket, from a page of the server's origin); the viewer's "2D layers"
// toggle then draws the occupancy and reflectivity raster tiles of that map.
//
//   node --test tests/browser/layers.test.mjs       (env: RMAPD, RMAP_TEST_ARTIFACTS)

import assert from 'node:assert/strict';
import { after, before, describe, test } from 'node:test';

import { artifactPath, getJson, launchBrowser, log, openViewerPage, startRmapd, waitFor } from './lib/harness.mjs';
import { VIEWER_BACKGROUND, decodePng, foregroundStats } from './lib/png.mjs';

let server;
let browser;

/** Fraction of the viewer's canvas that is not background, from a screenshot. */
async function drawnFraction(page, file) {
  const rect = await page.evaluate(() => {
    const r = document.querySelector('canvas.map-canvas').getBoundingClientRect();
    return { x: r.left, y: r.top, width: r.width, height: r.height };
  });
  const shot = await page.screenshot({ path: artifactPath(file) });
  return foregroundStats(decodePng(shot), VIEWER_BACKGROUND, { rect }).fraction;
}

/** Runs in the page: streams `scans` scans of a 8 m × 6 m room to map `map`; resolves to the acks. */
async function streamRoom({ map, scans }) {
  const varint = (value) => {
    const out = [];
    let n = BigInt(value);
    while (n >= 0x80n) {
      out.push(Number(n & 0x7fn) | 0x80);
      n >>= 7n;
    }
    out.push(Number(n));
    return out;
  };
  const key = (field, wire) => varint((field << 3) | wire);
  const bytes = (field, b) => [...key(field, 2), ...varint(b.length), ...b];
  const text = (field, s) => bytes(field, [...new TextEncoder().encode(s)]);
  const float = (field, v) => {
    const b = new Uint8Array(4);
    new DataView(b.buffer).setFloat32(0, v, true);
    return [...key(field, 5), ...b];
  };
  const floats = (field, list) => {
    const b = new Uint8Array(4 * list.length);
    const view = new DataView(b.buffer);
    list.forEach((v, i) => view.setFloat32(4 * i, v, true));
    return bytes(field, [...b]);
  };
  // Robot at the origin of a room [-4, 4] × [-3, 3]; the east wall is retro-reflective.
  const beams = 720;
  const ranges = [];
  const intensities = [];
  for (let i = 0; i < beams; i++) {
    const a = -Math.PI + (i * 2 * Math.PI) / beams;
    const c = Math.cos(a);
    const s = Math.sin(a);
    const tx = c > 0 ? 4 / c : c < 0 ? -4 / c : Infinity;
    const ty = s > 0 ? 3 / s : s < 0 ? -3 / s : Infinity;
    ranges.push(Math.min(tx, ty));
    intensities.push(tx < ty && c > 0 ? 900 : 250);
  }
  const hello = bytes(2, [...text(1, 'room-bot'), ...text(2, map),
    ...bytes(3, [...text(1, 'front'), ...key(2, 0), ...varint(1), ...text(3, 'browser-laser')])]);
  const ws = new WebSocket(`ws://${location.host}/v1/stream/robot`);
  ws.binaryType = 'arraybuffer';
  const acks = [];
  const errors = [];
  const done = new Promise((resolve) => {
    ws.onmessage = (e) => {
      const first = new Uint8Array(e.data)[0];
      if (first === 0x0a) {
        for (let k = 1; k <= scans; k++) {
          const scan = bytes(3, [...text(1, 'front'), ...key(2, 0), ...varint(k * 100000000),
            ...float(3, -Math.PI), ...float(4, (2 * Math.PI) / beams), ...float(5, 0.05), ...float(6, 20),
            ...floats(7, ranges), ...floats(8, intensities)]);
          ws.send(new Uint8Array([...key(1, 0), ...varint(k), ...scan]));
        }
      } else if (first === 0x12) {
        acks.push(e.data.byteLength);
        if (acks.length === scans) resolve();
      } else if (first === 0x22) {
        errors.push(new TextDecoder().decode(new Uint8Array(e.data)));
        resolve();
      }
    };
  });
  ws.onopen = () => ws.send(new Uint8Array(hello));
  await done;
  ws.close();
  return { acks: acks.length, errors };
}

describe('2D layers in the viewer', { timeout: 120000 }, () => {
  before(async () => {
    server = await startRmapd();
    browser = await launchBrowser();
  });

  after(async () => {
    if (browser) await browser.close().catch(() => {});
    if (server) await server.stop();
  });

  test('the toggle draws the occupancy and reflectivity tiles of a laser map', async () => {
    const feeder = await browser.newPage();
    await feeder.goto(`${server.url}/healthz`);
    const fed = await feeder.evaluate(streamRoom, { map: 'room', scans: 10 });
    assert.deepEqual(fed, { acks: 10, errors: [] });
    const info = await getJson(server, '/v1/maps/room/layers');
    assert.equal(info.scans, 10);
    log(`layers: version ${info.version}, bounds ${JSON.stringify(info.known_bounds)}`);

    const { page, record } = await openViewerPage(browser, `${server.url}/?map=room`);
    await waitFor('the map', () => page.evaluate(() => window.rmapViewer.map() === 'room'), { timeout: 20000 });
    await waitFor('cuboids drawn', () => page.evaluate(() => window.rmapViewer.cuboidCount() > 0), { timeout: 30000 });
    await page.waitForTimeout(500);
    const without = await drawnFraction(page, 'viewer-layers-off.png');

    await page.check('#show-layers');
    await waitFor('occupancy tiles', () => page.evaluate(() => {
      const l = window.rmapViewer.layers();
      return l.available && l.tiles.length > 0 && l.tiles.every((k) => k.startsWith('occupancy/'));
    }), { timeout: 20000 });
    assert.equal(await page.isHidden('#layers-empty'), true);
    // The room's free floor is drawn where the 3D view shows only the planar cloud of walls.
    const withOccupancy = await waitFor('the occupancy view drawn', async () => {
      const f = await drawnFraction(page, 'viewer-layers-occupancy.png');
      return f > without + 0.1 && f;
    }, { timeout: 15000, interval: 500 });
    log(`non-background: ${without.toFixed(4)} without the layer, ${withOccupancy.toFixed(4)} with occupancy`);

    await page.selectOption('#layer-select', 'reflectivity');
    await waitFor('reflectivity tiles', () => page.evaluate(() => {
      const l = window.rmapViewer.layers();
      return l.tiles.length > 0 && l.tiles.every((k) => k.startsWith('reflectivity/'));
    }), { timeout: 20000 });
    // Reflectivity exists only where beams ended (the walls): far less than the occupancy's floor.
    // Polled: a software-WebGL frame can take a while to reach the canvas.
    const withReflectivity = await waitFor('the reflectivity view drawn', async () => {
      const f = await drawnFraction(page, 'viewer-layers-reflectivity.png');
      return f < withOccupancy - 0.1 && f;
    }, { timeout: 15000, interval: 500 });
    log(`non-background with reflectivity: ${withReflectivity.toFixed(4)}`);

    await page.uncheck('#show-layers');
    await waitFor('layers removed', () => page.evaluate(() => window.rmapViewer.layers().tiles.length === 0));
    assert.ok(record.paths.some((p) => p.startsWith('/v1/maps/room/layers/occupancy/')));
    assert.deepEqual(record.foreign, []);
    assert.deepEqual(record.pageErrors, []);
    await page.context().close();
  });
});
