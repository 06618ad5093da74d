// Tests of the checked PLY reader (ply_format.h): small inline files with exact expectations.
#include "conelod/mesh/ply_format.h"

#include <cmath>
#include <cstring>
#include <string>

#include <gtest/gtest.h>

using namespace conelod;

namespace {

std::string Read(const std::string& bytes, PlyMesh& m) { return ParsePly(bytes.data(), bytes.size(), "t.ply", m); }

const char* const kTriangleHeader =
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 1\nproperty list uchar int vertex_indices\nend_header\n";

double SignedAreaZ(const PlyMesh& m) {  // the sum of the triangles' signed areas in the z = 0 plane
  double a = 0;
  for (const auto& t : m.triangles) {
    const auto& p = m.positions[t[0]];
    const auto& q = m.positions[t[1]];
    const auto& r = m.positions[t[2]];
    a += 0.5 * ((double(q[0]) - p[0]) * (double(r[1]) - p[1]) - (double(q[1]) - p[1]) * (double(r[0]) - p[0]));
  }
  return a;
}

}  // namespace

TEST(PlyFormat, ReadsAsciiTriangle) {
  PlyMesh m;
  ASSERT_EQ(Read(std::string(kTriangleHeader) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", m), "");
  ASSERT_EQ(m.positions.size(), 3u);
  ASSERT_EQ(m.triangles.size(), 1u);
  EXPECT_EQ(m.triangles[0][2], 2u);
  EXPECT_TRUE(m.faceQuality.empty());
}

// Big-endian doubles came out NaN for most vertices with the importer used before, and a face
// element with an extra property lost every face.
TEST(PlyFormat, ReadsBigEndianDoubleWithExtraFaceProperty) {
  std::string f =
      "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\n"
      "element face 1\nproperty list uchar uint vertex_indices\nproperty int flags\nend_header\n";
  auto be64 = [&](double v) {
    uint64_t u;
    std::memcpy(&u, &v, 8);
    for (int i = 7; i >= 0; --i) f += char((u >> (8 * i)) & 0xff);
  };
  auto be32 = [&](uint32_t u) {
    for (int i = 3; i >= 0; --i) f += char((u >> (8 * i)) & 0xff);
  };
  const double c[9] = {0.25, -1.5, 3, 1e-3, 2, -7, 100, 0, 0.125};
  for (double v : c) be64(v);
  f += char(3);
  be32(0);
  be32(1);
  be32(2);
  be32(0xdeadbeef);  // the extra face property: skipped, the face kept
  PlyMesh m;
  ASSERT_EQ(Read(f, m), "");
  ASSERT_EQ(m.triangles.size(), 1u);
  for (int i = 0; i < 9; ++i) EXPECT_EQ(m.positions[size_t(i / 3)][size_t(i % 3)], float(c[i]));
}

// The non-convex 7-gon that a fan turned into a flipped triangle outside the polygon: ear
// clipping gives 5 triangles, all of the polygon's orientation, covering exactly its area.
TEST(PlyFormat, EarClipsNonConvexPolygon) {
  const std::string f =
      "ply\nformat ascii 1.0\nelement vertex 7\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n4 0 0\n4 3 0\n3 1 0\n2 3 0\n1 1 0\n0 3 0\n7 0 1 2 3 4 5 6\n";
  PlyMesh m;
  ASSERT_EQ(Read(f, m), "");
  ASSERT_EQ(m.triangles.size(), 5u);
  EXPECT_EQ(m.polygons, 1u);
  double shoelace = 0;
  for (size_t i = 0; i < 7; ++i) {
    const auto& p = m.positions[i];
    const auto& q = m.positions[(i + 1) % 7];
    shoelace += 0.5 * (double(p[0]) * q[1] - double(q[0]) * p[1]);
  }
  EXPECT_NEAR(SignedAreaZ(m), shoelace, 1e-9);
  for (const auto& t : m.triangles) {  // each triangle has the polygon's (counter-clockwise) orientation
    PlyMesh one = m;
    one.triangles = {t};
    EXPECT_GT(SignedAreaZ(one), 0);
  }
}

TEST(PlyFormat, ConvexQuadGivesTheFanFromItsFirstCorner) {
  const std::string f =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nproperty float quality\nend_header\n"
      "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3 7\n";
  PlyMesh m;
  ASSERT_EQ(Read(f, m), "");
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(m.triangles[0], (std::array<uint32_t, 3>{{0, 1, 2}}));
  EXPECT_EQ(m.triangles[1], (std::array<uint32_t, 3>{{0, 2, 3}}));
  EXPECT_EQ(m.faceQuality, (std::vector<float>{7, 7}));  // a polygon's triangles share its quality
}

TEST(PlyFormat, RefusesCrossingPolygonByName) {
  const std::string f =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 1 0\n1 0 0\n0 1 0\n4 0 1 2 3\n";
  PlyMesh m;
  EXPECT_NE(Read(f, m).find("edges cross"), std::string::npos);
}

// Counts are checked against the bytes in the file before anything is allocated.
TEST(PlyFormat, RefusesCountsTheFileCannotHold) {
  PlyMesh m;
  std::string big = kTriangleHeader;
  big.replace(big.find("vertex 3"), 8, "vertex 100000000");
  EXPECT_NE(Read(big + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", m).find("truncated or corrupt"), std::string::npos);
  std::string negative = kTriangleHeader;
  negative.replace(negative.find("vertex 3"), 8, "vertex -5");
  EXPECT_NE(Read(negative, m).find("not a whole number"), std::string::npos);
}

TEST(PlyFormat, RefusesShortFacesAndBadIndices) {
  PlyMesh m;
  const std::string h = kTriangleHeader, v = "0 0 0\n1 0 0\n0 1 0\n";
  EXPECT_NE(Read(h + v + "2 0 1\n", m).find("2 corners (a face needs at least 3)"), std::string::npos);
  EXPECT_NE(Read(h + v + "0\n", m).find("0 corners"), std::string::npos);
  EXPECT_NE(Read(h + v + "3 0 1 3\n", m).find("uses vertex 3 but there are 3 vertices"), std::string::npos);
  EXPECT_NE(Read(h + v + "3 0 1\n", m).find("ends early"), std::string::npos);
}

TEST(PlyFormat, NamesOtherFormats) {
  PlyMesh m;
  for (const char* other : {"OFF\n3 1 0\n", "solid x\nfacet\n", "v 0 0 0\nf 1 2 3\n", "\x1f\x8b\x08\x00"})
    EXPECT_NE(Read(other, m).find("only PLY is read"), std::string::npos) << other;
}
