// The cuboids of many tiles in one pair of instance buffers (matrix, colour), drawn as
// InstancedMeshes of up to CHUNK instances each over slices of those buffers.
//
// Each tile owns a contiguous segment of instances [start, start + cap). Replacing a tile
// rewrites its segment in place when the new cuboids fit (with 1/8 slack for growth), else the
// segment is abandoned (collapsed to a point) and the tile is appended. Abandoned space is
// compacted with copyWithin once it exceeds a quarter of the buffer; the buffers double when
// full. Only the written ranges are uploaded (addUpdateRange), so a tile update costs O(tile),
// never O(map), and nothing is allocated per frame.
//
// The chunk meshes share the two GPU buffers: each one's instanceMatrix/instanceColor is an
// InterleavedBufferAttribute viewing its slice of the one InstancedBufferAttribute. Chunks let a
// slow (software) renderer draw a large map over several animation frames (scene3d.js).

import * as THREE from 'three';

export const CHUNK = 8192;

const COLLAPSED = new Float32Array([0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1]);

export class InstanceLayer {
  /**
   * @param {THREE.Object3D} parent
   * @param {THREE.BufferGeometry} geometry unit cube centred on the origin (shared)
   * @param {THREE.Material} material
   */
  constructor(parent, geometry, material, { capacity = 1 << 16, renderOrder = 0 } = {}) {
    this.group = new THREE.Group();
    parent.add(this.group);
    this.geometry = geometry;
    this.material = material;
    this.renderOrder = renderOrder;
    this.segments = new Map();
    this.end = 0; // high-water mark
    this.live = 0; // instances in use
    this.chunks = [];
    this.matrices = null;
    this.colors = null;
    this.allocate(Math.ceil(capacity / CHUNK) * CHUNK);
  }

  allocate(capacity) {
    const matrices = new THREE.InstancedBufferAttribute(new Float32Array(capacity * 16), 16);
    const colors = new THREE.InstancedBufferAttribute(new Float32Array(capacity * 3), 3);
    matrices.setUsage(THREE.DynamicDrawUsage);
    colors.setUsage(THREE.DynamicDrawUsage);
    if (this.matrices) {
      matrices.array.set(this.matrices.array.subarray(0, this.end * 16));
      colors.array.set(this.colors.array.subarray(0, this.end * 3));
      // Frees the old GPU buffers (WebGLObjects listens for this on instanced meshes).
      if (this.chunks.length) this.chunks[0].dispatchEvent({ type: 'dispose' });
    }
    for (const mesh of this.chunks) this.group.remove(mesh);
    this.chunks = [];
    this.matrices = matrices;
    this.colors = colors;
    this.capacity = capacity;
    for (let start = 0; start < capacity; start += CHUNK) {
      const mesh = new THREE.InstancedMesh(this.geometry, this.material, 0);
      mesh.instanceMatrix = new THREE.InterleavedBufferAttribute(matrices, 16, start * 16);
      mesh.instanceColor = new THREE.InterleavedBufferAttribute(colors, 3, start * 3);
      mesh.frustumCulled = false; // tiles are culled before they get here
      mesh.matrixAutoUpdate = false;
      mesh.renderOrder = this.renderOrder;
      mesh.userData.start = start;
      this.chunks.push(mesh);
      this.group.add(mesh);
    }
    this.updateCounts();
  }

  updateCounts() {
    for (const mesh of this.chunks) {
      const n = Math.min(CHUNK, Math.max(0, this.end - mesh.userData.start));
      mesh.count = n;
      mesh.visible = n > 0;
    }
  }

  /** Chunks holding instances, in order (for drawing a few per frame). */
  activeChunks() {
    return Math.ceil(this.end / CHUNK);
  }

  get count() {
    return this.live;
  }

  set visible(v) {
    this.group.visible = v;
  }

