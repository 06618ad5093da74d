// ConeLOD — internals of the .clod file shared by its writer and reader: chunk ids, fixed layouts,
// CRC-32, little-endian encoding. The layout is documented in lod_format.md; keep the two in step.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace conelod {
namespace lodfile {

constexpr uint32_t FourCC(char a, char b, char c, char d) {
  return uint32_t(uint8_t(a)) | uint32_t(uint8_t(b)) << 8 | uint32_t(uint8_t(c)) << 16 | uint32_t(uint8_t(d)) << 24;
}
constexpr uint32_t kRoot = FourCC('C', 'L', 'O', 'D');   // the whole file; its data is the header
constexpr uint32_t kHier = FourCC('H', 'I', 'E', 'R');   // the node records, packed (each with its CRC)
constexpr uint32_t kGeos = FourCC('G', 'E', 'O', 'S');   // the nodes' compressed geometry, packed
constexpr uint32_t kIndex = FourCC('I', 'N', 'D', 'X');  // the offset index, in IBLK blocks
constexpr uint32_t kIBlock = FourCC('I', 'B', 'L', 'K');
constexpr uint32_t kTexture = FourCC('T', 'E', 'X', 'R');  // with texture coordinates: the image

// 9: version 8 plus each record above level 0 holding its creator group's typical distance (f32 after the
// error; LodNode::typical); 8: the positions' residuals range-coded with adaptive models (lod_entropy.h) instead of
// meshoptimizer's vertex codec; 7: each geometry stream (positions, triangles, vertex ids, attributes) deflated when
// that is smaller (a code per stream says which); 6: a compact offset index (varint sizes per entry, a table of where
// each block starts) and the header's attributes field always present (0: geometry only): written; 5: version 4 plus
// per-vertex attribute streams (colour, normals), the attributes field present; 4: a group's
// parentError and parents in its first record only; 3: quantized, compressed nodes (5, 4, 3 are
// still read); 2: float positions per level, refused by name; 1: the tree of groups, refused.
constexpr uint32_t kVersion = 9;                // the newest version read, and the one written
constexpr uint32_t kTypicalVersion = 9;         // the first whose records hold the typical distance
constexpr uint32_t kCodedPositionsVersion = 8;  // the first with range-coded positions (lod_entropy.h)
constexpr uint32_t kDeflateVersion = 7;         // the first whose geometry streams may be deflated
constexpr uint64_t kMaxDeflateRatio = 1032;     // deflate's largest expansion on inflating (RFC 1951)
constexpr uint32_t kAttributeVersion = 5;       // the first with the header's attributes field
constexpr uint32_t kCompactIndexVersion = 6;    // the first with the compact index
constexpr uint32_t kOldestReadVersion = 3;
constexpr uint32_t kMaxLevels = 64;
constexpr uint32_t kNoParent = 0xFFFFFFFFu;
constexpr uint32_t kMaxGridBits = 30;  // grid coordinates below 2^30 (the u32 vertex stream)

// Chunk header: id, CRC-32 of the chunk's own data, size of that data, total size of the
// sub-chunks that follow it (headers included).
constexpr size_t kChunkHeaderBytes = 24;
struct ChunkHeader {
  uint32_t id = 0;
  uint32_t crc = 0;
  uint64_t dataBytes = 0;
  uint64_t childBytes = 0;
  uint64_t totalBytes() const { return kChunkHeaderBytes + dataBytes + childBytes; }
};

// Fixed part of the root chunk's data (then kLevelEntryBytes per level).
constexpr size_t kHeaderFixedBytes = 4 + 4 + 8 * 4 + 4 * 6 + 8 * 3 + 8 * 4 + 4 + 4;  // = 128
constexpr size_t kLevelEntryBytes = 8 * 3 + 4 + 4;                                   // = 32
constexpr size_t kIndexDataBytes = 8 + 4 + 4;   // INDX data = 16 (version 6: then u32 per block)
constexpr size_t kIndexBlockBaseBytes = 8 + 8;  // IBLK: two bases ...
constexpr size_t kIndexEntryBytes = 4 + 4;      // ... then ends (versions 3 to 5)
constexpr size_t kIndexBlockStartBytes = 4;     // version 6: INDX data lists each IBLK's start
// The smallest record: CRC, cone, sphere (version 4: a level-0 record has no error field; version
// 3: 34 bytes, every record with its error and parentError).
constexpr size_t kRecordFixedBytes = 4 + 2 * 3 + 4 * 4;
constexpr uint16_t kEmptyConeAngle = 0xFFFF;  // a record's cone angle: no face normal
constexpr size_t kGeomMinBytes = 4 + 1;       // a geometry blob: CRC, flags, then varints and codecs
constexpr uint8_t kGeomWidePositions = 1;     // geometry flag: positions are u32 x 3 (else u16 x 4)
// Versions 5, 6: attribute streams, announced by the header's `attributes` field and by the same bits
// in every geometry blob's flags (each unit carries every stream the file has).
constexpr uint8_t kGeomColors = 2;     // u8 x 4 RGBA per unit vertex
constexpr uint8_t kGeomNormals = 4;    // octahedral u16 x 2 per unit vertex (EncodeNormal)
constexpr uint8_t kGeomTexCoords = 8;  // u16 x 2 per unit vertex over the header's UV box
constexpr uint32_t kKnownAttributes = kGeomColors | kGeomNormals | kGeomTexCoords;
constexpr size_t kHeaderAttributeBytes = 4 + 4;  // versions 5, 6: u32 attributes, u32 pad after the levels
// With kGeomTexCoords (versions 5, 6): then f32 uvMin[2], f32 uvMax[2], u64 textureOffset (0: none).
constexpr size_t kHeaderTexCoordBytes = 4 * 4 + 8;
// The TEXR chunk's data: u32 nameBytes, u32 mimeBytes, u64 imageBytes, then the three.
constexpr size_t kTextureFixedBytes = 4 + 4 + 8;
constexpr uint32_t kIndexBlock = 512;  // index entries per IBLK (4 KiB)
// meshoptimizer's codec versions written: vertex 0 (every version decodes it), index 1 (0.14+).
constexpr int kVertexCodecVersion = 0;
constexpr int kIndexCodecVersion = 1;

uint32_t Crc32(const void* data, size_t bytes, uint32_t crc = 0);

// Version 6 positions: each unit vertex's grid coordinates (minus the unit's corner) are stored as
// the residual from a prediction made from vertices decoded before it. The faces, as the index
// codec gives them back, are walked in order; a corner not yet visited is predicted by the
// parallelogram across the opposite edge when an earlier face has that edge (a + b - c), else
// that edge's midpoint when both its ends were visited, else a visited corner of the face, else
// the vertex visited last (0 for the first); vertices no face uses come last, in index order,
// from the vertex visited last. Residuals are taken modulo 2^(8 x width) (width: 2 or 4 bytes a
// coordinate) and laid out so that meshoptimizer's vertex codec, which codes each byte's change
// from the previous vertex, sees the residual's signed bytes: byte j of a stored coordinate is
// the running sum (mod 256) of byte j of the residuals of the vertices before it and itself,
// where a residual is written as signed digits d_0 + 256 d_1 + ... (each d in -128..127, the last
// one taken mod 256).
class PositionPredictor {
 public:
  // Walks the unit: visit(v, prediction) for each vertex in the order above; the callback sets
  // q[v] (the writer: the value it knows; the reader: prediction + residual). q holds
  // vertexCount x 3 values below 2^32; corners are below vertexCount (checked by the caller).
  template <typename Visit>
  void Walk(const uint32_t* corners, size_t faceCount, size_t vertexCount, uint64_t* q, Visit visit) {
    // Each face's three directed edges, bucketed by their first vertex in face order (a
    // counting sort): the edge b -> a of the earliest face before f is the first match in b's
    // bucket whose face is below f.
    first_.assign(vertexCount + 1, 0);
    for (size_t i = 0; i < faceCount * 3; ++i) ++first_[corners[i] + 1];
    for (size_t v = 0; v < vertexCount; ++v) first_[v + 1] += first_[v];
    edges_.resize(faceCount * 3);
    fill_.assign(first_.begin(), first_.end() - 1);
    for (size_t f = 0; f < faceCount; ++f)
      for (int k = 0; k < 3; ++k) {
        const uint32_t* t = corners + 3 * f;
        edges_[fill_[t[k]]++] = Edge{t[(k + 1) % 3], t[(k + 2) % 3], uint32_t(f)};
      }
    visited_.assign(vertexCount, 0);
    uint64_t last[3] = {0, 0, 0};
    uint64_t pred[3];
    auto done = [&](uint32_t v) {
      visited_[v] = 1;
      for (int c = 0; c < 3; ++c) last[c] = q[3 * size_t(v) + size_t(c)];
    };
    for (size_t f = 0; f < faceCount; ++f) {
      const uint32_t* t = corners + 3 * f;
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = t[k];
        if (visited_[v]) continue;
        const uint32_t a = t[(k + 1) % 3], b = t[(k + 2) % 3];
        const uint64_t *qa = q + 3 * size_t(a), *qb = q + 3 * size_t(b);
        if (visited_[a] && visited_[b]) {
          uint32_t c = kNone;  // the opposite corner of an earlier face's edge b -> a
          for (uint32_t i = first_[b]; i < first_[b + 1] && edges_[i].face < f; ++i)
            if (edges_[i].to == a) {
              c = edges_[i].opposite;
              break;
            }
          for (int i = 0; i < 3; ++i)
            pred[i] = c != kNone ? qa[i] + qb[i] - q[3 * size_t(c) + size_t(i)] : (qa[i] + qb[i]) >> 1;
          kind_ = c != kNone ? kParallelogram : kMidpoint;
        } else if (visited_[a] || visited_[b]) {
          const uint64_t* qk = visited_[a] ? qa : qb;
          for (int i = 0; i < 3; ++i) pred[i] = qk[i];
          kind_ = kNeighbour;
        } else {
          for (int i = 0; i < 3; ++i) pred[i] = last[i];
          kind_ = kPrevious;
        }
        visit(v, pred);
        done(v);
      }
    }
    for (uint32_t v = 0; v < vertexCount; ++v)
      if (!visited_[v]) {
        for (int i = 0; i < 3; ++i) pred[i] = last[i];
        kind_ = kPrevious;
        visit(v, pred);
        done(v);
      }
  }
  // The kind of the prediction just passed to visit (version 8 codes the residuals by kind).
  enum Kind { kParallelogram = 0, kMidpoint = 1, kNeighbour = 2, kPrevious = 3 };
  int kind() const { return kind_; }
  void Release() {  // its buffers (a reader keeps little between units)
    std::vector<uint8_t>().swap(visited_);
    std::vector<uint32_t>().swap(first_);
    std::vector<uint32_t>().swap(fill_);
    std::vector<Edge>().swap(edges_);
  }
  size_t bytes() const {
    return visited_.capacity() + (first_.capacity() + fill_.capacity()) * 4 + edges_.capacity() * sizeof(Edge);
  }

