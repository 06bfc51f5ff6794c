// rmap viewer: wires the API, the viewer stream, the tile manager and the renderer to the page.
//
// URL parameters: map=NAME (map to open), color=height|probability, free=1, rotate=1,
// budget=N (cuboids drawn at most), renderer=2d (force the canvas fallback), debug=1.
// A read-only hook for tests and scripts: window.rmapViewer (see the bottom of this file).

import { Api, ApiError } from './api.js';
import { ROBOT_COLORS, loopColor } from './colors.js';
import { Renderer2D } from './fallback2d.js';
import { Layers2D } from './layers2d.js';
import { Renderer3D, webglAvailable } from './scene3d.js';
import { ViewerStream } from './stream.js';
import { TileManager, keyName } from './tiles.js';

const $ = (id) => document.getElementById(id);
const params = new URLSearchParams(window.location.search);
const loadId = `${Date.now().toString(36)}-${Math.random().toString(36).slice(2, 8)}`;

const MAP_POLL_MS = 2000;
const ROBOT_POLL_MS = 2000;
const LOOP_POLL_MS = 5000;
const TRAJECTORY_LIMIT = 100000;
const SOFTWARE_BUDGET = 60000;
const BOX_PAGE = 10000;
const BOX_COUNT_LIMIT = 100000;

let overlayTimer = null;

const bootMs = performance.now(); // modules loaded and running

const state = {
  maps: [],
  map: null,
  mapInfo: null,
  streamState: 'connecting',
  streamDetail: '',
  robots: new Map(), // id → {color, colorIndex, info, pose, rate, lastSeq, lastSeqAt, traj: {loaded, loading, stamp, buffer}}
  robotOrder: 0,
  loops: [],
  loopIds: new Set(),
  lastQuery: null,
  lastBox: null,
  timings: { start: bootMs, rendererMs: null, mapsMs: null, indexMs: null, firstTileMs: null, idleMs: null,
    firstPictureMs: null, refinedMs: null },
  errors: [],
  layersAvailable: null,
  pendingAuth: false,
};

// ----- renderer -----

const view = $('view');
let renderer;
if (webglAvailable() && params.get('renderer') !== '2d') {
  try {
    renderer = new Renderer3D(view);
  } catch (e) {
    console.warn('WebGL renderer failed, using the 2D view:', e);
    renderer = null;
  }
}
if (!renderer) {
  renderer = new Renderer2D(view);
  showOverlay('WebGL is not available: showing the map from above (2D).', 6000);
}

state.timings.rendererMs = performance.now();
if (renderer.software) {
  console.info(`rmap viewer: software WebGL (${renderer.gpuName}); drawing at most ${SOFTWARE_BUDGET} cuboids`);
}

const api = new Api();
const tiles = new TileManager(api, renderer, {
  onIndex: () => {
    if (state.timings.indexMs === null) state.timings.indexMs = performance.now();
  },
  onLoaded: () => {
    if (state.timings.firstTileMs === null) state.timings.firstTileMs = performance.now();
  },
  onIdle: () => {
    if (state.timings.idleMs === null && renderer.cuboidCount() > 0) state.timings.idleMs = performance.now();
  },
  onEpochChange: () => resetRobotsTrajectories(),
  onError: (e) => noteError(e),
});
// A software rasteriser draws ~10^5 boxes per second: keep the drawn set small there.
// ?budget=N overrides (cuboids drawn at most).
tiles.maxDrawn = Number(params.get('budget')) || (renderer.software ? SOFTWARE_BUDGET
  : renderer.kind === 'canvas2d' ? 200000 : 3000000);
renderer.onViewChange = () => tiles.scheduleSelect(60);
// Called when a complete frame is on the canvas; startedAt: when that frame began (a progressive
// frame spans several animation frames).
renderer.onRendered = (count, startedAt) => {
  const t = state.timings;
  const now = performance.now();
  if (count > 0 && t.firstPictureMs === null) t.firstPictureMs = now;
  if (count > 0 && t.refinedMs === null && t.idleMs !== null && startedAt >= t.idleMs) t.refinedMs = now;
};

// ----- token prompt -----

