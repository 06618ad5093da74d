// ConeLOD — reading the .clod file on demand (lod_read.h; byte layout in lod_format.md).
//
// Kamiya, Suzuki, Kawachi, §8-9: the viewer keeps little in memory and reads from the file as it
// refines. Open() reads the header, checks the index and container chunks it points to, and
// loads the roots (records and geometry). Everything else is read by node: its index entry (one
// IBLK block), its record, its geometry and the vertex blocks it uses. Every size and
// count read from the file is checked against the file's size before anything is allocated, and
// every chunk's CRC-32 is checked before its data is used.
#include "conelod/lod/lod_read.h"

#include <zlib.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <unordered_map>

#include <meshoptimizer.h>

#include "conelod/lod/lod_entropy.h"
#include "conelod/lod/lod_internal.h"

namespace conelod {

using namespace lodfile;

constexpr uint32_t LodNode::kNoGroup;  // (C++14: a definition for odr-uses)

size_t LodGeometry::bytes() const {
  return vertexIds.capacity() * sizeof(uint32_t) + positions.capacity() * sizeof(vcg::Point3f) +
         faces.capacity() * sizeof(faces[0]) + sizeof(LodGeometry);
}

namespace {

// Where the bytes come from: a file (pread) or a file image in memory.
class ByteSource {
 public:
  virtual ~ByteSource() = default;
  virtual bool read(uint64_t offset, size_t n, uint8_t* dst) = 0;
  virtual size_t heldBytes() const { return 0; }
  uint64_t size = 0;
};

class FileSource : public ByteSource {
 public:
  explicit FileSource(int fd) : fd_(fd) {}
  ~FileSource() override { ::close(fd_); }
  bool read(uint64_t offset, size_t n, uint8_t* dst) override {
    while (n > 0) {
      const ssize_t r = ::pread(fd_, dst, n, off_t(offset));
      if (r < 0 && errno == EINTR) continue;
      if (r <= 0) return false;
      dst += r;
      n -= size_t(r);
      offset += uint64_t(r);
    }
    return true;
  }

 private:
  int fd_;
};

class MemorySource : public ByteSource {
 public:
  explicit MemorySource(std::vector<uint8_t> b) : bytes_(std::move(b)) { size = bytes_.size(); }
  bool read(uint64_t offset, size_t n, uint8_t* dst) override {
    if (offset > bytes_.size() || n > bytes_.size() - offset) return false;
    if (n) std::memcpy(dst, bytes_.data() + offset, n);
    return true;
  }
  size_t heldBytes() const override { return bytes_.capacity(); }

 private:
  std::vector<uint8_t> bytes_;
};

// Version 7's deflated geometry streams (raw RFC 1951): one z_stream, reset for each stream.
constexpr size_t kZlibBlockHeader = alignof(std::max_align_t);
class StreamInflater {
 public:
  StreamInflater() = default;
  ~StreamInflater() { Release(); }
  // Frees zlib's state (set up again by the next Inflate).
  void Release() {
    if (ok_) inflateEnd(&z_);
    ok_ = false;
  }
  StreamInflater(const StreamInflater&) = delete;
  StreamInflater& operator=(const StreamInflater&) = delete;
  // True when `in` is one whole deflate stream that gives exactly `out`'s n bytes.
  bool Inflate(const uint8_t* in, size_t inBytes, uint8_t* out, size_t outBytes) {
    if (inBytes > 0xFFFFFFFFu || outBytes > 0xFFFFFFFFu) return false;
    if (!ok_) {
      z_ = z_stream{};
      z_.zalloc = &Alloc;
      z_.zfree = &Free;
      z_.opaque = &bytes_;
      ok_ = inflateInit2(&z_, -15) == Z_OK;
    }
    if (!ok_ || inflateReset(&z_) != Z_OK) return false;
    z_.next_in = const_cast<Bytef*>(in);
    z_.avail_in = uInt(inBytes);
    z_.next_out = out;
    z_.avail_out = uInt(outBytes);
    return inflate(&z_, Z_FINISH) == Z_STREAM_END && z_.avail_in == 0 && z_.avail_out == 0;
  }
  // What zlib holds: its state (about 7 KiB) and, once an inflate stopped short, its window.
  size_t bytes() const { return bytes_; }

