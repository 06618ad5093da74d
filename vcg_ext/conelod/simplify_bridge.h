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
#include <limits>
#include <unordered_map>
#include <vector>

#include <vcg/complex/complex.h>

#include "conelod/feature/feature_simplify.h"

namespace conelod {

// Name of the per-vertex int attribute holding the VertexClass of each vertex after a
// feature-preserving simplification (0 = V_K smooth, 1 = V_M feature line, 2 = V_C feature vertex).
inline const char* VertexClassAttributeName() { return "conelod_vertex_class"; }

// The extended-quadric mean of MeanSurvivorColours (below) for any per-vertex values: for each output vertex o (input
// vertex inputVertex[o]; `survivor`: per input vertex, the output vertex its collapses ended in), the area-weighted
// mean at its position of the linear functions that the input faces of the input vertices it stands for give to the `C`
// values get(face, corner, channel) (a vertex's value, or a face corner's: texture coordinates per corner); means[o x C
// ...] and weight[o] (0: all its faces have zero area, no mean). The faces are the mesh's as given to ToIndexedMesh.
template <class MeshType, class Get>
void SurvivorQuadricMeans(const MeshType& m, const std::vector<uint32_t>& survivor,
                          const std::vector<uint32_t>& inputVertex, int C, Get get, std::vector<double>& means,
                          std::vector<double>& weight) {
  using ConstVertexPointer = typename MeshType::ConstVertexPointer;
  std::vector<ConstVertexPointer> vertexOfIndex;
  std::vector<uint32_t> indexOfSlot(m.vert.size(), UINT32_MAX);
  for (const auto& v : m.vert)
    if (!v.IsD()) {
      indexOfSlot[size_t(&v - &m.vert[0])] = uint32_t(vertexOfIndex.size());
      vertexOfIndex.push_back(&v);
    }
  const size_t n = inputVertex.size();
  means.assign(n * size_t(C), 0.0);
  weight.assign(n, 0.0);
  for (const auto& f : m.face) {
    if (f.IsD()) continue;
    const vcg::Point3d p0 = vcg::Point3d::Construct(f.cV(0)->cP()), e1 = vcg::Point3d::Construct(f.cV(1)->cP()) - p0,
                       e2 = vcg::Point3d::Construct(f.cV(2)->cP()) - p0;
    const vcg::Point3d nrm = e1 ^ e2;
    const double n2 = nrm.SquaredNorm();
    if (!(n2 > 0)) continue;
    const double third = std::sqrt(n2) / 6.0;
    for (int j = 0; j < 3; ++j) {
      const uint32_t i = indexOfSlot[size_t(f.cV(j) - &m.vert[0])];
      const uint32_t o = i < survivor.size() ? survivor[i] : UINT32_MAX;
      if (o == UINT32_MAX) continue;
      const vcg::Point3d q = vcg::Point3d::Construct(vertexOfIndex[inputVertex[o]]->cP()) - p0;
      for (int k = 0; k < C; ++k) {
        const double c0 = get(f, 0, k), c1 = get(f, 1, k), c2 = get(f, 2, k);
        const vcg::Point3d g = ((e2 ^ nrm) * (c1 - c0) + (nrm ^ e1) * (c2 - c0)) / n2;
        means[size_t(o) * size_t(C) + size_t(k)] += third * (c0 + g * q);
      }
      weight[o] += third;
    }
  }
  for (size_t o = 0; o < n; ++o)
    if (weight[o] > 0)
      for (int k = 0; k < C; ++k) means[o * size_t(C) + size_t(k)] /= weight[o];
}

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
// ToIndexedMesh (before WriteSimplifiedMesh); only on success. Normals and texture coordinates:
// MeanSurvivorNormalsAndTexCoords.
// Seam vertices of per-vertex texture coordinates: 1 for each vertex (by index in vertexOfIndex)
// whose position, in single precision, another vertex holds too.
template <class VertexPointer>
std::vector<char> SeamVertices(const std::vector<VertexPointer>& vertexOfIndex) {
  std::vector<uint32_t> order(vertexOfIndex.size());
  for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  auto key = [&](uint32_t i) {
    const auto& p = vertexOfIndex[i]->cP();
    return std::array<float, 3>{{float(p[0]), float(p[1]), float(p[2])}};
  };
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key(a) < key(b); });
  std::vector<char> seam(order.size(), 0);
  for (size_t i = 1; i < order.size(); ++i)
    if (key(order[i]) == key(order[i - 1])) seam[order[i]] = seam[order[i - 1]] = 1;
  return seam;
}

