// ConeLOD — conversions between any vcg triangle mesh (MeshLab's CMeshO, the CLI's mesh) and the
// core's IndexedMesh, and the writing of group results back as named per-face attributes,
// per-face quality and per-face colour.
//
// Requirements: per-face quality and colour for WriteGroupResults (checked with vcg's Require*).
#pragma once

#include <string>
#include <vector>

#include <vcg/complex/complex.h>

#include "conelod/grouping/group_colors.h"
#include "conelod/grouping/group_hierarchy.h"
#include "conelod/mesh/indexed_mesh.h"
#include "conelod/mesh/weld.h"

namespace conelod {

// Name of the per-face int attribute holding the group id at hierarchy level `level` (1-based).
inline std::string GroupAttributeName(int level) { return "conelod_group_L" + std::to_string(level); }

// Live (non-deleted) faces and the vertices they and the live vertices use. faceOfIndex[i] is the
// mesh face that became IndexedMesh face i.
template <class MeshType>
IndexedMesh ToIndexedMesh(const MeshType& m, std::vector<size_t>* faceOfIndex = nullptr) {
  IndexedMesh out;
  std::vector<uint32_t> remap(m.vert.size(), UINT32_MAX);
  out.positions.reserve(size_t(m.vn));
  for (size_t i = 0; i < m.vert.size(); ++i) {
    if (m.vert[i].IsD()) continue;
    remap[i] = uint32_t(out.positions.size());
    const auto& p = m.vert[i].cP();
    out.positions.emplace_back(float(p[0]), float(p[1]), float(p[2]));
  }
  out.faces.reserve(size_t(m.fn));
  if (faceOfIndex) {
    faceOfIndex->clear();
    faceOfIndex->reserve(size_t(m.fn));
  }
  for (size_t i = 0; i < m.face.size(); ++i) {
    const auto& f = m.face[i];
    if (f.IsD()) continue;
    std::array<uint32_t, 3> t;
    for (int k = 0; k < 3; ++k) {
      const auto* v = f.cV(k);
      const size_t vi = size_t(v - &m.vert[0]);
      t[size_t(k)] = (v && vi < m.vert.size()) ? remap[vi] : UINT32_MAX;
    }
    out.faces.push_back(t);
    if (faceOfIndex) faceOfIndex->push_back(i);
  }
  return out;
}

// The working copy the grouping, the group-preserving collapse and the LOD build run on:
// ToIndexedMesh(m) with its vertices welded by exact position and its unreferenced vertices left
// out (weld.h), so that a seam the mesh repeats is no border to them. Faces keep ToIndexedMesh's
// order (faceOfIndex as there), so per-face results map back as they are; `representative`
// (optional): per welded vertex, the ToIndexedMesh vertex it stands for (for ApplySimplifiedMesh,
// MapToRepresentatives). `m` itself is not changed.
template <class MeshType>
IndexedMesh ToWeldedIndexedMesh(const MeshType& m, std::vector<size_t>* faceOfIndex = nullptr,
                                std::vector<uint32_t>* representative = nullptr) {
  WeldResult w = WeldByPosition(ToIndexedMesh(m, faceOfIndex));
  if (representative) *representative = std::move(w.representative);
  return std::move(w.mesh);
}

// Replaces each vertex index of `sourceVertex` (into a welded mesh) by its representative.
inline void MapToRepresentatives(const std::vector<uint32_t>& representative, std::vector<uint32_t>& sourceVertex) {
  for (uint32_t& v : sourceVertex) v = representative[v];
}

// Writes, for every level k, the per-face int attribute GroupAttributeName(k); per-face quality =
// group id at `displayLevel` and a distinct colour per group. Only call on success: the mesh is
// changed here and nowhere else.
template <class MeshType>
void WriteGroupResults(MeshType& m, const std::vector<size_t>& faceOfIndex, const GroupHierarchy& h, int displayLevel) {
  vcg::tri::RequirePerFaceQuality(m);
  vcg::tri::RequirePerFaceColor(m);
  for (int level = 1; level <= h.levelCount(); ++level) {
    auto attr = vcg::tri::Allocator<MeshType>::template GetPerFaceAttribute<int>(m, GroupAttributeName(level));
    const auto& fg = h.level(level).faceGroup;
    for (auto& f : m.face) attr[f] = -1;
    for (size_t i = 0; i < faceOfIndex.size(); ++i) attr[m.face[faceOfIndex[i]]] = fg[i];
  }
  // Levels of an earlier run above this run's top would be stale: remove them.
  for (int level = h.levelCount() + 1;; ++level) {
    auto stale = vcg::tri::Allocator<MeshType>::template FindPerFaceAttribute<int>(m, GroupAttributeName(level));
    if (!vcg::tri::Allocator<MeshType>::IsValidHandle(m, stale)) break;
    vcg::tri::Allocator<MeshType>::DeletePerFaceAttribute(m, stale);
  }
  const auto& fg = h.level(displayLevel).faceGroup;
  for (size_t i = 0; i < faceOfIndex.size(); ++i) {
    auto& f = m.face[faceOfIndex[i]];
    f.Q() = typename MeshType::FaceType::QualityType(fg[i]);
    f.C() = GroupColor(fg[i]);
  }
}

// Applies a simplification computed on ToIndexedMesh(m, &faceOfIndex) to `m` in place: the faces
// and vertices that the simplification removed are deleted, the kept vertices take their new
// positions and the kept faces their new vertices; then the vectors are compacted. Kept faces and
// vertices keep all their data (quality, colour, named attributes). sourceFace/sourceVertex: per
// face/vertex of `simplified`, the IndexedMesh face/vertex it was (group_qem.h's GroupQemResult).
// Topology (FF/VF adjacency), bounding box and normals are the caller's to update.
template <class MeshType>
void ApplySimplifiedMesh(MeshType& m, const std::vector<size_t>& faceOfIndex, const IndexedMesh& simplified,
                         const std::vector<uint32_t>& sourceFace, const std::vector<uint32_t>& sourceVertex) {
  using CoordType = typename MeshType::CoordType;
  using ScalarType = typename MeshType::ScalarType;
  std::vector<size_t> vertOfIndex;  // ToIndexedMesh keeps the live vertices in order
  vertOfIndex.reserve(size_t(m.vn));
  for (size_t i = 0; i < m.vert.size(); ++i)
    if (!m.vert[i].IsD()) vertOfIndex.push_back(i);
  std::vector<char> keepVertex(m.vert.size(), 0), keepFace(m.face.size(), 0);
  for (size_t o = 0; o < sourceVertex.size(); ++o) {
    auto& v = m.vert[vertOfIndex[sourceVertex[o]]];
    keepVertex[vertOfIndex[sourceVertex[o]]] = 1;
    const auto& p = simplified.positions[o];
    v.P() = CoordType(ScalarType(p[0]), ScalarType(p[1]), ScalarType(p[2]));
  }
  for (size_t o = 0; o < sourceFace.size(); ++o) {
    auto& f = m.face[faceOfIndex[sourceFace[o]]];
    keepFace[faceOfIndex[sourceFace[o]]] = 1;
    for (int k = 0; k < 3; ++k) f.V(k) = &m.vert[vertOfIndex[sourceVertex[simplified.faces[o][size_t(k)]]]];
  }
  for (size_t i = 0; i < m.face.size(); ++i)
    if (!m.face[i].IsD() && !keepFace[i]) vcg::tri::Allocator<MeshType>::DeleteFace(m, m.face[i]);
  for (size_t i = 0; i < m.vert.size(); ++i)
    if (!m.vert[i].IsD() && !keepVertex[i]) vcg::tri::Allocator<MeshType>::DeleteVertex(m, m.vert[i]);
  vcg::tri::Allocator<MeshType>::CompactEveryVector(m);
}

// Per-face int attribute `attributeName` = cluster id (-1 for faces not in the indexed mesh), per-face
// quality = cluster id and a distinct colour per cluster. Only call on success.
template <class MeshType>
void WriteFaceClusters(MeshType& m, const std::vector<size_t>& faceOfIndex, const std::vector<int>& faceCluster,
                       const std::string& attributeName) {
  vcg::tri::RequirePerFaceQuality(m);
  vcg::tri::RequirePerFaceColor(m);
  auto attr = vcg::tri::Allocator<MeshType>::template GetPerFaceAttribute<int>(m, attributeName);
  for (auto& f : m.face) attr[f] = -1;
  for (size_t i = 0; i < faceOfIndex.size(); ++i) {
    auto& f = m.face[faceOfIndex[i]];
    attr[f] = faceCluster[i];
    f.Q() = typename MeshType::FaceType::QualityType(faceCluster[i]);
    f.C() = GroupColor(faceCluster[i]);
  }
}

// Appends the indexed mesh to `m` (an empty mesh normally): vertices, then faces in order.
template <class MeshType>
void AppendIndexedMesh(MeshType& m, const IndexedMesh& in) {
  const size_t firstVertex = m.vert.size();
  auto vi = vcg::tri::Allocator<MeshType>::AddVertices(m, in.positions.size());
  for (const auto& p : in.positions) {
    vi->P() = typename MeshType::CoordType(p[0], p[1], p[2]);
    ++vi;
  }
  auto fi = vcg::tri::Allocator<MeshType>::AddFaces(m, in.faces.size());
  for (const auto& t : in.faces) {
    for (int k = 0; k < 3; ++k) fi->V(k) = &m.vert[firstVertex + t[size_t(k)]];
    ++fi;
  }
}

}  // namespace conelod
