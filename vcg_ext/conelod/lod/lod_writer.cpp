// ConeLOD — writing the .clod file (lod_build.h; byte layout in lod_format.md).
//
// Kamiya, Suzuki, Kawachi, §8: a file of chunks, each an id, its size and its data followed by
// sub-chunks. The writer takes the cluster DAG (lod_dag.cpp), first computes the small per-node
// records (cone, sphere, errors, the children / siblings / parents lists: about 100-150 bytes a
// node), then streams the geometry level by level, coarsest first, through one reused buffer:
// besides the DAG it holds only the level's face order and vertex renumbering. Container sizes
// and the header's offsets are patched in place at the end. With --memory (lod_spill.h) the
// levels' faces come back from the temporary folder one level at a time (LevelFaces). Both passes
// run on the build's threads (records node by node; geometry a window of units at a time, written
// in file order): the bytes do not depend on the thread count.
#include "conelod/lod/lod_build.h"
#include "conelod/lod/lod_read.h"
#include "conelod/lod/lod_spill.h"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <numeric>

#include <meshoptimizer.h>
#include <zlib.h>

#include "conelod/lod/lod_entropy.h"
#include "conelod/lod/lod_internal.h"
#include "conelod/mesh/mesh_check.h"
#include "conelod/mesh/safe_file.h"
#include "conelod/parallel.h"
#include "conelod/stage_log.h"

namespace conelod {
namespace {

using namespace lodfile;

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Version 7's geometry streams: each codec output is deflated (raw RFC 1951, zlib level 9) and
// stored so when that is smaller, as `uv code` = bytes x 2 + 1, `uv rawBytes`, the deflated bytes;
// else as it is, `uv code` = bytes x 2, the bytes (lod_format.md, "Geometry"). One z_stream, reset
// for each stream (its 256 KiB state is allocated once).
class StreamDeflater {
 public:
  StreamDeflater() { ok_ = deflateInit2(&z_, 9, Z_DEFLATED, -15, 9, Z_DEFAULT_STRATEGY) == Z_OK; }
  ~StreamDeflater() {
    if (ok_) deflateEnd(&z_);
  }
  StreamDeflater(const StreamDeflater&) = delete;
  StreamDeflater& operator=(const StreamDeflater&) = delete;
  // Appends the stream to `e`; gives back the bytes it took (its code and size fields not counted).
  // False: zlib failed (out of memory).
  bool put(Encoder& e, const std::vector<uint8_t>& data, uint64_t& stored) {
    if (!ok_ || deflateReset(&z_) != Z_OK) return false;
    out_.resize(deflateBound(&z_, uLong(data.size())) + 16);
    z_.next_in = const_cast<Bytef*>(data.data());
    z_.avail_in = uInt(data.size());
    z_.next_out = out_.data();
    z_.avail_out = uInt(out_.size());
    if (deflate(&z_, Z_FINISH) != Z_STREAM_END) return false;
    const size_t z = size_t(z_.total_out);
    Encoder sizes;
    sizes.uv(uint64_t(data.size()));
    if (z + sizes.bytes.size() < data.size()) {
      e.uv(uint64_t(z) * 2 + 1);
      e.raw(sizes.bytes.data(), sizes.bytes.size());
      e.raw(out_.data(), z);
      stored = z;
    } else {
      e.uv(uint64_t(data.size()) * 2);
      e.raw(data.data(), data.size());
      stored = data.size();
    }
    return true;
  }

 private:
  z_stream z_{};
  bool ok_ = false;
  std::vector<uint8_t> out_;
};

// Buffered output with absolute-offset patching (FILE* with a large buffer).
class OutFile {
 public:
  // Writes a temporary file beside `path`, renamed over it by close() (safe_file.h).
  std::string open(const std::string& path) {
    path_ = path;
    const std::string err = safe_.open(path);
    f_ = safe_.file();
    return err;
  }
  bool write(const void* p, size_t n) {
    if (!ok_) return false;
    if (n && std::fwrite(p, 1, n, f_) != n) failed();
    offset_ += n;
    return ok_;
  }
  bool write(const Encoder& e) { return write(e.bytes.data(), e.bytes.size()); }
  // Writes a complete leaf chunk: header (CRC of `data`) and data.
  bool chunk(uint32_t id, const Encoder& data, uint64_t childBytes = 0) {
    ChunkHeader h;
    h.id = id;
    h.dataBytes = data.bytes.size();
    h.childBytes = childBytes;
    h.crc = Crc32(data.bytes.data(), data.bytes.size());
    Encoder e;
    EncodeChunkHeader(e, h);
    return write(e) && write(data);
  }
  bool patch(uint64_t at, const Encoder& e) {
    if (!ok_) return false;
    if (std::fseek(f_, long(at), SEEK_SET) != 0 ||
        std::fwrite(e.bytes.data(), 1, e.bytes.size(), f_) != e.bytes.size() || std::fseek(f_, 0, SEEK_END) != 0)
      failed();
    return ok_;
  }
  // Commits the file when every write succeeded, else removes the temporary file.
  bool close() {
    f_ = nullptr;
    if (ok_) {
      error_ = safe_.commit();
      ok_ = error_.empty();
    }
    safe_.discard();
    return ok_;
  }
  const std::string& error() const { return error_; }
  void abandon() {
    f_ = nullptr;
    ok_ = false;
    safe_.discard();
  }
  uint64_t offset() const { return offset_; }
  bool ok() const { return ok_; }

 private:
  void failed() {
    error_ = "cannot write '" + path_ + "': " + std::strerror(errno);
    ok_ = false;
  }

