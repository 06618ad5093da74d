// ConeLOD — reading the .clod file on demand (lod_read.h; byte layout in lod_format.md).
//
// Kamiya, Suzuki, Kawachi, §8-9: the viewer keeps little in memory and reads from the file as it
// refines. Open() reads the header, checks the index and container chunks it points to, and
// loads the roots (records and geometry). Everything else is read by node: its index entry (one
// 12 KiB IBLK block), its record, its geometry and the vertex blocks it uses. Every size and
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
#include <cstring>
#include <unordered_map>

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

struct LevelEntry {
  uint64_t faces = 0, nodes = 0, vertices = 0, firstId = 0, levelOffset = 0, vertOffset = 0;
  float error = 0;
};

struct IndexEntry {
  uint64_t record = 0, geometry = 0;
  uint32_t recordBytes = 0, geometryBytes = 0;
};

std::string Num(uint64_t v) { return std::to_string(v); }

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

struct LodReader::Impl {
  std::unique_ptr<ByteSource> src;
  LodFileInfo info;
  std::vector<LevelEntry> levels;
  uint64_t hierOffset = 0, indexOffset = 0;
  uint32_t vertexBlock = 0, indexBlock = 0;
  std::vector<uint32_t> roots;
  struct Entry {
    LodNode node;
    uint64_t geometryOffset = 0;
    uint32_t geometryBytes = 0;
    std::unique_ptr<LodGeometry> geometry;
  };
  std::unordered_map<uint32_t, Entry> nodes;
  size_t geometryBytes = 0;     // of the loaded geometry
  std::vector<uint8_t> buffer;  // reused for reads
  // The last index block read (a node's children share one most of the time).
  uint64_t cachedIndexBlock = ~uint64_t(0);
  std::vector<IndexEntry> indexCache;

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

  // Index entries of nodes [first, first+count).
  Status ReadIndex(uint32_t first, uint32_t count, std::vector<IndexEntry>& out) {
    out.clear();
    const uint64_t blocksData = kChunkHeaderBytes + kIndexDataBytes;
    const uint64_t blockBytes = kChunkHeaderBytes + uint64_t(indexBlock) * kIndexEntryBytes;
    for (uint64_t i = first; i < uint64_t(first) + count;) {
      const uint64_t b = i / indexBlock;
      if (b != cachedIndexBlock) {
        const uint64_t entries = std::min<uint64_t>(indexBlock, info.nodeCount - b * indexBlock);
        const uint64_t bytes = kChunkHeaderBytes + entries * kIndexEntryBytes;
        Status s = ReadRange(indexOffset + blocksData + b * blockBytes, bytes, "index block");
        if (!s.ok()) return s;
        ChunkHeader h;
        s = CheckChunk(buffer.data(), bytes, kIBlock, bytes, "index block", h);
        if (!s.ok()) return s;
        indexCache.resize(size_t(entries));
        Decoder d(buffer.data() + kChunkHeaderBytes, size_t(entries * kIndexEntryBytes));
        for (auto& e : indexCache) {
          e.record = d.u64();
          e.geometry = d.u64();
          e.recordBytes = d.u32();
          e.geometryBytes = d.u32();
        }
        cachedIndexBlock = b;
      }
      const IndexEntry& e = indexCache[size_t(i - b * indexBlock)];
      if (e.record < hierOffset || e.record > src->size || e.recordBytes > src->size - e.record ||
          e.geometry > src->size || e.geometryBytes > src->size - e.geometry || e.recordBytes < kChunkHeaderBytes ||
          e.geometryBytes < kChunkHeaderBytes)
        return Status::Invalid("corrupt index: the entry of node " + Num(i) + " points past the end of the file");
      out.push_back(e);
      ++i;
    }
    return Status::Ok();
  }

