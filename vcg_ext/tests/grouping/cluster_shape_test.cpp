// Tests of cluster_shape.h: exact boundary lengths on a grid, ragged versus straight partitions.
#include "conelod/grouping/cluster_shape.h"

#include <gtest/gtest.h>

#include <cmath>

#include "test_util.h"

namespace conelod {
namespace {

TEST(ClusterShape, GridHalvesAndCheckerboard) {
  const IndexedMesh g = test::Grid(8);  // 8 x 8 unit quads, 128 triangles, face 2k/2k+1 = quad k
  std::vector<int> halves(g.faces.size()), checker(g.faces.size());
  for (size_t f = 0; f < g.faces.size(); ++f) {
    const int quad = int(f / 2), x = quad % 8, y = quad / 8;
    halves[f] = x < 4 ? 0 : 1;
    checker[f] = (x + y) % 2;
  }
  const ClusterShape h = MeasureClusterShape(g, halves);
  EXPECT_EQ(h.clusters, 2);
  EXPECT_NEAR(h.boundaryLength, 8.0, 1e-9);  // the straight line x = 4
  EXPECT_NEAR(h.boundaryRatio, 8.0 / std::sqrt(3.14159265358979 * 64 * 2), 1e-9);
  // Each half is a 4 x 8 rectangle: 4 pi 32 / 24².
  EXPECT_NEAR(h.meanCompactness, 4 * 3.14159265358979 * 32 / (24.0 * 24.0), 1e-9);
  const ClusterShape c = MeasureClusterShape(g, checker);
  EXPECT_EQ(c.clusters, 2);
  EXPECT_NEAR(c.boundaryLength, 2 * 7 * 8, 1e-9);  // every inner quad edge
  EXPECT_GT(c.boundaryRatio, 10 * h.boundaryRatio);
  EXPECT_LT(c.meanCompactness, 0.1 * h.meanCompactness);
}

TEST(ClusterShape, ClosedSurfaceInOneCluster) {
  const ClusterShape s = MeasureClusterShape(test::Cube(), std::vector<int>(12, 0));
  EXPECT_EQ(s.clusters, 1);
  EXPECT_EQ(s.boundaryLength, 0.0);
  EXPECT_EQ(s.meanCompactness, 0.0);  // no boundary: nothing to measure
}

}  // namespace
}  // namespace conelod
