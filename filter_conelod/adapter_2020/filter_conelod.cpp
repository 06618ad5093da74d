// ConeLOD MeshLab plugin for MeshLab 2020.09 (see filter_conelod.h).
#include "filter_conelod.h"

#include <common/ml_shared_data_context.h>

#include "../filter_table.h"
#include "../show_face_colour.h"

using namespace conelod_plugin;

namespace {

const FilterSpec* Spec(int id) {
  const std::vector<FilterSpec>& t = Filters();
  return id >= 0 && size_t(id) < t.size() ? &t[size_t(id)] : nullptr;
}

void AddParams(const std::vector<ParamSpec>& specs, MeshDocument* md, RichParameterList& par) {
  for (const ParamSpec& p : specs) {
    switch (p.kind) {
      case ParamKind::Bool:
        par.addParam(RichBool(p.name, p.number != 0, p.label, p.help));
        break;
      case ParamKind::Int:
        par.addParam(RichInt(p.name, int(p.number), p.label, p.help));
        break;
      case ParamKind::Float:
        par.addParam(RichFloat(p.name, float(p.number), p.label, p.help));
        break;
      case ParamKind::AbsPerc:
        par.addParam(RichAbsPerc(p.name, float(p.number), 0.0f, float(p.absMax), p.label, p.help));
        break;
      case ParamKind::Enum:
        par.addParam(RichEnum(p.name, int(p.number), p.choices, p.label, p.help));
        break;
      case ParamKind::Position:
      case ParamKind::Direction:
        par.addParam(RichPoint3f(p.name, p.point, p.label, p.help));
        break;
      case ParamKind::OpenFile:
        par.addParam(RichOpenFile(p.name, p.path, p.choices, p.label, p.help));
        break;
      case ParamKind::SaveFile:
        par.addParam(RichSaveFile(p.name, p.path, p.choices.value(0), p.label, p.help));
        break;
      case ParamKind::Mesh:  // without a layer, the form that does not assert on an empty document
        if (p.mesh)
          par.addParam(RichMesh(p.name, const_cast<MeshModel*>(p.mesh), md, p.label, p.help));
        else
          par.addParam(RichMesh(p.name, 0, p.label, p.help));
        break;
    }
  }
}

// The values of `par`; a parameter the list lacks (a hand-written script) takes its default.
Args ReadArgs(const std::vector<ParamSpec>& specs, const RichParameterList& par) {
  Args a;
  for (const ParamSpec& p : specs) {
    const QString& n = p.name;
    const bool given = par.hasParameter(n);
    switch (p.kind) {
      case ParamKind::Bool:
        a.set(n, given ? double(par.getBool(n)) : p.number);
        break;
      case ParamKind::Int:
        a.set(n, given ? double(par.getInt(n)) : p.number);
        break;
      case ParamKind::Float:
        a.set(n, given ? double(par.getFloat(n)) : p.number);
        break;
      case ParamKind::AbsPerc:
        a.set(n, given ? double(par.getAbsPerc(n)) : p.number);
        break;
      case ParamKind::Enum:
        a.set(n, given ? double(par.getEnum(n)) : p.number);
        break;
      case ParamKind::Position:
      case ParamKind::Direction:
        a.set(n, given ? par.getPoint3f(n) : p.point);
        break;
      case ParamKind::OpenFile:
        a.set(n, given ? par.getOpenFileName(n) : p.path);
        break;
      case ParamKind::SaveFile:
        a.set(n, given ? par.getSaveFileName(n) : p.path);
        break;
      case ParamKind::Mesh:
        a.set(n, given ? par.getMesh(n) : const_cast<MeshModel*>(p.mesh));
        break;
    }
  }
  return a;
}

}  // namespace

FilterConeLodPlugin::FilterConeLodPlugin() {
  for (int id = 0; id < int(Filters().size()); ++id) typeList << id;
  for (FilterIDType id : types()) actionList << new QAction(filterName(id), this);
}

QString FilterConeLodPlugin::pluginName() const { return "FilterConeLOD"; }

QString FilterConeLodPlugin::filterName(FilterIDType filter) const {
  const FilterSpec* f = Spec(filter);
  return f ? f->name : QString();
}

QString FilterConeLodPlugin::filterInfo(FilterIDType filter) const {
  const FilterSpec* f = Spec(filter);
  return f ? f->info : QString();
}

MeshFilterInterface::FilterClass FilterConeLodPlugin::getClass(QAction* a) {
  const FilterSpec* f = Spec(ID(a));
  switch (f ? f->menu : Menu::Measure) {
    case Menu::FaceColoring:
      return MeshFilterInterface::FaceColoring;
    case Menu::Measure:
      return MeshFilterInterface::Measure;
    case Menu::Remeshing:
      return MeshFilterInterface::Remeshing;
    case Menu::MeshCreation:
      return MeshFilterInterface::MeshCreation;
  }
  return MeshFilterInterface::Measure;
}

MeshFilterInterface::FILTER_ARITY FilterConeLodPlugin::filterArity(QAction* a) const {
  const FilterSpec* f = Spec(ID(a));
  return f && f->arity == Arity::None ? NONE : SINGLE_MESH;
}

int FilterConeLodPlugin::getRequirements(QAction* a) {
  const FilterSpec* f = Spec(ID(a));
  return f ? f->requirements : int(MeshModel::MM_NONE);
}

// The post-conditions of the run that just ended when it returned some (ShowFaceColour: the GUI
// asks right after applyFilter); otherwise, e.g. when a dialog opens and decides on its preview,
// the filter's own.
int FilterConeLodPlugin::postCondition(QAction* a) const {
  const FilterSpec* f = Spec(ID(a));
  if (f && ID(a) == lastRun_ && lastPostConditions_ != -1) return lastPostConditions_;
  return f ? f->postConditions : int(MeshModel::MM_NONE);
}

void FilterConeLodPlugin::initParameterSet(QAction* a, MeshModel& m, RichParameterList& par) {
  lastRun_ = -1;
  if (const FilterSpec* f = Spec(ID(a))) AddParams(f->params(nullptr, &m), nullptr, par);
}

void FilterConeLodPlugin::initParameterSet(QAction* a, MeshDocument& md, RichParameterList& par) {
  lastRun_ = -1;
  if (const FilterSpec* f = Spec(ID(a))) AddParams(f->params(&md, md.mm()), &md, par);
}

bool FilterConeLodPlugin::applyFilter(QAction* a, MeshDocument& md, const RichParameterList& par,
                                      vcg::CallBackPos* cb) {
  errorMessage.clear();
  lastRun_ = -1;
  const FilterSpec* f = Spec(ID(a));
  if (!f) {
    errorMessage = "unknown filter";
    return false;
  }
  Report report([this](const std::string& line, bool isError) {
    Log(isError ? GLLogStream::SYSTEM : GLLogStream::FILTER, line);
  });
  errorMessage = RunFilter(*f, md, ReadArgs(f->params(&md, md.mm()), par), cb, report);
  if (!errorMessage.isEmpty()) return false;
  if (f->showFaceColour) {
    lastRun_ = ID(a);
    lastPostConditions_ = conelod_plugin::ShowFaceColour(md, glContext);
  }
  return true;
}

MESHLAB_PLUGIN_NAME_EXPORTER(FilterConeLodPlugin)