  // Reads the records of nodes [first, first+count) (one level, consecutive in the file).
  Status LoadRecords(uint32_t first, uint32_t count) {
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
    uint64_t at = 0;
    for (uint32_t i = 0; i < count; ++i) {
      const uint32_t id = first + i;
      ChunkHeader h;
      s = CheckChunk(buffer.data() + at, entries[i].recordBytes, kNode, entries[i].recordBytes, "the record of a node",
                     h);
      if (!s.ok()) return Status::Invalid(s.message + " " + Num(id));
      Decoder d(buffer.data() + at + kChunkHeaderBytes, size_t(h.dataBytes));
      at += entries[i].recordBytes;
      Entry e;
      LodNode& n = e.node;
      const uint32_t fileId = d.u32();
      n.level = int(d.u32());
      n.group = d.u32();
      const uint32_t children = d.u32(), siblings = d.u32(), parents = d.u32();
      for (int j = 0; j < 3; ++j) n.cone.axis[j] = d.f64();
      n.cone.halfAngle = d.f64();
      for (int j = 0; j < 3; ++j) n.center[j] = d.f32();
      n.radius = d.f32();
      n.faceCount = d.u32();
      n.vertexCount = d.u32();
      n.error = d.f32();
      n.parentError = d.f32();
      const std::string bad = "corrupt record of node " + Num(id) + ": ";
      if (d.overrun || h.dataBytes != kNodeFixedBytes + (uint64_t(children) + siblings + parents) * 4)
        return Status::Invalid(bad + "its size does not match its list lengths");
      if (fileId != id || n.level != int(level)) return Status::Invalid(bad + "wrong id or level");
      const bool top = level + 1 == levels.size();
      if (top != (n.group == LodNode::kNoGroup) || top != (parents == 0))
        return Status::Invalid(bad + (top ? "a root with a group or parents" : "no group or no parents"));
      if (level == 0 ? (children != 0 || siblings != 1) : (children == 0 || siblings == 0))
        return Status::Invalid(bad + "children out of range");
      const bool emptyCone = n.cone.halfAngle == NormalCone::Empty().halfAngle;
      if (!(std::isfinite(n.cone.halfAngle) && n.cone.halfAngle <= NormalCone::kPi + 1e-9) ||
          !(n.cone.halfAngle >= 0 || emptyCone) || !std::isfinite(n.cone.axis[0] + n.cone.axis[1] + n.cone.axis[2]) ||
          !std::isfinite(n.center[0] + n.center[1] + n.center[2]) || !(n.radius >= 0) || !std::isfinite(n.radius))
        return Status::Invalid(bad + "non-finite or negative cone or sphere");
      if (!(n.error >= 0) || !std::isfinite(n.error) || (level == 0 && n.error != 0) || !(n.parentError >= n.error) ||
          (top ? !std::isinf(n.parentError) : !std::isfinite(n.parentError)))
        return Status::Invalid(bad + "bad error bounds");
      if (n.vertexCount > uint64_t(3) * n.faceCount || n.faceCount > levels[level].faces || n.faceCount == 0)
        return Status::Invalid(bad + "impossible face or vertex count");
      auto readIds = [&](uint32_t count, uint32_t lvl, std::vector<uint32_t>& out) {
        out.resize(count);
        for (auto& v : out) {
          v = d.u32();
          if (lvl >= levels.size() || v < levels[lvl].firstId || v >= levels[lvl].firstId + levels[lvl].nodes)
            return false;
        }
        return true;
      };
      if (!readIds(children, level - 1, n.children)) return Status::Invalid(bad + "child out of range");
      if (!readIds(siblings, level, n.siblings) ||
          std::find(n.siblings.begin(), n.siblings.end(), id) == n.siblings.end())
        return Status::Invalid(bad + "sibling out of range");
      if (!readIds(parents, level + 1, n.parents)) return Status::Invalid(bad + "parent out of range");
      e.geometryOffset = entries[i].geometry;
      e.geometryBytes = entries[i].geometryBytes;
      if (uint64_t(e.geometryBytes) < kChunkHeaderBytes + kGeomFixedBytes + uint64_t(n.faceCount) * 6)
        return Status::Invalid(bad + "its geometry chunk is too small for its face count");
      auto it = nodes.find(id);
      if (it == nodes.end()) nodes.emplace(id, std::move(e));
    }
    return Status::Ok();
  }

