// ConeLOD MeshLab plugin — what the filter table (filter_table.h) uses of MeshLab, for every
// version it is built for. CONELOD_MESHLAB_API is set by CMake: 2020 for MeshLab 2020.09, 2022
// for 2022.02 and later (2023.12, 2025.07: the same document and mesh classes).
#pragma once

#if !defined(CONELOD_MESHLAB_API)
#error "CONELOD_MESHLAB_API must be defined (2020 or 2022)"
#endif

#if CONELOD_MESHLAB_API >= 2022
#include <common/ml_document/mesh_document.h>
#else
#include <common/meshmodel.h>
#endif

#include <vector>

namespace conelod_plugin {

// The standard update after changing coordinates (renamed in 2021).
inline void UpdateBoxAndNormals(MeshModel& m) {
#if CONELOD_MESHLAB_API >= 2022
  m.updateBoxAndNormals();
#else
  m.UpdateBoxAndNormals();
#endif
}

// The layers of a document, in order.
inline std::vector<const MeshModel*> Layers(const MeshDocument& doc) {
  std::vector<const MeshModel*> layers;
#if CONELOD_MESHLAB_API >= 2022
  for (const MeshModel& m : doc.meshIterator()) layers.push_back(&m);
#else
  for (const MeshModel* m : doc.meshList) layers.push_back(m);
#endif
  return layers;
}

// MeshLab 2020.09's parameter dialog passes on only a file chosen with the "..." button beside a
// file box and ignores a path typed into it; 2022.02 and later pass on what the box holds.
constexpr bool kDialogPassesTypedPaths = CONELOD_MESHLAB_API >= 2022;

}  // namespace conelod_plugin
