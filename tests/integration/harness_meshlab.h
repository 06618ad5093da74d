// The plugin harness's view of MeshLab: loading a filter plugin as MeshLab does and calling its
// filters, for MeshLab 2020.09 (MeshFilterInterface) and 2022.02+ (FilterPlugin).
// CONELOD_MESHLAB_API is 2020 or 2022 (set by CMake, as for the plugin).
#pragma once

#include <QDir>
#include <QFile>
#include <QTemporaryDir>
#include <map>
#include <memory>
#include <string>

#include <common/GLLogStream.h>
#include <common/filterscript.h>
#include <common/mlexception.h>
#if CONELOD_MESHLAB_API >= 2022
#include <common/plugins/interfaces/filter_plugin.h>
#include <common/plugins/plugin_manager.h>
#include <common/python/python_utils.h>
#else
#include <common/interfaces.h>
#include <common/pluginmanager.h>
#endif

namespace harness {

#if CONELOD_MESHLAB_API >= 2022
using Filter = FilterPlugin;
inline Value* PathValue(const QString& path) { return new StringValue(path); }
inline int MeshRef(const MeshModel* m) { return m->id(); }  // a RichMesh's value: the mesh id
#else
using Filter = MeshFilterInterface;
inline Value* PathValue(const QString& path) { return new FileValue(path); }
#endif

inline int LayerCount(MeshDocument& md) {
#if CONELOD_MESHLAB_API >= 2022
  return int(md.meshNumber());
#else
  return md.size();
#endif
}

// An enum's value (2020.09 checks the value's type: EnumValue, not IntValue).
inline void SetEnum(RichParameterList& par, const QString& name, int value) {
#if CONELOD_MESHLAB_API >= 2022
  par.setValue(name, IntValue(value));
#else
  par.setValue(name, EnumValue(value));
#endif
}

// The choices an enum parameter shows (empty when `name` is not an enum).
inline QStringList EnumChoices(const RichParameterList& par, const QString& name) {
  const RichEnum* e = par.hasParameter(name) ? dynamic_cast<const RichEnum*>(&par.getParameterByName(name)) : nullptr;
  return e ? e->enumvalues : QStringList();
}

inline void SetPath(RichParameterList& par, const QString& name, const QString& path) {
  std::unique_ptr<Value> v(PathValue(path));
  par.setValue(name, *v);
}

// One filter plugin, loaded by MeshLab's own PluginManager (which checks it as MeshLab does: in
// 2022+ the version series and scalar, in every version the class, requirements and arity of
// each filter).
class Plugin {
 public:
  // Loads `path`; on failure returns false and the PluginManager's reason.
  bool load(const QString& path, QString& why) {
    try {
#if CONELOD_MESHLAB_API >= 2022
      pm_.loadPlugin(QFileInfo(path).absoluteFilePath());
      for (FilterPlugin* f : pm_.filterPluginIterator()) filter_ = f;
#else
      // 2020.09's manager loads folders: one that holds only this plugin.
      if (!dir_.isValid() || !QFile::link(QFileInfo(path).absoluteFilePath(), dir_.filePath("libfilter_conelod.so"))) {
        why = "cannot make a plugin folder";
        return false;
      }
      RichParameterList globals;
      pm_.loadPlugins(globals, QDir(dir_.path()));
      if (!pm_.meshFilterPlugins().isEmpty()) filter_ = pm_.meshFilterPlugins().front();
#endif
    } catch (const MLException& e) {
      why = e.what();
      return false;
    }
    if (!filter_) why = "no filter plugin in " + path;
    if (filter_) filter_->setLog(&log_);
    return filter_ != nullptr;
  }

  Filter* filter() const { return filter_; }
  GLLogStream& log() { return log_; }

  QStringList names() const {
    QStringList l;
    for (QAction* a : filter_->actions()) l << filter_->filterName(a);
    return l;
  }
  QAction* action(const QString& name) const {
    for (QAction* a : filter_->actions())
      if (filter_->filterName(a) == name) return a;
    return nullptr;
  }