api.onUnauthorized = (reason) => new Promise((resolve) => {
  const dialog = $('token-dialog');
  const input = $('token-input');
  $('token-reason').textContent = api.currentToken()
    ? `The server refused the token (${reason.message || reason.code}). Enter another one.`
    : 'This server needs a bearer token (viewer, robot or admin).';
  setStatus('unauthorized', 'token required');
  state.pendingAuth = true;
  const form = $('token-form');
  const done = (event) => {
    event.preventDefault();
    const token = input.value.trim();
    if (!token) return;
    form.removeEventListener('submit', done);
    dialog.close();
    state.pendingAuth = false;
    input.value = '';
    resolve(token);
    stream.retryNow();
  };
  form.addEventListener('submit', done);
  if (!dialog.open) dialog.showModal();
  input.focus();
});

// ----- viewer stream -----

const stream = new ViewerStream(api, {
  onStatus: (s, detail) => setStatus(s, detail),
  onHello: () => {
    if (state.map) {
      tiles.refreshIndex();
      refreshRobots(true);
    } else {
      refreshMaps();
    }
  },
  onFrame: (frame) => handleFrame(frame),
  onFailure: async () => {
    // The upgrade failed; ask over HTTP what is wrong (a 401 opens the token prompt).
    try {
      await api.request('/v1/maps');
      if (state.map) {
        const status = await api.probe(`/v1/maps/${encodeURIComponent(state.map)}`);
        if (status === 404) refreshMaps();
      }
    } catch {
      // server unreachable: the stream keeps retrying with back-off
    }
  },
});

function handleFrame(frame) {
  switch (frame.type) {
    case 'tiles':
      if (!state.map) {
        refreshMaps();
        return;
      }
      if (frame.map === state.map) tiles.applyTilesFrame(frame);
      break;
    case 'poses':
      if (frame.map === state.map || (!frame.map && state.map)) onPoses(frame.poses || []);
      break;
    case 'resync':
      tiles.refreshIndex();
      refreshRobots(true);
      refreshLoops({ all: true });  // skipped frames may have withdrawn closures it lists
      break;
    case 'loop_closure':
      if (frame.map === state.map) addLoopClosures([frame], true);
      break;
    case 'loop_closure_withdrawn':
      if (frame.map === state.map) withdrawLoopClosure(frame);
      break;
    default:  // hello, and frame types of later servers
      break;
  }
}

// ----- maps -----

async function refreshMaps() {
  let json;
  try {
    json = await api.json('/v1/maps');
  } catch (e) {
    noteError(e);
    return;
  }
  state.maps = json.maps || [];
  if (state.timings.mapsMs === null) state.timings.mapsMs = performance.now();
  const select = $('map-select');
  const names = state.maps.map((m) => m.name);
  const current = [...select.options].map((o) => o.value);
  if (names.join('\n') !== current.join('\n')) {
    select.replaceChildren(...names.map((n) => new Option(n, n)));
  }
  $('map-empty').classList.toggle('hidden', names.length > 0);
  if (!state.map) {
    const wanted = params.get('map');
    const pick = (wanted && names.includes(wanted) && wanted) || (names.includes('sim') && 'sim') || names[0];
    if (pick) selectMap(pick);
    else if (stream.stopped) stream.connect('');
    return;
  }
  if (!names.includes(state.map)) return;
  select.value = state.map;
  onMapInfo(state.maps.find((m) => m.name === state.map));
}

function onMapInfo(info) {
  state.mapInfo = info;
  if (info && info.bounds) {
    const { min, max } = info.bounds;
    if ($('z-cut').value === $('z-cut').max) renderer.setZRange(min[2], Math.max(max[2], min[2] + 1));
    $('legend').replaceChildren(...legendFor(renderer.colorMode));
    // Follow the map while it grows (until the user moves the camera), but not every small change.
    const last = state.fittedBounds;
    const grown = !last || [0, 1, 2].some((a) => {
      const extent = Math.max(max[a] - min[a], last.max[a] - last.min[a], 1);
      return Math.abs(min[a] - last.min[a]) > 0.1 * extent || Math.abs(max[a] - last.max[a]) > 0.1 * extent;
    });
    if (grown) {
      state.fittedBounds = { min: min.slice(), max: max.slice() };
      renderer.fitBounds(min, max);
    }
    if ($('z-cut').value !== $('z-cut').max) applyZCut();
  }
  renderStats();
}

function selectMap(name) {
  if (state.map === name) return;
  state.map = name;
  state.mapInfo = null;
  state.fittedBounds = null;
  $('map-select').value = name;
  const url = new URL(window.location.href);
  url.searchParams.set('map', name);
  window.history.replaceState(null, '', url);
  renderer.userMoved = false;
  tiles.reset(name);
  renderer.showHighlight(null);
  renderer.hideSelection();
  for (const id of [...state.robots.keys()]) removeRobot(id);
  state.loops = [];
  state.loopIds.clear();
  renderLoops();
  stream.connect(name);
  tiles.refreshIndex();
  refreshMaps();
  refreshRobots(true);
  refreshLoops();
  if ($('show-layers').checked) probeLayers();
}

