// Tile index, cache and level-of-detail selection.
//
// The index (tileset.json, then kept current by the viewer stream's `tiles` frames) knows every
// non-empty tile of the map on levels 0..6 with its version. Selection walks the levels as an
// octree from level 6 down: a tile is refined into its (up to 8) children on the next finer level
// while one of its cells covers more than `targetPx` pixels on screen; a tile is replaced by its
// children only once all of its visible children are loaded, so the picture goes from coarse to
// fine without holes. Loads are prioritised coarse first, then by distance to the camera.
//
// Cached tiles whose version in the index rises are marked stale and refetched one at a time
// (conditional GET with the tile's ETag); the renderer swaps that tile's cuboids in place.
// An epoch change (rmapd restarted) drops the whole cache.

export const MAX_LEVEL = 6;
export const TILE_CELLS = 64;

const K36 = 2 ** 36;
const K24 = 2 ** 24;
const K12 = 2 ** 12;

/** Numeric key of tile (L, x, y, z); |x|,|y|,|z| ≤ 1026 always holds (API §7.1). */
export function tileKey(L, x, y, z) {
  return L * K36 + (x + 2048) * K24 + (y + 2048) * K12 + (z + 2048);
}
export function keyLevel(key) { return Math.floor(key / K36); }
export function keyX(key) { return (Math.floor(key / K24) % K12) - 2048; }
export function keyY(key) { return (Math.floor(key / K12) % K12) - 2048; }
export function keyZ(key) { return (key % K12) - 2048; }
export function keyName(key) { return `${keyLevel(key)}/${keyX(key)}/${keyY(key)}/${keyZ(key)}`; }

const MAX_LOADS = 6; // browsers open 6 HTTP/1.1 connections per host
const MAX_REFRESHES = 2; // refetches of changed tiles in parallel
const REFRESH_GAP_MS = 250; // pause between refresh rounds (keeps the network idle now and then)
const REFRESH_MIN_INTERVAL_MS = 1000; // per tile

// Binary max-heap of selection nodes by on-screen cell size.
function heapPush(heap, node) {
  heap.push(node);
  let i = heap.length - 1;
  while (i > 0) {
    const p = (i - 1) >> 1;
    if (heap[p].cellPx >= heap[i].cellPx) break;
    [heap[p], heap[i]] = [heap[i], heap[p]];
    i = p;
  }
}

function heapPop(heap) {
  const top = heap[0];
  const last = heap.pop();
  if (heap.length > 0) {
    heap[0] = last;
    let i = 0;
    for (;;) {
      const l = 2 * i + 1;
      const r = l + 1;
      let m = i;
      if (l < heap.length && heap[l].cellPx > heap[m].cellPx) m = l;
      if (r < heap.length && heap[r].cellPx > heap[m].cellPx) m = r;
      if (m === i) break;
      [heap[m], heap[i]] = [heap[i], heap[m]];
      i = m;
    }
  }
  return top;
}

export class TileManager {
  /**
   * @param {import('./api.js').Api} api
   * @param {object} renderer  setTile(key, tile, L) / removeTile(key) / clearTiles() / view
   * @param {{onIndex?:()=>void, onLoaded?:(rec)=>void, onEpochChange?:(epoch)=>void, onError?:(e)=>void}} hooks
   */
  constructor(api, renderer, hooks = {}) {
    this.api = api;
    this.renderer = renderer;
    this.hooks = hooks;
    this.targetPx = 3.0; // a cell may cover up to this many pixels before refining
    this.maxDrawn = 2500000; // cuboids drawn at most (refinement stops beyond)
    this.cacheBudget = 5000000; // cuboids kept in the cache
    this.showFree = false;
    this.reset(null);
  }

