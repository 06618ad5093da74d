// ConeLOD MeshLab plugin: a thin adapter from MeshLab's filter interface to the core in vcg_ext/.
// Each filter maps its parameters to the core's Params, enables the mesh components it writes,
// calls the core with MeshLab's progress callback, logs its figures, and reports bad input with
// errorMessage (and the log, since meshlabserver prints only the log). On failure the mesh is
// left exactly as it was: the core works on a copy and results are written only on success.
#pragma once

#include <common/interfaces.h>

class FilterConeLodPlugin : public QObject, public MeshFilterInterface {
  Q_OBJECT
  MESHLAB_PLUGIN_IID_EXPORTER(MESH_FILTER_INTERFACE_IID)
  Q_INTERFACES(MeshFilterInterface)

 public:
  // Ids are stable: scripts name filters by their names, which never change either.
  enum {
    FP_CONE_GROUPING,
    FP_CULLING_COST,
    FP_GROUP_QEM,
    FP_GROUP_INTEGRITY,
    FP_FEATURE_SIMPLIFY,
    FP_PIXEL_BUDGET,
    FP_PCA_PARTITION,
    FP_PROGRESSIVE_MESH,
    FP_LOD_EXPORT,
    FP_LOD_EXTRACT,
  };

  FilterConeLodPlugin();
  QString pluginName() const override;
  QString filterName(FilterIDType filter) const override;
  QString filterInfo(FilterIDType filter) const override;
  FilterClass getClass(QAction* a) override;
  FILTER_ARITY filterArity(QAction* a) const override;
  int getRequirements(QAction* a) override;
  int postCondition(QAction* a) const override;
  void initParameterSet(QAction* a, MeshModel& m, RichParameterList& par) override;
  void initParameterSet(QAction* a, MeshDocument& md, RichParameterList& par) override;
  bool applyFilter(QAction* a, MeshDocument& md, const RichParameterList& par, vcg::CallBackPos* cb) override;

 private:
  bool applyConeGrouping(MeshModel& mm, const RichParameterList& par, vcg::CallBackPos* cb);
  bool applyCullingCost(MeshModel& mm, const RichParameterList& par, vcg::CallBackPos* cb);
  bool applyGroupQem(MeshModel& mm, const RichParameterList& par, vcg::CallBackPos* cb);
  bool applyGroupIntegrity(MeshDocument& md, const RichParameterList& par);
  bool applyFeatureSimplify(MeshModel& mm, const RichParameterList& par, vcg::CallBackPos* cb);
  bool applyPixelBudget(MeshModel& mm, const RichParameterList& par, vcg::CallBackPos* cb);
  bool applyPcaPartition(MeshModel& mm, const RichParameterList& par, vcg::CallBackPos* cb);
  bool applyProgressiveMesh(MeshDocument& md, MeshModel& mm, const RichParameterList& par, vcg::CallBackPos* cb);
  bool applyLodExport(MeshModel& mm, const RichParameterList& par, vcg::CallBackPos* cb);
  bool applyLodExtract(MeshDocument& md, const RichParameterList& par, vcg::CallBackPos* cb);
  bool fail(const QString& message);  // logs and sets errorMessage; returns false
};
