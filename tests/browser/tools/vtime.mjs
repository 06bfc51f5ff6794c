// Development aid, and the model of the outside check: what `chromium --headless
// --virtual-time-budget=B --screenshot` does (components/headless/command_handler/headless_command.js):
// load the page (real time, until the load event), then setVirtualTimePolicy
// {policy: pauseIfNetworkFetchesPending, budget: B, maxVirtualTimeTaskStarvationCount: 9999},
// wait for Emulation.virtualTimeBudgetExpired, then Page.captureScreenshot.
//   node tests/browser/tools/vtime.mjs URL [budget_ms] [out.png]
import fs from 'node:fs';
import { launchBrowser } from '../lib/harness.mjs';
import { virtualTimeScreenshot } from '../lib/virtual_time.mjs';

const [url, budget = '15000', out = '/tmp/vtime.png'] = process.argv.slice(2);
const browser = await launchBrowser();
const context = await browser.newContext({ viewport: { width: 1280, height: 800 } });
const page = await context.newPage();
const t0 = Date.now();
page.on('console', (m) => console.log(`[real ${((Date.now() - t0) / 1000).toFixed(2)} s] ${m.text()}`));
const result = await virtualTimeScreenshot(page, url, { budgetMs: Number(budget), timeoutMs: 120000 });
console.log(JSON.stringify({ ...result, png: undefined }));
if (result.png) fs.writeFileSync(out, result.png);
await browser.close();
