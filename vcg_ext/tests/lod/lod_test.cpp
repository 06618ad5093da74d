// Tests of lod_build.h and lod_read.h: the .clod file written, read back and refined. Tiny meshes built in code with
// exact expectations, then the bunny: the full-budget round trip gives the input back exactly,
// small budgets give fewer faces and finer levels where the eye looks, and every kind of bad file
// is refused with its message. Then the cracks: cuts of watertight meshes (a sphere, a torus, the
// armadillo) at many eyes, budgets and priorities, with and without culling, welded by position
// (not by the file's ids), have no border edge, no over-used edge and, culled nodes dropped,
// border edges only against culled nodes.
#include "conelod/lod/lod_build.h"
#include "conelod/lod/lod_read.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <set>
#include <unordered_map>

#include <dirent.h>
#include <sys/stat.h>
#include <unistd.h>

#include "conelod/grouping/cone_grouping.h"
#include "conelod/lod/lod_entropy.h"
#include "conelod/lod/lod_internal.h"
#include "conelod/lod/lod_spill.h"
#include "conelod/mesh/ply_format.h"
#include "conelod/mesh/sampled_distance.h"
#include "conelod/mesh/weld.h"
#include "conelod/mesh/sorted_faces.h"
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

// A mesh, its DAG, and its .clod file (path and bytes).
struct Built {
  IndexedMesh mesh;
  LodDag dag;
  LodBuildStats stats;
  std::string path;
  std::vector<uint8_t> bytes;
};

void Build(Built& b, const std::string& name, const LodBuildParams& p = LodBuildParams()) {
  const Status d = BuildLodDag(b.mesh, p, b.dag);
  ASSERT_TRUE(d.ok()) << d.message;
  b.path = TempPath(name + ".clod");
  const Status s = WriteLodFile(b.mesh, b.dag, b.path, &b.stats);
  ASSERT_TRUE(s.ok()) << s.message;
  b.bytes = ReadBytes(b.path);
  ASSERT_EQ(b.bytes.size(), b.stats.fileBytes);
}

// Edges of a mesh whose vertices are welded by identical position (bit for bit), with the number
// of faces using each.
using PosKey = std::array<float, 3>;
using EdgeKey = std::pair<PosKey, PosKey>;
struct EdgeKeyHash {
  size_t operator()(const EdgeKey& e) const {
    uint64_t h = 1469598103934665603ull;
    for (const PosKey* k : {&e.first, &e.second})
      for (float x : *k) {
        uint32_t u;
        std::memcpy(&u, &x, 4);
        h = (h ^ u) * 1099511628211ull;
      }
    return size_t(h ^ (h >> 29));
  }
};
using EdgeMap = std::unordered_map<EdgeKey, int, EdgeKeyHash>;
// Faces with two corners at one position (the grid can round a sliver's corners together) have
// no area: they neither open nor overlap anything and are left out.
EdgeMap EdgesByPosition(const IndexedMesh& m) {
  EdgeMap edges;
  edges.reserve(m.faces.size() * 2);
  for (const auto& t : m.faces) {
    const vcg::Point3f &p0 = m.positions[t[0]], &p1 = m.positions[t[1]], &p2 = m.positions[t[2]];
    if (p0 == p1 || p1 == p2 || p2 == p0) continue;
    for (int i = 0; i < 3; ++i) {
      const vcg::Point3f& a = m.positions[t[size_t(i)]];
      const vcg::Point3f& b = m.positions[t[size_t((i + 1) % 3)]];
      PosKey ka{{a[0], a[1], a[2]}}, kb{{b[0], b[1], b[2]}};
      if (kb < ka) std::swap(ka, kb);
      ++edges[{ka, kb}];
    }
  }
  return edges;
}

// The mesh with its positions rounded on a file's grid: what a full-budget cut must give back
// (ExtractCutMesh leaves out the faces that use a vertex twice).
IndexedMesh OnGrid(const IndexedMesh& m, const LodGrid& grid) {
  IndexedMesh q = m;
  for (auto& p : q.positions) p = grid.Round(p);
  q.faces.erase(std::remove_if(q.faces.begin(), q.faces.end(), UsesAVertexTwice), q.faces.end());
  return q;
}

// The faces of the cut's nodes (the culled ones too, or not) that use one vertex twice: no
// surface, left out by ExtractCutMesh.
size_t FlatFaces(LodReader& r, const LodCut& cut, bool includeCulled) {
  size_t flat = 0;
  for (size_t i = 0; i < cut.nodes.size(); ++i) {
    if (!includeCulled && cut.culled[i]) continue;
    EXPECT_TRUE(r.LoadGeometry(cut.nodes[i]).ok());
    const LodGeometry& g = *r.geometry(cut.nodes[i]);
    for (const auto& t : g.faces) flat += UsesAVertexTwice({g.vertexIds[t[0]], g.vertexIds[t[1]], g.vertexIds[t[2]]});
  }
  return flat;
}

struct CrackCount {
  size_t border = 0, overused = 0, drawnBorderNotCulled = 0;
};

