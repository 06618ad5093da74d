// Tests of sampled_distance.h: exact distances between parallel planes, zero to itself, the
// asymmetry of one-sided distances, faces against the surface.
#include "conelod/mesh/sampled_distance.h"

#include <gtest/gtest.h>

#include "conelod/vcg_bridge.h"
#include "conelod/vcg_mesh.h"
#include "test_util.h"

namespace conelod {
namespace {

IndexedMesh Shifted(IndexedMesh m, vcg::Point3f d) {
  for (auto& p : m.positions) p += d;
  return m;
}

TEST(SampledDistance, ParallelPlanes) {
  const IndexedMesh a = test::Grid(8), b = Shifted(test::Grid(8), vcg::Point3f(0, 0, 0.5f));
  SurfaceDistance d;
  ASSERT_TRUE(SampledDistance(a, b, 5000, d).ok());
  EXPECT_NEAR(d.max, 0.5, 1e-6);
  EXPECT_NEAR(d.mean, 0.5, 1e-6);
  EXPECT_NEAR(d.rms, 0.5, 1e-6);
  EXPECT_EQ(d.samples, 81u + 5000u);
  HausdorffResult h;
  ASSERT_TRUE(SampledHausdorff(a, a, 2000, h).ok());
  EXPECT_EQ(h.hausdorff, 0.0);
  EXPECT_NEAR(h.diagonal, std::sqrt(128.0), 1e-6);
}

TEST(SampledDistance, OneSidedDistancesDiffer) {
  // A small square over the middle of a big one: every point of the small one is 1 away from the
  // big one, but the big one's corners are far from the small one.
  const IndexedMesh big = test::Grid(10);
  IndexedMesh small = Shifted(test::Grid(2), vcg::Point3f(4, 4, 1));
  HausdorffResult h;
  ASSERT_TRUE(SampledHausdorff(small, big, 2000, h).ok());
  EXPECT_NEAR(h.ab.max, 1.0, 1e-6);
  EXPECT_GT(h.ba.max, 5.0);
  EXPECT_EQ(h.hausdorff, h.ba.max);
}

TEST(SampledDistance, FacesAgainstTheSurface) {
  const IndexedMesh grid = test::Grid(4);
  IndexedMesh flipped = Shifted(grid, vcg::Point3f(0, 0, 0.01f));
  EXPECT_EQ(CountFacesAgainstSurface(flipped, grid), 0u);
  for (size_t f = 0; f < 5; ++f) std::swap(flipped.faces[f][1], flipped.faces[f][2]);
  EXPECT_EQ(CountFacesAgainstSurface(flipped, grid), 5u);
}

TEST(SampledDistance, PointJustBelowTheGridsUpperSide) {
  // A level of the armadillo's hierarchy (test_meshes/grid_rounding_target.ply) and a query point
  // just below the upper z side of the box vcglib's grid used to build around it: float rounding
  // put the point in the cell past the last one (an out-of-range read that crashed
  // `conelod simplify --hierarchy --samples 200000` on the armadillo).
  CMesh m;
  ASSERT_EQ(LoadPly(m, std::string(CONELOD_SOURCE_DIR) + "/test_meshes/grid_rounding_target.ply"), "");
  const IndexedMesh target = ToIndexedMesh(m);
  IndexedMesh query;
  const vcg::Point3f p(-4.39941788f, -7.07787657f, 57.0442238f);
  query.positions = {p, p + vcg::Point3f(-0.5f, 0, 0), p + vcg::Point3f(0, -0.5f, 0)};
  query.faces = {{{0, 1, 2}}};
  SurfaceDistance d;
  ASSERT_TRUE(SampledDistance(query, target, 100, d).ok());
  EXPECT_EQ(d.samples, 103u);
  EXPECT_GT(d.max, 0.0);
  EXPECT_LT(d.max, 20.0);
}

TEST(SampledDistance, BadInput) {
  IndexedMesh empty;
  SurfaceDistance d;
  EXPECT_FALSE(SampledDistance(empty, test::Cube(), 10, d).ok());
  EXPECT_FALSE(SampledDistance(test::Cube(), test::Cube(), -1, d).ok());
}

}  // namespace
}  // namespace conelod