 private:
  // zlib's allocations, counted (each block's size kept in front of it, in an aligned header).
  static voidpf Alloc(voidpf opaque, uInt items, uInt size) {
    const size_t n = size_t(items) * size;
    char* p = static_cast<char*>(std::malloc(n + kZlibBlockHeader));
    if (!p) return Z_NULL;
    std::memcpy(p, &n, sizeof n);
    *static_cast<size_t*>(opaque) += n;
    return p + kZlibBlockHeader;
  }
  static void Free(voidpf opaque, voidpf address) {
    if (!address) return;
    char* p = static_cast<char*>(address) - kZlibBlockHeader;
    size_t n;
    std::memcpy(&n, p, sizeof n);
    *static_cast<size_t*>(opaque) -= n;
    std::free(p);
  }
  z_stream z_{};
  bool ok_ = false;
  size_t bytes_ = 0;
};

struct LevelEntry {
  uint64_t faces = 0, nodes = 0, firstId = 0;
  float error = 0;
};

// Where a node's record and geometry blobs lie (absolute offsets, sizes).
struct IndexEntry {
  uint64_t record = 0, geometry = 0;
  uint64_t recordBytes = 0, geometryBytes = 0;
};

std::string Num(uint64_t v) { return std::to_string(v); }

// What a node's attributes hold (with their hash map node).
size_t AttributeBytes(const LodAttributes& a) {
  return (a.colors.capacity() + a.normals.capacity() + a.texCoords.capacity()) * 4 + sizeof(LodAttributes) +
         4 * sizeof(void*);
}

// The fuzz build (scripts/fuzz.sh) accepts bad CRCs, so that mutated inputs reach the structural
// checks behind them: every count, size and offset must hold up without the checksums' help.
#ifdef FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION
constexpr bool kCheckCrc = false;
#else
constexpr bool kCheckCrc = true;
#endif

}  // namespace

uint32_t lodfile::Crc32(const void* data, size_t bytes, uint32_t crc) {
  // CRC-32 (IEEE 802.3) is zlib's; its length argument is 32-bit, so larger blocks go in pieces.
  const Bytef* p = static_cast<const Bytef*>(data);
  uLong c = crc;
  do {
    const size_t n = std::min<size_t>(bytes, 1u << 30);
    c = crc32(c, p, uInt(n));
    p += n;
    bytes -= n;
  } while (bytes > 0);
  return uint32_t(c);
}

std::string lodfile::ChunkName(uint32_t id) {
  std::string s;
  for (int i = 0; i < 4; ++i) {
    const char c = char((id >> (8 * i)) & 0xFF);
    if (c < 32 || c > 126) {
      char hex[16];
      std::snprintf(hex, sizeof hex, "0x%08x", id);
      return hex;
    }
    s += c;
  }
  return s;
}

uint32_t LodGrid::Quantize(double c, int axis) const {
  const double t = std::nearbyint((c - origin[axis]) / step);
  const double top = double((uint64_t(1) << bits) - 1);
  return uint32_t(t < 0 ? 0 : t > top ? top : t);
}

vcg::Point3f LodGrid::Round(const vcg::Point3f& p) const {
  vcg::Point3f r;
  for (int c = 0; c < 3; ++c) r[c] = Dequantize(Quantize(p[c], c), c);
  return r;
}

double LodGrid::ErrorBound() const {
  // Half a cell's diagonal, and half a float's unit in the last place at the largest coordinate
  // (at most |x| 2^-23) per coordinate for the decoded float.
  double largest = 0;
  for (int c = 0; c < 3; ++c)
    largest =
        std::max({largest, std::fabs(origin[c]), std::fabs(origin[c] + double((uint64_t(1) << bits) - 1) * step)});
  return std::sqrt(3.0) / 2 * (step + largest * std::ldexp(1.0, -23));
}

LodGrid ChooseLodGrid(const vcg::Box3f& box, double precision) {
  LodGrid g;
  vcg::Box3f b = box;
  if (b.IsNull()) b = vcg::Box3f(vcg::Point3f(0, 0, 0), vcg::Point3f(0, 0, 0));
  const double diag = std::max(double(b.Diag()), 1e-30);
  double extent = 0;
  for (int c = 0; c < 3; ++c) {
    g.origin[c] = double(b.min[c]);
    extent = std::max(extent, double(b.max[c]) - double(b.min[c]));
  }
  // The cell's half diagonal is 0.99 of the bound: the rest covers the float rounding; where it
  // does not (a fine precision far from the origin), the cell shrinks by what is missing.
  const double target = std::max(precision, kMinLodPrecision) * diag;
  const double floor = extent / double((uint64_t(1) << kMaxGridBits) - 2);
  g.step = std::max(0.99 * 2 * target / std::sqrt(3.0), floor);
  auto setBits = [&]() {
    const double cells = std::nearbyint(extent / g.step) + 1;  // the largest coordinate, plus a margin
    g.bits = 1;
    while (g.bits < kMaxGridBits && double((uint64_t(1) << g.bits) - 1) < cells) ++g.bits;
  };
  setBits();
  for (int i = 0; i < 4 && g.ErrorBound() > target && g.step > floor; ++i) {
    g.step = std::max(g.step - (g.ErrorBound() - target) * 2 / std::sqrt(3.0) * 1.01, floor);
    setBits();
  }
  return g;
}

struct LodReader::Impl {
  std::unique_ptr<ByteSource> src;
  LodFileInfo info;
  std::vector<LevelEntry> levels;
  uint64_t hierOffset = 0, geosOffset = 0, indexOffset = 0, textureOffset = 0;
  uint64_t hierBegin = 0, hierEnd = 0, geosBegin = 0, geosEnd = 0;  // the blobs' data
  uint32_t indexBlock = 0;
  uint32_t attributeMask = 0;  // versions 5, 6: kGeomColors | kGeomNormals | kGeomTexCoords, the streams of every unit
  std::vector<uint32_t> roots;
  struct Entry {
    LodNode node;
    uint64_t geometryOffset = 0;
    uint32_t geometryBytes = 0;  // below 2^32: an index entry's offsets are u32 from its block's base
    bool groupHead = true;       // version 4: the record holds its group's parentError and parents
    std::unique_ptr<LodGeometry> geometry;
  };
  std::unordered_map<uint32_t, Entry> nodes;
  // Versions 5, 6: the attributes of the nodes whose geometry is loaded (apart, so that a
  // geometry-only file's nodes cost no more).
  std::unordered_map<uint32_t, LodAttributes> nodeAttributes;
  size_t geometryBytes = 0;     // of the loaded geometry (its attributes included)
  std::vector<uint8_t> buffer;  // reused for reads
  // The last unit decoded (the clusters of one group, or the roots: one geometry blob), kept
  // while its nodes are read one by one, and let go once each of them has been (its size is the
  // group's, not the cut's).
  struct Unit {
    uint64_t offset = ~uint64_t(0);         // of its blob; ~0: none
    uint64_t firstNode = 0, nodeCount = 0;  // its nodes' ids
    std::vector<bool> served;               // per node: its geometry taken out
    uint64_t servedCount = 0;
    std::vector<uint64_t> faceStart;      // per node, into corners / 3; nodeCount + 1 entries
    std::vector<vcg::Point3f> positions;  // per unit vertex
    std::vector<uint32_t> corners, vertexIds;
    LodAttributes attributes;  // per unit vertex (versions 5, 6)
    size_t bytes() const {
      return served.capacity() / 8 + faceStart.capacity() * 8 + positions.capacity() * sizeof(vcg::Point3f) +
             (corners.capacity() + vertexIds.capacity() + attributes.colors.capacity() + attributes.normals.capacity() +
              attributes.texCoords.capacity()) *
                 4;
    }
  } unit;
  std::vector<uint8_t> positionScratch;  // reused for decoding
  // Version 7: the inflated streams (positions and triangles, then ids and attributes), reused.
  std::vector<uint8_t> streamScratch[2];
  StreamInflater inflater;
  std::vector<uint64_t> gridScratch, residualScratch;
  PositionPredictor predictor;  // versions 6 to 8: the positions' predictions
  // Version 8: the residuals' adaptive models (35 KiB), held only while a unit decodes.
  std::unique_ptr<PositionResidualModel> residualModel;
  std::vector<uint32_t> idScratch, localScratch;
  // The last index block read (a node's children share one most of the time).
  uint64_t cachedIndexBlock = ~uint64_t(0);
  std::vector<IndexEntry> indexCache;
  // Version 6: where each index block starts, from the first block's header (INDX's data).
  std::vector<uint32_t> blockStarts;
  uint64_t indexChildBytes = 0;

  uint32_t levelOf(uint32_t id) const {
    for (size_t k = 0; k < levels.size(); ++k)
      if (id >= levels[k].firstId && id < levels[k].firstId + levels[k].nodes) return uint32_t(k);
    return 0;
  }

  // Reads [offset, offset+n) into `buffer`, checking it lies in the file.
  Status ReadRange(uint64_t offset, uint64_t n, const char* what) {
    if (offset > src->size || n > src->size - offset)
      return Status::Invalid(std::string("corrupt file: ") + what + " at offset " + Num(offset) + " (" + Num(n) +
                             " bytes) lies past the end of the file (" + Num(src->size) + " bytes)");
    buffer.resize(size_t(n));
    if (!src->read(offset, size_t(n), buffer.data()))
      return Status::Invalid(std::string("cannot read ") + what + " at offset " + Num(offset));
    return Status::Ok();
  }

  // Checks the chunk whose header is at p (within a buffer of `avail` bytes): its id, its size
  // (data + children == `expectedTotal` when non-zero), the data within `avail`, the CRC.
  static Status CheckChunk(const uint8_t* p, uint64_t avail, uint32_t id, uint64_t expectedTotal, const char* what,
                           ChunkHeader& h) {
    if (avail < kChunkHeaderBytes) return Status::Invalid(std::string("truncated ") + what);
    h = DecodeChunkHeader(p);
    if (h.id != id)
      return Status::Invalid(std::string("corrupt file: expected a ") + ChunkName(id) + " chunk (" + what +
                             "), found " + ChunkName(h.id));
    if (h.dataBytes > avail - kChunkHeaderBytes || h.childBytes > (uint64_t(1) << 62) ||
        (expectedTotal && h.totalBytes() != expectedTotal))
      return Status::Invalid(std::string("corrupt chunk size in ") + what);
    if (kCheckCrc && Crc32(p + kChunkHeaderBytes, size_t(h.dataBytes)) != h.crc)
      return Status::Invalid(std::string("checksum mismatch in ") + what);
    return Status::Ok();
  }

  // A blob (a record or a node's geometry): its first 4 bytes are the CRC-32 of the rest.
  static bool BlobCrcOk(const uint8_t* p, uint64_t bytes) {
    return !kCheckCrc || (bytes >= 4 && Crc32(p + 4, size_t(bytes - 4)) == Decoder(p, 4).u32());
  }

  // Versions 3 to 5: block b at a fixed offset, entries u32 ends relative to the block's bases.
  Status ReadIndexBlock(uint64_t b) {
    const uint64_t blocksData = kChunkHeaderBytes + kIndexDataBytes;
    const uint64_t blockBytes = kChunkHeaderBytes + kIndexBlockBaseBytes + uint64_t(indexBlock) * kIndexEntryBytes;
    const uint64_t entries = std::min<uint64_t>(indexBlock, info.nodeCount - b * indexBlock);
    const uint64_t bytes = kChunkHeaderBytes + kIndexBlockBaseBytes + entries * kIndexEntryBytes;
    Status s = ReadRange(indexOffset + blocksData + b * blockBytes, bytes, "index block");
    if (!s.ok()) return s;
    ChunkHeader h;
    s = CheckChunk(buffer.data(), bytes, kIBlock, bytes, "index block", h);
    if (!s.ok()) return s;
    indexCache.resize(size_t(entries));
    Decoder d(buffer.data() + kChunkHeaderBytes, size_t(bytes - kChunkHeaderBytes));
    uint64_t record = d.u64(), geometry = d.u64();
    const std::string bad = "corrupt index block " + Num(b) + ": ";
    if (record < hierBegin || record > hierEnd || geometry < geosBegin || geometry > geosEnd)
      return Status::Invalid(bad + "it points outside the records or the geometry");
    // Nodes of one unit share its geometry blob: an entry ending where the previous one
    // ended has the previous one's blob.
    const uint64_t recordBase = record, geometryBase = geometry;
    uint64_t lastEnd = ~uint64_t(0);
    for (auto& e : indexCache) {
      const uint64_t recordEnd = recordBase + d.u32(), geometryEnd = geometryBase + d.u32();
      if (geometryEnd != lastEnd && lastEnd != ~uint64_t(0)) geometry = lastEnd;
      if (recordEnd < record || recordEnd > hierEnd || geometryEnd <= geometry || geometryEnd > geosEnd)
        return Status::Invalid(bad + "an entry points outside the records or the geometry");
      e.record = record;
      e.recordBytes = recordEnd - record;
      e.geometry = geometry;
      e.geometryBytes = geometryEnd - geometry;
      record = recordEnd;
      lastEnd = geometryEnd;
    }
    return Status::Ok();
  }