// Checks a cut: no node twice, its face count, and its cracks: the mesh of the whole cut welded by
// position has `border` edges used by one face (a crack or a T-junction when the input has none)
// and `overused` edges used by 3+ faces (overlap); the drawn nodes alone have
// `drawnBorderNotCulled` border edges that no culled node of the cut has (a hole culling made
// visible; input borders excepted).
CrackCount CheckCut(const Built& b, LodReader& r, const LodCut& cut, const EdgeMap* inputEdges = nullptr) {
  std::vector<uint32_t> nodes = cut.nodes;
  std::sort(nodes.begin(), nodes.end());
  EXPECT_TRUE(std::adjacent_find(nodes.begin(), nodes.end()) == nodes.end()) << "a node twice in the cut";
  size_t faces = 0;
  for (uint32_t id : cut.nodes) faces += r.node(id).faceCount;
  EXPECT_EQ(faces, cut.faces);
  CrackCount c;
  IndexedMesh all, drawn;
  EXPECT_TRUE(ExtractCutMesh(r, cut, true, all).ok());
  EXPECT_TRUE(ExtractCutMesh(r, cut, false, drawn).ok());
  EXPECT_EQ(all.faces.size(), cut.faces - FlatFaces(r, cut, true));
  EXPECT_EQ(drawn.faces.size(), cut.drawnFaces - FlatFaces(r, cut, false));
  const EdgeMap input = inputEdges ? EdgeMap() : EdgesByPosition(OnGrid(b.mesh, r.info().grid));
  const EdgeMap& in = inputEdges ? *inputEdges : input;
  for (const auto& e : EdgesByPosition(all)) {
    const auto i = in.find(e.first);
    if (e.second == 1 && !(i != in.end() && i->second == 1)) ++c.border;
    if (e.second > 2 && !(i != in.end() && i->second > 2)) ++c.overused;  // the input's own excepted
  }
  LodCut culledOnly = cut;
  for (auto& f : culledOnly.culled) f = uint8_t(!f);
  IndexedMesh culled;
  EXPECT_TRUE(ExtractCutMesh(r, culledOnly, false, culled).ok());
  const auto culledEdges = EdgesByPosition(culled);
  for (const auto& e : EdgesByPosition(drawn))
    if (e.second == 1 && !culledEdges.count(e.first) && !(in.count(e.first) && in.at(e.first) == 1))
      ++c.drawnBorderNotCulled;
  return c;
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

// The chunks' checksum is zlib's CRC-32: the standard check value, and the same in pieces.
TEST(Checksum, IsTheStandardCrc32) {
  EXPECT_EQ(Crc32("123456789", 9), 0xCBF43926u);
  EXPECT_EQ(Crc32(nullptr, 0), 0u);
  EXPECT_EQ(Crc32("6789", 4, Crc32("12345", 5)), 0xCBF43926u);
}

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
    LodBuildParams p;
    p.clusterFaces = 16;
    Build(*tiny_, "sphere", p);
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
  const size_t H = b.dag.levels.size();
  ASSERT_GE(H, 3u) << "the tiny sphere should give a DAG of several levels";
  EXPECT_EQ(i.version, 9u);
  EXPECT_EQ(i.levels, int(H));
  EXPECT_EQ(i.inputFaces, 128u);
  EXPECT_EQ(i.inputVertices, 66u);
  {  // global ids: one per vertex some level uses
    std::vector<uint8_t> used(b.dag.positions.size(), 0);
    for (const auto& L : b.dag.levels)
      for (const auto& t : L.faces)
        for (uint32_t v : t) used[v] = 1;
    EXPECT_EQ(i.globalVertices, size_t(std::count(used.begin(), used.end(), 1)));
  }
  EXPECT_EQ(i.fileBytes, b.bytes.size());
  for (size_t k = 0; k < H; ++k) {
    EXPECT_EQ(i.levelNodes[k], b.dag.levels[k].clusterCount());
    EXPECT_EQ(i.levelFaces[k], b.dag.levels[k].faces.size());
    if (k) {
      EXPECT_LT(i.levelFaces[k], i.levelFaces[k - 1]);
    }
  }
  EXPECT_NEAR(i.box.min[0], -1, 1e-6);
  EXPECT_NEAR(i.box.max[2], 1, 1e-6);
  // Roots: the top level's nodes, ids 0..; records and geometry loaded at Open.
  ASSERT_EQ(r->roots().size(), i.levelNodes.back());
  for (size_t k = 0; k < r->roots().size(); ++k) {
    EXPECT_EQ(r->roots()[k], uint32_t(k));
    ASSERT_TRUE(r->hasNode(uint32_t(k)));
    EXPECT_EQ(r->node(uint32_t(k)).level, int(H) - 1);
    EXPECT_EQ(r->node(uint32_t(k)).group, LodNode::kNoGroup);
    EXPECT_TRUE(r->node(uint32_t(k)).parents.empty());
    EXPECT_TRUE(std::isinf(r->node(uint32_t(k)).parentError));
    EXPECT_NE(r->geometry(uint32_t(k)), nullptr);
  }
  // Nothing finer is loaded at Open.
  EXPECT_FALSE(r->hasNode(uint32_t(r->roots().size())));
  // Walk every node through the children lists: children at the level below, all in one group
  // whose error is the node's; siblings share children; errors grow up the DAG; the border of a
  // group (its children's vertices also used outside it) is kept by the clusters made from it.
  std::vector<uint32_t> todo = r->roots();
  std::vector<uint8_t> seen(size_t(i.nodeCount), 0);
  std::unordered_map<uint32_t, vcg::Point3f> positionOfId;  // the same in every node using it
  size_t count = 0;
  while (!todo.empty()) {
    const uint32_t id = todo.back();
    todo.pop_back();
    if (seen[id]) continue;
    seen[id] = 1;
    ++count;
    ASSERT_TRUE(r->LoadChildren(id).ok());
    const LodNode n = r->node(id);
    EXPECT_EQ(r->levelOfNode(id), uint32_t(n.level));
    EXPECT_LE(n.error, n.parentError);
    if (n.level == 0) {
      EXPECT_TRUE(n.children.empty());
      EXPECT_EQ(n.error, 0.f);
    } else {
      EXPECT_FALSE(n.children.empty());
      EXPECT_GT(n.error, 0.f);
    }
    for (uint32_t s : n.siblings) {
      ASSERT_TRUE(r->LoadNode(s).ok());
      EXPECT_EQ(r->node(s).children, n.children);
      EXPECT_EQ(r->node(s).error, n.error);
    }
    for (uint32_t c : n.children) {
      ASSERT_TRUE(r->hasNode(c));
      const LodNode& cn = r->node(c);
      EXPECT_EQ(cn.level, n.level - 1);
      EXPECT_EQ(cn.parentError, n.error);
      EXPECT_LE(cn.error, n.error);
      std::vector<uint32_t> p = cn.parents, sib = n.siblings;
      std::sort(p.begin(), p.end());
      std::sort(sib.begin(), sib.end());
      EXPECT_EQ(p, sib) << "a child's parents are the clusters made from its group";
      todo.push_back(c);
    }
    // Every face's normal lies in the node's cone (exact minimal cone of its own faces).
    ASSERT_TRUE(r->LoadGeometry(id).ok());
    const LodGeometry& g = *r->geometry(id);
    EXPECT_EQ(g.faces.size(), n.faceCount);
    EXPECT_EQ(g.positions.size(), n.vertexCount);
    for (size_t v = 0; v < g.vertexIds.size(); ++v) {
      EXPECT_LT(g.vertexIds[v], i.globalVertices);
      EXPECT_EQ(g.positions[v], i.grid.Round(g.positions[v])) << "a position off the grid";
      const auto ins = positionOfId.emplace(g.vertexIds[v], g.positions[v]);
      EXPECT_EQ(ins.first->second, g.positions[v]) << "vertex " << g.vertexIds[v] << " differs between nodes";
    }
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
  EXPECT_EQ(count, i.nodeCount);
  EXPECT_EQ(positionOfId.size(), i.globalVertices);
}

TEST_F(TinyLod, FullBudgetGivesTheInputBack) {
  const Built& b = *tiny_;
  auto r = OpenOk(b.bytes);
  ASSERT_TRUE(r);
  LodCut cut;
  ASSERT_TRUE(RefineLod(*r, Eye(0.3, 0.2, 5, 1000), cut).ok());
  EXPECT_EQ(cut.faces, 128u);
  for (uint32_t id : cut.nodes) EXPECT_EQ(r->node(id).level, 0);
  const CrackCount c = CheckCut(b, *r, cut);
  EXPECT_EQ(c.border, 0u);
  EXPECT_EQ(c.overused, 0u);
  IndexedMesh out;
  std::vector<int> level;
  ASSERT_TRUE(ExtractCutMesh(*r, cut, true, out, &level).ok());
  EXPECT_EQ(out.faces.size(), 128u);
  EXPECT_EQ(out.positions.size(), 66u);  // welded: the input's shared vertices
  EXPECT_EQ(SortedFacePositions(out), SortedFacePositions(OnGrid(b.mesh, r->info().grid)));
  EXPECT_TRUE(std::all_of(level.begin(), level.end(), [](int l) { return l == 0; }));
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
void PutU32(std::vector<uint8_t>& bytes, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) bytes[at + size_t(i)] = uint8_t(v >> (8 * i));
}
void PutF32(std::vector<uint8_t>& bytes, size_t at, float v) {
  uint32_t u;
  std::memcpy(&u, &v, 4);
  PutU32(bytes, at, u);
}
// The same for a record or a node's geometry (a blob: its CRC, then what it covers).
void RechecksumBlob(std::vector<uint8_t>& bytes, size_t at, size_t size) {
  PutU32(bytes, at, Crc32(bytes.data() + at + 4, size - 4));
}

// The version 6 index of a good file, parsed apart from the reader (lod_format.md): where each
// IBLK starts, and per node where its record and its geometry blob lie.
struct ParsedIndex {
  size_t indexAt = 0, startsAt = 0;  // the INDX chunk; its table of block starts (in its data)
  std::vector<size_t> blockAt;       // each IBLK chunk (absolute)
  struct Entry {
    size_t record, recordBytes, geometry, geometryBytes;
  };
  std::vector<Entry> entries;
};
ParsedIndex ParseIndex(const std::vector<uint8_t>& f) {
  ParsedIndex x;
  x.indexAt = size_t(Decoder(f.data() + kChunkHeaderBytes + 80, 8).u64());
  const size_t n = size_t(Decoder(f.data() + x.indexAt + kChunkHeaderBytes, 8).u64());
  const size_t blocks = (n + kIndexBlock - 1) / kIndexBlock;
  x.startsAt = x.indexAt + kChunkHeaderBytes + kIndexDataBytes;
  const size_t first = x.startsAt + kIndexBlockStartBytes * blocks;
  for (size_t b = 0; b < blocks; ++b) {
    x.blockAt.push_back(first + Decoder(f.data() + x.startsAt + 4 * b, 4).u32());
    const ChunkHeader h = DecodeChunkHeader(f.data() + x.blockAt.back());
    EXPECT_EQ(h.id, kIBlock);
    Decoder d(f.data() + x.blockAt.back() + kChunkHeaderBytes, size_t(h.dataBytes));
    size_t record = size_t(d.u64()), geometry = size_t(d.u64()), end = geometry;
    for (size_t i = b * kIndexBlock; i < std::min(n, (b + 1) * kIndexBlock); ++i) {
      const uint64_t code = d.uv();
      if (code & 1) {
        geometry = end;
        end += size_t(d.uv());
      }
      x.entries.push_back({record, size_t(code >> 1) + kRecordFixedBytes, geometry, end - geometry});
      record += x.entries.back().recordBytes;
    }
    EXPECT_EQ(d.left(), 0u);
    EXPECT_FALSE(d.overrun);
  }
  return x;
}

TEST_F(TinyLod, BadFilesAreRefusedWithTheirReason) {
  const std::vector<uint8_t>& good = tiny_->bytes;
  auto has = [](const std::string& msg, const std::string& what) { return msg.find(what) != std::string::npos; };
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
    std::vector<uint8_t> ply = {'p', 'l', 'y', '\n', 'f', 'o', 'r', 'm', 'a', 't', ' ', 'b', 'i',
                                'n', 'a', 'r', 'y',  '_', 'l', 'i', 't', 't', 'l', 'e', '_', 'e'};
    EXPECT_TRUE(has(OpenError(ply), "not a .clod file")) << OpenError(ply);
  }
  {  // wrong version (a valid checksum: a file from a future writer)
    std::vector<uint8_t> b = good;
    b[kChunkHeaderBytes] = 10;
    Rechecksum(b, 0);
    EXPECT_TRUE(has(OpenError(b), "unsupported .clod version 10")) << OpenError(b);
    // Files of the previous versions: named, with what to do.
    b[kChunkHeaderBytes] = 2;
    Rechecksum(b, 0);
    EXPECT_TRUE(has(OpenError(b), ".clod version 2 file (uncompressed")) << OpenError(b);
    EXPECT_TRUE(has(OpenError(b), "rebuild it with conelod lod build")) << OpenError(b);
    b[kChunkHeaderBytes] = 1;
    Rechecksum(b, 0);
    EXPECT_TRUE(has(OpenError(b), ".clod version 1 file (written by an older ConeLOD")) << OpenError(b);
    EXPECT_TRUE(has(OpenError(b), "rebuild it with conelod lod build")) << OpenError(b);
  }
  {  // decoded values checked even with valid checksums: a NaN bounding box
    std::vector<uint8_t> b = good;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    uint32_t u;
    std::memcpy(&u, &nan, 4);
    for (int k = 0; k < 4; ++k) b[kChunkHeaderBytes + 40 + size_t(k)] = uint8_t(u >> (8 * k));
    Rechecksum(b, 0);
    EXPECT_TRUE(has(OpenError(b), "bounding box")) << OpenError(b);
  }
  // Where node 0's record and the last node's geometry are (the index's first and last entries).
  const size_t hier = size_t(Decoder(good.data() + kChunkHeaderBytes + 64, 8).u64());
  const size_t index = size_t(Decoder(good.data() + kChunkHeaderBytes + 80, 8).u64());
  const size_t rec = hier + kChunkHeaderBytes;  // node 0's record
  const ParsedIndex parsed = ParseIndex(good);
  ASSERT_EQ(parsed.entries.size(), size_t(OpenOk(good)->info().nodeCount));
  ASSERT_EQ(parsed.entries[0].record, rec);
  const size_t recBytes = parsed.entries[0].recordBytes;
  {  // a root's record with a negative radius, then a negative error, then a typical distance over
     // its error or negative (version 9), then a group: checksum redone
    auto refused = [&](size_t at, float value, const char* message) {
      std::vector<uint8_t> b = good;
      PutF32(b, rec + at, value);
      RechecksumBlob(b, rec, recBytes);
      EXPECT_TRUE(has(OpenError(b), message)) << at << ": " << OpenError(b);
    };
    refused(4 + 6 + 12, -0.5f, "negative cone or sphere");
    refused(4 + 6 + 16, -1.f, "bad error bounds");
    refused(4 + 6 + 20, 2 * Decoder(good.data() + rec + 4 + 6 + 16, 4).f32() + 1.f, "bad error bounds");
    refused(4 + 6 + 20, -1.f, "bad error bounds");
    std::vector<uint8_t> b = good;
    ASSERT_EQ(b[rec + kRecordFixedBytes + 8], 0);  // a root's group (after its errors): none
    b[rec + kRecordFixedBytes + 8] = 1;
    RechecksumBlob(b, rec, recBytes);
    EXPECT_TRUE(has(OpenError(b), "a root with a group")) << OpenError(b);
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
  {  // corrupted chunk size: the records' container
    std::vector<uint8_t> b = good;
    PutU64(b, hier + 8, 1000000000);
    EXPECT_TRUE(has(OpenError(b), "corrupt chunk size in the hierarchy chunk")) << OpenError(b);
  }
  {  // corrupted checksum: one byte of the header's data, then one of a root's record
    std::vector<uint8_t> b = good;
    const ChunkHeader h0 = DecodeChunkHeader(good.data());
    b[kChunkHeaderBytes + 20] ^= 1;
    EXPECT_TRUE(has(OpenError(b), "checksum mismatch in the file header")) << OpenError(b);
    b = good;
    b[kChunkHeaderBytes + h0.dataBytes - 1] ^= 1;  // the last level entry's padding is covered too
    EXPECT_TRUE(has(OpenError(b), "checksum mismatch")) << OpenError(b);
    b = good;
    b[rec + 10] ^= 1;
    EXPECT_TRUE(has(OpenError(b), "checksum mismatch in the record of a node 0")) << OpenError(b);
    // The last bytes of the file are the last index block's entries: only read on demand.
    b = good;
    b[b.size() - 6] ^= 0x40;
    const std::string e = FullReadError(b);
    EXPECT_TRUE(has(e, "checksum mismatch in index block")) << e;
  }
  // The last node's geometry (level 0, read on demand) ends where the index chunk begins; its
  // blob is its unit's (its nodes' entries name the same blob).
  const size_t geomStart = parsed.entries.back().geometry;
  const size_t geomEnd = geomStart + parsed.entries.back().geometryBytes;
  ASSERT_EQ(geomEnd, index);
  {  // a node's geometry: its checksum is checked when it is read
    std::vector<uint8_t> b = good;
    b[(geomStart + geomEnd) / 2] ^= 0x10;
    EXPECT_EQ(OpenError(b), "");
    const std::string e = FullReadError(b);
    EXPECT_TRUE(has(e, "checksum mismatch in the geometry of a node")) << e;
  }
  {  // hostile geometry with a valid checksum: every byte of it changed in turn, the codecs' output
     // checked (a clean read or an error naming the node, never a crash: ASan runs this too)
    size_t refused = 0;
    for (size_t at = geomStart + 4; at < geomEnd; ++at) {
      std::vector<uint8_t> b = good;
      b[at] ^= 0xA5;
      RechecksumBlob(b, geomStart, geomEnd - geomStart);
      const std::string e = FullReadError(b);
      if (!e.empty()) {
        ++refused;
        EXPECT_TRUE(has(e, "corrupt geometry of node")) << e;
      }
    }
    EXPECT_GT(refused, (geomEnd - geomStart) / 4);
  }
  {  // offsets past the end: the index offset, the hierarchy offset (valid header checksum)
    std::vector<uint8_t> b = good;
    PutU64(b, kChunkHeaderBytes + 80, b.size() + 4096);  // index offset
    Rechecksum(b, 0);
    EXPECT_TRUE(has(OpenError(b), "past the end")) << OpenError(b);
    b = good;
    PutU64(b, kChunkHeaderBytes + 64, uint64_t(1) << 62);  // hierarchy offset
    Rechecksum(b, 0);
    EXPECT_TRUE(has(OpenError(b), "past the end")) << OpenError(b);
  }
  {  // a quantization grid of 0 bits, or a NaN step
    std::vector<uint8_t> b = good;
    PutU32(b, kChunkHeaderBytes + 120, 0);
    Rechecksum(b, 0);
    EXPECT_TRUE(has(OpenError(b), "bad quantization grid")) << OpenError(b);
    b = good;
    PutU64(b, kChunkHeaderBytes + 112, 0x7FF8000000000000ull);
    Rechecksum(b, 0);
    EXPECT_TRUE(has(OpenError(b), "bad quantization grid")) << OpenError(b);
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

// A version 3 file (written by the ConeLOD before version 4, from data/sphere512.ply) reads as the
// version 4 file of the same DAG: every record and the full-budget cut are the same. Both files
// are stored (sphere512_v4.clod: `conelod lod build sphere512.ply` of main at 2f4772b, whose
// collapse order in the LOD build was still the one the version 3 file was written with): the
// DAG a build makes today follows the collapse's order.
TEST(Lod, Version3FilesStillRead) {
  const std::string dir = std::string(CONELOD_SOURCE_DIR) + "/vcg_ext/tests/lod/data/";
  CMesh m;
  ASSERT_EQ(LoadPly(m, dir + "sphere512.ply"), "");
  const std::string path = dir + "sphere512_v4.clod";
  std::unique_ptr<LodReader> r3, r4;
  Status s = LodReader::Open(dir + "sphere512_v3.clod", r3);
  ASSERT_TRUE(s.ok()) << s.message;
  s = LodReader::Open(path, r4);
  ASSERT_TRUE(s.ok()) << s.message;
  EXPECT_EQ(r3->info().version, 3u);
  EXPECT_EQ(r4->info().version, 4u);
  ASSERT_EQ(r3->info().nodeCount, r4->info().nodeCount);
  EXPECT_LT(ReadBytes(path).size(), ReadBytes(dir + "sphere512_v3.clod").size());
  size_t inherited = 0;
  for (uint32_t id = 0; id < r4->info().nodeCount; ++id) {
    ASSERT_TRUE(r3->LoadNode(id).ok());
    s = r4->LoadNode(id);  // alone: a record that names its group's first reads that one too
    ASSERT_TRUE(s.ok()) << s.message;
    const LodNode &a = r3->node(id), &c = r4->node(id);
    EXPECT_EQ(a.level, c.level);
    EXPECT_EQ(a.group, c.group);
    EXPECT_EQ(a.children, c.children);
    EXPECT_EQ(a.siblings, c.siblings);
    EXPECT_EQ(a.parents, c.parents) << id;
    EXPECT_EQ(a.center, c.center);
    EXPECT_EQ(a.radius, c.radius);
    EXPECT_EQ(a.cone.axis, c.cone.axis);
    EXPECT_EQ(a.cone.halfAngle, c.cone.halfAngle);
    EXPECT_EQ(a.faceCount, c.faceCount);
    EXPECT_EQ(a.vertexCount, c.vertexCount);
    EXPECT_EQ(a.error, c.error);
    EXPECT_EQ(a.parentError, c.parentError) << id;
    if (id > 0 && c.group != LodNode::kNoGroup && r4->node(id - 1).group == c.group &&
        r4->levelOfNode(id - 1) == r4->levelOfNode(id))
      ++inherited;
  }
  EXPECT_GT(inherited, 0u);  // the file has records that take their group's parents
  {                          // a record naming a record that is not its group's first (its `back` + 1, the last byte)
    const std::vector<uint8_t> good = ReadBytes(path);
    const size_t index = size_t(Decoder(good.data() + kChunkHeaderBytes + 80, 8).u64());
    const size_t block0 = index + kChunkHeaderBytes + kIndexDataBytes + kChunkHeaderBytes;
    const uint64_t recordBase = Decoder(good.data() + block0, 8).u64();
    auto recordEnd = [&](uint32_t id) {
      return size_t(recordBase + Decoder(good.data() + block0 + kIndexBlockBaseBytes + 8 * id, 4).u32());
    };
    uint32_t id = 1;
    while (id < r4->info().nodeCount &&
           (r4->node(id).group == LodNode::kNoGroup || r4->node(id - 1).group != r4->node(id).group ||
            r4->levelOfNode(id - 1) != r4->levelOfNode(id)))
      ++id;
    ASSERT_LT(id, r4->info().nodeCount);
    ASSERT_LT(id, kIndexBlock);
    std::vector<uint8_t> b = good;
    const size_t end = recordEnd(id), begin = recordEnd(id - 1);
    ASSERT_GT(b[end - 1], 0);  // back: 1 byte here
    ASSERT_LT(b[end - 1], 127);
    ++b[end - 1];
    RechecksumBlob(b, begin, end - begin);
    std::unique_ptr<LodReader> r;
    s = LodReader::OpenMemory(b, r);
    ASSERT_TRUE(s.ok()) << s.message;
    s = r->LoadNode(id);
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.message.find("a bad group reference"), std::string::npos) << s.message;
  }
  for (LodReader* r : {r3.get(), r4.get()}) {
    LodView view;
    view.eye = vcg::Point3d(0, 0, 5);
    view.faceBudget = size_t(1) << 40;
    view.cullBackFacing = false;
    LodCut cut;
    ASSERT_TRUE(RefineLod(*r, view, cut).ok());
    IndexedMesh out;
    ASSERT_TRUE(ExtractCutMesh(*r, cut, true, out).ok());
    EXPECT_EQ(SortedFacePositions(out), SortedFacePositions(OnGrid(ToIndexedMesh(m), r->info().grid)));
  }
}

// Version 9 (a typical distance per record) reads as the version 4 to 8 files of the same DAG: every
// record, every node's geometry and attributes, the header's figures. They are stored: written by
// main at 0d3679e (before version 6) with `conelod lod build` of data/sphere512.ply
// (sphere512_v4b.clod) and of data/sphere512_color.ply, the same sphere with a colour and a normal
// per vertex (sphere512_color_v5.clod), by main at 66bfa1b (version 6, before version 7:
// sphere512_v6.clod, sphere512_color_v6.clod) and by main at 432a962 (version 7, before version
// 8: sphere512_v7.clod, sphere512_color_v7.clod, `--precision 2e-5`) and by main at cde0507
// (version 8, before version 9: sphere512_v8.clod, sphere512_color_v8.clod, built with the
// parameters below), all at 2e-5; version 9 is built here the same way.
TEST(Lod, Version4And5FilesStillRead) {
  const std::string dir = std::string(CONELOD_SOURCE_DIR) + "/vcg_ext/tests/lod/data/";
  for (const std::string file :
       {"sphere512_v4b.clod", "sphere512_v6.clod", "sphere512_v7.clod", "sphere512_v8.clod", "sphere512_color_v5.clod",
        "sphere512_color_v6.clod", "sphere512_color_v7.clod", "sphere512_color_v8.clod"}) {
    SCOPED_TRACE(file);
    const std::string name = file.substr(0, file.rfind("_v"));
    const uint32_t oldVersion = uint32_t(file[file.rfind("_v") + 2] - '0');
    const std::string old = dir + file;
    PlyMesh ply;
    ASSERT_EQ(ReadPly(dir + name + ".ply", ply), "");
    IndexedMesh im;
    LodAttributes at;
    for (const auto& c : ply.colors) {
      std::array<uint8_t, 4> q;
      for (size_t i = 0; i < 4; ++i) q[i] = uint8_t(std::lround(std::min(1.f, std::max(0.f, c[i])) * 255.f));
      at.colors.push_back(q);
    }
    for (const auto& n : ply.normals) at.normals.push_back(EncodeLodNormal(vcg::Point3f(n[0], n[1], n[2])));
    for (const auto& p : ply.positions) im.positions.emplace_back(p[0], p[1], p[2]);
    im.faces = ply.triangles;
    const std::string path = TempPath(name + "_v9.clod");
    LodBuildParams params;
    params.precision = 2e-5;
    // The stored files' DAG: level ratio 0.5 and groups of 12 clusters at every level (main at
    // 432a962, before coarseLevelRatio, fineGroupClusters and topGroupClusters were set).
    params.coarseLevelRatio = 0;
    params.fineGroupClusters = 0;
    params.topGroupClusters = 0;
    params.refreshRatio = 0;  // (the default today) no memoryless steps in the groups
    ASSERT_TRUE(BuildLodFile(im, params, path, nullptr, Progress(), at.empty() ? nullptr : &at).ok());
    std::unique_ptr<LodReader> ro, rn;
    Status s = LodReader::Open(old, ro);
    ASSERT_TRUE(s.ok()) << s.message;
    s = LodReader::Open(path, rn);
    ASSERT_TRUE(s.ok()) << s.message;
    const LodFileInfo &io = ro->info(), &in = rn->info();
    EXPECT_EQ(io.version, oldVersion);
    EXPECT_EQ(oldVersion, oldVersion >= 6 ? oldVersion : at.empty() ? 4u : 5u);
    EXPECT_EQ(in.version, 9u);
    EXPECT_EQ(io.colors, in.colors);
    EXPECT_EQ(io.normals, in.normals);
    EXPECT_EQ(in.colors, !at.colors.empty());
    ASSERT_EQ(io.nodeCount, in.nodeCount);
    EXPECT_EQ(io.levelFaces, in.levelFaces);
    EXPECT_EQ(io.globalVertices, in.globalVertices);
    EXPECT_EQ(io.grid.step, in.grid.step);
    // Version 6: the same bytes but for the header (version, attributes field) and the index, 8
    // bytes a node smaller than version 4 or 5; version 7: the deflated streams smaller again;
    // version 8: the coded positions smaller again; version 9: 4 bytes more a node above level 0
    // (its typical distance), the rest the same bytes.
    const size_t oldBytes = ReadBytes(old).size(), newBytes = ReadBytes(path).size();
    const size_t typicalBytes = 4 * (in.nodeCount - in.levelNodes[0]);
    if (oldVersion == 8)
      EXPECT_EQ(newBytes, oldBytes + typicalBytes);
    else
      EXPECT_LT(newBytes + (oldVersion >= 6 ? 0 : 5 * io.nodeCount), oldBytes + typicalBytes);
    size_t positiveTypical = 0;
    for (uint32_t id = 0; id < in.nodeCount; ++id) {
      ASSERT_TRUE(ro->LoadNode(id).ok());
      s = rn->LoadNode(id);
      ASSERT_TRUE(s.ok()) << s.message;
      const LodNode &a = ro->node(id), &c = rn->node(id);
      EXPECT_EQ(a.children, c.children);
      EXPECT_EQ(a.siblings, c.siblings);
      EXPECT_EQ(a.parents, c.parents) << id;
      EXPECT_EQ(a.center, c.center);
      EXPECT_EQ(a.radius, c.radius);
      EXPECT_EQ(a.cone.axis, c.cone.axis);
      EXPECT_EQ(a.error, c.error);
      EXPECT_EQ(a.parentError, c.parentError) << id;
      EXPECT_EQ(a.typical, -1.f);  // not in the older files
      EXPECT_GE(c.typical, 0.f);
      EXPECT_LE(c.typical, c.error);
      positiveTypical += c.typical > 0;
      ASSERT_TRUE(ro->LoadGeometry(id).ok());
      s = rn->LoadGeometry(id);
      ASSERT_TRUE(s.ok()) << s.message;
      EXPECT_EQ(ro->geometry(id)->vertexIds, rn->geometry(id)->vertexIds) << id;
      EXPECT_EQ(ro->geometry(id)->positions, rn->geometry(id)->positions) << id;
      EXPECT_EQ(ro->geometry(id)->faces, rn->geometry(id)->faces) << id;
      if (!at.empty()) {
        ASSERT_TRUE(ro->attributes(id) && rn->attributes(id));
        EXPECT_EQ(ro->attributes(id)->colors, rn->attributes(id)->colors) << id;
        EXPECT_EQ(ro->attributes(id)->normals, rn->attributes(id)->normals) << id;
      }
    }
    EXPECT_GT(positiveTypical, in.levelNodes[1]);  // at least the simplified groups' above level 1
    std::remove(path.c_str());
  }
}

// Version 6 positions are residuals of predictions made along the faces (lod_internal.h's
// PositionPredictor): the full-budget cut gives back the input on the grid exactly, on a grid of
// u16 units and on one fine enough that the coarse units are u32 ("wide"), and the predicted
// positions take fewer bytes than the stored ones did (the version 4 file of the same sphere).
TEST(Lod, PredictedPositionsRoundTripNarrowAndWide) {
  const IndexedMesh m = test::Sphere(5);
  LodBuildParams p;
  size_t wideUnits = 0;
  for (double precision : {2e-5, 1e-7}) {
    SCOPED_TRACE(precision);
    p.precision = precision;
    const std::string path = TempPath("sphere_predicted.clod");
    LodBuildStats st;
    ASSERT_TRUE(BuildLodFile(m, p, path, &st).ok());
    std::unique_ptr<LodReader> r;
    ASSERT_TRUE(LodReader::Open(path, r).ok());
    LodCut cut;
    ASSERT_TRUE(RefineLod(*r, Eye(0, 0, 5, size_t(1) << 30, false), cut).ok());
    IndexedMesh out;
    ASSERT_TRUE(ExtractCutMesh(*r, cut, true, out).ok());
    EXPECT_EQ(SortedFacePositions(out), SortedFacePositions(OnGrid(m, r->info().grid)));
    // The geometry blobs' flags (each blob: CRC, flags, ...; the index gives where they start).
    const std::vector<uint8_t> f = ReadBytes(path);
    const ParsedIndex x = ParseIndex(f);
    std::set<size_t> blobs;
    for (const auto& e : x.entries) blobs.insert(e.geometry);
    for (size_t at : blobs) wideUnits += f[at + 4] & kGeomWidePositions;
    std::remove(path.c_str());
  }
  EXPECT_GT(wideUnits, 0u);
  // Against the stored sphere512_v4b.clod (the same input, stored positions): fewer bytes.
  const std::string dir = std::string(CONELOD_SOURCE_DIR) + "/vcg_ext/tests/lod/data/";
  PlyMesh ply;
  ASSERT_EQ(ReadPly(dir + "sphere512.ply", ply), "");
  IndexedMesh im;
  for (const auto& q : ply.positions) im.positions.emplace_back(q[0], q[1], q[2]);
  im.faces = ply.triangles;
  LodBuildStats st;
  const std::string path = TempPath("sphere512_predicted.clod");
  LodBuildParams p4;
  p4.precision = 2e-5;  // the version 4 file's
  ASSERT_TRUE(BuildLodFile(im, p4, path, &st).ok());
  std::remove(path.c_str());
  EXPECT_LT(st.positionBytes, 4490u);  // the version 4 file's positions (conelod lod build at 0d3679e)
}

// A geometry blob's streams (lod_format.md, "Geometry"; version 7): where each stream's code
// lies, whether it is deflated, where its face counts lie.
struct ParsedBlob {
  std::vector<size_t> faceCountAt;  // each node's face count (a varint)
  struct Stream {
    size_t codeAt, rawAt, dataAt, bytes;  // rawAt: the rawBytes varint (deflated only, else 0)
    bool deflated;
  };
  std::vector<Stream> streams;  // positions, triangles, then (when some vertex is not new) ids
};
ParsedBlob ParseBlob(const std::vector<uint8_t>& f, size_t at, size_t bytes) {
  ParsedBlob x;
  Decoder d(f.data() + at, bytes);
  d.u32();
  const uint8_t flags = uint8_t(d.take(1)[0]);
  EXPECT_EQ(flags & ~kGeomWidePositions, 0);  // geometry only
  d.uv();
  const uint64_t count = d.uv();
  for (uint64_t i = 0; i < count; ++i) {
    x.faceCountAt.push_back(at + d.at());
    d.uv();
  }
  const size_t vc = size_t(d.uv());
  for (int i = 0; i < 4; ++i) d.uv();
  auto stream = [&]() {
    ParsedBlob::Stream st{at + d.at(), 0, 0, 0, false};
    const uint64_t code = d.uv();
    st.deflated = code & 1;
    if (st.deflated) {
      st.rawAt = at + d.at();
      d.uv();
    }
    st.dataAt = at + d.at();
    st.bytes = size_t(code >> 1);
    d.take(st.bytes);
    x.streams.push_back(st);
  };
  stream();
  stream();
  const uint8_t* mask = d.take((vc + 7) / 8);
  size_t fresh = 0;
  for (size_t v = 0; v < vc; ++v) fresh += (mask[v / 8] >> (v % 8)) & 1;
  if (fresh < vc) stream();
  EXPECT_EQ(d.left(), 0u);
  EXPECT_FALSE(d.overrun);
  return x;
}

// Version 8's position coder (lod_entropy.h): residuals of every size, both widths, every kind,
// read back exactly; the stream truncated, with a byte more, or not starting with 0 is refused
// (ok() false), and random bytes never make the decoder read past its stream (ASan builds) nor
// give a bit length above the width without saying so.
TEST(Lod, PositionResidualCoderRoundTripsAndRefusesBadStreams) {
  uint64_t seed = 42;
  auto next = [&]() {
    seed = seed * 6364136223846793005ull + 1442695040888963407ull;
    return seed >> 11;
  };
  for (int width : {2, 4}) {
    SCOPED_TRACE(width);
    const uint64_t mask = (uint64_t(1) << (8 * width)) - 1;
    const size_t vertices = 3000;
    std::vector<uint64_t> r(vertices * 3);
    std::vector<uint8_t> kinds(vertices);
    for (size_t v = 0; v < vertices; ++v) {
      kinds[v] = uint8_t(v < 10 ? v % 4 : next() % 8 == 0 ? next() % 4 : 0);
      for (int c = 0; c < 3; ++c) {
        const int bits = v < 40 ? int(v % 20) * width * 8 / 20 : int(next() % 9);  // extremes first
        const int64_t x = bits ? int64_t(next() % (uint64_t(1) << bits)) - (int64_t(1) << (bits - 1)) : 0;
        r[3 * v + size_t(c)] = uint64_t(x) & mask;
      }
    }
    r[0] = mask;                                  // -1
    r[1] = uint64_t(1) << (8 * width - 1);        // the most negative
    r[2] = (uint64_t(1) << (8 * width - 1)) - 1;  // the most positive
    std::vector<uint8_t> bytes;
    std::vector<uint32_t> scratch;
    PositionResidualModel model;
    {
      RangeEncoder rc(bytes);
      const uint32_t m = PositionResidualModel::TypicalLength(r.data(), kinds.data(), vertices, width, scratch);
      EXPECT_GE(m, 2u);  // the median length of residuals of 0 to 8 bits, evenly
      EXPECT_LE(m, 5u);
      rc.Raw(m, 6);
      model.Reset(m, width);
      for (size_t v = 0; v < vertices; ++v) model.Encode(rc, kinds[v], &r[3 * v], width);
      rc.Finish();
    }
    EXPECT_LE(bytes.size(), PositionStreamBound(vertices));
    std::printf("width %d: %zu residuals of 0 to 9 bits (and extremes) in %.2f bits each\n", width, r.size(),
                8.0 * double(bytes.size()) / double(r.size()));
    auto decode = [&](const std::vector<uint8_t>& b, std::vector<uint64_t>& out) {
      RangeDecoder rc(b.data(), b.size());
      const uint32_t m = rc.Raw(6);
      model.Reset(m, width);
      bool fine = m <= uint32_t(8 * width);
      out.assign(vertices * 3, 0);
      for (size_t v = 0; v < vertices; ++v) fine = model.Decode(rc, kinds[v], &out[3 * v], width) && fine;
      return fine && rc.ok();
    };
    std::vector<uint64_t> back;
    ASSERT_TRUE(decode(bytes, back));
    EXPECT_EQ(back, r);
    std::vector<uint8_t> bad(bytes.begin(), bytes.end() - 1);
    EXPECT_FALSE(decode(bad, back));  // truncated
    bad = bytes;
    bad.push_back(0);
    EXPECT_FALSE(decode(bad, back));  // a byte more
    bad = bytes;
    bad[0] = 1;
    EXPECT_FALSE(decode(bad, back));  // not its first byte
    size_t refused = 0;
    for (int k = 0; k < 200; ++k) {  // random bytes: ends, decoded or refused
      bad.resize(size_t(next() % 64));
      for (auto& x : bad) x = uint8_t(next());
      if (!bad.empty()) bad[0] = 0;
      refused += !decode(bad, back);
      for (uint64_t x : back) ASSERT_LE(x, mask);
    }
    EXPECT_EQ(refused, 200u);
  }
}

// Version 7's deflated streams: the sphere's file has some (and some left as they are), reads
// back exactly (the round trip on the grid), and a deflated stream whose sizes lie (each with a
// valid CRC) is refused by name: rawBytes one off, the deflated flag cleared, a face count past
// what the triangles' codec bytes can hold.
TEST(Lod, DeflatedStreamsAreReadAndChecked) {
  const IndexedMesh m = test::Sphere(5);
  const std::string path = TempPath("sphere_deflated.clod");
  LodBuildStats st;
  ASSERT_TRUE(BuildLodFile(m, LodBuildParams(), path, &st).ok());
  const std::vector<uint8_t> f = ReadBytes(path);
  std::remove(path.c_str());
  ASSERT_EQ(FullReadError(f), "");
  {
    std::unique_ptr<LodReader> r = OpenOk(f);
    LodCut cut;
    ASSERT_TRUE(RefineLod(*r, Eye(0, 0, 5, size_t(1) << 30, false), cut).ok());
    IndexedMesh out;
    ASSERT_TRUE(ExtractCutMesh(*r, cut, true, out).ok());
    EXPECT_EQ(SortedFacePositions(out), SortedFacePositions(OnGrid(m, r->info().grid)));
  }
  const ParsedIndex x = ParseIndex(f);
  size_t deflated[3] = {0, 0, 0}, streams[3] = {0, 0, 0}, node = 0;
  std::map<size_t, size_t> blobNode;  // blob -> its first node
  for (size_t i = 0; i < x.entries.size(); ++i) blobNode.emplace(x.entries[i].geometry, i);
  for (const auto& b : blobNode) {
    const ParsedBlob pb = ParseBlob(f, b.first, x.entries[b.second].geometryBytes);
    for (size_t k = 0; k < pb.streams.size(); ++k) {
      deflated[k] += pb.streams[k].deflated;
      ++streams[k];
    }
    if (pb.streams[1].deflated && (f[pb.faceCountAt[0]] & 0x80))
      node = b.second;  // the last such (level 0): triangles deflated, a face count of 2 bytes
  }
  std::printf("sphere (8192 faces): %zu units; deflated positions %zu, triangles %zu, ids %zu of %zu, %zu, %zu\n",
              blobNode.size(), deflated[0], deflated[1], deflated[2], streams[0], streams[1], streams[2]);
  EXPECT_EQ(deflated[0], 0u);  // version 8: range-coded positions, stored as they are
  EXPECT_GT(deflated[1], streams[1] / 2);
  ASSERT_GT(node, 0u);
  const size_t at = x.entries[node].geometry, bytes = x.entries[node].geometryBytes;
  const ParsedBlob pb = ParseBlob(f, at, bytes);
  auto geometryError = [&](const std::vector<uint8_t>& b) {
    std::unique_ptr<LodReader> r = OpenOk(b);
    Status s = r->LoadNode(uint32_t(node));
    if (s.ok()) s = r->LoadGeometry(uint32_t(node));
    return s.message;
  };
  for (size_t k = 1; k < 2; ++k) {  // the triangles (version 8's positions are not deflated)
    const char* what = "its triangles do not decode";
    {  // rawBytes one off (its varint's lowest digit changed: the same length)
      std::vector<uint8_t> b = f;
      uint8_t& low = b[pb.streams[k].rawAt];
      low = uint8_t((low & 0x7F) ? low - 1 : low + 1);
      RechecksumBlob(b, at, bytes);
      EXPECT_NE(geometryError(b).find(what), std::string::npos) << geometryError(b);
      b = f;
      uint8_t& low2 = b[pb.streams[k].rawAt];
      low2 = uint8_t((low2 & 0x7F) < 0x7F ? low2 + 1 : low2 - 1);
      RechecksumBlob(b, at, bytes);
      EXPECT_NE(geometryError(b), "");
    }
    {  // the deflated flag cleared: the same bytes read as they are
      std::vector<uint8_t> b = f;
      b[pb.streams[k].codeAt] ^= 1;
      RechecksumBlob(b, at, bytes);
      EXPECT_NE(geometryError(b), "");
    }
  }
  {  // a face count far past the triangles' codec bytes, within the blob's bound
    std::vector<uint8_t> b = f;
    const size_t c = pb.faceCountAt[0];
    ASSERT_FALSE(b[c + 1] & 0x80);  // two bytes: set the second digit to its largest
    b[c + 1] = 0x7F;
    RechecksumBlob(b, at, bytes);
    const std::string e = geometryError(b);
    EXPECT_NE(e.find("more faces than its triangles can hold"), std::string::npos) << e;
  }
}

// The compact index (version 6): a few bytes a node, random access by block, and hostile entries
// (each with a valid CRC) refused by name; a file of several blocks (the bunny's nodes) reads
// every node through each block.
TEST(Lod, CompactIndexIsSmallAndChecked) {
  Built b;
  CMesh m;
  ASSERT_EQ(LoadPly(m, test::MeshPath("stanford_bunny_bun_zipper.ply")), "");
  b.mesh = ToIndexedMesh(m);
  LodBuildParams p;
  p.clusterFaces = 32;  // more nodes: several index blocks
  // The corruptions below are tuned to this file's bytes (what a shifted block start lands on):
  // the DAG of level ratio 0.5 and groups of 12 clusters at every level.
  p.coarseLevelRatio = 0;
  p.fineGroupClusters = 0;
  p.topGroupClusters = 0;
  Build(b, "bunny_index", p);
  const std::vector<uint8_t>& good = b.bytes;
  const ParsedIndex x = ParseIndex(good);
  const size_t n = x.entries.size();
  ASSERT_GE(x.blockAt.size(), 3u);
  const size_t indexBytes = good.size() - x.indexAt;
  std::printf("bunny, 32-face clusters: %zu nodes, index %zu bytes (%.2f a node; versions 3-5: %zu)\n", n, indexBytes,
              double(indexBytes) / double(n),
              kChunkHeaderBytes + kIndexDataBytes + x.blockAt.size() * (kChunkHeaderBytes + kIndexBlockBaseBytes) +
                  n * kIndexEntryBytes);
  EXPECT_LT(indexBytes, n * 2);  // versions 3 to 5: 8 bytes a node and more
  {                              // every node's entry as the parse finds it: the blobs the reader reads are those
    auto r = OpenOk(good);
    ASSERT_TRUE(r);
    for (uint32_t id = 0; id < n; id += 7) {  // blocks out of order, each cached in turn
      const uint32_t j = uint32_t((uint64_t(id) * 2654435761u) % n);
      Status s = r->LoadNode(j);
      ASSERT_TRUE(s.ok()) << s.message;
      s = r->LoadGeometry(j);
      ASSERT_TRUE(s.ok()) << s.message;
    }
    EXPECT_EQ(FullReadError(good), "");
  }
  auto has = [](const std::string& msg, const std::string& what) { return msg.find(what) != std::string::npos; };
  const size_t last = x.blockAt.size() - 1;
  {  // a block's start moved (INDX data, its CRC redone): out of the index, refused at Open;
     // a byte further, refused when the block is read
    std::vector<uint8_t> bad = good;
    PutU32(bad, x.startsAt + 4 * last, 0x7FFFFFFFu);
    Rechecksum(bad, x.indexAt);
    EXPECT_TRUE(has(OpenError(bad), "bad start of index block " + std::to_string(last))) << OpenError(bad);
    bad = good;
    PutU32(bad, x.startsAt + 4 * last, uint32_t(x.blockAt[last] - x.blockAt[0]) + 1);
    Rechecksum(bad, x.indexAt);
    EXPECT_EQ(OpenError(bad), "");
    const std::string e = FullReadError(bad);
    EXPECT_TRUE(has(e, "(index block), found")) << e;
    bad = good;
    PutU32(bad, x.startsAt, 1);
    Rechecksum(bad, x.indexAt);
    EXPECT_TRUE(has(OpenError(bad), "bad start of index block 0")) << OpenError(bad);
  }
  // An IBLK's entries, rewritten (its CRC redone): the last block's first entry.
  const size_t blockData = x.blockAt[last] + kChunkHeaderBytes;
  const size_t e0 = blockData + kIndexBlockBaseBytes;
  auto rewritten = [&](const std::vector<uint8_t>& entries0, size_t replaced) {
    std::vector<uint8_t> bad = good;
    bad.erase(bad.begin() + long(e0), bad.begin() + long(e0 + replaced));
    bad.insert(bad.begin() + long(e0), entries0.begin(), entries0.end());
    return bad;
  };
  {  // the first entry without a blob of its own, a record or a blob past the end of its
     // container, a byte left over: the chunks' sizes and the CRC made consistent each time
    ASSERT_EQ(good[e0] & 1, 1);
    std::vector<uint8_t> bad = good;
    bad[e0] ^= 1;
    Rechecksum(bad, x.blockAt[last]);
    std::string e = FullReadError(bad);
    EXPECT_TRUE(has(e, "corrupt index block " + std::to_string(last) + ": its first entry has no geometry")) << e;
    // A record past the records' end: the first entry's record size huge (a 9-byte varint).
    const std::vector<uint8_t> huge = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x01};
    size_t firstLen = 1;
    while (good[e0 + firstLen - 1] & 0x80) ++firstLen;
    bad = rewritten(huge, firstLen);
    // The block grew by huge.size() - firstLen bytes: its chunk size and the root's.
    const uint64_t grow = huge.size() - firstLen;
    PutU64(bad, x.blockAt[last] + 8, DecodeChunkHeader(good.data() + x.blockAt[last]).dataBytes + grow);
    PutU64(bad, x.indexAt + 16, DecodeChunkHeader(good.data() + x.indexAt).childBytes + grow);
    PutU64(bad, 16, DecodeChunkHeader(good.data()).childBytes + grow);
    Rechecksum(bad, x.blockAt[last]);
    e = FullReadError(bad);
    EXPECT_TRUE(has(e, "corrupt index block " + std::to_string(last) + ": an entry points outside")) << e;
    // A trailing byte in the block.
    bad = good;
    bad.insert(bad.end(), uint8_t(0));
    PutU64(bad, x.blockAt[last] + 8, DecodeChunkHeader(good.data() + x.blockAt[last]).dataBytes + 1);
    PutU64(bad, x.indexAt + 16, DecodeChunkHeader(good.data() + x.indexAt).childBytes + 1);
    PutU64(bad, 16, DecodeChunkHeader(good.data()).childBytes + 1);
    Rechecksum(bad, x.blockAt[last]);
    e = FullReadError(bad);
    EXPECT_TRUE(has(e, "corrupt index block " + std::to_string(last) + ": it does not end with its last entry")) << e;
    // A geometry size past the geometry's end.
    bad = good;
    const size_t at = e0 + firstLen;  // the first entry's blob size (a varint)
    size_t len = 1;
    while (good[at + len - 1] & 0x80) ++len;
    const std::vector<uint8_t> big = {0xFF, 0xFF, 0xFF, 0xFF, 0x0F};
    bad.erase(bad.begin() + long(at), bad.begin() + long(at + len));
    bad.insert(bad.begin() + long(at), big.begin(), big.end());
    const int64_t g = int64_t(big.size()) - int64_t(len);
    PutU64(bad, x.blockAt[last] + 8, uint64_t(int64_t(DecodeChunkHeader(good.data() + x.blockAt[last]).dataBytes) + g));
    PutU64(bad, x.indexAt + 16, uint64_t(int64_t(DecodeChunkHeader(good.data() + x.indexAt).childBytes) + g));
    PutU64(bad, 16, uint64_t(int64_t(DecodeChunkHeader(good.data()).childBytes) + g));
    Rechecksum(bad, x.blockAt[last]);
    e = FullReadError(bad);
    EXPECT_TRUE(has(e, "corrupt index block " + std::to_string(last) + ": an entry points outside")) << e;
  }
  {  // every byte of the index changed in turn (CRC redone): a clean read or a refusal, no crash
    size_t refused = 0, tried = 0;
    const size_t stride = std::max<size_t>(1, (good.size() - x.indexAt) / 400);
    for (size_t at = x.indexAt + kChunkHeaderBytes; at < good.size(); at += stride) {
      std::vector<uint8_t> bad = good;
      bad[at] ^= 0x21;
      size_t chunk = x.indexAt;
      for (size_t b = 0; b < x.blockAt.size(); ++b)
        if (at >= x.blockAt[b]) chunk = x.blockAt[b];
      if (at >= chunk + kChunkHeaderBytes) Rechecksum(bad, chunk);
      refused += !FullReadError(bad).empty();
      ++tried;
    }
    EXPECT_GT(refused, tried / 2) << "of " << tried;
  }
  std::remove(b.path.c_str());
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
  // The cut of `fraction` of the bunny's faces by the error in model units (far eye, no culling):
  // its RMS distance to the input ÷ our static collapse's at the cut's face count (the larger
  // direction, 100,000 samples).
  static double CutAgainstStatic(double fraction);
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
  EXPECT_EQ(cut.maxLevelDifference, 0);
  const CrackCount c = CheckCut(*bunny_, *r, cut);
  EXPECT_EQ(c.border, 0u);
  IndexedMesh out;
  ASSERT_TRUE(ExtractCutMesh(*r, cut, true, out).ok());
  EXPECT_EQ(out.faces.size(), 69451u);
  EXPECT_EQ(SortedFacePositions(out), SortedFacePositions(OnGrid(bunny_->mesh, r->info().grid)));
  // Welded: the input's used vertices (the bunny has unreferenced ones).
  std::vector<uint8_t> used(bunny_->mesh.positions.size(), 0);
  for (const auto& t : bunny_->mesh.faces)
    for (uint32_t v : t) used[v] = 1;
  EXPECT_EQ(out.positions.size(), size_t(std::count(used.begin(), used.end(), 1)));
}

// Positions are quantized on one grid: no vertex of any level moves by more than the stated bound,
// itself within the precision asked for; a coarser precision gives a smaller file; a precision out
// of range is refused.
TEST_F(BunnyLod, QuantizationStaysWithinItsBound) {
  auto r = Open();
  ASSERT_TRUE(r);
  const LodFileInfo& info = r->info();
  vcg::Box3f span;
  for (const auto& L : bunny_->dag.levels)
    for (const auto& t : L.faces)
      for (uint32_t v : t) span.Add(bunny_->dag.positions[v]);
  EXPECT_LE(info.quantizationError, kDefaultLodPrecision * span.Diag() * (1 + 1e-9));
  EXPECT_GT(info.quantizationError, 0.0);
  double worst = 0;
  for (const auto& L : bunny_->dag.levels)
    for (const auto& t : L.faces)
      for (uint32_t v : t) {
        const vcg::Point3f& p = bunny_->dag.positions[v];
        worst = std::max(worst, double((info.grid.Round(p) - p).Norm()));
      }
  EXPECT_LE(worst, info.quantizationError);
  EXPECT_GT(worst, info.quantizationError / 4) << "the bound should not be loose";
  // The file's positions are those rounded ones: level 0 (the round trip test) and every level
  // (HeaderAndNodeStructure) lie on the grid. A coarser grid: a smaller file, a larger bound.
  const std::string coarse = TempPath("bunny_coarse.clod");
  LodBuildStats st;
  ASSERT_TRUE(WriteLodFile(bunny_->mesh, bunny_->dag, coarse, &st, Progress(), 1e-3).ok());
  EXPECT_LT(st.fileBytes, bunny_->stats.fileBytes * 9 / 10);
  EXPECT_NEAR(st.quantizationError, 1e-3 * span.Diag(), 0.05e-3 * span.Diag());
  std::remove(coarse.c_str());
  for (double bad : {0.0, 0.5, -1.0, std::numeric_limits<double>::quiet_NaN()}) {
    const Status s = WriteLodFile(bunny_->mesh, bunny_->dag, coarse, &st, Progress(), bad);
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.message.find("precision"), std::string::npos) << s.message;
    EXPECT_NE(access(coarse.c_str(), F_OK), 0) << "no file is left";
  }
}