  // The parameters MeshLab's dialog would show for `md`.
  RichParameterList params(QAction* a, MeshDocument& md) {
#if CONELOD_MESHLAB_API >= 2022
    return filter_->initParameterList(a, md);
#else
    RichParameterList par;
    filter_->initParameterSet(a, md, par);
    return par;
#endif
  }

  // Runs the filter as the GUI does (requirements enabled first); returns "" on success,
  // otherwise the message MeshLab would show. `figures` (2022+): the filter's returned values.
  QString apply(QAction* a, MeshDocument& md, const RichParameterList& par, vcg::CallBackPos* cb,
                std::map<std::string, QVariant>* figures = nullptr) {
    if (md.mm()) md.mm()->updateDataMask(filter_->getRequirements(a));
#if CONELOD_MESHLAB_API >= 2022
    try {
      unsigned int postConditions = MeshModel::MM_UNKNOWN;
      std::map<std::string, QVariant> r = filter_->applyFilter(a, par, md, postConditions, cb);
      if (figures) *figures = r;
      return QString();
    } catch (const MLException& e) {
      return QString(e.what()).isEmpty() ? QString("(an empty MLException)") : QString(e.what());
    }
#else
    (void)figures;
    return filter_->applyFilter(a, md, par, cb)
               ? QString()
               : (filter_->errorMsg().isEmpty() ? QString("(no message)") : filter_->errorMsg());
#endif
  }

#if CONELOD_MESHLAB_API >= 2022
  // Runs a filter script as MeshLab 2022+ runs the one of its Filter Script dialog
  // (MainWindow::runFilterScript: FilterScript::open, then per filter: PluginManager::filterAction,
  // the requirements, applyFilter with the script's parameters as they are, the post-conditions,
  // CompactEveryVector, the colour masks of the filter's class); the GL context it makes for
  // filters is left out (no ConeLOD filter draws). Returns "" or the first failure.
  QString runScript(const QString& path, MeshDocument& md, vcg::CallBackPos* cb,
                    const std::map<QString, QString>& paths = {}) {
    FilterScript script;
    if (!script.open(path)) return "FilterScript::open failed on " + path;
    if (script.isEmpty()) return "no filter in " + path;
    for (FilterNameParameterValuesPair& pair : script) {
      QAction* a = pm_.filterAction(pair.filterName());
      if (!a) return "no filter named '" + pair.filterName() + "'";
      FilterPlugin* f = qobject_cast<FilterPlugin*>(a->parent());
      for (const auto& kv : paths)
        if (pair.second.hasParameter(kv.first)) SetPath(pair.second, kv.first, kv.second);
      if (md.mm()) md.mm()->updateDataMask(f->getRequirements(a));
      f->setLog(&log_);
      try {
        unsigned int postConditions = MeshModel::MM_UNKNOWN;
        f->applyFilter(a, pair.second, md, postConditions, cb);
        for (MeshModel* m = md.nextMesh(); m; m = md.nextMesh(m))
          vcg::tri::Allocator<CMeshO>::CompactEveryVector(m->cm);
        const int classes = int(f->getClass(a));
        if (md.mm() && (classes & FilterPlugin::FaceColoring)) md.mm()->updateDataMask(MeshModel::MM_FACECOLOR);
      } catch (const MLException& e) {
        return pair.filterName() + " failed: " + e.what();
      }
    }
    return QString();
  }

  // The name PyMeshLab gives a filter and a parameter (MeshLab's own pymeshlab functions).
  QString pythonName(QAction* a) const { return filter_->pythonFilterName(a); }
  static QString pythonName(const RichParameter& p) { return p.pythonName(); }
#endif

 private:
  PluginManager pm_;
#if CONELOD_MESHLAB_API < 2022
  QTemporaryDir dir_;
#endif
  Filter* filter_ = nullptr;
  GLLogStream log_;
};

}  // namespace harness