  Status LoadGeometry(uint32_t id) {
    auto it = nodes.find(id);
    Entry& e = it->second;
    if (e.geometry) return Status::Ok();
    const LodNode& n = e.node;
    const std::string bad = "corrupt geometry of node " + Num(id) + ": ";
    Status s = ReadRange(e.geometryOffset, e.geometryBytes, "node geometry");
    if (!s.ok()) return s;
    ChunkHeader h;
    s = CheckChunk(buffer.data(), e.geometryBytes, kGeom, e.geometryBytes, "the geometry of a node", h);
    if (!s.ok()) return Status::Invalid(s.message + " " + Num(id));
    Decoder d(buffer.data() + kChunkHeaderBytes, size_t(h.dataBytes));
    const uint32_t fileId = d.u32(), vc = d.u32(), fc = d.u32(), flags = d.u32();
    if (fileId != id || vc != n.vertexCount || fc != n.faceCount ||
        (flags & ~(kGeomHasSourceIds | kGeomShortIndices)) || !(flags & kGeomHasSourceIds) ||
        ((flags & kGeomShortIndices) && vc > 65536))
      return Status::Invalid(bad + "does not match its record");
    const uint64_t idArrays = 2;
    const bool shortIndices = flags & kGeomShortIndices;
    if (h.dataBytes != kGeomFixedBytes + idArrays * 4 * uint64_t(vc) + (shortIndices ? 6 : 12) * uint64_t(fc))
      return Status::Invalid(bad + "its size does not match its counts");
    std::unique_ptr<LodGeometry> g(new LodGeometry);
    std::vector<uint32_t> levelIds(vc);
    const uint64_t levelVertices = levels[size_t(n.level)].vertices;
    for (auto& v : levelIds) {
      v = d.u32();
      if (v >= levelVertices) return Status::Invalid(bad + "vertex id out of range");
    }
    g->vertexIds.resize(vc);
    const uint64_t idLimit = n.level == 0 ? info.inputVertices : info.globalVertices;
    for (auto& v : g->vertexIds) {
      v = d.u32();
      if (v >= idLimit) return Status::Invalid(bad + "global vertex id out of range");
    }
    g->faces.resize(fc);
    for (auto& t : g->faces)
      for (auto& v : t) {
        v = shortIndices ? d.u16() : d.u32();
        if (v >= vc) return Status::Invalid(bad + "face index out of range");
      }
    s = ReadPositions(uint32_t(n.level), levelIds, g->positions);
    if (!s.ok()) return Status::Invalid(bad + s.message);
    geometryBytes += g->bytes();
    e.geometry = std::move(g);
    return Status::Ok();
  }

