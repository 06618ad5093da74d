// web/clod.js refuses a deflated geometry stream that is not exactly one whole deflate stream of
// the size it claims, as the desktop reader does (lod_reader.cpp's StreamInflater): in a unit of
// FILE whose triangles are deflated, the stream is rewritten (the blob's CRC made good again) with
// bytes after its end (1 and 3), without its last byte, and with rawBytes one less and one more;
// each must give "its triangles do not decode", and the blob rewritten unchanged must decode.
// Prints one line a case; exits with 1 when one is not as expected (it_web_reader_refuses_bad_deflate).
//   node web_deflate_check.mjs SOURCE_DIR FILE.clod
import { readFileSync } from 'fs';
import { pathToFileURL } from 'url';

const [source, file] = process.argv.slice(2);
const { ClodReader, crc32 } = await import(pathToFileURL(`${source}/web/clod.js`).href);
const { MeshoptDecoder } = await import(pathToFileURL(`${source}/web/node_modules/meshoptimizer/meshopt_decoder.mjs`).href);
await MeshoptDecoder.ready;
const bytes = readFileSync(file);
let crafted = new Uint8Array(0);  // served at the file's end, where no range of the file lies
const src = { size: bytes.length, bytesFetched: 0, requests: 0,
  async read(o, n) {
    if (o >= bytes.length) return crafted.subarray(o - bytes.length, o - bytes.length + n);
    return new Uint8Array(bytes.buffer, bytes.byteOffset + o, n);
  } };
const r = new ClodReader(src);
await r._open();

function uv(b, at) {  // [value, next offset]
  let x = 0, mul = 1;
  for (;;) {
    const c = b[at++];
    x += (c & 0x7f) * mul;
    mul *= 128;
    if (!(c & 0x80)) return [x, at];
  }
}
function uvBytes(x) {
  const out = [];
  do {
    out.push((x % 128) | (x >= 128 ? 0x80 : 0));
    x = Math.floor(x / 128);
  } while (x > 0);
  return out;
}
// Where the triangles' stream of a blob lies: [code offset, rawBytes, data offset, stored bytes, end].
function triangles(b) {
  let at = 5, x;
  [, at] = uv(b, at);  // first node
  let count;
  [count, at] = uv(b, at);
  for (let i = 0; i < count; ++i) [, at] = uv(b, at);
  for (let i = 0; i < 5; ++i) [, at] = uv(b, at);  // vertex count, qmin, first new id
  const stream = (from) => {
    let code, raw = -1, p;
    [code, p] = uv(b, from);
    if (code % 2) [raw, p] = uv(b, p);
    return [from, raw, p, Math.floor(code / 2), p + Math.floor(code / 2)];
  };
  const pos = stream(at);
  return stream(pos[4]);
}

let found = null;
for (let id = 0; id < r.info.nodeCount && !found; ++id) {
  await r.loadNode(id);
  const n = r.nodes.get(id);
  const blob = bytes.subarray(n.geometry, n.geometry + n.geometryBytes);
  const t = triangles(blob);
  if (t[1] >= 0 && t[3] > 8) found = { id, blob, t };
}
if (!found) {
  console.log('no unit with deflated triangles');
  process.exit(1);
}
const { id, blob, t } = found;
const [codeAt, raw, dataAt, stored, end] = t;
const data = blob.subarray(dataAt, end);
// The blob with the triangles' stream replaced by (deflated bytes, rawBytes), its CRC made good.
function rewrite(d, rawBytes) {
  const head = Array.from(blob.subarray(4, codeAt));
  const out = Uint8Array.from([0, 0, 0, 0, ...head, ...uvBytes(d.length * 2 + 1), ...uvBytes(rawBytes), ...d, ...blob.subarray(end)]);
  new DataView(out.buffer).setUint32(0, crc32(out, 4, out.length), true);
  return out;
}
const cases = [
  ['unchanged', data, raw, null],
  ['1 byte after its end', Uint8Array.from([...data, 0]), raw, 'its triangles do not decode'],
  ['3 bytes after its end', Uint8Array.from([...data, 1, 2, 3]), raw, 'its triangles do not decode'],
  ['its last byte missing', data.subarray(0, data.length - 1), raw, 'its triangles do not decode'],
  ['rawBytes one less', data, raw - 1, 'its triangles do not decode'],
  ['rawBytes one more', data, raw + 1, 'its triangles do not decode'],
];
let failed = 0;
for (const [name, d, rawBytes, want] of cases) {
  crafted = rewrite(d, rawBytes);
  let got = null;
  try {
    await r._decodeUnit(bytes.length, crafted.length, id);
  } catch (e) {
    got = e.message;
  }
  const ok = want === null ? got === null : got !== null && got.includes(want);
  if (!ok) ++failed;
  console.log(`node ${id}, triangles ${stored} bytes deflated from ${raw}: ${name}: ${got === null ? 'decoded' : 'refused: ' + got}${ok ? '' : '  <- NOT AS EXPECTED'}`);
}
process.exit(failed ? 1 : 0);
