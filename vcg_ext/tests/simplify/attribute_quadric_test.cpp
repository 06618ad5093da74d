// Tests of attribute_quadric.h: a linear colour survives any collapse exactly (the attribute
// planes reproduce it at any new position, which the survivor's own colour does not); a texture
// seam given per face corner keeps its vertices in place and its charts apart while it is
// simplified along; weight 0 keeps the attribute-free collapse; a colour edge steers the collapse
// order with a weight.
#include "conelod/simplify/attribute_quadric.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "conelod/mesh/attributes.h"
#include "conelod/simplify/group_qem.h"
#include "test_util.h"

namespace conelod {
namespace {

constexpr int kN = 12;

// Grid(kN) scaled to the unit square in z = 0 ( vertex (x, y) = y (n+1) + x) with RGB = a linear function of
// the position, bent along its middle column so that collapses move vertices off the old ones.
IndexedMesh UnitGrid() {
  IndexedMesh m = test::Grid(kN);
  for (auto& p : m.positions) p /= float(kN);
  return m;
}
IndexedMesh BentGrid() {
  IndexedMesh m = UnitGrid();
  for (auto& p : m.positions) p[2] = 0.3f * std::fabs(p[0] - 0.5f);
  return m;
}
std::array<float, 3> LinearColour(const vcg::Point3f& p) {
  return {{0.2f + 0.5f * p[0], 0.9f - 0.6f * p[1], 0.1f + 0.3f * p[0] + 0.4f * p[1]}};
}
// Per face corner, texture coordinates of two charts cut at x = 0.5: (x, y) left of the cut (by
// the face's centroid), (x + 1, y) right of it.
std::vector<float> TwoChartCorners(const IndexedMesh& m) {
  std::vector<float> corner;
  for (const auto& t : m.faces) {
    const float cx = (m.positions[t[0]][0] + m.positions[t[1]][0] + m.positions[t[2]][0]) / 3;
    for (uint32_t v : t) {
      corner.push_back(m.positions[v][0] + (cx > 0.5f ? 1 : 0));
      corner.push_back(m.positions[v][1]);
    }
  }
  return corner;
}
// Per face corner, the values of the corner's vertex.
std::vector<float> Corners(const IndexedMesh& m, const VertexAttributes& a) {
  std::vector<float> c;
  for (const auto& t : m.faces)
    for (uint32_t v : t) c.insert(c.end(), a.of(v), a.of(v) + a.channels());
  return c;
}
// The values at output corner k of face f.
std::vector<float> At(const AttributeQuadrics& aq, const GroupQemResult& r, size_t f, int k) {
  std::vector<float> out(size_t(aq.channels()));
  const uint32_t o = r.mesh.faces[f][size_t(k)];
  const auto& q = r.mesh.positions[o];
  aq.Evaluate(r.sourceFace[f], k, r.sourceVertex[o], vcg::Point3d(q[0], q[1], q[2]), out.data());
  return out;
}
// Every face of `r` (simplified with TwoChartCorners' texture coordinates) has its corners in one
// chart, and each corner's (u, v) is its vertex's (x, y), u shifted by 1 in the right chart.
void ExpectTwoChartsFollowPositions(const AttributeQuadrics& aq, const GroupQemResult& r) {
  for (size_t f = 0; f < r.mesh.faceCount(); ++f) {
    int right = 0;
    for (int k = 0; k < 3; ++k) {
      const auto uv = At(aq, r, f, k);
      const auto& q = r.mesh.positions[r.mesh.faces[f][size_t(k)]];
      right += uv[0] >= 1;
      EXPECT_NEAR(uv[0] - (uv[0] >= 1 ? 1 : 0), q[0], 1e-5) << "u does not follow x in its chart";
      EXPECT_NEAR(uv[1], q[1], 1e-5) << "v does not follow y";
    }
    EXPECT_TRUE(right == 0 || right == 3) << "face " << f << " has corners of both charts";
  }
}
VertexAttributes ColoursOf(const IndexedMesh& m) {
  VertexAttributes a;
  a.colorChannels = 3;
  for (const auto& p : m.positions)
    for (float c : LinearColour(p)) a.values.push_back(c);
  return a;
}
// Every corner of `r` (simplified from `m` with `aq`'s linear colours) has the linear colour at its
// vertex's place; returns how many corners sit at a vertex that moved.
size_t ExpectLinearColours(const IndexedMesh& m, const AttributeQuadrics& aq, const GroupQemResult& r) {
  size_t moved = 0;
  for (size_t f = 0; f < r.mesh.faceCount(); ++f)
    for (int k = 0; k < 3; ++k) {
      const uint32_t o = r.mesh.faces[f][size_t(k)];
      const auto got = At(aq, r, f, k);
      const auto want = LinearColour(r.mesh.positions[o]);
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[size_t(c)], want[size_t(c)], 2e-5) << "vertex " << o;
      moved += r.mesh.positions[o] != m.positions[r.sourceVertex[o]];
    }
  return moved;
}

// With memoryless steps too (GroupQemParams::refreshRatio: the models built again from the faces
// of the step, three times on the way to an eighth): the colour stays exactly linear.
TEST(AttributeQuadric, ReproducesALinearColourAtEveryNewPosition) {
  const IndexedMesh m = BentGrid();
  const VertexAttributes colours = ColoursOf(m);
  for (double refresh : {0.0, 0.5}) {
    SCOPED_TRACE(refresh);
    AttributeQuadrics aq;
    ASSERT_TRUE(aq.Init(m, colours, Corners(m, colours), 1.0).ok());
    GroupQemParams p;
    p.targetFaces = m.faceCount() / 8;
    p.condition1 = false;
    p.refreshRatio = refresh;
    GroupQemResult r;
    ASSERT_TRUE(
        SimplifyPreservingGroups(m, std::vector<int>(m.faceCount(), 0), p, r, Progress(), {}, nullptr, &aq).ok());
    ASSERT_LE(r.mesh.faceCount(), p.targetFaces);
    const size_t moved = ExpectLinearColours(m, aq, r);
    EXPECT_GT(moved, 0u) << "no vertex moved: the test would not tell interpolation from the survivor's colour";
  }
}

// A grid cut along x = 0.5 into two texture charts, given per face corner (u = x left, x + 1
// right): the middle column's vertices are seam vertices. They never move, the seam is simplified
// along itself, and no face ends with corners of both charts.
TEST(AttributeQuadric, KeepsTextureSeams) {
  const IndexedMesh m = BentGrid();
  VertexAttributes layout;
  layout.texCoords = true;
  const std::vector<float> corner = TwoChartCorners(m);
  for (double refresh : {0.0, 0.5}) {  // with memoryless steps too (the models rebuilt around the seam)
    SCOPED_TRACE(refresh);
    AttributeQuadrics aq;
    ASSERT_TRUE(aq.Init(m, layout, corner, 1.0).ok());
    EXPECT_EQ(aq.seamVertices(), size_t(kN + 1));
    GroupQemParams p;
    p.targetFaces = 16;
    p.condition1 = false;
    p.refreshRatio = refresh;
    GroupQemResult r;
    ASSERT_TRUE(
        SimplifyPreservingGroups(m, std::vector<int>(m.faceCount(), 0), p, r, Progress(), {}, nullptr, &aq).ok());
    size_t seamLeft = 0;
    for (size_t o = 0; o < r.mesh.positions.size(); ++o)
      if (aq.seam(r.sourceVertex[o])) {
        ++seamLeft;
        EXPECT_EQ(r.mesh.positions[o], m.positions[r.sourceVertex[o]]) << "a seam vertex moved";
      }
    EXPECT_GE(seamLeft, 2u);
    EXPECT_LT(seamLeft, size_t(kN + 1)) << "the seam was not simplified along itself";
    ExpectTwoChartsFollowPositions(aq, r);
  }
}

// An atlas of small charts: the bent grid cut into 6 x 6 charts of 2 x 2 cells, chart (i, j)'s
// texture coordinates (x + 2 i, y + 2 j) per face corner, so that every chart's border vertex is
// on a seam (5 seam lines each way, 105 vertices) and 25 of them are junctions of four charts. Junctions used to stay,
// and the collapse stopped far above a small target. With AllowSeamMoves they go (and small charts with them) at a
// cost, and still no face takes a coordinate from another chart: every face's corners lie in one chart's tile [2 i + i
// / 6, 2 i + (i + 1) / 6] x [2 j + j / 6, ...], i.e. each corner keeps a value of its own chart.
TEST(AttributeQuadric, ChartJunctionsGoWithoutCrossingSeams) {
  const IndexedMesh m = BentGrid();
  constexpr int kCharts = kN / 2;
  VertexAttributes layout;
  layout.texCoords = true;
  std::vector<float> corner;
  for (const auto& t : m.faces) {
    const float cx = (m.positions[t[0]][0] + m.positions[t[1]][0] + m.positions[t[2]][0]) / 3;
    const float cy = (m.positions[t[0]][1] + m.positions[t[1]][1] + m.positions[t[2]][1]) / 3;
    const int i = int(cx * kCharts), j = int(cy * kCharts);
    for (uint32_t v : t) {
      corner.push_back(m.positions[v][0] + 2.0f * float(i));
      corner.push_back(m.positions[v][1] + 2.0f * float(j));
    }
  }
  GroupQemParams p;
  p.targetFaces = 24;
  p.condition1 = false;
  const std::vector<int> groups(m.faceCount(), 0);
  const auto run = [&](bool moves, AttributeQuadrics& aq, GroupQemResult& r) {
    ASSERT_TRUE(aq.Init(m, layout, corner, 1.0).ok());
    aq.AllowSeamMoves(moves);
    ASSERT_TRUE(SimplifyPreservingGroups(m, groups, p, r, Progress(), {}, nullptr, &aq).ok());
  };
  AttributeQuadrics fixedAq, movingAq;
  GroupQemResult fixed, moving;
  run(false, fixedAq, fixed);
  run(true, movingAq, moving);
  EXPECT_EQ(fixedAq.seamVertices(), 105u);
  EXPECT_GT(fixed.mesh.faceCount(), 4 * p.targetFaces) << "the junctions should have stopped it";
  EXPECT_LE(moving.mesh.faceCount(), p.targetFaces);
  size_t away = 0;  // corners whose coordinates are not their chart's function of the position
  for (size_t f = 0; f < moving.mesh.faceCount(); ++f) {
    int ci = -1, cj = -1;
    for (int k = 0; k < 3; ++k) {
      const auto uv = At(movingAq, moving, f, k);
      const int i = int(std::floor((uv[0] + 0.5f) / 2)), j = int(std::floor((uv[1] + 0.5f) / 2));  // tiles 1 apart
      if (k == 0) ci = i, cj = j;
      EXPECT_TRUE(i == ci && j == cj) << "face " << f << " has corners of two charts";
      const float x = uv[0] - 2.0f * float(i), y = uv[1] - 2.0f * float(j);
      EXPECT_TRUE(x >= float(i) / kCharts - 1e-5f && x <= float(i + 1) / kCharts + 1e-5f &&
                  y >= float(j) / kCharts - 1e-5f && y <= float(j + 1) / kCharts + 1e-5f)
          << "face " << f << ": (" << uv[0] << ", " << uv[1] << ") outside its chart's tile";
      const auto& q = moving.mesh.positions[moving.mesh.faces[f][size_t(k)]];
      away += std::fabs(x - q[0]) > 1e-5f || std::fabs(y - q[1]) > 1e-5f;
    }
  }
  EXPECT_GT(away, 0u) << "no junction moved: the test would not see a seam move";
}

// A grid curved along y (z = 0.6 (y - 0.5)^2) cut along x = 0.5 into two charts (u = x left, x + 1
// right, v = y, per face corner): the seam is a polyline of chords, and the quadric's minimum on a
// seam edge lies inside it. Without seam moves a collapse along the seam slides the merged vertex
// there (a seam vertex used to stay at one end): every seam vertex stays on the input's seam and
// each side's coordinates are its chart's at its place. With seam moves a seam vertex may also
// leave the seam at a cost (the texture stretched): its coordinates stay its chart's at its anchor.
IndexedMesh CurvedGrid() {
  IndexedMesh m = UnitGrid();
  for (auto& p : m.positions) p[2] = 0.6f * (p[1] - 0.5f) * (p[1] - 0.5f);
  return m;
}
void SimplifyTwoCharts(const IndexedMesh& m, bool moves, AttributeQuadrics& aq, GroupQemResult& r) {
  VertexAttributes layout;
  layout.texCoords = true;
  const std::vector<float> corner = TwoChartCorners(m);
  ASSERT_TRUE(aq.Init(m, layout, corner, 1.0).ok());
  aq.AllowSeamMoves(moves);
  GroupQemParams p;
  p.targetFaces = 24;
  p.condition1 = false;
  ASSERT_TRUE(SimplifyPreservingGroups(m, std::vector<int>(m.faceCount(), 0), p, r, Progress(), {}, nullptr, &aq).ok());
  ASSERT_LE(r.mesh.faceCount(), p.targetFaces);
}
// z of the input's seam polyline (x = 0.5) at y.
float SeamZ(float y) {
  const int i = std::min(kN - 1, std::max(0, int(std::floor(y * kN))));
  const float y0 = float(i) / kN, y1 = float(i + 1) / kN, t = (y - y0) / (y1 - y0);
  const float z0 = 0.6f * (y0 - 0.5f) * (y0 - 0.5f), z1 = 0.6f * (y1 - 0.5f) * (y1 - 0.5f);
  return z0 + t * (z1 - z0);
}

TEST(AttributeQuadric, SeamVerticesSlideAlongTheirSeam) {
  const IndexedMesh m = CurvedGrid();
  AttributeQuadrics aq;
  GroupQemResult r;
  SimplifyTwoCharts(m, false, aq, r);
  size_t slid = 0;
  for (size_t o = 0; o < r.mesh.positions.size(); ++o) {
    if (!aq.seam(r.sourceVertex[o])) continue;
    const auto& q = r.mesh.positions[o];
    EXPECT_NEAR(q[0], 0.5f, 1e-5f) << "a seam vertex left the seam";
    EXPECT_NEAR(q[2], SeamZ(q[1]), 1e-5f) << "a seam vertex left the seam's chords";
    slid += std::fabs(q[1] * kN - std::round(q[1] * kN)) > 1e-3f;
  }
  EXPECT_GT(slid, 0u) << "no seam vertex between two input vertices: no collapse slid along the seam";
  ExpectTwoChartsFollowPositions(aq, r);
}

TEST(AttributeQuadric, SeamVerticesLeaveTheSeamOnlyWithSeamMoves) {
  const IndexedMesh m = CurvedGrid();
  AttributeQuadrics aq;
  GroupQemResult r;
  SimplifyTwoCharts(m, true, aq, r);
  size_t off = 0;
  for (size_t o = 0; o < r.mesh.positions.size(); ++o) {
    if (!aq.seam(r.sourceVertex[o])) continue;
    const auto& q = r.mesh.positions[o];
    off += std::fabs(q[0] - 0.5f) > 1e-5f || std::fabs(q[2] - SeamZ(q[1])) > 1e-5f;
  }
  EXPECT_GT(off, 0u) << "no seam vertex left the seam: the quadric's minimum should have drawn one off";
  for (size_t f = 0; f < r.mesh.faceCount(); ++f) {
    int right = 0;
    for (int k = 0; k < 3; ++k) {
      const auto uv = At(aq, r, f, k);
      right += uv[0] >= 1;
      const float u = uv[0] - (uv[0] >= 1 ? 1 : 0);
      // Each chart's own coordinates: left u in [0, 0.5], right in [0.5, 1] (after the shift).
      EXPECT_TRUE(uv[0] >= 1 ? u >= 0.5f - 1e-5f && u <= 1 + 1e-5f : u >= -1e-5f && u <= 0.5f + 1e-5f)
          << "face " << f << ": u " << uv[0] << " outside its chart";
      EXPECT_TRUE(uv[1] >= -1e-5f && uv[1] <= 1 + 1e-5f);
    }
    EXPECT_TRUE(right == 0 || right == 3) << "face " << f << " has corners of both charts";
  }
}

// A seam vertex that drifts (seam moves) takes its charts' coordinates at its new place where they
// stay inside each chart (AttributeQuadrics::Reparameterize): the flat grid cut at x = 0.5 into two
// charts (u = x left, x + 1 right, v = y), its middle vertex moved. Into the left chart: the left
// side follows exactly, the right side (the move would leave its faces in texture space) keeps
// its value. Along the seam: both follow. Farther than its faces reach: cut at their border.
TEST(AttributeQuadric, ReparameterizeFollowsTheMoveInsideTheChart) {
  const IndexedMesh m = UnitGrid();
  const uint32_t mid = uint32_t((kN / 2) * (kN + 1) + kN / 2);
  ASSERT_FLOAT_EQ(m.positions[mid][0], 0.5f);
  ASSERT_FLOAT_EQ(m.positions[mid][1], 0.5f);
  VertexAttributes layout;
  layout.texCoords = true;
  const std::vector<float> corner = TwoChartCorners(m);
  std::vector<uint32_t> fan;
  for (uint32_t f = 0; f < uint32_t(m.faceCount()); ++f)
    if (std::find(m.faces[f].begin(), m.faces[f].end(), mid) != m.faces[f].end()) fan.push_back(f);
  ASSERT_EQ(fan.size(), 6u);
  const AttributeQuadrics::FaceCorners faces = [&](uint32_t f) -> const std::array<uint32_t, 3>& { return m.faces[f]; };
  const auto pos = [&](uint32_t v) { return vcg::Point3d::Construct(m.positions[v]); };
  const vcg::Point3d from = pos(mid);
  // Moves mid by d; expects (u, v) on the left and right side's corners at mid.
  const auto check = [&](const vcg::Point3d& d, float lu, float lv, float ru, float rv) {
    AttributeQuadrics aq;
    ASSERT_TRUE(aq.Init(m, layout, corner, 1.0).ok());
    ASSERT_TRUE(aq.seam(mid));
    aq.Reparameterize(mid, from, from + d, fan.data(), fan.size(), faces, pos);
    int sides[2] = {0, 0};
    for (uint32_t f : fan) {
      const auto& t = m.faces[f];
      const int k = t[0] == mid ? 0 : (t[1] == mid ? 1 : 2);
      float uv[2];
      aq.Evaluate(f, k, mid, from + d, uv);
      const bool right = corner[(3 * size_t(f) + size_t(k)) * 2] >= 1;  // its side in the input
      ++sides[right];
      EXPECT_NEAR(uv[0], right ? ru : lu, 1e-6) << "u, move (" << d[0] << ", " << d[1] << ")";
      EXPECT_NEAR(uv[1], right ? rv : lv, 1e-6) << "v, move (" << d[0] << ", " << d[1] << ")";
    }
    EXPECT_TRUE(sides[0] > 0 && sides[1] > 0);
  };
  check(vcg::Point3d(-0.03, 0.02, 0), 0.47f, 0.52f, 1.5f, 0.5f);        // into the left chart
  check(vcg::Point3d(0.03, -0.02, 0), 0.5f, 0.5f, 1.53f, 0.48f);        // into the right chart
  check(vcg::Point3d(0, 0.03, 0), 0.5f, 0.53f, 1.5f, 0.53f);            // along the seam
  check(vcg::Point3d(0, 0, 0.05), 0.5f, 0.5f, 1.5f, 0.5f);              // along the normal
  check(vcg::Point3d(-0.2, 0, 0), 0.5f - 1.0f / kN, 0.5f, 1.5f, 0.5f);  // cut at the fan's border
}

// Weight 0: the collapse is the attribute-free one, vertex for vertex.
TEST(AttributeQuadric, WeightZeroKeepsTheAttributeFreeCollapse) {
  const IndexedMesh m = BentGrid();
  AttributeQuadrics aq;
  ASSERT_TRUE(aq.Init(m, ColoursOf(m), Corners(m, ColoursOf(m)), 0.0).ok());
  GroupQemParams p;
  p.targetFaces = 40;
  const std::vector<int> groups(m.faceCount(), 0);
  GroupQemResult with, without;
  ASSERT_TRUE(SimplifyPreservingGroups(m, groups, p, with, Progress(), {}, nullptr, &aq).ok());
  ASSERT_TRUE(SimplifyPreservingGroups(m, groups, p, without).ok());
  EXPECT_EQ(with.mesh.positions, without.mesh.positions);
  EXPECT_EQ(with.mesh.faces, without.mesh.faces);
}

// A flat grid whose colour jumps from black to white between two columns (no seam: each vertex
// has one colour, the faces across the jump blend): with a weight, the collapses keep the jump
// sharp, so the colour interpolated on the result at the original vertices is closer to theirs.
TEST(AttributeQuadric, WeightSteersTheCollapseAwayFromColourEdges) {
  IndexedMesh m = UnitGrid();
  VertexAttributes a;
  a.colorChannels = 3;
  for (const auto& q : m.positions)
    for (int c = 0; c < 3; ++c) a.values.push_back(q[0] < 0.45f ? 0.0f : 1.0f);
  auto error = [&](double weight) {
    AttributeQuadrics aq;
    EXPECT_TRUE(aq.Init(m, a, Corners(m, a), weight).ok());
    GroupQemParams p;
    p.targetFaces = 60;
    p.condition1 = false;
    GroupQemResult r;
    EXPECT_TRUE(
        SimplifyPreservingGroups(m, std::vector<int>(m.faceCount(), 0), p, r, Progress(), {}, nullptr, &aq).ok());
    std::vector<float> red(r.mesh.positions.size());
    for (size_t f = 0; f < r.mesh.faceCount(); ++f)
      for (int k = 0; k < 3; ++k) red[r.mesh.faces[f][size_t(k)]] = At(aq, r, f, k)[0];
    // Sum of squared differences at the input's vertices, interpolated in the output face
    // (in the plane) that holds each.
    double sum = 0;
    for (size_t v = 0; v < m.positions.size(); ++v) {
      const auto& p0 = m.positions[v];
      for (const auto& t : r.mesh.faces) {
        const auto &A = r.mesh.positions[t[0]], &B = r.mesh.positions[t[1]], &C = r.mesh.positions[t[2]];
        const double det = (B[0] - A[0]) * (C[1] - A[1]) - (C[0] - A[0]) * (B[1] - A[1]);
        if (det == 0) continue;
        const double u = ((p0[0] - A[0]) * (C[1] - A[1]) - (C[0] - A[0]) * (p0[1] - A[1])) / det;
        const double w = ((B[0] - A[0]) * (p0[1] - A[1]) - (p0[0] - A[0]) * (B[1] - A[1])) / det;
        if (u < -1e-9 || w < -1e-9 || u + w > 1 + 1e-9) continue;
        const double got = (1 - u - w) * red[t[0]] + u * red[t[1]] + w * red[t[2]];
        sum += (got - a.of(v)[0]) * (got - a.of(v)[0]);
        break;
      }
    }
    return sum;
  };
  EXPECT_LT(error(1.0), 0.5 * error(0.0));
}

// From 4,096 faces the collapse runs in its spatial (Morton) order; the attributes are renumbered
// with the mesh and given back in the input's numbering. A 50 x 50 bent grid (5,000 faces): a
// linear colour is still reproduced at every new position; weight 0 gives the attribute-free
// result (same order, same ties); a colour the same on every vertex (0.5, not exact in binary)
// changes nothing at weight 1 and is 0.5 exactly everywhere on the result.
TEST(AttributeQuadric, SpatialOrderCarriesTheAttributes) {
  IndexedMesh m = test::Grid(50);
  for (auto& p : m.positions) {
    p /= 50.0f;
    p[2] = 0.3f * std::fabs(p[0] - 0.5f);
  }
  ASSERT_GE(m.faceCount(), 4096u);
  const std::vector<int> groups(m.faceCount(), 0);
  GroupQemParams p;
  p.targetFaces = m.faceCount() / 10;
  GroupQemResult plain;
  ASSERT_TRUE(SimplifyPreservingGroups(m, groups, p, plain).ok());

  const VertexAttributes colours = ColoursOf(m);
  AttributeQuadrics linear;
  ASSERT_TRUE(linear.Init(m, colours, Corners(m, colours), 1.0).ok());
  GroupQemResult r;
  ASSERT_TRUE(SimplifyPreservingGroups(m, groups, p, r, Progress(), {}, nullptr, &linear).ok());
  const size_t moved = ExpectLinearColours(m, linear, r);
  EXPECT_GT(moved, 0u);

  AttributeQuadrics zero;
  ASSERT_TRUE(zero.Init(m, colours, Corners(m, colours), 0.0).ok());
  GroupQemResult withZero;
  ASSERT_TRUE(SimplifyPreservingGroups(m, groups, p, withZero, Progress(), {}, nullptr, &zero).ok());
  EXPECT_EQ(withZero.mesh.positions, plain.mesh.positions);
  EXPECT_EQ(withZero.mesh.faces, plain.mesh.faces);

  VertexAttributes grey;
  grey.colorChannels = 3;
  grey.values.assign(3 * m.positions.size(), 0.5f);
  AttributeQuadrics constant;
  ASSERT_TRUE(constant.Init(m, grey, Corners(m, grey), 1.0).ok());
  GroupQemResult withGrey;
  ASSERT_TRUE(SimplifyPreservingGroups(m, groups, p, withGrey, Progress(), {}, nullptr, &constant).ok());
  EXPECT_EQ(withGrey.mesh.positions, plain.mesh.positions);
  EXPECT_EQ(withGrey.mesh.faces, plain.mesh.faces);
  for (size_t f = 0; f < withGrey.mesh.faceCount(); ++f)
    for (int k = 0; k < 3; ++k)
      for (float c : At(constant, withGrey, f, k)) EXPECT_EQ(c, 0.5f);
}

TEST(AttributeQuadric, RefusesMismatchedInput) {
  const IndexedMesh m = BentGrid();
  const VertexAttributes a = ColoursOf(m);
  std::vector<float> corner = Corners(m, a);
  AttributeQuadrics aq;
  EXPECT_TRUE(aq.Init(m, a, corner, 1.0).ok());
  EXPECT_FALSE(aq.Init(m, a, corner, -1.0).ok());
  corner.pop_back();
  EXPECT_FALSE(aq.Init(m, a, corner, 1.0).ok());
}

}  // namespace
}  // namespace conelod
