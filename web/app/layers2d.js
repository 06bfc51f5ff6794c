// The 2D layers of a map (laser SLAM occupancy and reflectivity rasters, GET …/layers and
// …/layers/{layer}/{z}/{x}/{y}.png): picks a zoom that covers the known cells with a few
// 256-px tiles, fetches them with their ETags and hands them to the renderer as images with
// their map-frame bounds. Slippy convention: tile y grows towards −y of the map frame.

const MAX_TILES_PER_AXIS = 4;

export class Layers2D {
  constructor(api, renderer, { onState } = {}) {
    this.api = api;
    this.renderer = renderer;
    this.onState = onState || (() => {});
    this.map = null;
    this.layer = 'occupancy';
    this.info = null;
    this.tiles = new Map(); // "layer/z/x/y" → {etag, image, bounds}
    this.shown = []; // keys of the tiles the renderer draws
    this.generation = 0;
  }

  /** Shows `layer` of `map`, or nothing when map is null. */
  async show(map, layer) {
    if (map !== this.map || layer !== this.layer) this.clear();
    this.map = map;
    this.layer = layer;
    await this.refresh();
  }

  clear() {
    this.generation++;
    this.tiles.clear();
    this.info = null;
    this.showTiles([]);
  }

  showTiles(list) {
    this.renderer.setLayerTiles(list);
    this.shown = list.map((t) => t.key);
  }

  hide() {
    this.map = null;
    this.clear();
  }

  /** Re-reads the layers' description and refetches tiles whose version changed. */
  async refresh() {
    if (!this.map) return;
    const generation = this.generation;
    const map = encodeURIComponent(this.map);
    let info;
    try {
      info = await this.api.json(`/v1/maps/${map}/layers`);
    } catch (e) {
      if (generation !== this.generation) return;
      this.info = null;
      this.showTiles([]);
      this.onState(e.status === 404 ? 'none' : 'error', e);
      return;
    }
    if (generation !== this.generation) return;
    const unchanged = this.info && this.info.epoch === info.epoch && this.info.version === info.version;
    this.info = info;
    if (unchanged && this.shown.length > 0) return; // same grid: the tiles drawn are current
    if (!info.known_bounds) {
      this.onState('none');
      return;
    }
    const wanted = tilesCovering(info, info.known_bounds);
    await Promise.all(wanted.map((t) => this.fetchTile(map, t, generation)));
    if (generation !== this.generation) return;
    const keys = new Set(wanted.map((t) => `${this.layer}/${t.z}/${t.x}/${t.y}`));
    for (const key of [...this.tiles.keys()]) if (!keys.has(key)) this.tiles.delete(key);
    this.showTiles([...this.tiles.values()].filter((t) => t.image));
    this.onState('shown', info);
  }

  async fetchTile(map, t, generation) {
    const key = `${this.layer}/${t.z}/${t.x}/${t.y}`;
    const held = this.tiles.get(key);
    const response = await this.api.request(`/v1/maps/${map}/layers/${this.layer}/${t.z}/${t.x}/${t.y}.png`,
      { etag: held && held.etag });
    if (generation !== this.generation || response.status === 304) return;
    const image = await createImageBitmap(await response.blob());
    if (generation !== this.generation) return;
    this.tiles.set(key, { key, etag: response.headers.get('ETag'), image, bounds: t.bounds });
  }
}

/** Tiles of the zoom at which `bounds` ({min:[x,y], max:[x,y]}, m) spans at most a few tiles. */
export function tilesCovering(info, bounds) {
  const extent = info.extent_max_m[0] - info.extent_min_m[0];
  const span = Math.max(bounds.max[0] - bounds.min[0], bounds.max[1] - bounds.min[1], 1e-9);
  const z = Math.max(0, Math.min(info.native_zoom, Math.floor(Math.log2((MAX_TILES_PER_AXIS - 1) * extent / span))));
  const n = 2 ** z;
  const edge = extent / n;
  const col = (x) => Math.min(n - 1, Math.max(0, Math.floor((x - info.extent_min_m[0]) / edge)));
  const row = (y) => Math.min(n - 1, Math.max(0, Math.floor((info.extent_max_m[1] - y) / edge)));
  const out = [];
  for (let y = row(bounds.max[1]); y <= row(bounds.min[1]); y++) {
    for (let x = col(bounds.min[0]); x <= col(bounds.max[0]); x++) {
      const x0 = info.extent_min_m[0] + x * edge;
      const y1 = info.extent_max_m[1] - y * edge;
      out.push({ z, x, y, bounds: [x0, y1 - edge, x0 + edge, y1] });
    }
  }
  return out;
}