  // Version 6: block b where the INDX data says, read whole (its CRC checked); per entry a varint
  // (record size - kRecordFixedBytes) x 2 + 1 when the entry starts a new geometry blob, whose
  // size follows; else (never the block's first) it shares the previous entry's blob.
  Status ReadCompactIndexBlock(uint64_t b) {
    const uint64_t entries = std::min<uint64_t>(indexBlock, info.nodeCount - b * indexBlock);
    const uint64_t start = blockStarts[size_t(b)];
    const uint64_t end = b + 1 < blockStarts.size() ? blockStarts[size_t(b) + 1] : indexChildBytes;
    const uint64_t bytes = end - start;  // > entries + the bases (checked at Open)
    Status s = ReadRange(
        indexOffset + kChunkHeaderBytes + kIndexDataBytes + blockStarts.size() * kIndexBlockStartBytes + start, bytes,
        "index block");
    if (!s.ok()) return s;
    ChunkHeader h;
    s = CheckChunk(buffer.data(), bytes, kIBlock, bytes, "index block", h);
    if (!s.ok()) return s;
    indexCache.resize(size_t(entries));
    Decoder d(buffer.data() + kChunkHeaderBytes, size_t(bytes - kChunkHeaderBytes));
    uint64_t record = d.u64(), geometry = d.u64(), geometryEnd = geometry;
    const std::string bad = "corrupt index block " + Num(b) + ": ";
    if (record < hierBegin || record > hierEnd || geometry < geosBegin || geometry > geosEnd)
      return Status::Invalid(bad + "it points outside the records or the geometry");
    bool firstEntry = true;
    for (auto& e : indexCache) {
      const uint64_t code = d.uv();
      const uint64_t recordBytes = (code >> 1) + kRecordFixedBytes;
      if ((code & 1) == 0 && firstEntry) return Status::Invalid(bad + "its first entry has no geometry");
      if (code & 1) {
        const uint64_t n = d.uv();
        if (n > geosEnd - geometryEnd)
          return Status::Invalid(bad + "an entry points outside the records or the geometry");
        geometry = geometryEnd;
        geometryEnd += n;
      }
      if (d.overrun || recordBytes > hierEnd - record)
        return Status::Invalid(bad + "an entry points outside the records or the geometry");
      e.record = record;
      e.recordBytes = recordBytes;
      e.geometry = geometry;
      e.geometryBytes = geometryEnd - geometry;
      if (e.geometryBytes > 0xFFFFFFFFu) return Status::Invalid(bad + "a geometry blob of 4 GiB or more");
      record += recordBytes;
      firstEntry = false;
    }
    if (d.left() != 0) return Status::Invalid(bad + "it does not end with its last entry");
    return Status::Ok();
  }

  // Index entries of nodes [first, first+count).
  Status ReadIndex(uint32_t first, uint32_t count, std::vector<IndexEntry>& out) {
    out.clear();
    for (uint64_t i = first; i < uint64_t(first) + count;) {
      const uint64_t b = i / indexBlock;
      if (b != cachedIndexBlock) {
        Status s = info.version >= kCompactIndexVersion ? ReadCompactIndexBlock(b) : ReadIndexBlock(b);
        if (!s.ok()) {
          cachedIndexBlock = ~uint64_t(0);
          return s;
        }
        cachedIndexBlock = b;
      }
      const IndexEntry& e = indexCache[size_t(i - b * indexBlock)];
      if (e.recordBytes < kRecordFixedBytes || e.geometryBytes < kGeomMinBytes)
        return Status::Invalid("corrupt index: the entry of node " + Num(i) + " is too small");
      out.push_back(e);
      ++i;
    }
    return Status::Ok();
  }

  // Reads the records of nodes [first, first+count) (one level, consecutive in the file). Version
  // 4: a record that names its group's first record takes parentError and parents from it (read
  // here if not loaded; headOnly: this is such a read, and the record must be its group's first).
  Status LoadRecords(uint32_t first, uint32_t count, bool headOnly = false) {
    if (count == 0) return Status::Ok();
    std::vector<IndexEntry> entries;
    Status s = ReadIndex(first, count, entries);
    if (!s.ok()) return s;
    uint64_t span = 0;
    for (uint32_t i = 0; i < count; ++i) {
      if (entries[i].record != entries[0].record + span)
        return Status::Invalid("corrupt index: node records " + Num(first) + ".." + Num(first + count - 1) +
                               " are not consecutive");
      span += entries[i].recordBytes;
    }
    s = ReadRange(entries[0].record, span, "node records");
    if (!s.ok()) return s;
    const uint32_t level = levelOf(first);
    const bool v4 = info.version >= 4;
    struct Pending {
      Entry e;
      uint32_t id, head;
    };
    std::vector<Pending> pending;  // records whose group's first record is not loaded
    uint64_t at = 0;
    for (uint32_t i = 0; i < count; ++i) {
      const uint32_t id = first + i;
      const std::string bad = "corrupt record of node " + Num(id) + ": ";
      const uint8_t* p = buffer.data() + at;
      const uint64_t bytes = entries[i].recordBytes;
      at += bytes;
      if (!BlobCrcOk(p, bytes)) return Status::Invalid("checksum mismatch in the record of a node " + Num(id));
      Decoder d(p + 4, size_t(bytes - 4));
      Entry e;
      LodNode& n = e.node;
      n.level = int(level);
      uint16_t oct[2];
      oct[0] = uint16_t(d.u16());
      oct[1] = uint16_t(d.u16());
      const uint32_t angle = d.u16();
      if (angle == kEmptyConeAngle) {
        n.cone = NormalCone::Empty();
      } else {
        double axis[3];
        DecodeConeAxis(oct, axis);
        for (int j = 0; j < 3; ++j) n.cone.axis[j] = axis[j];
        n.cone.halfAngle = std::min(NormalCone::kPi, angle * kConeAngleUnit);
      }
      for (int j = 0; j < 3; ++j) n.center[j] = d.f32();
      n.radius = d.f32();
      n.error = v4 && level == 0 ? 0.f : d.f32();
      if (info.version >= kTypicalVersion) n.typical = level == 0 ? 0.f : d.f32();
      if (!v4) n.parentError = d.f32();
      const uint64_t group = d.uv(), faces = d.uv(), vertices = d.uv(), children = d.uv();
      const bool top = level + 1 == levels.size();
      if (d.overrun || group > 0xFFFFFFFFull || faces > 0xFFFFFFFFull || vertices > 0xFFFFFFFFull)
        return Status::Invalid(bad + "a count out of range");
      n.group = group ? uint32_t(group - 1) : LodNode::kNoGroup;
      n.faceCount = uint32_t(faces);
      n.vertexCount = uint32_t(vertices);
      if (top != (group == 0)) return Status::Invalid(bad + (top ? "a root with a group" : "no group"));
      if (level == 0 ? children != 0 : (children == 0 || children > levels[level - 1].nodes))
        return Status::Invalid(bad + "children out of range");
      if (children) {
        const uint64_t firstChild = d.uv();
        if (d.overrun || firstChild > levels[level - 1].nodes - children)
          return Status::Invalid(bad + "child out of range");
        n.children.resize(size_t(children));
        for (uint64_t c = 0; c < children; ++c)
          n.children[size_t(c)] = uint32_t(levels[level - 1].firstId + firstChild + c);
      }
      // Sorted distinct ids of one level: the first as an offset into the level, then gaps - 1.
      auto readIds = [&](uint32_t lvl, std::vector<uint32_t>& out) {
        const uint64_t count = d.uv();
        if (d.overrun || count > d.left() || (count && lvl >= levels.size())) return false;
        out.resize(size_t(count));
        if (!count) return true;
        const uint64_t end = levels[lvl].firstId + levels[lvl].nodes;
        uint64_t next = levels[lvl].firstId;
        for (auto& v : out) {
          const uint64_t gap = d.uv();
          if (d.overrun || gap >= end - next) return false;
          v = uint32_t(next + gap);
          next = uint64_t(v) + 1;
        }
        return true;
      };
      if (!readIds(level, n.siblings) || std::find(n.siblings.begin(), n.siblings.end(), id) == n.siblings.end())
        return Status::Invalid(bad + "sibling out of range");
      if (level == 0 && n.siblings.size() != 1) return Status::Invalid(bad + "siblings at level 0");
      const uint64_t back = v4 ? d.uv() : 0;  // how many ids back its group's first record is
      if (d.overrun || back > id - levels[level].firstId || (back && top) || (back && headOnly))
        return Status::Invalid(bad + "a bad group reference");
      e.groupHead = back == 0;
      if (back == 0) {
        if (v4) n.parentError = d.f32();
        if (!readIds(level + 1, n.parents)) return Status::Invalid(bad + "parent out of range");
        if (top != n.parents.empty()) return Status::Invalid(bad + (top ? "a root with parents" : "no parents"));
      }
      if (d.left() != 0) return Status::Invalid(bad + "its size does not match its contents");
      const bool emptyCone = n.cone.halfAngle == NormalCone::Empty().halfAngle;
      if (!(std::isfinite(n.cone.halfAngle) && n.cone.halfAngle <= NormalCone::kPi) ||
          !(n.cone.halfAngle >= 0 || emptyCone) || !std::isfinite(n.cone.axis[0] + n.cone.axis[1] + n.cone.axis[2]) ||
          !std::isfinite(n.center[0] + n.center[1] + n.center[2]) || !(n.radius >= 0) || !std::isfinite(n.radius))
        return Status::Invalid(bad + "non-finite or negative cone or sphere");
      if (!(n.error >= 0) || !std::isfinite(n.error) || (level == 0 && n.error != 0) ||
          (info.version >= kTypicalVersion && !(n.typical >= 0 && n.typical <= n.error)))
        return Status::Invalid(bad + "bad error bounds");
      if (n.vertexCount > uint64_t(3) * n.faceCount || n.faceCount > levels[level].faces || n.faceCount == 0 ||
          n.vertexCount == 0)
        return Status::Invalid(bad + "impossible face or vertex count");
      e.geometryOffset = entries[i].geometry;
      if (entries[i].geometryBytes > 0xFFFFFFFFu) return Status::Invalid(bad + "its geometry is too large");
      e.geometryBytes = uint32_t(entries[i].geometryBytes);
      // The index codec spends at least a byte a triangle and 17 more (meshopt_decodeIndexBuffer).
      if (e.geometryBytes < kGeomMinBytes + 17 + uint64_t(n.faceCount))
        return Status::Invalid(bad + "its geometry is too small for its face count");
      if (!e.groupHead) {
        const uint32_t head = uint32_t(id - back);
        auto h = nodes.find(head);
        if (h == nodes.end()) {
          pending.push_back(Pending{std::move(e), id, head});
          continue;
        }
        Status st = Inherit(e, h->second, id);
        if (!st.ok()) return st;
      } else if (!(n.parentError >= n.error) || (top ? !std::isinf(n.parentError) : !std::isfinite(n.parentError))) {
        return Status::Invalid(bad + "bad error bounds");
      }
      auto it = nodes.find(id);
      if (it == nodes.end()) nodes.emplace(id, std::move(e));
    }
    // (The read buffer is free again: the group's first records can be read. They are dropped
    // afterwards: only the records asked for stay resident.)
    std::vector<uint32_t> readHeads;
    for (Pending& pe : pending) {
      if (nodes.find(pe.head) == nodes.end()) {
        Status st = LoadRecords(pe.head, 1, true);
        if (!st.ok()) return st;
        readHeads.push_back(pe.head);
      }
      Status st = Inherit(pe.e, nodes.find(pe.head)->second, pe.id);
      if (!st.ok()) return st;
      if (nodes.find(pe.id) == nodes.end()) nodes.emplace(pe.id, std::move(pe.e));
    }
    for (uint32_t h : readHeads) nodes.erase(h);
    return Status::Ok();
  }