$('map-select').addEventListener('change', (e) => selectMap(e.target.value));

// ----- robots -----

function robotEntry(id) {
  let r = state.robots.get(id);
  if (!r) {
    const colorIndex = state.robotOrder++ % ROBOT_COLORS.length;
    r = { id, colorIndex, color: ROBOT_COLORS[colorIndex], info: null, pose: null, rate: null, lastSeq: null,
      lastSeqAt: 0, traj: { loaded: false, loading: false, stamp: -1, seq: -1, buffer: [] } };
    state.robots.set(id, r);
    loadTrajectory(r);
  }
  return r;
}

function removeRobot(id) {
  state.robots.delete(id);
  renderer.removeRobot(id);
}

function resetRobotsTrajectories() {
  for (const r of state.robots.values()) {
    r.traj = { loaded: false, loading: false, stamp: -1, seq: -1, buffer: [] };
    loadTrajectory(r);
  }
}

async function refreshRobots(reloadTrajectories = false) {
  if (!state.map) return;
  const map = state.map;
  let json;
  try {
    json = await api.json('/v1/robots');
  } catch (e) {
    noteError(e);
    return;
  }
  if (map !== state.map) return;
  const now = Date.now();
  const seen = new Set();
  for (const info of json.robots || []) {
    if (info.map !== map && !(info.pose && info.pose.map === map)) continue;
    seen.add(info.robot_id);
    const r = robotEntry(info.robot_id);
    // Messages per second over at least a second (polls can come closer together).
    if (r.lastSeq === null) {
      r.lastSeq = info.last_seq;
      r.lastSeqAt = now;
    } else if (now - r.lastSeqAt >= 1000) {
      const rate = ((info.last_seq - r.lastSeq) * 1000) / (now - r.lastSeqAt);
      r.rate = r.rate === null ? rate : 0.5 * r.rate + 0.5 * rate;
      r.lastSeq = info.last_seq;
      r.lastSeqAt = now;
    }
    if (!info.connected) r.rate = 0;
    r.info = info;
    if (info.pose && info.pose.map === map && (!r.pose || info.pose.stamp_ns > r.pose.stamp_ns)) setPose(r, info.pose);
    if (reloadTrajectories && r.traj.loaded) {
      r.traj = { loaded: false, loading: false, stamp: -1, seq: -1, buffer: [] };
      loadTrajectory(r);
    }
  }
  for (const id of [...state.robots.keys()]) if (!seen.has(id)) removeRobot(id);
  renderRobots();
}

function setPose(r, pose) {
  r.pose = pose;
  renderer.setRobotPose(r.id, r.color, pose.position, pose.orientation);
}

function onPoses(poses) {
  for (const pose of poses) {
    if (state.map && pose.map && pose.map !== state.map) continue;
    const r = robotEntry(pose.robot_id);
    if (r.pose && pose.stamp_ns < r.pose.stamp_ns) continue;
    setPose(r, pose);
    if (r.traj.loaded) appendTrajectory(r, [pose]);
    else r.traj.buffer.push(pose);
  }
  renderRobots();
}

async function loadTrajectory(r) {
  if (r.traj.loading) return;
  const traj = r.traj;
  traj.loading = true;
  try {
    const json = await api.json(`/v1/robots/${encodeURIComponent(r.id)}/trajectory?limit=${TRAJECTORY_LIMIT}`);
    if (state.robots.get(r.id) !== r || r.traj !== traj) return;
    const poses = json.poses || [];
    const flat = new Float32Array(poses.length * 3);
    poses.forEach((p, i) => flat.set(p.position, 3 * i));
    renderer.addTrajectory(r.id, r.color, flat, true);
    if (poses.length) {
      traj.stamp = poses[poses.length - 1].stamp_ns;
      traj.seq = poses[poses.length - 1].seq;
    }
    traj.loaded = true;
    const buffered = traj.buffer;
    traj.buffer = [];
    appendTrajectory(r, buffered);
  } catch (e) {
    noteError(e);
  } finally {
    traj.loading = false;
  }
}

