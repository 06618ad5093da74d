// Tests of lod.h: the .clod file written, read back and refined. Tiny meshes built in code with
// exact expectations, then the bunny: the full-budget round trip gives the input back exactly,
// small budgets give fewer faces and finer levels where the eye looks, every cut covers every
// input face exactly once with adjacent nodes at most one level apart (checked here from the
// input's own edges, not from the refiner's figures), and every kind of bad file is refused with
// its message.
#include "conelod/lod.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <map>

#include <unistd.h>

#include "conelod/lod_internal.h"
#include "conelod/sorted_faces.h"
#include "conelod/vcg_bridge.h"
#include "conelod/vcg_mesh.h"
#include "test_util.h"

namespace conelod {
namespace {

using namespace lodfile;

// Per process: ctest runs the tests of this file in parallel processes, each building its files.
std::string TempPath(const std::string& name) {
  return ::testing::TempDir() + "conelod_lod_test_" + std::to_string(getpid()) + "_" + name;
}

std::vector<uint8_t> ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// A mesh, its hierarchy and levels, and its .clod file (path and bytes).
struct Built {
  IndexedMesh mesh;
  GroupHierarchy hierarchy;
  std::vector<SimplifiedLevel> levels;
  LodBuildStats stats;
  std::string path;
  std::vector<uint8_t> bytes;
};

void Build(Built& b, const std::string& name, const ConeGroupingParams& gp = ConeGroupingParams()) {
  ASSERT_TRUE(BuildConeHierarchy(b.mesh, gp, b.hierarchy).ok());
  ASSERT_TRUE(BuildSimplifiedLevels(b.mesh, b.hierarchy, HierarchicalSimplificationParams(), b.levels).ok());
  b.path = TempPath(name + ".clod");
  const Status s = WriteLodFile(b.mesh, b.hierarchy, b.levels, b.path, &b.stats);
  ASSERT_TRUE(s.ok()) << s.message;
  b.bytes = ReadBytes(b.path);
  ASSERT_EQ(b.bytes.size(), b.stats.fileBytes);
}

// Input faces covered by a node: those of its group at its level (level 0: the level-1 group).
const std::vector<int>& FaceGroupOf(const GroupHierarchy& h, int nodeLevel) { return h.level(std::max(1, nodeLevel)).faceGroup; }

// Checks a cut against the input: each input face covered by exactly one node; adjacent input
// faces (sharing an edge) in nodes at most `maxDiff` levels apart. Returns the per-face node level.
std::vector<int> CheckCut(const Built& b, LodReader& r, const LodCut& cut, int maxDiff = 1) {
  const size_t F = b.mesh.faces.size();
  std::vector<int> faceLevel(F, -1);
  // Group -> cut node level, per node level.
  std::vector<std::map<uint32_t, int>> inCut(size_t(r.info().levels));
  for (uint32_t id : cut.nodes) {
    const LodNode& n = r.node(id);
    EXPECT_TRUE(inCut[size_t(n.level)].emplace(n.group, n.level).second) << "node " << id << " twice in the cut";
  }
  for (size_t f = 0; f < F; ++f) {
    int covers = 0;
    for (int k = 0; k < r.info().levels; ++k)
      if (inCut[size_t(k)].count(uint32_t(FaceGroupOf(b.hierarchy, k)[f]))) {
        ++covers;
        faceLevel[f] = k;
      }
    EXPECT_EQ(covers, 1) << "input face " << f << " covered " << covers << " times";
    if (covers != 1) return faceLevel;
  }
  const FaceAdjacency adj = BuildFaceAdjacency(b.mesh);
  int worst = 0;
  for (uint32_t f = 0; f < F; ++f)
    for (uint32_t i = adj.offsets[f]; i < adj.offsets[f + 1]; ++i)
      worst = std::max(worst, std::abs(faceLevel[f] - faceLevel[adj.neighbours[i]]));
  EXPECT_LE(worst, maxDiff);
  EXPECT_EQ(worst, cut.maxLevelDifference) << "the refiner's figure disagrees with the input's edges";
  size_t faces = 0;
  for (uint32_t id : cut.nodes) faces += r.node(id).faceCount;
  EXPECT_EQ(faces, cut.faces);
  return faceLevel;
}

std::unique_ptr<LodReader> OpenOk(const std::vector<uint8_t>& bytes) {
  std::unique_ptr<LodReader> r;
  const Status s = LodReader::OpenMemory(bytes, r);
  EXPECT_TRUE(s.ok()) << s.message;
  return r;
}

std::string OpenError(const std::vector<uint8_t>& bytes) {
  std::unique_ptr<LodReader> r;
  const Status s = LodReader::OpenMemory(bytes, r);
  if (s.ok()) return "";
  EXPECT_FALSE(r);
  return s.message;
}

// Opens, refines at full budget and extracts: "" or the first error.
std::string FullReadError(const std::vector<uint8_t>& bytes) {
  std::unique_ptr<LodReader> r;
  Status s = LodReader::OpenMemory(bytes, r);
  if (!s.ok()) return s.message;
  LodView v;
  v.eye = vcg::Point3d(0, 0, 10);
  v.faceBudget = size_t(1) << 40;
  LodCut cut;
  s = RefineLod(*r, v, cut);
  if (!s.ok()) return s.message;
  IndexedMesh m;
  s = ExtractCutMesh(*r, cut, true, m);
  return s.ok() ? "" : s.message;
}

LodView Eye(double x, double y, double z, size_t budget, bool cull = true) {
  LodView v;
  v.eye = vcg::Point3d(x, y, z);
  v.faceBudget = budget;
  v.cullBackFacing = cull;
  return v;
}

// --- Priority ---------------------------------------------------------------------------------

TEST(RefinementPriority, FollowsThePapersFormula) {
  LodNode n;
  n.cone.axis = vcg::Point3d(0, 0, 1);
  n.cone.halfAngle = 0;
  n.center = vcg::Point3f(0, 0, 0);
  // Facing the eye: a + c = 0 -> 0; seen edge-on: a = pi/2 -> 1/2; from behind -> 1.
  EXPECT_NEAR(RefinementPriority(n, Eye(0, 0, 5, 0)), 0.0, 1e-12);
  EXPECT_NEAR(RefinementPriority(n, Eye(5, 0, 0, 0)), 0.5, 1e-12);
  EXPECT_NEAR(RefinementPriority(n, Eye(0, 0, -5, 0)), 1.0, 1e-12);
  // A wide cone raises it: a = pi/4, c = pi/4 -> (1 - cos(pi/2)) / 2 = 1/2; a + c >= pi -> 1.
  n.cone.halfAngle = NormalCone::kPi / 4;
  EXPECT_NEAR(RefinementPriority(n, Eye(1, 0, 1, 0)), 0.5, 1e-12);
  EXPECT_EQ(RefinementPriority(n, Eye(-1, 0, -1, 0)), 1.0);
  // Orthographic: e = -viewDir.
  LodView o;
  o.orthographic = true;
  o.viewDir = vcg::Point3d(0, 0, -1);
  n.cone.halfAngle = 0;
  EXPECT_NEAR(RefinementPriority(n, o), 0.0, 1e-12);
}

// --- A tiny mesh: exact structure -------------------------------------------------------------

class TinyLod : public ::testing::Test {
 protected:
  static void SetUpTestCase() {
    tiny_ = new Built;
    tiny_->mesh = test::Sphere(2);  // 128 faces, 66 vertices
    Build(*tiny_, "sphere");
  }
  static void TearDownTestCase() {
    std::remove(tiny_->path.c_str());
    delete tiny_;
  }
  static Built* tiny_;
};
Built* TinyLod::tiny_ = nullptr;

TEST_F(TinyLod, HeaderAndNodeStructure) {
  const Built& b = *tiny_;
  auto r = OpenOk(b.bytes);
  ASSERT_TRUE(r);
  const LodFileInfo& i = r->info();
  const int H = b.hierarchy.levelCount();
  EXPECT_EQ(i.version, 1u);
  EXPECT_EQ(i.levels, H + 1);
  EXPECT_EQ(i.inputFaces, 128u);
  EXPECT_EQ(i.inputVertices, 66u);
  EXPECT_EQ(i.fileBytes, b.bytes.size());
  EXPECT_EQ(i.levelFaces[0], 128u);
  EXPECT_EQ(i.levelNodes[0], b.hierarchy.level(1).groups.size());
  for (int k = 1; k <= H; ++k) {
    EXPECT_EQ(i.levelNodes[size_t(k)], b.hierarchy.level(k).groups.size());
    EXPECT_EQ(i.levelFaces[size_t(k)], b.levels[size_t(k - 1)].mesh.faces.size());
  }
  EXPECT_NEAR(i.box.min[0], -1, 1e-6);
  EXPECT_NEAR(i.box.max[2], 1, 1e-6);
  // Roots: the top level's nodes, ids 0..; records and geometry loaded at Open.
  ASSERT_EQ(r->roots().size(), i.levelNodes.back());
  for (size_t k = 0; k < r->roots().size(); ++k) {
    EXPECT_EQ(r->roots()[k], uint32_t(k));
    ASSERT_TRUE(r->hasNode(uint32_t(k)));
    EXPECT_EQ(r->node(uint32_t(k)).level, H);
    EXPECT_EQ(r->node(uint32_t(k)).parent, -1);
    EXPECT_NE(r->geometry(uint32_t(k)), nullptr);
  }
  // Nothing finer is loaded at Open.
  EXPECT_FALSE(r->hasNode(uint32_t(r->roots().size())));
  // Walk every node: children consecutive, at the level below, naming their parent; level-1
  // nodes have one child (the level-0 node of the same group).
  std::vector<uint32_t> todo = r->roots();
  size_t seen = 0;
  while (!todo.empty()) {
    const uint32_t id = todo.back();
    todo.pop_back();
    ++seen;
    ASSERT_TRUE(r->LoadChildren(id).ok());
    const LodNode n = r->node(id);
    EXPECT_EQ(r->levelOfNode(id), uint32_t(n.level));
    if (n.level == 0) {
      EXPECT_EQ(n.childCount, 0u);
    }
    if (n.level == 1) {
      EXPECT_EQ(n.childCount, 1u);
    }
    for (uint32_t c = n.firstChild; c < n.firstChild + n.childCount; ++c) {
      ASSERT_TRUE(r->hasNode(c));
      EXPECT_EQ(r->node(c).level, n.level - 1);
      EXPECT_EQ(r->node(c).parent, int64_t(id));
      if (n.level == 1) {
        EXPECT_EQ(r->node(c).group, n.group);
      }
      todo.push_back(c);
    }
    // Every face's normal lies in the node's cone (exact minimal cone of its own faces).
    ASSERT_TRUE(r->LoadGeometry(id).ok());
    const LodGeometry& g = *r->geometry(id);
    EXPECT_EQ(g.faces.size(), n.faceCount);
    EXPECT_EQ(g.positions.size(), n.vertexCount);
    for (const auto& t : g.faces) {
      IndexedMesh one;
      one.positions = {g.positions[t[0]], g.positions[t[1]], g.positions[t[2]]};
      one.faces = {{0, 1, 2}};
      vcg::Point3d nrm;
      double area;
      FaceNormalAndArea(one, 0, nrm, area);
      if (area > 0) {
        EXPECT_TRUE(n.cone.contains(nrm, 1e-7));
      }
      for (uint32_t v : t) EXPECT_LE((g.positions[v] - n.center).Norm(), n.radius * (1 + 1e-5f));
    }
  }
  EXPECT_EQ(seen, i.nodeCount);
}

TEST_F(TinyLod, FullBudgetGivesTheInputBack) {
  const Built& b = *tiny_;
  auto r = OpenOk(b.bytes);
  ASSERT_TRUE(r);
  LodCut cut;
  ASSERT_TRUE(RefineLod(*r, Eye(0.3, 0.2, 5, 1000), cut).ok());
  EXPECT_EQ(cut.faces, 128u);
  for (uint32_t id : cut.nodes) EXPECT_EQ(r->node(id).level, 0);
  CheckCut(b, *r, cut);
  IndexedMesh out;
  std::vector<int> level;
  ASSERT_TRUE(ExtractCutMesh(*r, cut, true, out, &level).ok());
  EXPECT_EQ(out.faces.size(), 128u);
  EXPECT_EQ(out.positions.size(), 66u);  // welded: the input's shared vertices
  EXPECT_EQ(SortedFacePositions(out), SortedFacePositions(b.mesh));
  EXPECT_TRUE(std::all_of(level.begin(), level.end(), [](int l) { return l == 0; }));
  // The level-0 vertex ids are the input's vertex indices.
  for (uint32_t id : cut.nodes) {
    const LodGeometry& g = *r->geometry(id);
    for (size_t v = 0; v < g.vertexIds.size(); ++v) EXPECT_EQ(g.positions[v], b.mesh.positions[g.vertexIds[v]]);
  }
}

TEST_F(TinyLod, ZeroBudgetKeepsTheRoots) {
  auto r = OpenOk(tiny_->bytes);
  ASSERT_TRUE(r);
  LodCut cut;
  ASSERT_TRUE(RefineLod(*r, Eye(0, 0, 5, 0), cut).ok());
  std::vector<uint32_t> nodes = cut.nodes;
  std::sort(nodes.begin(), nodes.end());
  EXPECT_EQ(nodes, r->roots());
  EXPECT_EQ(cut.refinements, 0u);
  EXPECT_EQ(cut.faces, r->info().levelFaces.back());
}

TEST_F(TinyLod, FileAndMemoryReadersAgree) {
  std::unique_ptr<LodReader> a, m;
  ASSERT_TRUE(LodReader::Open(tiny_->path, a).ok());
  m = OpenOk(tiny_->bytes);
  LodCut ca, cm;
  ASSERT_TRUE(RefineLod(*a, Eye(0, 3, 1, 60), ca).ok());
  ASSERT_TRUE(RefineLod(*m, Eye(0, 3, 1, 60), cm).ok());
  EXPECT_EQ(ca.nodes, cm.nodes);
  EXPECT_EQ(ca.culled, cm.culled);
}

TEST_F(TinyLod, EveryFlippedByteIsReadOrRefused) {
  // A bounded in-test fuzz: each byte of the file flipped in turn must give a clean result or an
  // error, never a crash (ASan/UBSan builds run this too). Almost every flip must be refused
  // (the CRCs); a flip in a padding field may pass.
  const std::vector<uint8_t>& good = tiny_->bytes;
  ASSERT_EQ(FullReadError(good), "");
  // Every byte of the header, then a sample of the rest (the fuzz target, scripts/fuzz.sh, goes
  // further), so that the test stays quick under the sanitizers.
  size_t refused = 0, tried = 0;
  const size_t header = kChunkHeaderBytes + size_t(DecodeChunkHeader(good.data()).dataBytes);
  const size_t stride = std::max<size_t>(1, good.size() / 600);
  for (size_t at = 0; at < good.size(); at += at < header ? 1 : stride) {
    std::vector<uint8_t> bad = good;
    bad[at] ^= 0x5A;
    if (!FullReadError(bad).empty()) ++refused;
    ++tried;
  }
  EXPECT_GE(refused, tried * 99 / 100) << "of " << tried << " flipped bytes";
  // And every truncation.
  for (size_t n = 0; n < good.size(); n += stride) {
    std::vector<uint8_t> cut(good.begin(), good.begin() + long(n));
    EXPECT_NE(FullReadError(cut), "") << n << " bytes";
  }
}

// --- Bad files: each refused with its message ---------------------------------------------------

// Rewrites the chunk at `at` after `edit` changed its data, with a fresh CRC (so that only the
// intended inconsistency remains).
void Rechecksum(std::vector<uint8_t>& bytes, size_t at) {
  ChunkHeader h = DecodeChunkHeader(bytes.data() + at);
  const uint32_t crc = Crc32(bytes.data() + at + kChunkHeaderBytes, size_t(h.dataBytes));
  for (int i = 0; i < 4; ++i) bytes[at + 4 + size_t(i)] = uint8_t(crc >> (8 * i));
}
void PutU64(std::vector<uint8_t>& bytes, size_t at, uint64_t v) {
  for (int i = 0; i < 8; ++i) bytes[at + size_t(i)] = uint8_t(v >> (8 * i));
}

TEST_F(TinyLod, BadFilesAreRefusedWithTheirReason) {
  const std::vector<uint8_t>& good = tiny_->bytes;
  auto has = [](const std::string& msg, const std::string& what) {
    return msg.find(what) != std::string::npos;
  };
  {  // truncated
    std::vector<uint8_t> b(good.begin(), good.end() - 100);
    EXPECT_TRUE(has(OpenError(b), "truncated")) << OpenError(b);
    b.resize(10);
    EXPECT_TRUE(has(OpenError(b), "truncated")) << OpenError(b);
    EXPECT_TRUE(has(OpenError({}), "truncated"));
  }
  {  // wrong magic
    std::vector<uint8_t> b = good;
    b[0] = 'X';
    EXPECT_TRUE(has(OpenError(b), "wrong magic")) << OpenError(b);
    std::vector<uint8_t> ply = {'p', 'l', 'y', '\n', 'f', 'o', 'r', 'm', 'a', 't', ' ', 'b', 'i', 'n', 'a', 'r', 'y',
                                '_', 'l', 'i', 't', 't', 'l', 'e', '_', 'e'};
    EXPECT_TRUE(has(OpenError(ply), "not a .clod file")) << OpenError(ply);
  }
  {  // wrong version (a valid checksum: a file from a future writer)
    std::vector<uint8_t> b = good;
    b[kChunkHeaderBytes] = 7;
    Rechecksum(b, 0);
    EXPECT_TRUE(has(OpenError(b), "unsupported .clod version 7")) << OpenError(b);
  }
  {  // corrupted chunk size: the root's child size
    std::vector<uint8_t> b = good;
    PutU64(b, 16, DecodeChunkHeader(b.data()).childBytes + 1000);
    EXPECT_TRUE(has(OpenError(b), "truncated")) << OpenError(b);
    PutU64(b, 16, DecodeChunkHeader(good.data()).childBytes - 8);
    EXPECT_TRUE(has(OpenError(b), "corrupt chunk size")) << OpenError(b);
    b = good;
    PutU64(b, 8, uint64_t(1) << 60);  // the header's data size
    EXPECT_TRUE(has(OpenError(b), "corrupt chunk size")) << OpenError(b);
  }
  {  // corrupted chunk size: a node record's (found through the index)
    std::vector<uint8_t> b = good;
    const size_t hier = size_t(Decoder(b.data() + kChunkHeaderBytes + 56, 8).u64());  // hierarchy offset
    const size_t firstRecord = hier + kChunkHeaderBytes;
    PutU64(b, firstRecord + 8, 1000000);
    EXPECT_TRUE(has(OpenError(b), "corrupt chunk size")) << OpenError(b);
  }
  {  // corrupted checksum: one byte of the header's data, then one of a root's geometry
    std::vector<uint8_t> b = good;
    const ChunkHeader h0 = DecodeChunkHeader(good.data());
    b[kChunkHeaderBytes + 20] ^= 1;
    EXPECT_TRUE(has(OpenError(b), "checksum mismatch in the file header")) << OpenError(b);
    b = good;
    b[kChunkHeaderBytes + h0.dataBytes - 1] ^= 1;  // the last level entry's padding is covered too
    EXPECT_TRUE(has(OpenError(b), "checksum mismatch")) << OpenError(b);
    // The last bytes of the file are the last index block's entries: only read on demand.
    b = good;
    b[b.size() - 30] ^= 0x40;
    const std::string e = FullReadError(b);
    EXPECT_TRUE(has(e, "checksum mismatch in index block")) << e;
  }
  {  // a vertex block's checksum: found when the geometry using it is read
    std::vector<uint8_t> b = good;
    const size_t level0 = kChunkHeaderBytes + kHeaderFixedBytes;  // level 0's entry
    const size_t vert = size_t(Decoder(b.data() + level0 + 40, 8).u64());
    b[vert + kChunkHeaderBytes + kVertDataBytes + kChunkHeaderBytes + 5] ^= 0x10;
    EXPECT_EQ(OpenError(b), "");
    const std::string e = FullReadError(b);
    EXPECT_TRUE(has(e, "checksum mismatch in a vertex block")) << e;
  }
  {  // offsets past the end: the index offset, the hierarchy offset (valid header checksum)
    std::vector<uint8_t> b = good;
    PutU64(b, kChunkHeaderBytes + 64, b.size() + 4096);  // index offset
    Rechecksum(b, 0);
    EXPECT_TRUE(has(OpenError(b), "past the end")) << OpenError(b);
    b = good;
    PutU64(b, kChunkHeaderBytes + 56, uint64_t(1) << 62);  // hierarchy offset
    Rechecksum(b, 0);
    EXPECT_TRUE(has(OpenError(b), "past the end")) << OpenError(b);
  }
  {  // huge counts: refused before anything is allocated
    std::vector<uint8_t> b = good;
    PutU64(b, kChunkHeaderBytes + kHeaderFixedBytes, uint64_t(1) << 40);  // level 0's face count
    Rechecksum(b, 0);
    EXPECT_TRUE(has(OpenError(b), "larger than the file")) << OpenError(b);
  }
  {  // a missing file
    std::unique_ptr<LodReader> r;
    const Status s = LodReader::Open(TempPath("does_not_exist.clod"), r);
    EXPECT_FALSE(s.ok());
    EXPECT_TRUE(has(s.message, "cannot open")) << s.message;
  }
}

// --- The bunny --------------------------------------------------------------------------------

class BunnyLod : public ::testing::Test {
 protected:
  static void SetUpTestCase() {
    bunny_ = new Built;
    CMesh m;
    ASSERT_EQ(LoadPly(m, test::MeshPath("stanford_bunny_bun_zipper.ply")), "");
    bunny_->mesh = ToIndexedMesh(m);
    Build(*bunny_, "bunny");
  }
  static void TearDownTestCase() {
    std::remove(bunny_->path.c_str());
    delete bunny_;
  }
  static std::unique_ptr<LodReader> Open() {
    std::unique_ptr<LodReader> r;
    const Status s = LodReader::Open(bunny_->path, r);
    EXPECT_TRUE(s.ok()) << s.message;
    return r;
  }
  static Built* bunny_;
};
Built* BunnyLod::bunny_ = nullptr;

TEST_F(BunnyLod, FullBudgetRoundTripIsExact) {
  auto r = Open();
  ASSERT_TRUE(r);
  LodCut cut;
  ASSERT_TRUE(RefineLod(*r, Eye(0, 0.1, 0.6, size_t(1) << 30), cut).ok());
  EXPECT_EQ(cut.faces, 69451u);
  EXPECT_GT(cut.groupsCulled, 0u);  // culled nodes are refined too, last
  CheckCut(*bunny_, *r, cut, 0);
  IndexedMesh out;
  ASSERT_TRUE(ExtractCutMesh(*r, cut, true, out).ok());
  EXPECT_EQ(out.faces.size(), 69451u);
  EXPECT_EQ(SortedFacePositions(out), SortedFacePositions(bunny_->mesh));
  // Welded: the input's used vertices (the bunny has unreferenced ones).
  std::vector<uint8_t> used(bunny_->mesh.positions.size(), 0);
  for (const auto& t : bunny_->mesh.faces)
    for (uint32_t v : t) used[v] = 1;
  EXPECT_EQ(out.positions.size(), size_t(std::count(used.begin(), used.end(), 1)));
}

TEST_F(BunnyLod, SmallBudgetsRefineWhereTheEyeLooks) {
  auto r = Open();
  ASSERT_TRUE(r);
  const vcg::Box3f box = r->info().box;
  const vcg::Point3f c = box.Center();
  const double d = 3 * box.Diag();
  size_t previous = 0;
  for (double fraction : {0.02, 0.05, 0.1, 0.3}) {
    SCOPED_TRACE(fraction);
    const size_t budget = size_t(fraction * 69451);
    // Eye on +z: the front half (z above the centre) should be finer than the back half.
    LodCut cut;
    ASSERT_TRUE(RefineLod(*r, Eye(c[0], c[1], c[2] + d, budget), cut).ok());
    EXPECT_LE(cut.faces, budget);
    EXPECT_GT(cut.faces, budget * 8 / 10);  // the budget is used
    EXPECT_GT(cut.faces, previous);
    previous = cut.faces;
    EXPECT_LE(cut.maxLevelDifference, 1);
    const std::vector<int> level = CheckCut(*bunny_, *r, cut);
    // Per input face, its node's level, averaged over each half of the model (z above / below the
    // centre); drawn faces per half.
    auto halves = [&](const LodCut& k, const std::vector<int>& faceLevel, double out[4]) {
      double sum[2] = {0, 0}, count[2] = {0, 0}, drawn[2] = {0, 0};
      for (size_t f = 0; f < bunny_->mesh.faces.size(); ++f) {
        const auto& t = bunny_->mesh.faces[f];
        const float z = bunny_->mesh.positions[t[0]][2] + bunny_->mesh.positions[t[1]][2] + bunny_->mesh.positions[t[2]][2];
        const int side = z > 3 * c[2] ? 0 : 1;
        sum[side] += faceLevel[f];
        count[side] += 1;
      }
      for (size_t i = 0; i < k.nodes.size(); ++i)
        if (!k.culled[i]) drawn[r->node(k.nodes[i]).center[2] > c[2] ? 0 : 1] += r->node(k.nodes[i]).faceCount;
      out[0] = sum[0] / count[0];
      out[1] = sum[1] / count[1];
      out[2] = drawn[0];
      out[3] = drawn[1];
    };
    double h[4];
    halves(cut, level, h);
    IndexedMesh out;
    ASSERT_TRUE(ExtractCutMesh(*r, cut, true, out).ok());
    EXPECT_EQ(out.faces.size(), cut.faces);
    EXPECT_LT(out.faces.size(), 69451u);
    // At 2% the cut is the roots and a few more (541 faces at the top level): too coarse to say.
    if (fraction < 0.05) continue;
    EXPECT_LT(h[0], h[1]) << "the half facing the eye should be finer";
    EXPECT_GT(h[2], h[3]) << "more faces drawn on the half facing the eye";
    // The same eye from -z: now the other half is finer.
    LodCut other;
    ASSERT_TRUE(RefineLod(*r, Eye(c[0], c[1], c[2] - d, budget), other).ok());
    halves(other, CheckCut(*bunny_, *r, other), h);
    EXPECT_GT(h[0], h[1]);
    EXPECT_LT(h[2], h[3]);
  }
}

TEST_F(BunnyLod, CulledNodesFaceAwayFromTheEye) {
  auto r = Open();
  ASSERT_TRUE(r);
  const vcg::Point3d eye(0.3, 0.2, 0.5);
  LodCut cut;
  ASSERT_TRUE(RefineLod(*r, Eye(eye[0], eye[1], eye[2], 20000), cut).ok());
  ASSERT_GT(cut.groupsCulled, 0u);
  size_t checked = 0;
  for (size_t i = 0; i < cut.nodes.size(); ++i) {
    if (!cut.culled[i]) continue;
    ASSERT_TRUE(r->LoadGeometry(cut.nodes[i]).ok());
    const LodGeometry& g = *r->geometry(cut.nodes[i]);
    for (const auto& t : g.faces) {
      const vcg::Point3d a = vcg::Point3d::Construct(g.positions[t[0]]);
      const vcg::Point3d n = (vcg::Point3d::Construct(g.positions[t[1]]) - a) ^ (vcg::Point3d::Construct(g.positions[t[2]]) - a);
      EXPECT_LE(n * (eye - a), 1e-12) << "a culled face looks at the eye";
      ++checked;
    }
  }
  EXPECT_GT(checked, 0u);
  // Without culling nothing is flagged.
  ASSERT_TRUE(RefineLod(*r, Eye(eye[0], eye[1], eye[2], 20000, false), cut).ok());
  EXPECT_EQ(cut.groupsCulled, 0u);
  EXPECT_EQ(cut.drawnFaces, cut.faces);
}

TEST_F(BunnyLod, StepwiseRefinementMatchesRefineLod) {
  auto r = Open();
  ASSERT_TRUE(r);
  const LodView view = Eye(-0.2, 0.15, 0.4, 15000);
  LodCut whole;
  ASSERT_TRUE(RefineLod(*r, view, whole).ok());
  LodRefiner refiner(*r);
  ASSERT_TRUE(refiner.Start(view).ok());
  size_t steps = 0;
  while (!refiner.Done()) {
    ASSERT_TRUE(refiner.Step(7).ok());
    ++steps;
    ASSERT_LE(refiner.cut().maxLevelDifference, 1);  // after every step, not only at the end
  }
  EXPECT_GT(steps, 3u);
  std::vector<uint32_t> a = whole.nodes, b = refiner.cut().nodes;
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  EXPECT_EQ(a, b);
  // Coarser levels first: every level-(k-1) node appears only once every visible level-k node that
  // can be refined under the budget... checked loosely: no cut node is more than 2 levels finer
  // than the coarsest visible one.
  int coarsest = 0, finest = 64;
  for (size_t i = 0; i < b.size(); ++i) {
    coarsest = std::max(coarsest, r->node(b[i]).level);
    finest = std::min(finest, r->node(b[i]).level);
  }
  EXPECT_LE(coarsest - finest, 3);
}

TEST_F(BunnyLod, EvictionLowersResidentBytes) {
  auto r = Open();
  ASSERT_TRUE(r);
  const size_t atOpen = r->residentBytes();
  LodCut cut;
  ASSERT_TRUE(RefineLod(*r, Eye(0, 0.1, 0.6, 20000), cut).ok());
  const size_t refined = r->residentBytes();
  EXPECT_GT(refined, atOpen);
  size_t evicted = 0;
  for (uint32_t id : cut.nodes)
    if (r->geometry(id)) {
      r->EvictGeometry(id);
      ++evicted;
      EXPECT_EQ(r->geometry(id), nullptr);
    }
  EXPECT_GT(evicted, 0u);
  EXPECT_LT(r->residentBytes(), refined - 20000 * 6);  // at least the triangles went
  // The refiner starting again evicts what it no longer draws.
  LodRefiner refiner(*r);
  ASSERT_TRUE(refiner.Start(Eye(0, 0.1, 0.6, 40000)).ok());
  while (!refiner.Done()) ASSERT_TRUE(refiner.Step(64).ok());
  const size_t big = r->residentBytes();
  ASSERT_TRUE(refiner.Start(Eye(0, 0.1, 0.6, 0)).ok());
  EXPECT_LT(r->residentBytes(), big);
  for (uint32_t id : refiner.cut().nodes) EXPECT_NE(r->geometry(id), nullptr);
}

TEST_F(BunnyLod, ResidentMemoryFollowsTheCutNotTheModel) {
  auto r = Open();
  ASSERT_TRUE(r);
  // The whole model as the core holds it: positions and faces.
  const size_t model = bunny_->mesh.positions.size() * 12 + bunny_->mesh.faces.size() * 12;
  EXPECT_LT(r->residentBytes(), model / 20) << "coarsest level";
  LodCut cut;
  ASSERT_TRUE(RefineLod(*r, Eye(0, 0.1, 0.6, 69451 / 10), cut).ok());
  EXPECT_LT(r->residentBytes(), model / 4) << "10% budget";
}

TEST(Lod, WriterRefusesMismatchedInput) {
  IndexedMesh m = test::Sphere(1);
  GroupHierarchy h;
  ASSERT_TRUE(BuildConeHierarchy(m, ConeGroupingParams(), h).ok());
  std::vector<SimplifiedLevel> levels;
  const std::string path = TempPath("refused.clod");
  std::remove(path.c_str());
  EXPECT_FALSE(WriteLodFile(m, h, levels, path).ok());  // no levels
  ASSERT_TRUE(BuildSimplifiedLevels(m, h, HierarchicalSimplificationParams(), levels).ok());
  levels[0].faceGroup[0] = 1 << 20;
  EXPECT_FALSE(WriteLodFile(m, h, levels, path).ok());
  std::ifstream in(path);
  EXPECT_FALSE(in.good()) << "no file is left behind";
  EXPECT_FALSE(WriteLodFile(m, h, levels, "/nonexistent-dir/x.clod").ok());
}

TEST(Lod, CancellingLeavesNoFile) {
  IndexedMesh m = test::Sphere(3);
  const std::string path = TempPath("cancelled.clod");
  std::remove(path.c_str());
  // Stop at each stage in turn: grouping, simplification, records, geometry.
  for (int stopAt : {1, 30, 91, 97}) {
    int last = -1;
    const Progress stop = [&](int percent, const char*) {
      EXPECT_GE(percent, last) << "progress must rise";
      last = percent;
      return percent < stopAt;
    };
    const Status s = BuildLodFile(m, LodBuildParams(), path, nullptr, stop);
    EXPECT_EQ(s.code, Status::Code::Cancelled) << stopAt;
    std::ifstream in(path);
    EXPECT_FALSE(in.good()) << "a cancelled build leaves no file (" << stopAt << ")";
  }
}

TEST(Lod, BuildLodFileReportsItsFigures) {
  IndexedMesh m = test::Sphere(3);  // 512 faces
  LodBuildParams p;
  LodBuildStats st;
  const std::string path = TempPath("stats.clod");
  ASSERT_TRUE(BuildLodFile(m, p, path, &st).ok());
  EXPECT_EQ(st.inputFaces, 512u);
  EXPECT_EQ(st.levelFaces[0], 512u);
  ASSERT_EQ(size_t(st.levels), st.levelFaces.size());
  for (size_t k = 1; k < st.levelFaces.size(); ++k) EXPECT_LE(st.levelFaces[k], st.levelFaces[k - 1]);
  EXPECT_EQ(st.levelNodes[0], st.levelNodes[1]);
  EXPECT_EQ(ReadBytes(path).size(), st.fileBytes);
  std::remove(path.c_str());
}

}  // namespace
}  // namespace conelod
