// WebGL renderer (Three.js): instanced cuboids, robots, trajectories, loop closures, picking.
// Z is up (map frame). Renders on demand: requestRender() marks the frame dirty; the
// requestAnimationFrame loop draws it, and a timer draws it too when animation frames are
// throttled (background tabs, headless virtual time).

import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

import { cuboidColor, loopColor } from './colors.js';
import { cuboidMaterial, threeFaceBoxGeometry } from './cuboid_material.js';
import { InstanceLayer } from './instances.js';
import { TILE_CELLS } from './tiles.js';

const BACKGROUND = 0x12161c;
const FRAME_SAMPLES = 2048;
const STEP_CHUNKS = 2; // instance chunks drawn per animation frame by the progressive renderer
// After a progressive frame of N animation frames, map updates wait N * REST_FRAMES idle
// animation frames, so a live map does not keep a software rasteriser drawing all the time.
// Counted in frames, not ms: under headless virtual time performance.now() stands still while
// the page draws. Without the rest, chromium --headless --virtual-time-budget --screenshot of a
// live map never returned: its budget took longer in real time than in virtual time, and the
// capture then waits for a frame that paused virtual time never lets come (docs/BENCHMARKS.md §3).
const REST_FRAMES = 3;

function gpuName(gl) {
  try {
    const ext = gl.getExtension('WEBGL_debug_renderer_info');
    return String(gl.getParameter(ext ? ext.UNMASKED_RENDERER_WEBGL : gl.RENDERER));
  } catch {
    return '';
  }
}

export function webglAvailable() {
  try {
    const canvas = document.createElement('canvas');
    return !!(canvas.getContext('webgl2') || canvas.getContext('webgl'));
  } catch {
    return false;
  }
}