// The writer encodes the nodes on several threads, a window of units (at least 65,536 faces) at a
// time, and writes them in file order: the bunny's file (its level 0 in two windows at 1 and 3
// threads, in one at 5) is the same byte for byte at every thread count.
TEST_F(BunnyLod, FileDoesNotDependOnWriterThreads) {
  ASSERT_GT(bunny_->dag.levels[0].faces.size(), size_t(1) << 16);
  const std::string path = TempPath("bunny_threads.clod");
  for (int threads : {1, 3, 5}) {
    SCOPED_TRACE("threads " + std::to_string(threads));
    LodBuildStats st;
    const Status s = WriteLodFile(bunny_->mesh, bunny_->dag, path, &st, Progress(), kDefaultLodPrecision, threads);
    ASSERT_TRUE(s.ok()) << s.message;
    EXPECT_TRUE(ReadBytes(path) == bunny_->bytes);
    EXPECT_EQ(st.positionBytes, bunny_->stats.positionBytes);
    EXPECT_EQ(st.triangleBytes, bunny_->stats.triangleBytes);
    EXPECT_EQ(st.vertexIdBytes, bunny_->stats.vertexIdBytes);
  }
  std::remove(path.c_str());
}

TEST_F(BunnyLod, SmallBudgetsRefineWhereTheEyeLooks) {
  auto r = Open();
  ASSERT_TRUE(r);
  const vcg::Box3f box = r->info().box;
  const vcg::Point3f c = box.Center();
  const double d = 1 * box.Diag();  // near enough for the screen-space error to tell the halves apart
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
    // (The bunny has holes, whose borders the coarse levels move: its cracks are not counted
    // here; LodCracks below checks watertight meshes.)
    EXPECT_EQ(CheckCut(*bunny_, *r, cut).overused, 0u);
    // Per half of the model (node centre's z above / below the centre): the mean level of the
    // cut's nodes, and the faces drawn.
    auto halves = [&](const LodCut& k, double out[4]) {
      double sum[2] = {0, 0}, count[2] = {0, 0}, drawn[2] = {0, 0};
      for (size_t i = 0; i < k.nodes.size(); ++i) {
        const LodNode& n = r->node(k.nodes[i]);
        const int side = n.center[2] > c[2] ? 0 : 1;
        sum[side] += n.level * double(n.faceCount);
        count[side] += n.faceCount;
        if (!k.culled[i]) drawn[side] += n.faceCount;
      }
      out[0] = sum[0] / std::max(1.0, count[0]);
      out[1] = sum[1] / std::max(1.0, count[1]);
      out[2] = drawn[0];
      out[3] = drawn[1];
    };
    double h[4];
    halves(cut, h);
    IndexedMesh out;
    ASSERT_TRUE(ExtractCutMesh(*r, cut, true, out).ok());
    EXPECT_EQ(out.faces.size(), cut.faces);
    EXPECT_LT(out.faces.size(), 69451u);
    // At 2% the cut is the roots and a few more (541 faces at the top level): too coarse to say.
    if (fraction < 0.05) continue;
    // The same budget from -z: each half is finer, and has more faces drawn, when the eye looks
    // at it than when it looks at the other half (compared between the two eyes, as the bunny's
    // halves differ in size and detail).
    LodCut other;
    ASSERT_TRUE(RefineLod(*r, Eye(c[0], c[1], c[2] - d, budget), other).ok());
    double o[4];
    halves(other, o);
    // The mean level moves by whole groups: at 5 % (3,472 faces) the +z half seen from +z was at
    // 5.14 against 5.09 from -z, with 1,742 of its faces drawn against 1,500: the faces drawn
    // say where the budget goes; the mean level only from 10 % on.
    if (fraction >= 0.1) {
      EXPECT_LT(h[0], o[0]) << "the +z half should be finer seen from +z";
      EXPECT_GT(h[1], o[1]) << "the -z half should be finer seen from -z";
    }
    EXPECT_GT(h[2], o[2]) << "more faces drawn on the +z half seen from +z";
    EXPECT_LT(h[3], o[3]) << "more faces drawn on the -z half seen from -z";
  }
}

