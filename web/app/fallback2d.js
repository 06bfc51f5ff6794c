// Canvas 2D renderer, used only when WebGL is unavailable: the map seen from above, occupied
// cuboids drawn lowest first and coloured like the 3D view, robots, trajectories and loop
// closures on top. Drag to pan, wheel to zoom. Same interface as Renderer3D.

import { cuboidColor, loopColor } from './colors.js';
import { pickTiles } from './scene3d.js';

const BACKGROUND = '#12161c';
const BINS = 24;

function toCss(rgb) {
  const s = (v) => Math.round(255 * (v <= 0.0031308 ? 12.92 * v : 1.055 * v ** (1 / 2.4) - 0.055));
  return `rgb(${s(rgb[0])},${s(rgb[1])},${s(rgb[2])})`;
}

export class Renderer2D {
  constructor(container) {
    this.kind = 'canvas2d';
    this.container = container;
    this.canvas = document.createElement('canvas');
    this.canvas.className = 'map-canvas';
    container.appendChild(this.canvas);
    this.ctx = this.canvas.getContext('2d');
    this.tiles = new Map();
    this.robots = new Map();
    this.loops = [];
    this.layerTiles = [];
    this.colorMode = 'height';
    this.zLo = 0;
    this.zHi = 3;
    this.showFree = false;
    this.cx = 0;
    this.cy = 0;
    this.scale = 20; // px per metre
    this.dirty = true;
    this.timer = null;
    this.frames = 0;
    this.userMoved = false;
    this.controlsEnabled = true;
    this.highlight = null;
    this.selection = null;
    this.onViewChange = null;
    this.onRendered = null;
    this.rgb = new Float32Array(3);
    this.colorCache = new Map();
    const self = this;
    this.view = {
      boxVisible(b) {
        const w = self.canvas.width / self.scale / 2;
        const h = self.canvas.height / self.scale / 2;
        return b[3] >= self.cx - w && b[0] <= self.cx + w && b[4] >= self.cy - h && b[1] <= self.cy + h;
      },
      boxDistance() { return 0; },
      pixelsPerMetre() { return self.scale; },
    };
    this.installInput();
    this.resize();
    let resizeTimer = null;
    new ResizeObserver(() => {
      clearTimeout(resizeTimer);
      resizeTimer = setTimeout(() => this.resize(), 120); // meanwhile CSS stretches the last frame
    }).observe(container);
  }

  installInput() {
    let drag = null;
    this.canvas.addEventListener('pointerdown', (e) => {
      if (!this.controlsEnabled || e.button !== 0) return;
      drag = { x: e.clientX, y: e.clientY, cx: this.cx, cy: this.cy };
    });
    window.addEventListener('pointermove', (e) => {
      if (!drag) return;
      this.cx = drag.cx - (e.clientX - drag.x) / this.scale;
      this.cy = drag.cy + (e.clientY - drag.y) / this.scale;
      this.userMoved = true;
      this.viewChanged();
    });
    window.addEventListener('pointerup', () => { drag = null; });
    this.canvas.addEventListener('wheel', (e) => {
      e.preventDefault();
      const [wx, wy] = this.toWorld(e.clientX, e.clientY);
      this.scale *= Math.exp(-e.deltaY * 0.0015);
      this.scale = Math.min(Math.max(this.scale, 0.05), 5000);
      const [nx, ny] = this.toWorld(e.clientX, e.clientY);
      this.cx += wx - nx;
      this.cy += wy - ny;
      this.userMoved = true;
      this.viewChanged();
    }, { passive: false });
  }

  resize() {
    const ratio = Math.min(window.devicePixelRatio || 1, 2);
    this.canvas.width = Math.max(1, Math.round(this.container.clientWidth * ratio));
    this.canvas.height = Math.max(1, Math.round(this.container.clientHeight * ratio));
    this.ratio = ratio;
    this.viewChanged();
    if (this.frames > 0) this.renderNow(); // resizing cleared the canvas
  }

  viewChanged() {
    this.requestRender();
    if (this.onViewChange) this.onViewChange();
  }

  toWorld(clientX, clientY) {
    const rect = this.canvas.getBoundingClientRect();
    const px = (clientX - rect.left) * this.ratio;
    const py = (clientY - rect.top) * this.ratio;
    return [this.cx + (px - this.canvas.width / 2) / this.scale, this.cy - (py - this.canvas.height / 2) / this.scale];
  }

  sx(x) { return (x - this.cx) * this.scale + this.canvas.width / 2; }
  sy(y) { return this.canvas.height / 2 - (y - this.cy) * this.scale; }