export class Renderer3D {
  constructor(container) {
    this.kind = 'webgl';
    this.container = container;
    this.renderer = new THREE.WebGLRenderer({ antialias: false, powerPreference: 'high-performance', preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
    this.renderer.setClearColor(BACKGROUND, 1);
    this.canvas = this.renderer.domElement;
    this.canvas.className = 'map-canvas';
    container.appendChild(this.canvas);

    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(50, 1, 0.05, 5000);
    this.camera.up.set(0, 0, 1);
    this.camera.position.set(-15, -20, 18);
    this.controls = new OrbitControls(this.camera, this.canvas);
    this.controls.target.set(0, 0, 0);
    this.controls.screenSpacePanning = false; // pan in the ground plane
    this.controls.maxPolarAngle = Math.PI * 0.495;
    this.controls.autoRotateSpeed = 1.5;
    // Camera moves the viewer makes itself (following a growing map) redraw like map updates.
    this.controls.addEventListener('change', () => this.viewChanged(this.automaticView ? 'data' : 'view'));
    this.interacting = false;
    this.controls.addEventListener('start', () => { this.userMoved = true; this.interacting = true; });
    this.controls.addEventListener('end', () => { this.interacting = false; });

    this.scene.add(new THREE.HemisphereLight(0xdfe8ff, 0x3a3228, 1.6));
    const sun = new THREE.DirectionalLight(0xffffff, 1.6);
    sun.position.set(0.35, -0.5, 1.0);
    this.scene.add(sun);
    this.scene.add(sun.target);

    this.grid = null;
    this.boxGeometry = threeFaceBoxGeometry();
    this.occupiedMaterial = cuboidMaterial();
    this.freeMaterial = cuboidMaterial({ opacity: 0.12 });
    this.mapGroup = new THREE.Group();
    this.scene.add(this.mapGroup);
    this.occupied = new InstanceLayer(this.mapGroup, this.boxGeometry, this.occupiedMaterial, { capacity: 1 << 17 });
    this.free = new InstanceLayer(this.mapGroup, this.boxGeometry, this.freeMaterial, { capacity: 1 << 12, renderOrder: 2 });
    this.tiles = new Map(); // key → tile (drawn)

    this.colorMode = 'height';
    this.zLo = 0;
    this.zHi = 3;
    this.showFree = false;
    this.keepOccupied = (p) => p >= 0.5;
    this.keepFree = (p) => p < 0.5;
    this.colorFn = (tile, k, out, o) => cuboidColor(tile, k, this.colorMode, this.zLo, this.zHi, tile.resolution, out, o);

    this.robotGroup = new THREE.Group();
    this.scene.add(this.robotGroup);
    this.robots = new Map();
    this.markerGeometry = new THREE.ConeGeometry(0.22, 0.7, 16);
    this.markerGeometry.rotateZ(-Math.PI / 2); // tip along +x (the robot's heading)
    this.markerScale = 1;

    this.loopGroup = new THREE.Group();
    this.scene.add(this.loopGroup);
    this.layerGroup = new THREE.Group(); // 2D layer rasters on the ground plane
    this.scene.add(this.layerGroup);
    this.layerGeometry = new THREE.PlaneGeometry(1, 1);
    // Image row 0 is the tile's +y edge; ImageBitmaps are not flipped on upload, so flip the UVs.
    const uv = this.layerGeometry.attributes.uv;
    for (let i = 0; i < uv.count; i++) uv.setY(i, 1 - uv.getY(i));

    const edges = new THREE.EdgesGeometry(new THREE.BoxGeometry(1, 1, 1));
    this.highlight = new THREE.LineSegments(edges, new THREE.LineBasicMaterial({ color: 0xffffff, depthTest: false }));
    this.highlight.renderOrder = 10;
    this.highlight.visible = false;
    this.scene.add(this.highlight);
    this.selection = new THREE.LineSegments(edges, new THREE.LineBasicMaterial({ color: 0x7fd1ff, depthTest: false }));
    this.selection.renderOrder = 10;
    this.selection.visible = false;
    this.scene.add(this.selection);

    // Scratch objects: nothing below allocates per frame.
    this.frustum = new THREE.Frustum();
    this.projScreen = new THREE.Matrix4();
    this.scratchBox = new THREE.Box3();
    this.raycaster = new THREE.Raycaster();
    this.ndc = new THREE.Vector2();
    this.plane = new THREE.Plane(new THREE.Vector3(0, 0, 1), 0);
    this.planeHit = new THREE.Vector3();
    this.tanHalfFov = Math.tan(THREE.MathUtils.degToRad(this.camera.fov) / 2);

    const self = this;
    this.view = {
      boxVisible(b) {
        self.scratchBox.min.set(b[0], b[1], b[2]);
        self.scratchBox.max.set(b[3], b[4], b[5]);
        return self.frustum.intersectsBox(self.scratchBox);
      },
      boxDistance(b) {
        const p = self.camera.position;
        const dx = Math.max(b[0] - p.x, 0, p.x - b[3]);
        const dy = Math.max(b[1] - p.y, 0, p.y - b[4]);
        const dz = Math.max(b[2] - p.z, 0, p.z - b[5]);
        return Math.sqrt(dx * dx + dy * dy + dz * dz);
      },
      pixelsPerMetre(dist) {
        return self.heightPx / (2 * Math.max(dist, self.camera.near) * self.tanHalfFov);
      },
    };

    this.onViewChange = null;
    this.onRendered = null;
    this.gl = this.renderer.getContext();
    this.gpuName = gpuName(this.gl);
    // Software rasterisers (SwiftShader, llvmpipe: headless browsers, VMs) draw ~10^5 boxes/s.
    this.software = /swiftshader|llvmpipe|softpipe|software/i.test(this.gpuName);
    this.dataIntervalMs = this.software ? 1000 : 100;
    this.progressive = this.software;
    this.pass = null;
    this.automaticView = false; // set while fitBounds moves the camera
    this.lastPassSteps = 0; // animation frames the last progressive frame took
    this.idleFrames = 0; // animation frames since then without drawing
    this.frameTimes = new Float32Array(FRAME_SAMPLES); // whole frames (all passes' steps), ms
    this.frameCount = 0;
    this.lastFrameDone = 0;
    this.dirty = true;
    this.viewDirty = true;
    this.lastRender = 0;
    this.fallbackTimer = null;
    this.frames = 0;
    this.frameDeltas = new Float32Array(FRAME_SAMPLES);
    this.renderTimes = new Float32Array(FRAME_SAMPLES);
    this.frameCursor = 0;
    this.lastRaf = 0;
    this.userMoved = false;
    this.resize();
    // Resizes apply after a short pause; meanwhile CSS stretches the last frame. (Resizing the
    // drawing buffer clears it, and a screenshot taken right after a viewport change, like
    // headless Chromium's, would otherwise catch an empty canvas.)
    this.resizeTimer = null;
    this.resizeObserver = new ResizeObserver(() => {
      clearTimeout(this.resizeTimer);
      this.resizeTimer = setTimeout(() => this.resize(), 120);
    });
    this.resizeObserver.observe(container);
    this.loop = this.loop.bind(this);
    requestAnimationFrame(this.loop);
  }

  resize() {
    const w = Math.max(1, this.container.clientWidth);
    const h = Math.max(1, this.container.clientHeight);
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.heightPx = h * this.renderer.getPixelRatio();
    if (this.lastFit && !this.userMoved) this.fitBounds(this.lastFit[0], this.lastFit[1]);
    else this.viewChanged();
    if (this.frames > 0) this.renderNow(); // the new drawing buffer is empty: start filling it at once
  }

  viewChanged(kind = 'view') {
    this.camera.updateMatrixWorld();
    this.projScreen.multiplyMatrices(this.camera.projectionMatrix, this.camera.matrixWorldInverse);
    this.frustum.setFromProjectionMatrix(this.projScreen);
    this.requestRender(kind);
    if (this.onViewChange) this.onViewChange();
  }

  /**
   * Marks the frame dirty. 'view' (camera moves, user actions) draws at the next animation
   * frame; 'data' (tiles, poses) at most every `dataIntervalMs`, so a busy map does not keep a
   * slow (software) GPU rendering all the time.
   */
  requestRender(kind = 'view') {
    if (kind === 'view') this.viewDirty = true;
    this.dirty = true;
    // Animation frames normally draw; this timer only covers pages whose frames are throttled.
    if (this.fallbackTimer === null) {
      this.fallbackTimer = setTimeout(() => {
        this.fallbackTimer = null;
        if (this.dirty && performance.now() - this.lastRaf > 1500) this.renderNow();
      }, 2000);
    }
  }

  loop(t) {
    requestAnimationFrame(this.loop);
    if (this.lastRaf > 0) {
      this.frameDeltas[this.frameCursor % FRAME_SAMPLES] = t - this.lastRaf;
    }
    this.lastRaf = t;
    this.renderTimes[this.frameCursor % FRAME_SAMPLES] = 0;
    // Rotation moves on once the previous (possibly progressive) frame is complete.
    if (this.controls.autoRotate && this.pass === null) this.controls.update(); // emits 'change' → dirty
    const rested = this.idleFrames >= REST_FRAMES * this.lastPassSteps;
    const due = this.dirty && (this.viewDirty || (rested && performance.now() - this.lastRender >= this.dataIntervalMs));
    if (this.pass === null && !due) this.idleFrames++;
    if (!this.progressive) {
      if (due) this.renderNow();
    } else if (this.pass === null) {
      if (due) this.renderNow();
    } else {
      // Camera moves meanwhile wait for this frame to complete: restarting would show nothing
      // new until the user stops.
      this.passStep();
    }
    this.frameCursor++;
  }

  /**
   * Draws the frame. On a software rasteriser (progressive) the map is drawn over several
   * animation frames, one chunk of instances each, into a preserved drawing buffer: no single
   * task blocks the page for long (a long one can stall a headless browser's screenshot).
   */
  renderNow() {
    this.dirty = false;
    this.viewDirty = false;
    if (this.progressive) {
      // The whole pass uses the camera of its start.
      if (!this.passCamera) this.passCamera = this.camera.clone();
      else this.passCamera.copy(this.camera);
      this.pass = { step: 0, started: performance.now() };
      this.passStep();
      return;
    }
    const t0 = performance.now();
    this.renderer.autoClear = true;
    this.renderer.render(this.scene, this.camera);
    this.lastRender = t0;
    this.renderTimes[this.frameCursor % FRAME_SAMPLES] = performance.now() - t0;
    this.frameDone(t0);
  }

  // Progressive frames are drawn into an offscreen target and shown when complete, so the canvas
  // never shows half a map.
  ensureTarget() {
    const size = this.renderer.getDrawingBufferSize(new THREE.Vector2());
    if (!this.target) {
      this.target = new THREE.WebGLRenderTarget(size.x, size.y, { depthBuffer: true });
      this.blitScene = new THREE.Scene();
      this.blitCamera = new THREE.OrthographicCamera(-1, 1, 1, -1, 0, 1);
      const quad = new THREE.Mesh(new THREE.PlaneGeometry(2, 2),
        new THREE.MeshBasicMaterial({ map: this.target.texture, depthTest: false, depthWrite: false, toneMapped: false }));
      quad.frustumCulled = false;
      this.blitScene.add(quad);
    } else if (this.target.width !== size.x || this.target.height !== size.y) {
      this.target.setSize(size.x, size.y);
    }
    return this.target;
  }

  passStep() {
    const pass = this.pass;
    const occ = this.occupied.activeChunks();
    const free = this.showFree ? this.free.activeChunks() : 0;
    const per = STEP_CHUNKS;
    const steps = Math.max(1, Math.ceil((occ + free) / per));
    const s = pass.step;
    for (let i = 0; i < this.occupied.chunks.length; i++) {
      const mesh = this.occupied.chunks[i];
      mesh.visible = Math.floor(i / per) === s && mesh.count > 0;
    }
    for (let i = 0; i < this.free.chunks.length; i++) {
      const mesh = this.free.chunks[i];
      mesh.visible = Math.floor((i + occ) / per) === s && mesh.count > 0;
    }
    const t0 = performance.now();
    this.renderer.setRenderTarget(this.ensureTarget());
    this.renderer.autoClear = s === 0;
    this.renderer.render(this.scene, this.passCamera);
    this.renderer.autoClear = true;
    this.renderer.setRenderTarget(null);
    for (const mesh of this.occupied.chunks) mesh.visible = mesh.count > 0;
    for (const mesh of this.free.chunks) mesh.visible = mesh.count > 0;
    pass.step++;
    if (pass.step >= steps) {
      this.renderer.render(this.blitScene, this.blitCamera);
    }
    this.renderTimes[this.frameCursor % FRAME_SAMPLES] = performance.now() - t0;
    if (pass.step >= steps) {
      this.pass = null;
      this.lastPassSteps = steps;
      this.idleFrames = 0;
      this.lastRender = t0;
      this.frameDone(pass.started);
    }
  }

  // A complete frame is on the canvas. Frame time = time since the previous one completed
  // (meaningful while rendering continuously, e.g. rotating).
  frameDone(startedAt) {
    const now = performance.now();
    this.frames++;
    if (this.lastFrameDone > 0) {
      this.frameTimes[this.frameCount % FRAME_SAMPLES] = now - this.lastFrameDone;
      this.frameCount++;
    }
    this.lastFrameDone = now;
    if (this.onRendered) this.onRendered(this.cuboidCount(), startedAt);
  }

  /**
   * Of the last `n` animation frames: rAF deltas and render CPU times (ms); of the last `n`
   * complete frames: their duration (ms; a progressive frame spans several animation frames).
   */
  frameStats(n = 240) {
    const count = Math.min(n, this.frameCursor - 1, FRAME_SAMPLES);
    const deltas = [];
    const renders = [];
    for (let i = 1; i <= count; i++) {
      const j = (this.frameCursor - i + FRAME_SAMPLES) % FRAME_SAMPLES;
      deltas.push(this.frameDeltas[j]);
      renders.push(this.renderTimes[j]);
    }
    const frames = [];
    for (let i = 1; i <= Math.min(n, this.frameCount, FRAME_SAMPLES); i++) {
      frames.push(this.frameTimes[(this.frameCount - i + FRAME_SAMPLES) % FRAME_SAMPLES]);
    }
    return { deltas, renders, frames, progressive: this.progressive, frameCount: this.frameCount };
  }

  setAutoRotate(on) {
    this.controls.autoRotate = on;
    this.requestRender();
  }

  // ----- map -----

  setTile(key, tile) {
    this.tiles.set(key, tile);
    this.writeTile(key, tile);
    this.requestRender('data');
  }

  writeTile(key, tile) {
    let occupied = tile.occupied;
    if (occupied === undefined) {
      occupied = 0;
      for (let k = 0; k < tile.count; k++) if (tile.probability[k] >= 0.5) occupied++;
      tile.occupied = occupied;
    }
    this.occupied.write(key, tile, occupied, this.keepOccupied, this.colorFn);
    if (this.showFree) this.free.write(key, tile, tile.count - occupied, this.keepFree, this.colorFn);
  }

  removeTile(key) {
    this.tiles.delete(key);
    this.occupied.remove(key);
    this.free.remove(key);
    this.requestRender('data');
  }

  clearTiles() {
    this.tiles.clear();
    this.occupied.clear();
    this.free.clear();
    this.requestRender('data');
  }

  rebuild(kind = 'view') {
    this.occupied.clear();
    this.free.clear();
    for (const [key, tile] of this.tiles) this.writeTile(key, tile);
    this.free.visible = this.showFree;
    this.requestRender(kind);
  }

  setColorMode(mode) {
    if (mode === this.colorMode) return;
    this.colorMode = mode;
    this.rebuild();
  }

  setShowFree(show) {
    if (show === this.showFree) return;
    this.showFree = show;
    this.rebuild();
  }

  /** Height range of the colour ramp; recolours only when it moved noticeably. */
  setZRange(lo, hi) {
    const span = Math.max(hi - lo, 1e-6);
    if (Math.abs(lo - this.zLo) < 0.1 * span && Math.abs(hi - this.zHi) < 0.1 * span) return;
    this.zLo = lo;
    this.zHi = hi;
    if (this.colorMode === 'height') this.rebuild('data'); // follows the map, not the user
  }

  /** Hides cuboids whose bottom is above z (m); Infinity shows all. */
  setZCut(z) {
    const v = Number.isFinite(z) ? z : 1e9;
    this.occupiedMaterial.uniforms.zCut.value = v;
    this.freeMaterial.uniforms.zCut.value = v;
    this.zCut = z;
    this.requestRender();
  }

  cuboidCount() {
    return this.occupied.count + (this.showFree ? this.free.count : 0);
  }

  /** Frames the camera on a box (map bounds); sizes grid and markers to it. */
  fitBounds(min, max, { force = false } = {}) {
    const same = this.lastFit && this.lastFit[0].every((v, i) => v === min[i]) && this.lastFit[1].every((v, i) => v === max[i])
      && this.lastFitAspect === this.camera.aspect;
    if (same && !force) return;
    this.lastFit = [min.slice(), max.slice()];
    this.lastFitAspect = this.camera.aspect;
    const kind = force ? 'view' : 'data';
    if (this.userMoved && !force) {
      this.sizeGrid(min, max, kind);
      return;
    }
    const cx = (min[0] + max[0]) / 2;
    const cy = (min[1] + max[1]) / 2;
    const cz = (min[2] + max[2]) / 2;
    const size = Math.max(max[0] - min[0], max[1] - min[1], (max[2] - min[2]) * 2, 2);
    const aspect = Math.min(this.camera.aspect, 1.6);
    const dist = (size / (2 * this.tanHalfFov)) * (aspect < 1 ? 1.3 / aspect : 1.1);
    const dir = new THREE.Vector3(-0.45, -0.75, 0.85).normalize();
    this.controls.target.set(cx, cy, cz);
    this.camera.position.set(cx + dir.x * dist, cy + dir.y * dist, cz + dir.z * dist);
    this.camera.near = Math.max(0.01, dist / 2000);
    this.camera.far = dist * 50;
    this.camera.updateProjectionMatrix();
    this.automaticView = !force;
    this.controls.update();
    this.automaticView = false;
    this.sizeGrid(min, max, kind);
    this.viewChanged(kind);
  }

  sizeGrid(min, max, kind = 'view') {
    const extent = Math.max(max[0] - min[0], max[1] - min[1], 4);
    const step = extent > 200 ? 10 : extent > 40 ? 5 : 1;
    const size = Math.ceil((extent * 1.4) / step) * step;
    const key = `${size}/${step}/${min[2]}`;
    this.markerScale = Math.min(20, Math.max(0.6, extent / 30));
    for (const robot of this.robots.values()) robot.marker.scale.setScalar(this.markerScale);
    if (this.gridKey === key) return;
    this.gridKey = key;
    if (this.grid) {
      this.scene.remove(this.grid);
      this.grid.geometry.dispose();
      this.grid.material.dispose();
    }
    this.grid = new THREE.GridHelper(size, size / step, 0x3b4656, 0x252c36);
    this.grid.rotation.x = Math.PI / 2; // XZ → XY
    this.grid.position.set(Math.round((min[0] + max[0]) / 2), Math.round((min[1] + max[1]) / 2), min[2] - 0.01);
    this.scene.add(this.grid);
    this.groundZ = min[2];
    this.requestRender(kind);
  }

  // ----- robots, trajectories, loop closures -----

  robot(id, color) {
    let robot = this.robots.get(id);
    if (!robot) {
      const marker = new THREE.Mesh(this.markerGeometry, new THREE.MeshBasicMaterial({ color }));
      marker.scale.setScalar(this.markerScale);
      marker.visible = false;
      marker.renderOrder = 5;
      const geometry = new THREE.BufferGeometry();
      const positions = new Float32Array(3 * 1024);
      geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3).setUsage(THREE.DynamicDrawUsage));
      geometry.setDrawRange(0, 0);
      const line = new THREE.Line(geometry, new THREE.LineBasicMaterial({ color, transparent: true, opacity: 0.9 }));
      line.frustumCulled = false;
      this.robotGroup.add(marker);
      this.robotGroup.add(line);
      robot = { marker, line, count: 0 };
      this.robots.set(id, robot);
    }
    return robot;
  }