 private:
  static constexpr uint32_t kNone = 0xFFFFFFFFu;
  struct Edge {
    uint32_t to, opposite, face;
  };
  std::vector<uint8_t> visited_;
  std::vector<uint32_t> first_, fill_;  // per vertex: where its edges start; the next free slot
  std::vector<Edge> edges_;
  int kind_ = kPrevious;
};

// The residual r (mod 2^(8 x width)) as signed byte digits added to the running bytes `lane`.
inline void AddResidualBytes(uint64_t r, int width, uint8_t* lane) {
  int64_t rest = int64_t(r << (64 - 8 * width)) >> (64 - 8 * width);  // r as a signed value
  for (int j = 0; j < width; ++j) {
    const int8_t digit = int8_t(uint8_t(rest & 0xFF));
    lane[j] = uint8_t(lane[j] + uint8_t(digit));
    rest = (rest - digit) >> 8;
  }
}
// The residual (mod 2^(8 x width)) from a vertex's stored bytes and the previous vertex's.
inline uint64_t ResidualFromBytes(const uint8_t* bytes, const uint8_t* previous, int width) {
  uint64_t r = 0;
  for (int j = width - 1; j >= 0; --j) r = (r << 8) + uint64_t(int64_t(int8_t(uint8_t(bytes[j] - previous[j]))));
  return width == 8 ? r : r & ((uint64_t(1) << (8 * width)) - 1);
}