  reset(map) {
    if (this.abort) this.abort.abort();
    this.abort = new AbortController();
    this.map = map;
    this.epoch = null;
    this.resolution = 0;
    this.mapVersion = 0;
    this.index = [];
    for (let L = 0; L <= MAX_LEVEL; L++) this.index.push(new Map());
    this.cache = new Map();
    this.drawn = new Set();
    this.gen = 0;
    this.missing = []; // [priority, key] of tiles wanted and not loaded, best first
    this.missingSet = new Set();
    this.loading = 0;
    this.refreshing = 0;
    this.refreshTimer = null;
    this.selectTimer = null;
    this.indexLoaded = false;
    this.indexLoading = null;
    this.drawnCuboids = 0;
    this.nextDrawn = null;
    this.stats = { loads: 0, refreshes: 0, notModified: 0, bytes: 0, errors: 0 };
    if (this.renderer) this.renderer.clearTiles();
  }

  /** Reads tileset.json (again): after the stream's hello, a resync, or a reconnect. */
  refreshIndex() {
    if (!this.map) return Promise.resolve();
    if (this.indexLoading) return this.indexLoading;
    const map = this.map;
    const signal = this.abort.signal;
    this.indexLoading = this.api.json(`/v1/maps/${encodeURIComponent(map)}/tileset.json`, { signal })
      .then((json) => {
        if (map !== this.map) return;
        this.applyTileset(json);
      })
      .catch((e) => {
        if (e.name !== 'AbortError' && this.hooks.onError) this.hooks.onError(e);
      })
      .finally(() => {
        this.indexLoading = null;
      });
    return this.indexLoading;
  }

  applyTileset(json) {
    if (this.epoch !== null && json.epoch !== this.epoch) this.dropCache();
    if (this.epoch !== json.epoch && this.hooks.onEpochChange) this.hooks.onEpochChange(json.epoch);
    this.epoch = json.epoch;
    this.resolution = json.resolution_m;
    this.mapVersion = Math.max(this.mapVersion, json.map_version || 0);
    for (let L = 0; L <= MAX_LEVEL; L++) this.index[L].clear();
    for (const level of json.levels) {
      const idx = this.index[level.level];
      if (!idx) continue;
      for (const [x, y, z, version] of level.tiles) idx.set(tileKey(level.level, x, y, z), version);
    }
    for (const rec of this.cache.values()) {
      const v = this.index[rec.L].get(rec.key);
      if (v === undefined) continue;
      if (rec.tile && v > rec.version) rec.stale = true;
    }
    this.indexLoaded = true;
    if (this.hooks.onIndex) this.hooks.onIndex();
    this.scheduleSelect(0);
  }

  /** A `tiles` frame of the viewer stream: versions of changed tiles. */
  applyTilesFrame(frame) {
    if (frame.map !== this.map || !this.indexLoaded) return;
    this.mapVersion = Math.max(this.mapVersion, frame.map_version || 0);
    for (const t of frame.tiles) {
      const [L, x, y, z, version] = t;
      const idx = this.index[L];
      if (!idx) continue;
      const key = tileKey(L, x, y, z);
      const old = idx.get(key);
      if (old === undefined || version > old) idx.set(key, version);
      const rec = this.cache.get(key);
      if (rec && rec.tile && version > rec.version) rec.stale = true;
    }
    if (this.hooks.onIndex) this.hooks.onIndex();
    this.scheduleSelect(0);
    this.scheduleRefresh(0);
  }

  dropCache() {
    if (this.abort) this.abort.abort();
    this.abort = new AbortController();
    this.cache.clear();
    this.drawn.clear();
    this.missing = [];
    this.missingSet.clear();
    this.loading = 0;
    this.refreshing = 0;
    this.drawnCuboids = 0;
    this.renderer.clearTiles();
  }

  setShowFree(show) {
    this.showFree = show;
    this.scheduleSelect(0);
  }