  setRobotPose(id, color, position, orientation) {
    const robot = this.robot(id, color);
    robot.marker.position.set(position[0], position[1], position[2]);
    // API orientation is [w, x, y, z].
    robot.marker.quaternion.set(orientation[1], orientation[2], orientation[3], orientation[0]);
    robot.marker.visible = true;
    this.requestRender('data');
  }

  /** Replaces (reset) or extends a robot's trajectory with flat [x, y, z, …] positions. */
  addTrajectory(id, color, flat, reset) {
    const robot = this.robot(id, color);
    const geometry = robot.line.geometry;
    let attr = geometry.getAttribute('position');
    if (reset) robot.count = 0;
    const need = robot.count + flat.length / 3;
    if (need > attr.count) {
      let cap = attr.count;
      while (cap < need) cap *= 2;
      const grown = new Float32Array(3 * cap);
      grown.set(attr.array.subarray(0, 3 * robot.count));
      geometry.dispose();
      const fresh = new THREE.BufferGeometry();
      fresh.setAttribute('position', new THREE.BufferAttribute(grown, 3).setUsage(THREE.DynamicDrawUsage));
      robot.line.geometry = fresh;
      attr = fresh.getAttribute('position');
      attr.needsUpdate = true;
    } else {
      attr.addUpdateRange(3 * robot.count, flat.length);
      attr.needsUpdate = true;
    }
    attr.array.set(flat, 3 * robot.count);
    robot.count = need;
    robot.line.geometry.setDrawRange(0, robot.count);
    this.requestRender('data');
  }

