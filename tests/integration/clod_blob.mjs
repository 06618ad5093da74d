// Shared by the web reader's hostile-stream checks (web_deflate_check.mjs, web_positions_check.mjs):
// web/clod.js's ClodReader over FILE, whose reads past the file's end serve a crafted unit, and
// the blob layout of a unit's geometry streams (lod_format.md) to find and rewrite one stream.
import { readFileSync } from 'fs';
import { pathToFileURL } from 'url';

// { clod (web/clod.js's exports), r (the opened reader), bytes (FILE), craft (serves a unit at
// bytes.length: craft(u) returns u's length) }.
export async function openCrafted(source, file) {
  const clod = await import(pathToFileURL(`${source}/web/clod.js`).href);
  const { MeshoptDecoder } = await import(pathToFileURL(`${source}/web/node_modules/meshoptimizer/meshopt_decoder.mjs`).href);
  await MeshoptDecoder.ready;
  const bytes = readFileSync(file);
  let crafted = new Uint8Array(0);  // served at the file's end, where no range of the file lies
  const src = { size: bytes.length, bytesFetched: 0, requests: 0,
    async read(o, n) {
      if (o >= bytes.length) return crafted.subarray(o - bytes.length, o - bytes.length + n);
      return new Uint8Array(bytes.buffer, bytes.byteOffset + o, n);
    } };
  const r = new clod.ClodReader(src);
  await r._open();
  return { clod, r, bytes, craft(u) { crafted = u; return u.length; } };
}

export function uv(b, at) {  // [value, next offset]
  let x = 0, mul = 1;
  for (;;) {
    const c = b[at++];
    x += (c & 0x7f) * mul;
    mul *= 128;
    if (!(c & 0x80)) return [x, at];
  }
}
export function uvBytes(x) {
  const out = [];
  do {
    out.push((x % 128) | (x >= 128 ? 0x80 : 0));
    x = Math.floor(x / 128);
  } while (x > 0);
  return out;
}

// The first k geometry streams of a blob (0: positions, 1: triangles), each
// { codeAt, raw (rawBytes, -1: stored as it is), dataAt, stored, end }.
export function streams(b, k) {
  let at = 5, count;
  [, at] = uv(b, at);  // first node
  [count, at] = uv(b, at);
  for (let i = 0; i < count; ++i) [, at] = uv(b, at);
  for (let i = 0; i < 5; ++i) [, at] = uv(b, at);  // vertex count, qmin, first new id
  const out = [];
  for (let i = 0; i < k; ++i) {
    let code, raw = -1, p;
    [code, p] = uv(b, at);
    if (code % 2) [raw, p] = uv(b, p);
    const stored = Math.floor(code / 2);
    out.push({ codeAt: at, raw, dataAt: p, stored, end: p + stored });
    at = p + stored;
  }
  return out;
}

// The blob with stream s replaced by d (deflated from rawBytes when rawBytes >= 0, else stored as
// it is), its CRC made good.
export function rewrite(blob, s, d, rawBytes, crc32) {
  const code = rawBytes >= 0 ? [...uvBytes(d.length * 2 + 1), ...uvBytes(rawBytes)] : uvBytes(d.length * 2);
  const out = Uint8Array.from([0, 0, 0, 0, ...blob.subarray(4, s.codeAt), ...code, ...d, ...blob.subarray(s.end)]);
  new DataView(out.buffer).setUint32(0, crc32(out, 4, out.length), true);
  return out;
}
