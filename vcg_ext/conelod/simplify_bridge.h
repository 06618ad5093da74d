// ConeLOD — writes a FeatureSimplifyResult (feature_simplify.h) back into the vcg mesh it came
// from, in place, and marks the feature lines for display.
//
// The simplification only removes vertices and faces (half-edge collapses and edge swaps never
// create a vertex), so the surviving vertices and faces keep every attribute they had: colour,
// quality, normals, texture coordinates per vertex, named attributes. MeanSurvivorColours then
// gives each survivor the colour that stands for the vertices it took over.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include <vcg/complex/complex.h>

#include "conelod/feature/feature_simplify.h"

namespace conelod {

// Name of the per-vertex int attribute holding the VertexClass of each vertex after a
// feature-preserving simplification (0 = V_K smooth, 1 = V_M feature line, 2 = V_C feature vertex).
inline const char* VertexClassAttributeName() { return "conelod_vertex_class"; }

// Issue 26. A half-edge collapse keeps the survivor where it was, so its own colour is the input
// surface's colour at that one point; but each output vertex now stands for the input vertices
// its collapses took over (FeatureSimplifyResult::survivor). Gives each output vertex the colour
// (RGBA, 0-255, rounded and clamped) that Garland & Heckbert's extended quadric of those input
// vertices gives at its position (as attribute_quadric.h, with positions that do not move): on
// each input face of each such vertex the colour is linear in position, and the output vertex
// takes the mean of those linear functions at its position, each face weighted by a third of its
// area per corner it has in the cluster. A constant colour stays exact, so does a colour linear
// in position on a flat region. A vertex whose faces all have zero area keeps its colour. Nothing
// is done when the mesh has no per-vertex colour. Call on the mesh as it was given to
// ToIndexedMesh (before WriteSimplifiedMesh); only on success. Texture coordinates and normals
// stay the survivor's own: the texture is sampled at the survivor's exact coordinates, which are
// right for its unchanged position.
template <class MeshType>
void MeanSurvivorColours(MeshType& m, const FeatureSimplifyResult& r) {
  if (!vcg::tri::HasPerVertexColor(m)) return;
  using VertexPointer = typename MeshType::VertexPointer;
  std::vector<VertexPointer> vertexOfIndex;
  std::vector<uint32_t> indexOfSlot(m.vert.size(), UINT32_MAX);
  for (auto& v : m.vert)
    if (!v.IsD()) {
      indexOfSlot[size_t(&v - &m.vert[0])] = uint32_t(vertexOfIndex.size());
      vertexOfIndex.push_back(&v);
    }
  std::vector<std::array<double, 5>> sum(r.inputVertex.size(), std::array<double, 5>{{0, 0, 0, 0, 0}});
  for (auto& f : m.face) {
    if (f.IsD()) continue;
    const vcg::Point3d p0 = vcg::Point3d::Construct(f.V(0)->P()), e1 = vcg::Point3d::Construct(f.V(1)->P()) - p0,
                       e2 = vcg::Point3d::Construct(f.V(2)->P()) - p0;
    const vcg::Point3d n = e1 ^ e2;
    const double n2 = n.SquaredNorm();
    if (!(n2 > 0)) continue;
    const double third = std::sqrt(n2) / 6.0;
    for (int j = 0; j < 3; ++j) {
      const uint32_t i = indexOfSlot[size_t(f.V(j) - &m.vert[0])];
      const uint32_t o = i < r.survivor.size() ? r.survivor[i] : UINT32_MAX;
      if (o == UINT32_MAX) continue;
      const vcg::Point3d q = vcg::Point3d::Construct(vertexOfIndex[r.inputVertex[o]]->P()) - p0;
      for (int k = 0; k < 4; ++k) {
        const double c0 = f.V(0)->C()[k], c1 = f.V(1)->C()[k], c2 = f.V(2)->C()[k];
        const vcg::Point3d g = ((e2 ^ n) * (c1 - c0) + (n ^ e1) * (c2 - c0)) / n2;
        sum[o][size_t(k)] += third * (c0 + g * q);
      }
      sum[o][4] += third;
    }
  }
  for (size_t o = 0; o < r.inputVertex.size(); ++o) {
    if (!(sum[o][4] > 0)) continue;
    auto& c = vertexOfIndex[r.inputVertex[o]]->C();
    for (int k = 0; k < 4; ++k)
      c[k] = (unsigned char)std::min(255L, std::max(0L, std::lround(sum[o][size_t(k)] / sum[o][4])));
  }
}

// `faceOfIndex` is the map returned by ToIndexedMesh (indexed face -> mesh face); indexed
// vertices are the mesh's non-deleted vertices in order (as ToIndexedMesh numbers them).
// Faces that did not survive are deleted, so are the vertices the collapses removed (vertices
// that no face used before are kept); the vertex classes go to the per-vertex attribute
// VertexClassAttributeName(); the vectors are compacted. Only call on success.
//
// With `markFeatures`: selects the feature vertices (V_C and V_M), colours the vertices (V_M
// red, V_C blue, others light grey) when the mesh has per-vertex colour, selects the feature
// edges (face-edge selection) and sets every other edge "faux", so that MeshLab's wireframe
// view draws the feature edges only (as its "Select Crease Edges" filter does).
template <class MeshType>
void WriteSimplifiedMesh(MeshType& m, const std::vector<size_t>& faceOfIndex, const FeatureSimplifyResult& r,
                         bool markFeatures) {
  using VertexPointer = typename MeshType::VertexPointer;
  std::vector<VertexPointer> vertexOfIndex;
  vertexOfIndex.reserve(size_t(m.vn));
  for (auto& v : m.vert)
    if (!v.IsD()) vertexOfIndex.push_back(&v);
  auto slot = [&m](VertexPointer v) { return size_t(v - &m.vert[0]); };
  std::vector<char> usedBefore(m.vert.size(), 0), usedAfter(m.vert.size(), 0);
  for (auto& f : m.face)
    if (!f.IsD())
      for (int k = 0; k < 3; ++k) usedBefore[slot(f.V(k))] = 1;
  std::vector<char> keep(m.face.size(), 0);
  for (size_t i = 0; i < r.mesh.faces.size(); ++i) {
    auto& f = m.face[faceOfIndex[r.inputFace[i]]];
    keep[faceOfIndex[r.inputFace[i]]] = 1;
    for (int k = 0; k < 3; ++k) {
      VertexPointer v = vertexOfIndex[r.inputVertex[r.mesh.faces[i][size_t(k)]]];
      f.V(k) = v;
      usedAfter[slot(v)] = 1;
    }
  }
  for (size_t i = 0; i < m.face.size(); ++i)
    if (!m.face[i].IsD() && !keep[i]) vcg::tri::Allocator<MeshType>::DeleteFace(m, m.face[i]);
  for (size_t i = 0; i < m.vert.size(); ++i)
    if (!m.vert[i].IsD() && usedBefore[i] && !usedAfter[i]) vcg::tri::Allocator<MeshType>::DeleteVertex(m, m.vert[i]);

  auto cls = vcg::tri::Allocator<MeshType>::template GetPerVertexAttribute<int>(m, VertexClassAttributeName());
  for (auto& v : m.vert) cls[v] = int(VertexClass::Unused);
  for (size_t i = 0; i < r.inputVertex.size(); ++i) cls[*vertexOfIndex[r.inputVertex[i]]] = int(r.vertexClass[i]);

  if (markFeatures) {
    const bool colour = vcg::tri::HasPerVertexColor(m);
    for (auto& v : m.vert) {
      if (v.IsD()) continue;
      const int c = cls[v];
      if (c == int(VertexClass::FeatureLine) || c == int(VertexClass::Feature))
        v.SetS();
      else
        v.ClearS();
      if (colour)
        v.C() = c == int(VertexClass::FeatureLine) ? vcg::Color4b(220, 40, 40, 255)
                : c == int(VertexClass::Feature)   ? vcg::Color4b(40, 80, 230, 255)
                                                   : vcg::Color4b(200, 200, 200, 255);
    }
    std::vector<std::vector<size_t>> nbr(m.vert.size());
    for (const auto& e : r.featureEdges) {
      const size_t a = slot(vertexOfIndex[r.inputVertex[e[0]]]), b = slot(vertexOfIndex[r.inputVertex[e[1]]]);
      nbr[a].push_back(b);
      nbr[b].push_back(a);
    }
    for (auto& f : m.face) {
      if (f.IsD()) continue;
      for (int k = 0; k < 3; ++k) {
        const size_t a = slot(f.V0(k)), b = slot(f.V1(k));
        if (std::find(nbr[a].begin(), nbr[a].end(), b) != nbr[a].end()) {
          f.ClearF(k);
          f.SetFaceEdgeS(k);
        } else {
          f.SetF(k);
          f.ClearFaceEdgeS(k);
        }
      }
    }
  }
  vcg::tri::Allocator<MeshType>::CompactEveryVector(m);
}

}  // namespace conelod
