// Tests of manifold_check.h on tiny meshes with known defects.
#include "conelod/mesh/manifold_check.h"

#include <gtest/gtest.h>

#include "test_util.h"

namespace conelod {
namespace {

TEST(ManifoldCheck, CubeIsValidGridHasABorder) {
  const ManifoldReport c = CheckManifold(test::Cube());
  EXPECT_TRUE(c.valid());
  EXPECT_EQ(c.borderEdges, 0u);
  const ManifoldReport g = CheckManifold(test::Grid(3));
  EXPECT_TRUE(g.valid());
  EXPECT_EQ(g.borderEdges, 12u);
}

TEST(ManifoldCheck, FindsEachDefect) {
  IndexedMesh flipped = test::Cube();
  std::swap(flipped.faces[0][1], flipped.faces[0][2]);
  EXPECT_EQ(CheckManifold(flipped).misorientedEdges, 3u);

  IndexedMesh fin = test::Grid(1);  // two triangles, plus a third on their diagonal
  fin.positions.emplace_back(0.5f, 0.5f, 1.f);
  fin.faces.push_back({0, 3, 4});
  EXPECT_EQ(CheckManifold(fin).nonManifoldEdges, 1u);

  // Two triangles touching at one vertex: a pinch.
  IndexedMesh bow;
  bow.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
  bow.faces = {{0, 1, 2}, {0, 3, 4}};
  const ManifoldReport b = CheckManifold(bow);
  EXPECT_EQ(b.nonManifoldVertices, 1u);
  EXPECT_FALSE(b.valid());

  IndexedMesh degenerate = test::Grid(1);
  degenerate.faces.push_back({0, 0, 1});
  EXPECT_EQ(CheckManifold(degenerate).degenerateFaces, 1u);
}

}  // namespace
}  // namespace conelod