// By the error in model units a group too large for what is left of the budget is passed over
// and smaller ones fill the rest (issue 29: the cut stopped at the first that did not fit, 82 %
// of a 5 % budget), and the cut stays watertight. The 2 % cut fills too: the top levels' groups
// of 6 clusters (LodBuildParams::topGroupClusters) refine in small steps (with 12: 82 %). The 10 %
// cut (6,803 faces of 6,945) stops 3 faces short of 98 %: its groups add about 600 faces each,
// and the moves that would fill it undo more than they gain (lod_refine.cpp, Fill; ordered by the
// typical distance of version 9; by the largest distance it filled 99.7 % at 1.11x our static
// collapse against 1.08x now).
TEST_F(BunnyLod, ObjectErrorCutsFillTheirBudget) {
  auto r = Open();
  ASSERT_TRUE(r);
  for (double fraction : {0.02, 0.05, 0.1, 0.25}) {
    SCOPED_TRACE(fraction);
    LodView v = Eye(0, 0.1, 100, size_t(fraction * 69451), false);
    v.priority = LodPriority::ObjectError;
    LodCut cut;
    ASSERT_TRUE(RefineLod(*r, v, cut).ok());
    EXPECT_LE(cut.faces, v.faceBudget);
    EXPECT_GE(cut.faces, v.faceBudget * (fraction == 0.1 ? 979 : 980) / 1000);
    EXPECT_EQ(CheckCut(*bunny_, *r, cut).overused, 0u);
  }
}

// Near the top of the DAG one expansion adds hundreds of faces, so a greedy pass can end well
// short of its budget with nothing left that fits. By the error in model units the refiner then
// undoes expansions for others that fit and gain more (lod_refine.cpp, Fill): over budgets of
// 2-30 % of the bunny, 9 cuts of 57 end below 98 % of their budget (the 10 % cut at 97.96 %:
// BunnyLod.ObjectErrorCutsFillTheirBudget); ordered by the largest distance (version 8's files), 8,
// and 12 when one expansion was only undone for one. Every cut within its budget, none with an
// edge used by three faces.
TEST_F(BunnyLod, ObjectErrorCutsSwapGroupsToFillTheirBudget) {
  auto r = Open();
  ASSERT_TRUE(r);
  int below = 0;
  for (int step = 0; step <= 56; ++step) {
    const size_t budget = size_t((0.02 + 0.005 * step) * 69451);
    SCOPED_TRACE(budget);
    LodView v = Eye(0, 0.1, 100, budget, false);
    v.priority = LodPriority::ObjectError;
    LodCut cut;
    ASSERT_TRUE(RefineLod(*r, v, cut).ok());
    EXPECT_LE(cut.faces, budget);
    EXPECT_EQ(CheckCut(*bunny_, *r, cut).overused, 0u);
    if (cut.faces * 100 < budget * 98) ++below;
  }
  EXPECT_LE(below, 9);
}

// By the error in model units the groups are expanded by what they gain for the cut's RMS
// distance per face they add, their error accumulated up the DAG by the mean rather than the max
// (lod_refine.cpp, MeanError; issue 29): the bunny's 5 % cut is closer to the input than our static
// collapse (GroupQemParams' defaults) to its face count: 0.870x (by the file's error, the largest
// distance accumulated by the max, it was 1.02x when this test was written).
TEST_F(BunnyLod, ObjectErrorCutIsAsCloseAsTheStaticCollapse) { EXPECT_LE(CutAgainstStatic(0.05), 1.0); }

// Ordered by the groups' typical distance (version 9: the geometric mean of the RMS and the
// largest distance of each group's vertices; lod_refine.cpp, MeanError) the bunny's 10 % cut is
// 0.873x this collapse at its count (6,803 faces); ordered by the largest distance alone, what a
// version-8 file gives the order, 0.899x (6,924 faces).
TEST_F(BunnyLod, ObjectErrorCutsOrderByTheTypicalDistance) {
  const double ratio = CutAgainstStatic(0.10);
  EXPECT_LE(ratio, 0.885);
}

double BunnyLod::CutAgainstStatic(double fraction) {
  auto r = Open();
  LodView v = Eye(0, 0.1, 100, size_t(fraction * 69451), false);
  v.priority = LodPriority::ObjectError;
  LodCut cut;
  IndexedMesh m;
  GroupHierarchy h;
  if (!r || !RefineLod(*r, v, cut).ok() || !ExtractCutMesh(*r, cut, true, m).ok() ||
      !BuildConeHierarchy(bunny_->mesh, ConeGroupingParams(), h).ok()) {
    ADD_FAILURE() << "no cut of the bunny at " << fraction;
    return 1e9;
  }
  GroupQemParams p;
  p.targetFaces = m.faces.size();
  GroupQemResult ours;
  if (!SimplifyPreservingGroups(bunny_->mesh, h.level(AutoGroupLevel(h, p.targetFaces)).faceGroup, p, ours).ok()) {
    ADD_FAILURE() << "no static collapse of the bunny to " << p.targetFaces;
    return 1e9;
  }
  auto rms = [&](const IndexedMesh& x) {
    HausdorffResult d;
    EXPECT_TRUE(SampledHausdorff(x, bunny_->mesh, 100000, d).ok());
    return std::max(d.ab.rms, d.ba.rms);
  };
  const double cutRms = rms(m), staticRms = rms(ours.mesh);
  std::printf("bunny %.0f %% cut: %zu faces, RMS %.5f; static %zu faces, %.5f; ratio %.3f\n", 100 * fraction,
              size_t(cut.faces), cutRms, ours.mesh.faces.size(), staticRms, cutRms / staticRms);
  return cutRms / staticRms;
}

// The level ratio per level (LodBuildParams::coarseLevelRatio): levels 1 and 2 keep about half
// the faces of the level below, the levels from 2 up (at most 3/8 of the input's faces) about
// 0.6 of theirs (a group stops short only where its locked border leaves no cheap collapse).
TEST_F(BunnyLod, CoarseLevelsKeepSixTenthsOfTheirFaces) {
  const auto& L = bunny_->dag.levels;
  ASSERT_GE(L.size(), 6u);
  auto ratio = [&](size_t k) { return double(L[k].faces.size()) / double(L[k - 1].faces.size()); };
  for (size_t k : {1, 2}) {
    EXPECT_GT(ratio(k), 0.48) << k;
    EXPECT_LT(ratio(k), 0.53) << k;
  }
  for (size_t k : {3, 4, 5}) {
    EXPECT_GT(ratio(k), 0.58) << k;
    EXPECT_LT(ratio(k), 0.66) << k;
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
      const vcg::Point3d n =
          (vcg::Point3d::Construct(g.positions[t[1]]) - a) ^ (vcg::Point3d::Construct(g.positions[t[2]]) - a);
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
  }
  EXPECT_GT(steps, 3u);
  std::vector<uint32_t> a = whole.nodes, b = refiner.cut().nodes;
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  EXPECT_EQ(a, b);
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
  IndexedMesh m = test::Sphere(2);
  LodDag dag;
  const std::string path = TempPath("refused.clod");
  std::remove(path.c_str());
  EXPECT_FALSE(WriteLodFile(m, dag, path).ok());  // no levels
  LodBuildParams p;
  p.clusterFaces = 16;
  ASSERT_TRUE(BuildLodDag(m, p, dag).ok());
  LodDag bad = dag;
  bad.levels[0].faceCluster[0] = 1 << 20;
  EXPECT_FALSE(WriteLodFile(m, bad, path).ok());
  bad = dag;
  bad.levels.back().faces[0][0] = 1u << 30;
  EXPECT_FALSE(WriteLodFile(m, bad, path).ok());
  std::ifstream in(path);
  EXPECT_FALSE(in.good()) << "no file is left behind";
  EXPECT_FALSE(WriteLodFile(m, dag, "/nonexistent-dir/x.clod").ok());
  EXPECT_FALSE(BuildLodDag(
                   m,
                   [] {
                     LodBuildParams q;
                     q.clusterFaces = 1;
                     return q;
                   }(),
                   dag)
                   .ok());
  EXPECT_FALSE(BuildLodDag(
                   m,
                   [] {
                     LodBuildParams q;
                     q.simplification.levelRatio = 1;
                     return q;
                   }(),
                   dag)
                   .ok());
  EXPECT_FALSE(BuildLodDag(
                   m,
                   [] {
                     LodBuildParams q;
                     q.maxGroupError = 0;
                     return q;
                   }(),
                   dag)
                   .ok());
}

// fineGroupClusters (24 by default): larger groups on the levels above 3/8 of the input's faces
// only, the cuts still watertight; out of range it is refused.
TEST(Lod, FineGroupClustersGatherLargerGroupsOnTheFineLevels) {
  Built plain, fine;
  plain.mesh = fine.mesh = test::Sphere(5);  // 8192 faces, 64 clusters
  LodBuildParams p, q;
  ASSERT_EQ(p.fineGroupClusters, 24);
  q.fineGroupClusters = 0;  // groupClusters on every fine level
  Build(plain, "sphere_plain", q);
  Build(fine, "sphere_fine", p);
  auto groups = [](const LodDag::Level& L) {
    return std::set<int>(L.clusterGroup.begin(), L.clusterGroup.end()).size();
  };
  ASSERT_GE(plain.dag.levels.size(), 3u);
  ASSERT_GE(fine.dag.levels.size(), 3u);
  EXPECT_LT(groups(fine.dag.levels[0]), groups(plain.dag.levels[0]));
  std::unique_ptr<LodReader> r;
  ASSERT_TRUE(LodReader::Open(fine.path, r).ok());
  for (double pct : {5.0, 20.0, 50.0}) {
    LodView v;
    v.eye = vcg::Point3d(0, 0, 5);
    v.faceBudget = size_t(8192 * pct / 100);
    v.priority = LodPriority::ObjectError;
    LodCut cut;
    ASSERT_TRUE(RefineLod(*r, v, cut).ok());
    const CrackCount k = CheckCut(fine, *r, cut);
    EXPECT_EQ(k.border, 0u) << pct;
    EXPECT_EQ(k.overused, 0u) << pct;
  }
  std::remove(plain.path.c_str());
  std::remove(fine.path.c_str());
  p.fineGroupClusters = 1;
  LodDag dag;
  EXPECT_FALSE(BuildLodDag(fine.mesh, p, dag).ok());
  // So are a top group size and a coarse levels' ratio out of range.
  q = LodBuildParams();
  q.topGroupClusters = 1;
  EXPECT_FALSE(BuildLodDag(fine.mesh, q, dag).ok());
  for (double bad : {-0.1, 1.5, std::numeric_limits<double>::quiet_NaN()}) {
    q = LodBuildParams();
    q.topFaceShare = bad;
    EXPECT_FALSE(BuildLodDag(fine.mesh, q, dag).ok()) << bad;
  }
  for (double bad : {-0.1, 1.0, std::numeric_limits<double>::quiet_NaN()}) {
    q = LodBuildParams();
    q.coarseLevelRatio = bad;
    EXPECT_FALSE(BuildLodDag(fine.mesh, q, dag).ok()) << bad;
  }
  // And a memoryless steps' ratio out of [0, 1) (each group would otherwise stay as it is).
  for (double bad : {-0.1, 1.0, std::numeric_limits<double>::quiet_NaN()}) {
    q = LodBuildParams();
    q.refreshRatio = bad;
    EXPECT_FALSE(BuildLodDag(fine.mesh, q, dag).ok()) << bad;
  }
}

// A thin closed lens (two layers meeting back to back along their rim, as a scan's layers where a
// crack was welded): each level of the DAG is simplified from the one below with fresh quadrics,
// and the rim's planes (GroupQemParams::foldPlanes) keep its outline in place. Without them the
// rim slid into the sheet a little more at every level: RMS distance to the input (% of the
// diagonal) at levels 2 / 4 / 6 (2,300 / 824 / 294 faces) of 0.0100 / 0.0201 / 0.0317, against
// 0.0013 / 0.0040 / 0.0096 with them.
TEST(Lod, SheetRimsKeepTheirPlaceLevelAfterLevel) {
  const IndexedMesh m = WeldByPosition(test::Lens(48, 0.01f)).mesh;
  ASSERT_EQ(m.faces.size(), 9216u);
  LodDag dag;
  ASSERT_TRUE(BuildLodDag(m, LodBuildParams(), dag).ok());
  ASSERT_GE(dag.levels.size(), 7u);
  for (auto bound : {std::make_pair(2, 0.0025), std::make_pair(4, 0.008), std::make_pair(6, 0.019)}) {
    IndexedMesh level;
    level.positions = dag.positions;
    level.faces = dag.levels[size_t(bound.first)].faces;
    HausdorffResult d;
    ASSERT_TRUE(SampledHausdorff(level, m, 50000, d).ok());
    EXPECT_LE(d.rmsPct(), bound.second) << "level " << bound.first << ", " << level.faces.size() << " faces";
  }
}

// Below the top levels, a group that the greedy pass leaves under half the clusters asked joins a
// neighbouring group (LodBuildParams::mergeSmallGroups): fewer groups and fewer small ones on
// those levels, none over 3/2 of the clusters asked; the top levels keep groups of at most 6;
// without it no group is over the clusters asked.
TEST(Lod, SmallGroupsJoinANeighbourBelowTheTop) {
  const IndexedMesh sphere = test::Sphere(7);  // 131,072 faces
  struct Sizes {
    size_t groups = 0, small = 0;
    int most = 0;
  };
  // The clusters asked of a group on a level of that many faces (fine, top, else coarse).
  auto top = [](size_t faces) { return faces < 6144; };
  auto asked = [&](const LodBuildParams& p, size_t faces) {
    const bool large = faces >= size_t(p.largeGroupCount) * size_t(p.largeGroupClusters) * p.clusterFaces;
    return 8 * faces > 3 * sphere.faces.size() ? p.fineGroupClusters
           : top(faces)                        ? p.topGroupClusters
           : large                             ? p.largeGroupClusters
                                               : p.groupClusters;
  };
  // Per level: its faces, and its groups' count, the groups under half the clusters asked, the
  // most clusters of one group.
  auto levels = [&](const LodBuildParams& p) {
    LodDag dag;
    EXPECT_TRUE(BuildLodDag(sphere, p, dag).ok());
    std::vector<std::pair<size_t, Sizes>> out;
    for (const LodDag::Level& L : dag.levels) {
      if (L.clusterGroup.empty() || L.clusterGroup[0] < 0) continue;
      const int per = asked(p, L.faces.size());
      std::map<int, int> size;
      for (int g : L.clusterGroup) ++size[g];
      Sizes z;
      z.groups = size.size();
      for (const auto& kv : size) {
        z.small += 2 * kv.second < per;
        z.most = std::max(z.most, kv.second);
      }
      out.push_back({L.faces.size(), z});
    }
    return out;
  };
  LodBuildParams merged, greedy;
  ASSERT_TRUE(merged.mergeSmallGroups);
  greedy.mergeSmallGroups = false;
  const auto m = levels(merged), g = levels(greedy);
  ASSERT_GE(m.size(), 4u);
  // Level 0 is the same clusters either way.
  ASSERT_EQ(m[0].first, g[0].first);
  EXPECT_LT(m[0].second.groups, g[0].second.groups);
  EXPECT_LT(2 * m[0].second.small, g[0].second.small)
      << m[0].second.small << " small groups merged, " << g[0].second.small << " greedy";
  for (const auto& l : m) {
    const int per = asked(merged, l.first);
    EXPECT_LE(l.second.most, top(l.first) ? per : per + per / 2) << l.first << " faces";
  }
  for (const auto& l : g) EXPECT_LE(l.second.most, asked(greedy, l.first)) << l.first << " faces";
}

// The top levels (groups of topGroupClusters = 6) are those under the faces of 4 groups of 12
// clusters (6,144), whatever the input's size: a sphere of 131,072 faces has groups of more than
// 6 clusters on each coarse level above 6,144 faces (LodBuildParams::topFaceShare 0). With the top
// also under 6 % of the input (topFaceShare 0.06, as the dragon's levels of 6,144-52,284 faces
// were built) its levels of 6,144-7,864 faces are grouped by 6 at most.
// LodBuildParams::largeFineGroupClusters: a fine level that holds 32 groups of 64 clusters gathers
// groups that large (here clusters of 32 faces, so a level of 65,536 faces does); without it, or on
// a smaller level, groups of fineGroupClusters (24; at most 3/2 of it once small ones join).
TEST(Lod, LargeFineLevelsGatherLargerGroups) {
  const IndexedMesh sphere = test::Sphere(7);
  ASSERT_EQ(sphere.faces.size(), 131072u);
  auto level0 = [&](const LodBuildParams& p, double& mean) {
    LodDag dag;
    EXPECT_TRUE(BuildLodDag(sphere, p, dag).ok());
    std::map<int, int> size;
    for (int g : dag.levels[0].clusterGroup) ++size[g];
    int most = 0;
    for (const auto& kv : size) most = std::max(most, kv.second);
    mean = double(dag.levels[0].clusterGroup.size()) / double(size.size());
    return most;
  };
  LodBuildParams p;
  ASSERT_EQ(p.largeFineGroupClusters, 64);
  p.clusterFaces = 32;
  double mean = 0;
  EXPECT_GT(level0(p, mean), 36);
  EXPECT_GT(mean, 36.0);
  p.largeFineGroupClusters = 0;
  EXPECT_LE(level0(p, mean), 36);
  p.largeFineGroupClusters = 64;
  p.clusterFaces = 128;  // 32 groups of 64 clusters: 262,144 faces, more than the sphere's
  EXPECT_LE(level0(p, mean), 36);
  p.largeFineGroupClusters = 65;
  LodDag dag;
  EXPECT_FALSE(BuildLodDag(sphere, p, dag).ok());
}