  removeRobot(id) {
    const robot = this.robots.get(id);
    if (!robot) return;
    this.robotGroup.remove(robot.marker);
    this.robotGroup.remove(robot.line);
    robot.marker.material.dispose();
    robot.line.geometry.dispose();
    robot.line.material.dispose();
    this.robots.delete(id);
    this.requestRender('data');
  }

  /** 2D layer tiles: [{image (ImageBitmap), bounds: [x0, y0, x1, y1] (m)}], drawn on z = 0. */
  setLayerTiles(list) {
    for (const child of [...this.layerGroup.children]) {
      this.layerGroup.remove(child);
      child.material.map.dispose();
      child.material.dispose();
    }
    for (const t of list) {
      const texture = new THREE.Texture(t.image);
      texture.magFilter = THREE.NearestFilter; // one cell per texel at the native zoom
      texture.minFilter = THREE.LinearFilter;
      texture.generateMipmaps = false;
      texture.colorSpace = THREE.SRGBColorSpace;
      texture.needsUpdate = true;
      const material = new THREE.MeshBasicMaterial({ map: texture, transparent: true, depthWrite: false,
        side: THREE.DoubleSide });
      const mesh = new THREE.Mesh(this.layerGeometry, material);
      const [x0, y0, x1, y1] = t.bounds;
      mesh.scale.set(x1 - x0, y1 - y0, 1);
      mesh.position.set((x0 + x1) / 2, (y0 + y1) / 2, 0.01);
      mesh.renderOrder = 1;
      this.layerGroup.add(mesh);
    }
    this.requestRender('data');
  }

