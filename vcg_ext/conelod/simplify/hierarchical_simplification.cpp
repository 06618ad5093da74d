// ConeLOD — hierarchical simplification (see hierarchical_simplification.h).
#include "conelod/simplify/hierarchical_simplification.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>

#include <vcg/space/box3.h>

#include "conelod/grouping/cone_grouping.h"
#include "conelod/simplify/attribute_quadric.h"
#include "conelod/parallel.h"

namespace conelod {

namespace {

constexpr uint32_t kNone = UINT32_MAX;
constexpr int kMaxParts = 8;
constexpr int kGroupsPerPart = 16;  // no group may hold more than 1/16 of a part's faces

}  // namespace

std::vector<uint8_t> CutGroupsIntoParts(const IndexedMesh& mesh, const std::vector<int>& faceGroup, int parts,
                                        int parity) {
  struct Group {
    vcg::Point3d sum{0, 0, 0};
    size_t faces = 0;
    int id = 0;
    vcg::Point3d centroid() const { return sum / double(faces); }
  };
  const int maxId = faceGroup.empty() ? 0 : *std::max_element(faceGroup.begin(), faceGroup.end());
  std::vector<Group> groups(size_t(maxId) + 1);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& t = mesh.faces[f];
    Group& g = groups[size_t(faceGroup[f])];
    g.sum += vcg::Point3d::Construct(mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3.0;
    ++g.faces;
  }
  for (size_t i = 0; i < groups.size(); ++i) groups[i].id = int(i);
  groups.erase(std::remove_if(groups.begin(), groups.end(), [](const Group& g) { return g.faces == 0; }), groups.end());
  std::vector<uint8_t> partOfGroup(size_t(maxId) + 1, 0);

  struct Cut {
    size_t begin, end;
    int parts, firstPart, depth;
  };
  std::vector<Cut> todo{{0, groups.size(), parts, 0, 0}};
  while (!todo.empty()) {
    const Cut c = todo.back();
    todo.pop_back();
    if (c.parts == 1 || c.end - c.begin < 2) {
      for (size_t i = c.begin; i < c.end; ++i) partOfGroup[size_t(groups[i].id)] = uint8_t(c.firstPart);
      continue;
    }
    vcg::Box3d box;
    for (size_t i = c.begin; i < c.end; ++i) box.Add(groups[i].centroid());
    const vcg::Point3d dim = box.Dim();
    int order[3] = {0, 1, 2};
    std::sort(order, order + 3, [&](int a, int b) { return dim[a] > dim[b] || (dim[a] == dim[b] && a < b); });
    const int axis = parity < 0 ? order[0] : order[(parity + c.depth) % 2];
    std::sort(groups.begin() + long(c.begin), groups.begin() + long(c.end), [axis](const Group& a, const Group& b) {
      const double ca = a.sum[axis] / double(a.faces), cb = b.sum[axis] / double(b.faces);
      return ca < cb || (ca == cb && a.id < b.id);
    });
    size_t total = 0;
    for (size_t i = c.begin; i < c.end; ++i) total += groups[i].faces;
    size_t mid = c.begin, acc = 0;
    while (mid < c.end - 1 && 2 * (acc + groups[mid].faces) <= total) acc += groups[mid++].faces;
    if (mid == c.begin) ++mid;
    const int half = c.parts / 2;
    todo.push_back({c.begin, mid, half, c.firstPart, c.depth + 1});
    todo.push_back({mid, c.end, c.parts - half, c.firstPart + half, c.depth + 1});
  }
  std::vector<uint8_t> part(mesh.faces.size());
  for (size_t f = 0; f < part.size(); ++f) part[f] = partOfGroup[size_t(faceGroup[f])];
  return part;
}

namespace {

// One part of a level: its faces and vertices (indices into the level's input, increasing), the
// sub-mesh and groups handed to the simplifier, and what it gave back.
struct Part {
  std::vector<uint32_t> faces, vertices;
  GroupQemParams params;
  GroupQemResult result;
  std::vector<float> corner;  // with attributes: per face corner of `result`
  Status status;
  std::atomic<int> percent{0};
};

// The level's attributes (HierarchyAttributes): the layout, the weight and the corner values of the
// mesh being simplified (the level below's).
struct LevelAttributes {
  const HierarchyAttributes* attributes = nullptr;
  const std::vector<float>* belowCorners = nullptr;
};

// Simplifies `mesh` (one piece or a part) with `la`'s attributes when it has some: the corner values
// of its faces are those of `belowFace`'s faces (identity when empty), and `corner` gets the
// result's corners at their vertices' new positions.
Status SimplifyWithAttributes(const IndexedMesh& mesh, const std::vector<int>& groups, const GroupQemParams& qp,
                              GroupQemResult& r, const Progress& progress,
                              const std::vector<const std::vector<int>*>& coarser, const GroupQemRegion* region,
                              const LevelAttributes& la, const std::vector<uint32_t>& belowFace,
                              std::vector<float>& corner, size_t* seamVertices = nullptr) {
  if (!la.attributes) return SimplifyPreservingGroups(mesh, groups, qp, r, progress, coarser, region);
  const size_t C = size_t(la.attributes->layout.channels());
  std::vector<float> values;
  if (belowFace.empty()) {
    values = *la.belowCorners;
  } else {
    values.reserve(3 * belowFace.size() * C);
    for (uint32_t f : belowFace)
      values.insert(values.end(), la.belowCorners->begin() + std::ptrdiff_t(3 * f * C),
                    la.belowCorners->begin() + std::ptrdiff_t(3 * (f + 1) * C));
  }
  AttributeQuadrics aq;
  Status s = aq.Init(mesh, la.attributes->layout, std::move(values), la.attributes->weight);
  if (!s.ok()) return s;
  aq.AllowSeamMoves(la.attributes->seamMoves);
  if (seamVertices) *seamVertices = aq.seamVertices();
  s = SimplifyPreservingGroups(mesh, groups, qp, r, progress, coarser, region, &aq);
  if (!s.ok()) return s;
  corner.assign(3 * r.mesh.faces.size() * C, 0.0f);
  for (size_t f = 0; f < r.mesh.faces.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const uint32_t o = r.mesh.faces[f][size_t(k)];
      const auto& q = r.mesh.positions[o];
      aq.Evaluate(r.sourceFace[f], k, r.sourceVertex[o], vcg::Point3d(q[0], q[1], q[2]),
                  corner.data() + (3 * f + size_t(k)) * C);
    }
  return Status::Ok();
}

void SimplifyPart(const IndexedMesh& below, const std::vector<std::vector<int>>& groups,
                  const std::vector<uint8_t>& partOfFace, const std::vector<uint8_t>& shared, int index, double ratio,
                  double diagonal, const std::atomic<bool>& cancel, const LevelAttributes& la, Part& part) {
  try {
    for (uint32_t f = 0; f < partOfFace.size(); ++f)
      if (partOfFace[f] == index) part.faces.push_back(f);
    if (part.faces.empty()) {  // fewer groups than parts: nothing to do here
      part.result.stats.stop = GroupQemStats::Stop::TargetReached;
      part.percent.store(100, std::memory_order_relaxed);
      return;
    }
    std::vector<uint32_t> local(below.positions.size(), kNone);
    for (uint32_t f : part.faces)
      for (uint32_t v : below.faces[f]) local[v] = 0;
    for (uint32_t v = 0; v < local.size(); ++v)
      if (local[v] == 0) {
        local[v] = uint32_t(part.vertices.size());
        part.vertices.push_back(v);
      }
    IndexedMesh sub;
    sub.positions.reserve(part.vertices.size());
    for (uint32_t v : part.vertices) sub.positions.push_back(below.positions[v]);
    sub.faces.reserve(part.faces.size());
    for (uint32_t f : part.faces) {
      const auto& t = below.faces[f];
      sub.faces.push_back({local[t[0]], local[t[1]], local[t[2]]});
    }
    std::vector<std::vector<int>> subGroups(groups.size(), std::vector<int>(part.faces.size()));
    for (size_t j = 0; j < groups.size(); ++j)
      for (size_t i = 0; i < part.faces.size(); ++i) subGroups[j][i] = groups[j][part.faces[i]];
    std::vector<const std::vector<int>*> coarser;
    for (size_t j = 1; j < subGroups.size(); ++j) coarser.push_back(&subGroups[j]);
    GroupQemRegion region;
    region.diagonal = diagonal;
    region.frozenVertex.resize(part.vertices.size());
    for (size_t i = 0; i < part.vertices.size(); ++i) region.frozenVertex[i] = shared[part.vertices[i]];
    part.params.targetFaces = std::max<size_t>(1, size_t(std::floor(ratio * double(part.faces.size()))));
    part.status = SimplifyWithAttributes(
        sub, subGroups[0], part.params, part.result,
        [&](int percent, const char*) {
          part.percent.store(percent, std::memory_order_relaxed);
          return !cancel.load(std::memory_order_relaxed);
        },
        coarser, &region, la, part.faces, part.corner);
  } catch (const std::bad_alloc&) {
    part.status = Status::OutOfMemory("not enough memory to simplify a part of the level");
  } catch (const std::exception& e) {
    part.status = Status::Invalid(std::string("internal error while simplifying a part of the level: ") + e.what());
  }
  part.percent.store(100, std::memory_order_relaxed);
}

// Simplifies `below` in `parts` parts side by side; `out` as SimplifyPreservingGroups would give it
// for the whole level (indices into `below`, faces and vertices in their order there).
// With attributes (`la`), `corner` gets the output's corner values, as SimplifyWithAttributes.
Status SimplifyInParts(const IndexedMesh& below, const std::vector<std::vector<int>>& groups, int parts, int parity,
                       const HierarchicalSimplificationParams& params, GroupQemResult& out, const Progress& progress,
                       const LevelAttributes& la, std::vector<float>& corner) {
  out = GroupQemResult();
  corner.clear();
  // Cut along the contours of the coarsest level whose groups are small enough for balanced parts
  // (coarse levels can hold a whole connected component in one group).
  size_t cutLayer = 0;
  for (size_t j = groups.size(); j-- > 0;) {
    std::vector<size_t> faces;
    for (int g : groups[j]) {
      if (size_t(g) >= faces.size()) faces.resize(size_t(g) + 1, 0);
      ++faces[size_t(g)];
    }
    if (*std::max_element(faces.begin(), faces.end()) * kGroupsPerPart * size_t(parts) <= below.faces.size()) {
      cutLayer = j;
      break;
    }
  }
  const std::vector<uint8_t> partOfFace = CutGroupsIntoParts(below, groups[cutLayer], parts, parity);
  // A vertex used by faces of two parts is shared: it stays where it is at this level.
  std::vector<uint8_t> firstPart(below.positions.size(), 0xff), shared(below.positions.size(), 0);
  for (size_t f = 0; f < below.faces.size(); ++f)
    for (uint32_t v : below.faces[f]) {
      if (firstPart[v] == 0xff)
        firstPart[v] = partOfFace[f];
      else if (firstPart[v] != partOfFace[f])
        shared[v] = 1;
    }
  const double diagonal = UsedVertexBox(below).Diag();

  std::vector<Part> part(static_cast<size_t>(parts));
  for (Part& p : part) p.params = params.qem;
  std::atomic<bool> cancel{false};
  std::atomic<int> next{0};
  const auto work = [&](unsigned) {
    for (int i; (i = next.fetch_add(1)) < parts;)
      SimplifyPart(below, groups, partOfFace, shared, i, params.levelRatio, diagonal, cancel, la, part[size_t(i)]);
  };
  // Progress and cancellation from this thread only (MeshLab's callbacks are not thread-safe).
  RunThreadsWhile(unsigned(std::min(SimplificationThreads(params), parts)), work, [&] {
    if (!progress || cancel.load()) return;
    int sum = 0;
    for (const Part& p : part) sum += p.percent.load(std::memory_order_relaxed);
    if (!progress(std::min(99, sum / parts), "Hierarchical simplification: simplifying parts side by side"))
      cancel.store(true);
  });
  for (const Part& p : part)
    if (!p.status.ok() && p.status.code != Status::Code::Cancelled) return p.status;
  if (cancel.load()) return Status::Cancelled();
  for (const Part& p : part)
    if (!p.status.ok()) return p.status;

  // Put the parts together: surviving vertices and faces in their order in `below`.
  std::vector<uint32_t> newIndex(below.positions.size(), kNone);
  std::vector<vcg::Point3f> position(below.positions.size());
  std::vector<uint8_t> faceAlive(below.faces.size(), 0);
  std::vector<std::array<uint32_t, 3>> face(below.faces.size());
  const size_t C = la.attributes ? size_t(la.attributes->layout.channels()) : 0;
  std::vector<float> faceCorner(3 * below.faces.size() * C);  // per face of `below` that stays
  GroupQemStats& st = out.stats;
  st.stop = GroupQemStats::Stop::TargetReached;
  for (const Part& p : part) {
    const GroupQemResult& r = p.result;
    for (size_t i = 0; i < r.sourceVertex.size(); ++i) {
      const uint32_t v = p.vertices[r.sourceVertex[i]];
      newIndex[v] = 0;
      position[v] = r.mesh.positions[i];
    }
    for (size_t i = 0; i < r.sourceFace.size(); ++i) {
      const uint32_t f = p.faces[r.sourceFace[i]];
      faceAlive[f] = 1;
      for (int k = 0; k < 3; ++k) face[f][size_t(k)] = p.vertices[r.sourceVertex[r.mesh.faces[i][size_t(k)]]];
      if (C)
        std::copy(p.corner.begin() + std::ptrdiff_t(3 * i * C), p.corner.begin() + std::ptrdiff_t(3 * (i + 1) * C),
                  faceCorner.begin() + std::ptrdiff_t(3 * f * C));
    }
    st.facesIn += r.stats.facesIn;
    st.facesOut += r.stats.facesOut;
    st.collapses += r.stats.collapses;
    st.evaluations += r.stats.evaluations;
    st.refusedTopology += r.stats.refusedTopology;
    st.refusedCondition1 += r.stats.refusedCondition1;
    st.refusedCondition2 += r.stats.refusedCondition2;
    st.refusedLock += r.stats.refusedLock;
    st.refusedFixed += r.stats.refusedFixed;
    st.refusedGeometry += r.stats.refusedGeometry;
    st.maxCollapseError = std::max(st.maxCollapseError, r.stats.maxCollapseError);
    if (r.stats.stop != GroupQemStats::Stop::TargetReached) st.stop = r.stats.stop;
  }
  for (uint32_t v = 0; v < newIndex.size(); ++v)
    if (newIndex[v] == 0) {
      newIndex[v] = uint32_t(out.mesh.positions.size());
      out.mesh.positions.push_back(position[v]);
      out.sourceVertex.push_back(v);
    }
  out.mesh.faces.reserve(st.facesOut);
  out.sourceFace.reserve(st.facesOut);
  for (uint32_t f = 0; f < face.size(); ++f)
    if (faceAlive[f]) {
      out.mesh.faces.push_back({newIndex[face[f][0]], newIndex[face[f][1]], newIndex[face[f][2]]});
      out.sourceFace.push_back(f);
      if (C)
        corner.insert(corner.end(), faceCorner.begin() + std::ptrdiff_t(3 * f * C),
                      faceCorner.begin() + std::ptrdiff_t(3 * (f + 1) * C));
    }
  return Status::Ok();
}

}  // namespace

int SimplificationThreads(const HierarchicalSimplificationParams& params) {
  return params.threads > 0 ? params.threads : int(CoreCount());
}

Status BuildSimplifiedLevels(const IndexedMesh& mesh, const GroupHierarchy& hierarchy,
                             const HierarchicalSimplificationParams& params, std::vector<SimplifiedLevel>& out,
                             const Progress& progress, const HierarchyAttributes* attributes) {
  out.clear();
  if (attributes && attributes->layout.empty()) attributes = nullptr;
  if (attributes && attributes->inputCorners.size() != 3 * mesh.faces.size() * size_t(attributes->layout.channels()))
    return Status::Invalid("the attributes do not fit the mesh: " + std::to_string(attributes->inputCorners.size()) +
                           " corner values for " + std::to_string(mesh.faces.size()) + " faces");
  if (!(params.levelRatio > 0 && params.levelRatio <= 1)) return Status::Invalid("the level ratio must be in (0, 1]");
  if (hierarchy.levelCount() == 0) return Status::Invalid("the group hierarchy has no level");
  if (hierarchy.faceCount != int(mesh.faces.size()))
    return Status::Invalid("the group hierarchy was built for " + std::to_string(hierarchy.faceCount) +
                           " faces, the mesh has " + std::to_string(mesh.faces.size()));
  const int levels = hierarchy.levelCount();
  std::vector<SimplifiedLevel> result(static_cast<size_t>(levels));
  const IndexedMesh* below = &mesh;
  const std::vector<uint32_t>* belowSource = nullptr;  // input face of each face of `below`
  for (int k = 1; k <= levels; ++k) {
    SimplifiedLevel& L = result[size_t(k - 1)];
    L.level = k;
    const size_t facesBelow = below->faces.size();
    // Groups of level k and of every coarser level, per face of `below`.
    std::vector<std::vector<int>> groups(size_t(levels - k + 1), std::vector<int>(facesBelow));
    for (int j = k; j <= levels; ++j) {
      const auto& fg = hierarchy.level(j).faceGroup;
      auto& g = groups[size_t(j - k)];
      for (size_t f = 0; f < facesBelow; ++f) g[f] = fg[belowSource ? (*belowSource)[f] : f];
    }
    std::vector<const std::vector<int>*> coarser;
    for (size_t j = 1; j < groups.size(); ++j) coarser.push_back(&groups[j]);

    HierarchicalSimplificationParams levelParams = params;  // keepCones: the cones of level k
    if (params.qem.keepCones) {  // every coarser level's bounds too: its faces start inside them
      levelParams.qem.coneBound = LevelConeBounds(hierarchy, k);
      levelParams.qem.coarserConeBound.clear();
      for (int j = k + 1; j <= levels; ++j) levelParams.qem.coarserConeBound.push_back(LevelConeBounds(hierarchy, j));
    }
    GroupQemParams qp = levelParams.qem;
    qp.targetFaces = std::max<size_t>(1, size_t(std::floor(params.levelRatio * double(facesBelow))));
    L.targetFaces = qp.targetFaces;
    int parts = 1;
    if (params.facesPerPart > 0)
      while (parts < kMaxParts && facesBelow >= 2 * size_t(parts) * params.facesPerPart) parts *= 2;
    GroupQemResult r;
    const Progress levelProgress = SubProgress(progress, 100 * (k - 1) / levels, 100 * k / levels);
    LevelAttributes la;
    if (attributes) {
      la.attributes = attributes;
      la.belowCorners = k > 1 ? &result[size_t(k - 2)].corner : &attributes->inputCorners;
    }
    Status s = ValidateParams(qp);
    if (s.ok())
      s = parts > 1 ? SimplifyInParts(*below, groups, parts, (k - 1) % 2, levelParams, r, levelProgress, la, L.corner)
                    : SimplifyWithAttributes(*below, groups[0], qp, r, levelProgress, coarser, nullptr, la, {},
                                             L.corner, &L.seamVertices);
    if (!s.ok()) return s;
    L.mesh = std::move(r.mesh);
    L.stats = r.stats;
    L.sourceFace.resize(r.sourceFace.size());
    L.faceGroup.resize(r.sourceFace.size());
    for (size_t f = 0; f < r.sourceFace.size(); ++f) {
      L.sourceFace[f] = belowSource ? (*belowSource)[r.sourceFace[f]] : r.sourceFace[f];
      L.faceGroup[f] = groups[0][r.sourceFace[f]];
    }
    L.sourceVertex.resize(r.sourceVertex.size());
    for (size_t v = 0; v < r.sourceVertex.size(); ++v)
      L.sourceVertex[v] = k > 1 ? result[size_t(k - 2)].sourceVertex[r.sourceVertex[v]] : r.sourceVertex[v];
    below = &L.mesh;
    belowSource = &L.sourceFace;
  }
  out = std::move(result);
  return Status::Ok();
}

}  // namespace conelod