// Per level of `mesh`'s DAG under 3/8 of its faces and of at least 6,144 (and not a root level):
// its faces and the most clusters of one of its groups.
std::vector<std::pair<size_t, int>> LargestCoarseGroups(const IndexedMesh& mesh, const LodBuildParams& p) {
  LodDag dag;
  EXPECT_TRUE(BuildLodDag(mesh, p, dag).ok());
  std::vector<std::pair<size_t, int>> out;
  for (const LodDag::Level& L : dag.levels) {
    if (8 * L.faces.size() > 3 * mesh.faces.size() || L.faces.size() < 6144 || L.clusterGroup.empty() ||
        L.clusterGroup[0] < 0)
      continue;
    std::map<int, int> size;
    for (int g : L.clusterGroup) ++size[g];
    int most = 0;
    for (const auto& kv : size) most = std::max(most, kv.second);
    out.push_back({L.faces.size(), most});
  }
  return out;
}

TEST(Lod, TopGroupsAreSmallOnlyUnderAFaceCount) {
  const IndexedMesh sphere = test::Sphere(7);
  const size_t F = sphere.faces.size();
  ASSERT_EQ(F, 131072u);
  LodBuildParams p;
  ASSERT_EQ(p.topFaceShare, 0);
  const auto byCount = LargestCoarseGroups(sphere, p);
  ASSERT_GE(byCount.size(), 3u);
  for (const auto& l : byCount) EXPECT_GT(l.second, 6) << l.first << " faces: groups of 12";
  p.topFaceShare = 0.06;
  size_t inWindow = 0;
  for (const auto& l : LargestCoarseGroups(sphere, p))
    if (double(l.first) < 0.06 * double(F)) {
      ++inWindow;
      EXPECT_LE(l.second, 6) << l.first << " faces, under 6 % of the input: groups of 6";
    }
  EXPECT_GE(inWindow, 1u);
}

// LodBuildParams::largeGroupClusters: a coarse level (under 3/8 of the input's faces, above the
// top) that holds 8 groups of 24 clusters (24,576 faces at 128 faces a cluster) gathers groups of
// 24 (at most 36 once small ones join); a smaller coarse level, or none with 0, groups of 12 (at
// most 18). Out-of-range values are refused.
TEST(Lod, LargeCoarseLevelsGatherLargerGroups) {
  const IndexedMesh sphere = test::Sphere(7);  // 131,072 faces
  LodBuildParams p;
  ASSERT_EQ(p.largeGroupClusters, 24);
  ASSERT_EQ(p.largeGroupCount, 8);
  size_t large = 0, small = 0;
  for (const auto& l : LargestCoarseGroups(sphere, p)) {
    if (l.first >= 24576) {
      ++large;
      EXPECT_GT(l.second, 18) << l.first << " faces: groups of 24";
      EXPECT_LE(l.second, 36) << l.first << " faces";
    } else {
      ++small;
      EXPECT_LE(l.second, 18) << l.first << " faces: groups of 12";
    }
  }
  EXPECT_GE(large, 1u);
  EXPECT_GE(small, 1u);
  p.largeGroupClusters = 0;
  for (const auto& l : LargestCoarseGroups(sphere, p))
    EXPECT_LE(l.second, 18) << l.first << " faces, off: groups of 12";
  LodDag dag;
  p.largeGroupClusters = 65;
  EXPECT_FALSE(BuildLodDag(sphere, p, dag).ok());
  p.largeGroupClusters = 24;
  p.largeGroupCount = 0;
  EXPECT_FALSE(BuildLodDag(sphere, p, dag).ok());
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
  EXPECT_EQ(st.levelNodes.back(), 1u);
  EXPECT_EQ(ReadBytes(path).size(), st.fileBytes);
  std::remove(path.c_str());
}

// An 8-face mesh with 58 unreferenced vertices (issue 24, item 2): the reader once compared the
// input's vertex count, unreferenced included, with the file's size and refused the file that
// `conelod lod build` had just written. Built by BuildLodFile (which welds and leaves the
// unreferenced vertices out) and by BuildLodDag + WriteLodFile on the mesh as it is: both read.
TEST(Lod, UnreferencedVerticesGiveAReadableFile) {
  IndexedMesh m;
  m.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  m.faces = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (int i = 0; i < 58; ++i) m.positions.push_back({float(i), 7, 7});
  const std::string path = TempPath("unreferenced.clod");
  LodBuildStats st;
  ASSERT_TRUE(BuildLodFile(m, LodBuildParams(), path, &st).ok());
  EXPECT_EQ(st.droppedVertices, 58u);
  EXPECT_EQ(st.inputVertices, 6u);
  for (int direct = 0; direct < 2; ++direct) {
    if (direct) {
      Built b;
      b.mesh = m;
      Build(b, "unreferenced_direct");
      ASSERT_EQ(b.dag.inputVertices, 64u);
      std::rename(b.path.c_str(), path.c_str());
    }
    SCOPED_TRACE(direct ? "BuildLodDag + WriteLodFile" : "BuildLodFile");
    std::unique_ptr<LodReader> r;
    const Status s = LodReader::Open(path, r);
    ASSERT_TRUE(s.ok()) << s.message;
    LodCut cut;
    ASSERT_TRUE(RefineLod(*r, Eye(0, 0, 5, 1000), cut).ok());
    IndexedMesh out;
    ASSERT_TRUE(ExtractCutMesh(*r, cut, true, out).ok());
    EXPECT_EQ(out.faces.size(), 8u);
    EXPECT_EQ(out.positions.size(), 6u);
    EXPECT_EQ(SortedFacePositions(out), SortedFacePositions(OnGrid(m, r->info().grid)));
  }
  std::remove(path.c_str());
}

// --- Screen-space refinement ------------------------------------------------------------------

// The viewer's camera (viewer/lod_viewer_widget.cpp): 35 degrees vertical field of view, 600
// pixels high, framed so that the bounding sphere fills the view; `zoom` divides the distance.
struct ScreenView {
  LodView view;
  double scale;
};
ScreenView ViewerEye(const LodFileInfo& info, vcg::Point3d dir, double zoom, size_t budget) {
  const double fov = 35 * NormalCone::kPi / 180;
  const vcg::Point3d c = vcg::Point3d::Construct(info.box.Center());
  const double radius = info.box.Diag() / 2;
  ScreenView s;
  s.view.eye = c + dir.Normalize() * (radius / std::sin(fov / 2) * 1.05 / zoom);
  s.view.faceBudget = budget;
  s.view.projectionScale = s.scale = 600 / (2 * std::tan(fov / 2));
  s.view.maxPixelError = 1;
  return s;
}

// The largest error, in pixels, of a drawn (not culled) node of the cut, projected at the nearest
// point of its bounding sphere; computed here, not by the refiner.
double WorstDrawnPixelError(LodReader& r, const LodCut& cut, const ScreenView& s) {
  double worst = 0;
  for (size_t i = 0; i < cut.nodes.size(); ++i) {
    if (cut.culled[i]) continue;
    const LodNode& n = r.node(cut.nodes[i]);
    const double d = (s.view.eye - vcg::Point3d::Construct(n.center)).Norm() - double(n.radius);
    worst = std::max(worst, d > 0 ? double(n.error) * s.scale / d : (n.error > 0 ? HUGE_VAL : 0.0));
  }
  return worst;
}

// Issue 24, item 17: a still cut meets the pixel error wherever it is drawn, or has spent its
// budget. Eyes all around and zoomed in up to 8x (inside the bounding sphere): a near group whose
// clusters are not all in the cut (some wait on far or back-facing groups below a pixel) must
// still be refined.
void ExpectStillCutsMeetThePixelError(LodReader& r, const std::string& name, size_t budget) {
  const std::vector<vcg::Point3d> dirs = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0},      {-1, 0, 0},
                                          {0, 1, 0}, {1, 1, 1},  {-1, 0.3, 0.6}, {0.4, -1, 0.2}};
  size_t unmet = 0, cuts = 0, budgetCuts = 0;
  for (const auto& dir : dirs)
    for (double zoom : {1.0, 2.0, 4.0, 8.0}) {
      const ScreenView s = ViewerEye(r.info(), dir, zoom, budget);
      LodCut cut;
      ASSERT_TRUE(RefineLod(r, s.view, cut).ok());
      ++cuts;
      EXPECT_LE(cut.faces, std::max(budget, size_t(r.info().levelFaces.back())));
      if (cut.budgetReached) {
        ++budgetCuts;
        continue;
      }
      const double worst = WorstDrawnPixelError(r, cut, s);
      EXPECT_LE(worst, 1.0) << name << ": eye direction " << dir[0] << "," << dir[1] << "," << dir[2] << " zoom "
                            << zoom << ", " << cut.faces << " faces of a budget of " << budget;
      unmet += worst > 1.0;
    }
  EXPECT_EQ(unmet, 0u);
  EXPECT_LT(budgetCuts, cuts) << "every cut hit the budget: the test proves little";
}

TEST_F(BunnyLod, StillCutsMeetThePixelErrorOrTheBudget) {
  auto r = Open();
  ASSERT_TRUE(r);
  ExpectStillCutsMeetThePixelError(*r, "bunny", 69451);
}

// --- Cracks -----------------------------------------------------------------------------------

// A torus of n x m quads (two triangles each): watertight, genus 1.
IndexedMesh Torus(int n, int m, float R, float r) {
  IndexedMesh t;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const double u = 2 * NormalCone::kPi * i / n, v = 2 * NormalCone::kPi * j / m;
      t.positions.emplace_back(float((R + r * std::cos(v)) * std::cos(u)), float((R + r * std::cos(v)) * std::sin(u)),
                               float(r * std::sin(v)));
    }
  auto id = [&](int i, int j) { return uint32_t(((i + n) % n) * m + (j + m) % m); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      t.faces.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      t.faces.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return t;
}

size_t InputBorderEdges(const IndexedMesh& m) {
  size_t k = 0;
  for (const auto& e : EdgesByPosition(m)) k += e.second != 2;
  return k;
}

// Every cut of a watertight mesh, at every eye, budget and priority, with and without culling,
// is watertight: welded by position, no edge used by one face (crack, T-junction) or by three
// (overlap); the drawn nodes' border lies along culled nodes only.
// With `ply` (b.mesh: that file welded), the file is the streamed build's (BuildLodFileFromPly,
// `sample` its sampleFaces).
void ExpectCrackFree(Built& b, const std::string& name, const LodBuildParams& params = LodBuildParams(),
                     const std::string& ply = "", size_t sample = 0) {
  ASSERT_EQ(InputBorderEdges(b.mesh), 0u) << name << " must be watertight for this test";
  if (ply.empty()) {
    Build(b, name, params);
  } else {
    b.path = TempPath(name + ".clod");
    const Status s = BuildLodFileFromPly(ply, params, b.path, &b.stats, Progress(), nullptr, sample);
    ASSERT_TRUE(s.ok()) << s.message;
    b.bytes = ReadBytes(b.path);
  }
  std::unique_ptr<LodReader> r;
  ASSERT_TRUE(LodReader::Open(b.path, r).ok());
  const vcg::Box3f box = r->info().box;
  const vcg::Point3d c = vcg::Point3d::Construct(box.Center());
  const double d = box.Diag();
  const std::vector<vcg::Point3d> eyes = {
      c + vcg::Point3d(0, 0, 2 * d),
      c + vcg::Point3d(0, 0, -2 * d),
      c + vcg::Point3d(1.5 * d, 0.3 * d, 0),
      c + vcg::Point3d(-0.2 * d, 1.2 * d, 0.4 * d),
      c + vcg::Point3d(0.3 * d, 0.1 * d, 0.45 * d),  // close: strong screen-space falloff
      c};                                            // inside the model
  const size_t F = b.mesh.faces.size();
  size_t cuts = 0, mixed = 0;
  for (const auto& eye : eyes)
    for (double pct : {0.0, 5.0, 20.0, 50.0, 80.0, 100.0})
      for (bool cull : {true, false})
        for (LodPriority pr : {LodPriority::ScreenError, LodPriority::ObjectError, LodPriority::ConeFg}) {
          LodView v;
          v.eye = eye;
          v.faceBudget = size_t(double(F) * pct / 100);
          v.cullBackFacing = cull;
          v.priority = pr;
          LodCut cut;
          ASSERT_TRUE(RefineLod(*r, v, cut).ok());
          SCOPED_TRACE(name + " budget " + std::to_string(pct) + "% cull " + std::to_string(cull) + " priority " +
                       std::to_string(int(pr)) + " eye " + std::to_string(eye[0]) + "," + std::to_string(eye[1]) + "," +
                       std::to_string(eye[2]));
          const CrackCount k = CheckCut(b, *r, cut);
          EXPECT_EQ(k.border, 0u);
          EXPECT_EQ(k.overused, 0u);
          EXPECT_EQ(k.drawnBorderNotCulled, 0u);
          if (pct == 100) {
            EXPECT_EQ(cut.faces, F);
          }
          if (pct > 0) {
            EXPECT_LE(cut.faces, std::max(v.faceBudget, size_t(r->info().levelFaces.back())));
          }
          ++cuts;
          mixed += cut.maxLevelDifference > 0;
        }
  EXPECT_GT(mixed, cuts / 3) << "most cuts should mix levels (else the test proves little)";
  // A screen-space cut with a real projection: refined where the error exceeds a pixel.
  LodView v;
  v.eye = eyes[4];
  v.faceBudget = F;
  v.projectionScale = 1000 / (2 * std::tan(0.5 * 0.7));  // 1000 pixels, 40 degrees
  v.maxPixelError = 1;
  LodCut cut;
  ASSERT_TRUE(RefineLod(*r, v, cut).ok());
  const CrackCount k = CheckCut(b, *r, cut);
  EXPECT_EQ(k.border, 0u);
  EXPECT_EQ(k.overused, 0u);
  std::remove(b.path.c_str());
}

TEST(LodCracks, SphereCutsAreWatertight) {
  Built b;
  b.mesh = test::Sphere(5);  // 8192 faces
  ExpectCrackFree(b, "sphere");
}

TEST(LodCracks, TorusCutsAreWatertight) {
  Built b;
  b.mesh = Torus(96, 48, 1.f, 0.35f);  // 9216 faces
  ExpectCrackFree(b, "torus");
}

TEST(LodCracks, ArmadilloCutsAreWatertight) {
  Built b;
  CMesh m;
  ASSERT_EQ(LoadPly(m, test::MeshPath("stanford_armadillo_cgal.ply")), "");
  b.mesh = ToIndexedMesh(m);
  ExpectCrackFree(b, "armadillo");
}

// The dragon's file repeats vertices along seams (151 components and 4,270 border edges by
// index; closed once welded by position). BuildLodFile welds it: its cuts are watertight by
// position. Unwelded, the seams were simplified from each side on their own: at 5 / 20 / 50 % of
// the faces from the eye below, 1,708 / 1,264 / 800 crack edges. The DAG is built once; each cut's
// edges are compared with the input's (welded by position: its 108 slivers along the seams use
// their edges three times and are no crack).
TEST(LodCracks, DragonCutsAreWatertightOnceWelded) {
  Built b;
  CMesh m;
  ASSERT_EQ(LoadPly(m, test::MeshPath("stanford_dragon_vrip_binary.ply")), "");
  b.mesh = ToIndexedMesh(m);
  m.Clear();
  b.path = TempPath("dragon.clod");
  LodBuildStats st;
  ASSERT_TRUE(BuildLodFile(b.mesh, LodBuildParams(), b.path, &st).ok());
  EXPECT_EQ(st.mergedVertices, 2100u);
  std::unique_ptr<LodReader> r;
  ASSERT_TRUE(LodReader::Open(b.path, r).ok());
  const EdgeMap input = EdgesByPosition(OnGrid(b.mesh, r->info().grid));
  size_t inputBorder = 0;
  for (const auto& e : input) inputBorder += e.second == 1;
  ASSERT_EQ(inputBorder, 0u);
  const size_t F = b.mesh.faces.size();
  const vcg::Point3d c = vcg::Point3d::Construct(r->info().box.Center());
  const double d = r->info().box.Diag();
  for (const vcg::Point3d& eye : {vcg::Point3d(0, 0.1, 0.3), c + vcg::Point3d(0.6 * d, 0.2 * d, -0.5 * d)})
    for (double pct : {5.0, 20.0, 50.0, 80.0, 100.0}) {
      LodCut cut;
      ASSERT_TRUE(RefineLod(*r, Eye(eye[0], eye[1], eye[2], size_t(double(F) * pct / 100)), cut).ok());
      SCOPED_TRACE("dragon budget " + std::to_string(pct) + "% eye " + std::to_string(eye[0]) + "," +
                   std::to_string(eye[1]) + "," + std::to_string(eye[2]));
      const CrackCount k = CheckCut(b, *r, cut, &input);
      EXPECT_EQ(k.border, 0u);
      EXPECT_EQ(k.overused, 0u);
      EXPECT_EQ(k.drawnBorderNotCulled, 0u);
      if (pct == 100) {
        EXPECT_EQ(cut.faces, F);
      }
    }
  std::remove(b.path.c_str());
}

// --- Spatial chunks (LodBuildParams::chunkFaces, conelod lod build --memory) ---------------------

LodBuildParams Chunked(size_t chunkFaces, int threads = 0) {
  LodBuildParams p;
  p.chunkFaces = chunkFaces;
  p.simplification.threads = threads;
  return p;
}

// The number of chunks BuildLodDag splits `m` into.
size_t ChunksOf(const IndexedMesh& m, const LodBuildParams& p) {
  LodDag dag;
  size_t chunks = 0;
  EXPECT_TRUE(BuildLodDag(m, p, dag, Progress(), &chunks).ok());
  return chunks;
}

// A mesh built in chunks of at most 512 faces (16 chunks of the sphere and of the torus, 128 of
// the armadillo): every cut, at every eye, budget and priority, is watertight; the full budget
// gives the input back.
TEST(LodChunks, SphereCutsAreWatertight) {
  Built b;
  b.mesh = test::Sphere(5);  // 8192 faces
  EXPECT_EQ(ChunksOf(b.mesh, Chunked(512)), 16u);
  ExpectCrackFree(b, "sphere_chunks", Chunked(512));
}

TEST(LodChunks, TorusCutsAreWatertight) {
  Built b;
  b.mesh = Torus(96, 48, 1.f, 0.35f);  // 9216 faces
  EXPECT_EQ(ChunksOf(b.mesh, Chunked(600)), 16u);
  ExpectCrackFree(b, "torus_chunks", Chunked(600));
}

TEST(LodChunks, ArmadilloCutsAreWatertight) {
  Built b;
  CMesh m;
  ASSERT_EQ(LoadPly(m, test::MeshPath("stanford_armadillo_cgal.ply")), "");
  b.mesh = ToIndexedMesh(m);
  const size_t chunk = (b.mesh.faces.size() + 15) / 16;
  EXPECT_EQ(ChunksOf(b.mesh, Chunked(chunk)), 16u);
  ExpectCrackFree(b, "armadillo_chunks", Chunked(chunk));
}

// A mesh of at most chunkFaces faces is one chunk: its file is byte for byte the unchunked build's
// (what `lod build` without --memory wrote before). One face fewer splits it: another file.
TEST(LodChunks, OneChunkIsTheUnchunkedFile) {
  Built plain, one, two;
  plain.mesh = one.mesh = two.mesh = Torus(64, 32, 1.f, 0.35f);  // 4096 faces
  Build(plain, "torus_plain");
  Build(one, "torus_one_chunk", Chunked(4096));
  Build(two, "torus_two_chunks", Chunked(4095));
  EXPECT_EQ(ChunksOf(one.mesh, Chunked(4096)), 1u);
  EXPECT_EQ(ChunksOf(two.mesh, Chunked(4095)), 2u);
  EXPECT_EQ(one.bytes, plain.bytes);
  EXPECT_NE(two.bytes, plain.bytes);
  for (Built* b : {&plain, &one, &two}) std::remove(b->path.c_str());
}

