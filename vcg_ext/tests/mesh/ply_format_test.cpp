// Tests of the checked PLY reader (ply_format.h): small inline files with exact expectations.
#include "conelod/mesh/ply_format.h"

#include "conelod/grouping/group_colors.h"
#include "conelod/vcg_mesh.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <thread>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

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

namespace {

double Orient2(const std::array<float, 3>& a, const std::array<float, 3>& b, const std::array<float, 3>& c) {
  return (double(b[0]) - a[0]) * (double(c[1]) - a[1]) - (double(b[1]) - a[1]) * (double(c[0]) - a[0]);
}

// Whether p is strictly inside the polygon `ring` (z = 0; crossing number).
bool InsidePolygon(const std::vector<std::array<float, 3>>& ring, double x, double y) {
  bool inside = false;
  for (size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++) {
    const double xi = ring[i][0], yi = ring[i][1], xj = ring[j][0], yj = ring[j][1];
    if ((yi > y) != (yj > y) && x < (xj - xi) * (y - yi) / (yj - yi) + xi) inside = !inside;
  }
  return inside;
}

// Checks the triangulation of the simple polygon `ring` (z = 0, corners 0..n-1 in order):
// every triangle has the polygon's orientation (or no area), lies inside it (its centroid does),
// and together they cover exactly its area. "" or what is wrong.
std::string CheckTriangulation(const std::vector<std::array<float, 3>>& ring,
                               const std::vector<std::array<uint32_t, 3>>& tris) {
  double area = 0;
  for (size_t i = 0; i < ring.size(); ++i) {
    const auto& p = ring[i];
    const auto& q = ring[(i + 1) % ring.size()];
    area += 0.5 * (double(p[0]) * q[1] - double(q[0]) * p[1]);
  }
  const double sign = area > 0 ? 1 : -1;
  if (tris.size() != ring.size() - 2) return "not n - 2 triangles";
  double sum = 0;
  for (const auto& t : tris) {
    const double a = 0.5 * sign * Orient2(ring[t[0]], ring[t[1]], ring[t[2]]);
    if (a < 0)
      return "a reversed triangle " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]);
    if (a > 0) {
      const double cx = (double(ring[t[0]][0]) + ring[t[1]][0] + ring[t[2]][0]) / 3;
      const double cy = (double(ring[t[0]][1]) + ring[t[1]][1] + ring[t[2]][1]) / 3;
      if (!InsidePolygon(ring, cx, cy)) return "a triangle outside the polygon";
    }
    sum += a;
  }
  if (std::fabs(sum - std::fabs(area)) > 1e-9 * std::max(1.0, std::fabs(area)))
    return "the triangles cover " + std::to_string(sum) + ", the polygon " + std::to_string(std::fabs(area));
  return "";
}

bool Cross(const std::array<float, 3>& a, const std::array<float, 3>& b, const std::array<float, 3>& c,
           const std::array<float, 3>& d) {
  return Orient2(a, b, c) * Orient2(a, b, d) < 0 && Orient2(c, d, a) * Orient2(c, d, b) < 0;
}

// A random simple polygon with corners on a small integer grid (many corners on others'
// diagonals): random points, edges that cross uncrossed by reversing the run between them (2-opt),
// kept only when simple (no crossing, no corner on another edge, no repeated corner).
bool RandomSimplePolygon(std::mt19937& rng, std::vector<std::array<float, 3>>& ring) {
  const int n = std::uniform_int_distribution<int>(4, 12)(rng);
  const int grid = std::uniform_int_distribution<int>(3, 8)(rng);
  std::uniform_int_distribution<int> coord(0, grid);
  ring.clear();
  for (int i = 0; i < n; ++i) ring.push_back({float(coord(rng)), float(coord(rng)), 0.f});
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      if (ring[size_t(i)] == ring[size_t(j)]) return false;
  for (int round = 0; round < 200; ++round) {
    bool changed = false;
    for (int i = 0; i < n; ++i)
      for (int j = i + 2; j < n; ++j) {
        if (i == 0 && j == n - 1) continue;
        if (Cross(ring[size_t(i)], ring[size_t(i + 1)], ring[size_t(j)], ring[size_t((j + 1) % n)])) {
          std::reverse(ring.begin() + i + 1, ring.begin() + j + 1);
          changed = true;
        }
      }
    if (!changed) break;
  }
  for (int i = 0; i < n; ++i) {
    const auto& a = ring[size_t(i)];
    const auto& b = ring[size_t((i + 1) % n)];
    for (int j = 0; j < n; ++j) {
      if (j == i || j == (i + 1) % n) continue;
      const auto& p = ring[size_t(j)];
      if (Orient2(a, b, p) == 0 && std::min(a[0], b[0]) <= p[0] && p[0] <= std::max(a[0], b[0]) &&
          std::min(a[1], b[1]) <= p[1] && p[1] <= std::max(a[1], b[1]))
        return false;
      if (j > i + 1 && !(i == 0 && j == n - 1) && Cross(a, b, p, ring[size_t((j + 1) % n)])) return false;
    }
  }
  return true;
}

}  // namespace