  /**
   * Loop closures: [{a:[x,y,z], b:[x,y,z], source, fresh:boolean}], a line between the two poses
   * in its source's colour (colors.js), fresh ones drawn on top, and a dot of a fixed pixel size
   * at each pose: a place recognised where the map already puts it has its two poses a few
   * centimetres apart, and the line alone would not show.
   */
  setLoopClosures(list) {
    for (const child of [...this.loopGroup.children]) {
      this.loopGroup.remove(child);
      child.geometry.dispose();  // the dots share their lines' geometry: disposing twice is harmless
      child.material.dispose();
    }
    const groups = new Map();
    for (const lc of list) {
      const key = `${loopColor(lc.source)}|${lc.fresh ? 1 : 0}`;
      if (!groups.has(key)) groups.set(key, []);
      groups.get(key).push(lc);
    }
    for (const [key, items] of groups) {
      const [color, fresh] = key.split('|');
      const flat = new Float32Array(items.length * 6);
      items.forEach((lc, i) => flat.set([...lc.a, ...lc.b], 6 * i));
      const g = new THREE.BufferGeometry();
      g.setAttribute('position', new THREE.BufferAttribute(flat, 3));
      const material = new THREE.LineBasicMaterial({ color: new THREE.Color(color), depthTest: false,
        transparent: fresh !== '1', opacity: fresh === '1' ? 1 : 0.8 });
      const lines = new THREE.LineSegments(g, material);
      lines.renderOrder = fresh === '1' ? 7 : 6;
      lines.frustumCulled = false;
      this.loopGroup.add(lines);
      const ends = new THREE.Points(g, new THREE.PointsMaterial({ color: new THREE.Color(color),
        size: fresh === '1' ? 7 : 5, sizeAttenuation: false, depthTest: false }));
      ends.renderOrder = lines.renderOrder;
      ends.frustumCulled = false;
      this.loopGroup.add(ends);
    }
    this.requestRender('data');
  }

