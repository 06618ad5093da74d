// ConeLOD web viewer — the .clod (versions 3 to 8) reader over HTTP Range requests.
//
// The JavaScript twin of vcg_ext/conelod/lod/lod_reader.cpp; the byte layout is
// vcg_ext/conelod/lod/lod_format.md. It reads only the byte ranges it needs: the header, the three
// container headers, the index blocks of the nodes it reaches, their records and their units'
// geometry blobs. Every chunk's and blob's CRC-32 is checked before its data is used, every count
// against the bytes that hold it, and what meshoptimizer's decoders return against the file's
// ranges. Errors name the problem as the desktop reader's do.
import { MeshoptDecoder } from './node_modules/meshoptimizer/meshopt_decoder.mjs';

export const VERSION = 9;  // the newest read (9: a typical distance per record; 8: range-coded positions; 7: deflated streams; 6: the compact index; 5: with attribute streams; 4, 3: geometry only)
const OLDEST_VERSION = 3;
const CHUNK = 24;
const HEADER_FIXED = 128;
const LEVEL_ENTRY = 32;
const INDEX_DATA = 16;
const IBLOCK_BASE = 16;
const INDEX_ENTRY = 8;  // versions 3 to 5: u32 recordEnd, u32 geometryEnd
const COMPACT_INDEX_VERSION = 6;  // varint entries, INDX data listing where each block starts
const DEFLATE_VERSION = 7;  // each geometry stream deflated when that is smaller
const CODED_POSITIONS_VERSION = 8;  // positions' residuals range-coded (lod_entropy.h)
const TYPICAL_VERSION = 9;  // each record above level 0: its creator group's typical distance after the error
const MAX_DEFLATE_RATIO = 1032;  // deflate's largest expansion (RFC 1951)
const RECORD_FIXED = 26;  // the smallest record (version 4 at level 0): CRC, cone, sphere
const GEOM_MIN = 5;
const MAX_LEVELS = 64;
const MAX_GRID_BITS = 30;
const EMPTY_CONE = 0xffff;
const CONE_UNIT = Math.PI / 65534;
const FLAG_WIDE = 1;
const HIER_PAGE = 8192;  // the records are read and kept in pages of this size
// Optional per-vertex streams after the ids (versions 5, 6), announced by the header's attributes field
// and the same geometry flag bits (lod_format.md, "Attributes"), in this order: a reader that
// meets a bit it does not know refuses the file by name. Each entry: { bit, name, stride } decoded
// by meshopt_decodeVertexBuffer into unit.attributes[name] (vertexCount x stride bytes): colours
// RGBA8, normals as octahedral u16 x 2 (decodeNormal), texture coordinates as u16 x 2 over the
// header's UV box (decodeTexCoords).
export const OPTIONAL_STREAMS = [
  { bit: 2, name: 'colors', stride: 4 },
  { bit: 4, name: 'normals', stride: 4 },
  { bit: 8, name: 'texCoords', stride: 4 },
];
const KNOWN_ATTRIBUTES = OPTIONAL_STREAMS.reduce((m, s) => m | s.bit, 0);
const HEADER_ATTRIBUTES = 8;  // versions 5, 6: u32 attributes (6: 0 allowed), u32 pad after the level entries
const HEADER_TEXCOORDS = 24;  // with bit 8: f32 uvMin[2], f32 uvMax[2], u64 textureOffset
const TEXTURE_FIXED = 16;     // TEXR data: u32 nameBytes, u32 mimeBytes, u64 imageBytes, then the three

// A unit's texture coordinate codes (u16 x 2 a vertex) as floats, as the C++ reader decodes them
// (DecodeLodTexCoord: float(min + q (max - min) / 65535), in double).
export function decodeTexCoords(codes, uvMin, uvMax) {
  const q = new DataView(codes.buffer, codes.byteOffset, codes.byteLength), n = codes.byteLength / 4;
  const out = new Float32Array(n * 2);
  const su = (uvMax[0] - uvMin[0]) / 65535, sv = (uvMax[1] - uvMin[1]) / 65535;
  for (let i = 0; i < n; ++i) {
    out[2 * i] = uvMin[0] + q.getUint16(i * 4, true) * su;
    out[2 * i + 1] = uvMin[1] + q.getUint16(i * 4 + 2, true) * sv;
  }
  return out;
}

// An octahedral normal code (two u16, lod_internal.h's DecodeConeAxis) into out[at..at+2].
export function decodeNormal(cu, cv, out, at) {
  let u = (cu / 65535) * 2 - 1, v = (cv / 65535) * 2 - 1;
  const z = 1 - Math.abs(u) - Math.abs(v);
  if (z < 0) {
    const pu = u, pv = v;
    u = (1 - Math.abs(pv)) * (pu >= 0 ? 1 : -1);
    v = (1 - Math.abs(pu)) * (pv >= 0 ? 1 : -1);
  }
  const n = Math.hypot(u, v, z);
  out[at] = u / n;
  out[at + 1] = v / n;
  out[at + 2] = z / n;
}
const KNOWN_FLAGS = OPTIONAL_STREAMS.reduce((m, s) => m | s.bit, FLAG_WIDE);

const fourcc = (s) => s.charCodeAt(0) | (s.charCodeAt(1) << 8) | (s.charCodeAt(2) << 16) | (s.charCodeAt(3) << 24);
const ID = { CLOD: fourcc('CLOD') >>> 0, HIER: fourcc('HIER') >>> 0, GEOS: fourcc('GEOS') >>> 0,
  INDX: fourcc('INDX') >>> 0, IBLK: fourcc('IBLK') >>> 0, TEXR: fourcc('TEXR') >>> 0 };

function chunkName(id) {
  let s = '';
  for (let i = 0; i < 4; ++i) {
    const c = (id >>> (8 * i)) & 0xff;
    if (c < 32 || c > 126) return '0x' + (id >>> 0).toString(16).padStart(8, '0');
    s += String.fromCharCode(c);
  }
  return s;
}

const CRC_TABLE = (() => {
  const t = new Uint32Array(256);
  for (let n = 0; n < 256; ++n) {
    let c = n;
    for (let k = 0; k < 8; ++k) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
    t[n] = c >>> 0;
  }
  return t;
})();

// CRC-32 (IEEE 802.3, zlib's crc32) of bytes[begin, end).
export function crc32(bytes, begin = 0, end = bytes.length) {
  let c = 0xffffffff;
  for (let i = begin; i < end; ++i) c = CRC_TABLE[(c ^ bytes[i]) & 0xff] ^ (c >>> 8);
  return (c ^ 0xffffffff) >>> 0;
}

export class ClodError extends Error {}

// Version 4: a record's parentError and parents from its group's first record, checked.
function inherit(n, head) {
  if (!head.groupHead || head.group !== n.group || head.level !== n.level)
    throw new ClodError(`corrupt record of node ${n.id}: a bad group reference`);
  n.parentError = head.parentError;
  n.parents = head.parents;
  if (!(n.parentError >= n.error)) throw new ClodError(`corrupt record of node ${n.id}: bad error bounds`);
}