  // Timers of at least 20 ms: selection and refreshes start HTTP requests, and these should
  // never start in a task that needs no time to pass (see stream.js).
  scheduleSelect(delay = 30) {
    if (this.selectTimer !== null) return;
    delay = Math.max(delay, 20);
    this.selectTimer = setTimeout(() => {
      this.selectTimer = null;
      this.select();
    }, delay);
  }

  tileBox(L, x, y, z, out) {
    const edge = TILE_CELLS * (2 ** L) * this.resolution;
    out[0] = x * edge; out[1] = y * edge; out[2] = z * edge;
    out[3] = out[0] + edge; out[4] = out[1] + edge; out[5] = out[2] + edge;
    return out;
  }

  /**
   * Chooses the tiles to draw for the current view, updates the renderer, queues loads.
   *
   * The drawn set is a cut through the tile octree. Starting from the level-6 tiles, the tile of
   * the cut whose cells look largest on screen is replaced by its visible children, as long as its
   * cells cover more than `targetPx` pixels, it and all those children are loaded, and the cut
   * stays within `maxDrawn` cuboids. Children that are missing are queued for loading (largest
   * on-screen cells first), and their parent stays on screen meanwhile.
   */
  select() {
    if (!this.map || !this.indexLoaded || !this.resolution) return;
    const view = this.renderer.view;
    const gen = ++this.gen;
    this.curGen = gen;
    const nextDrawn = new Set();
    this.nextDrawn = nextDrawn;
    this.wanted = [];
    const box = [0, 0, 0, 0, 0, 0];
    const heap = [];
    const cut = [];
    let total = 0;
    for (const key of this.index[MAX_LEVEL].keys()) {
      const node = this.node(key, view, box);
      if (!node) continue;
      total += node.cost;
      this.place(node, heap, cut);
    }
    while (heap.length > 0) {
      const node = heapPop(heap);
      const children = [];
      const L = node.L;
      const idx = this.index[L - 1];
      for (let i = 0; i < 8; i++) {
        const c = tileKey(L - 1, 2 * node.x + (i & 1), 2 * node.y + ((i >> 1) & 1), 2 * node.z + ((i >> 2) & 1));
        if (!idx.has(c)) continue;
        const child = this.node(c, view, box);
        if (child) children.push(child);
      }
      if (children.length === 0) {
        cut.push(node);
        continue;
      }
      let all = true;
      let cost = 0;
      for (const child of children) {
        if (!child.rec || !child.rec.tile) all = false;
        cost += child.cost;
      }
      if (!all || total - node.cost + cost > this.maxDrawn) {
        cut.push(node);
        if (!all) for (const child of children) if (!child.rec || !child.rec.tile) this.want(child.key, child.cellPx);
        continue;
      }
      total += cost - node.cost;
      for (const child of children) this.place(child, heap, cut);
    }
    for (const node of cut) {
      if (node.rec && node.rec.tile) this.draw(node.rec);
      else {
        this.want(node.key, Infinity);
        this.drawLoadedBelow(node.L, node.x, node.y, node.z, view, box);
      }
    }

    // Renderer diff: removals first so their slots can be reused.
    for (const key of this.drawn) {
      if (!nextDrawn.has(key)) this.renderer.removeTile(key);
    }
    let drawnCuboids = 0;
    for (const key of nextDrawn) {
      const rec = this.cache.get(key);
      drawnCuboids += this.cost(rec);
      if (!this.drawn.has(key)) this.renderer.setTile(key, rec.tile, rec.L);
    }
    this.drawn = nextDrawn;
    this.nextDrawn = null;
    this.drawnCuboids = drawnCuboids;

    // Loads: largest on-screen cells first (coarse and near before fine and far).
    this.wanted.sort((a, b) => b[0] - a[0]);
    this.missing = this.wanted;
    this.missingSet = new Set();
    for (const w of this.missing) this.missingSet.add(w[1]);
    this.wanted = null;
    this.pump();
    this.scheduleRefresh(0);
    this.evict();
    if (this.loading === 0 && this.missing.length === 0 && this.hooks.onIdle) this.hooks.onIdle();
  }