// The chunks are built side by side (level 0) and their groups simplified side by side: the file
// does not depend on the number of threads.
TEST(LodChunks, FileDoesNotDependOnThreads) {
  CMesh m;
  ASSERT_EQ(LoadPly(m, test::MeshPath("stanford_bunny_bun_zipper.ply")), "");
  Built one, three;
  one.mesh = three.mesh = ToIndexedMesh(m);
  Build(one, "bunny_chunks_1", Chunked(4096, 1));
  Build(three, "bunny_chunks_3", Chunked(4096, 3));
  EXPECT_EQ(one.bytes, three.bytes);
  EXPECT_GT(one.stats.levels, 4);
  for (Built* b : {&one, &three}) std::remove(b->path.c_str());
}

// The file b.path of the welded dragon b.mesh: cuts from two eyes at 5 / 20 / 50 / 100 % have no
// crack nor overused edge, and the full budget gives b.mesh back exactly (on the grid, without
// the faces that use a vertex twice). Removes the file.
void ExpectDragonCutsWatertightAndRoundTripExact(const Built& b, const std::string& label) {
  const size_t F = b.mesh.faces.size();
  std::unique_ptr<LodReader> r;
  ASSERT_TRUE(LodReader::Open(b.path, r).ok());
  const EdgeMap input = EdgesByPosition(OnGrid(b.mesh, r->info().grid));
  const vcg::Point3d c = vcg::Point3d::Construct(r->info().box.Center());
  const double d = r->info().box.Diag();
  for (const vcg::Point3d& eye : {vcg::Point3d(0, 0.1, 0.3), c + vcg::Point3d(0.6 * d, 0.2 * d, -0.5 * d)})
    for (double pct : {5.0, 20.0, 50.0, 100.0}) {
      LodCut cut;
      ASSERT_TRUE(RefineLod(*r, Eye(eye[0], eye[1], eye[2], size_t(double(F) * pct / 100)), cut).ok());
      SCOPED_TRACE(label + ", budget " + std::to_string(pct) + "%");
      const CrackCount k = CheckCut(b, *r, cut, &input);
      EXPECT_EQ(k.border, 0u);
      EXPECT_EQ(k.overused, 0u);
      EXPECT_EQ(k.drawnBorderNotCulled, 0u);
      if (pct == 100) {
        EXPECT_EQ(cut.faces, F);
        IndexedMesh out;
        ASSERT_TRUE(ExtractCutMesh(*r, cut, true, out).ok());
        EXPECT_EQ(SortedFacePositions(out), SortedFacePositions(OnGrid(b.mesh, r->info().grid)));
        EXPECT_EQ(out.positions.size(), b.mesh.positions.size());
        // The dragon's faces with two corners at one position use one vertex twice once welded
        // (108): left out of the cut's mesh, so that MeshLab's filters can take it.
        const size_t flat = size_t(std::count_if(b.mesh.faces.begin(), b.mesh.faces.end(), UsesAVertexTwice));
        EXPECT_GT(flat, 0u);
        EXPECT_EQ(out.faces.size(), F - flat);
      }
    }
  std::remove(b.path.c_str());
}

// The dragon (871,414 faces, welded as BuildLodFile welds it) in 16 chunks: its cuts have no
// crack, the full budget gives the welded input back exactly (on the grid), its top is small.
// No edge is used by more than two faces on the grid either: the collapse keeps its vertices more
// than a grid cell from each other (GroupQemRegion::separation), so two vertices less than a cell
// apart never meet on the grid and pinch the sheets together.
TEST(LodChunks, DragonCutsAreWatertightAndItsRoundTripExact) {
  Built b;
  CMesh m;
  ASSERT_EQ(LoadPly(m, test::MeshPath("stanford_dragon_vrip_binary.ply")), "");
  b.mesh = WeldByPosition(ToIndexedMesh(m)).mesh;
  m.Clear();
  b.path = TempPath("dragon_chunks.clod");
  const size_t F = b.mesh.faces.size();
  LodBuildStats st;
  ASSERT_TRUE(BuildLodFile(b.mesh, Chunked((F + 15) / 16), b.path, &st).ok());
  EXPECT_EQ(st.chunks, 16u);
  EXPECT_EQ(st.mergedVertices, 0u);
  EXPECT_LT(st.levelFaces.back(), F / 100);
  ExpectDragonCutsWatertightAndRoundTripExact(b, "dragon in chunks");
}

// --- Attributes (version 5): per-vertex colour and normals through the DAG ---------------------

namespace attr {

// The bunny with a colour that is a linear function of position (so that the attribute quadrics
// reproduce it at every moved vertex, up to the RGBA8 rounding) and its vertex normals.
struct Coloured {
  IndexedMesh mesh;
  LodAttributes attributes;
  vcg::Box3f box;
};
std::array<uint8_t, 4> ColourAt(const vcg::Box3f& box, const vcg::Point3f& p) {
  std::array<uint8_t, 4> c;
  for (int i = 0; i < 3; ++i) {
    const float t = (p[i] - box.min[i]) / std::max(1e-20f, box.max[i] - box.min[i]);
    c[size_t(i)] = uint8_t(std::lround(std::min(1.f, std::max(0.f, t)) * 255.f));
  }
  c[3] = 255;
  return c;
}
Coloured ColouredBunny() {
  Coloured c;
  CMesh m;
  EXPECT_EQ(LoadPly(m, test::MeshPath("stanford_bunny_bun_zipper.ply")), "");
  c.mesh = ToIndexedMesh(m);
  for (const auto& p : c.mesh.positions) c.box.Add(p);
  std::vector<vcg::Point3f> n(c.mesh.positions.size(), vcg::Point3f(0, 0, 0));
  for (const auto& t : c.mesh.faces) {
    const vcg::Point3f fn =
        (c.mesh.positions[t[1]] - c.mesh.positions[t[0]]) ^ (c.mesh.positions[t[2]] - c.mesh.positions[t[0]]);
    for (uint32_t v : t) n[v] += fn;
  }
  for (size_t v = 0; v < c.mesh.positions.size(); ++v) {
    c.attributes.colors.push_back(ColourAt(c.box, c.mesh.positions[v]));
    c.attributes.normals.push_back(EncodeLodNormal(n[v].Norm() > 0 ? n[v] / n[v].Norm() : n[v]));
  }
  return c;
}
// In double, by atan2 (acos of a float dot product cannot tell angles below ~3e-4 rad).
double Angle(const vcg::Point3f& a, const vcg::Point3f& b) {
  const vcg::Point3d x = vcg::Point3d::Construct(a), y = vcg::Point3d::Construct(b);
  return std::atan2((x ^ y).Norm(), x * y);
}

}  // namespace attr

// The normal code: every direction reads back within the stated bound (the largest error found
// over a dense sample of the sphere is what lod_format.md states).
TEST(LodAttributes, NormalCodeStaysWithinItsBound) {
  double worst = 0;
  uint64_t s = 12345;
  auto rnd = [&]() {
    s = s * 6364136223846793005ull + 1442695040888963407ull;
    return double(s >> 11) / double(uint64_t(1) << 53) * 2 - 1;
  };
  for (int i = 0; i < 2000000; ++i) {
    vcg::Point3f n(static_cast<float>(rnd()), static_cast<float>(rnd()), static_cast<float>(rnd()));
    if (i < 6)
      n = vcg::Point3f(i % 3 == 0 ? 1.f : 0.f, i % 3 == 1 ? 1.f : 0.f, i % 3 == 2 ? 1.f : 0.f) * (i < 3 ? 1.f : -1.f);
    if (!(n.Norm() > 1e-3f)) continue;
    n /= n.Norm();
    const vcg::Point3f back = DecodeLodNormal(EncodeLodNormal(n));
    EXPECT_NEAR(back.Norm(), 1.0, 1e-6);
    worst = std::max(worst, attr::Angle(n, back));
  }
  EXPECT_LE(worst, kLodNormalErrorBound);
  std::printf("largest normal code error: %.3g rad\n", worst);
  // A zero normal reads back as +z, not as NaN.
  const vcg::Point3f z = DecodeLodNormal(EncodeLodNormal(vcg::Point3f(0, 0, 0)));
  EXPECT_NEAR(z[2], 1.0, 1e-6);
}

// The coloured bunny: a file with attribute streams; the full-budget cut gives every input vertex
// its colour exactly and its normal within the bound; a coarse cut interpolates the (linear)
// colour at the moved vertices, within the RGBA8 rounding; the geometry-only build is the file of
// BuildLodFile without attributes byte for byte.
TEST(LodAttributes, ColouredRoundTripIsExactAndCoarseLevelsInterpolate) {
  const attr::Coloured c = attr::ColouredBunny();
  const std::string path = TempPath("coloured.clod"), plain = TempPath("plain.clod"), plain2 = TempPath("plain2.clod");
  LodBuildStats st, sp;
  ASSERT_TRUE(BuildLodFile(c.mesh, LodBuildParams(), path, &st, Progress(), &c.attributes).ok());
  ASSERT_TRUE(BuildLodFile(c.mesh, LodBuildParams(), plain, &sp).ok());
  const LodAttributes none;
  ASSERT_TRUE(BuildLodFile(c.mesh, LodBuildParams(), plain2, nullptr, Progress(), &none).ok());
  EXPECT_EQ(ReadBytes(plain), ReadBytes(plain2));
  EXPECT_GT(st.colorBytes, 0u);
  EXPECT_GT(st.normalBytes, 0u);
  EXPECT_EQ(st.fileBytes, ReadBytes(path).size());
  EXPECT_EQ(sp.colorBytes + sp.normalBytes, 0u);
  std::printf("bunny .clod: %llu bytes geometry only, %llu with colour (%llu) and normals (%llu)\n",
              (unsigned long long)sp.fileBytes, (unsigned long long)st.fileBytes, (unsigned long long)st.colorBytes,
              (unsigned long long)st.normalBytes);
  std::unique_ptr<LodReader> r, rp;
  ASSERT_TRUE(LodReader::Open(path, r).ok());
  ASSERT_TRUE(LodReader::Open(plain, rp).ok());
  EXPECT_EQ(r->info().version, 9u);
  EXPECT_EQ(rp->info().version, 9u);
  EXPECT_TRUE(r->info().colors && r->info().normals);
  EXPECT_FALSE(rp->info().colors || rp->info().normals);

  // Full budget: input vertex by grid position.
  std::map<PosKey, size_t> inputAt;
  for (size_t v = 0; v < c.mesh.positions.size(); ++v) {
    const vcg::Point3f p = r->info().grid.Round(c.mesh.positions[v]);
    inputAt.emplace(PosKey{{p[0], p[1], p[2]}}, v);
  }
  LodCut cut;
  ASSERT_TRUE(RefineLod(*r, Eye(0, 0.1, 0.6, size_t(1) << 30), cut).ok());
  IndexedMesh out;
  LodAttributes a;
  ASSERT_TRUE(ExtractCutMesh(*r, cut, true, out, nullptr, nullptr, &a).ok());
  EXPECT_EQ(out.faces.size(), c.mesh.faces.size());
  ASSERT_EQ(a.colors.size(), out.positions.size());
  ASSERT_EQ(a.normals.size(), out.positions.size());
  size_t colourMismatch = 0, normalMismatch = 0;
  for (size_t v = 0; v < out.positions.size(); ++v) {
    const auto it = inputAt.find(PosKey{{out.positions[v][0], out.positions[v][1], out.positions[v][2]}});
    ASSERT_TRUE(it != inputAt.end());
    colourMismatch += a.colors[v] != c.attributes.colors[it->second];
    normalMismatch += a.normals[v] != c.attributes.normals[it->second];
  }
  EXPECT_EQ(colourMismatch, 0u);
  EXPECT_EQ(normalMismatch, 0u);  // the input's code, stored as is
  // The input's faces on the file's grid (each file's own: the grid spans the DAG's positions);
  // a geometry-only file extracts no attributes.
  EXPECT_EQ(SortedFacePositions(out), SortedFacePositions(OnGrid(c.mesh, r->info().grid)));
  LodCut cp;
  ASSERT_TRUE(RefineLod(*rp, Eye(0, 0.1, 0.6, size_t(1) << 30), cp).ok());
  IndexedMesh outPlain;
  LodAttributes ap;
  ASSERT_TRUE(ExtractCutMesh(*rp, cp, true, outPlain, nullptr, nullptr, &ap).ok());
  EXPECT_TRUE(ap.empty());

  // A coarse cut: 5 % of the faces. Every vertex's colour is the linear function at its place
  // (within rounding: the function is linear, clamped only outside the box); its normal faces
  // the way of the surface around it.
  LodCut coarse;
  ASSERT_TRUE(RefineLod(*r, Eye(0, 0.1, 0.6, c.mesh.faces.size() / 20, false), coarse).ok());
  IndexedMesh cm;
  ASSERT_TRUE(ExtractCutMesh(*r, coarse, true, cm, nullptr, nullptr, &a).ok());
  ASSERT_EQ(a.colors.size(), cm.positions.size());
  int worst = 0;
  size_t moved = 0;
  for (size_t v = 0; v < cm.positions.size(); ++v) {
    const auto want = attr::ColourAt(c.box, cm.positions[v]);
    moved += !inputAt.count(PosKey{{cm.positions[v][0], cm.positions[v][1], cm.positions[v][2]}});
    for (int i = 0; i < 4; ++i) worst = std::max(worst, std::abs(int(a.colors[v][size_t(i)]) - int(want[size_t(i)])));
  }
  EXPECT_GT(moved, cm.positions.size() / 2);  // most vertices were placed by the collapse
  EXPECT_LE(worst, 3) << "of 255";
  std::vector<vcg::Point3f> fn(cm.positions.size(), vcg::Point3f(0, 0, 0));
  for (const auto& t : cm.faces) {
    const vcg::Point3f n = (cm.positions[t[1]] - cm.positions[t[0]]) ^ (cm.positions[t[2]] - cm.positions[t[0]]);
    for (uint32_t v : t) fn[v] += n;
  }
  size_t facing = 0;
  for (size_t v = 0; v < cm.positions.size(); ++v) facing += attr::Angle(fn[v], DecodeLodNormal(a.normals[v])) < 1.0;
  EXPECT_GE(facing, cm.positions.size() * 95 / 100);
  // Colour shows the cut too: one more vertex stream, the same faces and positions.
  for (const std::string& p : {path, plain, plain2}) std::remove(p.c_str());
}

// Version 5 files: a flipped byte is refused or read cleanly, never a crash; the streams' flags
// must be the file's; a header naming an unknown stream is refused by name.
TEST(LodAttributes, BadVersion5FilesAreRefused) {
  // A small coloured sphere.
  const IndexedMesh im = test::Sphere(4);
  LodAttributes at;
  vcg::Box3f box;
  for (const auto& p : im.positions) box.Add(p);
  for (const auto& p : im.positions) {
    at.colors.push_back(attr::ColourAt(box, p));
    at.normals.push_back(EncodeLodNormal(p));
  }
  LodBuildParams params;
  params.clusterFaces = 32;
  params.groupClusters = 4;
  const std::string path = TempPath("sphere5.clod");
  ASSERT_TRUE(BuildLodFile(im, params, path, nullptr, Progress(), &at).ok());
  const std::vector<uint8_t> good = ReadBytes(path);
  std::remove(path.c_str());
  ASSERT_EQ(FullReadError(good), "");
  size_t refused = 0, tried = 0;
  const size_t header = kChunkHeaderBytes + size_t(DecodeChunkHeader(good.data()).dataBytes);
  const size_t stride = std::max<size_t>(1, good.size() / 600);
  for (size_t i = 0; i < good.size(); i += i < header ? 1 : stride) {
    std::vector<uint8_t> bad = good;
    bad[i] ^= 0x5A;
    if (!FullReadError(bad).empty()) ++refused;
    ++tried;
  }
  EXPECT_GE(refused, tried * 99 / 100) << "of " << tried << " flipped bytes";
  // The header's attributes field: unknown bits.
  const size_t field = header - kHeaderAttributeBytes;
  for (uint32_t mask : {16u, 2u | 32u}) {  // 0 is geometry only in version 6; 8 needs the UV fields
    std::vector<uint8_t> bad = good;
    PutU32(bad, field, mask);
    Rechecksum(bad, 0);
    EXPECT_NE(OpenError(bad).find("unknown attribute streams"), std::string::npos) << OpenError(bad);
  }
  // The header says colour only, or none (version 6: a geometry-only file): every unit's flags
  // then disagree.
  for (uint32_t mask : {uint32_t(kGeomColors), 0u}) {
    std::vector<uint8_t> bad = good;
    PutU32(bad, field, mask);
    Rechecksum(bad, 0);
    EXPECT_NE(FullReadError(bad).find("attribute streams are not the file's"), std::string::npos) << FullReadError(bad);
  }
  // Version 5 requires a stream.
  {
    std::vector<uint8_t> bad = good;
    PutU32(bad, kChunkHeaderBytes, 5);
    PutU32(bad, field, 0);
    Rechecksum(bad, 0);
    EXPECT_NE(OpenError(bad).find("unknown attribute streams"), std::string::npos) << OpenError(bad);
  }
  // Mislabelled as version 4: the header's size no longer fits.
  {
    std::vector<uint8_t> bad = good;
    PutU32(bad, kChunkHeaderBytes, 4);
    Rechecksum(bad, 0);
    EXPECT_NE(OpenError(bad), "");
  }
}

// --- Texture coordinates (version 5, bit 8) and the texture image (TEXR) ------------------------

namespace uv {

// A mesh with a texture atlas: each face's chart is the cell of its centroid in a k x k x k grid
// over the box; a vertex is repeated once per chart its faces use (as a PLY with per-vertex UVs,
// or per-face texcoord lists split by SplitWedgeTexCoords, has it), and its UV in chart c is
// (c % 8, c / 8) + 0.9 x its (x, y) in the box: linear in position within a chart, a seam
// wherever charts meet, junctions where three or more meet.
struct Textured {
  IndexedMesh mesh;  // split by chart
  LodAttributes attributes;
  vcg::Box3f box;
};
int ChartOf(const vcg::Box3f& box, const vcg::Point3f& c, int k) {
  int cell[3];
  for (int i = 0; i < 3; ++i)
    cell[i] = std::min(k - 1, std::max(0, int(k * (c[i] - box.min[i]) / std::max(1e-20f, box.max[i] - box.min[i]))));
  return (cell[2] * k + cell[1]) * k + cell[0];
}
std::array<float, 2> UvAt(const vcg::Box3f& box, const vcg::Point3f& p, int chart) {
  return {{float(chart % 8) + 0.9f * (p[0] - box.min[0]) / (box.max[0] - box.min[0]),
           float(chart / 8) + 0.9f * (p[1] - box.min[1]) / (box.max[1] - box.min[1])}};
}
Textured Atlas(const IndexedMesh& welded, int k, bool withTexture = true) {
  Textured t;
  for (const auto& p : welded.positions) t.box.Add(p);
  std::map<std::pair<uint32_t, int>, uint32_t> split;
  std::vector<std::array<float, 2>> uvs;
  for (const auto& f : welded.faces) {
    const vcg::Point3f c = (welded.positions[f[0]] + welded.positions[f[1]] + welded.positions[f[2]]) / 3.f;
    const int chart = ChartOf(t.box, c, k);
    std::array<uint32_t, 3> g;
    for (size_t i = 0; i < 3; ++i) {
      auto ins = split.emplace(std::make_pair(f[i], chart), uint32_t(t.mesh.positions.size()));
      if (ins.second) {
        t.mesh.positions.push_back(welded.positions[f[i]]);
        uvs.push_back(UvAt(t.box, welded.positions[f[i]], chart));
      }
      g[i] = ins.first->second;
    }
    t.mesh.faces.push_back(g);
  }
  for (int c = 0; c < 2; ++c) {
    t.attributes.uvMin[c] = std::numeric_limits<float>::infinity();
    t.attributes.uvMax[c] = -std::numeric_limits<float>::infinity();
    for (const auto& u : uvs) {
      t.attributes.uvMin[c] = std::min(t.attributes.uvMin[c], u[size_t(c)]);
      t.attributes.uvMax[c] = std::max(t.attributes.uvMax[c], u[size_t(c)]);
    }
  }
  for (const auto& u : uvs)
    t.attributes.texCoords.push_back(EncodeLodTexCoord(u.data(), t.attributes.uvMin, t.attributes.uvMax));
  if (withTexture) {
    t.attributes.texture.name = "atlas.png";
    t.attributes.texture.bytes = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
    for (int i = 0; i < 3000; ++i) t.attributes.texture.bytes.push_back(uint8_t(i * 7));
    t.attributes.texture.mime = LodTextureMime(t.attributes.texture.name, t.attributes.texture.bytes);
  }
  return t;
}
// Distinct (grid position, chart) pairs of a mesh split by chart: its wedges as the file keeps them.
size_t Wedges(const IndexedMesh& m, const LodAttributes& a, const LodGrid& grid) {
  std::set<std::pair<PosKey, std::array<uint16_t, 2>>> w;
  for (const auto& f : m.faces)
    for (uint32_t v : f) {
      const vcg::Point3f p = grid.Round(m.positions[v]);
      w.insert({PosKey{{p[0], p[1], p[2]}}, a.texCoords[v]});
    }
  return w.size();
}
// Each face of a cut lies in one chart (its corners' UVs on one chart's tile), and each corner's
// UV is its chart's linear function of its position within `tolerance` (a chart's UV span is
// 0.9). Returns the faces whose corners are on different charts.
size_t FacesAcrossCharts(const IndexedMesh& m, const LodAttributes& a, const vcg::Box3f& box, double tolerance,
                         double* worst) {
  size_t across = 0;
  *worst = 0;
  for (const auto& f : m.faces) {
    float uv[3][2];
    for (size_t i = 0; i < 3; ++i) DecodeLodTexCoord(a.texCoords[f[i]], a.uvMin, a.uvMax, uv[i]);
    // (A chart's tile is [c, c + 0.9]: its UVs rounded below c still name it.)
    const int cu = int(std::floor(uv[0][0] + 0.05f)), cv = int(std::floor(uv[0][1] + 0.05f));
    bool same = true;
    for (size_t i = 1; i < 3; ++i)
      same &= int(std::floor(uv[i][0] + 0.05f)) == cu && int(std::floor(uv[i][1] + 0.05f)) == cv;
    if (!same) {
      ++across;
      continue;
    }
    for (size_t i = 0; i < 3; ++i) {
      const auto want = UvAt(box, m.positions[f[i]], cv * 8 + cu);
      *worst = std::max({*worst, std::fabs(double(uv[i][0]) - want[0]), std::fabs(double(uv[i][1]) - want[1])});
    }
  }
  EXPECT_LE(*worst, tolerance);
  return across;
}

}  // namespace uv