// A geometric loop closure comes with a pose graph correction: the robots' trajectories the
// server keeps change, so they are read again, once per burst of closures (the server writes
// corrected poses within half a second).
const reloadRobots = new Set();
let reloadTimer = null;

function reloadTrajectoriesOf(ids) {
  for (const id of ids) if (id) reloadRobots.add(id);
  if (reloadTimer) return;
  reloadTimer = setTimeout(() => {
    reloadTimer = null;
    for (const id of reloadRobots) {
      const r = state.robots.get(id);
      if (r) loadTrajectory(r);
    }
    reloadRobots.clear();
  }, 1000);
}

function appendTrajectory(r, poses) {
  const fresh = poses.filter((p) => p.stamp_ns > r.traj.stamp);
  if (!fresh.length) return;
  const flat = new Float32Array(fresh.length * 3);
  fresh.forEach((p, i) => flat.set(p.position, 3 * i));
  r.traj.stamp = fresh[fresh.length - 1].stamp_ns;
  renderer.addTrajectory(r.id, r.color, flat, false);
}

function renderRobots() {
  const list = $('robots');
  const items = [];
  for (const r of state.robots.values()) {
    const li = document.createElement('li');
    if (r.info && !r.info.connected) li.classList.add('off');
    const sw = document.createElement('span');
    sw.className = `swatch swatch-${r.colorIndex}`;
    const name = document.createElement('span');
    name.className = 'name';
    name.textContent = r.id;
    name.title = r.info ? `${r.info.connected ? 'connected' : 'disconnected'}; last seq ${r.info.last_seq}` : r.id;
    const rate = document.createElement('span');
    rate.className = 'num';
    rate.textContent = r.info && !r.info.connected ? 'offline' : r.rate === null ? '… msg/s' : `${r.rate.toFixed(1)} msg/s`;
    const pos = document.createElement('span');
    pos.className = 'num';
    pos.textContent = r.pose ? r.pose.position.map((v) => v.toFixed(1)).join(', ') : '';
    li.append(sw, name, rate, pos);
    items.push(li);
  }
  list.replaceChildren(...items);
  $('robots-empty').classList.toggle('hidden', items.length > 0);
}

$('show-robots').addEventListener('change', (e) => renderer.setRobotsVisible(e.target.checked));

// ----- loop closures -----

// Closures as docs/API.md §6.10 gives them (the stream's frames add "type"): the two places'
// positions, null when a place's pose is unknown; a withdrawn one (withdrawn_ns set: the pose
// graph dropped it) stays listed, struck through, and is not drawn.
function addLoopClosures(events, fresh) {
  let changed = false;
  for (const e of events) {
    if (state.loopIds.has(e.id)) {
      const lc = e.withdrawn_ns != null && state.loops.find((l) => l.id === e.id);
      if (lc && !lc.withdrawn) {
        lc.event = e;
        lc.withdrawn = true;
        changed = true;
      }
      continue;
    }
    state.loopIds.add(e.id);
    state.loops.push({ id: e.id, event: e, a: e.query?.position ?? null, b: e.match?.position ?? null,
      source: e.source, fresh, withdrawn: e.withdrawn_ns != null, at: Date.now() });
    changed = true;
  }
  if (!changed) return;
  renderLoops();
  if (fresh) {
    const corrected = events.filter((e) => e.source === 'geometry');
    if (corrected.length) reloadTrajectoriesOf(corrected.flatMap((e) => [e.query?.robot_id, e.match?.robot_id]));
    setTimeout(() => {
      for (const lc of state.loops) lc.fresh = false;
      renderLoops();
    }, 4000);
  }
}

// The pose graph dropped a closure it had reported: its trajectories moved again.
function withdrawLoopClosure(e) {
  addLoopClosures([e], false);
  reloadTrajectoriesOf([e.query?.robot_id, e.match?.robot_id]);
}

// A closure's measured relative pose (docs/API.md §6.10) as its distance and turn, or '' when
// the closure measured none.
function measuredOffsetText(relative) {
  if (!relative?.position || !relative.orientation) return '';
  const [x, y, z] = relative.position;
  const turnDeg = (2 * Math.acos(Math.min(1, Math.abs(relative.orientation[0]))) * 180) / Math.PI;
  return `${Math.hypot(x, y, z).toFixed(2)} m ${turnDeg.toFixed(1)}°`;
}

