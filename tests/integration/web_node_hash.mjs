// Prints, for every node of a .clod file, its id, its vertex count and an FNV-1a hash of its
// vertices' positions as web/clod.js decodes them, sorted: tools/lod_node_hash.cpp's twin
// (it_web_reader_positions compares the two outputs).
//   node web_node_hash.mjs SOURCE_DIR FILE.clod
import { readFileSync } from 'fs';
import { pathToFileURL } from 'url';

const [source, file] = process.argv.slice(2);
const { ClodReader } = await import(pathToFileURL(`${source}/web/clod.js`).href);
const { MeshoptDecoder } = await import(pathToFileURL(`${source}/web/node_modules/meshoptimizer/meshopt_decoder.mjs`).href);
await MeshoptDecoder.ready;
const bytes = readFileSync(file);
// The file in memory, read as RangeSource reads it over HTTP.
const src = { size: bytes.length, bytesFetched: 0, requests: 0,
  async read(o, n) { return new Uint8Array(bytes.buffer, bytes.byteOffset + o, n); } };
const r = new ClodReader(src);
await r._open();
const out = [];
const f32 = new Float32Array(1), u32 = new Uint32Array(f32.buffer);
for (let id = 0; id < r.info.nodeCount; ++id) {
  await r.loadNode(id);
  const u = await r.loadUnit(id);
  const m = id - u.firstNode, used = new Set();
  for (let f = u.faceStart[m] * 3; f < u.faceStart[m + 1] * 3; ++f) used.add(u.corners[f]);
  const pts = [...used].map((v) => [u.positions[3 * v], u.positions[3 * v + 1], u.positions[3 * v + 2]]);
  pts.sort((a, b) => a[0] - b[0] || a[1] - b[1] || a[2] - b[2]);
  let h = 2166136261n;
  for (const p of pts)
    for (const x of p) {
      f32[0] = x;
      h = ((h ^ BigInt(u32[0])) * 16777619n) & 0xffffffffn;
    }
  out.push(`${id} ${pts.length} ${h}`);
}
console.log(out.join('\n'));
