// The outside check's screenshot, reproduced over CDP: chromium --headless --virtual-time-budget=B
// --screenshot loads the page in real time up to its load event, then grants B ms of virtual
// time (policy pauseIfNetworkFetchesPending, maxVirtualTimeTaskStarvationCount 9999), waits for
// Emulation.virtualTimeBudgetExpired and calls Page.captureScreenshot
// (components/headless/command_handler/headless_command.js in Chromium).

/**
 * @param stallMs  real ms the capture may take under paused virtual time before time is let run on
 * @returns {Promise<{png: Buffer|null, loadMs: number, budgetRealMs: number|null, screenshotMs: number|null,
 *   stalledMs?: number, error?: string}>}
 */
export async function virtualTimeScreenshot(page, url, { budgetMs = 15000, timeoutMs = 120000, stallMs = 5000 } = {}) {
  const cdp = await page.context().newCDPSession(page);
  const t0 = Date.now();
  const result = { png: null, loadMs: 0, budgetRealMs: null, screenshotMs: null };
  const timers = [];
  const deadline = (what) => new Promise((_, reject) => {
    timers.push(setTimeout(() => reject(new Error(`${what} did not finish within ${timeoutMs} ms of real time`)),
      Math.max(1, timeoutMs - (Date.now() - t0))));
  });
  try {
    await page.goto(url, { waitUntil: 'load' });
    result.loadMs = Date.now() - t0;
    const expired = new Promise((resolve) => cdp.once('Emulation.virtualTimeBudgetExpired', resolve));
    await cdp.send('Emulation.setVirtualTimePolicy',
      { budget: budgetMs, maxVirtualTimeTaskStarvationCount: 9999, policy: 'pauseIfNetworkFetchesPending' });
    const t1 = Date.now();
    await Promise.race([expired, deadline('the virtual time budget')]);
    result.budgetRealMs = Date.now() - t1;
    const t2 = Date.now();
    const capture = cdp.send('Page.captureScreenshot', { format: 'png' });
    const stall = new Promise((resolve) => { timers.push(setTimeout(() => resolve(null), stallMs)); });
    let shot = await Promise.race([capture, stall]);
    if (shot === null) {
      // The capture waits for a frame that paused virtual time may never let the compositor
      // finish when software GL runs late (busy 2-core machine): let time run on and wait for
      // the same capture, which then shows the page a few frames after the budget.
      result.stalledMs = Date.now() - t2;
      await cdp.send('Emulation.setVirtualTimePolicy', { policy: 'advance' });
      shot = await Promise.race([capture, deadline('Page.captureScreenshot')]);
    }
    result.screenshotMs = Date.now() - t2;
    result.png = Buffer.from(shot.data, 'base64');
  } catch (e) {
    result.error = e.message;
  }
  for (const t of timers) clearTimeout(t);
  await cdp.detach().catch(() => {});
  return result;
}
