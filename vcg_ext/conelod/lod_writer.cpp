// ConeLOD — writing the .clod file (lod.h; byte layout in lod_format.md).
//
// Kamiya, Suzuki, Kawachi, §8: a file of chunks, each an id, its size and its data followed by
// sub-chunks. The writer first computes the small per-node records (cone, sphere, neighbours:
// about 100 bytes a node), then streams the geometry level by level, coarsest first, through one
// reused buffer: the only per-level arrays it holds are the level's face order and vertex
// renumbering. Container sizes and the header's offsets are patched in place at the end.
#include "conelod/lod.h"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numeric>

#include "conelod/lod_internal.h"
#include "conelod/safe_file.h"

namespace conelod {
namespace {

using namespace lodfile;

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

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
    if (std::fseek(f_, long(at), SEEK_SET) != 0 || std::fwrite(e.bytes.data(), 1, e.bytes.size(), f_) != e.bytes.size() ||
        std::fseek(f_, 0, SEEK_END) != 0)
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

// One node level as the writer sees it: a mesh, per face its group, and the order of the nodes.
struct LevelView {
  const IndexedMesh* mesh = nullptr;
  const std::vector<int>* faceGroup = nullptr;  // per face of `mesh`: group of hierarchy level max(k,1)
  const std::vector<uint32_t>* sourceVertex = nullptr;  // null at level 0
};

struct NodeRecord {
  uint32_t level = 0, group = 0, parent = kNoParent, firstChild = 0, childCount = 0;
  NormalCone cone;
  vcg::Point3f center;
  float radius = 0;
  uint32_t faceCount = 0, vertexCount = 0;
  float error = 0;
  std::vector<uint32_t> neighbours;
};

// Faces of each node in node order (counting sort by group, then by the node order of groups).
void BucketFaces(const LevelView& L, const std::vector<uint32_t>& nodeOfGroup, size_t nodes,
                 std::vector<uint32_t>& start, std::vector<uint32_t>& faces) {
  const auto& fg = *L.faceGroup;
  start.assign(nodes + 1, 0);
  for (size_t f = 0; f < fg.size(); ++f) ++start[nodeOfGroup[size_t(fg[f])] + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  faces.resize(fg.size());
  std::vector<uint32_t> at(start.begin(), start.end() - 1);
  for (size_t f = 0; f < fg.size(); ++f) faces[at[nodeOfGroup[size_t(fg[f])]]++] = uint32_t(f);
}

}  // namespace

Status WriteLodFile(const IndexedMesh& mesh, const GroupHierarchy& hierarchy,
                    const std::vector<SimplifiedLevel>& levels, const std::string& path,
                    LodBuildStats* stats, const Progress& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  const int H = hierarchy.levelCount();
  if (H < 1) return Status::Invalid("the group hierarchy has no level");
  if (int(levels.size()) != H)
    return Status::Invalid("expected one simplified level per hierarchy level (" + std::to_string(H) + "), got " +
                           std::to_string(levels.size()));
  if (H + 1 > int(kMaxLevels)) return Status::Invalid("too many hierarchy levels for the file format");
  if (size_t(hierarchy.faceCount) != mesh.faces.size() || mesh.faces.empty())
    return Status::Invalid("the group hierarchy does not match the mesh");
  for (int k = 1; k <= H; ++k) {
    const SimplifiedLevel& S = levels[size_t(k - 1)];
    if (S.level != k || S.faceGroup.size() != S.mesh.faces.size() || S.sourceVertex.size() != S.mesh.positions.size())
      return Status::Invalid("simplified level " + std::to_string(k) + " does not match the hierarchy");
    const size_t groups = hierarchy.level(k).groups.size();
    for (int g : S.faceGroup)
      if (g < 0 || size_t(g) >= groups) return Status::Invalid("simplified level " + std::to_string(k) + " has a bad group id");
    for (const auto& t : S.mesh.faces)
      for (uint32_t v : t)
        if (v >= S.mesh.positions.size()) return Status::Invalid("simplified level " + std::to_string(k) + " has a bad vertex index");
  }
  for (const auto& t : mesh.faces)
    for (uint32_t v : t)
      if (v >= mesh.positions.size()) return Status::Invalid("the mesh has a face with a bad vertex index");
  const uint32_t nodeLevels = uint32_t(H + 1);

  // Node order: the top level's groups in order; each finer level lists the children of the level
  // above node by node, so that a node's children have consecutive ids. Level 0 = level 1's order.
  std::vector<std::vector<uint32_t>> groupOfNode(nodeLevels), nodeOfGroup(nodeLevels);
  {
    auto& top = groupOfNode[size_t(H)];
    top.resize(hierarchy.level(H).groups.size());
    std::iota(top.begin(), top.end(), 0u);
    for (int k = H; k >= 2; --k) {
      const GroupLevel& GL = hierarchy.level(k);
      auto& below = groupOfNode[size_t(k - 1)];
      for (uint32_t g : groupOfNode[size_t(k)]) {
        const Group& G = GL.groups[g];
        for (int c = 0; c < G.childCount; ++c) below.push_back(uint32_t(GL.children[size_t(G.firstChild + c)]));
      }
      if (below.size() != hierarchy.level(k - 1).groups.size())
        return Status::Invalid("the group hierarchy's child lists do not cover level " + std::to_string(k - 1));
    }
    groupOfNode[0] = groupOfNode[1];
    for (uint32_t k = 0; k < nodeLevels; ++k) {
      nodeOfGroup[k].assign(groupOfNode[k].size(), 0);
      for (size_t i = 0; i < groupOfNode[k].size(); ++i) nodeOfGroup[k][groupOfNode[k][i]] = uint32_t(i);
    }
  }
  // First node id of each level: coarsest first.
  std::vector<uint64_t> firstId(nodeLevels + 1, 0);
  {
    uint64_t id = 0;
    for (int k = int(nodeLevels) - 1; k >= 0; --k) {
      firstId[size_t(k)] = id;
      id += groupOfNode[size_t(k)].size();
    }
    firstId[nodeLevels] = id;  // total
    if (id >= kNoParent) return Status::Invalid("too many nodes for the file format");
  }
  const uint64_t nodeCount = firstId[nodeLevels];
  auto nodeId = [&](uint32_t k, uint32_t indexInLevel) { return uint32_t(firstId[k] + indexInLevel); };

  // Group adjacency at hierarchy level 1 from the input's edges, then mapped up through parents.
  // Per level: sorted unique pairs (a < b) of group indices.
  std::vector<std::vector<std::pair<uint32_t, uint32_t>>> adjacency(nodeLevels);
  {
    const FaceAdjacency adj = BuildFaceAdjacency(mesh);
    const auto& fg = hierarchy.level(1).faceGroup;
    auto& pairs = adjacency[1];
    for (uint32_t f = 0; f < mesh.faces.size(); ++f)
      for (uint32_t i = adj.offsets[f]; i < adj.offsets[f + 1]; ++i) {
        const uint32_t a = uint32_t(fg[f]), b = uint32_t(fg[adj.neighbours[i]]);
        if (a < b) pairs.emplace_back(a, b);
      }
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    for (int k = 2; k <= H; ++k) {
      const auto& groupsBelow = hierarchy.level(k - 1).groups;
      auto& up = adjacency[size_t(k)];
      for (const auto& p : adjacency[size_t(k - 1)]) {
        uint32_t a = uint32_t(groupsBelow[p.first].parent), b = uint32_t(groupsBelow[p.second].parent);
        if (a == b) continue;
        if (a > b) std::swap(a, b);
        up.emplace_back(a, b);
      }
      std::sort(up.begin(), up.end());
      up.erase(std::unique(up.begin(), up.end()), up.end());
    }
    adjacency[0] = adjacency[1];
  }

  const vcg::Box3d box = UsedVertexBox(mesh);
  const double diag = box.IsNull() ? 0.0 : box.Diag();
  std::vector<float> levelError(nodeLevels, 0.f);
  {
    double e = 0;
    for (int k = 1; k <= H; ++k) {
      e = std::max(e, levels[size_t(k - 1)].stats.maxCollapseError);
      levelError[size_t(k)] = float(e * diag);
    }
  }
  auto view = [&](uint32_t k) {
    LevelView v;
    if (k == 0) {
      v.mesh = &mesh;
      v.faceGroup = &hierarchy.level(1).faceGroup;
    } else {
      v.mesh = &levels[k - 1].mesh;
      v.faceGroup = &levels[k - 1].faceGroup;
      v.sourceVertex = &levels[k - 1].sourceVertex;
    }
    return v;
  };

  // Pass 1: node records (and the per-level counts).
  std::vector<NodeRecord> records(nodeCount);
  std::vector<uint64_t> levelVertices(nodeLevels, 0), levelFaces(nodeLevels, 0);
  {
    std::vector<uint32_t> start, faces, stamp;
    std::vector<vcg::Point3d> normals;
    for (uint32_t k = 0; k < nodeLevels; ++k) {
      if (progress && !progress(int(40 * k / nodeLevels), "LOD file: node records")) return Status::Cancelled();
      const LevelView L = view(k);
      const size_t nodes = groupOfNode[k].size();
      BucketFaces(L, nodeOfGroup[k], nodes, start, faces);
      levelFaces[k] = L.mesh->faces.size();
      stamp.assign(L.mesh->positions.size(), kNoParent);
      uint64_t usedVertices = 0;
      // Neighbour lists: CSR from the sorted pairs.
      std::vector<uint32_t> nStart(nodes + 1, 0), nList;
      for (const auto& p : adjacency[k]) {
        ++nStart[nodeOfGroup[k][p.first] + 1];
        ++nStart[nodeOfGroup[k][p.second] + 1];
      }
      std::partial_sum(nStart.begin(), nStart.end(), nStart.begin());
      nList.resize(nStart.back());
      {
        std::vector<uint32_t> at(nStart.begin(), nStart.end() - 1);
        for (const auto& p : adjacency[k]) {
          const uint32_t a = nodeOfGroup[k][p.first], b = nodeOfGroup[k][p.second];
          nList[at[a]++] = nodeId(k, b);
          nList[at[b]++] = nodeId(k, a);
        }
      }
      const GroupLevel& GL = hierarchy.level(std::max<int>(1, int(k)));
      for (uint32_t i = 0; i < nodes; ++i) {
        NodeRecord& R = records[nodeId(k, i)];
        const uint32_t g = groupOfNode[k][i];
        R.level = k;
        R.group = g;
        R.error = levelError[k];
        const Group& G = GL.groups[g];
        if (k == 0) {
          R.parent = nodeId(1, i);
        } else {
          R.parent = k == uint32_t(H) ? kNoParent : nodeId(k + 1, nodeOfGroup[k + 1][uint32_t(G.parent)]);
          if (k == 1) {
            R.firstChild = nodeId(0, i);
            R.childCount = 1;
          } else {
            // The children were listed in this node's order: find where they start.
            R.childCount = uint32_t(G.childCount);
            R.firstChild = G.childCount ? nodeId(k - 1, nodeOfGroup[k - 1][uint32_t(GL.children[size_t(G.firstChild)])]) : 0;
          }
        }
        R.neighbours.assign(nList.begin() + nStart[i], nList.begin() + nStart[i + 1]);
        std::sort(R.neighbours.begin(), R.neighbours.end());
        normals.clear();
        vcg::Box3f nb;
        uint32_t vc = 0;
        for (uint32_t j = start[i]; j < start[i + 1]; ++j) {
          const uint32_t f = faces[j];
          vcg::Point3d n;
          double area;
          FaceNormalAndArea(*L.mesh, f, n, area);
          if (area > 0) normals.push_back(n);
          for (uint32_t v : L.mesh->faces[f]) {
            nb.Add(L.mesh->positions[v]);
            if (stamp[v] != i) {
              stamp[v] = i;
              ++vc;
            }
          }
        }
        // Vertices shared with earlier nodes of the level are counted again here: vertexCount is
        // the node's own (local) count. Level vertices are counted at their first use.
        R.cone = normals.empty() ? NormalCone::Empty() : MinimalCone(normals);
        R.faceCount = start[i + 1] - start[i];
        R.vertexCount = vc;
        R.center = nb.IsNull() ? vcg::Point3f(0, 0, 0) : nb.Center();
        float r2 = 0;
        for (uint32_t j = start[i]; j < start[i + 1]; ++j)
          for (uint32_t v : L.mesh->faces[faces[j]]) r2 = std::max(r2, (L.mesh->positions[v] - R.center).SquaredNorm());
        R.radius = std::sqrt(r2) * (1 + 1e-6f);
      }
      std::vector<uint8_t> used(L.mesh->positions.size(), 0);
      for (const auto& t : L.mesh->faces)
        for (uint32_t v : t) used[v] = 1;
      usedVertices = uint64_t(std::count(used.begin(), used.end(), uint8_t(1)));
      levelVertices[k] = usedVertices;
      // Children ids must be consecutive: they are, by construction of the order; check it.
      if (k >= 2)
        for (uint32_t i = 0; i < nodes; ++i) {
          const NodeRecord& R = records[nodeId(k, i)];
          const Group& G = GL.groups[R.group];
          for (int c = 0; c < G.childCount; ++c)
            if (nodeId(k - 1, nodeOfGroup[k - 1][uint32_t(GL.children[size_t(G.firstChild + c)])]) != R.firstChild + uint32_t(c))
              return Status::Invalid("internal error: children are not consecutive");
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

  // The root chunk's header and data, rewritten at the end with the final offsets.
  std::vector<uint64_t> levelOffset(nodeLevels, 0), vertOffset(nodeLevels, 0);
  uint64_t hierOffset = 0, indexOffset = 0;
  auto encodeHeader = [&]() {
    Encoder e;
    e.u32(kVersion);
    e.u32(nodeLevels);
    e.u64(mesh.positions.size());
    e.u64(mesh.faces.size());
    e.u64(nodeCount);
    for (int i = 0; i < 3; ++i) e.f32(box.IsNull() ? 0.f : float(box.min[i]));
    for (int i = 0; i < 3; ++i) e.f32(box.IsNull() ? 0.f : float(box.max[i]));
    e.u64(hierOffset);
    e.u64(indexOffset);
    e.u32(kVertexBlock);
    e.u32(kIndexBlock);
    for (uint32_t k = 0; k < nodeLevels; ++k) {
      e.u64(levelFaces[k]);
      e.u64(groupOfNode[k].size());
      e.u64(levelVertices[k]);
      e.u64(firstId[k]);
      e.u64(levelOffset[k]);
      e.u64(vertOffset[k]);
      e.f32(levelError[k]);
      e.u32(0);
    }
    return e;
  };
  Encoder header = encodeHeader();
  const uint64_t headerBytes = header.bytes.size();
  out.chunk(kRoot, header);  // placeholder: rewritten at the end

  // Node records, coarsest level first (node id order).
  struct IndexEntry { uint64_t record = 0, geometry = 0; uint32_t recordBytes = 0, geometryBytes = 0; };
  std::vector<IndexEntry> index(nodeCount);
  hierOffset = out.offset();
  {
    Encoder none;
    out.chunk(kHier, none);  // placeholder for the child size
    Encoder e;
    for (uint32_t id = 0; id < nodeCount; ++id) {
      const NodeRecord& R = records[id];
      e.clear();
      e.u32(id);
      e.u32(R.level);
      e.u32(R.group);
      e.u32(R.parent);
      e.u32(R.firstChild);
      e.u32(R.childCount);
      for (int i = 0; i < 3; ++i) e.f64(R.cone.axis[i]);
      e.f64(R.cone.halfAngle);
      for (int i = 0; i < 3; ++i) e.f32(R.center[i]);
      e.f32(R.radius);
      e.u32(R.faceCount);
      e.u32(R.vertexCount);
      e.f32(R.error);
      e.u32(uint32_t(R.neighbours.size()));
      for (uint32_t n : R.neighbours) e.u32(n);
      index[id].record = out.offset();
      index[id].recordBytes = uint32_t(kChunkHeaderBytes + e.bytes.size());
      out.chunk(kNode, e);
    }
    ChunkHeader h;
    h.id = kHier;
    h.crc = Crc32(nullptr, 0);
    h.childBytes = out.offset() - hierOffset - kChunkHeaderBytes;
    Encoder he;
    EncodeChunkHeader(he, h);
    out.patch(hierOffset, he);
  }
  records.clear();
  records.shrink_to_fit();

  // Geometry, coarsest level first.
  {
    std::vector<uint32_t> start, faces, levelId, local, order, verts;
    std::vector<vcg::Point3f> block;
    Encoder e;
    for (int k = int(nodeLevels) - 1; k >= 0; --k) {
      if (progress && !progress(40 + int(55 * (int(nodeLevels) - 1 - k) / int(nodeLevels)), "LOD file: geometry")) {
        fail("cancelled");  // removes the partial file
        return Status::Cancelled();
      }
      const LevelView L = view(uint32_t(k));
      const size_t nodes = groupOfNode[size_t(k)].size();
      BucketFaces(L, nodeOfGroup[size_t(k)], nodes, start, faces);
      // Level vertex ids by first use in node order.
      levelId.assign(L.mesh->positions.size(), kNoParent);
      order.clear();
      for (uint32_t f : faces)
        for (uint32_t v : L.mesh->faces[f])
          if (levelId[v] == kNoParent) {
            levelId[v] = uint32_t(order.size());
            order.push_back(v);
          }
      levelOffset[size_t(k)] = out.offset();
      e.clear();
      e.u32(uint32_t(k));
      e.u32(0);
      e.u64(nodes);
      e.u64(L.mesh->faces.size());
      e.u64(order.size());
      out.chunk(kLevel, e);  // child size patched below
      vertOffset[size_t(k)] = out.offset();
      const uint64_t blocks = (order.size() + kVertexBlock - 1) / kVertexBlock;
      e.clear();
      e.u32(uint32_t(k));
      e.u32(kVertexBlock);
      e.u64(order.size());
      out.chunk(kVert, e, blocks * kChunkHeaderBytes + order.size() * 12);
      for (uint64_t b = 0; b < blocks; ++b) {
        e.clear();
        const size_t end = std::min<size_t>(order.size(), size_t((b + 1) * kVertexBlock));
        for (size_t v = size_t(b * kVertexBlock); v < end; ++v)
          for (int i = 0; i < 3; ++i) e.f32(L.mesh->positions[order[v]][i]);
        out.chunk(kVBlock, e);
      }
      local.assign(L.mesh->positions.size(), kNoParent);
      for (uint32_t i = 0; i < nodes; ++i) {
        const uint32_t id = nodeId(uint32_t(k), i);
        // Local vertices by first use within the node.
        verts.clear();
        for (uint32_t j = start[i]; j < start[i + 1]; ++j)
          for (uint32_t v : L.mesh->faces[faces[j]])
            if (local[v] == kNoParent) {
              local[v] = uint32_t(verts.size());
              verts.push_back(v);
            }
        e.clear();
        e.u32(id);
        e.u32(uint32_t(verts.size()));
        e.u32(start[i + 1] - start[i]);
        const bool shortIndices = verts.size() <= 65536;
        e.u32((k == 0 ? kGeomHasSourceIds : 0) | (shortIndices ? kGeomShortIndices : 0));
        for (uint32_t v : verts) e.u32(levelId[v]);
        if (k == 0)
          for (uint32_t v : verts) e.u32(v);
        for (uint32_t j = start[i]; j < start[i + 1]; ++j)
          for (uint32_t v : L.mesh->faces[faces[j]]) shortIndices ? e.u16(local[v]) : e.u32(local[v]);
        for (uint32_t v : verts) local[v] = kNoParent;
        index[id].geometry = out.offset();
        index[id].geometryBytes = uint32_t(kChunkHeaderBytes + e.bytes.size());
        out.chunk(kGeom, e);
      }
      // Patch the LEVL chunk's child size.
      ChunkHeader h;
      h.id = kLevel;
      Encoder d;
      d.u32(uint32_t(k));
      d.u32(0);
      d.u64(nodes);
      d.u64(L.mesh->faces.size());
      d.u64(order.size());
      h.dataBytes = d.bytes.size();
      h.crc = Crc32(d.bytes.data(), d.bytes.size());
      h.childBytes = out.offset() - levelOffset[size_t(k)] - kChunkHeaderBytes - h.dataBytes;
      Encoder he;
      EncodeChunkHeader(he, h);
      out.patch(levelOffset[size_t(k)], he);
      if (!out.ok()) return fail(out.error());
    }
  }

  // The offset index, in blocks.
  indexOffset = out.offset();
  {
    const uint64_t blocks = (nodeCount + kIndexBlock - 1) / kIndexBlock;
    Encoder e;
    e.u64(nodeCount);
    e.u32(kIndexBlock);
    e.u32(0);
    out.chunk(kIndex, e, blocks * kChunkHeaderBytes + nodeCount * kIndexEntryBytes);
    for (uint64_t b = 0; b < blocks; ++b) {
      e.clear();
      const uint64_t end = std::min<uint64_t>(nodeCount, (b + 1) * kIndexBlock);
      for (uint64_t i = b * kIndexBlock; i < end; ++i) {
        e.u64(index[i].record);
        e.u64(index[i].geometry);
        e.u32(index[i].recordBytes);
        e.u32(index[i].geometryBytes);
      }
      out.chunk(kIBlock, e);
    }
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
    stats->inputVertices = mesh.positions.size();
    stats->inputFaces = mesh.faces.size();
    stats->levels = int(nodeLevels);
    stats->levelFaces.assign(levelFaces.begin(), levelFaces.end());
    stats->levelNodes.clear();
    for (uint32_t k = 0; k < nodeLevels; ++k) stats->levelNodes.push_back(groupOfNode[k].size());
    stats->nodes = size_t(nodeCount);
    stats->fileBytes = fileBytes;
    stats->writeSeconds = Seconds(t0);
  }
  return Status::Ok();
}

Status BuildLodFile(const IndexedMesh& mesh, const LodBuildParams& params, const std::string& path,
                    LodBuildStats* stats, const Progress& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  GroupHierarchy hierarchy;
  Status s = BuildConeHierarchy(mesh, params.grouping, hierarchy, SubProgress(progress, 0, 25));
  if (!s.ok()) return s;
  const double groupingSeconds = Seconds(t0);
  const auto t1 = std::chrono::steady_clock::now();
  std::vector<SimplifiedLevel> levels;
  s = BuildSimplifiedLevels(mesh, hierarchy, params.simplification, levels, SubProgress(progress, 25, 90));
  if (!s.ok()) return s;
  const double simplifySeconds = Seconds(t1);
  s = WriteLodFile(mesh, hierarchy, levels, path, stats, SubProgress(progress, 90, 100));
  if (!s.ok()) return s;
  if (stats) {
    stats->groupingSeconds = groupingSeconds;
    stats->simplifySeconds = simplifySeconds;
    stats->seconds = Seconds(t0);
  }
  return Status::Ok();
}

}  // namespace conelod
