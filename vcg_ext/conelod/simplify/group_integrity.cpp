// ConeLOD — group integrity (see group_integrity.h).
#include "conelod/simplify/group_integrity.h"

#include "conelod/grouping/normal_cone.h"
#include "conelod/common.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace conelod {

namespace {

Status CheckIds(const IndexedMesh& m, const std::vector<int>& ids, const char* which) {
  if (ids.size() != m.faces.size())
    return Status::Invalid(std::string(which) + ": " + std::to_string(ids.size()) + " group ids for " +
                           std::to_string(m.faces.size()) + " faces");
  for (int g : ids)
    if (g < 0) return Status::Invalid(std::string(which) + ": group ids must be >= 0");
  for (const auto& t : m.faces)
    for (uint32_t v : t)
      if (v >= m.positions.size()) return Status::Invalid(std::string(which) + ": a face refers to a missing vertex");
  return Status::Ok();
}

}  // namespace

int GroupPieces::piecesOf(int id) const {
  const auto it = std::lower_bound(ids.begin(), ids.end(), id);
  return (it != ids.end() && *it == id) ? pieces[size_t(it - ids.begin())] : 0;
}

GroupPieces CountGroupPieces(const IndexedMesh& mesh, const std::vector<int>& faceGroup) {
  GroupPieces out;
  out.ids = faceGroup;
  std::sort(out.ids.begin(), out.ids.end());
  out.ids.erase(std::unique(out.ids.begin(), out.ids.end()), out.ids.end());
  out.pieces.assign(out.ids.size(), 0);
  if (mesh.faces.empty()) return out;
  const FaceAdjacency adj = BuildFaceAdjacency(mesh);
  const uint32_t nf = uint32_t(mesh.faces.size());
  std::vector<uint32_t> parent(nf);
  std::iota(parent.begin(), parent.end(), 0u);
  for (uint32_t f = 0; f < nf; ++f)
    for (uint32_t i = adj.offsets[f]; i < adj.offsets[f + 1]; ++i) {
      const uint32_t g = adj.neighbours[i];
      if (faceGroup[g] != faceGroup[f] || UsesAVertexTwice(mesh.faces[f]) || UsesAVertexTwice(mesh.faces[g])) continue;
      const uint32_t a = FindRoot(parent, f), b = FindRoot(parent, g);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  // One root per piece; a face that uses a vertex twice is none (the collapse leaves such faces
  // out: GroupQemResult::mesh).
  for (uint32_t f = 0; f < nf; ++f)
    if (FindRoot(parent, f) == f && !UsesAVertexTwice(mesh.faces[f]))
      ++out.pieces[size_t(std::lower_bound(out.ids.begin(), out.ids.end(), faceGroup[f]) - out.ids.begin())];
  return out;
}

Status MeasureGroupIntegrity(const IndexedMesh& before, const std::vector<int>& groupBefore, const IndexedMesh& after,
                             const std::vector<int>& groupAfter, GroupIntegrity& out) {
  out = GroupIntegrity();
  Status s = CheckIds(before, groupBefore, "before");
  if (!s.ok()) return s;
  s = CheckIds(after, groupAfter, "after");
  if (!s.ok()) return s;
  return MeasureGroupIntegrity(CountGroupPieces(before, groupBefore), after, groupAfter, out);
}

Status MeasureGroupIntegrity(const GroupPieces& pb, const IndexedMesh& after, const std::vector<int>& groupAfter,
                             GroupIntegrity& out) {
  out = GroupIntegrity();
  Status s = CheckIds(after, groupAfter, "after");
  if (!s.ok()) return s;
  const GroupPieces pa = CountGroupPieces(after, groupAfter);
  const size_t kListed = 20;
  out.groupsBefore = int(pb.ids.size());
  out.groupsAfter = int(pa.ids.size());
  for (size_t i = 0; i < pb.ids.size(); ++i) {
    const int id = pb.ids[i], n = pb.pieces[i], m = pa.piecesOf(id);
    if (n == 0) continue;  // no piece of surface to keep
    if (n > 1) ++out.groupsDisconnectedBefore;
    if (m == 0) {
      ++out.groupsVanished;
      if (out.vanishedIds.size() < kListed) out.vanishedIds.push_back(id);
    } else if (m > n) {
      ++out.groupsSplit;
      if (out.splitIds.size() < kListed) out.splitIds.push_back(id);
    }
  }
  for (size_t i = 0; i < pa.ids.size(); ++i) {
    if (pa.pieces[i] > 1) ++out.groupsDisconnectedAfter;
    if (pb.piecesOf(pa.ids[i]) == 0) ++out.groupsNew;
  }
  return Status::Ok();
}

int CountConesOverLimit(const IndexedMesh& mesh, const std::vector<int>& faceGroup, double limitDeg,
                        std::vector<int>* overIds) {
  if (overIds) overIds->clear();
  if (faceGroup.size() != mesh.faces.size() || !(limitDeg < 180)) return 0;
  std::vector<uint32_t> order(mesh.faces.size());
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](uint32_t x, uint32_t y) { return faceGroup[x] < faceGroup[y]; });
  const double limit = limitDeg * NormalCone::kPi / 180 + 1e-6;
  int over = 0;
  std::vector<vcg::Point3d> normals;
  for (size_t i = 0; i < order.size();) {
    const int id = faceGroup[order[i]];
    normals.clear();
    for (; i < order.size() && faceGroup[order[i]] == id; ++i) {
      const auto& t = mesh.faces[order[i]];
      const vcg::Point3d p0 = vcg::Point3d::Construct(mesh.positions[t[0]]);
      const vcg::Point3d n =
          (vcg::Point3d::Construct(mesh.positions[t[1]]) - p0) ^ (vcg::Point3d::Construct(mesh.positions[t[2]]) - p0);
      const double len = n.Norm();
      if (len > 0) normals.push_back(n / len);
    }
    if (normals.empty()) continue;
    if (MinimalCone(normals).halfAngle > limit) {
      ++over;
      if (overIds && overIds->size() < 10) overIds->push_back(id);
    }
  }
  return over;
}

Status GroupIdsFromValues(const std::vector<const std::vector<float>*>& values, std::vector<std::vector<int>>& ids) {
  ids.assign(values.size(), std::vector<int>());
  bool integral = true;
  for (const auto* list : values)
    for (float v : *list) {
      if (!std::isfinite(v)) return Status::Invalid("a per-face group value (quality) is NaN or infinite");
      if (!(v >= 0 && v < 2147483647.0f && v == std::floor(v))) integral = false;
    }
  if (integral) {
    for (size_t i = 0; i < values.size(); ++i) ids[i].assign(values[i]->begin(), values[i]->end());
    return Status::Ok();
  }
  std::vector<float> distinct;
  for (const auto* list : values) distinct.insert(distinct.end(), list->begin(), list->end());
  std::sort(distinct.begin(), distinct.end());
  distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
  for (size_t i = 0; i < values.size(); ++i) {
    ids[i].reserve(values[i]->size());
    for (float v : *values[i])
      ids[i].push_back(int(std::lower_bound(distinct.begin(), distinct.end(), v) - distinct.begin()));
  }
  return Status::Ok();
}

}  // namespace conelod