  SafeFile safe_;
  std::string path_;
  std::FILE* f_ = nullptr;
  std::string error_;
  uint64_t offset_ = 0;
  bool ok_ = true;
};

struct NodeRecord {
  uint32_t level = 0, group = LodNode::kNoGroup;
  std::vector<uint32_t> children, siblings, parents;
  NormalCone cone;
  vcg::Point3f center;
  float radius = 0;
  uint32_t faceCount = 0, vertexCount = 0;
  float error = 0, parentError = 0, typical = 0;
};

// Faces of each node of a level in node order (counting sort by node).
void BucketFaces(const std::vector<uint32_t>& faceCluster, const std::vector<uint32_t>& nodeOfCluster,
                 std::vector<uint32_t>& start, std::vector<uint32_t>& faces) {
  const size_t nodes = nodeOfCluster.size();
  start.assign(nodes + 1, 0);
  for (uint32_t c : faceCluster) ++start[nodeOfCluster[c] + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  faces.resize(faceCluster.size());
  std::vector<uint32_t> at(start.begin(), start.end() - 1);
  for (size_t f = 0; f < faceCluster.size(); ++f) faces[at[nodeOfCluster[faceCluster[f]]]++] = uint32_t(f);
}

// The nodes [n0, n1) of a part of a level (its faces' clusters' nodes, which no other part has).
void NodeRange(const std::vector<uint32_t>& faceCluster, const std::vector<uint32_t>& nodeOfCluster, uint32_t& n0,
               uint32_t& n1) {
  n0 = ~0u;
  n1 = 0;
  for (uint32_t c : faceCluster) {
    n0 = std::min(n0, nodeOfCluster[c]);
    n1 = std::max(n1, nodeOfCluster[c] + 1);
  }
  if (n0 > n1) n0 = n1 = 0;
}

// A level's faces and faceCluster: the DAG's own, or read back from the spill into `faces` and
// `faceCluster` (one level at a time).
class LevelFaces {
 public:
  LevelFaces(const LodDag& dag, const LodSpill* spill) : dag_(dag), spill_(spill) {}
  // A level the streamed build spilled a chunk at a time is read back a part (a chunk) at a time:
  // each part holds whole nodes, and whole groups (LodSpill::append).
  size_t parts(size_t k) const { return spill_ && spill_->has(k) ? spill_->parts(k) : 1; }
  Status load(size_t k, size_t part = 0) {
    if (spill_ && spill_->has(k)) {
      const Status s = spill_->get(k, part, own_, ownCluster_);
      faces_ = &own_;
      cluster_ = &ownCluster_;
      return s;
    }
    own_ = std::vector<std::array<uint32_t, 3>>();
    ownCluster_ = std::vector<uint32_t>();
    faces_ = &dag_.levels[k].faces;
    cluster_ = &dag_.levels[k].faceCluster;
    return Status::Ok();
  }
  size_t count(size_t k) const {
    return spill_ && spill_->has(k) ? size_t(spill_->faceCount(k)) : dag_.levels[k].faces.size();
  }
  const std::vector<std::array<uint32_t, 3>>& faces() const { return *faces_; }
  const std::vector<uint32_t>& faceCluster() const { return *cluster_; }

 private:
  const LodDag& dag_;
  const LodSpill* spill_;
  std::vector<std::array<uint32_t, 3>> own_;
  std::vector<uint32_t> ownCluster_;
  const std::vector<std::array<uint32_t, 3>>* faces_ = nullptr;
  const std::vector<uint32_t>* cluster_ = nullptr;
};

// Per group (or creator) of a level: the node ids of its clusters, CSR.
void ListBy(const std::vector<int>& key, size_t keys, const std::vector<uint32_t>& nodeId, std::vector<uint32_t>& start,
            std::vector<uint32_t>& list) {
  start.assign(keys + 1, 0);
  for (int k : key)
    if (k >= 0) ++start[size_t(k) + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  list.assign(start.back(), 0);
  std::vector<uint32_t> at(start.begin(), start.end() - 1);
  for (size_t c = 0; c < key.size(); ++c)
    if (key[c] >= 0) list[at[size_t(key[c])]++] = nodeId[c];
  for (size_t k = 0; k < keys; ++k) std::sort(list.begin() + start[k], list.begin() + start[k + 1]);
}

// The geometry of one unit (lod_writer's geometry pass): its blob but for what the units before it
// decide (EncodeUnit), finished once that is known (FinishUnit).
struct UnitInput {
  const std::vector<std::array<uint32_t, 3>>& levelFaces;
  const std::vector<uint32_t>& start;  // BucketFaces: the level's faces node by node
  const std::vector<uint32_t>& faces;
  const std::vector<vcg::Point3f>& positions;
  const LodGrid& grid;
  const LodAttributes& attributes;
  uint32_t attributeMask;
  uint64_t firstId;  // the level's first node id
};

// A thread's buffers, reused from unit to unit (none carries anything into the next unit's bytes).
struct UnitScratch {
  // A unit's vertex ids -> its local ids (in the order its faces first use them): a small
  // open-addressing table per unit ((id + 1) << 32 | local id; 0: empty), not an array over every
  // vertex of the DAG (4 bytes a vertex, the out-of-core build's peak).
  std::vector<uint64_t> slots;
  std::vector<uint32_t> idx, tmp, remap, q32, decoded;
  std::vector<uint64_t> qrel, residual;
  std::vector<uint8_t> kinds, ibuf, buf, attr;
  PositionPredictor predictor;
  PositionResidualModel residualModel;
  StreamDeflater deflater;
};

struct EncodedUnit {
  std::vector<uint32_t> verts;  // the unit's vertices in their stored order
  // The blob's fields before the first new global id, those between it and the vertex mask (the
  // positions and the triangles), those after the global ids (the attribute streams).
  Encoder head, mid, tail;
  std::vector<uint8_t> mask;  // which vertices are new to the file
  std::vector<uint32_t> old;  // the others' global ids
  uint64_t firstGlobal = 0, globalAfter = 0;
  Encoder blob;  // FinishUnit: the whole blob, and its CRC
  uint32_t crc = 0;
  uint64_t positionBytes = 0, indexBytes = 0, idBytes = 0, colorBytes = 0, normalBytes = 0, texCoordBytes = 0;
  const char* error = nullptr;
};

// Units encoded side by side between two writes: at least 2^16 faces, 2^14 a thread (about 15
// bytes a face while held: the window's blobs and vertex lists).
uint64_t WindowFaces(unsigned threads) { return std::max<uint64_t>(uint64_t(1) << 16, uint64_t(threads) << 14); }

void EncodeUnit(const UnitInput& in, uint32_t u0, uint32_t u1, UnitScratch& S, EncodedUnit& U) {
  const std::vector<uint32_t>& start = in.start;
  std::vector<uint32_t>& verts = U.verts;
  std::vector<uint32_t>& idx = S.idx;
  std::vector<uint32_t>& tmp = S.tmp;
  verts.clear();
  idx.clear();
  {
    size_t mask = 63;
    while (mask + 1 < 6 * size_t(start[u1] - start[u0])) mask = mask << 1 | 1;
    S.slots.assign(mask + 1, 0);
    for (uint32_t j = start[u0]; j < start[u1]; ++j)
      for (uint32_t v : in.levelFaces[in.faces[j]]) {
        const uint64_t key = (uint64_t(v) + 1) << 32;
        size_t h = size_t((uint64_t(v) * 0x9E3779B97F4A7C15ull) >> 32) & mask;
        while (S.slots[h] && (S.slots[h] & ~uint64_t(0xFFFFFFFFu)) != key) h = (h + 1) & mask;
        if (!S.slots[h]) {
          S.slots[h] = key | verts.size();
          verts.push_back(v);
        }
        idx.push_back(uint32_t(S.slots[h]));
      }
  }
  const size_t vc = verts.size();
  tmp.resize(idx.size());
  for (uint32_t i = u0; i < u1; ++i) {  // each node's faces for the vertex cache, in place
    const size_t a = size_t(start[i] - start[u0]) * 3, n = size_t(start[i + 1] - start[i]) * 3;
    meshopt_optimizeVertexCache(tmp.data() + a, idx.data() + a, n, vc);
  }
  S.remap.resize(vc);
  meshopt_optimizeVertexFetchRemap(S.remap.data(), tmp.data(), tmp.size(), vc);
  for (size_t j = 0; j < idx.size(); ++j) idx[j] = S.remap[tmp[j]];
  tmp.assign(vc, 0);
  for (size_t v = 0; v < vc; ++v) tmp[S.remap[v]] = verts[v];
  verts.swap(tmp);
  // Quantized positions relative to the unit's smallest corner.
  uint32_t qmin[3] = {~0u, ~0u, ~0u}, qmax[3] = {0, 0, 0};
  std::vector<uint32_t>& q32 = S.q32;
  q32.resize(vc * 3);
  for (size_t v = 0; v < vc; ++v)
    for (int c = 0; c < 3; ++c) {
      const uint32_t q = in.grid.Quantize(in.positions[verts[v]][c], c);
      q32[v * 3 + size_t(c)] = q;
      qmin[c] = std::min(qmin[c], q);
      qmax[c] = std::max(qmax[c], q);
    }
  const bool wide = std::max({qmax[0] - qmin[0], qmax[1] - qmin[1], qmax[2] - qmin[2]}) > 0xFFFFu;
  Encoder& e = U.head;
  const uint8_t flags = uint8_t((wide ? kGeomWidePositions : 0) | in.attributeMask);
  e.raw(&flags, 1);
  e.uv(in.firstId + u0);  // the unit's nodes
  e.uv(u1 - u0);
  for (uint32_t i = u0; i < u1; ++i) e.uv(start[i + 1] - start[i]);
  e.uv(vc);
  for (int c = 0; c < 3; ++c) e.uv(qmin[c]);
  // (then the first new global id: FinishUnit)
  // The triangles are coded first: the positions' predictions walk the faces as the reader
  // gets them back from the index codec (which may rotate a face's corners).
  std::vector<uint8_t>& ibuf = S.ibuf;
  ibuf.resize(meshopt_encodeIndexBufferBound(idx.size(), vc));
  ibuf.resize(meshopt_encodeIndexBuffer(ibuf.data(), ibuf.size(), idx.data(), idx.size()));
  if (ibuf.empty()) {
    U.error = "internal error: the index codec failed";
    return;
  }
  S.decoded.resize(idx.size());
  if (meshopt_decodeIndexBuffer(S.decoded.data(), S.decoded.size(), 4, ibuf.data(), ibuf.size()) != 0) {
    U.error = "internal error: the index codec failed";
    return;
  }
  // Positions: the residuals of the predictions, range-coded in the order the prediction
  // visits the vertices, each in the context of its prediction's kind (lod_entropy.h).
  const int width = wide ? 4 : 2;
  const uint64_t valueMask = (uint64_t(1) << (8 * width)) - 1;
  std::vector<uint64_t>& qrel = S.qrel;
  qrel.resize(vc * 3);
  for (size_t v = 0; v < vc; ++v)
    for (int c = 0; c < 3; ++c) qrel[v * 3 + size_t(c)] = q32[v * 3 + size_t(c)] - qmin[c];
  S.residual.clear();
  S.kinds.clear();
  S.predictor.Walk(S.decoded.data(), S.decoded.size() / 3, vc, qrel.data(), [&](uint32_t v, const uint64_t* pred) {
    for (size_t c = 0; c < 3; ++c) S.residual.push_back((qrel[3 * size_t(v) + c] - pred[c]) & valueMask);
    S.kinds.push_back(uint8_t(S.predictor.kind()));
  });
  std::vector<uint8_t>& buf = S.buf;
  buf.clear();
  {
    RangeEncoder rc(buf);
    const uint32_t m = PositionResidualModel::TypicalLength(S.residual.data(), S.kinds.data(), vc, width, tmp);
    rc.Raw(m, 6);
    S.residualModel.Reset(m, width);
    for (size_t i = 0; i < vc; ++i) S.residualModel.Encode(rc, S.kinds[i], &S.residual[3 * i], width);
    rc.Finish();
  }
  uint64_t stored = buf.size();
  U.mid.uv(stored * 2);  // stored as it is: a range coder's output does not deflate
  U.mid.raw(buf.data(), buf.size());
  U.positionBytes = stored;
  if (!S.deflater.put(U.mid, ibuf, stored)) {
    U.error = "internal error: deflate failed";
    return;
  }
  U.indexBytes = stored;
  // Attribute streams, 4 bytes a unit vertex each, in the unit's vertex order.
  std::vector<uint8_t>& attr = S.attr;
  auto stream = [&](uint64_t& counter) {
    buf.resize(meshopt_encodeVertexBufferBound(vc, 4));
    buf.resize(meshopt_encodeVertexBuffer(buf.data(), buf.size(), attr.data(), vc, 4));
    if (buf.empty() || !S.deflater.put(U.tail, buf, stored)) return false;
    counter += stored;
    return true;
  };
  // Two u16 codes a vertex (normals, texture coordinates), little-endian.
  auto codePairs = [&](const std::vector<std::array<uint16_t, 2>>& codes) {
    attr.resize(vc * 4);
    for (size_t v = 0; v < vc; ++v)
      for (size_t c = 0; c < 2; ++c) {
        const uint16_t x = codes[verts[v]][c];
        attr[4 * v + 2 * c] = uint8_t(x & 0xFF);
        attr[4 * v + 2 * c + 1] = uint8_t(x >> 8);
      }
  };
  const LodAttributes& attributes = in.attributes;
  if (in.attributeMask & kGeomColors) {
    attr.resize(vc * 4);
    for (size_t v = 0; v < vc; ++v) std::memcpy(attr.data() + 4 * v, attributes.colors[verts[v]].data(), 4);
    if (!stream(U.colorBytes)) U.error = "internal error: the vertex codec failed";
  }
  if (!U.error && (in.attributeMask & kGeomNormals)) {
    codePairs(attributes.normals);
    if (!stream(U.normalBytes)) U.error = "internal error: the vertex codec failed";
  }
  if (!U.error && (in.attributeMask & kGeomTexCoords)) {
    codePairs(attributes.texCoords);
    if (!stream(U.texCoordBytes)) U.error = "internal error: the vertex codec failed";
  }
}

// The blob of a unit whose global ids are known (firstGlobal, mask, old, globalAfter), and its CRC.
void FinishUnit(EncodedUnit& U, UnitScratch& S) {
  Encoder& e = U.blob;
  e.bytes.reserve(U.head.bytes.size() + 10 + U.mid.bytes.size() + U.mask.size() + 4 * U.old.size() + 16 +
                  U.tail.bytes.size());
  e.raw(U.head.bytes.data(), U.head.bytes.size());
  e.uv(U.firstGlobal);  // the first new global id
  e.raw(U.mid.bytes.data(), U.mid.bytes.size());
  e.raw(U.mask.data(), U.mask.size());
  U.idBytes = U.mask.size();
  if (!U.old.empty()) {
    std::vector<uint8_t>& buf = S.buf;
    buf.resize(meshopt_encodeIndexSequenceBound(U.old.size(), size_t(U.globalAfter)));
    buf.resize(meshopt_encodeIndexSequence(buf.data(), buf.size(), U.old.data(), U.old.size()));
    if (buf.empty()) {
      U.error = "internal error: the index sequence codec failed";
      return;
    }
    uint64_t stored = 0;
    if (!S.deflater.put(e, buf, stored)) {
      U.error = "internal error: deflate failed";
      return;
    }
    U.idBytes += stored;
  }
  e.raw(U.tail.bytes.data(), U.tail.bytes.size());
  U.crc = Crc32(e.bytes.data(), e.bytes.size());
  // Only the blob is held until it is written.
  U.head = U.mid = U.tail = Encoder();
  U.verts = std::vector<uint32_t>();
  U.mask = std::vector<uint8_t>();
  U.old = std::vector<uint32_t>();
}

}  // namespace

std::string LodAttributes::Check(size_t vertices) const {
  if (!colors.empty() && colors.size() != vertices)
    return "the LOD attributes have " + std::to_string(colors.size()) + " colours for " + std::to_string(vertices) +
           " vertices";
  if (!normals.empty() && normals.size() != vertices)
    return "the LOD attributes have " + std::to_string(normals.size()) + " normals for " + std::to_string(vertices) +
           " vertices";
  if (!texCoords.empty() && texCoords.size() != vertices)
    return "the LOD attributes have " + std::to_string(texCoords.size()) + " texture coordinates for " +
           std::to_string(vertices) + " vertices";
  if (!texCoords.empty())
    for (int c = 0; c < 2; ++c)
      if (!std::isfinite(uvMin[c]) || !std::isfinite(uvMax[c]) || !(uvMin[c] <= uvMax[c]))
        return "the LOD attributes' UV box is not finite or is inverted";
  if (!place.empty()) {
    if (place.size() != vertices) return "the LOD attributes' places do not fit the vertices";
    for (size_t v = 0; v < place.size(); ++v)
      if (place[v] > v || place[place[v]] != place[v]) return "the LOD attributes' places are inconsistent";
  }
  if (!texture.empty()) {
    if (texCoords.empty()) return "a texture image without texture coordinates";
    const std::string bad = CheckLodTextureName(texture.name);
    if (!bad.empty()) return bad;
    if (texture.mime.empty() || texture.mime.size() > kMaxLodTextureNameBytes)
      return "the texture's MIME type is empty or too long";
  }
  return "";
}

std::string LodTextureMime(const std::string& name, const std::vector<uint8_t>& b) {
  auto starts = [&](std::initializer_list<uint8_t> sig) {
    return b.size() >= sig.size() && std::equal(sig.begin(), sig.end(), b.begin());
  };
  if (starts({0xFF, 0xD8, 0xFF})) return "image/jpeg";
  if (starts({0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A})) return "image/png";
  if (starts({'B', 'M'})) return "image/bmp";
  if (starts({'G', 'I', 'F', '8'})) return "image/gif";
  if (b.size() >= 12 && starts({'R', 'I', 'F', 'F'}) && std::equal(b.begin() + 8, b.begin() + 12, "WEBP"))
    return "image/webp";
  std::string ext =
      name.substr(std::min(name.size(), name.rfind('.') == std::string::npos ? name.size() : name.rfind('.') + 1));
  for (char& c : ext) c = char(std::tolower((unsigned char)c));
  if (ext == "tga") return "image/x-tga";
  return "application/octet-stream";
}

std::array<uint16_t, 2> EncodeLodTexCoord(const float uv[2], const float uvMin[2], const float uvMax[2]) {
  std::array<uint16_t, 2> q;
  for (int c = 0; c < 2; ++c) {
    const double range = double(uvMax[c]) - double(uvMin[c]);
    const double t = range > 0 ? (double(uv[c]) - double(uvMin[c])) / range * 65535.0 : 0.0;
    q[size_t(c)] = uint16_t(std::isfinite(t) ? std::lround(std::min(65535.0, std::max(0.0, t))) : 0);
  }
  return q;
}

std::array<uint16_t, 2> EncodeLodNormal(const vcg::Point3f& n) {
  std::array<uint16_t, 2> code;
  EncodeNormal(&n[0], code.data());
  return code;
}

vcg::Point3f DecodeLodNormal(const std::array<uint16_t, 2>& code) {
  double a[3];
  DecodeConeAxis(code.data(), a);
  return vcg::Point3f(float(a[0]), float(a[1]), float(a[2]));
}

Status WriteLodFile(const IndexedMesh& mesh, const LodDag& dag, const std::string& path, LodBuildStats* stats,
                    const Progress& progress, double precision, int threads) {
  if (dag.levels.size() < 1) return Status::Invalid("the LOD DAG has no level");
  if (dag.levels[0].faces != mesh.faces || mesh.faces.empty() || dag.inputVertices != mesh.positions.size() ||
      dag.positions.size() < mesh.positions.size())
    return Status::Invalid("the LOD DAG does not match the mesh");
  return WriteLodFileFrom(dag, nullptr, mesh.positions.size(), mesh.faces.size(), UsedVertexBox(mesh), path, stats,
                          progress, precision, threads);
}

Status WriteLodFileFrom(const LodDag& dag, const LodSpill* spill, size_t inputVertices, size_t inputFaces,
                        const vcg::Box3d& box, const std::string& path, LodBuildStats* stats, const Progress& progress,
                        double precision, int threadCount) {
  StageLog::Laps laps;
  const auto t0 = std::chrono::steady_clock::now();
  const unsigned threads = threadCount > 0 ? unsigned(threadCount) : CoreCount();
  const size_t H = dag.levels.size();
  if (H < 1) return Status::Invalid("the LOD DAG has no level");
  if (H > kMaxLevels) return Status::Invalid("too many LOD levels for the file format");
  if (inputFaces == 0 || dag.inputVertices != inputVertices || dag.positions.size() < inputVertices)
    return Status::Invalid("the LOD DAG does not match the mesh");
  if (dag.positions.size() >= kNoParent) return Status::Invalid("too many vertices for the file format");
  {
    const std::string bad = dag.attributes.Check(dag.positions.size());
    if (!bad.empty()) return Status::Invalid(bad);
  }
  // Attribute streams (the header's attributes field and every blob's flags); none: 0.
  const LodAttributes& attributes = dag.attributes;
  const uint32_t attributeMask = (attributes.colors.empty() ? 0u : kGeomColors) |
                                 (attributes.normals.empty() ? 0u : kGeomNormals) |
                                 (attributes.texCoords.empty() ? 0u : kGeomTexCoords);
  LevelFaces level(dag, spill);
  if (level.count(0) != inputFaces) return Status::Invalid("the LOD DAG does not match the mesh");
  // The box of the positions the levels use (the grid's span), found while checking them: the
  // faces side by side, a box a block of faces, the blocks' boxes added in order (as the faces
  // were one by one: of equal coordinates, such as 0 and -0, the first stays).
  vcg::Box3f span;
  constexpr size_t kSpanBlock = size_t(1) << 15;
  std::vector<vcg::Box3f> blockSpan;
  for (size_t k = 0; k < H; ++k) {
    const LodDag::Level& L = dag.levels[k];
    const std::string bad = "LOD level " + std::to_string(k) + " is inconsistent";
    const size_t C = L.clusterCount();
    for (size_t part = 0; part < level.parts(k); ++part) {
      Status s = level.load(k, part);
      if (!s.ok()) return s;
      const auto& faces = level.faces();
      const auto& faceCluster = level.faceCluster();
      if (faceCluster.size() != faces.size() || L.clusterCreator.size() != C || L.clusterError.size() != C || C == 0 ||
          (k > 0 && L.clusterTypical.size() != C))
        return Status::Invalid(bad);
      std::atomic<bool> badCluster(false), badVertex(false);
      blockSpan.assign((faces.size() + kSpanBlock - 1) / kSpanBlock, vcg::Box3f());
      ParallelChunks(faces.size(), threads, kSpanBlock, [&](size_t from, size_t to, unsigned) {
        vcg::Box3f& box = blockSpan[from / kSpanBlock];
        for (size_t f = from; f < to; ++f) {
          if (faceCluster[f] >= C) badCluster = true;
          for (uint32_t v : faces[f]) {
            if (v < dag.positions.size())
              box.Add(dag.positions[v]);
            else
              badVertex = true;
          }
        }
      });
      if (badCluster) return Status::Invalid(bad);
      if (badVertex) return Status::Invalid(bad + " (a bad vertex index)");
      for (const vcg::Box3f& b : blockSpan) span.Add(b);
    }
    const size_t groupsBelow = k ? dag.levels[k - 1].groupError.size() : 0;
    for (size_t c = 0; c < C; ++c) {
      if (k == 0 ? L.clusterCreator[c] != -1 : (L.clusterCreator[c] < 0 || size_t(L.clusterCreator[c]) >= groupsBelow))
        return Status::Invalid(bad + " (a bad creator group)");
      const int g = L.clusterGroup[c];
      if (k + 1 == H ? g != -1 : (g < 0 || size_t(g) >= L.groupError.size()))
        return Status::Invalid(bad + " (a bad group)");
    }
  }
  const uint32_t nodeLevels = uint32_t(H);

  laps.Mark("write: check, box");
  // Node order within a level: by group (so a group's clusters, a node's children, are
  // consecutive), then by creator, then by cluster index.
  std::vector<std::vector<uint32_t>> clusterOfNode(H), nodeOfCluster(H);
  for (size_t k = 0; k < H; ++k) {
    const LodDag::Level& L = dag.levels[k];
    auto& order = clusterOfNode[k];
    order.resize(L.clusterCount());
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
      if (L.clusterGroup[a] != L.clusterGroup[b]) return L.clusterGroup[a] < L.clusterGroup[b];
      return L.clusterCreator[a] < L.clusterCreator[b];
    });
    nodeOfCluster[k].assign(order.size(), 0);
    for (size_t i = 0; i < order.size(); ++i) nodeOfCluster[k][order[i]] = uint32_t(i);
  }
  std::vector<uint64_t> firstId(nodeLevels + 1, 0);
  {
    uint64_t id = 0;
    for (int k = int(nodeLevels) - 1; k >= 0; --k) {
      firstId[size_t(k)] = id;
      id += clusterOfNode[size_t(k)].size();
    }
    firstId[nodeLevels] = id;
    if (id >= kNoParent) return Status::Invalid("too many nodes for the file format");
  }
  const uint64_t nodeCount = firstId[nodeLevels];
  laps.Mark("write: node order");
  // Node ids per cluster, per level.
  std::vector<std::vector<uint32_t>> idOfCluster(H);
  for (size_t k = 0; k < H; ++k) {
    idOfCluster[k].resize(nodeOfCluster[k].size());
    for (size_t c = 0; c < nodeOfCluster[k].size(); ++c) idOfCluster[k][c] = uint32_t(firstId[k] + nodeOfCluster[k][c]);
  }