  requestRender() {
    this.dirty = true;
    if (this.timer !== null) return;
    const run = () => {
      this.timer = null;
      if (this.dirty) this.renderNow();
    };
    this.timer = setTimeout(run, 16);
  }

  renderNow() {
    this.dirty = false;
    const ctx = this.ctx;
    ctx.fillStyle = BACKGROUND;
    ctx.fillRect(0, 0, this.canvas.width, this.canvas.height);
    ctx.imageSmoothingEnabled = false; // one cell per pixel at the native zoom
    for (const t of this.layerTiles) {
      const [x0, y0, x1, y1] = t.bounds;
      ctx.drawImage(t.image, this.sx(x0), this.sy(y1), (x1 - x0) * this.scale, (y1 - y0) * this.scale);
    }
    // Bucket cuboids by top height so higher ones are drawn over lower ones.
    const bins = [];
    for (let i = 0; i < BINS; i++) bins.push([]);
    const span = Math.max(this.zHi - this.zLo, 1e-6);
    const cut = Number.isFinite(this.zCut) ? this.zCut : Infinity;
    for (const tile of this.tiles.values()) {
      const r = tile.resolution;
      for (let k = 0; k < tile.count; k++) {
        const p = tile.probability[k];
        if (p < 0.5 && !this.showFree) continue;
        if (tile.minCell[3 * k + 2] * r > cut) continue;
        const top = (tile.maxCell[3 * k + 2] + 1) * r;
        const bin = Math.min(BINS - 1, Math.max(0, Math.floor(((top - this.zLo) / span) * BINS)));
        bins[bin].push(tile, k);
      }
    }
    for (const bin of bins) {
      for (let i = 0; i < bin.length; i += 2) {
        const tile = bin[i];
        const k = bin[i + 1];
        const r = tile.resolution;
        const a = 3 * k;
        cuboidColor(tile, k, this.colorMode, this.zLo, this.zHi, r, this.rgb, 0);
        ctx.globalAlpha = tile.probability[k] < 0.5 ? 0.15 : 1;
        ctx.fillStyle = this.css(this.rgb);
        const x0 = this.sx(tile.minCell[a] * r);
        const y0 = this.sy((tile.maxCell[a + 1] + 1) * r);
        const w = (tile.maxCell[a] + 1 - tile.minCell[a]) * r * this.scale;
        const h = (tile.maxCell[a + 1] + 1 - tile.minCell[a + 1]) * r * this.scale;
        ctx.fillRect(x0, y0, Math.max(w, 1), Math.max(h, 1));
      }
    }
    ctx.globalAlpha = 1;
    ctx.lineWidth = 1.5 * this.ratio;
    for (const robot of this.robotsVisible === false ? [] : this.robots.values()) {
      if (robot.count > 1) {
        ctx.strokeStyle = robot.color;
        ctx.beginPath();
        for (let i = 0; i < robot.count; i++) {
          const x = this.sx(robot.flat[3 * i]);
          const y = this.sy(robot.flat[3 * i + 1]);
          if (i === 0) ctx.moveTo(x, y);
          else ctx.lineTo(x, y);
        }
        ctx.stroke();
      }
      if (robot.pose) {
        const [w, qx, qy, qz] = robot.pose.orientation;
        const yaw = Math.atan2(2 * (w * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz));
        const x = this.sx(robot.pose.position[0]);
        const y = this.sy(robot.pose.position[1]);
        const s = 9 * this.ratio;
        ctx.fillStyle = robot.color;
        ctx.beginPath();
        ctx.moveTo(x + s * Math.cos(yaw), y - s * Math.sin(yaw));
        ctx.lineTo(x + 0.6 * s * Math.cos(yaw + 2.4), y - 0.6 * s * Math.sin(yaw + 2.4));
        ctx.lineTo(x + 0.6 * s * Math.cos(yaw - 2.4), y - 0.6 * s * Math.sin(yaw - 2.4));
        ctx.closePath();
        ctx.fill();
      }
    }
    for (const lc of this.loops) {
      ctx.strokeStyle = ctx.fillStyle = loopColor(lc.source);
      ctx.lineWidth = lc.fresh ? 2 : 1;
      ctx.beginPath();
      ctx.moveTo(this.sx(lc.a[0]), this.sy(lc.a[1]));
      ctx.lineTo(this.sx(lc.b[0]), this.sy(lc.b[1]));
      ctx.stroke();
      // A dot at each pose: the two poses of a recognised place may be centimetres apart.
      const r = lc.fresh ? 3.5 : 2.5;
      for (const p of [lc.a, lc.b]) ctx.fillRect(this.sx(p[0]) - r, this.sy(p[1]) - r, 2 * r, 2 * r);
    }
    for (const [box, color] of [[this.highlight, '#ffffff'], [this.selection, '#7fd1ff']]) {
      if (!box) continue;
      ctx.strokeStyle = color;
      ctx.strokeRect(this.sx(box[0][0]), this.sy(box[1][1]), (box[1][0] - box[0][0]) * this.scale,
        (box[1][1] - box[0][1]) * this.scale);
    }
    this.frames++;
    if (this.onRendered) this.onRendered(this.cuboidCount(), performance.now());
  }