function renderLoops() {
  renderer.setLoopClosures(state.loops.filter((lc) => lc.a && lc.b && !lc.withdrawn));
  const items = state.loops.slice(-200).reverse().map((lc) => {
    const li = document.createElement('li');
    if (lc.fresh) li.classList.add('fresh');
    if (lc.withdrawn) {
      li.classList.add('withdrawn');
      li.title = 'withdrawn: a later pose graph optimisation dropped it';
    }
    const name = document.createElement('span');
    name.className = 'name';
    const robots = [lc.event.query?.robot_id, lc.event.match?.robot_id].filter(Boolean).join(' ↔ ');
    name.textContent = `#${lc.id}${robots ? ` ${robots}` : ''}`;
    const source = document.createElement('span');
    source.className = 'loop-source';
    source.style.color = loopColor(lc.source);
    source.textContent = lc.source || '';
    const offset = document.createElement('span');
    offset.className = 'num loop-offset';
    offset.textContent = measuredOffsetText(lc.event.relative_pose);
    offset.title = 'measured relative pose: the newer place from the older one';
    // An ambiguous match (a corridor): the offset holds only across this direction.
    const along = lc.event.ambiguous_direction;
    if (along && offset.textContent) {
      offset.textContent += ' ↔';
      offset.title += `; ambiguous: known only to about a metre along (${along[0].toFixed(2)}, ${along[1].toFixed(2)}) of the older place's frame`;
    }
    const when = document.createElement('span');
    when.className = 'num';
    const stamp = lc.event.query?.stamp_ns ?? lc.event.detected_ns;
    when.textContent = stamp ? new Date(stamp / 1e6).toLocaleTimeString() : '';
    li.append(name, source, offset, when);
    return li;
  });
  $('loops').replaceChildren(...items);
  $('loops-empty').classList.toggle('hidden', items.length > 0);
}

// New closures since the newest listed; `all`: every closure again, to learn of withdrawals.
async function refreshLoops({ all = false } = {}) {
  if (!state.map) return;
  const map = state.map;
  const since = all ? 0 : state.loops.reduce((m, lc) => (typeof lc.id === 'number' && lc.id > m ? lc.id : m), 0);
  try {
    const json = await api.json(`/v1/loop-closures?map=${encodeURIComponent(map)}&since=${since}${all ? '&limit=100000' : ''}`);
    if (map === state.map) addLoopClosures(json.loop_closures || [], false);
  } catch (e) {
    noteError(e);
  }
}

// ----- 2D layers -----

const layers = new Layers2D(api, renderer, {
  onState: (status, detail) => {
    state.layersAvailable = status === 'shown';
    state.layersVersion = status === 'shown' ? detail.version : null;
    $('layers-empty').classList.toggle('hidden', status === 'shown' || !$('show-layers').checked);
    if (status === 'error') noteError(detail);
  },
});

function probeLayers() {
  if (!state.map || !$('show-layers').checked) return;
  layers.show(state.map, $('layer-select').value).catch((e) => noteError(e));
}

$('show-layers').addEventListener('change', (e) => {
  if (e.target.checked) {
    probeLayers();
  } else {
    layers.hide();
    $('layers-empty').classList.add('hidden');
  }
});
$('layer-select').addEventListener('change', () => probeLayers());
setInterval(() => probeLayers(), MAP_POLL_MS);

// ----- display options -----

function setColorMode(mode) {
  renderer.setColorMode(mode);
  $('legend').replaceChildren(...legendFor(mode));
}

function legendFor(mode) {
  const lo = document.createElement('span');
  const bar = document.createElement('span');
  const hi = document.createElement('span');
  bar.className = `bar legend-${mode}`;
  if (mode === 'height') {
    lo.textContent = `${renderer.zLo.toFixed(1)} m`;
    hi.textContent = `${renderer.zHi.toFixed(1)} m`;
  } else {
    lo.textContent = 'free 0';
    hi.textContent = '1 occupied';
  }
  return [lo, bar, hi];
}

for (const radio of document.querySelectorAll('input[name="color"]')) {
  radio.addEventListener('change', (e) => { if (e.target.checked) setColorMode(e.target.value); });
}
$('show-free').addEventListener('change', (e) => {
  tiles.setShowFree(e.target.checked);
  renderer.setShowFree(e.target.checked);
});
$('auto-rotate').addEventListener('change', (e) => renderer.setAutoRotate(e.target.checked));