// Little-endian fields and LEB128 varints of a byte array; `overrun` once a read passes the end.
class Decoder {
  constructor(bytes, begin = 0, end = bytes.length) {
    this.b = bytes;
    this.v = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    this.p = begin;
    this.end = end;
    this.overrun = false;
  }
  need(n) {
    if (this.overrun || n > this.end - this.p) {
      this.overrun = true;
      return false;
    }
    return true;
  }
  left() { return this.overrun ? 0 : this.end - this.p; }
  u8() { if (!this.need(1)) return 0; return this.b[this.p++]; }
  u16() { if (!this.need(2)) return 0; const x = this.v.getUint16(this.p, true); this.p += 2; return x; }
  u32() { if (!this.need(4)) return 0; const x = this.v.getUint32(this.p, true); this.p += 4; return x; }
  // u64 as a Number; values beyond 2^53 (never valid in a file this reader can fetch) give Infinity.
  u64() {
    if (!this.need(8)) return 0;
    const lo = this.v.getUint32(this.p, true), hi = this.v.getUint32(this.p + 4, true);
    this.p += 8;
    return hi >= 0x200000 ? Infinity : hi * 4294967296 + lo;
  }
  f32() { if (!this.need(4)) return 0; const x = this.v.getFloat32(this.p, true); this.p += 4; return x; }
  f64() { if (!this.need(8)) return 0; const x = this.v.getFloat64(this.p, true); this.p += 8; return x; }
  uv() {
    let x = 0, mul = 1;
    for (let i = 0; i < 10; ++i) {
      if (!this.need(1)) return 0;
      const c = this.b[this.p++];
      x += (c & 0x7f) * mul;
      if (!(c & 0x80)) return x > Number.MAX_SAFE_INTEGER ? Infinity : x;
      mul *= 128;
    }
    this.overrun = true;
    return 0;
  }
  take(n) {
    if (!(n >= 0) || !this.need(n)) return null;
    const r = this.b.subarray(this.p, this.p + n);
    this.p += n;
    return r;
  }
}

// Versions 3 to 5: a unit's grid coordinates (minus its corner) as stored, u16 x 4 or u32 x 3.
function storedGrid(raw, vc, wide) {
  const q = new Float64Array(vc * 3), rv = new DataView(raw.buffer, raw.byteOffset, raw.byteLength);
  for (let v = 0; v < vc; ++v)
    for (let c = 0; c < 3; ++c) q[v * 3 + c] = wide ? rv.getUint32(v * 12 + 4 * c, true) : rv.getUint16(v * 8 + 2 * c, true);
  return q;
}

// Version 8: lod_entropy.h's RangeDecoder (LZMA's range coder: 32-bit range, 11-bit adaptive
// probabilities), the same integer arithmetic. Never reads outside its bytes; `ok()` is false for
// a stream that is truncated, has bytes left over, does not start with 0 or holds a value the
// encoder cannot have written.
const RANGE_TOP = 2 ** 24;
class RangeDecoder {
  constructor(bytes) {
    this.b = bytes;
    this.p = 0;
    this.bad = bytes.length < 5 || bytes[0] !== 0;
    this.range = 0xffffffff;
    this.code = 0;
    for (let i = 0; i < 5; ++i) this.code = ((this.code << 8) | this.next()) >>> 0;
  }
  next() {
    if (this.p < this.b.length) return this.b[this.p++];
    this.bad = true;
    return 0;
  }
  normalize() {
    while (this.range < RANGE_TOP) {
      this.range = (this.range << 8) >>> 0;
      this.code = ((this.code << 8) | this.next()) >>> 0;
    }
  }
  // One adaptive bit; probs[i] is the probability of a 0 in 1/2048, updated by 1/16 of the way.
  bit(probs, i) {
    const p = probs[i], bound = (this.range >>> 11) * p;
    let bit;
    if (this.code < bound) {
      this.range = bound;
      probs[i] = p + ((2048 - p) >> 4);
      bit = 0;
    } else {
      this.code -= bound;
      this.range -= bound;
      probs[i] = p - (p >> 4);
      bit = 1;
    }
    this.normalize();
    return bit;
  }
  // `bits` (1..16) equiprobable bits.
  raw(bits) {
    this.range = this.range >>> bits;
    let v = Math.floor(this.code / this.range);
    if (v >= 2 ** bits) {
      this.bad = true;
      v %= 2 ** bits;
    }
    this.code -= v * this.range;
    this.normalize();
    return v;
  }
  ok() {
    return !this.bad && this.p === this.b.length;
  }
}

// Version 8: a unit's position residuals (lod_entropy.h's PositionResidualModel): per coordinate
// its zigzagged value's bit length n (six adaptive bits, a binary tree, in the context of the
// prediction's kind, the axis and for y and z the previous axis's n), then for n >= 2 the bit
// below the leading one (adaptive, per kind and n) and the n - 2 bits below (16 at a time).
// The stream starts with m (6 equiprobable bits), and the length trees start from a prior around
// it (reset).
const LENGTH_CONTEXTS = 1 + 2 * 34;
const KIND_OFFSET = [0, 2, 2, 4];
class PositionResidualModel {
  constructor() {
    this.length = new Uint16Array(4 * LENGTH_CONTEXTS * 64);
    this.high = new Uint16Array(4 * 34);
  }
  // Kind k's trees give n the weight 2^(24 - |n - m - offset_k|) (0 above 8 x width), each node's
  // probability of a 0 floor(2048 x left / (left + right)) within [32, 2016]; high bits one half.
  reset(m, width) {
    this.high.fill(1024);
    const w = new Array(64), tree = new Uint16Array(64);
    for (let k = 0; k < 4; ++k) {
      for (let n = 0; n < 64; ++n) {
        const d = Math.abs(n - m - KIND_OFFSET[k]);
        w[n] = n > 8 * width ? 0 : 2 ** (d < 24 ? 24 - d : 0);
      }
      for (let depth = 0; depth < 6; ++depth)
        for (let node = 1 << depth; node < 2 << depth; ++node) {
          const span = 64 >> depth, first = (node - (1 << depth)) * span;
          let l = 0, r = 0;
          for (let i = 0; i < span / 2; ++i) l += w[first + i];
          for (let i = span / 2; i < span; ++i) r += w[first + i];
          const p = l + r ? Math.floor((l * 2048) / (l + r)) : 1024;
          tree[node] = Math.min(2016, Math.max(32, p));
        }
      for (let c = 0; c < LENGTH_CONTEXTS; ++c) this.length.set(tree.subarray(1), (k * LENGTH_CONTEXTS + c) * 64 + 1);
    }
  }
  // The three residuals (mod 2^(8 x width)) of one vertex into r; false on a length above 8 x width
  // (at once, as the desktop reader: no model of a longer length exists).
  decode(rc, kind, r, width) {
    let previous = 0;
    for (let c = 0; c < 3; ++c) {
      const tree = 64 * (kind * LENGTH_CONTEXTS + (c === 0 ? 0 : 1 + (c - 1) * 34 + previous));
      let node = 1;
      for (let i = 0; i < 6; ++i) node = node * 2 + rc.bit(this.length, tree + node);
      const n = node - 64;
      if (n > 8 * width) return false;
      let z = n ? 1 : 0;
      if (n >= 2) {
        z = z * 2 + rc.bit(this.high, kind * 34 + n);
        for (let left = n - 2; left > 0;) {
          const take = Math.min(left, 16);
          left -= take;
          z = z * 2 ** take + rc.raw(take);
        }
      }
      // z >> 1 for z even, -(z >> 1) - 1 for z odd, modulo 2^(8 x width)
      const half = Math.floor(z / 2), modulus = 2 ** (8 * width);
      r[c] = z % 2 ? (modulus - 1 - half) % modulus : half % modulus;
      previous = n;
    }
    return true;
  }
}