  std::vector<float> levelError(nodeLevels, 0.f);
  for (size_t k = 0; k < H; ++k)
    for (float e : dag.levels[k].clusterError) levelError[k] = std::max(levelError[k], e);

  // The grid: over every position a level uses (a collapse may place a vertex outside the input's
  // box). Records (spheres, cones) are computed from the positions as they will be read.
  LodGrid grid;
  {
    for (const auto& p : dag.positions)
      if (!std::isfinite(p[0] + p[1] + p[2])) return Status::Invalid("the LOD DAG has a non-finite position");
    if (!(precision >= kMinLodPrecision && precision <= kMaxLodPrecision))
      return Status::Invalid("the LOD precision must be between 1e-9 and 0.01 of the diagonal");
    // Six significant digits: MeshLab's dialog holds the precision as a float (2e-5 arrives as
    // 1.99999999e-5), and the filter must write the CLI's file byte for byte.
    char digits[32];
    std::snprintf(digits, sizeof digits, "%.6g", precision);
    grid = ChooseLodGrid(span, std::strtod(digits, nullptr));
  }
  // A position as it will be read (computed when needed: a copy of every position is 12 bytes a
  // vertex of the DAG at the peak).
  auto rounded = [&](uint32_t v) { return grid.Round(dag.positions[v]); };