// Each level's groups are simplified and re-cut into clusters side by side, their vertices marked
// and the next level assembled on the threads: the file does not depend on their number, built
// whole (BuildLevels) and with texture seams (places), the latter in chunks too
// (GroupClustersByChunk). (LodChunks.FileDoesNotDependOnThreads: the bunny in chunks; LodStream:
// the streamed build.)
TEST(LodBuild, FileDoesNotDependOnThreads) {
  const IndexedMesh torus = Torus(96, 48, 1.f, 0.35f);  // 9216 faces
  const uv::Textured t = uv::Atlas(torus, 3);
  std::vector<uint8_t> plain[2], textured[2], chunked[2];
  const int threads[2] = {1, 3};
  for (int i = 0; i < 2; ++i) {
    LodBuildParams p;
    p.simplification.threads = threads[i];
    const std::string path = TempPath("threads_" + std::to_string(threads[i]) + ".clod");
    LodBuildStats st;
    ASSERT_TRUE(BuildLodFile(torus, p, path, &st).ok());
    EXPECT_GT(st.levels, 5);
    plain[i] = ReadBytes(path);
    ASSERT_TRUE(BuildLodFile(t.mesh, p, path, &st, Progress(), &t.attributes).ok());
    EXPECT_GT(st.texCoordBytes, 0u);
    textured[i] = ReadBytes(path);
    p.chunkFaces = 1200;
    ASSERT_TRUE(BuildLodFile(t.mesh, p, path, &st, Progress(), &t.attributes).ok());
    EXPECT_EQ(st.chunks, 8u);
    chunked[i] = ReadBytes(path);
    std::remove(path.c_str());
  }
  ASSERT_FALSE(plain[0].empty());
  EXPECT_EQ(plain[0], plain[1]);
  EXPECT_EQ(textured[0], textured[1]);
  EXPECT_EQ(chunked[0], chunked[1]);
  EXPECT_NE(textured[0], chunked[0]);
}

// The UV stream: a textured torus (27 charts) gives a version 5 file with bit 8 and its texture;
// at full budget the cut is the input's faces with one vertex per (position, UV), each UV within
// LodTexCoordErrorBound of the input's; a coarse cut has no face across charts and its UVs are
// the charts' linear functions at the moved vertices; the texture reads back byte for byte.
TEST(LodTexCoords, UvStreamRoundTripIsExactUpToTheQuantization) {
  const uv::Textured t = uv::Atlas(Torus(96, 48, 1.f, 0.35f), 3);
  const std::string path = TempPath("textured.clod");
  LodBuildStats st;
  const Status b = BuildLodFile(t.mesh, LodBuildParams(), path, &st, Progress(), &t.attributes);
  ASSERT_TRUE(b.ok()) << b.message;
  EXPECT_GT(st.texCoordBytes, 0u);
  EXPECT_EQ(st.textureBytes, t.attributes.texture.bytes.size());
  EXPECT_EQ(st.fileBytes, ReadBytes(path).size());
  std::unique_ptr<LodReader> r;
  ASSERT_TRUE(LodReader::Open(path, r).ok());
  const LodFileInfo& info = r->info();
  EXPECT_EQ(info.version, 9u);
  EXPECT_TRUE(info.texCoords);
  EXPECT_FALSE(info.colors || info.normals);
  EXPECT_EQ(info.textureName, "atlas.png");
  EXPECT_EQ(info.textureMime, "image/png");
  EXPECT_EQ(info.textureBytes, t.attributes.texture.bytes.size());
  for (int c = 0; c < 2; ++c) {
    EXPECT_EQ(info.uvMin[c], t.attributes.uvMin[c]);
    EXPECT_EQ(info.uvMax[c], t.attributes.uvMax[c]);
  }
  LodTexture tex;
  ASSERT_TRUE(r->LoadTexture(tex).ok());
  EXPECT_EQ(tex.bytes, t.attributes.texture.bytes);
  EXPECT_EQ(tex.name, "atlas.png");
  std::printf(
      "textured torus: %zu levels, %llu bytes, of which UVs %llu, texture %llu; level faces:", info.levelFaces.size(),
      (unsigned long long)st.fileBytes, (unsigned long long)st.texCoordBytes, (unsigned long long)st.textureBytes);
  for (auto f : info.levelFaces) std::printf(" %llu", (unsigned long long)f);
  std::printf("\n");
  EXPECT_LT(info.levelFaces.back() * 2, info.levelFaces[0]) << "the levels should go down";

  // Full budget: every input wedge back once, its UV within the bound.
  LodCut cut;
  ASSERT_TRUE(RefineLod(*r, Eye(0, 0.2, 4, size_t(1) << 30), cut).ok());
  IndexedMesh out;
  LodAttributes a;
  ASSERT_TRUE(ExtractCutMesh(*r, cut, true, out, nullptr, nullptr, &a).ok());
  ASSERT_EQ(a.texCoords.size(), out.positions.size());
  EXPECT_EQ(out.faces.size(), t.mesh.faces.size());
  EXPECT_EQ(out.positions.size(), uv::Wedges(t.mesh, t.attributes, info.grid));
  EXPECT_EQ(SortedFacePositions(out), SortedFacePositions(OnGrid(t.mesh, info.grid)));
  std::map<PosKey, std::vector<std::array<float, 2>>> inputAt;
  for (size_t v = 0; v < t.mesh.positions.size(); ++v) {
    const vcg::Point3f p = info.grid.Round(t.mesh.positions[v]);
    float in[2];
    DecodeLodTexCoord(t.attributes.texCoords[v], t.attributes.uvMin, t.attributes.uvMax, in);
    inputAt[PosKey{{p[0], p[1], p[2]}}].push_back({{in[0], in[1]}});
  }
  const double bound = LodTexCoordErrorBound(info.uvMin, info.uvMax);
  double worst = 0;
  for (size_t v = 0; v < out.positions.size(); ++v) {
    const auto it = inputAt.find(PosKey{{out.positions[v][0], out.positions[v][1], out.positions[v][2]}});
    ASSERT_TRUE(it != inputAt.end());
    float got[2];
    DecodeLodTexCoord(a.texCoords[v], a.uvMin, a.uvMax, got);
    double best = HUGE_VAL;
    for (const auto& w : it->second)
      best = std::min(best, std::max(std::fabs(double(w[0]) - got[0]), std::fabs(double(w[1]) - got[1])));
    worst = std::max(worst, best);
  }
  EXPECT_EQ(worst, 0.0) << "the input's codes are stored as they are";
  // Against the input's float UVs: within the stated quantization bound.
  double worstFloat = 0;
  for (size_t v = 0; v < t.mesh.positions.size(); ++v) {
    const vcg::Point3f c = t.mesh.positions[v];
    float back[2];
    DecodeLodTexCoord(t.attributes.texCoords[v], info.uvMin, info.uvMax, back);
    const int chart = int(std::floor(back[1] + 0.05f)) * 8 + int(std::floor(back[0] + 0.05f));
    const auto exact = uv::UvAt(t.box, c, chart);
    worstFloat = std::max({worstFloat, std::fabs(double(exact[0]) - back[0]), std::fabs(double(exact[1]) - back[1])});
  }
  EXPECT_LE(worstFloat, bound);
  std::printf("UV quantization: largest error %.3g, bound %.3g (UV box %g x %g)\n", worstFloat, bound,
              double(info.uvMax[0] - info.uvMin[0]), double(info.uvMax[1] - info.uvMin[1]));
  double lin = 0;
  EXPECT_EQ(uv::FacesAcrossCharts(out, a, t.box, 2 * bound + 1e-6, &lin), 0u);

  // Coarse cuts: no face across a seam, UVs linear in position within each chart.
  for (size_t budget : {t.mesh.faces.size() / 20, t.mesh.faces.size() / 4}) {
    LodCut coarse;
    ASSERT_TRUE(RefineLod(*r, Eye(0, 0.2, 4, budget, false), coarse).ok());
    IndexedMesh cm;
    ASSERT_TRUE(ExtractCutMesh(*r, coarse, true, cm, nullptr, nullptr, &a).ok());
    EXPECT_LT(cm.faces.size(), t.mesh.faces.size() * 3 / 4);
    size_t moved = 0;
    for (const auto& p : cm.positions) moved += !inputAt.count(PosKey{{p[0], p[1], p[2]}});
    EXPECT_GT(moved, 0u) << "no vertex moved: interpolation not exercised";
    EXPECT_EQ(uv::FacesAcrossCharts(cm, a, t.box, 0.01, &lin), 0u) << "a face drags its UVs across a seam";
    std::printf("cut of %zu faces: %zu moved vertices, UV off the charts' linear function by %.3g at most\n",
                cm.faces.size(), moved, lin);
  }
  std::remove(path.c_str());

  // Without the image the file has the UV stream only; with neither, the geometry-only file.
  uv::Textured bare = uv::Atlas(Torus(24, 12, 1.f, 0.35f), 2, false);
  const std::string p2 = TempPath("uv_only.clod");
  ASSERT_TRUE(BuildLodFile(bare.mesh, LodBuildParams(), p2, nullptr, Progress(), &bare.attributes).ok());
  ASSERT_TRUE(LodReader::Open(p2, r).ok());
  EXPECT_TRUE(r->info().texCoords);
  EXPECT_EQ(r->info().textureBytes, 0u);
  EXPECT_FALSE(r->LoadTexture(tex).ok());
  std::remove(p2.c_str());
}

// Cracks: every cut of textured watertight meshes (a sphere and a torus, their atlases' seams and
// junctions) is watertight by position, as the untextured ones (ExpectCrackFree's checks).
void ExpectTexturedCrackFree(const IndexedMesh& welded, int k, const std::string& name) {
  const uv::Textured t = uv::Atlas(welded, k);
  Built b;
  b.mesh = t.mesh;
  b.path = TempPath(name + ".clod");
  ASSERT_TRUE(BuildLodFile(b.mesh, LodBuildParams(), b.path, nullptr, Progress(), &t.attributes).ok());
  std::unique_ptr<LodReader> r;
  ASSERT_TRUE(LodReader::Open(b.path, r).ok());
  ASSERT_TRUE(r->info().texCoords);
  const EdgeMap input = EdgesByPosition(OnGrid(b.mesh, r->info().grid));
  size_t inputBorder = 0;
  for (const auto& e : input) inputBorder += e.second != 2;
  ASSERT_EQ(inputBorder, 0u);
  const vcg::Point3d c = vcg::Point3d::Construct(r->info().box.Center());
  const double d = r->info().box.Diag();
  const size_t F = b.mesh.faces.size();
  size_t mixed = 0, cuts = 0;
  for (const vcg::Point3d& eye : {c + vcg::Point3d(0, 0, 2 * d), c + vcg::Point3d(1.5 * d, 0.3 * d, 0),
                                  c + vcg::Point3d(0.3 * d, 0.1 * d, 0.45 * d)})
    for (double pct : {0.0, 5.0, 20.0, 50.0, 100.0})
      for (bool cull : {true, false}) {
        LodCut cut;
        ASSERT_TRUE(RefineLod(*r, Eye(eye[0], eye[1], eye[2], size_t(double(F) * pct / 100), cull), cut).ok());
        SCOPED_TRACE(name + " budget " + std::to_string(pct) + "% cull " + std::to_string(cull));
        const CrackCount k2 = CheckCut(b, *r, cut, &input);
        EXPECT_EQ(k2.border, 0u);
        EXPECT_EQ(k2.overused, 0u);
        EXPECT_EQ(k2.drawnBorderNotCulled, 0u);
        if (pct == 100) {
          EXPECT_EQ(cut.faces, F);
        }
        ++cuts;
        mixed += cut.maxLevelDifference > 0;
      }
  EXPECT_GT(mixed, cuts / 3) << "most cuts should mix levels (else the test proves little)";
  std::remove(b.path.c_str());
}

// Every stream (colours, normals, texture coordinates, the texture image) at 1 and 3 writer
// threads, in memory and spilled in chunks: the same bytes.
TEST(LodTexCoords, AttributeFileDoesNotDependOnWriterThreads) {
  uv::Textured t = uv::Atlas(Torus(96, 48, 1.f, 0.35f), 3);
  for (const auto& p : t.mesh.positions) {
    t.attributes.colors.push_back(attr::ColourAt(t.box, p));
    t.attributes.normals.push_back(EncodeLodNormal(p.Norm() > 0 ? p / p.Norm() : p));
  }
  for (size_t chunkFaces : {size_t(0), size_t(2048)}) {
    std::vector<uint8_t> bytes[2];
    uint64_t streams[2] = {0, 0};
    for (int i = 0; i < 2; ++i) {
      LodBuildParams p;
      p.chunkFaces = chunkFaces;
      p.simplification.threads = i == 0 ? 1 : 3;
      const std::string path = TempPath("attr_threads.clod");
      LodBuildStats st;
      const Status s = BuildLodFile(t.mesh, p, path, &st, Progress(), &t.attributes);
      ASSERT_TRUE(s.ok()) << s.message;
      EXPECT_GT(st.colorBytes, 0u);
      EXPECT_GT(st.normalBytes, 0u);
      EXPECT_GT(st.texCoordBytes, 0u);
      EXPECT_GT(st.nodes, 100u);
      streams[i] = st.colorBytes + st.normalBytes + st.texCoordBytes;
      bytes[i] = ReadBytes(path);
      std::remove(path.c_str());
    }
    SCOPED_TRACE("chunkFaces " + std::to_string(chunkFaces));
    EXPECT_TRUE(bytes[0] == bytes[1]);
    EXPECT_EQ(streams[0], streams[1]);
  }
}

TEST(LodTexCoords, TexturedSphereCutsAreWatertight) { ExpectTexturedCrackFree(test::Sphere(5), 3, "tex_sphere"); }
TEST(LodTexCoords, TexturedTorusCutsAreWatertight) {
  ExpectTexturedCrackFree(Torus(96, 48, 1.f, 0.35f), 4, "tex_torus");
}

// The textured dragon of `scripts/get_test_meshes.sh attributes` (per-vertex UVs repeated along
// its seams, a real UV atlas of 21,142 seam positions): its cuts are watertight by position and no face of a
// coarse cut has UVs from two charts. The mesh is fetched into deps/test_meshes (or
// CONELOD_ATTRIBUTE_MESHES); the test says so and passes without it.
TEST(LodTexCoords, TexturedDragonCutsAreWatertight) {
  const char* env = std::getenv("CONELOD_ATTRIBUTE_MESHES");
  const std::string dir = env ? env : std::string(CONELOD_SOURCE_DIR) + "/deps/test_meshes";
  PlyMesh ply;
  if (!ReadPly(dir + "/dragon_textured.ply", ply).empty()) {
    std::printf("no %s/dragon_textured.ply (scripts/get_test_meshes.sh attributes): not checked\n", dir.c_str());
    return;
  }
  if (!ply.wedgeTexCoords.empty()) SplitWedgeTexCoords(ply);
  ASSERT_FALSE(ply.texCoords.empty());
  Built b;
  for (const auto& p : ply.positions) b.mesh.positions.emplace_back(p[0], p[1], p[2]);
  b.mesh.faces = ply.triangles;
  LodAttributes a;
  for (int c = 0; c < 2; ++c) {
    a.uvMin[c] = std::numeric_limits<float>::infinity();
    a.uvMax[c] = -std::numeric_limits<float>::infinity();
    for (const auto& t : ply.texCoords) {
      a.uvMin[c] = std::min(a.uvMin[c], t[size_t(c)]);
      a.uvMax[c] = std::max(a.uvMax[c], t[size_t(c)]);
    }
  }
  for (const auto& t : ply.texCoords) a.texCoords.push_back(EncodeLodTexCoord(t.data(), a.uvMin, a.uvMax));
  b.path = TempPath("dragon_textured.clod");
  LodBuildStats st;
  ASSERT_TRUE(BuildLodFile(b.mesh, LodBuildParams(), b.path, &st, Progress(), &a).ok());
  std::unique_ptr<LodReader> r;
  ASSERT_TRUE(LodReader::Open(b.path, r).ok());
  std::printf("textured dragon: %zu faces, %zu levels, level faces:", b.mesh.faces.size(), size_t(r->info().levels));
  for (auto f : r->info().levelFaces) std::printf(" %llu", (unsigned long long)f);
  std::printf("\n");
  const EdgeMap input = EdgesByPosition(OnGrid(b.mesh, r->info().grid));
  const size_t F = b.mesh.faces.size();
  const vcg::Point3d c = vcg::Point3d::Construct(r->info().box.Center());
  const double d = r->info().box.Diag();
  for (const vcg::Point3d& eye : {c + vcg::Point3d(0, 0, 2 * d), c + vcg::Point3d(0.6 * d, 0.2 * d, -0.5 * d)})
    for (double pct : {0.0, 5.0, 20.0, 50.0, 100.0}) {
      LodCut cut;
      ASSERT_TRUE(RefineLod(*r, Eye(eye[0], eye[1], eye[2], size_t(double(F) * pct / 100)), cut).ok());
      SCOPED_TRACE("textured dragon budget " + std::to_string(pct) + "%");
      const CrackCount k = CheckCut(b, *r, cut, &input);
      EXPECT_EQ(k.border, 0u);
      EXPECT_EQ(k.overused, 0u);
      EXPECT_EQ(k.drawnBorderNotCulled, 0u);
      if (pct == 100) {
        EXPECT_EQ(cut.faces, F);
      }
    }
  std::remove(b.path.c_str());
}

