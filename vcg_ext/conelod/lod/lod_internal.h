// ConeLOD — internals of the .clod file shared by its writer and reader: chunk ids, fixed layouts,
// CRC-32, little-endian encoding. The layout is documented in lod_format.md; keep the two in step.
#pragma once

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
constexpr uint32_t kHier = FourCC('H', 'I', 'E', 'R');   // container of the node records
constexpr uint32_t kNode = FourCC('N', 'O', 'D', 'E');   // one node record
constexpr uint32_t kLevel = FourCC('L', 'E', 'V', 'L');  // one node level: VERT, then GEOM per node
constexpr uint32_t kVert = FourCC('V', 'E', 'R', 'T');   // a level's shared vertices, in VBLK blocks
constexpr uint32_t kVBlock = FourCC('V', 'B', 'L', 'K');
constexpr uint32_t kGeom = FourCC('G', 'E', 'O', 'M');   // one node's geometry
constexpr uint32_t kIndex = FourCC('I', 'N', 'D', 'X');  // the offset index, in IBLK blocks
constexpr uint32_t kIBlock = FourCC('I', 'B', 'L', 'K');

constexpr uint32_t kVersion = 2;  // 2: the cluster DAG (1: the tree of groups, refused)
constexpr uint32_t kMaxLevels = 64;
constexpr uint32_t kNoParent = 0xFFFFFFFFu;

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
constexpr size_t kHeaderFixedBytes = 4 + 4 + 8 * 4 + 4 * 6 + 8 + 8 + 4 + 4;  // = 88
constexpr size_t kLevelEntryBytes = 8 * 6 + 4 + 4;                           // = 56
constexpr size_t kLevelDataBytes = 4 + 4 + 8 * 3;                            // LEVL data = 32
constexpr size_t kVertDataBytes = 4 + 4 + 8;                                 // VERT data = 16
constexpr size_t kIndexDataBytes = 8 + 4 + 4;                                // INDX data = 16
constexpr size_t kNodeFixedBytes = 4 * 6 + 8 * 4 + 4 * 4 + 4 * 4;            // NODE data = 88 + 4/listed id
constexpr size_t kIndexEntryBytes = 8 + 8 + 4 + 4;                           // = 24
constexpr size_t kGeomFixedBytes = 4 * 4;                                    // GEOM data = 16 + arrays
constexpr uint32_t kGeomHasSourceIds = 1;  // GEOM flag: global vertex ids follow the level ids (always set)
constexpr uint32_t kGeomShortIndices = 2;  // GEOM flag: triangle corners are u16 (vertexCount <= 65536)
constexpr uint32_t kVertexBlock = 256;     // vertices per VBLK (3 KiB)
constexpr uint32_t kIndexBlock = 512;      // index entries per IBLK (12 KiB)

uint32_t Crc32(const void* data, size_t bytes, uint32_t crc = 0);

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