  laps.Mark("write: grid");
  // Pass 1: node records (and the per-level counts), the nodes of a part side by side on `threads`
  // threads (each writes its own nodes' records).
  std::vector<NodeRecord> records(nodeCount);
  std::vector<uint64_t> levelFaces(nodeLevels, 0);
  {
    std::vector<uint32_t> start, faces;
    struct RecordScratch {
      std::vector<vcg::Point3d> normals;
      std::vector<vcg::Point3f> corners;  // the node's face corners as they will be read
      // The node's vertices, counted once each: an open-addressing set (id + 1; 0: empty).
      std::vector<uint32_t> slots;
    };
    std::vector<RecordScratch> scratch(threads);
    std::vector<uint32_t> byGroupStart, byGroup, byCreatorStart, byCreator, aboveStart, above;
    for (uint32_t k = 0; k < nodeLevels; ++k) {
      if (progress && !progress(int(30 * k / nodeLevels), "LOD file: node records")) return Status::Cancelled();
      const LodDag::Level& L = dag.levels[k];
      levelFaces[k] = level.count(k);
      ListBy(L.clusterCreator, k ? dag.levels[k - 1].groupError.size() : 0, idOfCluster[k], byCreatorStart, byCreator);
      if (k > 0)
        ListBy(dag.levels[k - 1].clusterGroup, dag.levels[k - 1].groupError.size(), idOfCluster[k - 1], byGroupStart,
               byGroup);
      if (k + 1 < nodeLevels)
        ListBy(dag.levels[k + 1].clusterCreator, L.groupError.size(), idOfCluster[k + 1], aboveStart, above);
      for (size_t part = 0; part < level.parts(k); ++part) {
        Status s = level.load(k, part);
        if (!s.ok()) return s;
        const auto& levelFaceList = level.faces();
        BucketFaces(level.faceCluster(), nodeOfCluster[k], start, faces);
        uint32_t n0 = 0, n1 = uint32_t(clusterOfNode[k].size());
        if (level.parts(k) > 1) NodeRange(level.faceCluster(), nodeOfCluster[k], n0, n1);
        std::atomic<bool> notConsecutive(false);
        ParallelChunks(n1 - n0, threads, 64, [&](size_t from, size_t to, unsigned thread) {
          RecordScratch& S = scratch[thread];
          std::vector<vcg::Point3d>& normals = S.normals;
          for (uint32_t i = n0 + uint32_t(from); i < n0 + uint32_t(to); ++i) {
            const uint32_t c = clusterOfNode[k][i];
            NodeRecord& R = records[firstId[k] + i];
            R.level = k;
            R.error = L.clusterError[c];
            if (k == 0) {
              R.siblings.assign(1, uint32_t(firstId[k] + i));
            } else {
              const size_t cr = size_t(L.clusterCreator[c]);
              R.typical = std::max(0.f, std::min(R.error, L.clusterTypical[c]));
              R.children.assign(byGroup.begin() + byGroupStart[cr], byGroup.begin() + byGroupStart[cr + 1]);
              R.siblings.assign(byCreator.begin() + byCreatorStart[cr], byCreator.begin() + byCreatorStart[cr + 1]);
              // A group's clusters have consecutive ids (the node order): the file stores the range.
              if (R.children.empty() || R.children.back() - R.children.front() + 1 != R.children.size()) {
                notConsecutive = true;
                return;
              }
            }
            if (L.clusterGroup[c] >= 0) {
              const size_t g = size_t(L.clusterGroup[c]);
              R.group = uint32_t(g);
              R.parentError = L.groupError[g];
              R.parents.assign(above.begin() + aboveStart[g], above.begin() + aboveStart[g + 1]);
            } else {
              R.parentError = std::numeric_limits<float>::infinity();
            }
            normals.clear();
            S.corners.clear();
            size_t mask = 63;
            while (mask + 1 < 6 * size_t(start[i + 1] - start[i])) mask = mask << 1 | 1;
            S.slots.assign(mask + 1, 0);
            uint32_t vc = 0;
            vcg::Box3f nb;
            for (uint32_t j = start[i]; j < start[i + 1]; ++j) {
              const auto& t = levelFaceList[faces[j]];
              const vcg::Point3f r0 = rounded(t[0]), r1 = rounded(t[1]), r2 = rounded(t[2]);
              S.corners.push_back(r0);
              S.corners.push_back(r1);
              S.corners.push_back(r2);
              const vcg::Point3d a = vcg::Point3d::Construct(r0), b = vcg::Point3d::Construct(r1),
                                 cc = vcg::Point3d::Construct(r2);
              const vcg::Point3d n = (b - a) ^ (cc - a);
              const double len = n.Norm();
              const double scale = std::max({(b - a).SquaredNorm(), (cc - a).SquaredNorm(), (cc - b).SquaredNorm()});
              if (len > 1e-12 * scale && len > 0) normals.push_back(n / len);
              for (int q = 0; q < 3; ++q) {
                const uint32_t key = t[size_t(q)] + 1;
                size_t h = size_t((uint64_t(key) * 0x9E3779B97F4A7C15ull) >> 32) & mask;
                while (S.slots[h] && S.slots[h] != key) h = (h + 1) & mask;
                if (!S.slots[h]) {
                  S.slots[h] = key;
                  ++vc;
                }
                nb.Add(q == 0 ? r0 : q == 1 ? r1 : r2);
              }
            }
            R.cone = normals.empty() ? NormalCone::Empty() : MinimalCone(normals);
            R.faceCount = start[i + 1] - start[i];
            R.vertexCount = vc;
            R.center = nb.IsNull() ? vcg::Point3f(0, 0, 0) : nb.Center();
            float r2 = 0;
            for (const vcg::Point3f& r : S.corners) r2 = std::max(r2, (r - R.center).SquaredNorm());
            R.radius = std::sqrt(r2) * (1 + 1e-6f);
          }
        });
        if (notConsecutive) return Status::Invalid("internal error: the children of a LOD node are not consecutive");
      }
    }
  }