// A record's cone axis: octahedral coordinates in two u16 (the writer widens the angle by the
// axis's rounding, so the cone still holds every normal).
inline void EncodeConeAxis(const double a[3], uint16_t out[2]) {
  const double l1 = std::fabs(a[0]) + std::fabs(a[1]) + std::fabs(a[2]);
  double u = l1 > 0 ? a[0] / l1 : 0, v = l1 > 0 ? a[1] / l1 : 0;
  if (l1 > 0 && a[2] < 0) {
    const double pu = u, pv = v;
    u = (1 - std::fabs(pv)) * (pu >= 0 ? 1 : -1);
    v = (1 - std::fabs(pu)) * (pv >= 0 ? 1 : -1);
  }
  out[0] = uint16_t(std::lround((std::max(-1.0, std::min(1.0, u)) + 1) / 2 * 65535));
  out[1] = uint16_t(std::lround((std::max(-1.0, std::min(1.0, v)) + 1) / 2 * 65535));
}
inline void DecodeConeAxis(const uint16_t in[2], double a[3]) {
  double u = in[0] / 65535.0 * 2 - 1, v = in[1] / 65535.0 * 2 - 1;
  const double z = 1 - std::fabs(u) - std::fabs(v);
  if (z < 0) {
    const double pu = u, pv = v;
    u = (1 - std::fabs(pv)) * (pu >= 0 ? 1 : -1);
    v = (1 - std::fabs(pu)) * (pv >= 0 ? 1 : -1);
  }
  const double n = std::sqrt(u * u + v * v + z * z);
  a[0] = u / n;
  a[1] = v / n;
  a[2] = z / n;
}
// A vertex normal: the cone axis's octahedral code (u16 x 2). Round trip: the decoded unit normal
// is within kLodNormalErrorBound radians of the input's direction (lod_build.h, lod_format.md).
// A zero or non-finite normal encodes as (0, 0, 1)'s code.
inline void EncodeNormal(const float n[3], uint16_t out[2]) {
  const double a[3] = {n[0], n[1], n[2]};
  if (!(std::isfinite(a[0] + a[1] + a[2])) || (a[0] == 0 && a[1] == 0 && a[2] == 0)) {
    const double z[3] = {0, 0, 1};
    EncodeConeAxis(z, out);
    return;
  }
  EncodeConeAxis(a, out);
}