  // Version 4: a record's parentError and parents from its group's first record, checked.
  static Status Inherit(Entry& e, const Entry& head, uint32_t id) {
    LodNode& n = e.node;
    if (!head.groupHead || head.node.group != n.group || head.node.level != n.level)
      return Status::Invalid("corrupt record of node " + Num(id) + ": a bad group reference");
    n.parentError = head.node.parentError;
    n.parents = head.node.parents;
    if (!(n.parentError >= n.error)) return Status::Invalid("corrupt record of node " + Num(id) + ": bad error bounds");
    return Status::Ok();
  }

  // A geometry stream: its size and bytes (versions 3 to 6); version 7: `uv code` (stored bytes
  // x 2 + deflated), then, when deflated, `uv rawBytes` (at most `bound`, the codec's own bound
  // for the unit's counts, and what deflate can give from the stored bytes) and the deflated
  // bytes, inflated into `scratch`. Gives back the codec's bytes and their count `n`; null when
  // the stream is truncated, out of bounds or does not inflate to exactly rawBytes.
  const uint8_t* TakeStream(Decoder& d, size_t bound, std::vector<uint8_t>& scratch, size_t& n) {
    const uint64_t code = d.uv();
    const bool deflated = info.version >= kDeflateVersion && (code & 1);
    const uint64_t stored = info.version >= kDeflateVersion ? code >> 1 : code;
    const uint64_t raw = deflated ? d.uv() : stored;
    if (d.overrun || stored > d.left()) return nullptr;
    const uint8_t* p = d.take(size_t(stored));
    n = size_t(raw);
    if (!deflated) return p;
    if (raw == 0 || raw > bound || raw > stored * kMaxDeflateRatio + 64) return nullptr;
    scratch.resize(size_t(raw));
    return inflater.Inflate(p, size_t(stored), scratch.data(), size_t(raw)) ? scratch.data() : nullptr;
  }