// Versions 6 to 8: the residuals of the positions' predictions and the predictions walked over the
// faces as lod_internal.h's PositionPredictor walks them (the same order, the same integer
// arithmetic modulo 2^(8 x width)). Version 6, 7 (`raw`): the residuals stored as running signed
// bytes (meshoptimizer's vertex codec); version 8 (`coded`): range-coded, decoded as the walk
// visits the vertices, in the context of each prediction's kind (0 parallelogram, 1 midpoint, 2 a
// neighbour, 3 the vertex visited before). Null when the coded residuals do not decode.
function predictedGrid(raw, vc, wide, corners, fc, coded = null) {
  const width = wide ? 4 : 2, stride = wide ? 12 : 8, modulus = 2 ** (8 * width);
  const wrap = (x) => ((x % modulus) + modulus) % modulus;
  const r = new Float64Array(vc * 3);
  if (!coded)
    for (let v = 0; v < vc; ++v)
      for (let c = 0; c < 3; ++c) {
        let x = 0;
        for (let j = width - 1; j >= 0; --j) {
          const at = v * stride + width * c + j;
          const delta = (raw[at] - (v ? raw[at - stride] : 0)) & 0xff;
          x = x * 256 + (delta >= 128 ? delta - 256 : delta);
        }
        r[v * 3 + c] = wrap(x);
      }
  const rc = coded ? new RangeDecoder(coded) : null, model = coded ? new PositionResidualModel() : null;
  const rv = [0, 0, 0];
  let fine = true;
  if (rc) {
    const m = rc.raw(6);
    model.reset(m, width);
    fine = m <= 8 * width;
  }
  const q = new Float64Array(vc * 3), visited = new Uint8Array(vc), opposite = new Map();
  const last = [0, 0, 0], pred = [0, 0, 0];
  const visit = (v, kind) => {
    if (rc) {
      fine = model.decode(rc, kind, rv, width) && fine;
      for (let c = 0; c < 3; ++c) r[v * 3 + c] = rv[c];
    }
    for (let c = 0; c < 3; ++c) last[c] = q[v * 3 + c] = wrap(pred[c] + r[v * 3 + c]);
    visited[v] = 1;
  };
  for (let f = 0; f < fc; ++f) {
    const t = [corners[3 * f], corners[3 * f + 1], corners[3 * f + 2]];
    for (let k = 0; k < 3; ++k) {
      const v = t[k];
      if (visited[v]) continue;
      const a = t[(k + 1) % 3], b = t[(k + 2) % 3];
      let kind;
      if (visited[a] && visited[b]) {
        const o = opposite.get(b * vc + a);  // a neighbour's edge b -> a
        for (let c = 0; c < 3; ++c)
          pred[c] = o !== undefined ? q[a * 3 + c] + q[b * 3 + c] - q[o * 3 + c] : Math.floor((q[a * 3 + c] + q[b * 3 + c]) / 2);
        kind = o !== undefined ? 0 : 1;
      } else if (visited[a] || visited[b]) {
        const k2 = visited[a] ? a : b;
        for (let c = 0; c < 3; ++c) pred[c] = q[k2 * 3 + c];
        kind = 2;
      } else {
        for (let c = 0; c < 3; ++c) pred[c] = last[c];
        kind = 3;
      }
      visit(v, kind);
    }
    for (let k = 0; k < 3; ++k) {
      const key = t[k] * vc + t[(k + 1) % 3];
      if (!opposite.has(key)) opposite.set(key, t[(k + 2) % 3]);
    }
  }
  for (let v = 0; v < vc; ++v)
    if (!visited[v]) {
      for (let c = 0; c < 3; ++c) pred[c] = last[c];
      visit(v, 3);
    }
  return rc && !(fine && rc.ok()) ? null : q;
}

// meshoptimizer's bounds on its codecs' output (meshopt_encodeVertexBufferBound,
// meshopt_encodeIndexBufferBound, meshopt_encodeIndexSequenceBound), which the desktop reader
// takes from the library: a deflated stream may not claim more.
export function vertexBufferBound(count, size) {
  const block = Math.min(256, Math.floor(8192 / size) & ~15);
  const blocks = Math.ceil(count / block), header = Math.floor((block / 16 + 3) / 4);
  return 1 + blocks * size * (header + block) + Math.max(32, size);
}
function vertexBits(vertices) {
  let bits = 1;
  while (bits < 32 && vertices > 2 ** bits) ++bits;
  return bits;
}
// lod_entropy.h's PositionStreamBound: the most bytes version 8's coded positions take.
export function positionStreamBound(vertices) {
  return vertices * 34 + 16;
}
export function indexBufferBound(indices, vertices) {
  return 1 + Math.floor(indices / 3) * (2 + 3 * Math.floor((vertexBits(vertices) + 1 + 6) / 7)) + 16;
}
export function indexSequenceBound(indices, vertices) {
  return 1 + indices * Math.floor((vertexBits(vertices) + 1 + 1 + 6) / 7) + 4;
}

// Exactly `rawBytes` from one whole raw deflate stream (the browser's own inflater); null when it
// is not one, gives more or fewer bytes, or has bytes after its end (as the desktop reader, which
// requires zlib to take every byte). DecompressionStream may ignore bytes after the end (Node's
// does), so a stream that inflates whole is inflated again without its last byte, which must
// then fail: a deflate stream's end lies in its last byte.
async function inflateRaw(bytes, rawBytes) {
  const out = await inflateWhole(bytes, rawBytes);
  if (!out || bytes.length === 0) return null;
  return (await inflateWhole(bytes.subarray(0, bytes.length - 1), rawBytes)) ? null : out;
}
// What `bytes` inflate to when they hold one whole stream of exactly rawBytes bytes; else null.
async function inflateWhole(bytes, rawBytes) {
  const out = new Uint8Array(rawBytes);
  let n = 0;
  try {
    const ds = new DecompressionStream('deflate-raw');
    const w = ds.writable.getWriter();
    w.write(bytes).catch(() => {});
    w.close().catch(() => {});
    const r = ds.readable.getReader();
    for (;;) {
      const { done, value } = await r.read();
      if (done) break;
      if (value.length > rawBytes - n) {
        r.cancel().catch(() => {});
        return null;
      }
      out.set(value, n);
      n += value.length;
    }
  } catch (e) {
    return null;
  }
  return n === rawBytes ? out : null;
}

// Byte ranges of a URL, fetched with Range requests; counts what it receives.
export class RangeSource {
  constructor(url) {
    this.url = url;
    this.size = -1;
    this.bytesFetched = 0;
    this.requests = 0;
  }
  // Reads [offset, offset + n); the first read also learns the file's size (Content-Range).
  async read(offset, n, what) {
    if (this.size >= 0 && (offset > this.size || n > this.size - offset))
      throw new ClodError(`corrupt file: ${what} at offset ${offset} (${n} bytes) lies past the end of the file (${this.size} bytes)`);
    if (n === 0) return new Uint8Array(0);
    ++this.requests;
    let r;
    try {
      r = await fetch(this.url, { headers: { Range: `bytes=${offset}-${offset + n - 1}` } });
    } catch (e) {
      throw new ClodError(`cannot read ${this.url}: ${e.message}`);
    }
    if (r.status === 416 && this.size < 0) throw new ClodError(`truncated .clod file: ${this.url} is shorter than ${what}`);
    if (r.status !== 206 && r.status !== 200)
      throw new ClodError(`cannot read ${what} of ${this.url}: HTTP ${r.status} ${r.statusText}`);
    const body = new Uint8Array(await r.arrayBuffer());
    this.bytesFetched += body.length;
    let start = 0;
    if (r.status === 206) {
      const m = /^bytes (\d+)-(\d+)\/(\d+)$/.exec(r.headers.get('Content-Range') || '');
      if (!m || Number(m[1]) !== offset) throw new ClodError(`${this.url}: the server answered a range it was not asked for`);
      this.size = Number(m[3]);
    } else {  // the server ignored the range: the whole file came
      this.size = body.length;
      start = offset;
    }
    if (start + n > body.length) {
      if (this.size >= 0 && offset + n > this.size)
        throw new ClodError(`truncated .clod file: ${what} at offset ${offset} lies past the end of the file (${this.size} bytes)`);
      throw new ClodError(`${this.url}: short read of ${what}`);
    }
    return body.subarray(start, start + n);
  }
}

function chunkHeader(b, at = 0) {
  const d = new Decoder(b, at, at + CHUNK);
  const h = { id: d.u32(), crc: d.u32(), dataBytes: d.u64(), childBytes: d.u64() };
  h.totalBytes = CHUNK + h.dataBytes + h.childBytes;
  return h;
}

function blobCrcOk(b, begin, end) {
  return end - begin >= 4 && crc32(b, begin + 4, end) === new DataView(b.buffer, b.byteOffset).getUint32(begin, true);
}