  OutFile out;
  const std::string openError = out.open(path);
  if (!openError.empty()) return Status::Invalid(openError);
  auto fail = [&](const std::string& why) {  // the user's file is untouched: only the temporary goes
    out.abandon();
    return Status::Invalid(why);
  };

  laps.Mark("write: pass 1 records");
  // The root chunk's header and data, rewritten at the end with the final offsets.
  uint64_t hierOffset = 0, geosOffset = 0, indexOffset = 0, globalVertices = 0, textureOffset = 0;
  uint64_t positionBytes = 0, indexBytes = 0, idBytes = 0;  // the codecs' output, for the stats
  uint64_t colorBytes = 0, normalBytes = 0, texCoordBytes = 0;
  auto encodeHeader = [&]() {
    Encoder e;
    e.u32(kVersion);
    e.u32(nodeLevels);
    e.u64(inputVertices);
    e.u64(inputFaces);
    e.u64(nodeCount);
    e.u64(globalVertices);
    for (int i = 0; i < 3; ++i) e.f32(box.IsNull() ? 0.f : float(box.min[i]));
    for (int i = 0; i < 3; ++i) e.f32(box.IsNull() ? 0.f : float(box.max[i]));
    e.u64(hierOffset);
    e.u64(geosOffset);
    e.u64(indexOffset);
    for (int i = 0; i < 3; ++i) e.f64(grid.origin[i]);
    e.f64(grid.step);
    e.u32(grid.bits);
    e.u32(kIndexBlock);
    for (uint32_t k = 0; k < nodeLevels; ++k) {
      e.u64(levelFaces[k]);
      e.u64(clusterOfNode[k].size());
      e.u64(firstId[k]);
      e.f32(levelError[k]);
      e.u32(0);
    }
    e.u32(attributeMask);  // 0: geometry only
    e.u32(0);
    if (attributeMask & kGeomTexCoords) {  // texture coordinates: the UV box and the image
      for (int c = 0; c < 2; ++c) e.f32(attributes.uvMin[c]);
      for (int c = 0; c < 2; ++c) e.f32(attributes.uvMax[c]);
      e.u64(textureOffset);
    }
    return e;
  };
  Encoder header = encodeHeader();
  const uint64_t headerBytes = header.bytes.size();
  out.chunk(kRoot, header);  // placeholder: rewritten at the end

