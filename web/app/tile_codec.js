// Hand-written decoder of the `rmap.v1.Tile` protobuf message (proto/rmap/v1/map_api.proto):
//
//   uint32 level = 1; sint32 x = 2; sint32 y = 3; sint32 z = 4; uint64 version = 5;
//   double resolution_m = 6; repeated sint32 min_cell = 7; repeated sint32 max_cell = 8;
//   repeated float probability = 9; uint64 epoch = 10;
//
// Repeated fields are accepted packed (wire type 2, proto3's default) and unpacked.
// Unknown fields are skipped. The result holds typed arrays: minCell/maxCell (Int32Array,
// 3 per cuboid) and probability (Float32Array, 1 per cuboid).

const WIRE_VARINT = 0;
const WIRE_I64 = 1;
const WIRE_LEN = 2;
const WIRE_I32 = 5;

class Reader {
  constructor(bytes) {
    this.buf = bytes;
    this.pos = 0;
    this.view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  }

  // Varint as a JS number; exact up to 2^53 (versions and epochs stay far below).
  varint() {
    const buf = this.buf;
    let pos = this.pos;
    let b = buf[pos++];
    if (b < 0x80) {
      this.pos = pos;
      return b;
    }
    let value = b & 0x7f;
    let mul = 128;
    do {
      if (pos >= buf.length) throw new Error('truncated varint');
      b = buf[pos++];
      value += (b & 0x7f) * mul;
      mul *= 128;
    } while (b >= 0x80);
    this.pos = pos;
    return value;
  }

  // 32-bit zigzag varint (sint32).
  sint32() {
    const buf = this.buf;
    let pos = this.pos;
    let result = 0;
    let shift = 0;
    let b;
    do {
      b = buf[pos++];
      if (shift < 32) result |= (b & 0x7f) << shift;
      shift += 7;
    } while (b >= 0x80 && shift < 70);
    this.pos = pos;
    return (result >>> 1) ^ -(result & 1);
  }

  skip(wire) {
    switch (wire) {
      case WIRE_VARINT:
        while (this.buf[this.pos++] >= 0x80);
        break;
      case WIRE_I64:
        this.pos += 8;
        break;
      case WIRE_LEN: {
        const n = this.varint();
        this.pos += n;
        break;
      }
      case WIRE_I32:
        this.pos += 4;
        break;
      default:
        throw new Error(`unsupported wire type ${wire}`);
    }
  }
}

// Counts varints in [start, end) to size a packed sint32 array exactly.
function countVarints(buf, start, end) {
  let n = 0;
  for (let i = start; i < end; i++) if (buf[i] < 0x80) n++;
  return n;
}

/**
 * Decodes a Tile message.
 * @param {ArrayBuffer|Uint8Array} data
 * @returns {{level:number,x:number,y:number,z:number,version:number,epoch:number,resolution:number,
 *            count:number,minCell:Int32Array,maxCell:Int32Array,probability:Float32Array}}
 */
export function decodeTile(data) {
  const bytes = data instanceof Uint8Array ? data : new Uint8Array(data);
  const r = new Reader(bytes);
  const tile = {
    level: 0, x: 0, y: 0, z: 0, version: 0, epoch: 0, resolution: 0,
    count: 0, minCell: null, maxCell: null, probability: null,
  };
  const minParts = [];
  const maxParts = [];
  const probParts = [];
  const end = bytes.length;
  while (r.pos < end) {
    const key = r.varint();
    const field = Math.floor(key / 8);
    const wire = key & 7;
    switch (field) {
      case 1: tile.level = r.varint(); break;
      case 2: tile.x = r.sint32(); break;
      case 3: tile.y = r.sint32(); break;
      case 4: tile.z = r.sint32(); break;
      case 5: tile.version = r.varint(); break;
      case 6:
        if (wire !== WIRE_I64) { r.skip(wire); break; }
        tile.resolution = r.view.getFloat64(r.pos, true);
        r.pos += 8;
        break;
      case 7:
      case 8: {
        const parts = field === 7 ? minParts : maxParts;
        if (wire === WIRE_LEN) {
          const n = r.varint();
          const stop = r.pos + n;
          const out = new Int32Array(countVarints(bytes, r.pos, stop));
          let i = 0;
          while (r.pos < stop) out[i++] = r.sint32();
          parts.push(out);
        } else if (wire === WIRE_VARINT) {
          parts.push(Int32Array.of(r.sint32()));
        } else {
          r.skip(wire);
        }
        break;
      }
      case 9:
        if (wire === WIRE_LEN) {
          const n = r.varint();
          const out = new Float32Array(n >> 2);
          for (let i = 0; i < out.length; i++) out[i] = r.view.getFloat32(r.pos + 4 * i, true);
          r.pos += n;
          probParts.push(out);
        } else if (wire === WIRE_I32) {
          probParts.push(Float32Array.of(r.view.getFloat32(r.pos, true)));
          r.pos += 4;
        } else {
          r.skip(wire);
        }
        break;
      case 10: tile.epoch = r.varint(); break;
      default: r.skip(wire);
    }
  }
  if (r.pos !== end) throw new Error('truncated tile message');
  tile.minCell = concatInt(minParts);
  tile.maxCell = concatInt(maxParts);
  tile.probability = concatFloat(probParts);
  const count = tile.probability.length;
  if (tile.minCell.length !== 3 * count || tile.maxCell.length !== 3 * count) {
    throw new Error(`tile with ${count} probabilities but ${tile.minCell.length}/${tile.maxCell.length} cell values`);
  }
  tile.count = count;
  return tile;
}

function concatInt(parts) {
  if (parts.length === 1) return parts[0];
  let n = 0;
  for (const p of parts) n += p.length;
  const out = new Int32Array(n);
  let o = 0;
  for (const p of parts) { out.set(p, o); o += p.length; }
  return out;
}

function concatFloat(parts) {
  if (parts.length === 1) return parts[0];
  let n = 0;
  for (const p of parts) n += p.length;
  const out = new Float32Array(n);
  let o = 0;
  for (const p of parts) { out.set(p, o); o += p.length; }
  return out;
}

/** Converts the JSON form of a tile (Accept: application/json) to the decoded shape. */
export function tileFromJson(json) {
  const n = json.cuboids.length;
  const minCell = new Int32Array(3 * n);
  const maxCell = new Int32Array(3 * n);
  const probability = new Float32Array(n);
  for (let k = 0; k < n; k++) {
    const c = json.cuboids[k];
    minCell[3 * k] = c.min_cell[0]; minCell[3 * k + 1] = c.min_cell[1]; minCell[3 * k + 2] = c.min_cell[2];
    maxCell[3 * k] = c.max_cell[0]; maxCell[3 * k + 1] = c.max_cell[1]; maxCell[3 * k + 2] = c.max_cell[2];
    probability[k] = c.probability;
  }
  return {
    level: json.level, x: json.x, y: json.y, z: json.z, version: json.version, epoch: json.epoch,
    resolution: json.resolution_m, count: n, minCell, maxCell, probability,
  };
}