  cost(rec) {
    if (!rec || !rec.tile) return 0;
    return rec.occupied + (this.showFree ? rec.tile.count - rec.occupied : 0);
  }

  /** A visible tile of the index as a selection node, or null when off screen. */
  node(key, view, box) {
    const L = keyLevel(key);
    const x = keyX(key);
    const y = keyY(key);
    const z = keyZ(key);
    this.tileBox(L, x, y, z, box);
    if (!view.boxVisible(box)) return null;
    const rec = this.cache.get(key);
    if (rec) rec.used = this.curGen;
    const cellPx = this.resolution * (2 ** L) * view.pixelsPerMetre(view.boxDistance(box));
    return { key, L, x, y, z, rec, cellPx, cost: this.cost(rec) };
  }

  // Into the refinement heap when worth refining and loaded, else final.
  place(node, heap, cut) {
    if (node.L > 0 && node.cellPx > this.targetPx && node.rec && node.rec.tile) heapPush(heap, node);
    else cut.push(node);
  }

  loaded(key) {
    const rec = this.cache.get(key);
    return rec !== undefined && rec.tile !== null;
  }

  want(key, priority) {
    if (this.loaded(key)) return;
    this.wanted.push([priority, key]);
  }

  draw(rec) {
    this.nextDrawn.add(rec.key);
    rec.used = this.curGen;
  }

  visibleChildren(L, x, y, z, view, box) {
    const out = [];
    const idx = this.index[L - 1];
    for (let i = 0; i < 8; i++) {
      const cx = 2 * x + (i & 1);
      const cy = 2 * y + ((i >> 1) & 1);
      const cz = 2 * z + ((i >> 2) & 1);
      const c = tileKey(L - 1, cx, cy, cz);
      if (!idx.has(c)) continue;
      this.tileBox(L - 1, cx, cy, cz, box);
      if (view.boxVisible(box)) out.push(c);
    }
    return out;
  }

  // While a tile loads, show what the cache holds below it (e.g. when zooming out).
  drawLoadedBelow(L, x, y, z, view, box) {
    if (L === 0) return;
    for (const c of this.visibleChildren(L, x, y, z, view, box)) {
      const rec = this.cache.get(c);
      if (rec && rec.tile) this.draw(rec);
      else this.drawLoadedBelow(L - 1, keyX(c), keyY(c), keyZ(c), view, box);
    }
  }

  pump() {
    while (this.loading < MAX_LOADS && this.missing.length > 0) {
      const [, key] = this.missing.shift();
      this.missingSet.delete(key);
      let rec = this.cache.get(key);
      if (rec && (rec.tile || rec.loading)) continue;
      if (!rec) {
        rec = { key, L: keyLevel(key), tile: null, version: 0, etag: null, loading: false, stale: false,
          lastFetch: 0, used: this.curGen, occupied: 0 };
        this.cache.set(key, rec);
      }
      this.fetchTile(rec, false);
    }
  }