  // The texture image (with texture coordinates and an image): its bytes as they are.
  if (!attributes.texture.empty()) {
    textureOffset = out.offset();
    Encoder e;
    e.u32(uint32_t(attributes.texture.name.size()));
    e.u32(uint32_t(attributes.texture.mime.size()));
    e.u64(attributes.texture.bytes.size());
    e.raw(attributes.texture.name.data(), attributes.texture.name.size());
    e.raw(attributes.texture.mime.data(), attributes.texture.mime.size());
    e.raw(attributes.texture.bytes.data(), attributes.texture.bytes.size());
    out.chunk(kTexture, e);
  }

  // A container of packed blobs (HIER, GEOS): its CRC field is 0, each blob carries its own.
  auto patchContainer = [&](uint32_t id, uint64_t at) {
    ChunkHeader h;
    h.id = id;
    h.dataBytes = out.offset() - at - kChunkHeaderBytes;
    Encoder he;
    EncodeChunkHeader(he, h);
    out.patch(at, he);
  };
  // Appends a blob: the CRC of `e`, then `e`.
  auto blob = [&](const Encoder& e) {
    Encoder c;
    c.u32(Crc32(e.bytes.data(), e.bytes.size()));
    return out.write(c) && out.write(e);
  };

  laps.Mark("write: header");
  // Node records, coarsest level first (node id order).
  std::vector<uint64_t> recordEnd(nodeCount), geometryEnd(nodeCount);  // offsets past each blob
  hierOffset = out.offset();
  {
    Encoder none;
    out.chunk(kHier, none);  // placeholder for the size
    Encoder e;
    auto idList = [&](const std::vector<uint32_t>& ids, uint64_t levelFirst) {
      e.uv(ids.size());
      uint64_t last = levelFirst;
      for (uint32_t n : ids) {  // sorted, distinct: first as an offset into its level, then gaps - 1
        e.uv(n - last);
        last = uint64_t(n) + 1;
      }
    };
    uint32_t groupFirst = 0;  // the first record of the current node's group
    for (uint32_t id = 0; id < nodeCount; ++id) {
      const NodeRecord& R = records[id];
      e.clear();
      // The cone: its axis in octahedral u16, its angle widened by the axis's rounding (so that it
      // still holds every normal of the node's faces) and rounded up.
      uint16_t oct[2] = {0, 0};
      uint16_t angle = kEmptyConeAngle;
      if (R.cone.halfAngle >= 0) {
        const double axis[3] = {R.cone.axis[0], R.cone.axis[1], R.cone.axis[2]};
        double back[3];
        EncodeConeAxis(axis, oct);
        DecodeConeAxis(oct, back);
        const double an = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
        const double dot = an > 0 ? (axis[0] * back[0] + axis[1] * back[1] + axis[2] * back[2]) / an : -1;
        const double half = R.cone.halfAngle + std::acos(std::max(-1.0, std::min(1.0, dot))) + 1e-6;
        angle = uint16_t(std::min(65534.0, std::ceil(half / kConeAngleUnit)));
      }
      e.u16(oct[0]);
      e.u16(oct[1]);
      e.u16(angle);
      for (int i = 0; i < 3; ++i) e.f32(R.center[i]);
      e.f32(R.radius);
      if (R.level > 0) {  // 0 at level 0
        e.f32(R.error);
        e.f32(R.typical);
      }
      e.uv(R.group == LodNode::kNoGroup ? 0 : uint64_t(R.group) + 1);
      e.uv(R.faceCount);
      e.uv(R.vertexCount);
      e.uv(R.children.size());
      if (!R.children.empty()) e.uv(R.children.front() - firstId[R.level - 1]);
      idList(R.siblings, firstId[R.level]);
      // A group's clusters are consecutive and share parentError and parents: the group's first
      // record holds them, the others name it (how many ids back).
      if (id == firstId[R.level] || records[id - 1].group != R.group) groupFirst = id;
      if (R.group != LodNode::kNoGroup && groupFirst != id) {
        e.uv(id - groupFirst);
      } else {
        e.uv(0);
        e.f32(R.parentError);
        idList(R.parents, R.level + 1 < nodeLevels ? firstId[R.level + 1] : 0);
      }
      blob(e);
      recordEnd[id] = out.offset();
    }
    patchContainer(kHier, hierOffset);
  }
  records.clear();
  records.shrink_to_fit();