// The texture chunk: a flipped byte of its image is caught by LoadTexture's CRC (the file still
// opens: the image is read on demand), a bad name or size by Open; a header whose attributes say
// texture coordinates without the UV box (or the reverse) is refused.
TEST(LodTexCoords, BadTextureChunksAreRefused) {
  const uv::Textured t = uv::Atlas(test::Sphere(3), 2);
  const std::string path = TempPath("tex_bad.clod");
  ASSERT_TRUE(BuildLodFile(t.mesh, LodBuildParams(), path, nullptr, Progress(), &t.attributes).ok());
  const std::vector<uint8_t> good = ReadBytes(path);
  std::remove(path.c_str());
  ASSERT_EQ(FullReadError(good), "");
  const size_t header = kChunkHeaderBytes + size_t(DecodeChunkHeader(good.data()).dataBytes);
  const ChunkHeader th = DecodeChunkHeader(good.data() + header);  // the TEXR chunk follows the header
  ASSERT_EQ(th.id, kTexture);
  const size_t image = header + kChunkHeaderBytes + kTextureFixedBytes + 9 + 9;  // "atlas.png", "image/png"
  {
    std::vector<uint8_t> bad = good;
    bad[image + 100] ^= 0x5A;
    std::unique_ptr<LodReader> r = OpenOk(bad);
    ASSERT_TRUE(r);
    LodTexture tex;
    const Status s = r->LoadTexture(tex);
    EXPECT_NE(s.message.find("checksum mismatch in the texture chunk"), std::string::npos) << s.message;
  }
  {
    std::vector<uint8_t> bad = good;
    bad[header + kChunkHeaderBytes + kTextureFixedBytes] = '/';  // the name: "/tlas.png"
    EXPECT_NE(OpenError(bad).find("not a plain file name"), std::string::npos) << OpenError(bad);
  }
  {
    std::vector<uint8_t> bad = good;
    PutU32(bad, header + kChunkHeaderBytes, 300);  // a name longer than the chunk allows
    EXPECT_NE(OpenError(bad).find("corrupt chunk size in the texture chunk"), std::string::npos) << OpenError(bad);
  }
  {
    std::vector<uint8_t> bad = good;
    PutU32(bad, header, kHier);  // not a TEXR chunk
    EXPECT_NE(OpenError(bad).find("expected a TEXR chunk"), std::string::npos) << OpenError(bad);
  }
  // The attributes field without bit 8 while the header holds the UV box.
  {
    std::vector<uint8_t> bad = good;
    PutU32(bad, header - kHeaderAttributeBytes - kHeaderTexCoordBytes, kGeomColors);
    Rechecksum(bad, 0);
    EXPECT_NE(OpenError(bad).find("does not match its attribute streams"), std::string::npos) << OpenError(bad);
  }
  // Flipped bytes all over: refused or read cleanly (the image's own bytes only by LoadTexture).
  size_t refused = 0, tried = 0;
  const size_t stride = std::max<size_t>(1, good.size() / 500);
  for (size_t i = 0; i < good.size(); i += i < image ? 1 : stride) {
    std::vector<uint8_t> bad = good;
    bad[i] ^= 0x5A;
    std::string e = FullReadError(bad);
    if (e.empty()) {
      std::unique_ptr<LodReader> r = OpenOk(bad);
      LodTexture tex;
      if (r && !r->LoadTexture(tex).ok()) e = "texture";
    }
    refused += !e.empty();
    ++tried;
  }
  EXPECT_GE(refused, tried * 99 / 100) << "of " << tried << " flipped bytes";
}

// Issue 27's out-of-core build: with chunkFaces BuildLodFile spills each finished level to a
// temporary folder beside the output and writes the file from there (lod_spill.h).

// The names in a folder (without . and ..), sorted.
std::vector<std::string> Listing(const std::string& dir) {
  std::vector<std::string> names;
  if (DIR* d = opendir(dir.c_str())) {
    while (dirent* e = readdir(d)) {
      const std::string n = e->d_name;
      if (n != "." && n != "..") names.push_back(n);
    }
    closedir(d);
  }
  std::sort(names.begin(), names.end());
  return names;
}

// A new empty folder of its own for one test's output.
std::string FreshFolder(const std::string& name) {
  std::string pattern = TempPath(name + ".XXXXXX");
  std::vector<char> buf(pattern.begin(), pattern.end());
  buf.push_back(0);
  EXPECT_NE(mkdtemp(buf.data()), nullptr);
  return buf.data();
}

// Watches the output's folder while a build runs: the most level files seen at once in a
// temporary folder of the build (.NAME.conelod-lod-*).
struct SpillWatch {
  std::string dir;
  size_t mostLevelFiles = 0;
  int calls = 0, cancelAt = -1;  // cancelAt: the progress call that cancels (after level files)
  Progress progress() {
    return [this](int, const char*) {
      size_t files = 0;
      for (const std::string& n : Listing(dir))
        if (n.find(".conelod-lod-") != std::string::npos) files += Listing(dir + "/" + n).size();
      mostLevelFiles = std::max(mostLevelFiles, files);
      ++calls;
      return !(cancelAt >= 0 && calls >= cancelAt && files > 0);
    };
  }
};

IndexedMesh WeldedBunny() {
  CMesh m;
  EXPECT_EQ(LoadPly(m, test::MeshPath("stanford_bunny_bun_zipper.ply")), "");
  return WeldByPosition(ToIndexedMesh(m)).mesh;
}

// The spilled build (both overloads) gives the in-memory chunked build's file byte for byte, its
// levels went through the folder, and the folder is gone afterwards: only the file is left.
TEST(LodSpill, SpilledBuildIsTheInMemoryFileAndLeavesOnlyTheFile) {
  Built memory;
  memory.mesh = WeldedBunny();
  Build(memory, "bunny_in_memory", Chunked(4096, 2));
  const std::string dir = FreshFolder("spill_ok");
  for (bool taken : {false, true}) {
    SpillWatch watch;
    watch.dir = dir;
    const std::string out = dir + "/bunny.clod";
    LodBuildStats st;
    IndexedMesh copy = memory.mesh;
    const Status s = taken ? BuildLodFile(std::move(copy), Chunked(4096, 2), out, &st, watch.progress())
                           : BuildLodFile(copy, Chunked(4096, 2), out, &st, watch.progress());
    ASSERT_TRUE(s.ok()) << s.message;
    EXPECT_EQ(st.chunks, 32u);  // 69,451 faces in chunks of 4,096
    EXPECT_GE(watch.mostLevelFiles, 3u) << "the levels were not spilled";
    EXPECT_EQ(ReadBytes(out), memory.bytes) << (taken ? "taken" : "copied");
    EXPECT_EQ(Listing(dir), std::vector<std::string>{"bunny.clod"});
    std::remove(out.c_str());
  }
  // Without chunks nothing is spilled, and the taken mesh gives the same file too.
  Built plain;
  plain.mesh = memory.mesh;
  Build(plain, "bunny_plain");
  SpillWatch watch;
  watch.dir = dir;
  IndexedMesh copy = plain.mesh;
  ASSERT_TRUE(BuildLodFile(std::move(copy), LodBuildParams(), dir + "/plain.clod", nullptr, watch.progress()).ok());
  EXPECT_EQ(watch.mostLevelFiles, 0u);
  EXPECT_EQ(ReadBytes(dir + "/plain.clod"), plain.bytes);
  std::remove((dir + "/plain.clod").c_str());
  rmdir(dir.c_str());
  for (Built* b : {&memory, &plain}) std::remove(b->path.c_str());
}

// A build that fails after levels were spilled leaves nothing behind: cancelled midway, or an
// output that cannot be written (a folder), found only by the writer.
TEST(LodSpill, FolderIsGoneAfterAFailure) {
  const IndexedMesh bunny = WeldedBunny();
  const std::string dir = FreshFolder("spill_fail");
  {
    SpillWatch watch;
    watch.dir = dir;
    watch.cancelAt = 3;
    const Status s = BuildLodFile(bunny, Chunked(4096), dir + "/cancelled.clod", nullptr, watch.progress());
    EXPECT_FALSE(s.ok());
    EXPECT_GE(watch.mostLevelFiles, 1u);
    EXPECT_EQ(Listing(dir), std::vector<std::string>{});
  }
  {
    const std::string folder = dir + "/a_folder.clod";
    ASSERT_EQ(mkdir(folder.c_str(), 0755), 0);
    SpillWatch watch;
    watch.dir = dir;
    IndexedMesh copy = bunny;
    const Status s = BuildLodFile(std::move(copy), Chunked(4096), folder, nullptr, watch.progress());
    EXPECT_FALSE(s.ok());
    EXPECT_GE(watch.mostLevelFiles, 3u);
    EXPECT_EQ(Listing(dir), std::vector<std::string>{"a_folder.clod"});
    EXPECT_EQ(Listing(folder), std::vector<std::string>{});
    rmdir(folder.c_str());
  }
  {  // a folder that cannot hold the temporary folder: refused before any work
    const std::string missing = dir + "/missing/out.clod";
    const Status s = BuildLodFile(bunny, Chunked(4096), missing, nullptr);
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.message.find("cannot write '"), std::string::npos) << s.message;
  }
  EXPECT_EQ(Listing(dir), std::vector<std::string>{});
  rmdir(dir.c_str());
}

// The in-place weld is WeldByPosition's, on a mesh with repeated and unreferenced vertices.
TEST(LodSpill, InPlaceWeldIsTheWeld) {
  IndexedMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {9, 9, 9}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {-0.f, 0, 0}};
  m.faces = {{{0, 1, 2}}, {{4, 6, 5}}, {{7, 4, 5}}};
  const WeldResult w = WeldByPosition(m);
  size_t merged = 0, dropped = 0;
  ASSERT_TRUE(WeldByPositionInPlace(m, &merged, &dropped));
  EXPECT_EQ(m.positions, w.mesh.positions);
  EXPECT_EQ(m.faces, w.mesh.faces);
  EXPECT_EQ(merged, w.mergedVertices);
  EXPECT_EQ(dropped, w.droppedVertices);
  EXPECT_EQ(merged, 3u);
  EXPECT_EQ(dropped, 1u);
  IndexedMesh bad;
  bad.positions = {{0, 0, 0}};
  bad.faces = {{{0, 0, 5}}};
  EXPECT_FALSE(WeldByPositionInPlace(bad));
  EXPECT_EQ(bad.faces[0][2], 5u);
}

// --- The streamed build (BuildLodFileFromPly, lod build --memory; docs/scale.md) -------------------

// A PLY file read as `lod build` reads it (ReadPly), welded.
IndexedMesh ReadWelded(const std::string& path) {
  PlyMesh ply;
  EXPECT_EQ(ReadPly(path, ply), "");
  IndexedMesh m;
  for (const auto& p : ply.positions) m.positions.emplace_back(p[0], p[1], p[2]);
  m.faces = ply.triangles;
  return WeldByPosition(m).mesh;
}

// With every face in the sample the chunks are KdChunks's: the streamed build's file is the
// in-memory chunked build's (hence the spilled one's) byte for byte, for 1 and 2 threads; the
// faces went through chunk files, and only the file is left. A sample of 1,000 faces gives other
// chunks (another file), the same for 1 and 2 threads.
TEST(LodStream, FullSampleIsTheChunkedBuildAndSamplesAreDeterministic) {
  const std::string bunny = test::MeshPath("stanford_bunny_bun_zipper.ply");
  Built memory;
  memory.mesh = ReadWelded(bunny);
  Build(memory, "bunny_chunks_memory", Chunked(4096, 2));
  ASSERT_FALSE(memory.bytes.empty());
  const std::string dir = FreshFolder("stream_ok");
  std::vector<uint8_t> sampled[2];
  for (int threads : {1, 2}) {
    SpillWatch watch;
    watch.dir = dir;
    const std::string out = dir + "/bunny.clod";
    LodBuildStats st;
    Status s = BuildLodFileFromPly(bunny, Chunked(4096, threads), out, &st, watch.progress(), nullptr, 1 << 20);
    ASSERT_TRUE(s.ok()) << s.message;
    EXPECT_EQ(st.chunks, 32u);
    EXPECT_EQ(st.inputFaces, memory.mesh.faces.size());
    EXPECT_GE(watch.mostLevelFiles, 17u) << "the faces did not go through chunk files";
    EXPECT_EQ(ReadBytes(out), memory.bytes) << threads << " threads";
    EXPECT_EQ(Listing(dir), std::vector<std::string>{"bunny.clod"});
    std::remove(out.c_str());
    s = BuildLodFileFromPly(bunny, Chunked(4096, threads), out, &st, Progress(), nullptr, 1000);
    ASSERT_TRUE(s.ok()) << s.message;
    sampled[threads - 1] = ReadBytes(out);
    EXPECT_EQ(Listing(dir), std::vector<std::string>{"bunny.clod"});
    std::remove(out.c_str());
  }
  EXPECT_EQ(sampled[0], sampled[1]);
  EXPECT_NE(sampled[0], memory.bytes);
  // One chunk: the unchunked path, the file of BuildLodFile without chunks.
  Built plain;
  plain.mesh = memory.mesh;
  Build(plain, "bunny_stream_plain");
  ASSERT_TRUE(BuildLodFileFromPly(bunny, Chunked(1 << 20), dir + "/one.clod").ok());
  EXPECT_EQ(ReadBytes(dir + "/one.clod"), plain.bytes);
  std::remove((dir + "/one.clod").c_str());
  // Bad input: the reader's message, nothing left behind.
  {
    const std::string bad = dir + "/bad.ply";
    std::ofstream(bad) << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                          "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
                          "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 7\n";
    std::string readError;
    const Status s = BuildLodFileFromPly(bad, Chunked(1), dir + "/bad.clod", nullptr, Progress(), &readError);
    EXPECT_FALSE(s.ok());
    EXPECT_NE(readError.find("uses vertex 7"), std::string::npos) << readError;
    std::remove(bad.c_str());
  }
  EXPECT_EQ(Listing(dir), std::vector<std::string>{});
  rmdir(dir.c_str());
  std::remove(memory.path.c_str());
  std::remove(plain.path.c_str());
}

// The front of the streamed build on several threads (the weld's sort in 2 to 8 parts, the faces
// given their chunks a block at a time, level 0 a wave of up to 4 chunks at a time): a generated
// triangle soup (12,800 faces of a wavy grid, each face with its own three vertices, so that the
// weld merges 38,400 vertices into 6,561, plus an unused one), binary and ASCII, in 16 chunks, is
// the in-memory chunked build of the welded grid byte for byte at 1, 2 and 5 threads.
TEST(LodStream, ThreadsGiveTheChunkedBuildOfASoup) {
  const int n = 80;
  IndexedMesh soup;
  auto at = [&](int i, int j) {
    return vcg::Point3f(float(i) / n, float(j) / n, 0.05f * std::sin(0.4f * float(i)) * std::cos(0.3f * float(j)));
  };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {  // two triangles a cell, every corner a vertex of its own
      for (const auto& t : {std::array<std::array<int, 2>, 3>{{{{i, j}}, {{i + 1, j}}, {{i + 1, j + 1}}}},
                            std::array<std::array<int, 2>, 3>{{{{i, j}}, {{i + 1, j + 1}}, {{i, j + 1}}}}}) {
        const uint32_t v = uint32_t(soup.positions.size());
        for (const auto& c : t) soup.positions.push_back(at(c[0], c[1]));
        soup.faces.push_back({{v, v + 1, v + 2}});
      }
    }
  soup.positions.push_back(vcg::Point3f(5, 5, 5));  // unused
  Built memory;
  memory.mesh = WeldByPosition(soup).mesh;
  ASSERT_EQ(memory.mesh.positions.size(), size_t((n + 1) * (n + 1)));
  Build(memory, "soup_chunks_memory", Chunked(1024, 2));
  ASSERT_FALSE(memory.bytes.empty());
  const std::string dir = FreshFolder("stream_soup");
  for (bool ascii : {false, true}) {
    const std::string ply = dir + (ascii ? "/soup_ascii.ply" : "/soup.ply");
    {
      std::ofstream out(ply, std::ios::binary);
      out << "ply\nformat " << (ascii ? "ascii" : "binary_little_endian") << " 1.0\nelement vertex "
          << soup.positions.size() << "\nproperty float x\nproperty float y\nproperty float z\nelement face "
          << soup.faces.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
      out.precision(9);
      for (const auto& p : soup.positions) {
        if (ascii) {
          out << p[0] << " " << p[1] << " " << p[2] << "\n";
        } else {
          out.write(reinterpret_cast<const char*>(&p[0]), 12);
        }
      }
      for (const auto& t : soup.faces) {
        if (ascii) {
          out << "3 " << t[0] << " " << t[1] << " " << t[2] << "\n";
        } else {
          out.put(3);
          out.write(reinterpret_cast<const char*>(t.data()), 12);
        }
      }
    }
    for (int threads : {1, 2, 5}) {
      const std::string out = dir + "/soup.clod";
      LodBuildStats st;
      const Status s = BuildLodFileFromPly(ply, Chunked(1024, threads), out, &st, Progress(), nullptr, 1 << 20);
      ASSERT_TRUE(s.ok()) << s.message;
      EXPECT_EQ(st.chunks, 16u);
      EXPECT_EQ(st.mergedVertices, soup.positions.size() - 1 - memory.mesh.positions.size());
      EXPECT_EQ(st.droppedVertices, 1u);
      EXPECT_EQ(ReadBytes(out), memory.bytes) << threads << " threads" << (ascii ? ", ASCII" : "");
      std::remove(out.c_str());
    }
    std::remove(ply.c_str());
  }
  EXPECT_EQ(Listing(dir), std::vector<std::string>{});
  rmdir(dir.c_str());
  std::remove(memory.path.c_str());
}

// Small chunks (the bunny in chunks of 48 to 1,024 faces: 2,048 to 128 chunks, each level built
// from the spill a kd chunk at a time until they merge, StreamLevels): the file is the in-memory
// chunked build's (levels above 0 built whole, BuildLevels), byte for byte, on 2 threads.
TEST(LodStream, SmallChunksAreTheChunkedBuild) {
  const std::string bunny = test::MeshPath("stanford_bunny_bun_zipper.ply");
  const std::string dir = FreshFolder("stream_small");
  for (size_t chunk : {48, 256, 1024}) {
    Built memory;
    memory.mesh = ReadWelded(bunny);
    Build(memory, "bunny_small_chunks", Chunked(chunk, 2));
    const std::string out = dir + "/bunny.clod";
    LodBuildStats st;
    const Status s = BuildLodFileFromPly(bunny, Chunked(chunk, 2), out, &st, Progress(), nullptr, 1 << 20);
    ASSERT_TRUE(s.ok()) << s.message;
    EXPECT_EQ(ReadBytes(out), memory.bytes) << chunk << " faces a chunk";
    std::remove(out.c_str());
    std::remove(memory.path.c_str());
  }
  EXPECT_EQ(Listing(dir), std::vector<std::string>{});
  rmdir(dir.c_str());
}

// Chunks from a sample of the centroids (16 chunks of the armadillo from 2,000 faces): every cut,
// at every eye, budget and priority, is watertight and the full budget gives the input back.
TEST(LodStream, SampledChunksCutsAreWatertight) {
  const std::string path = test::MeshPath("stanford_armadillo_cgal.ply");
  Built b;
  b.mesh = ReadWelded(path);
  const size_t chunk = (b.mesh.faces.size() + 15) / 16;
  ExpectCrackFree(b, "armadillo_stream", Chunked(chunk), path, 2000);
  EXPECT_EQ(b.stats.chunks, 16u);
}

// The dragon streamed in 16 chunks from a sample of 4,096 faces: its cuts have no crack and the
// full budget gives the welded input back exactly (on the grid).
TEST(LodStream, DragonCutsAreWatertightAndItsRoundTripExact) {
  const std::string path = test::MeshPath("stanford_dragon_vrip_binary.ply");
  Built b;
  b.mesh = ReadWelded(path);
  b.path = TempPath("dragon_stream.clod");
  const size_t F = b.mesh.faces.size();
  LodBuildStats st;
  const Status s = BuildLodFileFromPly(path, Chunked((F + 15) / 16, 2), b.path, &st, Progress(), nullptr, 4096);
  ASSERT_TRUE(s.ok()) << s.message;
  EXPECT_EQ(st.chunks, 16u);
  EXPECT_EQ(st.inputFaces, F);
  EXPECT_EQ(st.inputVertices, b.mesh.positions.size());
  EXPECT_LT(st.levelFaces.back(), F / 100);
  ExpectDragonCutsWatertightAndRoundTripExact(b, "dragon streamed");
}

}  // namespace
}  // namespace conelod