// Height cut: the slider spans the map's height; at its top nothing is hidden.
function applyZCut() {
  const slider = $('z-cut');
  const b = state.mapInfo && state.mapInfo.bounds;
  const t = Number(slider.value) / Number(slider.max);
  if (!b || t >= 1) {
    renderer.setZCut(Infinity);
    $('z-cut-value').textContent = 'off';
    if (b) renderer.setZRange(b.min[2], Math.max(b.max[2], b.min[2] + 1));
  } else {
    const z = b.min[2] + t * (b.max[2] - b.min[2]);
    renderer.setZCut(z);
    $('z-cut-value').textContent = `${z.toFixed(1)} m`;
    renderer.setZRange(b.min[2], Math.max(z, b.min[2] + 0.5)); // the colours span what is shown
  }
  $('legend').replaceChildren(...legendFor(renderer.colorMode));
}
$('z-cut').addEventListener('input', applyZCut);
$('fit-view').addEventListener('click', () => {
  const b = state.mapInfo && state.mapInfo.bounds;
  if (b) {
    state.fittedBounds = { min: b.min.slice(), max: b.max.slice() };
    renderer.userMoved = false;
    renderer.fitBounds(b.min, b.max, { force: true });
  }
});

// ----- click query and box select -----

let press = null;
view.addEventListener('pointerdown', (e) => {
  if (e.target !== renderer.canvas || e.button !== 0) return;
  if (e.shiftKey) {
    // Box select on the ground plane; keep the camera controls out of it.
    e.stopPropagation();
    e.preventDefault();
    const a = renderer.groundPoint(e.clientX, e.clientY);
    if (!a) return;
    renderer.setControlsEnabled(false);
    press = { box: true, a, b: a, id: e.pointerId };
    renderer.canvas.setPointerCapture(e.pointerId);
    return;
  }
  press = { box: false, x: e.clientX, y: e.clientY, t: performance.now() };
}, { capture: true });

view.addEventListener('pointermove', (e) => {
  if (!press || !press.box) return;
  const b = renderer.groundPoint(e.clientX, e.clientY);
  if (!b) return;
  press.b = b;
  const [min, max] = boxOf(press.a, press.b);
  renderer.showSelection(min, max);
}, { capture: true });

view.addEventListener('pointerup', (e) => {
  const p = press;
  press = null;
  if (!p) return;
  if (p.box) {
    renderer.setControlsEnabled(true);
    const [min, max] = boxOf(p.a, p.b);
    if (max[0] - min[0] < 1e-3 && max[1] - min[1] < 1e-3) {
      renderer.hideSelection();
      return;
    }
    boxQuery(min, max);
    return;
  }
  if (Math.hypot(e.clientX - p.x, e.clientY - p.y) < 5 && performance.now() - p.t < 800) pointQuery(e.clientX, e.clientY);
}, { capture: true });

function boxOf(a, b) {
  const bounds = state.mapInfo && state.mapInfo.bounds;
  const zlo = bounds ? bounds.min[2] : -1;
  const zhi = bounds ? bounds.max[2] : 5;
  return [[Math.min(a[0], b[0]), Math.min(a[1], b[1]), zlo], [Math.max(a[0], b[0]), Math.max(a[1], b[1]), zhi]];
}

function occupancyUrl(x, y, z) {
  return `/v1/maps/${encodeURIComponent(state.map)}/occupancy?x=${x}&y=${y}&z=${z}`;
}

async function pointQuery(clientX, clientY) {
  if (!state.map) return;
  const pick = renderer.pick(clientX, clientY);
  if (!pick) return;
  const [x, y, z] = pick.point;
  const entry = { point: [x, y, z], hit: pick.hit, level: pick.level ?? null, displayed: pick.cuboid || null,
    result: null, error: null, at: Date.now() };
  state.lastQuery = entry;
  renderQuery();
  try {
    entry.result = await api.json(occupancyUrl(x, y, z));
    const c = entry.result.cuboid;
    renderer.showHighlight(c ? c.min : pick.cuboid?.min || null, c ? c.max : pick.cuboid?.max || null);
  } catch (e) {
    entry.error = e.message;
  }
  if (state.lastQuery === entry) renderQuery();
}