  // Decodes the geometry blob at [offset, offset + bytes) (node id's) into `unit`.
  Status DecodeUnit(uint64_t offset, uint64_t bytes, uint32_t id) {
    unit.offset = ~uint64_t(0);
    const std::string bad = "corrupt geometry of node " + Num(id) + ": ";
    Status s = ReadRange(offset, bytes, "node geometry");
    if (!s.ok()) return s;
    if (!BlobCrcOk(buffer.data(), bytes))
      return Status::Invalid("checksum mismatch in the geometry of a node " + Num(id));
    Decoder d(buffer.data() + 4, size_t(bytes - 4));
    const uint8_t* flags = d.take(1);
    if (!flags || (*flags & ~(kGeomWidePositions | kKnownAttributes))) return Status::Invalid(bad + "unknown flags");
    if (uint32_t(*flags & kKnownAttributes) != attributeMask)
      return Status::Invalid(bad + "its attribute streams are not the file's");
    const bool wide = *flags & kGeomWidePositions;
    // Its nodes: consecutive ids of one level, each with its face count (the index codec spends
    // at least a byte a face, so the counts are bounded by the blob's size).
    const uint64_t first = d.uv(), count = d.uv();
    const LevelEntry& L = levels[levelOf(id)];
    if (d.overrun || first < L.firstId || count == 0 || count > L.nodes || first - L.firstId > L.nodes - count ||
        count > d.left())
      return Status::Invalid(bad + "its geometry blob names other nodes");
    unit.firstNode = first;
    unit.nodeCount = count;
    unit.served.assign(size_t(count), false);
    unit.servedCount = 0;
    unit.faceStart.assign(size_t(count) + 1, 0);
    // Version 7: the triangles may be deflated (at most kMaxDeflateRatio to 1); their inflated
    // codec bytes bound the faces again below, before anything of their size is allocated.
    const uint64_t maxFaces = info.version >= kDeflateVersion ? bytes * kMaxDeflateRatio : bytes;
    for (uint64_t i = 0; i < count; ++i) {
      const uint64_t fc = d.uv();
      if (d.overrun || fc == 0 || fc > maxFaces) return Status::Invalid(bad + "a face count out of range");
      unit.faceStart[size_t(i) + 1] = unit.faceStart[size_t(i)] + fc;
      if (unit.faceStart[size_t(i) + 1] > maxFaces) return Status::Invalid(bad + "more faces than its blob can hold");
    }
    const size_t fc = size_t(unit.faceStart.back());
    if (fc > 0x3FFFFFFF) return Status::Invalid(bad + "more faces than a unit can hold");  // 3 x fc corners: u32
    const uint64_t vc64 = d.uv();
    if (d.overrun || vc64 == 0 || vc64 > uint64_t(3) * fc) return Status::Invalid(bad + "impossible vertex count");
    const size_t vc = size_t(vc64);
    const uint64_t cells = uint64_t(1) << info.grid.bits;
    uint64_t qmin[3];
    for (auto& q : qmin) q = d.uv();
    const uint64_t firstNew = d.uv();
    if (d.overrun || qmin[0] >= cells || qmin[1] >= cells || qmin[2] >= cells || firstNew > info.globalVertices)
      return Status::Invalid(bad + "its grid corner or first vertex id is out of range");
    // Positions and triangles: their streams first (version 7: inflated), then the faces checked
    // against the triangles' codec bytes (at least a byte a face), then decoded.
    const size_t stride = wide ? 12 : 8;
    size_t n = 0, nt = 0;
    const bool coded = info.version >= kCodedPositionsVersion;
    const uint8_t* p = TakeStream(d, coded ? PositionStreamBound(vc) : meshopt_encodeVertexBufferBound(vc, stride),
                                  streamScratch[0], n);
    if (!p) return Status::Invalid(bad + "its positions do not decode");
    const uint8_t* pt = TakeStream(d, meshopt_encodeIndexBufferBound(fc * 3, vc), streamScratch[1], nt);
    if (!pt) return Status::Invalid(bad + "its triangles do not decode");
    if (fc > nt) return Status::Invalid(bad + "more faces than its triangles can hold");
    if (!coded) {
      positionScratch.resize(vc * stride);
      if (meshopt_decodeVertexBuffer(positionScratch.data(), vc, stride, p, n) != 0)
        return Status::Invalid(bad + "its positions do not decode");
    }
    unit.corners.resize(fc * 3);
    if (meshopt_decodeIndexBuffer(unit.corners.data(), fc * 3, 4, pt, nt) != 0)
      return Status::Invalid(bad + "its triangles do not decode");
    for (uint32_t v : unit.corners)
      if (v >= vc) return Status::Invalid(bad + "face index out of range");
    // Grid coordinates relative to qmin: stored (versions 3 to 5), or (version 6) the residuals
    // of the predictions as running signed bytes, the faces walked as the writer walked them.
    gridScratch.resize(vc * 3);
    const int width = wide ? 4 : 2;
    if (coded) {  // version 8: range-coded residuals, decoded as the walk visits the vertices
      const uint64_t valueMask = (uint64_t(1) << (8 * width)) - 1;
      RangeDecoder rc(p, n);
      const uint32_t m = rc.Raw(6);
      if (!residualModel) residualModel.reset(new PositionResidualModel);
      residualModel->Reset(m, width);
      bool fine = m <= uint32_t(8 * width);
      predictor.Walk(unit.corners.data(), fc, vc, gridScratch.data(), [&](uint32_t v, const uint64_t* pred) {
        uint64_t r[3] = {0, 0, 0};
        fine = residualModel->Decode(rc, predictor.kind(), r, width) && fine;
        for (size_t c = 0; c < 3; ++c) gridScratch[3 * size_t(v) + c] = (pred[c] + r[c]) & valueMask;
      });
      residualModel.reset();
      if (!fine || !rc.ok()) return Status::Invalid(bad + "its positions do not decode");
    } else if (info.version >= kCompactIndexVersion) {
      residualScratch.resize(vc * 3);
      static const uint8_t zeros[12] = {0};
      for (size_t v = 0; v < vc; ++v) {
        const uint8_t* at = positionScratch.data() + v * stride;
        const uint8_t* before = v ? at - stride : zeros;
        for (int c = 0; c < 3; ++c)
          residualScratch[v * 3 + size_t(c)] = ResidualFromBytes(at + width * c, before + width * c, width);
      }
      const uint64_t valueMask = (uint64_t(1) << (8 * width)) - 1;
      predictor.Walk(unit.corners.data(), fc, vc, gridScratch.data(), [&](uint32_t v, const uint64_t* pred) {
        for (size_t c = 0; c < 3; ++c)
          gridScratch[3 * size_t(v) + c] = (pred[c] + residualScratch[3 * size_t(v) + c]) & valueMask;
      });
    } else {
      for (size_t v = 0; v < vc; ++v)
        for (int c = 0; c < 3; ++c) {
          const uint8_t* q = positionScratch.data() + v * stride + size_t(width * c);
          gridScratch[v * 3 + size_t(c)] = wide ? Decoder(q, 4).u32() : Decoder(q, 2).u16();
        }
    }
    unit.positions.resize(vc);
    for (size_t v = 0; v < vc; ++v)
      for (int c = 0; c < 3; ++c) {
        const uint64_t off = gridScratch[v * 3 + size_t(c)];
        if (off >= cells - qmin[c]) return Status::Invalid(bad + "a position off the grid");
        unit.positions[v][c] = info.grid.Dequantize(uint32_t(qmin[c] + off), c);
      }
    // The prediction's buffers go (a unit's are 50-60 bytes a face): the reader holds the cut.
    std::vector<uint64_t>().swap(gridScratch);
    std::vector<uint64_t>().swap(residualScratch);
    predictor.Release();
    // Global ids: the vertices new to the file in order from firstNew, the others listed.
    const uint8_t* mask = d.take((vc + 7) / 8);
    if (!mask) return Status::Invalid(bad + "truncated vertex id mask");
    if (vc % 8 && (mask[vc / 8] >> (vc % 8))) return Status::Invalid(bad + "stray bits in the vertex id mask");
    size_t fresh = 0;
    for (size_t v = 0; v < vc; ++v) fresh += (mask[v / 8] >> (v % 8)) & 1;
    if (fresh > info.globalVertices - firstNew) return Status::Invalid(bad + "vertex id out of range");
    idScratch.resize(vc - fresh);
    if (vc > fresh) {
      p = TakeStream(d, meshopt_encodeIndexSequenceBound(vc - fresh, size_t(info.globalVertices)), streamScratch[0], n);
      if (!p || meshopt_decodeIndexSequence(idScratch.data(), idScratch.size(), 4, p, n) != 0)
        return Status::Invalid(bad + "its vertex ids do not decode");
    }
    // Attribute streams (versions 5, 6): 4 bytes a vertex each.
    auto stream = [&](const char* what, std::string& why) -> const uint8_t* {
      p = TakeStream(d, meshopt_encodeVertexBufferBound(vc, 4), streamScratch[0], n);
      positionScratch.resize(vc * 4);
      if (!p || meshopt_decodeVertexBuffer(positionScratch.data(), vc, 4, p, n) != 0) {
        why = bad + "its " + what + " do not decode";
        return nullptr;
      }
      return positionScratch.data();
    };
    // Two u16 codes a vertex (normals, texture coordinates), little-endian.
    auto codePairs = [&](const uint8_t* c, std::vector<std::array<uint16_t, 2>>& out) {
      out.resize(vc);
      for (size_t v = 0; v < vc; ++v)
        for (size_t k = 0; k < 2; ++k) out[v][k] = uint16_t(c[4 * v + 2 * k] | c[4 * v + 2 * k + 1] << 8);
    };
    std::string why;
    unit.attributes = LodAttributes();
    if (attributeMask & kGeomColors) {
      const uint8_t* c = stream("colours", why);
      if (!c) return Status::Invalid(why);
      unit.attributes.colors.resize(vc);
      for (size_t v = 0; v < vc; ++v) std::memcpy(unit.attributes.colors[v].data(), c + 4 * v, 4);
    }
    if (attributeMask & kGeomNormals) {
      const uint8_t* c = stream("normals", why);
      if (!c) return Status::Invalid(why);
      codePairs(c, unit.attributes.normals);
    }
    if (attributeMask & kGeomTexCoords) {
      const uint8_t* c = stream("texture coordinates", why);
      if (!c) return Status::Invalid(why);
      codePairs(c, unit.attributes.texCoords);
    }
    if (d.left() != 0) return Status::Invalid(bad + "its size does not match its contents");
    unit.vertexIds.resize(vc);
    for (size_t v = 0, nextNew = 0, nextOld = 0; v < vc; ++v) {
      if ((mask[v / 8] >> (v % 8)) & 1) {
        unit.vertexIds[v] = uint32_t(firstNew + nextNew++);
      } else {
        const uint32_t old = idScratch[nextOld++];
        if (old >= firstNew) return Status::Invalid(bad + "global vertex id out of range");
        unit.vertexIds[v] = old;
      }
    }
    localScratch.assign(vc, kNoParent);
    // The codecs' buffers go too (version 7: the inflated streams and zlib's state).
    std::vector<uint8_t>().swap(positionScratch);
    std::vector<uint8_t>().swap(streamScratch[0]);
    std::vector<uint8_t>().swap(streamScratch[1]);
    inflater.Release();
    unit.offset = offset;
    return Status::Ok();
  }