// A 7-gon with a corner (6) on the diagonal 0-4: the ear 0-4-5 was clipped past it, and what was
// left, pinched at corner 6, gave the triangle 0-5-6, reversed and outside the polygon.
TEST(PlyFormat, EarClipsPolygonWithACornerOnADiagonal) {
  const std::string f =
      "ply\nformat ascii 1.0\nelement vertex 7\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "1 0 0\n2 0 0\n3 1 0\n3 3 0\n1 4 0\n0 4 0\n1 2 0\n7 0 1 2 3 4 5 6\n";
  PlyMesh m;
  ASSERT_EQ(Read(f, m), "");
  EXPECT_EQ(CheckTriangulation(m.positions, m.triangles), "");
}

// Every triangle of a simple polygon lies inside it with its orientation, both orientations, for
// random polygons on small grids (on the reader before, 5 % of them failed).
TEST(PlyFormat, EarClipsRandomSimplePolygons) {
  std::mt19937 rng(24);
  int tested = 0, failed = 0;
  std::string first;
  while (tested < 3000) {
    std::vector<std::array<float, 3>> ring;
    if (!RandomSimplePolygon(rng, ring)) continue;
    if (tested % 2) std::reverse(ring.begin(), ring.end());  // both orientations
    ++tested;
    std::vector<uint32_t> corners(ring.size());
    for (size_t i = 0; i < ring.size(); ++i) corners[i] = uint32_t(i);
    std::vector<std::array<uint32_t, 3>> tris;
    std::string err = TriangulatePolygon(ring, corners, tris);
    if (err.empty()) err = CheckTriangulation(ring, tris);
    if (!err.empty() && failed++ == 0) {
      first = err + " in";
      for (const auto& p : ring) first += " (" + std::to_string(int(p[0])) + "," + std::to_string(int(p[1])) + ")";
    }
  }
  EXPECT_EQ(failed, 0) << "first: " << first;
}

// A convex polygon with corners on its edges (on the diagonals of the fan, with their edges along
// them) is triangulated as before.
TEST(PlyFormat, ConvexPolygonWithFlatCornersAsBefore) {
  const std::vector<std::array<float, 3>> ring = {{0, 0, 0}, {2, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 4, 0}, {0, 2, 0}};
  std::vector<std::array<uint32_t, 3>> tris;
  ASSERT_EQ(TriangulatePolygon(ring, {0, 1, 2, 3, 4, 5}, tris), "");
  const std::vector<std::array<uint32_t, 3>> fan = {{1, 2, 3}, {1, 3, 4}, {1, 4, 5}, {0, 1, 5}};
  EXPECT_EQ(tris, fan);
}

// Float index lists with fractions (truncated to 0 2 4 before), a property declared twice (the
// last one won), a face with both index lists (the second won): refused by name.
TEST(PlyFormat, RefusesAmbiguousIndicesAndProperties) {
  PlyMesh m;
  const std::string v = "0 0 0\n1 0 0\n0 1 0\n2 2 0\n0 2 0\n";
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n";
  std::string err =
      Read(head + "element face 1\nproperty list uchar float vertex_indices\nend_header\n" + v + "3 0.5 2.7 4.2\n", m);
  EXPECT_NE(err.find("face 0 has the vertex index 0.5, which is not a whole number"), std::string::npos) << err;
  EXPECT_EQ(Read(head + "element face 1\nproperty list uchar float vertex_indices\nend_header\n" + v + "3 0 2 4\n", m),
            "");  // whole numbers in a float list are fine
  err = Read(
      "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
      "property float x\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n",
      m);
  EXPECT_NE(err.find("declares a property 'x' twice"), std::string::npos) << err;
  err = Read(head +
                 "element face 1\nproperty list uchar int vertex_indices\nproperty list uchar int vertex_index\n"
                 "end_header\n" +
                 v + "3 0 1 2 3 2 3 4\n",
             m);
  EXPECT_NE(err.find("both a vertex_indices and a vertex_index list"), std::string::npos) << err;
}

