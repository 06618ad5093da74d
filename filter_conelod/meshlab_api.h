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

#include <QImage>
#include <string>
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

// Texture images. MeshLab 2022.02 and later keep a layer's images in memory (MeshModel::addTexture:
// the GUI draws them from there, saving the layer writes them beside the mesh); 2020.09 only names
// them in cm.textures and reads each from its file when it draws or saves (QFileInfo: a relative
// name is relative to the current folder), so a layer's image must exist as a file there.
constexpr bool kLayersHoldTextureImages = CONELOD_MESHLAB_API >= 2022;

// Names `name` as the layer's next texture (index cm.textures.size() before the call) and, from
// 2022.02 on, gives it `image`; 2020.09 ignores `image` (`name` must be the file's path).
inline void AddLayerTexture(MeshModel& m, const std::string& name, const QImage& image) {
#if CONELOD_MESHLAB_API >= 2022
  m.addTexture(name, image);
#else
  (void)image;
  m.cm.textures.push_back(name);
#endif
}

}  // namespace conelod_plugin
