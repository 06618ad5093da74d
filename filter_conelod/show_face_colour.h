// ConeLOD MeshLab plugin — showing the groups' face colours after a filter that changed the faces,
// the same for every plugin API (CONELOD_MESHLAB_API 2020 or 2022; included by each adapter only,
// since it needs MeshLab's GL context).
#pragma once

#if CONELOD_MESHLAB_API >= 2022
#include <common/ml_shared_data_context/ml_plugin_gl_context.h>
#else
#include <common/ml_shared_data_context.h>
#endif

namespace conelod_plugin {

// After a filter that changed the current mesh's faces and whose face colours must show
// (FilterSpec::showFaceColour). MeshLab's GUI then compares each mesh with its state before the
// filter (MeshDocument::meshDocStateData, MainWindow::updateSharedContextDataAfterFilterExecution):
// a new vertex or face count, or post-conditions naming them, make it refresh every attribute,
// and with the vertex colour refreshed the face colour is switched off. So the plugin refreshes
// the mesh's GL buffers itself, as the GUI would (connectivity included), records the new counts
// as the state before, and returns the post-conditions that remain (positions, normals, face
// colour and quality): the GUI then switches the face colour on, as after a FaceColoring filter
// that keeps the faces. Only with a GL view (glContext) whose state was recorded (the GUI; not
// PyMeshLab); otherwise returns -1 (keep the filter's post-conditions).
inline int ShowFaceColour(MeshDocument& md, MLPluginGLContext* gl) {
  MeshModel* mm = md.mm();
  if (!gl || !mm) return -1;
  const auto before = md.meshDocStateData().find(mm->id());
  if (before == md.meshDocStateData().end()) return -1;
  const int maskBefore = before->_mask;
  MLRenderingData::RendAtts all;
  MLPoliciesStandAloneFunctions::fromMeshModelMaskToMLRenderingAtts(MeshModel::MM_ALL, all);
  gl->meshAttributesUpdated(mm->id(), true, all);
  md.meshDocStateData().insert(
      mm->id(), MeshModelStateData(maskBefore, size_t(mm->cm.VN()), size_t(mm->cm.FN()), size_t(mm->cm.EN())));
  return MeshModel::MM_VERTCOORD | MeshModel::MM_VERTNORMAL | MeshModel::MM_FACENORMAL | MeshModel::MM_FACECOLOR |
         MeshModel::MM_FACEQUALITY;
}

}  // namespace conelod_plugin
