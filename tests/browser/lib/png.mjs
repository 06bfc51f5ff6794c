// Minimal PNG reader (8-bit RGB/RGBA, non-interlaced: what Chromium's screenshots are) and
// pixel statistics for the tests. Node's zlib does the inflating.

import zlib from 'node:zlib';

export function decodePng(buffer) {
  const sig = [137, 80, 78, 71, 13, 10, 26, 10];
  for (let i = 0; i < 8; i++) if (buffer[i] !== sig[i]) throw new Error('not a PNG');
  let pos = 8;
  let width = 0;
  let height = 0;
  let bitDepth = 0;
  let colorType = 0;
  let interlace = 0;
  const idat = [];
  while (pos < buffer.length) {
    const len = buffer.readUInt32BE(pos);
    const type = buffer.toString('latin1', pos + 4, pos + 8);
    const data = buffer.subarray(pos + 8, pos + 8 + len);
    if (type === 'IHDR') {
      width = data.readUInt32BE(0);
      height = data.readUInt32BE(4);
      bitDepth = data[8];
      colorType = data[9];
      interlace = data[12];
    } else if (type === 'IDAT') {
      idat.push(data);
    } else if (type === 'IEND') {
      break;
    }
    pos += 12 + len;
  }
  if (bitDepth !== 8 || (colorType !== 2 && colorType !== 6) || interlace !== 0) {
    throw new Error(`unsupported PNG (bit depth ${bitDepth}, colour type ${colorType}, interlace ${interlace})`);
  }
  const channels = colorType === 6 ? 4 : 3;
  const raw = zlib.inflateSync(Buffer.concat(idat));
  const stride = width * channels;
  const out = Buffer.alloc(width * height * 4);
  let prev = Buffer.alloc(stride);
  for (let y = 0; y < height; y++) {
    const filter = raw[y * (stride + 1)];
    const line = Buffer.from(raw.subarray(y * (stride + 1) + 1, (y + 1) * (stride + 1)));
    for (let i = 0; i < stride; i++) {
      const a = i >= channels ? line[i - channels] : 0;
      const b = prev[i];
      const c = i >= channels ? prev[i - channels] : 0;
      let v = line[i];
      if (filter === 1) v += a;
      else if (filter === 2) v += b;
      else if (filter === 3) v += (a + b) >> 1;
      else if (filter === 4) {
        const p = a + b - c;
        const pa = Math.abs(p - a);
        const pb = Math.abs(p - b);
        const pc = Math.abs(p - c);
        v += pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
      }
      line[i] = v & 0xff;
    }
    for (let x = 0; x < width; x++) {
      out[4 * (y * width + x)] = line[channels * x];
      out[4 * (y * width + x) + 1] = line[channels * x + 1];
      out[4 * (y * width + x) + 2] = line[channels * x + 2];
      out[4 * (y * width + x) + 3] = channels === 4 ? line[channels * x + 3] : 255;
    }
    prev = line;
  }
  return { width, height, rgba: out };
}

/**
 * Fraction of the pixels of `rect` ({x, y, width, height} in image pixels; default: all) whose
 * colour differs from `background` ([r, g, b]) by more than `tolerance` in some channel, and
 * how many distinct colours (quantised to 4 bits per channel) they have.
 */
export function foregroundStats(png, background, { rect, tolerance = 24 } = {}) {
  const x0 = Math.max(0, Math.floor(rect ? rect.x : 0));
  const y0 = Math.max(0, Math.floor(rect ? rect.y : 0));
  const x1 = Math.min(png.width, Math.ceil(rect ? rect.x + rect.width : png.width));
  const y1 = Math.min(png.height, Math.ceil(rect ? rect.y + rect.height : png.height));
  let n = 0;
  let fg = 0;
  const colors = new Set();
  for (let y = y0; y < y1; y++) {
    for (let x = x0; x < x1; x++) {
      const o = 4 * (y * png.width + x);
      const r = png.rgba[o];
      const g = png.rgba[o + 1];
      const b = png.rgba[o + 2];
      n++;
      if (Math.abs(r - background[0]) > tolerance || Math.abs(g - background[1]) > tolerance
          || Math.abs(b - background[2]) > tolerance) {
        fg++;
        colors.add(((r >> 4) << 8) | ((g >> 4) << 4) | (b >> 4));
      }
    }
  }
  return { fraction: n ? fg / n : 0, pixels: fg, colors: colors.size };
}

// The viewer's clear colour (scene3d.js / fallback2d.js BACKGROUND).
export const VIEWER_BACKGROUND = [0x12, 0x16, 0x1c];