// A FIFO as input is refused at once, without opening it (open() blocked until a writer came).
TEST(PlyFormat, RefusesAFifoWithoutOpeningIt) {
  char folder[] = "/tmp/conelod_fifo_XXXXXX";
  ASSERT_NE(mkdtemp(folder), nullptr);
  const std::string fifo = std::string(folder) + "/in.ply";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  // Should the reader block in open(), a writer comes after 2 s so that the test ends (and fails).
  std::thread writer([&] {
    std::this_thread::sleep_for(std::chrono::seconds(2));
    const int fd = ::open(fifo.c_str(), O_WRONLY | O_NONBLOCK);
    if (fd >= 0) ::close(fd);
  });
  const auto start = std::chrono::steady_clock::now();
  PlyMesh m;
  bool ioError = false;
  const std::string err = ReadPly(fifo, m, &ioError);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(seconds, 1.0);
  EXPECT_NE(err.find("is a FIFO"), std::string::npos) << err;
  EXPECT_TRUE(ioError);
  // Unblock a writer still waiting: a reader opening without blocking.
  const int fd = ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
  writer.join();
  if (fd >= 0) ::close(fd);
  unlink(fifo.c_str());
  rmdir(folder);
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

// Indices beyond any integer (the fuzzer's find: casting 1e300 to an integer is undefined) are
// named as they were read.
TEST(PlyFormat, NamesIndicesBeyondAnyInteger) {
  PlyMesh m;
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uint double vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
  std::string err = Read(head + "3 0 1 1e300\n", m);
  EXPECT_NE(err.find("face 0 uses vertex 1e+300 but there are 3 vertices"), std::string::npos) << err;
  err = Read(head + "3 0 1 -1e300\n", m);
  EXPECT_NE(err.find("face 0 uses vertex -1e+300 but there are 3 vertices"), std::string::npos) << err;
  err = Read(head + "3 0 1 4294967296\n", m);
  EXPECT_NE(err.find("face 0 uses vertex 4294967296 but there are 3 vertices"), std::string::npos) << err;
}

TEST(PlyFormat, NamesOtherFormats) {
  PlyMesh m;
  for (const char* other : {"OFF\n3 1 0\n", "solid x\nfacet\n", "v 0 0 0\nf 1 2 3\n", "\x1f\x8b\x08\x00"})
    EXPECT_NE(Read(other, m).find("only PLY is read"), std::string::npos) << other;
}

// Attributes (issue 26): what MeshLab writes for a coloured scan with normals, and for a textured
// mesh with per-face texture coordinates and its image named in the header.
TEST(PlyFormat, ReadsVertexColourNormalsAndTextureCoordinates) {
  const std::string f =
      "ply\nformat ascii 1.0\ncomment TextureFile my texture.png\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
      "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n"
      "property float texture_u\nproperty float texture_v\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0 0 0 1 255 0 51 255 0 0.5\n1 0 0 0 0 1 0 255 0 128 1 0.5\n0 1 0 0 1 0 0 0 255 0 0.25 1\n3 0 1 2\n";
  PlyMesh m;
  ASSERT_EQ(Read(f, m), "");
  ASSERT_EQ(m.colors.size(), 3u);
  EXPECT_TRUE(m.colorAlpha);
  EXPECT_FALSE(m.colorIsFloat);
  EXPECT_FLOAT_EQ(m.colors[0][0], 1.0f);
  EXPECT_FLOAT_EQ(m.colors[0][2], 0.2f);  // 51 / 255
  EXPECT_FLOAT_EQ(m.colors[1][3], 128.0f / 255);
  ASSERT_EQ(m.normals.size(), 3u);
  EXPECT_EQ(m.normals[2][1], 1.0f);
  ASSERT_EQ(m.texCoords.size(), 3u);
  EXPECT_EQ(m.texCoords[2][0], 0.25f);
  EXPECT_EQ(m.texCoords[2][1], 1.0f);
  ASSERT_EQ(m.textureFiles.size(), 1u);
  EXPECT_EQ(m.textureFiles[0], "my texture.png");  // a name with a space, as MeshLab writes it
  EXPECT_TRUE(m.wedgeTexCoords.empty());
  EXPECT_TRUE(m.hasAttributes());
}

TEST(PlyFormat, ReadsFloatColourWithoutAlphaAndSt) {
  const std::string f =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "property float diffuse_red\nproperty float diffuse_green\nproperty float diffuse_blue\n"
      "property float s\nproperty float t\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0 0.5 0.25 1 0 0\n1 0 0 0 0 0 1 0\n0 1 0 1 1 1 0 1\n3 0 1 2\n";
  PlyMesh m;
  ASSERT_EQ(Read(f, m), "");
  ASSERT_EQ(m.colors.size(), 3u);
  EXPECT_FALSE(m.colorAlpha);
  EXPECT_TRUE(m.colorIsFloat);
  EXPECT_EQ(m.colors[0][1], 0.25f);
  EXPECT_EQ(m.colors[0][3], 1.0f);
  ASSERT_EQ(m.texCoords.size(), 3u);
  EXPECT_EQ(m.texCoords[1][0], 1.0f);
}

// A quad with a texcoord list: each triangle of its fan takes its own corners' coordinates.
TEST(PlyFormat, ReadsPerFaceTexcoordListsThroughTriangulation) {
  const std::string f =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nproperty list uchar float texcoord\nend_header\n"
      "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3 8 0 0 0.5 0 0.5 0.5 0 0.5\n";
  PlyMesh m;
  ASSERT_EQ(Read(f, m), "");
  ASSERT_EQ(m.triangles.size(), 2u);
  ASSERT_EQ(m.wedgeTexCoords.size(), 2u);
  for (size_t t = 0; t < 2; ++t)
    for (size_t k = 0; k < 3; ++k) {
      const auto& p = m.positions[m.triangles[t][k]];
      EXPECT_EQ(m.wedgeTexCoords[t][2 * k], 0.5f * p[0]);  // u = x / 2, v = y / 2 on this quad
      EXPECT_EQ(m.wedgeTexCoords[t][2 * k + 1], 0.5f * p[1]);
    }
}

TEST(PlyFormat, RefusesIncompleteAttributes) {
  PlyMesh m;
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
  const std::string tail = "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  EXPECT_NE(
      Read(head + "property uchar red\nproperty uchar green\n" + tail + "0 0 0 1 1\n1 0 0 1 1\n0 1 0 1 1\n3 0 1 2\n", m)
          .find("lacks one of red, green, blue"),
      std::string::npos);
  EXPECT_NE(Read(head + "property float nx\n" + tail + "0 0 0 1\n1 0 0 1\n0 1 0 1\n3 0 1 2\n", m)
                .find("lacks one of nx, ny, nz"),
            std::string::npos);
  EXPECT_NE(Read(head + "property int red\nproperty int green\nproperty int blue\n" + tail +
                     "0 0 0 1 1 1\n1 0 0 1 1 1\n0 1 0 1 1 1\n3 0 1 2\n",
                 m)
                .find("colours are read as uchar, ushort or float"),
            std::string::npos);
  const std::string withList =
      "element face 1\nproperty list uchar int vertex_indices\n"
      "property list uchar float texcoord\nend_header\n";
  EXPECT_NE(Read(head + withList + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2 4 0 0 1 0\n", m).find("texcoord values"),
            std::string::npos);
}

// A geometry-only file has no attribute at all (the attribute-free paths stay as they were).
TEST(PlyFormat, GeometryOnlyHasNoAttributes) {
  PlyMesh m;
  ASSERT_EQ(Read(std::string(kTriangleHeader) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", m), "");
  EXPECT_FALSE(m.hasAttributes());
  EXPECT_TRUE(m.textureFiles.empty());
}

// Binary records in the host's byte order are read a block of 65,536 at a time on the threads;
// a block with a record of another shape (here a quad) or a bad index is read record by record.
// 70,000 vertices (with a byte after x y z) and 140,001 faces, binary at 1 and 3 threads, are
// the same ASCII file read record by record, bit for bit; a bad index in the second block gives
// the record-by-record message.
TEST(PlyFormat, BinaryBlocksOnThreadsAreTheRecordByRecordRead) {
  const uint32_t V = 70000, F = 140000;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> coord(-2, 2);
  std::vector<std::array<float, 3>> pos(V);
  for (auto& p : pos)
    for (float& x : p) x = coord(rng);
  pos[5] = {{-0.f, 0.f, 1e-30f}};
  std::vector<std::vector<uint32_t>> faces(F);
  for (auto& f : faces)
    for (int k = 0; k < 3; ++k) f.push_back(uint32_t(rng() % V));
  faces.insert(faces.begin() + 70000, std::vector<uint32_t>{0, 1, 2, 3});  // a quad in the second block
  auto header = [&](const char* format) {
    return std::string("ply\nformat ") + format + " 1.0\nelement vertex " + std::to_string(V) +
           "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar flags\nelement face " +
           std::to_string(faces.size()) + "\nproperty list uchar uint vertex_indices\nend_header\n";
  };
  auto files = [&](uint32_t badFace) {
    std::string ascii = header("ascii"), binary = header("binary_little_endian");
    char text[64];
    for (const auto& p : pos) {
      std::snprintf(text, sizeof text, "%.9g %.9g %.9g 7\n", double(p[0]), double(p[1]), double(p[2]));
      ascii += text;
      binary.append(reinterpret_cast<const char*>(p.data()), 12);
      binary += char(7);
    }
    for (uint32_t i = 0; i < faces.size(); ++i) {
      ascii += std::to_string(faces[i].size());
      binary += char(faces[i].size());
      for (uint32_t v : faces[i]) {
        const uint32_t w = i == badFace ? V : v;
        ascii += " " + std::to_string(w);
        binary.append(reinterpret_cast<const char*>(&w), 4);
      }
      ascii += "\n";
    }
    return std::make_pair(ascii, binary);
  };
  const uint16_t one = 1;
  unsigned char low;
  std::memcpy(&low, &one, 1);
  if (low != 1) GTEST_SKIP() << "a big-endian host reads these records one by one";
  const auto good = files(UINT32_MAX);
  PlyMesh fromAscii, fromBinary;
  ASSERT_EQ(Read(good.first, fromAscii), "");
  ASSERT_EQ(Read(good.second, fromBinary), "");
  ASSERT_EQ(fromAscii.triangles.size(), size_t(F) + 2);
  ASSERT_EQ(fromAscii.positions.size(), size_t(V));
  auto same = [](const PlyMesh& a, const PlyMesh& b) {
    return a.triangles == b.triangles && a.positions.size() == b.positions.size() &&
           std::memcmp(a.positions.data(), b.positions.data(), a.positions.size() * 12) == 0;
  };
  EXPECT_TRUE(same(fromAscii, fromBinary));
  const std::string path = ::testing::TempDir() + "conelod_ply_blocks_" + std::to_string(getpid()) + ".ply";
  {
    FILE* f = std::fopen(path.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    ASSERT_EQ(std::fwrite(good.second.data(), 1, good.second.size(), f), good.second.size());
    std::fclose(f);
  }
  PlyMesh threaded;
  ASSERT_EQ(ReadPly(path, threaded, nullptr, 3), "");
  EXPECT_TRUE(same(fromAscii, threaded));
  std::vector<std::array<uint32_t, 3>> streamed;  // streamed in batches on 3 threads
  PlyMesh held;
  ASSERT_EQ(ReadPlyStreaming(
                path, held,
                [&](const std::vector<std::array<uint32_t, 3>>& batch) {
                  streamed.insert(streamed.end(), batch.begin(), batch.end());
                  return std::string();
                },
                nullptr, 3),
            "");
  EXPECT_EQ(streamed, fromAscii.triangles);
  std::remove(path.c_str());
  const auto bad = files(100000);
  PlyMesh m;
  const std::string expected = "face 100000 uses vertex 70000 but there are 70000 vertices";
  EXPECT_NE(Read(bad.first, m).find(expected), std::string::npos);
  EXPECT_NE(Read(bad.second, m).find(expected), std::string::npos);
}

namespace {
std::string FileBytes(const std::string& path) {
  std::string bytes;
  if (std::FILE* f = std::fopen(path.c_str(), "rb")) {
    char buffer[4096];
    for (size_t n; (n = std::fread(buffer, 1, sizeof buffer, f)) > 0;) bytes.append(buffer, n);
    std::fclose(f);
  }
  return bytes;
}
}  // namespace

// `conelod group` writes its output straight from the file's data (SavePlyFaceValues): the same
// bytes as vcglib's exporter writes for the vcg mesh of the same data (SavePly), with every
// attribute that path takes (vertex colours as uchar, ushort or float, with and without alpha;
// normals), an unreferenced vertex, a polygon and a face quality of the input (replaced).
TEST(PlyFormat, FaceValuesWriterWritesWhatVcglibWrites) {
  char folder[] = "/tmp/conelod_facevalues_XXXXXX";
  ASSERT_NE(mkdtemp(folder), nullptr);
  const std::string mine = std::string(folder) + "/mine.ply", theirs = std::string(folder) + "/vcg.ply";
  struct Variant {
    const char* name;
    const char* vertexProperties;
    const char* vertexValues[5];
  };
  const Variant variants[] = {
      {"geometry", "", {"", "", "", "", ""}},
      {"rgb",
       "property uchar red\nproperty uchar green\nproperty uchar blue\n",
       {" 10 200 30", " 0 0 0", " 255 255 255", " 1 2 3", " 9 8 7"}},
      {"rgba+normals",
       "property float nx\nproperty float ny\nproperty float nz\nproperty uchar red\nproperty uchar green\n"
       "property uchar blue\nproperty uchar alpha\n",
       {" 0 0 1 10 200 30 128", " 0.6 0 0.8 0 0 0 0", " 0 1 0 255 255 255 255", " 1 0 0 1 2 3 4", " 0 0 -1 9 8 7 6"}},
      {"float colour",
       "property float red\nproperty float green\nproperty float blue\n",
       {" 0.5 0.25 1", " 0 0.003 0.999", " 1 1 1", " 0.1 0.2 0.3", " 0.7 0.8 0.9"}},
      {"normals",
       "property float nx\nproperty float ny\nproperty float nz\n",
       {" 0 0 1", " 1 0 0", " 0 1 0", " 0 0 -1", " 0.25 0.5 1e-7"}}};
  const char* const positions[5] = {"0 0 0", "1 0 0", "1 1 0.5", "0 1 0", "7 7 7"};  // vertex 4: unused
  for (const Variant& v : variants) {
    std::string file = std::string("ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\n") +
                       "property float z\n" + v.vertexProperties +
                       "element face 2\nproperty list uchar int vertex_indices\nproperty float quality\nend_header\n";
    for (int i = 0; i < 5; ++i) file += std::string(positions[i]) + v.vertexValues[i] + "\n";
    file += "4 0 1 2 3 0.5\n3 2 1 0 7\n";  // a quad (two triangles) and a triangle
    PlyMesh in;
    ASSERT_EQ(Read(file, in), "") << v.name;
    ASSERT_EQ(in.triangles.size(), 3u);
    const int mask = AttributeMask(PlyLoadMask(in, false));
    ASSERT_TRUE(PlyFaceValuesWritable(in, mask)) << v.name;
    const std::vector<int> faceValue = {2, 0, 2};
    const std::vector<vcg::Color4b> colour = {GroupColor(0), GroupColor(1), GroupColor(2)};
    const std::vector<float> quality = {0, 1, 2.5f};
    ASSERT_EQ(SavePlyFaceValues(in, mask, faceValue, colour, quality, mine), "") << v.name;
    CMesh m;
    MeshFromPlyData(in, false, m);
    for (size_t f = 0; f < m.face.size(); ++f) {
      m.face[f].Q() = quality[size_t(faceValue[f])];
      m.face[f].C() = colour[size_t(faceValue[f])];
    }
    ASSERT_EQ(SavePly(m, theirs, mask), "") << v.name;
    const std::string a = FileBytes(mine), b = FileBytes(theirs);
    EXPECT_GT(a.size(), 200u) << v.name;
    EXPECT_TRUE(a == b) << v.name << ": " << a.size() << " bytes, vcglib's " << b.size();
  }
  // Texture coordinates are not written this way (vcglib's exporter writes them), nor values out
  // of range: refused, nothing written.
  PlyMesh tex;
  ASSERT_EQ(Read("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                 "property float s\nproperty float t\nelement face 1\nproperty list uchar int vertex_indices\n"
                 "end_header\n0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n",
                 tex),
            "");
  EXPECT_FALSE(PlyFaceValuesWritable(tex, AttributeMask(PlyLoadMask(tex, false))));
  const std::string refused = std::string(folder) + "/refused.ply";
  EXPECT_NE(SavePlyFaceValues(tex, 0, {0}, {GroupColor(0)}, {0.f}, refused), "");
  PlyMesh plain;
  ASSERT_EQ(Read(std::string(kTriangleHeader) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", plain), "");
  EXPECT_NE(SavePlyFaceValues(plain, 0, {1}, {GroupColor(0)}, {0.f}, refused), "");
  EXPECT_EQ(FileBytes(refused), "");
  std::remove(mine.c_str());
  std::remove(theirs.c_str());
  rmdir(folder);
}