  laps.Mark("write: HIER");
  // Geometry, coarsest level first (node id order), one blob per *unit*: the clusters of one group
  // (a node's children, read together when it is refined; consecutive ids) or, at the top, all
  // the roots. A unit's vertices are stored once (in the order its faces first use them, the faces
  // ordered node by node for the vertex cache), quantized on the grid relative to the unit's
  // smallest corner; then its faces; then which vertices are new to the file (their global ids
  // follow on) and the global ids of the others.
  // The units are encoded on `threads` threads a window at a time (WindowFaces): each unit's blob
  // but its global ids side by side (EncodeUnit: no coder's state runs from one unit to the next),
  // then the global ids unit by unit in file order (the only state that does), then the blobs
  // finished side by side (FinishUnit) and written in order: the same bytes for every thread
  // count, with the window's blobs, not the file's, in memory.
  geosOffset = out.offset();
  std::vector<uint64_t> geometryStart(nodeCount);
  {
    Encoder none;
    out.chunk(kGeos, none);  // placeholder for the size
    std::vector<uint32_t> start, faces, unitStart;
    std::vector<uint32_t> fileId(dag.positions.size(), kNoParent);
    std::vector<std::unique_ptr<UnitScratch>> scratch(threads);
    auto scratchOf = [&](unsigned thread) -> UnitScratch& {
      if (!scratch[thread]) scratch[thread].reset(new UnitScratch());
      return *scratch[thread];
    };
    const uint64_t windowFaces = WindowFaces(threads);
    meshopt_encodeVertexVersion(kVertexCodecVersion);
    meshopt_encodeIndexVersion(kIndexCodecVersion);
    for (int k = int(nodeLevels) - 1; k >= 0; --k) {
      if (progress && !progress(30 + int(65 * (int(nodeLevels) - 1 - k) / int(nodeLevels)), "LOD file: geometry")) {
        fail("cancelled");  // removes the partial file
        return Status::Cancelled();
      }
      const LodDag::Level& L = dag.levels[size_t(k)];
      const auto& order = clusterOfNode[size_t(k)];
      const size_t nodes = order.size();
      for (size_t part = 0; part < level.parts(size_t(k)); ++part) {
        {
          const Status s = level.load(size_t(k), part);
          if (!s.ok()) return fail(s.message);
        }
        const auto& levelFaceList = level.faces();
        BucketFaces(level.faceCluster(), nodeOfCluster[size_t(k)], start, faces);
        uint32_t n0 = 0, n1 = uint32_t(nodes);
        if (level.parts(size_t(k)) > 1) NodeRange(level.faceCluster(), nodeOfCluster[size_t(k)], n0, n1);
        unitStart.clear();  // the part's units: nodes [unitStart[j], unitStart[j + 1])
        for (uint32_t u0 = n0; u0 < n1;) {
          unitStart.push_back(u0);
          uint32_t u1 = u0 + 1;
          while (u1 < n1 && L.clusterGroup[order[u1]] == L.clusterGroup[order[u0]]) ++u1;
          u0 = u1;
        }
        unitStart.push_back(n1);
        const UnitInput in{levelFaceList, start,      faces,         dag.positions,
                           grid,          attributes, attributeMask, firstId[size_t(k)]};
        const size_t units = unitStart.size() - 1;
        for (size_t w0 = 0; w0 < units;) {
          size_t w1 = w0;
          for (uint64_t f = 0; w1 < units && f < windowFaces; ++w1)
            f += start[unitStart[w1 + 1]] - start[unitStart[w1]];
          std::vector<EncodedUnit> window(w1 - w0);
          ParallelChunks(window.size(), threads, 1, [&](size_t b, size_t e, unsigned thread) {
            for (size_t j = b; j < e; ++j)
              EncodeUnit(in, unitStart[w0 + j], unitStart[w0 + j + 1], scratchOf(thread), window[j]);
          });
          // Which vertices are new to the file, in file order.
          for (EncodedUnit& U : window) {
            if (U.error) return fail(U.error);
            const size_t vc = U.verts.size();
            U.firstGlobal = globalVertices;
            U.mask.assign((vc + 7) / 8, 0);
            for (size_t v = 0; v < vc; ++v) {
              uint32_t& f = fileId[U.verts[v]];
              if (f == kNoParent) {
                f = uint32_t(globalVertices++);
                U.mask[v / 8] = uint8_t(U.mask[v / 8] | 1u << (v % 8));
              } else {
                U.old.push_back(f);
              }
            }
            U.globalAfter = globalVertices;
            if (globalVertices >= kNoParent) return fail("too many vertices for the file format");
          }
          ParallelChunks(window.size(), threads, 1, [&](size_t b, size_t e, unsigned thread) {
            for (size_t j = b; j < e; ++j) FinishUnit(window[j], scratchOf(thread));
          });
          for (size_t j = 0; j < window.size(); ++j) {
            const EncodedUnit& U = window[j];
            if (U.error) return fail(U.error);
            const uint64_t at = out.offset();
            Encoder c;
            c.u32(U.crc);
            out.write(c);
            out.write(U.blob);
            for (uint32_t i = unitStart[w0 + j]; i < unitStart[w0 + j + 1]; ++i) {
              geometryStart[firstId[size_t(k)] + i] = at;
              geometryEnd[firstId[size_t(k)] + i] = out.offset();
            }
            positionBytes += U.positionBytes;
            indexBytes += U.indexBytes;
            idBytes += U.idBytes;
            colorBytes += U.colorBytes;
            normalBytes += U.normalBytes;
            texCoordBytes += U.texCoordBytes;
          }
          w0 = w1;
        }
      }
      if (!out.ok()) return fail(out.error());
    }
    patchContainer(kGeos, geosOffset);
  }

  laps.Mark("write: GEOS");
  // The offset index (version 6), in blocks of kIndexBlock entries: each block gives the offsets
  // of its first record and its first node's geometry blob, then per entry its record's size and,
  // when the entry starts a new blob (not its unit's previous node), that blob's size, as varints;
  // the INDX chunk's data lists where each block starts, so that one block is read alone.
  indexOffset = out.offset();
  {
    const uint64_t blocks = (nodeCount + kIndexBlock - 1) / kIndexBlock;
    const uint64_t hierData = hierOffset + kChunkHeaderBytes;
    std::vector<Encoder> blockData(static_cast<size_t>(blocks));
    Encoder e;
    e.u64(nodeCount);
    e.u32(kIndexBlock);
    e.u32(0);
    uint64_t childBytes = 0;
    for (uint64_t b = 0; b < blocks; ++b) {
      if (childBytes > 0xFFFFFFFFu) return fail("too many nodes for the file format's index");
      e.u32(uint32_t(childBytes));
      Encoder& d = blockData[size_t(b)];
      const uint64_t first = b * kIndexBlock, end = std::min<uint64_t>(nodeCount, (b + 1) * kIndexBlock);
      uint64_t record = first ? recordEnd[first - 1] : hierData;
      d.u64(record);
      d.u64(geometryStart[first]);
      for (uint64_t i = first; i < end; ++i) {
        // (Nodes of one unit share its blob: the same start.)
        const bool newBlob = i == first || geometryStart[i] != geometryStart[i - 1];
        d.uv((recordEnd[i] - record - kRecordFixedBytes) * 2 + (newBlob ? 1 : 0));
        if (newBlob) d.uv(geometryEnd[i] - geometryStart[i]);
        record = recordEnd[i];
      }
      childBytes += kChunkHeaderBytes + d.bytes.size();
    }
    out.chunk(kIndex, e, childBytes);
    for (const Encoder& d : blockData) out.chunk(kIBlock, d);
  }
  const uint64_t fileBytes = out.offset();
  {
    header = encodeHeader();
    if (header.bytes.size() != headerBytes) return fail("internal error: header size changed");
    ChunkHeader h;
    h.id = kRoot;
    h.dataBytes = headerBytes;
    h.crc = Crc32(header.bytes.data(), header.bytes.size());
    h.childBytes = fileBytes - kChunkHeaderBytes - headerBytes;
    Encoder e;
    EncodeChunkHeader(e, h);
    e.bytes.insert(e.bytes.end(), header.bytes.begin(), header.bytes.end());
    out.patch(0, e);
  }
  if (!out.close()) return fail(out.error());
  if (progress) progress(100, "LOD file: written");