function decodeConeAxis(o0, o1) {
  let u = (o0 / 65535) * 2 - 1, v = (o1 / 65535) * 2 - 1;
  const z = 1 - Math.abs(u) - Math.abs(v);
  if (z < 0) {
    const pu = u, pv = v;
    u = (1 - Math.abs(pv)) * (pu >= 0 ? 1 : -1);
    v = (1 - Math.abs(pu)) * (pv >= 0 ? 1 : -1);
  }
  const n = Math.sqrt(u * u + v * v + z * z);
  return [u / n, v / n, z / n];
}

// A .clod file read on demand: open() reads the header, the containers' headers, the index
// chunk and the roots (records and geometry). Node records: node(id) once loaded (roots, or by
// loadChildren / loadNode). Geometry: loadUnit(id) decodes the unit (one blob, one range) that
// holds node id and returns it; its nodes' faces are consecutive in its index buffer.
export class ClodReader {
  constructor(source) {
    this.src = source;
    this.nodes = new Map();        // id -> record
    this.indexBlocks = new Map();  // block number -> Promise of its entries
    this.recordReads = new Map();  // 'first:count' -> Promise of a read of records in flight
    this.hierPages = new Map();    // page of the records -> Promise of its bytes
    this.units = new Map();        // blob offset -> Promise of the decoded unit
    this.unitSizes = new Map();  // blob offset -> bytes of the decoded unit (once decoded)
    this.unitBytes = 0;          // their sum
  }

  static async open(url) {
    await MeshoptDecoder.ready;
    const r = new ClodReader(new RangeSource(url));
    await r._open();
    return r;
  }

  async _open() {
    const src = this.src;
    // The root chunk's header and the header's data (at most 128 + 64 x 32 bytes) in one range.
    let head;
    try {
      head = await src.read(0, CHUNK + HEADER_FIXED + MAX_LEVELS * LEVEL_ENTRY + HEADER_ATTRIBUTES + HEADER_TEXCOORDS,
        'the file header');
    } catch (e) {
      if (src.size < 0 || src.size >= CHUNK + HEADER_FIXED + MAX_LEVELS * LEVEL_ENTRY + HEADER_ATTRIBUTES + HEADER_TEXCOORDS)
        throw e;
      head = await src.read(0, src.size, 'the file header');
    }
    const trunc = 'truncated .clod file: ';
    if (head.length < CHUNK) throw new ClodError(trunc + `${src.size} bytes, shorter than a chunk header`);
    const h = chunkHeader(head);
    if (h.id !== ID.CLOD) throw new ClodError(`not a .clod file (wrong magic: ${chunkName(h.id)}, expected CLOD)`);
    if (head.length < CHUNK + 4) throw new ClodError(trunc + 'no version field');
    const version = new Decoder(head, CHUNK).u32();
    if (version === 1)
      throw new ClodError(`this is a .clod version 1 file (written by an older ConeLOD, whose cuts could have cracks): rebuild it with conelod lod build (this reader reads versions 3 to ${VERSION})`);
    if (version === 2)
      throw new ClodError(`this is a .clod version 2 file (uncompressed, written by an older ConeLOD): rebuild it with conelod lod build (this reader reads versions 3 to ${VERSION})`);
    if (version < OLDEST_VERSION || version > VERSION)
      throw new ClodError(`unsupported .clod version ${version} (this reader reads versions 3 to ${VERSION})`);
    const tail = version >= 5 ? HEADER_ATTRIBUTES : 0;
    // With texture coordinates (bit 8) the UV box and the texture's offset follow (checked below).
    const extra = version >= 5 && h.dataBytes > HEADER_FIXED + tail &&
      (h.dataBytes - HEADER_FIXED - tail) % LEVEL_ENTRY === HEADER_TEXCOORDS ? HEADER_TEXCOORDS : 0;
    if (h.dataBytes < HEADER_FIXED + LEVEL_ENTRY + tail + extra ||
        h.dataBytes > HEADER_FIXED + MAX_LEVELS * LEVEL_ENTRY + tail + extra ||
        (h.dataBytes - HEADER_FIXED - tail - extra) % LEVEL_ENTRY !== 0 || !Number.isFinite(h.childBytes))
      throw new ClodError('corrupt chunk size in the file header');
    if (h.totalBytes > src.size) throw new ClodError(trunc + `the file has ${src.size} bytes, its header says ${h.totalBytes}`);
    if (h.totalBytes < src.size)
      throw new ClodError(`corrupt chunk size in the file header: it says ${h.totalBytes} bytes, the file has ${src.size}`);
    if (crc32(head, CHUNK, CHUNK + h.dataBytes) !== h.crc) throw new ClodError('checksum mismatch in the file header');
    const d = new Decoder(head, CHUNK, CHUNK + h.dataBytes);
    const info = (this.info = { version: d.u32() });
    const levelCount = d.u32();
    info.inputVertices = d.u64();
    info.inputFaces = d.u64();
    info.nodeCount = d.u64();
    info.globalVertices = d.u64();
    const b = [];
    for (let i = 0; i < 6; ++i) b.push(d.f32());
    info.boxMin = b.slice(0, 3);
    info.boxMax = b.slice(3);
    const bad = 'corrupt file header: ';
    for (let j = 0; j < 3; ++j)
      if (!Number.isFinite(b[j]) || !Number.isFinite(b[j + 3]) || b[j] > b[j + 3])
        throw new ClodError(bad + 'its bounding box is not finite or is inverted');
    this.hierOffset = d.u64();
    this.geosOffset = d.u64();
    this.indexOffset = d.u64();
    const grid = (info.grid = { origin: [d.f64(), d.f64(), d.f64()], step: d.f64(), bits: d.u32() });
    this.indexBlock = d.u32();
    if (grid.bits < 1 || grid.bits > MAX_GRID_BITS || !(grid.step > 0) || !Number.isFinite(grid.step))
      throw new ClodError(bad + 'bad quantization grid');
    for (let c = 0; c < 3; ++c) {
      const top = grid.origin[c] + (2 ** grid.bits - 1) * grid.step;
      if (!Number.isFinite(Math.fround(grid.origin[c])) || !Number.isFinite(Math.fround(top)))
        throw new ClodError(bad + 'bad quantization grid');
    }
    if (levelCount < 1 || levelCount > MAX_LEVELS || h.dataBytes !== HEADER_FIXED + levelCount * LEVEL_ENTRY + tail + extra)
      throw new ClodError(bad + `bad level count ${levelCount}`);
    if (this.indexBlock === 0 || this.indexBlock > 1 << 20) throw new ClodError(bad + 'bad block size');
    const levels = (this.levels = []);
    for (let k = 0; k < levelCount; ++k) {
      levels.push({ faces: d.u64(), nodes: d.u64(), firstId: d.u64(), error: d.f32() });
      d.u32();
    }
    this.attributeMask = 0;
    if (tail) {
      this.attributeMask = d.u32();
      d.u32();
      if ((this.attributeMask === 0 && version < COMPACT_INDEX_VERSION) || this.attributeMask & ~KNOWN_ATTRIBUTES)
        throw new ClodError(bad + `unknown attribute streams (${this.attributeMask}; this reader knows colour 2, normals 4 and texture coordinates 8)`);
    }
    info.colors = (this.attributeMask & 2) !== 0;
    info.normals = (this.attributeMask & 4) !== 0;
    info.texCoords = (this.attributeMask & 8) !== 0;
    if (info.texCoords !== (extra !== 0)) throw new ClodError(bad + 'its size does not match its attribute streams');
    this.textureOffset = 0;
    info.textureBytes = 0;
    if (extra) {
      info.uvMin = [d.f32(), d.f32()];
      info.uvMax = [d.f32(), d.f32()];
      this.textureOffset = d.u64();
      for (let c = 0; c < 2; ++c)
        if (!Number.isFinite(info.uvMin[c]) || !Number.isFinite(info.uvMax[c]) || info.uvMin[c] > info.uvMax[c])
          throw new ClodError(bad + 'its UV box is not finite or is inverted');
    }
    let id = 0;
    for (let k = levelCount - 1; k >= 0; --k) {
      const L = levels[k];
      if (L.firstId !== id || L.nodes === 0 || L.nodes > src.size / RECORD_FIXED)
        throw new ClodError(bad + `bad node count of level ${k}`);
      id += L.nodes;
      if (L.faces > src.size) throw new ClodError(bad + `counts of level ${k} larger than the file`);
    }
    if (id !== info.nodeCount || info.nodeCount >= 0xffffffff) throw new ClodError(bad + 'node counts do not add up');
    if (levels[0].faces !== info.inputFaces || info.globalVertices >= 0xffffffff)
      throw new ClodError(bad + 'level 0 does not match the input');
    for (const o of [this.hierOffset, this.geosOffset, this.indexOffset])
      if (!(o < src.size)) throw new ClodError(bad + 'an offset points past the end of the file');
    info.levels = levelCount;
    info.fileBytes = src.size;
    info.levelFaces = levels.map((L) => L.faces);
    if (this.textureOffset) {  // the texture chunk's header, name and MIME type (the image: loadTexture)
      if (!(this.textureOffset < src.size) || src.size - this.textureOffset < CHUNK + TEXTURE_FIXED)
        throw new ClodError(bad + "the texture's offset points past the end of the file");
      const t = await src.read(this.textureOffset, Math.min(CHUNK + TEXTURE_FIXED + 2 * 255, src.size - this.textureOffset),
        'the texture chunk');
      const th = chunkHeader(t);
      if (th.id !== ID.TEXR) throw new ClodError(`corrupt file: expected a TEXR chunk (the texture), found ${chunkName(th.id)}`);
      const dt = new Decoder(t, CHUNK, CHUNK + TEXTURE_FIXED);
      const nameBytes = dt.u32(), mimeBytes = dt.u32(), imageBytes = dt.u64();
      if (th.childBytes !== 0 || !(th.dataBytes <= src.size - this.textureOffset - CHUNK) || nameBytes > 255 ||
          mimeBytes > 255 || !(imageBytes > 0) || th.dataBytes !== TEXTURE_FIXED + nameBytes + mimeBytes + imageBytes ||
          t.length < CHUNK + TEXTURE_FIXED + nameBytes + mimeBytes)
        throw new ClodError('corrupt chunk size in the texture chunk');
      const text = (a, b) => String.fromCharCode(...t.subarray(a, b));
      info.textureName = new TextDecoder().decode(t.subarray(CHUNK + TEXTURE_FIXED, CHUNK + TEXTURE_FIXED + nameBytes));
      info.textureMime = text(CHUNK + TEXTURE_FIXED + nameBytes, CHUNK + TEXTURE_FIXED + nameBytes + mimeBytes);
      info.textureBytes = imageBytes;
      this.textureCrc = th.crc;
      this.textureData = [CHUNK + TEXTURE_FIXED + nameBytes + mimeBytes, th.dataBytes];
      if (!info.textureName || /[\u0000-\u001f\u007f/\\:]/.test(info.textureName) || !info.textureMime ||
          /[^\u0020-\u007e]/.test(info.textureMime))
        throw new ClodError('corrupt texture chunk: a bad name or MIME type');
    }
    // The containers and the index chunk (with the roots' index block, block 0: ids are coarsest first).
    const [hier, geos] = await Promise.all([
      src.read(this.hierOffset, CHUNK, 'the hierarchy chunk'),
      src.read(this.geosOffset, CHUNK, 'the geometry chunk'),
      this._readIndexChunk(),
    ]);
    [this.hierBegin, this.hierEnd] = this._container(hier, this.hierOffset, ID.HIER, 'the hierarchy chunk');
    [this.geosBegin, this.geosEnd] = this._container(geos, this.geosOffset, ID.GEOS, 'the geometry chunk');
    const top = levelCount - 1;
    await this.loadRecords(levels[top].firstId, levels[top].nodes);
    this.roots = [];
    for (let r = 0; r < levels[top].nodes; ++r) this.roots.push(r);
    await this.loadUnit(0);
  }

