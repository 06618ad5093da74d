// Tests of weld.h: vertices at identical positions become one, exactly and deterministically.
// Tiny meshes with exact expectations, then the dragon, whose file repeats vertices along seams.
#include "conelod/mesh/weld.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "conelod/mesh/mesh_check.h"
#include "conelod/vcg_bridge.h"
#include "conelod/vcg_mesh.h"
#include "test_util.h"

namespace conelod {
namespace {

// Two triangles of a square, each with its own copy of the diagonal's vertices (a seam).
IndexedMesh SplitSquare() {
  IndexedMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  m.faces = {{0, 1, 2}, {3, 4, 5}};
  return m;
}

TEST(Weld, ASeamBecomesAnInnerEdge) {
  const IndexedMesh m = SplitSquare();
  EXPECT_EQ(BuildFaceAdjacency(m).borderEdges, 6u);
  const WeldResult w = WeldByPosition(m);
  ASSERT_EQ(w.mesh.positions.size(), 4u);
  // Representatives: the lowest input index at each position, numbered in input order.
  EXPECT_EQ(w.representative, (std::vector<uint32_t>{0, 1, 2, 5}));
  ASSERT_EQ(w.mesh.faces.size(), 2u);
  EXPECT_EQ(w.mesh.faces[0], (std::array<uint32_t, 3>{{0, 1, 2}}));
  EXPECT_EQ(w.mesh.faces[1], (std::array<uint32_t, 3>{{0, 2, 3}}));
  EXPECT_EQ(w.mergedVertices, 2u);
  EXPECT_EQ(w.droppedVertices, 0u);
  EXPECT_EQ(BuildFaceAdjacency(w.mesh).borderEdges, 4u);
  // Every corner keeps its position bit for bit.
  for (size_t f = 0; f < 2; ++f)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(w.mesh.positions[w.mesh.faces[f][k]], m.positions[m.faces[f][k]]);
}

TEST(Weld, OnlyIdenticalPositionsMerge) {
  IndexedMesh m = SplitSquare();
  m.positions[3] = {0, std::nextafter(0.f, 1.f), 0};  // one float step away: a different point
  m.positions[4] = {1, 1, -0.f};                      // -0 is +0: the same point
  const WeldResult w = WeldByPosition(m);
  EXPECT_EQ(w.mesh.positions.size(), 5u);
  EXPECT_EQ(w.mergedVertices, 1u);
  EXPECT_EQ(w.mesh.faces[1][1], 2u);
}

TEST(Weld, UnreferencedVerticesAreDropped) {
  IndexedMesh m = test::Cube();
  const IndexedMesh cube = m;
  m.positions.insert(m.positions.begin(), {5, 5, 5});  // unreferenced, before every used vertex
  for (auto& t : m.faces)
    for (uint32_t& v : t) ++v;
  m.positions.push_back({0, 0, 0});  // unreferenced, at a used vertex's position
  const WeldResult w = WeldByPosition(m);
  EXPECT_EQ(w.droppedVertices, 2u);
  EXPECT_EQ(w.mergedVertices, 0u);
  EXPECT_EQ(w.mesh.positions, cube.positions);
  EXPECT_EQ(w.mesh.faces, cube.faces);
}

TEST(Weld, MeshesToRefuseComeBackAsTheyAre) {
  // No faces: the input checks' message still counts the vertices ("no faces (3 vertices)").
  IndexedMesh m;
  m.positions = {{0, 0, 0}, {0, 0, 0}, {1, 0, 0}};
  EXPECT_EQ(WeldByPosition(m).mesh.positions.size(), 3u);
  // An index out of range: left for RequireValidForFaces to refuse.
  m.faces = {{0, 1, 7}};
  const WeldResult w = WeldByPosition(m);
  EXPECT_EQ(w.mesh.positions.size(), 3u);
  EXPECT_EQ(w.mesh.faces, m.faces);
  EXPECT_FALSE(w.changed());
}

TEST(Weld, AMeshWithoutRepeatsIsUnchanged) {
  const IndexedMesh m = test::Sphere(3);
  const WeldResult w = WeldByPosition(m);
  EXPECT_FALSE(w.changed());
  EXPECT_EQ(w.mesh.positions, m.positions);
  EXPECT_EQ(w.mesh.faces, m.faces);
  for (size_t v = 0; v < w.representative.size(); ++v) EXPECT_EQ(w.representative[v], v);
}

TEST(Weld, FacesWhoseCornersMeetKeepTheirPlace) {
  // A sliver along a seam: two corners at one position. The face stays (face i is face i), with
  // a repeated vertex, so that per-face results map back one to one.
  IndexedMesh m = SplitSquare();
  m.positions.push_back({1, 0, 0});
  m.faces.push_back({1, 6, 2});
  const WeldResult w = WeldByPosition(m);
  ASSERT_EQ(w.mesh.faces.size(), 3u);
  EXPECT_EQ(w.mesh.faces[2], (std::array<uint32_t, 3>{{1, 1, 2}}));
}

TEST(Weld, TheOrderOfTheInputDoesNotMatterButForNumbering) {
  // The same surface with its vertices listed in reverse: the same welded faces by position.
  const IndexedMesh m = SplitSquare();
  IndexedMesh r;
  r.positions.assign(m.positions.rbegin(), m.positions.rend());
  for (const auto& t : m.faces) r.faces.push_back({5 - t[0], 5 - t[1], 5 - t[2]});
  const WeldResult a = WeldByPosition(m), b = WeldByPosition(r);
  ASSERT_EQ(a.mesh.faces.size(), b.mesh.faces.size());
  for (size_t f = 0; f < a.mesh.faces.size(); ++f)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(a.mesh.positions[a.mesh.faces[f][k]], b.mesh.positions[b.mesh.faces[f][k]]);
  EXPECT_EQ(b.representative, (std::vector<uint32_t>{0, 1, 2, 4}));  // the lowest index at each position
}

// The dragon repeats 2,100 vertices along seams: 151 components and 4,270 border edges by index;
// welded, no border edge is left and 10 closed pieces (108 slivers along the seams become faces
// with a repeated vertex).
TEST(Weld, TheDragonIsClosedOnceWelded) {
  CMesh cm;
  ASSERT_EQ(LoadPly(cm, test::MeshPath("stanford_dragon_vrip_binary.ply")), "");
  const IndexedMesh m = ToIndexedMesh(cm);
  const MeshReport before = CheckMesh(m);
  EXPECT_EQ(before.borderEdges, 4270u);
  EXPECT_EQ(before.components, 151);
  const WeldResult w = WeldByPosition(m);
  EXPECT_EQ(w.mesh.faces.size(), m.faces.size());
  EXPECT_EQ(w.mesh.positions.size() + w.mergedVertices + w.droppedVertices, m.positions.size());
  const MeshReport after = CheckMesh(w.mesh);
  EXPECT_EQ(after.borderEdges, 0u);
  EXPECT_EQ(after.components, 10);
  EXPECT_EQ(w.mergedVertices, 2100u);
}

TEST(Weld, InPlaceOnThreadsIsTheOneThreadWeld) {
  // Enough vertices for several sorted pieces (32,768 keys each at least): every 7th vertex of a
  // grid repeated (the copies at x = -0 where the grid has +0) and named by every third face
  // instead of the original; an unreferenced vertex at the end.
  IndexedMesh m = test::Grid(400);  // 160,801 vertices
  const size_t V = m.positions.size();
  for (size_t v = 0; v < V; v += 7) {
    vcg::Point3f p = m.positions[v];
    if (p[0] == 0) p[0] = -0.0f;
    m.positions.push_back(p);
  }
  for (size_t f = 0; f < m.faces.size(); f += 3)
    for (uint32_t& i : m.faces[f])
      if (i % 7 == 0) i = uint32_t(V + i / 7);
  m.positions.push_back(vcg::Point3f(5, 5, 5));
  const WeldResult ref = WeldByPosition(m);
  ASSERT_GT(ref.mergedVertices, 1000u);
  for (unsigned threads : {1u, 2u, 3u, 8u}) {
    IndexedMesh w = m;
    size_t merged = 0, dropped = 0;
    ASSERT_TRUE(WeldByPositionInPlace(w, &merged, &dropped, threads)) << threads;
    EXPECT_EQ(merged, ref.mergedVertices) << threads;
    EXPECT_EQ(dropped, ref.droppedVertices) << threads;
    EXPECT_TRUE(w.positions == ref.mesh.positions) << threads;
    EXPECT_TRUE(w.faces == ref.mesh.faces) << threads;
  }
}

}  // namespace
}  // namespace conelod