  // A node's geometry: its unit's blob decoded (once for all the unit's nodes, read one after the
  // other when their parent is refined), its faces taken out with their vertices.
  Status LoadGeometry(uint32_t id) {
    auto it = nodes.find(id);
    Entry& e = it->second;
    if (e.geometry) return Status::Ok();
    const LodNode& n = e.node;
    const std::string bad = "corrupt geometry of node " + Num(id) + ": ";
    if (unit.offset != e.geometryOffset) {
      Status s = DecodeUnit(e.geometryOffset, e.geometryBytes, id);
      if (!s.ok()) return s;
    }
    if (id < unit.firstNode || id - unit.firstNode >= unit.nodeCount)
      return Status::Invalid(bad + "its geometry blob names other nodes");
    const size_t m = size_t(id - unit.firstNode);
    const size_t f0 = size_t(unit.faceStart[m]), f1 = size_t(unit.faceStart[m + 1]);
    if (f1 - f0 != n.faceCount) return Status::Invalid(bad + "its face count does not match its record");
    std::unique_ptr<LodGeometry> g(new LodGeometry);
    LodAttributes a;
    for (int c = 0; c < 2; ++c) {
      a.uvMin[c] = info.uvMin[c];
      a.uvMax[c] = info.uvMax[c];
    }
    g->faces.resize(n.faceCount);
    g->positions.reserve(n.vertexCount);
    g->vertexIds.reserve(n.vertexCount);
    for (size_t f = f0; f < f1; ++f)
      for (size_t c = 0; c < 3; ++c) {
        const uint32_t u = unit.corners[f * 3 + c];
        if (localScratch[u] == kNoParent) {
          localScratch[u] = uint32_t(g->positions.size());
          g->positions.push_back(unit.positions[u]);
          g->vertexIds.push_back(unit.vertexIds[u]);
          if (!unit.attributes.colors.empty()) a.colors.push_back(unit.attributes.colors[u]);
          if (!unit.attributes.normals.empty()) a.normals.push_back(unit.attributes.normals[u]);
          if (!unit.attributes.texCoords.empty()) a.texCoords.push_back(unit.attributes.texCoords[u]);
        }
        g->faces[f - f0][c] = localScratch[u];
      }
    for (size_t f = f0 * 3; f < f1 * 3; ++f) localScratch[unit.corners[f]] = kNoParent;
    if (g->positions.size() != n.vertexCount)
      return Status::Invalid(bad + "its vertex count does not match its record");
    geometryBytes += g->bytes();
    e.geometry = std::move(g);
    if (attributeMask) {
      geometryBytes += AttributeBytes(a);
      nodeAttributes[id] = std::move(a);
    }
    if (!unit.served[m]) {
      unit.served[m] = true;
      if (++unit.servedCount == unit.nodeCount) unit = Unit();  // every node of it read
    }
    return Status::Ok();
  }

  // A container of blobs (HIER, GEOS) at `offset`: its header, its data inside the file.
  Status CheckContainer(uint64_t offset, uint32_t id, const char* what, uint64_t& begin, uint64_t& end) {
    Status s = ReadRange(offset, kChunkHeaderBytes, what);
    if (!s.ok()) return s;
    const ChunkHeader h = DecodeChunkHeader(buffer.data());
    if (h.id != id)
      return Status::Invalid(std::string("corrupt file: expected a ") + ChunkName(id) + " chunk (" + what +
                             "), found " + ChunkName(h.id));
    if (h.crc != 0 || h.childBytes != 0 || h.dataBytes > src->size - offset - kChunkHeaderBytes)
      return Status::Invalid(std::string("corrupt chunk size in ") + what);
    begin = offset + kChunkHeaderBytes;
    end = begin + h.dataBytes;
    return Status::Ok();
  }