  // The texture image stored in the file (its TEXR chunk), checked against the chunk's CRC:
  // { name, mime, bytes } (a Uint8Array), or null when the file has none.
  async loadTexture() {
    if (!this.textureOffset) return null;
    const [begin, dataBytes] = this.textureData;
    const b = await this.src.read(this.textureOffset, CHUNK + dataBytes, 'the texture chunk');
    if (crc32(b, CHUNK, CHUNK + dataBytes) !== this.textureCrc) throw new ClodError('checksum mismatch in the texture chunk');
    return { name: this.info.textureName, mime: this.info.textureMime, bytes: b.subarray(begin, CHUNK + dataBytes) };
  }

  _container(b, offset, id, what) {
    const h = chunkHeader(b);
    if (h.id !== id) throw new ClodError(`corrupt file: expected a ${chunkName(id)} chunk (${what}), found ${chunkName(h.id)}`);
    if (h.crc !== 0 || h.childBytes !== 0 || !(h.dataBytes <= this.src.size - offset - CHUNK))
      throw new ClodError(`corrupt chunk size in ${what}`);
    return [offset + CHUNK, offset + CHUNK + h.dataBytes];
  }

  async _readIndexChunk() {
    const n = this.info.nodeCount, blocks = Math.ceil(n / this.indexBlock);
    const compact = this.info.version >= COMPACT_INDEX_VERSION;
    const dataBytes = INDEX_DATA + (compact ? 4 * blocks : 0);  // version 6: u32 start per block
    const b = await this.src.read(this.indexOffset, CHUNK + dataBytes, 'the index chunk');
    const h = chunkHeader(b);
    if (h.id !== ID.INDX) throw new ClodError(`corrupt file: expected a INDX chunk (the index chunk), found ${chunkName(h.id)}`);
    if (h.dataBytes !== dataBytes) throw new ClodError('corrupt chunk size in the index chunk');
    if (crc32(b, CHUNK, CHUNK + dataBytes) !== h.crc) throw new ClodError('checksum mismatch in the index chunk');
    const d = new Decoder(b, CHUNK);
    const entries = d.u64(), block = d.u32();
    d.u32();
    if (entries !== n || block !== this.indexBlock ||
        !(compact ? h.childBytes >= blocks * (CHUNK + IBLOCK_BASE) + n
                  : h.childBytes === blocks * (CHUNK + IBLOCK_BASE) + n * INDEX_ENTRY) ||
        !(h.totalBytes <= this.src.size - this.indexOffset))
      throw new ClodError('corrupt chunk size in the index chunk');
    if (!compact) return;
    this.indexChildBytes = h.childBytes;
    this.blockStarts = [];
    const fullBlock = CHUNK + IBLOCK_BASE + this.indexBlock;  // every block before the last is full
    for (let k = 0; k < blocks; ++k) {
      const start = d.u32();
      const least = CHUNK + IBLOCK_BASE + Math.min(this.indexBlock, n - k * this.indexBlock);
      if ((k === 0 && start !== 0) || (k > 0 && start < this.blockStarts[k - 1] + fullBlock) ||
          start > h.childBytes || h.childBytes - start < least)
        throw new ClodError(`corrupt index chunk: bad start of index block ${k}`);
      this.blockStarts.push(start);
    }
  }

  // Index block `blk`: per entry { record, recordBytes, geometry, geometryBytes } (cached).
  _indexBlock(blk) {
    let p = this.indexBlocks.get(blk);
    if (!p) {
      p = this._readIndexBlock(blk);
      this.indexBlocks.set(blk, p);
      p.catch(() => this.indexBlocks.delete(blk));
    }
    return p;
  }

