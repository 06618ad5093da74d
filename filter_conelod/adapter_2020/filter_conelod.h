// ConeLOD MeshLab plugin for MeshLab 2020.09 (MeshFilterInterface): the filter table
// (../filter_table.h) as a plugin of that API. A failure sets errorMessage and returns false;
// the table has already logged it (meshlabserver prints only the log).
#pragma once

#include <common/interfaces.h>

class FilterConeLodPlugin : public QObject, public MeshFilterInterface {
  Q_OBJECT
  MESHLAB_PLUGIN_IID_EXPORTER(MESH_FILTER_INTERFACE_IID)
  Q_INTERFACES(MeshFilterInterface)

 public:
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
  // The filter (action id) that ran last and the post-conditions it returned (-1: its own), until
  // a dialog opens or the next run starts.
  int lastRun_ = -1;
  int lastPostConditions_ = -1;
};
