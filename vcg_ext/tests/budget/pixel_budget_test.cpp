// Tests of pixel_budget.h: covered pixels of shapes whose projected area is known, the framing,
// the worst view, and the budget.
#include "conelod/budget/pixel_budget.h"

#include <gtest/gtest.h>

#include <cmath>

#include "conelod/vcg_bridge.h"
#include "conelod/vcg_mesh.h"
#include "test_util.h"

namespace conelod {
namespace {

using P3 = vcg::Point3d;

// A square of side `side` in the z = 0 plane centred at the origin (two triangles).
IndexedMesh Square(float side) {
  IndexedMesh m;
  const float h = side / 2;
  m.positions = {{-h, -h, 0}, {h, -h, 0}, {h, h, 0}, {-h, h, 0}};
  m.faces = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

TEST(FramedView, BoundingSphereSpansTheShorterSide) {
  // The unit cube's diagonal sqrt(3) spans min(W, H) = 600 pixels.
  const OrthoView v = FramedView(test::Cube(), P3(0, 0, -1), 800, 600);
  EXPECT_NEAR(v.pixelsPerUnit, 600 / std::sqrt(3.0), 1e-9);
  EXPECT_NEAR(v.centre[0], 0.5, 1e-12);
  EXPECT_NEAR(v.right * v.up, 0.0, 1e-12);
  EXPECT_NEAR(v.direction * v.up, 0.0, 1e-12);
}

TEST(CountCoveredPixels, SquareHasItsAnalyticArea) {
  // Diagonal 2 sqrt(2) spans 1000 pixels: the square's side is 1000 / sqrt(2) = 707.1 pixels,
  // its area 500000 pixels.
  const IndexedMesh sq = Square(2);
  const OrthoView v = FramedView(sq, P3(0, 0, -1), 1000, 1000);
  const size_t pixels = CountCoveredPixels(sq, v);
  EXPECT_NEAR(double(pixels), 500000.0, 0.01 * 500000);
  // Pixel centres: columns 146..853 and rows 146..853 (708 each).
  EXPECT_EQ(pixels, 708u * 708u);
}

TEST(CountCoveredPixels, SphereHasItsAnalyticArea) {
  // A unit sphere (8192 faces, its silhouette a 128-gon inscribed in the circle) framed at
  // 1920 x 1080: the diagonal 2 sqrt(3) spans 1080 pixels, so its disc has radius
  // 540 / sqrt(3) = 311.8 pixels and area pi r^2 = 305362 pixels.
  const IndexedMesh sphere = test::Sphere(5);
  const double r = 540.0 / std::sqrt(3.0), area = M_PI * r * r;
  for (const P3& dir : AxisDirections()) {
    const size_t pixels = CountCoveredPixels(sphere, FramedView(sphere, dir, 1920, 1080));
    EXPECT_NEAR(double(pixels), area, 0.01 * area);
  }
}

TEST(CountCoveredPixels, OverlapsCountOnceAndEdgeOnCountsNothing) {
  IndexedMesh twice = Square(2);
  twice.positions.push_back({-1, -1, 0.5f});
  twice.positions.push_back({1, -1, 0.5f});
  twice.positions.push_back({1, 1, 0.5f});
  twice.faces.push_back({4, 5, 6});  // half of the square again, above it
  const OrthoView v = FramedView(Square(2), P3(0, 0, -1), 1000, 1000);
  EXPECT_EQ(CountCoveredPixels(twice, v), CountCoveredPixels(Square(2), v));
  EXPECT_EQ(CountCoveredPixels(Square(2), FramedView(Square(2), P3(1, 0, 0), 1000, 1000)), 0u);
}

TEST(ComputePixelBudget, WorstAxisAndBudget) {
  // A square in the z = 0 plane is seen whole from +-Z and edge-on from the other axes.
  const IndexedMesh sq = Square(2);
  PixelBudgetParams p;
  p.width = 1000;
  p.height = 1000;
  PixelBudgetResult r;
  ASSERT_TRUE(ComputePixelBudget(sq, p, r).ok());
  EXPECT_EQ(r.axisPixels[0], 0u);
  EXPECT_EQ(r.axisPixels[2], 0u);
  EXPECT_EQ(r.axisPixels[4], 708u * 708u);
  EXPECT_EQ(r.axisPixels[5], 708u * 708u);
  EXPECT_EQ(r.coveredPixels, 708u * 708u);
  EXPECT_NEAR(std::abs(r.viewDirection[2]), 1.0, 1e-12);
  EXPECT_EQ(r.targetFaces, 50u * 708u * 708u);
  EXPECT_TRUE(r.aboveCurrent);  // 2 faces: far below the budget
  p.view = BudgetView::PlusX;
  ASSERT_TRUE(ComputePixelBudget(sq, p, r).ok());
  EXPECT_EQ(r.coveredPixels, 0u);
  EXPECT_EQ(r.targetFaces, 0u);
  p.view = BudgetView::Direction;
  p.direction = P3(0, 0.6, -0.8);  // tilted: the square's area shrinks by cos = 0.8
  ASSERT_TRUE(ComputePixelBudget(sq, p, r).ok());
  EXPECT_NEAR(double(r.coveredPixels), 0.8 * 500000, 0.01 * 0.8 * 500000);
}

TEST(ComputePixelBudget, PixelsScaleWithTheResolution) {
  // The paper's Table 1 relation: at the same framing, covered pixels scale with the square of
  // the shorter side (16:9 resolutions: with the screen area).
  const IndexedMesh sphere = test::Sphere(5);
  PixelBudgetParams p;
  PixelBudgetResult full, hd, vga;
  ASSERT_TRUE(ComputePixelBudget(sphere, p, full).ok());
  p.width = 1280;
  p.height = 720;
  ASSERT_TRUE(ComputePixelBudget(sphere, p, hd).ok());
  p.width = 800;
  p.height = 600;
  ASSERT_TRUE(ComputePixelBudget(sphere, p, vga).ok());
  EXPECT_NEAR(double(hd.coveredPixels) / full.coveredPixels, (1280.0 * 720) / (1920.0 * 1080), 0.005);
  EXPECT_NEAR(double(vga.coveredPixels) / full.coveredPixels, (600.0 * 600) / (1080.0 * 1080), 0.005);
  EXPECT_EQ(full.targetFaces, size_t(std::llround(50.0 * full.coveredPixels)));
  EXPECT_EQ(full.aboveCurrent, full.targetFaces >= full.currentFaces);
}

TEST(ComputePixelBudget, RealMeshBelowItsBudgetAndAbove) {
  CMesh m;
  ASSERT_EQ(LoadPly(m, test::MeshPath("stanford_bunny_bun_zipper.ply")), "");
  const IndexedMesh bunny = ToIndexedMesh(m);
  PixelBudgetParams p;
  p.width = 320;
  p.height = 240;
  p.pixelFactor = 1;
  PixelBudgetResult r;
  ASSERT_TRUE(ComputePixelBudget(bunny, p, r).ok());
  EXPECT_GT(r.coveredPixels, 5000u);        // the bunny fills a good part of its framed disc
  EXPECT_LT(r.coveredPixels, 240u * 240u);  // but never more than the square around it
  EXPECT_FALSE(r.aboveCurrent);             // 1 face per pixel: far below its 69451 faces
  p.pixelFactor = 50;
  ASSERT_TRUE(ComputePixelBudget(bunny, p, r).ok());
  EXPECT_TRUE(r.aboveCurrent);
}

TEST(ComputePixelBudget, BadInputAndParameters) {
  PixelBudgetParams p;
  PixelBudgetResult r;
  IndexedMesh empty;
  Status s = ComputePixelBudget(empty, p, r);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message.find("no faces"), std::string::npos);
  p.width = 0;
  s = ComputePixelBudget(test::Cube(), p, r);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message.find("Width"), std::string::npos);
  p = PixelBudgetParams();
  p.pixelFactor = -1;
  EXPECT_FALSE(ComputePixelBudget(test::Cube(), p, r).ok());
  p = PixelBudgetParams();
  p.view = BudgetView::Direction;
  p.direction = P3(0, 0, 0);
  EXPECT_FALSE(ComputePixelBudget(test::Cube(), p, r).ok());
}

TEST(ParseBudgetView, NamesAndDirections) {
  BudgetView v;
  P3 d;
  ASSERT_TRUE(ParseBudgetView("worst", v, d));
  EXPECT_EQ(v, BudgetView::WorstAxis);
  ASSERT_TRUE(ParseBudgetView("-z", v, d));
  EXPECT_EQ(v, BudgetView::MinusZ);
  ASSERT_TRUE(ParseBudgetView("1,2,-3", v, d));
  EXPECT_EQ(v, BudgetView::Direction);
  EXPECT_EQ(d, P3(1, 2, -3));
  EXPECT_FALSE(ParseBudgetView("0,0,0", v, d));
  EXPECT_FALSE(ParseBudgetView("up", v, d));
  EXPECT_FALSE(ParseBudgetView("1,2", v, d));
}

}  // namespace
}  // namespace conelod
