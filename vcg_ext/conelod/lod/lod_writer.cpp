// ConeLOD — writing the .clod file (lod_build.h; byte layout in lod_format.md).
//
// Kamiya, Suzuki, Kawachi, §8: a file of chunks, each an id, its size and its data followed by
// sub-chunks. The writer takes the cluster DAG (lod_dag.cpp), first computes the small per-node
// records (cone, sphere, errors, the children / siblings / parents lists: about 100-150 bytes a
// node), then streams the geometry level by level, coarsest first, through one reused buffer:
// besides the DAG it holds only the level's face order and vertex renumbering. Container sizes
// and the header's offsets are patched in place at the end.
#include "conelod/lod/lod_build.h"
#include "conelod/lod/lod_read.h"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numeric>

#include "conelod/lod/lod_internal.h"
#include "conelod/mesh/mesh_check.h"
#include "conelod/mesh/safe_file.h"

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
  float error = 0, parentError = 0;
};

// Faces of each node of a level in node order (counting sort by node).
void BucketFaces(const LodDag::Level& L, const std::vector<uint32_t>& nodeOfCluster, std::vector<uint32_t>& start,
                 std::vector<uint32_t>& faces) {
  const size_t nodes = nodeOfCluster.size();
  start.assign(nodes + 1, 0);
  for (uint32_t c : L.faceCluster) ++start[nodeOfCluster[c] + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  faces.resize(L.faceCluster.size());
  std::vector<uint32_t> at(start.begin(), start.end() - 1);
  for (size_t f = 0; f < L.faceCluster.size(); ++f) faces[at[nodeOfCluster[L.faceCluster[f]]]++] = uint32_t(f);
}

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

}  // namespace