  Status open() {
    const std::string trunc = "truncated .clod file: ";
    if (src->size < kChunkHeaderBytes)
      return Status::Invalid(trunc + Num(src->size) + " bytes, shorter than a chunk header");
    Status s = ReadRange(0, kChunkHeaderBytes, "the file header");
    if (!s.ok()) return s;
    const ChunkHeader h = DecodeChunkHeader(buffer.data());
    if (h.id != kRoot) return Status::Invalid("not a .clod file (wrong magic: " + ChunkName(h.id) + ", expected CLOD)");
    if (src->size < kChunkHeaderBytes + 4) return Status::Invalid(trunc + "no version field");
    s = ReadRange(kChunkHeaderBytes, 4, "the version");
    if (!s.ok()) return s;
    const uint32_t version = Decoder(buffer.data(), 4).u32();
    if (version == 1)
      return Status::Invalid(
          "this is a .clod version 1 file (written by an older ConeLOD, whose cuts could have "
          "cracks): rebuild it with conelod lod build (this reader reads versions " +
          Num(kOldestReadVersion) + " to " + Num(kVersion) + ")");
    if (version == 2)
      return Status::Invalid(
          "this is a .clod version 2 file (uncompressed, written by an older ConeLOD): rebuild it "
          "with conelod lod build (this reader reads versions " +
          Num(kOldestReadVersion) + " to " + Num(kVersion) + ")");
    if (version < kOldestReadVersion || version > kVersion)
      return Status::Invalid("unsupported .clod version " + Num(version) + " (this reader reads versions " +
                             Num(kOldestReadVersion) + " to " + Num(kVersion) + ")");
    // The attributes field (versions 5, 6), and with texture coordinates the UV box and the texture's
    // offset (checked against the field below).
    const uint64_t tail = version >= kAttributeVersion ? kHeaderAttributeBytes : 0;
    const uint64_t extra = h.dataBytes > kHeaderFixedBytes + tail && version >= kAttributeVersion &&
                                   (h.dataBytes - kHeaderFixedBytes - tail) % kLevelEntryBytes == kHeaderTexCoordBytes
                               ? kHeaderTexCoordBytes
                               : 0;
    if (h.dataBytes < kHeaderFixedBytes + kLevelEntryBytes + tail + extra ||
        h.dataBytes > kHeaderFixedBytes + kMaxLevels * kLevelEntryBytes + tail + extra ||
        (h.dataBytes - kHeaderFixedBytes - tail - extra) % kLevelEntryBytes != 0 || h.childBytes > (uint64_t(1) << 62))
      return Status::Invalid("corrupt chunk size in the file header");
    if (h.totalBytes() > src->size)
      return Status::Invalid(trunc + "the file has " + Num(src->size) + " bytes, its header says " +
                             Num(h.totalBytes()));
    if (h.totalBytes() < src->size)
      return Status::Invalid("corrupt chunk size in the file header: it says " + Num(h.totalBytes()) +
                             " bytes, the file has " + Num(src->size));
    s = ReadRange(kChunkHeaderBytes, h.dataBytes, "the file header");
    if (!s.ok()) return s;
    if (kCheckCrc && Crc32(buffer.data(), size_t(h.dataBytes)) != h.crc)
      return Status::Invalid("checksum mismatch in the file header");
    Decoder d(buffer.data(), size_t(h.dataBytes));
    info.version = d.u32();
    const uint32_t levelCount = d.u32();
    info.inputVertices = d.u64();
    info.inputFaces = d.u64();
    info.nodeCount = d.u64();
    info.globalVertices = d.u64();
    float b[6];
    for (float& x : b) x = d.f32();
    info.box = vcg::Box3f(vcg::Point3f(b[0], b[1], b[2]), vcg::Point3f(b[3], b[4], b[5]));
    for (int j = 0; j < 3; ++j)
      if (!std::isfinite(b[j]) || !std::isfinite(b[j + 3]) || b[j] > b[j + 3])
        return Status::Invalid("corrupt file header: its bounding box is not finite or is inverted");
    hierOffset = d.u64();
    geosOffset = d.u64();
    indexOffset = d.u64();
    LodGrid& grid = info.grid;
    for (double& o : grid.origin) o = d.f64();
    grid.step = d.f64();
    grid.bits = d.u32();
    indexBlock = d.u32();
    const std::string bad = "corrupt file header: ";
    if (grid.bits < 1 || grid.bits > kMaxGridBits || !(grid.step > 0) || !std::isfinite(grid.step))
      return Status::Invalid(bad + "bad quantization grid");
    for (int c = 0; c < 3; ++c) {
      const double top = grid.origin[c] + double((uint64_t(1) << grid.bits) - 1) * grid.step;
      if (!std::isfinite(grid.origin[c]) || !std::isfinite(float(grid.origin[c])) || !std::isfinite(float(top)))
        return Status::Invalid(bad + "bad quantization grid");
    }
    info.quantizationError = grid.ErrorBound();
    if (levelCount < 1 || levelCount > kMaxLevels ||
        h.dataBytes != kHeaderFixedBytes + uint64_t(levelCount) * kLevelEntryBytes + tail + extra)
      return Status::Invalid(bad + "bad level count " + Num(levelCount));
    if (indexBlock == 0 || indexBlock > (1u << 20)) return Status::Invalid(bad + "bad block size");
    levels.resize(levelCount);
    uint64_t id = 0;
    for (uint32_t k = 0; k < levelCount; ++k) {
      LevelEntry& L = levels[k];
      L.faces = d.u64();
      L.nodes = d.u64();
      L.firstId = d.u64();
      L.error = d.f32();
      d.u32();
    }
    if (tail) {
      attributeMask = d.u32();
      d.u32();
      if ((attributeMask == 0 && info.version < kCompactIndexVersion) || (attributeMask & ~kKnownAttributes))
        return Status::Invalid(bad + "unknown attribute streams (" + Num(attributeMask) +
                               "; this reader knows colour 2, normals 4 and texture coordinates 8)");
      info.colors = attributeMask & kGeomColors;
      info.normals = attributeMask & kGeomNormals;
      info.texCoords = attributeMask & kGeomTexCoords;
      if (info.texCoords != (extra != 0)) return Status::Invalid(bad + "its size does not match its attribute streams");
    }
    if (extra) {
      for (float& x : info.uvMin) x = d.f32();
      for (float& x : info.uvMax) x = d.f32();
      textureOffset = d.u64();
      for (int c = 0; c < 2; ++c)
        if (!std::isfinite(info.uvMin[c]) || !std::isfinite(info.uvMax[c]) || !(info.uvMin[c] <= info.uvMax[c]))
          return Status::Invalid(bad + "its UV box is not finite or is inverted");
    }
    for (int k = int(levelCount) - 1; k >= 0; --k) {
      LevelEntry& L = levels[size_t(k)];
      if (L.firstId != id || L.nodes == 0 || L.nodes > src->size / kRecordFixedBytes)
        return Status::Invalid(bad + "bad node count of level " + Num(uint64_t(k)));
      id += L.nodes;
      // Each face takes at least a byte in the file (the index codec's).
      if (L.faces > src->size)
        return Status::Invalid(bad + "counts of level " + Num(uint64_t(k)) + " larger than the file");
    }
    if (id != info.nodeCount || info.nodeCount >= kNoParent) return Status::Invalid(bad + "node counts do not add up");
    if (levels[0].faces != info.inputFaces || info.globalVertices >= kNoParent)
      return Status::Invalid(bad + "level 0 does not match the input");
    if (hierOffset >= src->size || geosOffset >= src->size || indexOffset >= src->size)
      return Status::Invalid(bad + "an offset points past the end of the file");
    info.levels = int(levelCount);
    info.fileBytes = src->size;
    for (const auto& L : levels) {
      info.levelFaces.push_back(L.faces);
      info.levelNodes.push_back(L.nodes);
    }
    // The texture chunk: its header and its name and MIME type (the image is read by LoadTexture).
    if (textureOffset) {
      if (textureOffset >= src->size || src->size - textureOffset < kChunkHeaderBytes + kTextureFixedBytes)
        return Status::Invalid(bad + "the texture's offset points past the end of the file");
      s = ReadRange(textureOffset, kChunkHeaderBytes + kTextureFixedBytes, "the texture chunk");
      if (!s.ok()) return s;
      const ChunkHeader th = DecodeChunkHeader(buffer.data());
      Decoder dt(buffer.data() + kChunkHeaderBytes, kTextureFixedBytes);
      const uint32_t nameBytes = dt.u32(), mimeBytes = dt.u32();
      const uint64_t imageBytes = dt.u64();
      if (th.id != kTexture)
        return Status::Invalid("corrupt file: expected a TEXR chunk (the texture), found " + ChunkName(th.id));
      if (th.childBytes != 0 || th.dataBytes > src->size - textureOffset - kChunkHeaderBytes ||
          nameBytes > kMaxLodTextureNameBytes || mimeBytes > kMaxLodTextureNameBytes || imageBytes == 0 ||
          th.dataBytes != kTextureFixedBytes + uint64_t(nameBytes) + mimeBytes + imageBytes)
        return Status::Invalid("corrupt chunk size in the texture chunk");
      s = ReadRange(textureOffset + kChunkHeaderBytes + kTextureFixedBytes, uint64_t(nameBytes) + mimeBytes,
                    "the texture chunk");
      if (!s.ok()) return s;
      info.textureName.assign(reinterpret_cast<const char*>(buffer.data()), nameBytes);
      info.textureMime.assign(reinterpret_cast<const char*>(buffer.data()) + nameBytes, mimeBytes);
      const std::string why = CheckLodTextureName(info.textureName);
      if (!why.empty()) return Status::Invalid("corrupt texture chunk: " + why);
      if (info.textureMime.empty()) return Status::Invalid("corrupt texture chunk: no MIME type");
      for (unsigned char c : info.textureMime)
        if (c < 0x20 || c >= 0x7F) return Status::Invalid("corrupt texture chunk: its MIME type is not ASCII text");
      info.textureBytes = imageBytes;
    }
    // The containers the header points to.
    s = CheckContainer(hierOffset, kHier, "the hierarchy chunk", hierBegin, hierEnd);
    if (!s.ok()) return s;
    s = CheckContainer(geosOffset, kGeos, "the geometry chunk", geosBegin, geosEnd);
    if (!s.ok()) return s;
    {
      const uint64_t blocks = (info.nodeCount + indexBlock - 1) / indexBlock;
      const bool compact = info.version >= kCompactIndexVersion;
      // Version 6: the INDX data lists where each block starts (u32 each).
      const uint64_t dataBytes = kIndexDataBytes + (compact ? blocks * kIndexBlockStartBytes : 0);
      s = ReadRange(indexOffset, kChunkHeaderBytes + dataBytes, "the index chunk");
      if (!s.ok()) return s;
      ChunkHeader ih;
      s = CheckChunk(buffer.data(), kChunkHeaderBytes + dataBytes, kIndex, 0, "the index chunk", ih);
      if (!s.ok()) return s;
      Decoder di(buffer.data() + kChunkHeaderBytes, size_t(dataBytes));
      const uint64_t entries = di.u64();
      const uint32_t block = di.u32();
      di.u32();
      // A compact block: its header, its bases, at least a byte an entry.
      const uint64_t leastChildren = blocks * (kChunkHeaderBytes + kIndexBlockBaseBytes) + info.nodeCount;
      if (ih.dataBytes != dataBytes || entries != info.nodeCount || block != indexBlock ||
          (compact ? ih.childBytes < leastChildren
                   : ih.childBytes !=
                         blocks * (kChunkHeaderBytes + kIndexBlockBaseBytes) + info.nodeCount * kIndexEntryBytes) ||
          ih.totalBytes() > src->size - indexOffset)
        return Status::Invalid("corrupt chunk size in the index chunk");
      if (compact) {
        indexChildBytes = ih.childBytes;
        blockStarts.resize(size_t(blocks));
        for (uint64_t b = 0; b < blocks; ++b) {
          blockStarts[size_t(b)] = di.u32();
          const uint64_t entriesOf = std::min<uint64_t>(indexBlock, info.nodeCount - b * indexBlock);
          const uint64_t least = kChunkHeaderBytes + kIndexBlockBaseBytes + entriesOf;
          const uint64_t start = blockStarts[size_t(b)];
          // (Every block before the last is full.)
          const uint64_t fullBlock = kChunkHeaderBytes + kIndexBlockBaseBytes + indexBlock;
          if ((b == 0 && start != 0) || (b > 0 && start < uint64_t(blockStarts[size_t(b) - 1]) + fullBlock) ||
              start > ih.childBytes || ih.childBytes - start < least)
            return Status::Invalid("corrupt index chunk: bad start of index block " + Num(b));
        }
      }
    }
    // The roots: records and geometry.
    const uint32_t top = levelCount - 1;
    s = LoadRecords(uint32_t(levels[top].firstId), uint32_t(levels[top].nodes));
    if (!s.ok()) return s;
    for (uint32_t r = 0; r < levels[top].nodes; ++r) {
      roots.push_back(r);
      s = LoadGeometry(r);
      if (!s.ok()) return s;
    }
    return Status::Ok();
  }
};

LodReader::LodReader() : impl_(new Impl) {}
LodReader::~LodReader() = default;

Status LodReader::Open(const std::string& path, std::unique_ptr<LodReader>& out) {
  out.reset();
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return Status::Invalid("cannot open '" + path + "': " + std::strerror(errno));
  struct stat st;
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    return Status::Invalid("'" + path + "' is not a regular file");
  }
  std::unique_ptr<LodReader> r(new LodReader);
  r->impl_->src.reset(new FileSource(fd));
  r->impl_->src->size = uint64_t(st.st_size);
  Status s = r->impl_->open();
  if (!s.ok()) return Status::Invalid(path + ": " + s.message);
  out = std::move(r);
  return Status::Ok();
}

