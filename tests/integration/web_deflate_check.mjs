// web/clod.js refuses a deflated geometry stream that is not exactly one whole deflate stream of
// the size it claims, as the desktop reader does (lod_reader.cpp's StreamInflater): in a unit of
// FILE whose triangles are deflated, the stream is rewritten (the blob's CRC made good again) with
// bytes after its end (1 and 3), without its last byte, and with rawBytes one less and one more;
// each must give "its triangles do not decode", and the blob rewritten unchanged must decode.
// Prints one line a case; exits with 1 when one is not as expected (it_web_reader_refuses_bad_deflate).
//   node web_deflate_check.mjs SOURCE_DIR FILE.clod
import { openCrafted, streams, rewrite } from './clod_blob.mjs';

const [source, file] = process.argv.slice(2);
const { clod: { crc32 }, r, bytes, craft } = await openCrafted(source, file);

let found = null;
for (let id = 0; id < r.info.nodeCount && !found; ++id) {
  await r.loadNode(id);
  const n = r.nodes.get(id);
  const blob = bytes.subarray(n.geometry, n.geometry + n.geometryBytes);
  const t = streams(blob, 2)[1];
  if (t.raw >= 0 && t.stored > 8) found = { id, blob, t };
}
if (!found) {
  console.log('no unit with deflated triangles');
  process.exit(1);
}
const { id, blob, t } = found;
const { raw, stored } = t;
const data = blob.subarray(t.dataAt, t.end);
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
  const n = craft(rewrite(blob, t, d, rawBytes, crc32));  // the triangles' stream replaced
  let got = null;
  try {
    await r._decodeUnit(bytes.length, n, id);
  } catch (e) {
    got = e.message;
  }
  const ok = want === null ? got === null : got !== null && got.includes(want);
  if (!ok) ++failed;
  console.log(`node ${id}, triangles ${stored} bytes deflated from ${raw}: ${name}: ${got === null ? 'decoded' : 'refused: ' + got}${ok ? '' : '  <- NOT AS EXPECTED'}`);
}
process.exit(failed ? 1 : 0);
