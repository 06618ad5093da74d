// web/clod.js on hostile version 8 positions (range-coded residuals, lod_format.md "Coded
// positions"): in units of FILE, the positions' stream is rewritten (the blob's CRC made good
// again) with random bytes changed, without its last byte and with a byte more; each decode must
// end, either decoded or refused with a ClodError (never another exception, never a hang: the
// caller's timeout), and the stream rewritten unchanged must decode to the same positions.
// Prints a summary; exits with 1 on a failure (it_web_reader_survives_bad_positions).
//   node web_positions_check.mjs SOURCE_DIR FILE.clod
import { readFileSync } from 'fs';
import { pathToFileURL } from 'url';

const [source, file] = process.argv.slice(2);
const { ClodReader, ClodError, crc32 } = await import(pathToFileURL(`${source}/web/clod.js`).href);
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
if (r.info.version < 8) {
  console.log(`version ${r.info.version}: no coded positions`);
  process.exit(1);
}

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
// Where the positions' stream of a blob lies (stored as it is): [code offset, data offset, end].
function positions(b) {
  let at = 5, count;
  [, at] = uv(b, at);  // first node
  [count, at] = uv(b, at);
  for (let i = 0; i < count; ++i) [, at] = uv(b, at);
  for (let i = 0; i < 5; ++i) [, at] = uv(b, at);  // vertex count, qmin, first new id
  const [code, p] = uv(b, at);
  return code % 2 ? null : [at, p, p + code / 2];
}
function rewrite(blob, t, d) {
  const out = Uint8Array.from([0, 0, 0, 0, ...blob.subarray(4, t[0]), ...uvBytes(d.length * 2), ...d, ...blob.subarray(t[2])]);
  new DataView(out.buffer).setUint32(0, crc32(out, 4, out.length), true);
  return out;
}
let seed = 12345;
const random = () => (seed = (Math.imul(seed, 1103515245) + 12345) >>> 0) / 2 ** 32;

const units = new Map();
for (let id = 0; id < r.info.nodeCount; ++id) {
  await r.loadNode(id);
  const n = r.nodes.get(id);
  if (!units.has(n.geometry)) units.set(n.geometry, { id, blob: bytes.subarray(n.geometry, n.geometry + n.geometryBytes) });
}
const picked = [...units.values()].filter((_, i) => i % Math.max(1, Math.floor(units.size / 8)) === 0);
let decoded = 0, refused = 0, failed = 0;
for (const { id, blob } of picked) {
  const t = positions(blob);
  if (!t) {
    console.log(`node ${id}: positions deflated`);
    ++failed;
    continue;
  }
  const data = blob.subarray(t[1], t[2]);
  const mutations = [['unchanged', data], ['its last byte missing', data.subarray(0, data.length - 1)],
    ['a byte more', Uint8Array.from([...data, 0x55])]];
  for (let k = 0; k < 40; ++k) {
    const d = Uint8Array.from(data);
    for (let j = 0, n = 1 + Math.floor(random() * 3); j < n; ++j) d[Math.floor(random() * d.length)] ^= 1 + Math.floor(random() * 255);
    mutations.push([`random change ${k}`, d]);
  }
  const original = await r._decodeUnit(bytes.length + 0, (crafted = rewrite(blob, t, data)).length, id);
  for (const [name, d] of mutations) {
    crafted = rewrite(blob, t, d);
    try {
      const u = await r._decodeUnit(bytes.length, crafted.length, id);
      ++decoded;
      if (name === 'unchanged' && u.positions.join() !== original.positions.join()) {
        console.log(`node ${id}: unchanged: other positions`);
        ++failed;
      }
    } catch (e) {
      if (!(e instanceof ClodError) || !e.message.includes('its positions do not decode') && !e.message.includes('a position off the grid')) {
        console.log(`node ${id}: ${name}: ${e.constructor.name}: ${e.message}`);
        ++failed;
      } else {
        ++refused;
      }
      if (name === 'unchanged') ++failed;
    }
  }
}
console.log(`${picked.length} units, ${decoded + refused} decodes: ${decoded} decoded, ${refused} refused, ${failed} failures`);
process.exit(failed || refused === 0 ? 1 : 0);