  async _readIndexBlock(blk) {
    const entries = Math.min(this.indexBlock, this.info.nodeCount - blk * this.indexBlock);
    if (this.info.version >= COMPACT_INDEX_VERSION) return this._readCompactIndexBlock(blk, entries);
    const bytes = CHUNK + IBLOCK_BASE + entries * INDEX_ENTRY;
    const blockBytes = CHUNK + IBLOCK_BASE + this.indexBlock * INDEX_ENTRY;
    const b = await this.src.read(this.indexOffset + CHUNK + INDEX_DATA + blk * blockBytes, bytes, 'index block');
    const h = chunkHeader(b);
    if (h.id !== ID.IBLK) throw new ClodError(`corrupt file: expected a IBLK chunk (index block), found ${chunkName(h.id)}`);
    if (h.dataBytes !== bytes - CHUNK || h.childBytes !== 0) throw new ClodError('corrupt chunk size in index block');
    if (crc32(b, CHUNK, bytes) !== h.crc) throw new ClodError('checksum mismatch in index block');
    const d = new Decoder(b, CHUNK);
    let record = d.u64(), geometry = d.u64();
    const bad = `corrupt index block ${blk}: `;
    if (record < this.hierBegin || record > this.hierEnd || geometry < this.geosBegin || geometry > this.geosEnd)
      throw new ClodError(bad + 'it points outside the records or the geometry');
    const recordBase = record, geometryBase = geometry;
    let lastEnd = -1;
    const out = [];
    for (let i = 0; i < entries; ++i) {
      const recordEnd = recordBase + d.u32(), geometryEnd = geometryBase + d.u32();
      if (geometryEnd !== lastEnd && lastEnd !== -1) geometry = lastEnd;
      if (recordEnd < record || recordEnd > this.hierEnd || geometryEnd <= geometry || geometryEnd > this.geosEnd)
        throw new ClodError(bad + 'an entry points outside the records or the geometry');
      out.push({ record, recordBytes: recordEnd - record, geometry, geometryBytes: geometryEnd - geometry });
      record = recordEnd;
      lastEnd = geometryEnd;
    }
    return out;
  }

  // Version 6: the block where the INDX data says; per entry a varint (record size - RECORD_FIXED)
  // x 2 + 1 when the entry starts a new geometry blob, whose size follows, else (never the
  // block's first) the previous entry's blob.
  async _readCompactIndexBlock(blk, entries) {
    const starts = this.blockStarts;
    const start = starts[blk], end = blk + 1 < starts.length ? starts[blk + 1] : this.indexChildBytes;
    const bytes = end - start;
    const b = await this.src.read(this.indexOffset + CHUNK + INDEX_DATA + 4 * starts.length + start, bytes, 'index block');
    const h = chunkHeader(b);
    if (h.id !== ID.IBLK) throw new ClodError(`corrupt file: expected a IBLK chunk (index block), found ${chunkName(h.id)}`);
    if (h.dataBytes !== bytes - CHUNK || h.childBytes !== 0) throw new ClodError('corrupt chunk size in index block');
    if (crc32(b, CHUNK, bytes) !== h.crc) throw new ClodError('checksum mismatch in index block');
    const d = new Decoder(b, CHUNK);
    let record = d.u64(), geometry = d.u64(), geometryEnd = geometry;
    const bad = `corrupt index block ${blk}: `;
    if (record < this.hierBegin || record > this.hierEnd || geometry < this.geosBegin || geometry > this.geosEnd)
      throw new ClodError(bad + 'it points outside the records or the geometry');
    const out = [];
    for (let i = 0; i < entries; ++i) {
      const code = d.uv();
      const newBlob = code % 2 === 1;
      const recordBytes = Math.floor(code / 2) + RECORD_FIXED;
      if (!newBlob && i === 0) throw new ClodError(bad + 'its first entry has no geometry');
      if (newBlob) {
        const n = d.uv();
        if (!(n <= this.geosEnd - geometryEnd)) throw new ClodError(bad + 'an entry points outside the records or the geometry');
        geometry = geometryEnd;
        geometryEnd += n;
      }
      if (d.overrun || !(recordBytes <= this.hierEnd - record))
        throw new ClodError(bad + 'an entry points outside the records or the geometry');
      out.push({ record, recordBytes, geometry, geometryBytes: geometryEnd - geometry });
      record += recordBytes;
    }
    if (d.left() !== 0) throw new ClodError(bad + 'it does not end with its last entry');
    return out;
  }

  async _entries(first, count) {
    const out = [];
    for (let i = first; i < first + count; ++i) {
      const blk = Math.floor(i / this.indexBlock);
      const e = (await this._indexBlock(blk))[i - blk * this.indexBlock];
      if (e.recordBytes < RECORD_FIXED || e.geometryBytes < GEOM_MIN)
        throw new ClodError(`corrupt index: the entry of node ${i} is too small`);
      out.push(e);
    }
    return out;
  }

  levelOf(id) {
    for (let k = 0; k < this.levels.length; ++k)
      if (id >= this.levels[k].firstId && id < this.levels[k].firstId + this.levels[k].nodes) return k;
    return 0;
  }

  hasNode(id) { return this.nodes.has(id); }
  node(id) { return this.nodes.get(id); }

  // Bytes [offset, offset + n) of the records (HIER), read in pages of HIER_PAGE bytes that are
  // kept: a level's records are consecutive in id order, and a group's clusters, their children
  // and their parents have neighbouring ids, so one page serves many expansions (the demand for
  // a group's missing clusters reads records one by one).
  async _hier(offset, n) {
    if (offset < this.hierBegin || n > this.hierEnd - offset)
      throw new ClodError(`corrupt file: node records at offset ${offset} (${n} bytes) lie outside the hierarchy chunk`);
    const first = Math.floor((offset - this.hierBegin) / HIER_PAGE);
    const last = Math.floor((offset + n - 1 - this.hierBegin) / HIER_PAGE);
    const pending = [];
    for (let p = first; p <= last;) {
      if (this.hierPages.has(p)) {
        ++p;
        continue;
      }
      let q = p;  // a run of missing pages: one range
      while (q + 1 <= last && !this.hierPages.has(q + 1)) ++q;
      const begin = this.hierBegin + p * HIER_PAGE, end = Math.min(this.hierEnd, this.hierBegin + (q + 1) * HIER_PAGE);
      const read = this.src.read(begin, end - begin, 'node records'), runStart = p;
      for (let k = p; k <= q; ++k) {
        const at = (k - runStart) * HIER_PAGE;
        const page = read.then((b) => b.subarray(at, Math.min(b.length, at + HIER_PAGE)));
        this.hierPages.set(k, page);
        page.catch(() => this.hierPages.delete(k));
      }
      p = q + 1;
    }
    for (let p = first; p <= last; ++p) pending.push(this.hierPages.get(p));
    const pages = await Promise.all(pending);
    const out = new Uint8Array(n);
    for (let p = first, at = 0; p <= last; ++p) {
      const pageBegin = this.hierBegin + p * HIER_PAGE;
      const from = Math.max(offset, pageBegin) - pageBegin, to = Math.min(offset + n, pageBegin + pages[p - first].length) - pageBegin;
      out.set(pages[p - first].subarray(from, to), at);
      at += to - from;
    }
    return out;
  }

  // Records of nodes [first, first + count) (consecutive in the file): one range, read once
  // however many callers ask for it meanwhile.
  loadRecords(first, count, headOnly = false) {
    const key = first + ':' + count + (headOnly ? ':h' : '');
    let p = this.recordReads.get(key);
    if (!p) {
      p = this._loadRecords(first, count, headOnly);
      this.recordReads.set(key, p);
      p.finally(() => this.recordReads.delete(key)).catch(() => {});
    }
    return p;
  }