  async fetchTile(rec, refresh) {
    rec.loading = true;
    rec.lastFetch = performance.now();
    if (refresh) this.refreshing++;
    else this.loading++;
    const signal = this.abort.signal;
    const map = this.map;
    try {
      const tile = await this.api.tile(map, rec.L, keyX(rec.key), keyY(rec.key), keyZ(rec.key),
        { etag: refresh ? rec.etag : null, signal });
      if (signal.aborted || map !== this.map) return;
      if (tile === null) {
        // 304: unchanged since our copy.
        this.stats.notModified++;
        rec.stale = false;
        return;
      }
      if (this.epoch !== null && tile.epoch !== this.epoch) {
        // rmapd restarted since the index was read: start again from a fresh tileset.json.
        this.refreshIndex();
        return;
      }
      let occupied = 0;
      const p = tile.probability;
      for (let k = 0; k < p.length; k++) if (p[k] >= 0.5) occupied++;
      rec.tile = tile;
      rec.occupied = occupied;
      rec.version = tile.version;
      rec.etag = tile.etag;
      rec.stale = (this.index[rec.L].get(rec.key) || 0) > tile.version;
      if (refresh) this.stats.refreshes++;
      else this.stats.loads++;
      if (this.drawn.has(rec.key)) this.renderer.setTile(rec.key, tile, rec.L);
      if (this.hooks.onLoaded) this.hooks.onLoaded(rec);
      this.scheduleSelect(refresh ? 100 : 10);
    } catch (e) {
      if (e.name === 'AbortError' || signal.aborted) return;
      this.stats.errors++;
      if (this.hooks.onError) this.hooks.onError(e);
      if (!rec.tile) this.cache.delete(rec.key);
    } finally {
      if (!signal.aborted) {
        rec.loading = false;
        if (refresh) this.refreshing--;
        else this.loading--;
        this.pump();
        if (refresh) this.scheduleRefresh(REFRESH_GAP_MS);
      }
    }
  }

  // Changed tiles that are on screen are refetched a few at a time with pauses in between, so a
  // busy map never keeps the connection saturated (missing tiles always go first).
  scheduleRefresh(delay) {
    if (this.refreshTimer !== null) return;
    delay = Math.max(delay, 20);
    this.refreshTimer = setTimeout(() => {
      this.refreshTimer = null;
      this.refresh();
    }, delay);
  }

  refresh() {
    if (this.missing.length > 0 || this.loading > 0) {
      if (this.refreshing === 0) this.scheduleRefresh(REFRESH_GAP_MS);
      return;
    }
    const now = performance.now();
    let waiting = false;
    const candidates = [];
    for (const key of this.drawn) {
      const rec = this.cache.get(key);
      if (!rec || !rec.stale || rec.loading) continue;
      if (now - rec.lastFetch < REFRESH_MIN_INTERVAL_MS) {
        waiting = true;
        continue;
      }
      candidates.push(rec);
    }
    // Coarse first (they are what is seen when zoomed out), then the oldest.
    candidates.sort((a, b) => (b.L - a.L) || (a.lastFetch - b.lastFetch));
    for (const rec of candidates) {
      if (this.refreshing >= MAX_REFRESHES) break;
      this.fetchTile(rec, true);
    }
    if (this.refreshing === 0 && (waiting || candidates.length > 0)) this.scheduleRefresh(REFRESH_GAP_MS);
  }

  evict() {
    let total = 0;
    for (const rec of this.cache.values()) if (rec.tile) total += rec.tile.count;
    if (total <= this.cacheBudget) return;
    const old = [];
    for (const rec of this.cache.values()) {
      if (rec.tile && !rec.loading && !this.drawn.has(rec.key)) old.push(rec);
    }
    old.sort((a, b) => a.used - b.used);
    for (const rec of old) {
      if (total <= this.cacheBudget * 0.8) break;
      total -= rec.tile.count;
      this.cache.delete(rec.key);
    }
  }

  /** True while tiles the current view wants are still missing. */
  pending() {
    return this.missing.length + this.loading;
  }

  staleDrawn() {
    let n = 0;
    for (const key of this.drawn) if (this.cache.get(key)?.stale) n++;
    return n;
  }

  loadedCount() {
    let n = 0;
    for (const rec of this.cache.values()) if (rec.tile) n++;
    return n;
  }

  /** {"L/x/y/z": version} of every cached tile. */
  versions() {
    const out = {};
    for (const rec of this.cache.values()) if (rec.tile) out[keyName(rec.key)] = rec.version;
    return out;
  }

  /** Drawn tiles as records (for picking and the 2D renderer). */
  *drawnRecords() {
    for (const key of this.drawn) {
      const rec = this.cache.get(key);
      if (rec && rec.tile) yield rec;
    }
  }
}
