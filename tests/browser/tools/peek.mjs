// Development aid: open the viewer at URL in headless Chromium (the test flags), wait, print the
// page hook's state, console output and requests, and save a screenshot.
//   node tests/browser/tools/peek.mjs URL [seconds] [out.png]
import { launchBrowser, openViewerPage } from '../lib/harness.mjs';

const [url, seconds = '6', out = '/tmp/peek.png'] = process.argv.slice(2);
const browser = await launchBrowser();
const { page, record } = await openViewerPage(browser, url);
page.on('console', (m) => console.log(`console.${m.type()}: ${m.text()}`));
await page.waitForTimeout(Number(seconds) * 1000);
const state = await page.evaluate(() => {
  const v = window.rmapViewer;
  if (!v) return null;
  return { renderer: v.renderer(), map: v.map(), stream: v.streamState(), cuboids: v.cuboidCount(), tiles: v.tilesLoaded(),
    drawn: v.tilesDrawn().length, stats: v.tileStats(), timings: v.timings(), robots: v.robots(), errors: v.errors(), frames: v.frames() };
});
console.log(JSON.stringify(state, null, 1));
console.log('requests', record.requests, 'foreign', record.foreign, 'pageErrors', record.pageErrors);
await page.screenshot({ path: out });
await browser.close();