// A record's cone half-angle: units of pi / 65534, rounded up (kEmptyConeAngle: the empty cone).
constexpr double kConeAngleUnit = 3.14159265358979323846 / 65534;

// Appends little-endian fixed-width fields.
class Encoder {
 public:
  std::vector<uint8_t> bytes;
  void u16(uint32_t v) { little(uint16_t(v)); }
  void u32(uint32_t v) { little(v); }
  void u64(uint64_t v) { little(v); }
  void f32(float v) {
    uint32_t u;
    std::memcpy(&u, &v, 4);
    u32(u);
  }
  void f64(double v) {
    uint64_t u;
    std::memcpy(&u, &v, 8);
    u64(u);
  }
  // LEB128: 7 bits a byte, least significant first.
  void uv(uint64_t v) {
    while (v >= 0x80) {
      bytes.push_back(uint8_t(v | 0x80));
      v >>= 7;
    }
    bytes.push_back(uint8_t(v));
  }
  void raw(const void* p, size_t n) {
    const uint8_t* b = static_cast<const uint8_t*>(p);
    bytes.insert(bytes.end(), b, b + n);
  }
  void clear() { bytes.clear(); }

 private:
  template <typename T>
  void little(T v) {
    uint8_t b[sizeof(T)];
    for (size_t i = 0; i < sizeof(T); ++i) b[i] = uint8_t(v >> (8 * i));
    bytes.insert(bytes.end(), b, b + sizeof(T));  // one capacity check per field, not per byte
  }
};

// Reads little-endian fields from a byte range; reading past the end sets `overrun` and yields 0.
class Decoder {
 public:
  Decoder(const uint8_t* p, size_t n) : p_(p), n_(n) {}
  bool overrun = false;
  size_t left() const { return n_ - at_; }
  size_t at() const { return at_; }
  uint32_t u16() { return uint32_t(little<uint16_t>()); }
  uint32_t u32() { return little<uint32_t>(); }
  uint64_t u64() { return little<uint64_t>(); }
  float f32() {
    const uint32_t u = u32();
    float v;
    std::memcpy(&v, &u, 4);
    return v;
  }
  double f64() {
    const uint64_t u = u64();
    double v;
    std::memcpy(&v, &u, 8);
    return v;
  }
  // LEB128 (Encoder::uv); more than 10 bytes, or a value past 64 bits, sets `overrun`.
  uint64_t uv() {
    uint64_t v = 0;
    for (int shift = 0; shift < 64; shift += 7) {
      if (!need(1)) return 0;
      const uint8_t b = p_[at_++];
      if (shift == 63 && b > 1) break;
      v |= uint64_t(b & 0x7F) << shift;
      if (!(b & 0x80)) return v;
    }
    overrun = true;
    at_ = n_;
    return 0;
  }
  // The next n bytes (null and `overrun` when fewer are left).
  const uint8_t* take(size_t n) {
    if (!need(n)) return nullptr;
    const uint8_t* p = p_ + at_;
    at_ += n;
    return p;
  }

 private:
  template <typename T>
  T little() {
    if (!need(sizeof(T))) return 0;
    T v = 0;
    for (size_t i = 0; i < sizeof(T); ++i) v = T(v | T(p_[at_ + i]) << (8 * i));
    at_ += sizeof(T);
    return v;
  }
  bool need(size_t k) {
    if (n_ - at_ < k) {
      overrun = true;
      at_ = n_;
      return false;
    }
    return true;
  }
  const uint8_t* p_;
  size_t n_;
  size_t at_ = 0;
};

inline void EncodeChunkHeader(Encoder& e, const ChunkHeader& h) {
  e.u32(h.id);
  e.u32(h.crc);
  e.u64(h.dataBytes);
  e.u64(h.childBytes);
}
inline ChunkHeader DecodeChunkHeader(const uint8_t* p) {
  Decoder d(p, kChunkHeaderBytes);
  ChunkHeader h;
  h.id = d.u32();
  h.crc = d.u32();
  h.dataBytes = d.u64();
  h.childBytes = d.u64();
  return h;
}
std::string ChunkName(uint32_t id);  // "NODE", or hex for a non-printable id

}  // namespace lodfile
}  // namespace conelod