  // Version 4: a record that names its group's first record takes parentError and parents from it
  // (read here if not loaded; headOnly: this is such a read, and the record must be its group's first).
  async _loadRecords(first, count, headOnly = false) {
    if (count === 0) return;
    const entries = await this._entries(first, count);
    let span = 0;
    for (let i = 0; i < count; ++i) {
      if (entries[i].record !== entries[0].record + span)
        throw new ClodError(`corrupt index: node records ${first}..${first + count - 1} are not consecutive`);
      span += entries[i].recordBytes;
    }
    const buf = await this._hier(entries[0].record, span);
    const level = this.levelOf(first), levels = this.levels, top = level + 1 === levels.length;
    const v4 = this.info.version >= 4, pending = [];  // [node, head id]: the head not loaded yet
    let at = 0;
    for (let i = 0; i < count; ++i) {
      const id = first + i, bytes = entries[i].recordBytes;
      const bad = `corrupt record of node ${id}: `;
      const begin = at;
      at += bytes;
      if (this.nodes.has(id)) continue;
      if (!blobCrcOk(buf, begin, begin + bytes)) throw new ClodError(`checksum mismatch in the record of a node ${id}`);
      const d = new Decoder(buf, begin + 4, begin + bytes);
      const n = { id, level };
      const o0 = d.u16(), o1 = d.u16(), angle = d.u16();
      n.coneEmpty = angle === EMPTY_CONE;
      n.coneAxis = n.coneEmpty ? [0, 0, 1] : decodeConeAxis(o0, o1);
      n.coneHalfAngle = n.coneEmpty ? -1 : Math.min(Math.PI, angle * CONE_UNIT);
      n.center = [d.f32(), d.f32(), d.f32()];
      n.radius = d.f32();
      n.error = v4 && level === 0 ? 0 : d.f32();
      // (the typical distance orders the desktop refinement by error in model units; checked, kept)
      n.typical = this.info.version >= TYPICAL_VERSION ? (level === 0 ? 0 : d.f32()) : -1;
      if (!v4) n.parentError = d.f32();
      const group = d.uv(), faces = d.uv(), vertices = d.uv(), children = d.uv();
      if (d.overrun || group > 0xffffffff || faces > 0xffffffff || vertices > 0xffffffff)
        throw new ClodError(bad + 'a count out of range');
      n.group = group ? group - 1 : -1;
      n.faceCount = faces;
      n.vertexCount = vertices;
      if (top !== (group === 0)) throw new ClodError(bad + (top ? 'a root with a group' : 'no group'));
      if (level === 0 ? children !== 0 : children === 0 || children > levels[level - 1].nodes)
        throw new ClodError(bad + 'children out of range');
      n.children = [];
      if (children) {
        const firstChild = d.uv();
        if (d.overrun || firstChild > levels[level - 1].nodes - children) throw new ClodError(bad + 'child out of range');
        for (let c = 0; c < children; ++c) n.children.push(levels[level - 1].firstId + firstChild + c);
      }
      const readIds = (lvl) => {
        const cnt = d.uv();
        if (d.overrun || cnt > d.left() || (cnt && lvl >= levels.length)) return null;
        const out = [];
        if (!cnt) return out;
        const end = levels[lvl].firstId + levels[lvl].nodes;
        let next = levels[lvl].firstId;
        for (let j = 0; j < cnt; ++j) {
          const gap = d.uv();
          if (d.overrun || gap >= end - next) return null;
          out.push(next + gap);
          next += gap + 1;
        }
        return out;
      };
      n.siblings = readIds(level);
      if (!n.siblings || !n.siblings.includes(id)) throw new ClodError(bad + 'sibling out of range');
      if (level === 0 && n.siblings.length !== 1) throw new ClodError(bad + 'siblings at level 0');
      const back = v4 ? d.uv() : 0;  // how many ids back its group's first record is
      if (d.overrun || back > id - levels[level].firstId || (back && top) || (back && headOnly))
        throw new ClodError(bad + 'a bad group reference');
      n.groupHead = back === 0;
      if (back === 0) {
        if (v4) n.parentError = d.f32();
        n.parents = readIds(level + 1);
        if (!n.parents) throw new ClodError(bad + 'parent out of range');
        if (top !== (n.parents.length === 0)) throw new ClodError(bad + (top ? 'a root with parents' : 'no parents'));
      }
      if (d.left() !== 0) throw new ClodError(bad + 'its size does not match its contents');
      if (![...n.center, n.radius].every(Number.isFinite) || !(n.radius >= 0))
        throw new ClodError(bad + 'non-finite or negative cone or sphere');
      if (!(n.error >= 0) || !Number.isFinite(n.error) || (level === 0 && n.error !== 0) ||
          (this.info.version >= TYPICAL_VERSION && !(n.typical >= 0 && n.typical <= n.error)))
        throw new ClodError(bad + 'bad error bounds');
      if (n.groupHead && (!(n.parentError >= n.error) || (top ? n.parentError !== Infinity : !Number.isFinite(n.parentError))))
        throw new ClodError(bad + 'bad error bounds');
      if (n.vertexCount > 3 * n.faceCount || n.faceCount > levels[level].faces || n.faceCount === 0 || n.vertexCount === 0)
        throw new ClodError(bad + 'impossible face or vertex count');
      n.geometry = entries[i].geometry;
      n.geometryBytes = entries[i].geometryBytes;
      if (n.geometryBytes < GEOM_MIN + 17 + n.faceCount) throw new ClodError(bad + 'its geometry is too small for its face count');
      if (!n.groupHead) {
        const head = id - back;
        if (!this.nodes.has(head)) {
          pending.push([n, head]);
          continue;
        }
        inherit(n, this.nodes.get(head));
      }
      this.nodes.set(id, n);
    }
    // (A group's first record read here stays loaded: another caller may be waiting on it.)
    for (const [n, head] of pending) {
      if (!this.nodes.has(head)) await this.loadRecords(head, 1, true);
      inherit(n, this.nodes.get(head));
      if (!this.nodes.has(n.id)) this.nodes.set(n.id, n);
    }
  }

  async loadNode(id) {
    if (!(id >= 0 && id < this.info.nodeCount)) throw new ClodError(`no node ${id}`);
    if (!this.nodes.has(id)) await this.loadRecords(id, 1);
  }

  // The records of id's children (one group's clusters: one range), checked to be that group.
  async loadChildren(id) {
    const p = this.nodes.get(id), ch = p.children;
    if (ch.length && !ch.every((c) => this.nodes.has(c))) await this.loadRecords(ch[0], ch.length);
    for (const c of ch) {
      const n = this.nodes.get(c);
      if (n.parentError !== p.error || n.group !== this.nodes.get(ch[0]).group)
        throw new ClodError(`corrupt record of node ${c}: it does not belong to the group its parent ${id} was made from`);
    }
  }

  // The unit holding node id (whose record is loaded): decoded once, shared by its nodes.
  loadUnit(id) {
    const n = this.nodes.get(id);
    let p = this.units.get(n.geometry);
    if (!p) {
      p = this._decodeUnit(n.geometry, n.geometryBytes, id);
      this.units.set(n.geometry, p);
      p.catch(() => this.units.delete(n.geometry));
    }
    return p;
  }

  // Drops a decoded unit (its nodes left the cut); it is read again if needed.
  dropUnit(offset) {
    this.units.delete(offset);
    this.unitBytes -= this.unitSizes.get(offset) || 0;
    this.unitSizes.delete(offset);
  }

  // A geometry stream's codec bytes (lod_reader.cpp's TakeStream): its size and bytes (versions 3
  // to 6); version 7: `uv code` (stored bytes x 2 + deflated), then when deflated `uv rawBytes`
  // (at most `bound` and what deflate can give) and the deflated bytes, inflated. Null when the
  // stream is truncated, out of bounds or does not inflate to exactly rawBytes.
  async _stream(d, bound) {
    const code = d.uv();
    const v7 = this.info.version >= DEFLATE_VERSION, deflated = v7 && code % 2 === 1;
    const stored = v7 ? Math.floor(code / 2) : code;
    const raw = deflated ? d.uv() : stored;
    if (d.overrun || stored > d.left()) return null;
    const p = d.take(stored);
    if (!deflated) return p;
    if (raw === 0 || raw > bound || raw > stored * MAX_DEFLATE_RATIO + 64) return null;
    return inflateRaw(p, raw);
  }