Status LodReader::OpenMemory(std::vector<uint8_t> bytes, std::unique_ptr<LodReader>& out) {
  out.reset();
  std::unique_ptr<LodReader> r(new LodReader);
  r->impl_->src.reset(new MemorySource(std::move(bytes)));
  Status s = r->impl_->open();
  if (!s.ok()) return s;
  out = std::move(r);
  return Status::Ok();
}

const LodFileInfo& LodReader::info() const { return impl_->info; }
const std::vector<uint32_t>& LodReader::roots() const { return impl_->roots; }
bool LodReader::hasNode(uint32_t id) const { return impl_->nodes.count(id) > 0; }
const LodNode& LodReader::node(uint32_t id) const { return impl_->nodes.at(id).node; }
uint32_t LodReader::levelOfNode(uint32_t id) const { return impl_->levelOf(id); }

Status LodReader::LoadChildren(uint32_t id) {
  if (!hasNode(id)) return Status::Invalid("LoadChildren: node " + Num(id) + " is not loaded");
  const std::vector<uint32_t> children = node(id).children;  // copy: loading records may rehash
  const float error = node(id).error;
  // Runs of consecutive ids in one read each (a group's clusters are consecutive).
  for (size_t i = 0; i < children.size();) {
    size_t j = i + 1;
    while (j < children.size() && children[j] == children[j - 1] + 1) ++j;
    bool all = true;
    for (size_t k = i; k < j && all; ++k) all = hasNode(children[k]);
    if (!all) {
      Status s = impl_->LoadRecords(children[i], uint32_t(j - i));
      if (!s.ok()) return s;
    }
    i = j;
  }
  // The children are the clusters of one group: the group id was made from, whose error is id's.
  for (uint32_t c : children) {
    const LodNode& n = node(c);
    if (n.parentError != error || n.group != node(children[0]).group)
      return Status::Invalid("corrupt record of node " + Num(c) + ": it does not belong to the group its parent " +
                             Num(id) + " was made from");
  }
  return Status::Ok();
}

Status LodReader::LoadNode(uint32_t id) {
  if (id >= impl_->info.nodeCount) return Status::Invalid("LoadNode: no node " + Num(id));
  if (hasNode(id)) return Status::Ok();
  return impl_->LoadRecords(id, 1);
}

Status LodReader::LoadGeometry(uint32_t id) {
  if (!hasNode(id)) return Status::Invalid("LoadGeometry: node " + Num(id) + " is not loaded");
  return impl_->LoadGeometry(id);
}

const LodGeometry* LodReader::geometry(uint32_t id) const {
  auto it = impl_->nodes.find(id);
  return it == impl_->nodes.end() ? nullptr : it->second.geometry.get();
}

void LodReader::EvictGeometry(uint32_t id) {
  auto it = impl_->nodes.find(id);
  if (it == impl_->nodes.end() || !it->second.geometry) return;
  impl_->geometryBytes -= it->second.geometry->bytes();
  it->second.geometry.reset();
  auto a = impl_->nodeAttributes.find(id);
  if (a != impl_->nodeAttributes.end()) {
    impl_->geometryBytes -= AttributeBytes(a->second);
    impl_->nodeAttributes.erase(a);
  }
}

std::string CheckLodTextureName(const std::string& name) {
  if (name.empty()) return "the texture has no name";
  if (name.size() > kMaxLodTextureNameBytes) return "the texture's name is longer than 255 bytes";
  if (name == "." || name == "..") return "the texture's name '" + name + "' is not a file name";
  for (unsigned char c : name)
    if (c < 0x20 || c == 0x7F || c == '/' || c == '\\' || c == ':')
      return "the texture's name is not a plain file name (no folder, no control character)";
  return "";
}

void DecodeLodTexCoord(const std::array<uint16_t, 2>& code, const float uvMin[2], const float uvMax[2], float out[2]) {
  for (int c = 0; c < 2; ++c)
    out[c] = float(double(uvMin[c]) + double(code[size_t(c)]) * ((double(uvMax[c]) - double(uvMin[c])) / 65535.0));
}

double LodTexCoordErrorBound(const float uvMin[2], const float uvMax[2]) {
  double worst = 0;
  for (int c = 0; c < 2; ++c) {
    const double range = double(uvMax[c]) - double(uvMin[c]);
    const double top = std::max(std::fabs(double(uvMin[c])), std::fabs(double(uvMax[c])));
    worst = std::max(worst, range / 65535.0 / 2 + top * std::numeric_limits<float>::epsilon());
  }
  return worst;
}

Status LodReader::LoadTexture(LodTexture& out) {
  out = LodTexture();
  Impl& m = *impl_;
  if (!m.textureOffset) return Status::Invalid("this .clod file has no texture image");
  const uint64_t data = m.info.textureName.size() + m.info.textureMime.size() + m.info.textureBytes;
  Status s = m.ReadRange(m.textureOffset, kChunkHeaderBytes + kTextureFixedBytes + data, "the texture chunk");
  if (!s.ok()) return s;
  const ChunkHeader h = DecodeChunkHeader(m.buffer.data());
  if (kCheckCrc && Crc32(m.buffer.data() + kChunkHeaderBytes, size_t(kTextureFixedBytes + data)) != h.crc)
    return Status::Invalid("checksum mismatch in the texture chunk");
  const uint8_t* p = m.buffer.data() + kChunkHeaderBytes + kTextureFixedBytes;
  out.name = m.info.textureName;
  out.mime = m.info.textureMime;
  p += out.name.size() + out.mime.size();
  out.bytes.assign(p, p + m.info.textureBytes);
  std::vector<uint8_t>().swap(m.buffer);  // the image is not kept
  return Status::Ok();
}

const LodAttributes* LodReader::attributes(uint32_t id) const {
  auto it = impl_->nodeAttributes.find(id);
  return it == impl_->nodeAttributes.end() ? nullptr : &it->second;
}

size_t LodReader::residentBytes() const {
  const Impl& m = *impl_;
  size_t b = sizeof(LodReader) + sizeof(Impl) + m.levels.capacity() * sizeof(LevelEntry) + m.roots.capacity() * 4 +
             m.buffer.capacity() + m.positionScratch.capacity() + m.streamScratch[0].capacity() +
             m.streamScratch[1].capacity() + m.inflater.bytes() +
             (m.gridScratch.capacity() + m.residualScratch.capacity()) * 8 + m.predictor.bytes() +
             (m.idScratch.capacity() + m.localScratch.capacity()) * 4 + m.unit.bytes() +
             m.indexCache.capacity() * sizeof(IndexEntry) + m.blockStarts.capacity() * 4 +
             m.info.levelFaces.capacity() * 16 + m.src->heldBytes() + m.geometryBytes;
  // Hash map: buckets plus one heap node per record (key, entry, next pointer, cached hash).
  b += m.nodes.bucket_count() * sizeof(void*);
  for (const auto& kv : m.nodes)
    b += sizeof(kv) + 2 * sizeof(void*) +
         (kv.second.node.children.capacity() + kv.second.node.siblings.capacity() + kv.second.node.parents.capacity()) *
             4;
  return b;
}

}  // namespace conelod
