// Tests of sampled_distance.h: exact distances between parallel planes, zero to itself, the
// asymmetry of one-sided distances, faces against the surface.
#include "conelod/mesh/sampled_distance.h"

#include <gtest/gtest.h>

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

TEST(SampledDistance, BadInput) {
  IndexedMesh empty;
  SurfaceDistance d;
  EXPECT_FALSE(SampledDistance(empty, test::Cube(), 10, d).ok());
  EXPECT_FALSE(SampledDistance(test::Cube(), test::Cube(), -1, d).ok());
}

}  // namespace
}  // namespace conelod