  async _decodeUnit(offset, bytes, id) {
    const buf = await this.src.read(offset, bytes, 'node geometry');
    const bad = `corrupt geometry of node ${id}: `;
    if (!blobCrcOk(buf, 0, bytes)) throw new ClodError(`checksum mismatch in the geometry of a node ${id}`);
    const d = new Decoder(buf, 4, bytes);
    const flags = d.u8();
    if (d.overrun || flags & ~KNOWN_FLAGS)
      throw new ClodError(bad + `unknown flags 0x${flags.toString(16)} (written by a newer ConeLOD? this reader knows 0x${KNOWN_FLAGS.toString(16)})`);
    if ((flags & KNOWN_ATTRIBUTES) !== this.attributeMask) throw new ClodError(bad + "its attribute streams are not the file's");
    const wide = (flags & FLAG_WIDE) !== 0;
    const first = d.uv(), count = d.uv();
    const L = this.levels[this.levelOf(id)];
    if (d.overrun || first < L.firstId || count === 0 || count > L.nodes || first - L.firstId > L.nodes - count || count > d.left())
      throw new ClodError(bad + 'its geometry blob names other nodes');
    const faceStart = new Array(count + 1).fill(0);
    const maxFaces = this.info.version >= DEFLATE_VERSION ? bytes * MAX_DEFLATE_RATIO : bytes;
    for (let i = 0; i < count; ++i) {
      const fc = d.uv();
      if (d.overrun || fc === 0 || fc > maxFaces) throw new ClodError(bad + 'a face count out of range');
      faceStart[i + 1] = faceStart[i] + fc;
      if (faceStart[i + 1] > maxFaces) throw new ClodError(bad + 'more faces than its blob can hold');
    }
    const fc = faceStart[count];
    const vc = d.uv();
    if (d.overrun || vc === 0 || vc > 3 * fc) throw new ClodError(bad + 'impossible vertex count');
    const grid = this.info.grid, cells = 2 ** grid.bits;
    const qmin = [d.uv(), d.uv(), d.uv()];
    const firstNew = d.uv();
    if (d.overrun || qmin.some((q) => q >= cells) || firstNew > this.info.globalVertices)
      throw new ClodError(bad + 'its grid corner or first vertex id is out of range');
    const stride = wide ? 12 : 8;
    // The positions' and triangles' streams first (version 7: inflated), the faces checked against
    // the triangles' codec bytes (at least a byte a face), then decoded, as the desktop reader.
    const coded = this.info.version >= CODED_POSITIONS_VERSION;
    let p = await this._stream(d, coded ? positionStreamBound(vc) : vertexBufferBound(vc, stride));
    if (!p) throw new ClodError(bad + 'its positions do not decode');
    const pt = await this._stream(d, indexBufferBound(fc * 3, vc));
    if (!pt) throw new ClodError(bad + 'its triangles do not decode');
    if (fc > pt.length) throw new ClodError(bad + 'more faces than its triangles can hold');
    const raw = coded ? null : new Uint8Array(vc * stride);
    try {
      if (!coded) MeshoptDecoder.decodeVertexBuffer(raw, vc, stride, p);
    } catch (e) {
      throw new ClodError(bad + 'its positions do not decode');
    }
    const corners = new Uint32Array(fc * 3);
    try {
      MeshoptDecoder.decodeIndexBuffer(new Uint8Array(corners.buffer), fc * 3, 4, pt);
    } catch (e) {
      throw new ClodError(bad + 'its triangles do not decode');
    }
    for (let i = 0; i < corners.length; ++i) if (corners[i] >= vc) throw new ClodError(bad + 'face index out of range');
    const q = this.info.version >= COMPACT_INDEX_VERSION ? predictedGrid(raw, vc, wide, corners, fc, coded ? p : null) : storedGrid(raw, vc, wide);
    if (!q) throw new ClodError(bad + 'its positions do not decode');
    const positions = new Float32Array(vc * 3);
    for (let v = 0; v < vc; ++v)
      for (let c = 0; c < 3; ++c) {
        const off = q[v * 3 + c];
        if (off >= cells - qmin[c]) throw new ClodError(bad + 'a position off the grid');
        positions[v * 3 + c] = grid.origin[c] + (qmin[c] + off) * grid.step;  // double, then float: as the desktop reader
      }
    const mask = d.take((vc + 7) >> 3);
    if (!mask) throw new ClodError(bad + 'truncated vertex id mask');
    if (vc % 8 && mask[vc >> 3] >> (vc % 8)) throw new ClodError(bad + 'stray bits in the vertex id mask');
    let fresh = 0;
    for (let v = 0; v < vc; ++v) fresh += (mask[v >> 3] >> (v & 7)) & 1;
    if (fresh > this.info.globalVertices - firstNew) throw new ClodError(bad + 'vertex id out of range');
    const listed = new Uint32Array(vc - fresh);
    if (vc > fresh) {
      p = await this._stream(d, indexSequenceBound(vc - fresh, this.info.globalVertices));
      try {
        if (!p) throw new Error();
        MeshoptDecoder.decodeIndexSequence(new Uint8Array(listed.buffer), listed.length, 4, p);
      } catch (e) {
        throw new ClodError(bad + 'its vertex ids do not decode');
      }
    }
    const attributes = {};
    for (const s of OPTIONAL_STREAMS) {
      if (!(flags & s.bit)) continue;
      p = await this._stream(d, vertexBufferBound(vc, s.stride));
      const out = new Uint8Array(vc * s.stride);
      try {
        if (!p) throw new Error();
        MeshoptDecoder.decodeVertexBuffer(out, vc, s.stride, p);
      } catch (e) {
        throw new ClodError(bad + `its ${s.name === 'colors' ? 'colours' : s.name === 'texCoords' ? 'texture coordinates' : s.name} do not decode`);
      }
      attributes[s.name] = out;
    }
    if (d.left() !== 0) throw new ClodError(bad + 'its size does not match its contents');
    const vertexIds = new Uint32Array(vc);
    for (let v = 0, nextNew = 0, nextOld = 0; v < vc; ++v) {
      if ((mask[v >> 3] >> (v & 7)) & 1) {
        vertexIds[v] = firstNew + nextNew++;
      } else {
        const old = listed[nextOld++];
        if (old >= firstNew) throw new ClodError(bad + 'global vertex id out of range');
        vertexIds[v] = old;
      }
    }
    // Each node's faces and vertices must be its record's.
    const seen = new Uint32Array(vc);
    for (let m = 0; m < count; ++m) {
      const node = this.nodes.get(first + m);
      if (!node) continue;  // its record is not loaded (the roots' unit is checked whole at open)
      if (faceStart[m + 1] - faceStart[m] !== node.faceCount) throw new ClodError(bad + 'its face count does not match its record');
      let verts = 0;
      for (let f = faceStart[m] * 3; f < faceStart[m + 1] * 3; ++f)
        if (seen[corners[f]] !== m + 1) {
          seen[corners[f]] = m + 1;
          ++verts;
        }
      if (verts !== node.vertexCount) throw new ClodError(bad + 'its vertex count does not match its record');
    }
    const unit = { offset, firstNode: first, nodeCount: count, faceStart, positions, corners, vertexIds, attributes,
      bytes: positions.byteLength + corners.byteLength + vertexIds.byteLength +
        Object.values(attributes).reduce((b, a) => b + a.byteLength, 0) };
    if (this.units.has(offset)) {
      this.unitSizes.set(offset, unit.bytes);
      this.unitBytes += unit.bytes;
    }
    return unit;
  }
}
