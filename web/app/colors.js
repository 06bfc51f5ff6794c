// Colour ramps as small lookup tables (linear RGB floats, 3 per entry), built once.

const RAMP_SIZE = 256;

function buildRamp(stops) {
  const lut = new Float32Array(RAMP_SIZE * 3);
  for (let i = 0; i < RAMP_SIZE; i++) {
    const t = i / (RAMP_SIZE - 1);
    let k = 0;
    while (k < stops.length - 2 && t > stops[k + 1][0]) k++;
    const [t0, c0] = stops[k];
    const [t1, c1] = stops[k + 1];
    const u = Math.min(1, Math.max(0, (t - t0) / (t1 - t0)));
    for (let c = 0; c < 3; c++) {
      const srgb = c0[c] + (c1[c] - c0[c]) * u;
      lut[3 * i + c] = srgbToLinear(srgb / 255);
    }
  }
  return lut;
}

function srgbToLinear(v) {
  return v <= 0.04045 ? v / 12.92 : ((v + 0.055) / 1.055) ** 2.4;
}

// Height: deep blue → teal → green → yellow → orange → red (perceptually ordered, turbo-like).
export const HEIGHT_RAMP = buildRamp([
  [0.0, [48, 18, 129]], [0.15, [40, 110, 220]], [0.35, [32, 190, 190]], [0.55, [120, 210, 80]],
  [0.75, [245, 200, 45]], [0.9, [240, 120, 35]], [1.0, [200, 40, 30]],
]);

// Occupancy probability of occupied cuboids, 0.5 → 1: pale yellow → red → dark red.
export const OCCUPIED_RAMP = buildRamp([[0.0, [250, 230, 140]], [0.5, [240, 120, 50]], [1.0, [150, 20, 30]]]);

// Free cuboids, probability 0 → 0.5: light cyan → blue.
export const FREE_RAMP = buildRamp([[0.0, [150, 220, 255]], [1.0, [60, 110, 220]]]);

/** Writes the ramp colour at t ∈ [0, 1] into out[o..o+2]. */
export function rampAt(lut, t, out, o) {
  let i = (t * (RAMP_SIZE - 1) + 0.5) | 0;
  if (i < 0) i = 0;
  else if (i >= RAMP_SIZE) i = RAMP_SIZE - 1;
  out[o] = lut[3 * i];
  out[o + 1] = lut[3 * i + 1];
  out[o + 2] = lut[3 * i + 2];
}

/** CSS colour string (sRGB) of a ramp position, for legends and the 2D renderer. */
export function rampCss(lut, t) {
  const tmp = [0, 0, 0];
  rampAt(lut, t, tmp, 0);
  const s = (v) => Math.round(255 * (v <= 0.0031308 ? 12.92 * v : 1.055 * v ** (1 / 2.4) - 0.055));
  return `rgb(${s(tmp[0])},${s(tmp[1])},${s(tmp[2])})`;
}

// Robot colours (sRGB hex), by order of appearance.
export const ROBOT_COLORS = ['#e6194b', '#3cb44b', '#4363d8', '#f58231', '#911eb4', '#42d4f4', '#f032e6', '#bfef45',
  '#fabed4', '#469990', '#dcbeff', '#9a6324', '#800000', '#aaffc3', '#808000', '#000075'];

/**
 * Writes the colour of cuboid k of a tile into out[o..o+2].
 * mode: 'height' | 'probability'; zLo/zHi: height range (m) of the ramp; r: resolution (m).
 */
export function cuboidColor(tile, k, mode, zLo, zHi, r, out, o) {
  const p = tile.probability[k];
  if (mode === 'probability') {
    if (p >= 0.5) rampAt(OCCUPIED_RAMP, (p - 0.5) * 2, out, o);
    else rampAt(FREE_RAMP, p * 2, out, o);
    return;
  }
  if (p < 0.5) {
    rampAt(FREE_RAMP, 0.7, out, o);
    return;
  }
  const zc = 0.5 * (tile.minCell[3 * k + 2] + tile.maxCell[3 * k + 2] + 1) * r;
  rampAt(HEIGHT_RAMP, zHi > zLo ? (zc - zLo) / (zHi - zLo) : 0.5, out, o);
}

// Loop closures by the source that found them (GET /v1/loop-closures `source`), CSS colours.
export const LOOP_COLORS = { camera: '#ffd54a', laser_intensity: '#ff4df0', geometry: '#4dd0ff' };
export const LOOP_FALLBACK_COLOR = '#ffffff';

/** Colour of a loop closure's line: its source's, white for an unknown source. */
export function loopColor(source) {
  return LOOP_COLORS[source] || LOOP_FALLBACK_COLOR;
}
