// The viewer WebSocket (/v1/stream/viewer): JSON frames hello | tiles | poses | resync, and
// loop-closure events when the server starts sending them. Reconnects with exponential
// back-off (0.5 s doubling to 30 s, with jitter), reset once a hello arrives.

export class ViewerStream {
  /**
   * @param {import('./api.js').Api} api
   * @param {{onFrame:(f:object)=>void, onHello:()=>void, onStatus:(state:string, detail:string)=>void,
   *          onFailure:()=>Promise<void>|void}} handlers
   */
  constructor(api, handlers) {
    this.api = api;
    this.handlers = handlers;
    this.map = null;
    this.ws = null;
    this.delayMs = 500;
    this.timer = null;
    this.stopped = true;
    this.frames = 0;
    this.connects = 0;
    this.lastFrameAt = 0;
    this.queue = [];
    this.drainTimer = null;
  }

  /** (Re)connects for one map ('' = every map). */
  connect(map) {
    this.stop();
    this.map = map;
    this.stopped = false;
    this.delayMs = 500;
    this.open();
  }

  stop() {
    this.stopped = true;
    this.queue = [];
    clearTimeout(this.timer);
    this.timer = null;
    if (this.ws) {
      const ws = this.ws;
      this.ws = null;
      ws.onopen = ws.onmessage = ws.onclose = ws.onerror = null;
      try {
        ws.close(1000, 'viewer closed');
      } catch {
        // already closed
      }
    }
  }

  open() {
    if (this.stopped) return;
    const query = this.map ? `?map=${encodeURIComponent(this.map)}` : '';
    let ws;
    try {
      ws = new WebSocket(this.api.wsUrl(`/v1/stream/viewer${query}`), this.api.wsProtocols());
    } catch (e) {
      this.scheduleReconnect(`cannot open WebSocket: ${e.message}`);
      return;
    }
    this.ws = ws;
    this.connects++;
    this.handlers.onStatus('connecting', 'connecting…');
    let gotHello = false;
    ws.onmessage = (event) => {
      if (typeof event.data !== 'string') return;
      let frame;
      try {
        frame = JSON.parse(event.data);
      } catch {
        return;
      }
      this.frames++;
      this.lastFrameAt = performance.now();
      if (frame.type === 'hello') {
        gotHello = true;
        this.delayMs = 500;
        this.handlers.onStatus('live', 'live');
      }
      this.enqueue(frame);
    };
    ws.onclose = (event) => {
      if (this.ws !== ws) return;
      this.ws = null;
      const why = event.code === 1001 ? 'server stopping' : event.reason || `closed (${event.code})`;
      // A refused upgrade (401/403/404) looks like a plain failure in browsers: let the page probe
      // over HTTP, where the status is visible (and a 401 brings up the token prompt).
      if (gotHello) this.scheduleReconnect(why);
      else setTimeout(() => Promise.resolve(this.handlers.onFailure()).finally(() => this.scheduleReconnect(why)), 20);
    };
    ws.onerror = () => {
      // onclose follows and handles it.
    };
  }

  // Frames are handled in a timer task a few milliseconds later, in batches, never inside the
  // message event: work that a frame starts (HTTP requests) then waits for time to pass, so a page
  // whose clock is paused (a headless screenshot after its virtual-time budget) stays quiet.
  enqueue(frame) {
    this.queue.push(frame);
    if (this.drainTimer !== null) return;
    this.drainTimer = setTimeout(() => {
      this.drainTimer = null;
      const frames = this.queue;
      this.queue = [];
      for (const f of frames) {
        if (this.stopped) return;
        if (f.type === 'hello') this.handlers.onHello(f);
        else this.handlers.onFrame(f);
      }
    }, 30);
  }

  scheduleReconnect(why) {
    if (this.stopped) return;
    const delay = this.delayMs * (0.8 + 0.4 * Math.random());
    this.delayMs = Math.min(this.delayMs * 2, 30000);
    const until = Date.now() + delay;
    this.handlers.onStatus('reconnecting', `${why}; retrying in ${(delay / 1000).toFixed(1)} s`, until);
    clearTimeout(this.timer);
    this.timer = setTimeout(() => this.open(), delay);
  }

  /** Reconnect now (e.g. after the user entered a token). */
  retryNow() {
    if (this.stopped) return;
    clearTimeout(this.timer);
    if (this.ws) return;
    this.open();
  }
}