async function boxQuery(min, max) {
  if (!state.map) return;
  renderer.showSelection(min, max);
  const entry = { min, max, count: 0, occupied: 0, free: 0, first: [], complete: false, error: null };
  state.lastBox = entry;
  state.lastQuery = null;
  renderBox();
  const base = `/v1/maps/${encodeURIComponent(state.map)}/occupancy/box?min=${min.join(',')}&max=${max.join(',')}&limit=${BOX_PAGE}`;
  let token = null;
  try {
    do {
      const json = await api.json(token ? `${base}&page_token=${encodeURIComponent(token)}` : base);
      if (state.lastBox !== entry) return;
      for (const c of json.cuboids) {
        entry.count++;
        if (c.state === 'occupied') entry.occupied++;
        else entry.free++;
        if (entry.first.length < 8) entry.first.push(c);
      }
      token = json.next_page_token;
      renderBox();
    } while (token && entry.count < BOX_COUNT_LIMIT);
    entry.complete = !token;
  } catch (e) {
    entry.error = e.message;
  }
  renderBox();
}

const fmt = (v) => (Math.abs(v) >= 100 ? v.toFixed(1) : v.toFixed(2));
const vec = (v) => `(${v.map(fmt).join(', ')})`;

function renderQuery() {
  const q = state.lastQuery;
  const el = $('query');
  el.classList.remove('empty');
  const parts = [];
  const line = (label, value, cls) => {
    const div = document.createElement('div');
    const b = document.createElement('span');
    b.textContent = `${label} `;
    const v = document.createElement('span');
    v.textContent = value;
    if (cls) v.className = cls;
    div.append(b, v);
    parts.push(div);
  };
  line('point', vec(q.point));
  if (q.error) line('error', q.error);
  else if (!q.result) line('state', 'querying…');
  else {
    line('state', q.result.state, `state state-${q.result.state}`);
    line('probability', q.result.probability.toFixed(3));
    if (q.result.cuboid) line('cuboid', `${vec(q.result.cuboid.min)} – ${vec(q.result.cuboid.max)}`);
  }
  line('picked', q.hit ? `cuboid of level ${q.level}` : 'ground plane (no cuboid under the pointer)');
  el.replaceChildren(...parts);
}

function renderBox() {
  const b = state.lastBox;
  const el = $('query');
  el.classList.remove('empty');
  const head = document.createElement('div');
  head.textContent = `box ${vec(b.min)} – ${vec(b.max)}`;
  const count = document.createElement('div');
  const more = b.complete || b.error ? '' : b.count >= BOX_COUNT_LIMIT ? '+' : '…';
  count.textContent = `${b.count}${more} cuboids (${b.occupied} occupied, ${b.free} free)`;
  const parts = [head, count];
  if (b.error) {
    const err = document.createElement('div');
    err.textContent = `error: ${b.error}`;
    parts.push(err);
  }
  if (b.first.length) {
    const table = document.createElement('table');
    for (const c of b.first) {
      const tr = table.insertRow();
      tr.insertCell().textContent = c.state;
      tr.insertCell().textContent = c.probability.toFixed(2);
      tr.insertCell().textContent = `${vec(c.min)}–${vec(c.max)}`;
    }
    parts.push(table);
  }
  el.replaceChildren(...parts);
}

// ----- status, stats, errors -----

function setStatus(s, detail) {
  state.streamState = s;
  state.streamDetail = detail;
  const el = $('status');
  el.className = `status status-${s}`;
  el.textContent = s === 'live' ? 'live' : detail;
  el.title = detail;
}

function noteError(e) {
  if (e && e.name === 'AbortError') return;
  state.errors.push(String(e && e.message ? e.message : e));
  if (state.errors.length > 50) state.errors.shift();
  if (e instanceof ApiError && e.status === 0) setStatus('reconnecting', 'server unreachable');
}

function showOverlay(text, ms) {
  const el = $('overlay');
  el.textContent = text;
  el.classList.toggle('hidden', !text);
  clearTimeout(overlayTimer);
  if (ms) overlayTimer = setTimeout(() => el.classList.add('hidden'), ms);
}

function renderStats() {
  const info = state.mapInfo;
  const rows = [];
  const add = (k, v) => {
    const dt = document.createElement('dt');
    dt.textContent = k;
    const dd = document.createElement('dd');
    dd.textContent = v;
    rows.push(dt, dd);
  };
  if (info) {
    add('cuboids (server)', info.cuboids.toLocaleString('en-US'));
    add('resolution', `${info.resolution_m} m`);
    add('version', String(info.version));
  }
  add('cuboids drawn', renderer.cuboidCount().toLocaleString('en-US'));
  add('tiles', `${tiles.drawn.size} drawn, ${tiles.loadedCount()} cached`);
  const pending = tiles.pending();
  const stale = tiles.staleDrawn();
  // Always a row, so that the controls below do not jump as tiles come and go.
  add('loading', pending || stale ? `${pending} missing, ${stale} updating` : 'none');
  if (tiles.epoch !== null) add('epoch', String(tiles.epoch));
  $('map-stats').replaceChildren(...rows);
}

