// ConeLOD MeshLab plugin for MeshLab 2022.02 and later (FilterPlugin; 2023.12 and 2025.07 through
// compat.h): the filter table (../filter_table.h) as a plugin of that API. A failure throws
// MLException with the message, which the table has already logged; a success returns the
// filter's figures (PyMeshLab's apply_filter returns them as a dict).
//
// MeshLab loads the plugin only when its version series (first six characters, "2022.0") and
// scalar match its own: CMake compiles it with the MESHLAB_VERSION and MESHLAB_SCALAR of the
// MeshLab whose sources and libmeshlab-common it builds against.
#pragma once

#include <common/plugins/interfaces/filter_plugin.h>

class FilterConeLodPlugin : public QObject, public FilterPlugin {
  Q_OBJECT
  MESHLAB_PLUGIN_IID_EXPORTER(FILTER_PLUGIN_IID)
  Q_INTERFACES(FilterPlugin)

 public:
  FilterConeLodPlugin();
  QString pluginName() const override;
  QString vendor() const override;
  QString filterName(ActionIDType filter) const override;
  QString filterInfo(ActionIDType filter) const override;
  FilterClass getClass(const QAction* a) const override;
  FilterArity filterArity(const QAction* a) const override;
  int getRequirements(const QAction* a) override;
  int postCondition(const QAction* a) const override;
  RichParameterList initParameterList(const QAction* a, const MeshModel& m) override;
  RichParameterList initParameterList(const QAction* a, const MeshDocument& md) override;
  std::map<std::string, QVariant> applyFilter(const QAction* a, const RichParameterList& par, MeshDocument& md,
                                              unsigned int& postConditionMask, vcg::CallBackPos* cb) override;
};