template <class MeshType>
void MeanSurvivorColours(MeshType& m, const FeatureSimplifyResult& r) {
  if (!vcg::tri::HasPerVertexColor(m)) return;
  using VertexPointer = typename MeshType::VertexPointer;
  using FaceType = typename MeshType::FaceType;
  std::vector<double> means, weight;
  SurvivorQuadricMeans(
      m, r.survivor, r.inputVertex, 4, [](const FaceType& f, int j, int k) { return double(f.cV(j)->cC()[k]); }, means,
      weight);
  std::vector<VertexPointer> vertexOfIndex;
  for (auto& v : m.vert)
    if (!v.IsD()) vertexOfIndex.push_back(&v);
  for (size_t o = 0; o < r.inputVertex.size(); ++o) {
    if (!(weight[o] > 0)) continue;
    auto& c = vertexOfIndex[r.inputVertex[o]]->C();
    for (int k = 0; k < 4; ++k)
      c[k] = (unsigned char)std::min(255L, std::max(0L, std::lround(means[o * 4 + size_t(k)])));
  }
}

// Issue 26, the normals and per-vertex texture coordinates as MeanSurvivorColours does the colour:
// each output vertex takes the extended quadric's value at its position of the input vertices it
// stands for. The normal is then normalised (a zero or non-finite mean keeps the vertex's own).
// Texture coordinates only away from seams: a vertex that shares its position with another vertex
// (a seam read as vertices split by their coordinates, as the CLI reads per-face texcoord lists
// and per-vertex ones repeated) keeps its own, as a seam vertex keeps its own side's values in the
// group-preserving collapse (attribute_quadric.h); its faces are those of its own chart, and the
// texture there is exact at its unchanged position. Returns the number of output vertices that kept
// their coordinates as seam vertices. Call as MeanSurvivorColours (before WriteSimplifiedMesh).
template <class MeshType>
size_t MeanSurvivorNormalsAndTexCoords(MeshType& m, const FeatureSimplifyResult& r, bool normals, bool texCoords) {
  using VertexPointer = typename MeshType::VertexPointer;
  using VertexType = typename MeshType::VertexType;
  using FaceType = typename MeshType::FaceType;
  std::vector<VertexPointer> vertexOfIndex;
  for (auto& v : m.vert)
    if (!v.IsD()) vertexOfIndex.push_back(&v);
  std::vector<double> means, weight;
  if (normals && vcg::tri::HasPerVertexNormal(m)) {
    SurvivorQuadricMeans(
        m, r.survivor, r.inputVertex, 3, [](const FaceType& f, int j, int k) { return double(f.cV(j)->cN()[k]); },
        means, weight);
    for (size_t o = 0; o < r.inputVertex.size(); ++o) {
      const vcg::Point3d n(means[3 * o], means[3 * o + 1], means[3 * o + 2]);
      const double len = n.Norm();
      if (!(weight[o] > 0) || !(len > 0) || !std::isfinite(len)) continue;
      auto& out = vertexOfIndex[r.inputVertex[o]]->N();
      for (int k = 0; k < 3; ++k) out[k] = typename VertexType::NormalType::ScalarType(n[k] / len);
    }
  }
  size_t seamKept = 0;
  if (texCoords && vcg::tri::HasPerVertexTexCoord(m)) {
    const std::vector<char> seam = SeamVertices(vertexOfIndex);
    SurvivorQuadricMeans(
        m, r.survivor, r.inputVertex, 2,
        [](const FaceType& f, int j, int k) { return double(k == 0 ? f.cV(j)->cT().U() : f.cV(j)->cT().V()); }, means,
        weight);
    for (size_t o = 0; o < r.inputVertex.size(); ++o) {
      if (seam[r.inputVertex[o]]) {
        ++seamKept;
        continue;
      }
      if (!(weight[o] > 0) || !std::isfinite(means[2 * o]) || !std::isfinite(means[2 * o + 1])) continue;
      auto& t = vertexOfIndex[r.inputVertex[o]]->T();
      t.U() = typename VertexType::TexCoordType::ScalarType(means[2 * o]);
      t.V() = typename VertexType::TexCoordType::ScalarType(means[2 * o + 1]);
    }
  }
  return seamKept;
}

// Issue 26, texture coordinates per face corner (MeshLab's wedges). The seams of `im` (ToIndexedMesh
// of `m`, `faceOf` its face map): the edges whose two faces give an end different coordinates
// (u, v or texture index), as FeatureSimplifyParams::seamEdges wants them.
template <class MeshType>
std::vector<std::array<uint32_t, 2>> WedgeSeamEdges(const MeshType& m, const std::vector<size_t>& faceOf,
                                                    const IndexedMesh& im) {
  auto same = [](const vcg::TexCoord2f& a, const vcg::TexCoord2f& b) {
    return a.U() == b.U() && a.V() == b.V() && a.N() == b.N();
  };
  struct Seen {
    uint32_t face;
    uint8_t ka, kb;  // the corners of the edge's ends a < b in that face
    bool seam;
  };
  std::unordered_map<uint64_t, Seen> edges;
  edges.reserve(im.faces.size() * 2);
  std::vector<std::array<uint32_t, 2>> out;
  for (uint32_t i = 0; i < im.faces.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      uint32_t a = im.faces[i][size_t(k)], b = im.faces[i][size_t((k + 1) % 3)];
      uint8_t ka = uint8_t(k), kb = uint8_t((k + 1) % 3);
      if (a == b) continue;
      if (a > b) {
        std::swap(a, b);
        std::swap(ka, kb);
      }
      const uint64_t key = (uint64_t(a) << 32) | b;
      auto it = edges.find(key);
      if (it == edges.end()) {
        edges.emplace(key, Seen{i, ka, kb, false});
        continue;
      }
      Seen& s = it->second;
      if (s.seam) continue;
      const auto& f0 = m.face[faceOf[s.face]];
      const auto& f1 = m.face[faceOf[i]];
      if (!same(f0.cWT(s.ka), f1.cWT(ka)) || !same(f0.cWT(s.kb), f1.cWT(kb))) {
        s.seam = true;
        out.push_back({{a, b}});
      }
    }
  std::sort(out.begin(), out.end());
  return out;
}

