// ConeLOD — standalone check of BuildConeHierarchy on real meshes: builds each hierarchy twice,
// verifies the documented guarantees on every level, and prints digests of the results so that
// two builds of the code (before / after an optimisation) can be compared line by line.
//
// Guarantees checked: every face in exactly one group per level, ids by first appearance,
// parent/child links consistent, every group edge-connected, no cone above the level's
// threshold (threshold >= 180: no limit), every cone equal to the exact minimal cone of the
// group's normals (to 1e-9 rad: Welzl's last bits depend on the order of the normals) and
// holding them (to MinimalCone's slack of 1e-10 on cosines), boxes
// equal to the vertices' box, spheres enclosing the vertices (to the rounding of the float
// centre), deterministic output (two builds, same digests).
//
// Usage: check_grouping [--synthetic] [MESH.ply...]   exit status 0 when every check passed.
//   --synthetic adds generated meshes with the awkward cases: exact ties, +0/-0 coordinates,
//   non-manifold edges, duplicated and degenerate faces.
#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "conelod/grouping/cone_grouping.h"
#include "conelod/vcg_bridge.h"
#include "conelod/vcg_mesh.h"

namespace {

using namespace conelod;

struct Hash {
  uint64_t h = 1469598103934665603ull;  // FNV-1a
  void bytes(const void* p, size_t n) {
    const unsigned char* b = static_cast<const unsigned char*>(p);
    for (size_t i = 0; i < n; ++i) {
      h ^= b[i];
      h *= 1099511628211ull;
    }
  }
  template <class T>
  void add(const T& v) {
    bytes(&v, sizeof v);
  }
};

int failures = 0;
void Fail(const std::string& what) {
  if (++failures <= 20) std::printf("  FAIL: %s\n", what.c_str());
}

// Returns the digest lines of one hierarchy, checking it on the way.
std::vector<std::string> CheckHierarchy(const IndexedMesh& m, const FaceAdjacency& adj,
                                        const std::vector<vcg::Point3d>& normals, const GroupHierarchy& h) {
  std::vector<std::string> lines;
  const size_t nf = m.faces.size();
  for (int l = 1; l <= h.levelCount(); ++l) {
    const GroupLevel& lv = h.level(l);
    const size_t ng = lv.groups.size();
    const std::string at = "level " + std::to_string(l) + ": ";
    if (lv.faceGroup.size() != nf) {
      Fail(at + "faceGroup size");
      continue;
    }
    // Ids in order of first appearance over faces.
    int next = 0;
    bool badIds = false;
    std::vector<std::vector<uint32_t>> facesOf(ng);
    for (size_t f = 0; f < nf; ++f) {
      const int g = lv.faceGroup[f];
      if (g < 0 || size_t(g) >= ng || g > next) {
        badIds = true;
        break;
      }
      if (g == next) ++next;
      facesOf[size_t(g)].push_back(uint32_t(f));
    }
    if (badIds || size_t(next) != ng) {
      Fail(at + "group ids not numbered by first appearance");
      continue;
    }
    if (!GroupsAreEdgeConnected(adj, lv.faceGroup)) Fail(at + "a group is not edge-connected");

    // Children and parents.
    size_t childTotal = 0;
    for (size_t g = 0; g < ng; ++g) {
      const Group& grp = lv.groups[g];
      childTotal += size_t(grp.childCount);
      if (grp.faceCount != int(facesOf[g].size())) Fail(at + "faceCount of group " + std::to_string(g));
      for (int c = grp.firstChild; c < grp.firstChild + grp.childCount; ++c) {
        const int child = lv.children[size_t(c)];
        const bool ok =
            l == 1 ? lv.faceGroup[size_t(child)] == int(g) : h.level(l - 1).groups[size_t(child)].parent == int(g);
        if (!ok) {
          Fail(at + "child link of group " + std::to_string(g));
          break;
        }
      }
      if ((l == h.levelCount()) != (grp.parent < 0)) Fail(at + "parent link of group " + std::to_string(g));
    }
    if (childTotal != (l == 1 ? nf : h.level(l - 1).groups.size())) Fail(at + "children do not cover the level below");

    // Cones: exact, and within the threshold; spheres and boxes enclose the vertices.
    Hash partition, geometry;
    partition.bytes(lv.faceGroup.data(), nf * sizeof(int));
    double maxDeg = 0;
    std::vector<vcg::Point3d> scratch;
    for (size_t g = 0; g < ng; ++g) {
      const Group& grp = lv.groups[g];
      scratch.clear();
      for (uint32_t f : facesOf[g]) scratch.push_back(normals[f]);
      const NormalCone exact = MinimalCone(scratch);
      // Welzl's result depends on the order of the normals in its last bits: compare with a
      // tolerance, and check that the group's own cone holds every normal, with MinimalCone's
      // own slack on cosines (an angle slack of up to 1.4e-5 rad for a cone of half-angle 0).
      bool same = exact.empty() == grp.cone.empty() && exact.cullable() == grp.cone.cullable() &&
                  (!exact.cullable() || std::fabs(exact.halfAngle - grp.cone.halfAngle) <= 1e-9);
      if (grp.cone.cullable() && !grp.cone.empty()) {
        const double minCos = std::cos(grp.cone.halfAngle) - 1e-9;
        for (uint32_t f : facesOf[g])
          if (normals[f].SquaredNorm() > 0.5 && normals[f] * grp.cone.axis < minCos) same = false;
      }
      if (!same) Fail(at + "cone of group " + std::to_string(g) + " is not the exact minimal cone");
      const double deg = grp.cone.cullable() ? std::max(0.0, grp.cone.halfAngle) * 180 / NormalCone::kPi : 180;
      maxDeg = std::max(maxDeg, deg);
      vcg::Box3f box;
      // In double; the slack is the rounding of a float coordinate (the centre is stored in float).
      const vcg::Point3d center = vcg::Point3d::Construct(grp.center);
      const double slack =
          1e-6 * grp.radius +
          std::ldexp(std::max({std::fabs(center[0]), std::fabs(center[1]), std::fabs(center[2])}), -23);
      double miss = 0;
      for (uint32_t f : facesOf[g])
        for (uint32_t v : m.faces[f]) {
          box.Add(m.positions[v]);
          miss = std::max(miss, Distance(vcg::Point3d::Construct(m.positions[v]), center) - grp.radius);
        }
      if (miss > slack) {
        char buf[160];
        std::snprintf(buf, sizeof buf, "sphere of group %zu (radius %g) misses a vertex by %g", g, grp.radius, miss);
        Fail(at + buf);
      }
      if (!(box.min == grp.box.min && box.max == grp.box.max)) Fail(at + "box of group " + std::to_string(g));
      geometry.add(grp.cone.axis);
      geometry.add(grp.cone.halfAngle);
      geometry.add(grp.center);
      geometry.add(grp.radius);
      geometry.add(grp.box.min);
      geometry.add(grp.box.max);
      geometry.add(grp.faceCount);
      geometry.add(grp.area);
      geometry.add(grp.parent);
    }
    if (lv.thresholdDeg < 180 && maxDeg > lv.thresholdDeg) Fail(at + "a cone exceeds the threshold");
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "level %d groups %zu max_cone_deg %.6f partition %016" PRIx64 " geometry %016" PRIx64, l, ng, maxDeg,
                  partition.h, geometry.h);
    lines.push_back(buf);
  }
  return lines;
}