  /**
   * Writes the cuboids of `tile` that pass `keep(probability)` as the segment of `key`.
   * `n` is how many pass. colorFn(tile, k, out, offset) writes an RGB triple.
   */
  write(key, tile, n, keep, colorFn) {
    let seg = this.segments.get(key);
    if (seg && n > seg.cap) {
      this.release(seg);
      this.segments.delete(key);
      seg = undefined;
    }
    if (!seg) {
      if (n === 0) return;
      const cap = n + (n >> 3) + 8;
      seg = { start: this.reserve(cap), cap, count: 0 };
      this.segments.set(key, seg);
    }
    const m = this.matrices.array;
    const c = this.colors.array;
    const r = tile.resolution;
    const minCell = tile.minCell;
    const maxCell = tile.maxCell;
    const p = tile.probability;
    let i = seg.start;
    for (let k = 0, total = tile.count; k < total; k++) {
      if (!keep(p[k])) continue;
      const a = 3 * k;
      const x0 = minCell[a];
      const y0 = minCell[a + 1];
      const z0 = minCell[a + 2];
      const x1 = maxCell[a] + 1;
      const y1 = maxCell[a + 1] + 1;
      const z1 = maxCell[a + 2] + 1;
      const o = 16 * i;
      m[o] = (x1 - x0) * r; m[o + 1] = 0; m[o + 2] = 0; m[o + 3] = 0;
      m[o + 4] = 0; m[o + 5] = (y1 - y0) * r; m[o + 6] = 0; m[o + 7] = 0;
      m[o + 8] = 0; m[o + 9] = 0; m[o + 10] = (z1 - z0) * r; m[o + 11] = 0;
      m[o + 12] = 0.5 * (x0 + x1) * r; m[o + 13] = 0.5 * (y0 + y1) * r; m[o + 14] = 0.5 * (z0 + z1) * r; m[o + 15] = 1;
      colorFn(tile, k, c, 3 * i);
      i++;
    }
    const written = i - seg.start;
    for (let j = i; j < seg.start + seg.count; j++) m.set(COLLAPSED, 16 * j);
    const touched = Math.max(written, seg.count);
    this.live += written - seg.count;
    seg.count = written;
    this.markDirty(seg.start, touched);
  }

  remove(key) {
    const seg = this.segments.get(key);
    if (!seg) return;
    this.release(seg);
    this.segments.delete(key);
  }

  clear() {
    this.segments.clear();
    this.end = 0;
    this.live = 0;
    this.updateCounts();
  }

  release(seg) {
    const m = this.matrices.array;
    for (let j = seg.start; j < seg.start + seg.count; j++) m.set(COLLAPSED, 16 * j);
    this.markDirty(seg.start, seg.count);
    this.live -= seg.count;
    if (seg.start + seg.cap === this.end) {
      this.end = seg.start;
      this.updateCounts();
    }
  }

  reserve(cap) {
    if (this.end + cap > this.capacity) {
      if (this.end - this.live > this.end / 4) this.compact();
      if (this.end + cap > this.capacity) {
        const want = Math.max(this.capacity * 2, Math.ceil((this.end + cap) * 1.25));
        this.allocate(Math.ceil(want / CHUNK) * CHUNK);
      }
    }
    const start = this.end;
    this.end += cap;
    this.updateCounts();
    return start;
  }

  compact() {
    const segs = [...this.segments.values()].sort((a, b) => a.start - b.start);
    const m = this.matrices.array;
    const c = this.colors.array;
    let at = 0;
    for (const seg of segs) {
      if (seg.start !== at) {
        m.copyWithin(16 * at, 16 * seg.start, 16 * (seg.start + seg.count));
        c.copyWithin(3 * at, 3 * seg.start, 3 * (seg.start + seg.count));
        seg.start = at;
      }
      // Never more than before, so the segment cannot reach the next one before it has moved.
      seg.cap = Math.min(seg.cap, seg.count + (seg.count >> 3) + 8);
      for (let j = seg.start + seg.count; j < seg.start + seg.cap; j++) m.set(COLLAPSED, 16 * j);
      at += seg.cap;
    }
    this.end = at;
    this.updateCounts();
    this.markDirty(0, at);
  }

  markDirty(start, count) {
    if (count <= 0) return;
    this.matrices.addUpdateRange(16 * start, 16 * count);
    this.colors.addUpdateRange(3 * start, 3 * count);
    this.matrices.needsUpdate = true;
    this.colors.needsUpdate = true;
  }
}