// Issue 26, the wedge texture coordinates after a feature-preserving simplification of a mesh with
// seams given as FeatureSimplifyParams::seamEdges (WedgeSeamEdges): a kept vertex whose input
// corners all had one value (off the seams) takes, on every corner, the extended quadric's value at
// its position of the corners of the vertices it took over (as MeanSurvivorNormalsAndTexCoords);
// a seam vertex keeps its own corners' values, and a corner that a collapse moved onto it takes
// the one of its values nearest to the corner's old value (the value of its own chart: the face
// kept its side of the seam, which the collapse never crossed). Writes the new values into the
// faces that stay (m.face[faceOf[r.inputFace[i]]]); call before WriteSimplifiedMesh. Returns the
// number of output vertices on a seam.
template <class MeshType>
size_t SurvivorWedgeTexCoords(MeshType& m, const std::vector<size_t>& faceOf, const FeatureSimplifyResult& r) {
  using VertexPointer = typename MeshType::VertexPointer;
  using FaceType = typename MeshType::FaceType;
  std::vector<VertexPointer> vertexOfIndex;
  std::vector<uint32_t> indexOfSlot(m.vert.size(), UINT32_MAX);
  for (auto& v : m.vert)
    if (!v.IsD()) {
      indexOfSlot[size_t(&v - &m.vert[0])] = uint32_t(vertexOfIndex.size());
      vertexOfIndex.push_back(&v);
    }
  // Each input vertex's distinct corner values (a seam vertex has two or more).
  std::vector<std::vector<vcg::TexCoord2f>> values(vertexOfIndex.size());
  for (const auto& f : m.face) {
    if (f.IsD()) continue;
    for (int k = 0; k < 3; ++k) {
      auto& list = values[indexOfSlot[size_t(f.cV(k) - &m.vert[0])]];
      const vcg::TexCoord2f& t = f.cWT(k);
      bool known = false;
      for (const auto& x : list) known |= x.U() == t.U() && x.V() == t.V() && x.N() == t.N();
      if (!known) list.push_back(t);
    }
  }
  std::vector<double> means, weight;
  SurvivorQuadricMeans(
      m, r.survivor, r.inputVertex, 2,
      [](const FaceType& f, int j, int k) { return double(k == 0 ? f.cWT(j).U() : f.cWT(j).V()); }, means, weight);
  size_t seamVertices = 0;
  for (size_t o = 0; o < r.inputVertex.size(); ++o) seamVertices += values[r.inputVertex[o]].size() > 1;
  for (size_t i = 0; i < r.mesh.faces.size(); ++i) {
    FaceType& f = m.face[faceOf[r.inputFace[i]]];
    const VertexPointer oldV[3] = {f.V(0), f.V(1), f.V(2)};
    const vcg::TexCoord2f oldT[3] = {f.WT(0), f.WT(1), f.WT(2)};
    for (int k = 0; k < 3; ++k) {
      const uint32_t o = r.mesh.faces[i][size_t(k)];
      const uint32_t in = r.inputVertex[o];
      const auto& own = values[in];
      if (own.empty()) continue;
      vcg::TexCoord2f t = own[0];
      if (own.size() == 1) {  // off the seams: the quadric's value (the texture index its own)
        if (weight[o] > 0 && std::isfinite(means[2 * o]) && std::isfinite(means[2 * o + 1])) {
          t.U() = float(means[2 * o]);
          t.V() = float(means[2 * o + 1]);
        }
      } else {
        int same = -1;
        for (int j = 0; j < 3; ++j)
          if (oldV[j] == vertexOfIndex[in]) same = j;
        if (same >= 0) {
          t = oldT[same];
        } else {
          double best = std::numeric_limits<double>::infinity();
          for (const auto& x : own) {
            const double d = std::pow(double(x.U()) - oldT[k].U(), 2) + std::pow(double(x.V()) - oldT[k].V(), 2) +
                             (x.N() == oldT[k].N() ? 0.0 : 1e30);
            if (d < best) {
              best = d;
              t = x;
            }
          }
        }
      }
      f.WT(k) = t;
    }
  }
  return seamVertices;
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