Status WriteLodFile(const IndexedMesh& mesh, const LodDag& dag, const std::string& path, LodBuildStats* stats,
                    const Progress& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  const size_t H = dag.levels.size();
  if (H < 1) return Status::Invalid("the LOD DAG has no level");
  if (H > kMaxLevels) return Status::Invalid("too many LOD levels for the file format");
  if (dag.levels[0].faces != mesh.faces || mesh.faces.empty() || dag.inputVertices != mesh.positions.size() ||
      dag.positions.size() < mesh.positions.size())
    return Status::Invalid("the LOD DAG does not match the mesh");
  if (dag.positions.size() >= kNoParent) return Status::Invalid("too many vertices for the file format");
  for (size_t k = 0; k < H; ++k) {
    const LodDag::Level& L = dag.levels[k];
    const std::string bad = "LOD level " + std::to_string(k) + " is inconsistent";
    const size_t C = L.clusterCount();
    if (L.faceCluster.size() != L.faces.size() || L.clusterCreator.size() != C || L.clusterError.size() != C || C == 0)
      return Status::Invalid(bad);
    for (uint32_t c : L.faceCluster)
      if (c >= C) return Status::Invalid(bad);
    for (const auto& t : L.faces)
      for (uint32_t v : t)
        if (v >= dag.positions.size()) return Status::Invalid(bad + " (a bad vertex index)");
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
  // Node ids per cluster, per level.
  std::vector<std::vector<uint32_t>> idOfCluster(H);
  for (size_t k = 0; k < H; ++k) {
    idOfCluster[k].resize(nodeOfCluster[k].size());
    for (size_t c = 0; c < nodeOfCluster[k].size(); ++c) idOfCluster[k][c] = uint32_t(firstId[k] + nodeOfCluster[k][c]);
  }

  const vcg::Box3d box = UsedVertexBox(mesh);
  std::vector<float> levelError(nodeLevels, 0.f);
  for (size_t k = 0; k < H; ++k)
    for (float e : dag.levels[k].clusterError) levelError[k] = std::max(levelError[k], e);

  // Pass 1: node records (and the per-level counts).
  std::vector<NodeRecord> records(nodeCount);
  std::vector<uint64_t> levelVertices(nodeLevels, 0), levelFaces(nodeLevels, 0);
  {
    std::vector<uint32_t> start, faces, stamp(dag.positions.size(), kNoParent);
    std::vector<uint8_t> used(dag.positions.size(), 0);
    std::vector<vcg::Point3d> normals;
    std::vector<uint32_t> byGroupStart, byGroup, byCreatorStart, byCreator, aboveStart, above;
    for (uint32_t k = 0; k < nodeLevels; ++k) {
      if (progress && !progress(int(40 * k / nodeLevels), "LOD file: node records")) return Status::Cancelled();
      const LodDag::Level& L = dag.levels[k];
      BucketFaces(L, nodeOfCluster[k], start, faces);
      levelFaces[k] = L.faces.size();
      ListBy(L.clusterCreator, k ? dag.levels[k - 1].groupError.size() : 0, idOfCluster[k], byCreatorStart, byCreator);
      if (k > 0)
        ListBy(dag.levels[k - 1].clusterGroup, dag.levels[k - 1].groupError.size(), idOfCluster[k - 1], byGroupStart,
               byGroup);
      if (k + 1 < nodeLevels)
        ListBy(dag.levels[k + 1].clusterCreator, L.groupError.size(), idOfCluster[k + 1], aboveStart, above);
      for (uint32_t i = 0; i < clusterOfNode[k].size(); ++i) {
        const uint32_t c = clusterOfNode[k][i];
        NodeRecord& R = records[firstId[k] + i];
        R.level = k;
        R.error = L.clusterError[c];
        if (k == 0) {
          R.siblings.assign(1, uint32_t(firstId[k] + i));
        } else {
          const size_t cr = size_t(L.clusterCreator[c]);
          R.children.assign(byGroup.begin() + byGroupStart[cr], byGroup.begin() + byGroupStart[cr + 1]);
          R.siblings.assign(byCreator.begin() + byCreatorStart[cr], byCreator.begin() + byCreatorStart[cr + 1]);
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
        vcg::Box3f nb;
        uint32_t vc = 0;
        for (uint32_t j = start[i]; j < start[i + 1]; ++j) {
          const auto& t = L.faces[faces[j]];
          const vcg::Point3d a = vcg::Point3d::Construct(dag.positions[t[0]]),
                             b = vcg::Point3d::Construct(dag.positions[t[1]]),
                             cc = vcg::Point3d::Construct(dag.positions[t[2]]);
          const vcg::Point3d n = (b - a) ^ (cc - a);
          const double len = n.Norm();
          const double scale = std::max({(b - a).SquaredNorm(), (cc - a).SquaredNorm(), (cc - b).SquaredNorm()});
          if (len > 1e-12 * scale && len > 0) normals.push_back(n / len);
          for (uint32_t v : t) {
            nb.Add(dag.positions[v]);
            used[v] = 1;
            if (stamp[v] != i) {
              stamp[v] = i;
              ++vc;
            }
          }
        }
        R.cone = normals.empty() ? NormalCone::Empty() : MinimalCone(normals);
        R.faceCount = start[i + 1] - start[i];
        R.vertexCount = vc;
        R.center = nb.IsNull() ? vcg::Point3f(0, 0, 0) : nb.Center();
        float r2 = 0;
        for (uint32_t j = start[i]; j < start[i + 1]; ++j)
          for (uint32_t v : L.faces[faces[j]]) r2 = std::max(r2, (dag.positions[v] - R.center).SquaredNorm());
        R.radius = std::sqrt(r2) * (1 + 1e-6f);
      }
      uint64_t usedVertices = 0;
      for (const auto& t : L.faces)
        for (uint32_t v : t)
          if (used[v] == 1) {
            used[v] = 2;
            ++usedVertices;
          }
      for (const auto& t : L.faces)
        for (uint32_t v : t) used[v] = 0;
      std::fill(stamp.begin(), stamp.end(), kNoParent);
      levelVertices[k] = usedVertices;
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
    e.u64(dag.positions.size());
    for (int i = 0; i < 3; ++i) e.f32(box.IsNull() ? 0.f : float(box.min[i]));
    for (int i = 0; i < 3; ++i) e.f32(box.IsNull() ? 0.f : float(box.max[i]));
    e.u64(hierOffset);
    e.u64(indexOffset);
    e.u32(kVertexBlock);
    e.u32(kIndexBlock);
    for (uint32_t k = 0; k < nodeLevels; ++k) {
      e.u64(levelFaces[k]);
      e.u64(clusterOfNode[k].size());
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
  struct IndexEntry {
    uint64_t record = 0, geometry = 0;
    uint32_t recordBytes = 0, geometryBytes = 0;
  };
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
      e.u32(uint32_t(R.children.size()));
      e.u32(uint32_t(R.siblings.size()));
      e.u32(uint32_t(R.parents.size()));
      for (int i = 0; i < 3; ++i) e.f64(R.cone.axis[i]);
      e.f64(R.cone.halfAngle);
      for (int i = 0; i < 3; ++i) e.f32(R.center[i]);
      e.f32(R.radius);
      e.u32(R.faceCount);
      e.u32(R.vertexCount);
      e.f32(R.error);
      e.f32(R.parentError);
      for (uint32_t n : R.children) e.u32(n);
      for (uint32_t n : R.siblings) e.u32(n);
      for (uint32_t n : R.parents) e.u32(n);
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
    std::vector<uint32_t> start, faces, levelId(dag.positions.size(), kNoParent),
        local(dag.positions.size(), kNoParent), order, verts;
    std::vector<vcg::Point3f> block;
    Encoder e;
    for (int k = int(nodeLevels) - 1; k >= 0; --k) {
      if (progress && !progress(40 + int(55 * (int(nodeLevels) - 1 - k) / int(nodeLevels)), "LOD file: geometry")) {
        fail("cancelled");  // removes the partial file
        return Status::Cancelled();
      }
      const LodDag::Level& L = dag.levels[size_t(k)];
      const size_t nodes = clusterOfNode[size_t(k)].size();
      BucketFaces(L, nodeOfCluster[size_t(k)], start, faces);
      // Level vertex ids by first use in node order.
      order.clear();
      for (uint32_t f : faces)
        for (uint32_t v : L.faces[f])
          if (levelId[v] == kNoParent) {
            levelId[v] = uint32_t(order.size());
            order.push_back(v);
          }
      levelOffset[size_t(k)] = out.offset();
      e.clear();
      e.u32(uint32_t(k));
      e.u32(0);
      e.u64(nodes);
      e.u64(L.faces.size());
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
          for (int i = 0; i < 3; ++i) e.f32(dag.positions[order[v]][i]);
        out.chunk(kVBlock, e);
      }
      for (uint32_t i = 0; i < nodes; ++i) {
        const uint32_t id = uint32_t(firstId[size_t(k)] + i);
        // Local vertices by first use within the node.
        verts.clear();
        for (uint32_t j = start[i]; j < start[i + 1]; ++j)
          for (uint32_t v : L.faces[faces[j]])
            if (local[v] == kNoParent) {
              local[v] = uint32_t(verts.size());
              verts.push_back(v);
            }
        e.clear();
        e.u32(id);
        e.u32(uint32_t(verts.size()));
        e.u32(start[i + 1] - start[i]);
        const bool shortIndices = verts.size() <= 65536;
        e.u32(kGeomHasSourceIds | (shortIndices ? kGeomShortIndices : 0));
        for (uint32_t v : verts) e.u32(levelId[v]);
        for (uint32_t v : verts) e.u32(v);
        for (uint32_t j = start[i]; j < start[i + 1]; ++j)
          for (uint32_t v : L.faces[faces[j]]) shortIndices ? e.u16(local[v]) : e.u32(local[v]);
        for (uint32_t v : verts) local[v] = kNoParent;
        index[id].geometry = out.offset();
        index[id].geometryBytes = uint32_t(kChunkHeaderBytes + e.bytes.size());
        out.chunk(kGeom, e);
      }
      for (uint32_t v : order) levelId[v] = kNoParent;
      // Patch the LEVL chunk's child size.
      ChunkHeader h;
      h.id = kLevel;
      Encoder d;
      d.u32(uint32_t(k));
      d.u32(0);
      d.u64(nodes);
      d.u64(L.faces.size());
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
    for (uint32_t k = 0; k < nodeLevels; ++k) stats->levelNodes.push_back(clusterOfNode[k].size());
    stats->nodes = size_t(nodeCount);
    stats->fileBytes = fileBytes;
    stats->writeSeconds = Seconds(t0);
  }
  return Status::Ok();
}

Status BuildLodFile(const IndexedMesh& mesh, const LodBuildParams& params, const std::string& path,
                    LodBuildStats* stats, const Progress& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  Status s = RequireValidForFaces(mesh);
  if (!s.ok()) return s;
  // Vertices at one position are one vertex of the DAG (a seam the file repeats would otherwise be
  // simplified from each side on its own, and the cuts would open along it); unreferenced vertices
  // are not written.
  const WeldResult welded = WeldByPosition(mesh);
  LodDag dag;
  s = BuildLodDag(welded.mesh, params, dag, SubProgress(progress, 0, 90));
  if (!s.ok()) return s;
  const double dagSeconds = Seconds(t0);
  s = WriteLodFile(welded.mesh, dag, path, stats, SubProgress(progress, 90, 100));
  if (!s.ok()) return s;
  if (stats) {
    stats->mergedVertices = welded.mergedVertices;
    stats->droppedVertices = welded.droppedVertices;
    stats->groupingSeconds = 0;
    stats->simplifySeconds = dagSeconds;
    stats->seconds = Seconds(t0);
  }
  return Status::Ok();
}

}  // namespace conelod
