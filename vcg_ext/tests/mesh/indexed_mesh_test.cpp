// Tests of indexed_mesh.h and mesh_check.h: adjacency, border/non-manifold counts, components,
// connectivity checks and the input checks on bad meshes.
#include "conelod/mesh/indexed_mesh.h"

#include <gtest/gtest.h>

#include <limits>

#include "conelod/mesh/mesh_check.h"
#include "test_util.h"

namespace conelod {
namespace {

TEST(FaceAdjacency, ClosedCubeHasThreeNeighboursPerFace) {
  const FaceAdjacency adj = BuildFaceAdjacency(test::Cube());
  for (uint32_t f = 0; f < 12; ++f) EXPECT_EQ(adj.degree(f), 3u);
  EXPECT_EQ(adj.borderEdges, 0u);
  EXPECT_EQ(adj.nonManifoldEdges, 0u);
}

TEST(FaceAdjacency, SingleTriangleHasThreeBorderEdges) {
  IndexedMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.faces = {{0, 1, 2}};
  const FaceAdjacency adj = BuildFaceAdjacency(m);
  EXPECT_EQ(adj.degree(0), 0u);
  EXPECT_EQ(adj.borderEdges, 3u);
}

TEST(FaceAdjacency, ThreeFacesOnOneEdgeAreAllNeighbours) {
  // A "book": three triangles share the edge (0,1).
  IndexedMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  m.faces = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  const FaceAdjacency adj = BuildFaceAdjacency(m);
  for (uint32_t f = 0; f < 3; ++f) EXPECT_EQ(adj.degree(f), 2u);
  EXPECT_EQ(adj.nonManifoldEdges, 1u);
  EXPECT_EQ(adj.borderEdges, 6u);
}

TEST(FaceAdjacency, VertexOnlyContactIsNoAdjacency) {
  // Two triangles touching at one vertex: two components.
  IndexedMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
  m.faces = {{0, 1, 2}, {0, 3, 4}};
  const FaceAdjacency adj = BuildFaceAdjacency(m);
  std::vector<int> comp;
  EXPECT_EQ(ConnectedComponents(adj, comp), 2);
}

TEST(GroupsAreEdgeConnected, DetectsAGroupInTwoPieces) {
  const IndexedMesh grid = test::Grid(4);  // 32 faces in a strip order
  const FaceAdjacency adj = BuildFaceAdjacency(grid);
  std::vector<int> groups(grid.faces.size(), 0);
  EXPECT_TRUE(GroupsAreEdgeConnected(adj, groups));
  // Group 1 = the first and the last quad: far apart.
  groups[0] = groups[1] = 1;
  groups[30] = groups[31] = 1;
  std::vector<int> broken;
  EXPECT_FALSE(GroupsAreEdgeConnected(adj, groups, &broken));
  ASSERT_EQ(broken.size(), 1u);
  EXPECT_EQ(broken[0], 1);
}

TEST(CheckMesh, CountsTheProblemsOfAScan) {
  IndexedMesh m = test::Grid(2);            // 9 vertices, 8 faces
  m.positions.emplace_back(5.f, 5.f, 5.f);  // unreferenced
  m.faces.push_back({0, 1, 1});             // zero area (repeated vertex)
  const MeshReport r = CheckMesh(m);
  EXPECT_EQ(r.vertices, 10u);
  EXPECT_EQ(r.faces, 9u);
  EXPECT_EQ(r.unreferencedVertices, 1u);
  EXPECT_EQ(r.degenerateFaces, 1u);
  EXPECT_EQ(r.components, 1);
  EXPECT_EQ(r.borderEdges, 7u);  // the zero-area face lies on border edge (0,1): two faces now
  EXPECT_TRUE(RequireValidForFaces(r).ok());
}

TEST(CheckMesh, RefusesNoFacesNaNAndBadIndices) {
  IndexedMesh empty;
  empty.positions = {{0, 0, 0}};
  Status s = RequireValidForFaces(CheckMesh(empty));
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message.find("no faces"), std::string::npos);

  IndexedMesh nan = test::Grid(1);
  nan.positions[0][1] = std::numeric_limits<float>::quiet_NaN();
  s = RequireValidForFaces(CheckMesh(nan));
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message.find("NaN"), std::string::npos);

  IndexedMesh bad = test::Grid(1);
  bad.faces.push_back({0, 1, 99});
  s = RequireValidForFaces(CheckMesh(bad));
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message.find("do not exist"), std::string::npos);

  // A NaN in an unreferenced vertex is harmless.
  IndexedMesh harmless = test::Grid(1);
  harmless.positions.emplace_back(std::numeric_limits<float>::quiet_NaN(), 0.f, 0.f);
  EXPECT_TRUE(RequireValidForFaces(CheckMesh(harmless)).ok());
}

TEST(CheckMesh, AllZeroAreaFacesAreRefused) {
  IndexedMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};  // collinear
  m.faces = {{0, 1, 2}};
  const Status s = RequireValidForFaces(CheckMesh(m));
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message.find("zero area"), std::string::npos);
}

TEST(IndexedMesh, NormalizingScaleIsThePowerOfTwoThatBringsTheDiagonalToAboutOne) {
  IndexedMesh cube = test::Cube();  // diagonal sqrt(3): log2 0.79, rounded to 1
  EXPECT_EQ(NormalizingScale(cube), 0.5);
  for (int k : {-60, -20, 20, 60}) {
    IndexedMesh scaled = cube;
    for (auto& p : scaled.positions) p *= std::ldexp(1.0f, k);
    EXPECT_EQ(NormalizingScale(scaled), std::ldexp(0.5, -k)) << k;
  }
  // Unused vertices do not count; no faces, or a single point, give 1.
  cube.positions.emplace_back(1e6f, 0.f, 0.f);
  EXPECT_EQ(NormalizingScale(cube), 0.5);
  EXPECT_EQ(NormalizingScale(IndexedMesh()), 1.0);
  IndexedMesh point;
  point.positions = {{5, 5, 5}};
  point.faces = {{0, 0, 0}};
  EXPECT_EQ(NormalizingScale(point), 1.0);
}

}  // namespace
}  // namespace conelod