let lastFrames = renderer.frames;
let lastPerfAt = performance.now();
function renderPerf() {
  const now = performance.now();
  const fps = ((renderer.frames - lastFrames) * 1000) / Math.max(1, now - lastPerfAt);
  lastFrames = renderer.frames;
  lastPerfAt = now;
  const t = state.timings;
  const first = t.firstPictureMs === null ? '–' : `${Math.round(t.firstPictureMs)} ms`;
  $('perf').textContent = `${renderer.kind} · ${fps.toFixed(0)} renders/s · first picture ${first}`;
  const waiting = state.map && tiles.indexLoaded && renderer.cuboidCount() === 0 && tiles.pending() === 0
    && state.mapInfo && state.mapInfo.cuboids === 0;
  if (!state.map) showOverlay(state.maps.length === 0 ? 'Waiting for a map…' : '');
  else if (waiting) showOverlay('The map is empty so far.');
  else if ($('overlay').textContent.startsWith('Waiting') || $('overlay').textContent.startsWith('The map')) showOverlay('');
}

setInterval(() => {
  renderStats();
  renderPerf();
}, 500);
setInterval(() => refreshMaps(), MAP_POLL_MS);
setInterval(() => { refreshRobots(false); }, ROBOT_POLL_MS);
setInterval(() => refreshLoops(), LOOP_POLL_MS);

// ----- start -----

if (params.get('color') === 'probability') {
  document.querySelector('input[name="color"][value="probability"]').checked = true;
}
setColorMode(params.get('color') === 'probability' ? 'probability' : 'height');
if (params.get('free') === '1') {
  $('show-free').checked = true;
  tiles.setShowFree(true);
  renderer.setShowFree(true);
}
if (params.get('rotate') === '1') {
  $('auto-rotate').checked = true;
  renderer.setAutoRotate(true);
}
refreshMaps();

// ----- read-only hook for tests and scripts -----

const copy = (v) => (v === null || v === undefined ? null : JSON.parse(JSON.stringify(v)));
window.rmapViewer = Object.freeze({
  loadId,
  renderer: () => renderer.kind,
  map: () => state.map,
  streamState: () => state.streamState,
  cuboidCount: () => renderer.cuboidCount(),
  tilesLoaded: () => tiles.loadedCount(),
  tilesDrawn: () => [...tiles.drawn].map(keyName),
  tileVersions: () => tiles.versions(),
  tileStats: () => ({ ...tiles.stats, pending: tiles.pending(), staleDrawn: tiles.staleDrawn(), epoch: tiles.epoch,
    mapVersion: tiles.mapVersion, drawnCuboids: renderer.cuboidCount() }),
  robots: () => [...state.robots.values()].map((r) => ({ id: r.id, rate: r.rate, connected: r.info ? r.info.connected : null })),
  lastPose: (id) => copy(state.robots.get(id)?.pose ?? null),
  lastQuery: () => copy(state.lastQuery),
  lastBox: () => copy(state.lastBox),
  loopClosures: () => copy(state.loops.map((lc) => lc.event)),
  loopLines: () => renderer.loopLineCounts(),
  query: (x, y, z) => api.json(occupancyUrl(x, y, z)),
  timings: () => ({ ...state.timings }),
  layers: () => ({ available: state.layersAvailable, version: state.layersVersion ?? null,
    tiles: [...layers.shown] }),
  frameStats: (n) => renderer.frameStats(n),
  frames: () => renderer.frames,
  errors: () => [...state.errors],
  /** Client coordinates of a map point (3D renderer), for tests that click on the map. */
  project: (x, y, z) => {
    if (renderer.kind !== 'webgl') return null;
    return renderer.project([x, y, z]);
  },
});

// Diagnostics: ?debug=1 logs the tile and render counters once a second.
if (params.has('debug')) {
  setInterval(() => {
    const s = tiles.stats;
    console.log(`[rmap debug t=${performance.now().toFixed(0)}] drawn=${renderer.cuboidCount()} loads=${s.loads} `
      + `refreshes=${s.refreshes} notModified=${s.notModified} pending=${tiles.pending()} stale=${tiles.staleDrawn()} `
      + `renders=${renderer.frames} requests=${api.requests}`);
  }, 1000);
}