  if (stats) {
    stats->inputVertices = inputVertices;
    stats->inputFaces = inputFaces;
    stats->levels = int(nodeLevels);
    stats->levelFaces.assign(levelFaces.begin(), levelFaces.end());
    stats->levelNodes.clear();
    for (uint32_t k = 0; k < nodeLevels; ++k) stats->levelNodes.push_back(clusterOfNode[k].size());
    stats->nodes = size_t(nodeCount);
    stats->fileBytes = fileBytes;
    stats->recordBytes = geosOffset - hierOffset;
    stats->positionBytes = positionBytes;
    stats->triangleBytes = indexBytes;
    stats->vertexIdBytes = idBytes;
    stats->colorBytes = colorBytes;
    stats->normalBytes = normalBytes;
    stats->texCoordBytes = texCoordBytes;
    stats->textureBytes = attributes.texture.bytes.size();
    stats->quantizationError = grid.ErrorBound();
    stats->writeSeconds = Seconds(t0);
  }
  laps.Mark("write: index, close");
  return Status::Ok();
}

int LodWriterThreads(const LodBuildParams& params) {
  int threads = params.simplification.threads > 0 ? params.simplification.threads : int(CoreCount());
  if (params.chunkFaces > 0) threads = int(std::max<size_t>(1, std::min<size_t>(threads, params.chunkFaces / 2048)));
  return threads;
}

namespace {

// BuildLodFile of the welded mesh `welded` (taken: left empty). With chunks (--memory) the finished
// levels go to a temporary folder beside the output (lod_spill.h), removed before returning.
Status BuildWelded(IndexedMesh&& welded, size_t merged, size_t dropped, const LodAttributes* attributes,
                   size_t attributeConflicts, const LodBuildParams& params, const std::string& path,
                   LodBuildStats* stats, const Progress& progress, std::chrono::steady_clock::time_point t0) {
  const size_t inputVertices = welded.positions.size(), inputFaces = welded.faces.size();
  const vcg::Box3d box = UsedVertexBox(welded);
  LodSpill spill;
  if (params.chunkFaces > 0) {
    const std::string err = spill.create(path);
    if (!err.empty()) return Status::Invalid(err);
  }
  LodDag dag;
  size_t chunks = 1;
  Status s = BuildLodDagOwned(std::move(welded), params, dag, SubProgress(progress, 0, 90), &chunks,
                              params.chunkFaces > 0 ? &spill : nullptr, attributes);
  if (!s.ok()) return s;
  const double dagSeconds = Seconds(t0);
  s = WriteLodFileFrom(dag, params.chunkFaces > 0 ? &spill : nullptr, inputVertices, inputFaces, box, path, stats,
                       SubProgress(progress, 90, 100), params.precision, LodWriterThreads(params));
  if (!s.ok()) return s;
  if (stats) {
    stats->chunks = chunks;
    stats->mergedVertices = merged;
    stats->droppedVertices = dropped;
    stats->attributeConflicts = attributeConflicts;
    stats->groupingSeconds = 0;
    stats->simplifySeconds = dagSeconds;
    stats->seconds = Seconds(t0);
  }
  return Status::Ok();
}

}  // namespace

Status BuildLodFile(const IndexedMesh& mesh, const LodBuildParams& params, const std::string& path,
                    LodBuildStats* stats, const Progress& progress, const LodAttributes* attributes) {
  const auto t0 = std::chrono::steady_clock::now();
  Status s = RequireValidForFaces(mesh);
  if (!s.ok()) return s;
  if (attributes) {
    const std::string bad = attributes->Check(mesh.positions.size());
    if (!bad.empty()) return Status::Invalid(bad);
  }
  // Vertices at one position are one vertex of the DAG (a seam the file repeats would otherwise be
  // simplified from each side on its own, and the cuts would open along it); unreferenced vertices
  // are not written.
  WeldResult welded = WeldByPosition(mesh);
  // The welded vertices' attributes: their representative's.
  LodAttributes weldedAttributes;
  size_t conflicts = 0;
  const bool withAttributes = attributes && !attributes->empty();
  if (withAttributes) {
    const std::vector<uint32_t>& rep = welded.representative;
    for (uint32_t r : rep) {
      if (!attributes->colors.empty()) weldedAttributes.colors.push_back(attributes->colors[r]);
      if (!attributes->normals.empty()) weldedAttributes.normals.push_back(attributes->normals[r]);
    }
    // Input vertices welded into another whose values differ.
    std::vector<uint32_t> welded1(mesh.positions.size(), kNoParent);
    for (size_t f = 0; f < mesh.faces.size(); ++f)
      for (int k = 0; k < 3; ++k) welded1[mesh.faces[f][size_t(k)]] = welded.mesh.faces[f][size_t(k)];
    for (size_t v = 0; v < welded1.size(); ++v) {
      if (welded1[v] == kNoParent) continue;
      const uint32_t r = rep[welded1[v]];
      if ((!attributes->colors.empty() && attributes->colors[v] != attributes->colors[r]) ||
          (!attributes->normals.empty() && attributes->normals[v] != attributes->normals[r]))
        ++conflicts;
    }
  }
  size_t merged = welded.mergedVertices;
  if (withAttributes && !attributes->texCoords.empty()) {
    // Texture coordinates: one DAG vertex per (position, UV), a wedge; the wedges of a position
    // share it (and its colour and normal: the representative's) and are one place of the DAG.
    for (int c = 0; c < 2; ++c) {
      weldedAttributes.uvMin[c] = attributes->uvMin[c];
      weldedAttributes.uvMax[c] = attributes->uvMax[c];
    }
    weldedAttributes.texture = attributes->texture;
    const IndexedMesh& wm = welded.mesh;
    std::vector<uint64_t> keys;  // position << 32 | uv code, per face corner
    keys.reserve(3 * wm.faces.size());
    auto keyOf = [&](size_t f, size_t k) {
      const auto& uv = attributes->texCoords[mesh.faces[f][k]];
      return uint64_t(wm.faces[f][k]) << 32 | uint64_t(uv[0]) << 16 | uv[1];
    };
    for (size_t f = 0; f < wm.faces.size(); ++f)
      for (size_t k = 0; k < 3; ++k) keys.push_back(keyOf(f, k));
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    IndexedMesh wedgeMesh;
    LodAttributes& A = weldedAttributes;
    LodAttributes byPosition;
    byPosition.colors.swap(A.colors);
    byPosition.normals.swap(A.normals);
    wedgeMesh.positions.reserve(keys.size());
    for (size_t i = 0; i < keys.size(); ++i) {
      const uint32_t pos = uint32_t(keys[i] >> 32);
      wedgeMesh.positions.push_back(wm.positions[pos]);
      if (!byPosition.colors.empty()) A.colors.push_back(byPosition.colors[pos]);
      if (!byPosition.normals.empty()) A.normals.push_back(byPosition.normals[pos]);
      A.texCoords.push_back({{uint16_t(keys[i] >> 16 & 0xFFFF), uint16_t(keys[i] & 0xFFFF)}});
      A.place.push_back(i > 0 && (keys[i - 1] >> 32) == pos ? A.place.back() : uint32_t(i));
    }
    wedgeMesh.faces.resize(wm.faces.size());
    for (size_t f = 0; f < wm.faces.size(); ++f)
      for (size_t k = 0; k < 3; ++k)
        wedgeMesh.faces[f][k] = uint32_t(std::lower_bound(keys.begin(), keys.end(), keyOf(f, k)) - keys.begin());
    merged -= keys.size() - wm.positions.size();  // the wedges beyond one a position were not merged
    welded.mesh = std::move(wedgeMesh);
  }
  return BuildWelded(std::move(welded.mesh), merged, welded.droppedVertices,
                     withAttributes ? &weldedAttributes : nullptr, conflicts, params, path, stats, progress, t0);
}

Status BuildLodFile(IndexedMesh&& mesh, const LodBuildParams& params, const std::string& path, LodBuildStats* stats,
                    const Progress& progress, const LodAttributes* attributes) {
  // Attributes need the weld's representatives (the copying weld); without them the mesh is welded
  // in place.
  if (attributes && !attributes->empty()) {
    const IndexedMesh& input = mesh;
    Status s = BuildLodFile(input, params, path, stats, progress, attributes);
    mesh = IndexedMesh();
    return s;
  }
  const auto t0 = std::chrono::steady_clock::now();
  Status s = RequireValidForFaces(mesh);
  if (!s.ok()) return s;
  size_t merged = 0, dropped = 0;
  WeldByPositionInPlace(mesh, &merged, &dropped);  // as WeldByPosition, without a second copy
  return BuildWelded(std::move(mesh), merged, dropped, nullptr, 0, params, path, stats, progress, t0);
}

}  // namespace conelod