  /** Loop closure lines drawn, by colour: {'#4dd0ff': 3, …}. */
  loopLineCounts() {
    const out = {};
    for (const child of this.loopGroup.children) {
      if (!child.isLineSegments) continue;
      const key = `#${child.material.color.getHexString()}`;
      out[key] = (out[key] || 0) + child.geometry.getAttribute('position').count / 2;
    }
    return out;
  }

  // ----- picking -----

  setRay(clientX, clientY) {
    const rect = this.canvas.getBoundingClientRect();
    this.ndc.set(((clientX - rect.left) / rect.width) * 2 - 1, -((clientY - rect.top) / rect.height) * 2 + 1);
    this.raycaster.setFromCamera(this.ndc, this.camera);
    return this.raycaster.ray;
  }

  /**
   * The cuboid under a screen point: {hit, point:[x,y,z] just inside the hit face, tileKey, k};
   * without a hit, the point on the ground plane (hit false), or null.
   */
  pick(clientX, clientY) {
    const ray = this.setRay(clientX, clientY);
    const o = ray.origin;
    const d = ray.direction;
    const best = pickTiles(this.tiles, [o.x, o.y, o.z], [d.x, d.y, d.z], this.showFree, this.zCut ?? Infinity);
    if (best) return best;
    const g = this.groundPoint(clientX, clientY);
    return g ? { hit: false, point: g } : null;
  }