// Synthetic meshes for the cases real scans rarely hit. Deterministic (xorshift).
struct Rng {
  uint64_t s = 0x2545F4914F6CDD1Dull;
  double next() {  // [0, 1)
    s ^= s >> 12;
    s ^= s << 25;
    s ^= s >> 27;
    return double((s * 0x2545F4914F6CDD1Dull) >> 11) / 9007199254740992.0;
  }
};

// A height field with quantized heights (exactly coplanar faces: score ties everywhere), zero and
// negative-zero coordinates (boxes whose bounds are +0 or -0) and random diagonals.
IndexedMesh Terrain(Rng& rng) {
  const int k = 60;
  const float heights[] = {0.0f, -0.0f, 0.5f, 1.0f, -0.5f};
  IndexedMesh m;
  for (int i = 0; i <= k; ++i)
    for (int j = 0; j <= k; ++j) {
      const float z = rng.next() < 0.3 ? heights[int(rng.next() * 5)] : 0.0f;
      m.positions.emplace_back(i == k / 2 ? -0.0f : float(i - k / 2), float(j - k / 2), z);
    }
  for (uint32_t i = 0; i < uint32_t(k); ++i)
    for (uint32_t j = 0; j < uint32_t(k); ++j) {
      const uint32_t a = i * (k + 1) + j, b = a + 1, c = a + k + 1, d = c + 1;
      if (rng.next() < 0.5) {
        m.faces.push_back({a, c, b});
        m.faces.push_back({b, c, d});
      } else {
        m.faces.push_back({a, c, d});
        m.faces.push_back({a, d, b});
      }
    }
  return m;
}