  css(rgb) {
    const key = ((rgb[0] * 255) | 0) * 65536 + ((rgb[1] * 255) | 0) * 256 + ((rgb[2] * 255) | 0);
    let s = this.colorCache.get(key);
    if (!s) {
      s = toCss(rgb);
      this.colorCache.set(key, s);
    }
    return s;
  }

  frameStats() { return { deltas: [], renders: [] }; }
  setAutoRotate() {}
  setControlsEnabled(on) { this.controlsEnabled = on; }
  setRobotsVisible(on) { this.robotsVisible = on; this.requestRender(); }

  /** 2D layer tiles: [{image, bounds: [x0, y0, x1, y1] (m)}], drawn under the cuboids. */
  setLayerTiles(list) { this.layerTiles = list; this.requestRender(); }

  setTile(key, tile) {
    if (tile.occupied === undefined) {
      let n = 0;
      for (let k = 0; k < tile.count; k++) if (tile.probability[k] >= 0.5) n++;
      tile.occupied = n;
    }
    this.tiles.set(key, tile);
    this.requestRender();
  }

  removeTile(key) { this.tiles.delete(key); this.requestRender(); }
  clearTiles() { this.tiles.clear(); this.requestRender(); }
  setColorMode(mode) { this.colorMode = mode; this.requestRender(); }
  setShowFree(show) { this.showFree = show; this.requestRender(); }
  setZRange(lo, hi) { this.zLo = lo; this.zHi = hi; this.requestRender(); }
  setZCut(z) { this.zCut = z; this.requestRender(); }

  cuboidCount() {
    let n = 0;
    for (const tile of this.tiles.values()) n += this.showFree ? tile.count : tile.occupied;
    return n;
  }

  fitBounds(min, max, { force = false } = {}) {
    this.groundZ = min[2];
    if (this.userMoved && !force) return;
    this.cx = (min[0] + max[0]) / 2;
    this.cy = (min[1] + max[1]) / 2;
    const w = Math.max(max[0] - min[0], 2);
    const h = Math.max(max[1] - min[1], 2);
    this.scale = 0.9 * Math.min(this.canvas.width / w, this.canvas.height / h);
    this.viewChanged();
  }

  robot(id, color) {
    let robot = this.robots.get(id);
    if (!robot) {
      robot = { color, flat: new Float32Array(3 * 1024), count: 0, pose: null };
      this.robots.set(id, robot);
    }
    return robot;
  }

  setRobotPose(id, color, position, orientation) {
    this.robot(id, color).pose = { position, orientation };
    this.requestRender();
  }

  addTrajectory(id, color, flat, reset) {
    const robot = this.robot(id, color);
    if (reset) robot.count = 0;
    const need = robot.count + flat.length / 3;
    if (3 * need > robot.flat.length) {
      let cap = robot.flat.length;
      while (cap < 3 * need) cap *= 2;
      const grown = new Float32Array(cap);
      grown.set(robot.flat.subarray(0, 3 * robot.count));
      robot.flat = grown;
    }
    robot.flat.set(flat, 3 * robot.count);
    robot.count = need;
    this.requestRender();
  }

  removeRobot(id) { this.robots.delete(id); this.requestRender(); }
  setLoopClosures(list) { this.loops = list; this.requestRender(); }

  /** Loop closure lines drawn, by colour: {'#4dd0ff': 3, …}. */
  loopLineCounts() {
    const out = {};
    for (const lc of this.loops) out[loopColor(lc.source)] = (out[loopColor(lc.source)] || 0) + 1;
    return out;
  }

  pick(clientX, clientY) {
    const [x, y] = this.toWorld(clientX, clientY);
    const best = pickTiles(this.tiles, [x, y, 1e5], [1e-9, 1e-9, -1], this.showFree, this.zCut ?? Infinity);
    if (best) return best;
    return { hit: false, point: [x, y, this.groundZ || 0] };
  }

  groundPoint(clientX, clientY, z = this.groundZ || 0) {
    const [x, y] = this.toWorld(clientX, clientY);
    return [x, y, z];
  }

  showHighlight(min, max) { this.highlight = min ? [min, max] : null; this.requestRender(); }
  showSelection(min, max) { this.selection = [min, max]; this.requestRender(); }
  hideSelection() { this.selection = null; this.requestRender(); }
}