  groundPoint(clientX, clientY, z = this.groundZ || 0) {
    const ray = this.setRay(clientX, clientY);
    this.plane.constant = -z;
    if (!ray.intersectPlane(this.plane, this.planeHit)) return null;
    return [this.planeHit.x, this.planeHit.y, this.planeHit.z];
  }

  showHighlight(min, max) {
    placeBox(this.highlight, min, max);
    this.requestRender();
  }

  showSelection(min, max) {
    placeBox(this.selection, min, max);
    this.requestRender();
  }

  hideSelection() {
    this.selection.visible = false;
    this.requestRender();
  }

  setControlsEnabled(on) {
    this.controls.enabled = on;
  }

  setRobotsVisible(on) {
    this.robotGroup.visible = on;
    this.requestRender();
  }

  /** Client (CSS pixel) coordinates of a map point. */
  project(p) {
    const v = new THREE.Vector3(p[0], p[1], p[2]).project(this.camera);
    const rect = this.canvas.getBoundingClientRect();
    return [rect.left + ((v.x + 1) / 2) * rect.width, rect.top + ((1 - v.y) / 2) * rect.height];
  }
}

function placeBox(obj, min, max) {
  if (!min) {
    obj.visible = false;
    return;
  }
  obj.position.set((min[0] + max[0]) / 2, (min[1] + max[1]) / 2, (min[2] + max[2]) / 2);
  obj.scale.set(Math.max(max[0] - min[0], 1e-3), Math.max(max[1] - min[1], 1e-3), Math.max(max[2] - min[2], 1e-3));
  obj.visible = true;
}

