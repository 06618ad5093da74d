// web/clod.js on hostile version 8 positions (range-coded residuals, lod_format.md "Coded
// positions"): in units of FILE, the positions' stream is rewritten (the blob's CRC made good
// again) with random bytes changed, without its last byte and with a byte more; each decode must
// end, either decoded or refused with a ClodError (never another exception, never a hang: the
// caller's timeout), and the stream rewritten unchanged must decode to the same positions.
// Prints a summary; exits with 1 on a failure (it_web_reader_survives_bad_positions).
//   node web_positions_check.mjs SOURCE_DIR FILE.clod
import { openCrafted, streams, rewrite } from './clod_blob.mjs';

const [source, file] = process.argv.slice(2);
const { clod: { ClodError, crc32 }, r, bytes, craft } = await openCrafted(source, file);
if (r.info.version < 8) {
  console.log(`version ${r.info.version}: no coded positions`);
  process.exit(1);
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
  const t = streams(blob, 1)[0];
  if (t.raw >= 0) {
    console.log(`node ${id}: positions deflated`);
    ++failed;
    continue;
  }
  const data = blob.subarray(t.dataAt, t.end);
  const mutations = [['unchanged', data], ['its last byte missing', data.subarray(0, data.length - 1)],
    ['a byte more', Uint8Array.from([...data, 0x55])]];
  for (let k = 0; k < 40; ++k) {
    const d = Uint8Array.from(data);
    for (let j = 0, n = 1 + Math.floor(random() * 3); j < n; ++j) d[Math.floor(random() * d.length)] ^= 1 + Math.floor(random() * 255);
    mutations.push([`random change ${k}`, d]);
  }
  const original = await r._decodeUnit(bytes.length, craft(rewrite(blob, t, data, -1, crc32)), id);
  for (const [name, d] of mutations) {
    const n = craft(rewrite(blob, t, d, -1, crc32));
    try {
      const u = await r._decodeUnit(bytes.length, n, id);
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