// A bumpy sphere whose pole vertices lie on the z axis (x = y = 0) at slightly different heights.
IndexedMesh Sphere(Rng& rng) {
  const int rings = 40, segments = 80;
  const double pi = NormalCone::kPi;
  IndexedMesh m;
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double th = pi * i / rings, ph = 2 * pi * j / segments, r = 1 + 0.02 * rng.next();
      const double sx = i == 0 || i == rings ? 0.0 : std::sin(th);
      m.positions.emplace_back(float(r * sx * std::cos(ph)), float(r * sx * std::sin(ph)), float(r * std::cos(th)));
    }
  for (uint32_t i = 0; i < uint32_t(rings); ++i)
    for (uint32_t j = 0; j < uint32_t(segments); ++j) {
      const uint32_t a = i * segments + j, b = i * segments + (j + 1) % segments;
      const uint32_t c = a + segments, d = b + segments;
      m.faces.push_back({a, c, b});
      m.faces.push_back({b, c, d});
    }
  return m;
}

// Non-manifold fans, a duplicated face, degenerate faces (repeated and collinear corners), an
// isolated triangle.
IndexedMesh Oddities() {
  IndexedMesh m;
  const float p[][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, -1, 0.3f},
                        {1, 1, 1}, {5, 5, 5}, {6, 5, 5}, {5, 6, 5}, {0.5f, 0.5f, 0}};
  for (const auto& v : p) m.positions.emplace_back(v[0], v[1], v[2]);
  m.faces = {{0, 1, 2}, {0, 1, 3}, {0, 1, 4}, {0, 1, 2}, {0, 0, 1}, {1, 2, 9}, {6, 7, 8}, {2, 3, 5}, {3, 5, 5}};
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: check_grouping [--synthetic] [MESH.ply...]\n");
    return 1;
  }
  struct Named {
    const char* name;
    ConeGroupingParams p;
  };
  std::vector<Named> sets(4);
  sets[0].name = "default";
  sets[1].name = "cone-only";
  sets[1].p.shapeWeight = 0;
  sets[1].p.sizeWeight = 0;
  sets[2].name = "no-threshold";
  sets[2].p.coneThresholdDeg = 180;
  // The paper's best-first order: its digests are those of "default" before local maxima came in.
  sets[3].name = "strict-greedy";
  sets[3].p.strictGreedy = true;

  std::vector<std::pair<std::string, IndexedMesh>> meshes;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--synthetic") {
      Rng rng;
      meshes.emplace_back("synthetic terrain", Terrain(rng));
      meshes.emplace_back("synthetic sphere", Sphere(rng));
      meshes.emplace_back("synthetic oddities", Oddities());
      continue;
    }
    CMesh cm;
    const std::string err = LoadPly(cm, argv[i]);
    if (!err.empty()) {
      std::fprintf(stderr, "%s\n", err.c_str());
      return 1;
    }
    meshes.emplace_back(argv[i], ToIndexedMesh(cm));
  }
  for (const auto& named : meshes) {
    const IndexedMesh& m = named.second;
    const FaceAdjacency adj = BuildFaceAdjacency(m);
    std::vector<vcg::Point3d> normals;
    std::vector<double> areas;
    ComputeFaceNormalsAndAreas(m, normals, areas);
    for (const Named& s : sets) {
      std::printf("%s [%s]\n", named.first.c_str(), s.name);
      GroupHierarchy first, second;
      if (!BuildConeHierarchy(m, s.p, first).ok() || !BuildConeHierarchy(m, s.p, second).ok()) {
        Fail("build failed");
        continue;
      }
      const std::vector<std::string> a = CheckHierarchy(m, adj, normals, first);
      const std::vector<std::string> b = CheckHierarchy(m, adj, normals, second);
      if (a != b) Fail("two builds differ (not deterministic)");
      for (const std::string& line : a) std::printf("  %s\n", line.c_str());
    }
  }
  std::printf(failures ? "%d check(s) FAILED\n" : "all checks passed\n", failures);
  return failures ? 1 : 0;
}