/** Ray entry parameter into an axis-aligned box, or -1. */
function rayBox(o, inv, x0, y0, z0, x1, y1, z1, tmax) {
  let t1 = (x0 - o[0]) * inv[0];
  let t2 = (x1 - o[0]) * inv[0];
  let tmin = Math.min(t1, t2);
  let tmx = Math.max(t1, t2);
  t1 = (y0 - o[1]) * inv[1];
  t2 = (y1 - o[1]) * inv[1];
  tmin = Math.max(tmin, Math.min(t1, t2));
  tmx = Math.min(tmx, Math.max(t1, t2));
  t1 = (z0 - o[2]) * inv[2];
  t2 = (z1 - o[2]) * inv[2];
  tmin = Math.max(tmin, Math.min(t1, t2));
  tmx = Math.min(tmx, Math.max(t1, t2));
  if (tmx < Math.max(tmin, 0) || tmin > tmax) return -1;
  return Math.max(tmin, 0);
}

/** Nearest drawn cuboid along a ray, over the CPU copies of the drawn tiles. Shared with the 2D renderer. */
export function pickTiles(tiles, o, d, withFree, zCut = Infinity) {
  const inv = [1 / d[0], 1 / d[1], 1 / d[2]];
  let bestT = Infinity;
  let best = null;
  for (const [key, tile] of tiles) {
    const r = tile.resolution;
    const e = TILE_CELLS * (2 ** tile.level) * r;
    if (rayBox(o, inv, tile.x * e, tile.y * e, tile.z * e, (tile.x + 1) * e, (tile.y + 1) * e, (tile.z + 1) * e, bestT) < 0) continue;
    const mn = tile.minCell;
    const mx = tile.maxCell;
    const p = tile.probability;
    for (let k = 0; k < tile.count; k++) {
      if (!withFree && p[k] < 0.5) continue;
      const a = 3 * k;
      if (mn[a + 2] * r > zCut) continue;
      const t = rayBox(o, inv, mn[a] * r, mn[a + 1] * r, mn[a + 2] * r, (mx[a] + 1) * r, (mx[a + 1] + 1) * r, (mx[a + 2] + 1) * r, bestT);
      if (t >= 0 && t < bestT) {
        bestT = t;
        best = { key, tile, k };
      }
    }
  }
  if (!best) return null;
  // A quarter of a base cell inside the hit face: the query lands in the first cell behind it.
  const t = bestT + 0.25 * best.tile.resolution;
  const { tile, k } = best;
  const r = tile.resolution;
  const a = 3 * k;
  return {
    hit: true,
    point: [o[0] + d[0] * t, o[1] + d[1] * t, o[2] + d[2] * t],
    tileKey: best.key,
    level: tile.level,
    cuboid: {
      min: [tile.minCell[a] * r, tile.minCell[a + 1] * r, tile.minCell[a + 2] * r],
      max: [(tile.maxCell[a] + 1) * r, (tile.maxCell[a + 1] + 1) * r, (tile.maxCell[a + 2] + 1) * r],
      probability: tile.probability[k],
    },
  };
}