  // Positions of the given level vertices: reads the VBLK blocks they lie in, runs of consecutive
  // blocks in one read.
  Status ReadPositions(uint32_t level, const std::vector<uint32_t>& ids, std::vector<vcg::Point3f>& out) {
    out.resize(ids.size());
    if (ids.empty()) return Status::Ok();
    // Local vertices sorted by level id (id << 32 | local index), swept block by block.
    std::vector<uint64_t> byId(ids.size());
    for (size_t k = 0; k < ids.size(); ++k) byId[k] = uint64_t(ids[k]) << 32 | k;
    std::sort(byId.begin(), byId.end());
    std::vector<uint32_t> blocks;
    for (uint64_t e : byId) {
      const uint32_t b = uint32_t(e >> 32) / vertexBlock;
      if (blocks.empty() || blocks.back() != b) blocks.push_back(b);
    }
    const LevelEntry& L = levels[level];
    const uint64_t fullBlockBytes = kChunkHeaderBytes + uint64_t(vertexBlock) * 12;
    const uint64_t base = L.vertOffset + kChunkHeaderBytes + kVertDataBytes;
    size_t next = 0;  // into byId
    for (size_t i = 0; i < blocks.size();) {
      // A run of consecutive blocks (at most 64: 192 KiB) in one read.
      size_t j = i + 1;
      while (j < blocks.size() && blocks[j] == blocks[j - 1] + 1 && j - i < 64) ++j;
      const uint64_t firstVertex = uint64_t(blocks[i]) * vertexBlock;
      const uint64_t lastEnd = std::min<uint64_t>(L.vertices, uint64_t(blocks[j - 1] + 1) * vertexBlock);
      const uint64_t runBytes = uint64_t(j - i) * kChunkHeaderBytes + (lastEnd - firstVertex) * 12;
      Status s = ReadRange(base + uint64_t(blocks[i]) * fullBlockBytes, runBytes, "vertex blocks");
      if (!s.ok()) return s;
      uint64_t at = 0;
      for (size_t b = i; b < j; ++b) {
        const uint64_t v0 = uint64_t(blocks[b]) * vertexBlock;
        const uint64_t v1 = std::min<uint64_t>(L.vertices, v0 + vertexBlock);
        const uint64_t bytes = kChunkHeaderBytes + (v1 - v0) * 12;
        ChunkHeader h;
        s = CheckChunk(buffer.data() + at, bytes, kVBlock, bytes, "a vertex block", h);
        if (!s.ok()) return s;
        const uint8_t* p = buffer.data() + at + kChunkHeaderBytes;
        for (; next < byId.size() && (byId[next] >> 32) < v1; ++next) {
          const size_t k = size_t(byId[next] & 0xFFFFFFFFu);
          Decoder d(p + ((byId[next] >> 32) - v0) * 12, 12);
          for (int c = 0; c < 3; ++c) out[k][c] = d.f32();  // (not one expression: argument order is unspecified)
          if (!std::isfinite(out[k][0] + out[k][1] + out[k][2])) return Status::Invalid("non-finite vertex position");
        }
        at += bytes;
      }
      i = j;
    }
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
          "cracks): rebuild it with conelod lod build (this reader reads version " +
          Num(kVersion) + ")");
    if (version != kVersion)
      return Status::Invalid("unsupported .clod version " + Num(version) + " (this reader reads version " +
                             Num(kVersion) + ")");
    if (h.dataBytes < kHeaderFixedBytes + kLevelEntryBytes ||
        h.dataBytes > kHeaderFixedBytes + kMaxLevels * kLevelEntryBytes ||
        (h.dataBytes - kHeaderFixedBytes) % kLevelEntryBytes != 0 || h.childBytes > (uint64_t(1) << 62))
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
    indexOffset = d.u64();
    vertexBlock = d.u32();
    indexBlock = d.u32();
    const std::string bad = "corrupt file header: ";
    if (levelCount < 1 || levelCount > kMaxLevels ||
        h.dataBytes != kHeaderFixedBytes + uint64_t(levelCount) * kLevelEntryBytes)
      return Status::Invalid(bad + "bad level count " + Num(levelCount));
    if (vertexBlock == 0 || vertexBlock > (1u << 20) || indexBlock == 0 || indexBlock > (1u << 20))
      return Status::Invalid(bad + "bad block size");
    levels.resize(levelCount);
    uint64_t id = 0;
    for (uint32_t k = 0; k < levelCount; ++k) {
      LevelEntry& L = levels[k];
      L.faces = d.u64();
      L.nodes = d.u64();
      L.vertices = d.u64();
      L.firstId = d.u64();
      L.levelOffset = d.u64();
      L.vertOffset = d.u64();
      L.error = d.f32();
      d.u32();
    }
    for (int k = int(levelCount) - 1; k >= 0; --k) {
      LevelEntry& L = levels[size_t(k)];
      if (L.firstId != id || L.nodes == 0 || L.nodes > src->size / kChunkHeaderBytes)
        return Status::Invalid(bad + "bad node count of level " + Num(uint64_t(k)));
      id += L.nodes;
      // Each face takes at least 6 bytes in the file, each vertex 12.
      if (L.faces > src->size / 6 || L.vertices > src->size / 12)
        return Status::Invalid(bad + "counts of level " + Num(uint64_t(k)) + " larger than the file");
      if (L.levelOffset >= src->size || L.vertOffset >= src->size)
        return Status::Invalid(bad + "an offset points past the end of the file");
    }
    if (id != info.nodeCount || info.nodeCount >= kNoParent) return Status::Invalid(bad + "node counts do not add up");
    // The input's vertices may be unreferenced (not stored); every vertex made by the
    // simplification is stored, in 12 bytes at least.
    if (levels[0].faces != info.inputFaces || info.globalVertices < info.inputVertices ||
        info.globalVertices >= kNoParent || info.globalVertices - info.inputVertices > src->size / 12)
      return Status::Invalid(bad + "level 0 does not match the input");
    if (hierOffset >= src->size || indexOffset >= src->size)
      return Status::Invalid(bad + "an offset points past the end of the file");
    info.levels = int(levelCount);
    info.fileBytes = src->size;
    for (const auto& L : levels) {
      info.levelFaces.push_back(L.faces);
      info.levelNodes.push_back(L.nodes);
    }
    // The containers the header points to.
    {
      s = ReadRange(hierOffset, kChunkHeaderBytes, "the hierarchy chunk");
      if (!s.ok()) return s;
      ChunkHeader hh;
      s = CheckChunk(buffer.data(), kChunkHeaderBytes, kHier, 0, "the hierarchy chunk", hh);
      if (!s.ok()) return s;
      if (hh.childBytes > src->size - hierOffset) return Status::Invalid("corrupt chunk size in the hierarchy chunk");
      const uint64_t indexBytes = kChunkHeaderBytes + kIndexDataBytes;
      s = ReadRange(indexOffset, indexBytes, "the index chunk");
      if (!s.ok()) return s;
      ChunkHeader ih;
      s = CheckChunk(buffer.data(), indexBytes, kIndex, 0, "the index chunk", ih);
      if (!s.ok()) return s;
      Decoder di(buffer.data() + kChunkHeaderBytes, kIndexDataBytes);
      const uint64_t entries = di.u64();
      const uint32_t block = di.u32();
      const uint64_t blocks = (info.nodeCount + indexBlock - 1) / indexBlock;
      if (ih.dataBytes != kIndexDataBytes || entries != info.nodeCount || block != indexBlock ||
          ih.childBytes != blocks * kChunkHeaderBytes + info.nodeCount * kIndexEntryBytes ||
          ih.totalBytes() > src->size - indexOffset)
        return Status::Invalid("corrupt chunk size in the index chunk");
      for (uint32_t k = 0; k < levelCount; ++k) {
        LevelEntry& L = levels[k];
        // The level's container: its data must repeat the header's counts, its VERT follow it.
        const uint64_t lb = kChunkHeaderBytes + kLevelDataBytes;
        s = ReadRange(L.levelOffset, lb, "a level chunk");
        if (!s.ok()) return s;
        ChunkHeader lh;
        s = CheckChunk(buffer.data(), lb, kLevel, 0, "a level chunk", lh);
        if (!s.ok()) return s;
        Decoder dl(buffer.data() + kChunkHeaderBytes, kLevelDataBytes);
        const uint32_t lk = dl.u32(), lpad = dl.u32();
        const uint64_t ln = dl.u64(), lf = dl.u64(), lv = dl.u64();
        if (lh.dataBytes != kLevelDataBytes || lk != k || lpad != 0 || ln != L.nodes || lf != L.faces ||
            lv != L.vertices || L.vertOffset != L.levelOffset + lb || lh.totalBytes() > src->size - L.levelOffset)
          return Status::Invalid("corrupt level chunk of level " + Num(k) + ": it disagrees with the file header");
        const uint64_t vb = kChunkHeaderBytes + kVertDataBytes;
        s = ReadRange(L.vertOffset, vb, "a vertex chunk");
        if (!s.ok()) return s;
        ChunkHeader vh;
        s = CheckChunk(buffer.data(), vb, kVert, 0, "a vertex chunk", vh);
        if (!s.ok()) return s;
        Decoder dv(buffer.data() + kChunkHeaderBytes, kVertDataBytes);
        const uint32_t level = dv.u32(), block = dv.u32();
        const uint64_t count = dv.u64();
        const uint64_t nb = (L.vertices + vertexBlock - 1) / vertexBlock;
        if (vh.dataBytes != kVertDataBytes || level != k || block != vertexBlock || count != L.vertices ||
            vh.childBytes != nb * kChunkHeaderBytes + L.vertices * 12 || vh.totalBytes() > src->size - L.vertOffset)
          return Status::Invalid("corrupt chunk size in the vertex chunk of level " + Num(k));
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
}

size_t LodReader::residentBytes() const {
  const Impl& m = *impl_;
  size_t b = sizeof(LodReader) + sizeof(Impl) + m.levels.capacity() * sizeof(LevelEntry) + m.roots.capacity() * 4 +
             m.buffer.capacity() + m.indexCache.capacity() * sizeof(IndexEntry) + m.info.levelFaces.capacity() * 16 +
             m.src->heldBytes() + m.geometryBytes;
  // Hash map: buckets plus one heap node per record (key, entry, next pointer, cached hash).
  b += m.nodes.bucket_count() * sizeof(void*);
  for (const auto& kv : m.nodes)
    b += sizeof(kv) + 2 * sizeof(void*) +
         (kv.second.node.children.capacity() + kv.second.node.siblings.capacity() + kv.second.node.parents.capacity()) *
             4;
  return b;
}

}  // namespace conelod
