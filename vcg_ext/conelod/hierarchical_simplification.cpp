// ConeLOD — hierarchical simplification (see hierarchical_simplification.h).
#include "conelod/hierarchical_simplification.h"

#include <cmath>

namespace conelod {

Status BuildSimplifiedLevels(const IndexedMesh& mesh, const GroupHierarchy& hierarchy,
                             const HierarchicalSimplificationParams& params, std::vector<SimplifiedLevel>& out,
                             const Progress& progress) {
  out.clear();
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

    GroupQemParams qp = params.qem;
    qp.targetFaces = std::max<size_t>(1, size_t(std::floor(params.levelRatio * double(facesBelow))));
    L.targetFaces = qp.targetFaces;
    GroupQemResult r;
    const Status s = SimplifyPreservingGroups(*below, groups[0], qp, r,
                                              SubProgress(progress, 100 * (k - 1) / levels, 100 * k / levels), coarser);
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
