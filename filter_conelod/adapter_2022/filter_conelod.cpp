// ConeLOD MeshLab plugin for MeshLab 2022.02 and later (see filter_conelod.h).
#include "filter_conelod.h"

#include <common/ml_shared_data_context/ml_plugin_gl_context.h>
#include <common/mlexception.h>

#include "../filter_table.h"
#include "../show_face_colour.h"
#include "compat.h"

using namespace conelod_plugin;

namespace {

const FilterSpec* Spec(int id) {
  const std::vector<FilterSpec>& t = Filters();
  return id >= 0 && size_t(id) < t.size() ? &t[size_t(id)] : nullptr;
}

RichParameterList MakeParams(const std::vector<ParamSpec>& specs, const MeshDocument* md) {
  RichParameterList par;
  for (const ParamSpec& p : specs) {
    switch (p.kind) {
      case ParamKind::Bool:
        par.addParam(RichBool(p.name, p.number != 0, p.label, p.help));
        break;
      case ParamKind::Int:
        par.addParam(RichInt(p.name, int(p.number), p.label, p.help));
        break;
      case ParamKind::Float:
        par.addParam(RichFloat(p.name, Scalarm(p.number), p.label, p.help));
        break;
      case ParamKind::AbsPerc:
        par.addParam(RichAbsPercParameter(p.name, Scalarm(p.number), 0, Scalarm(p.absMax), p.label, p.help));
        break;
      case ParamKind::Enum:
        par.addParam(RichEnum(p.name, int(p.number), p.choices, p.label, p.help));
        break;
      case ParamKind::Position:
        par.addParam(RichPosition(p.name, Point3m::Construct(p.point), p.label, p.help));
        break;
      case ParamKind::Direction:
        par.addParam(RichDirection(p.name, Point3m::Construct(p.point), p.label, p.help));
        break;
      case ParamKind::OpenFile:
        par.addParam(RichOpenFileParameter(p.name, p.path, p.choices, p.label, p.help));
        break;
      case ParamKind::SaveFile:
        par.addParam(RichSaveFileParameter(p.name, p.path, p.choices.value(0), p.label, p.help));
        break;
      case ParamKind::Mesh:
        par.addParam(RichMesh(p.name, p.mesh ? p.mesh->id() : 0, md, p.label, p.help));
        break;
    }
  }
  return par;
}

// The values of `par`; a parameter the list lacks (a hand-written script: MeshLab 2022+ passes a
// script's parameters as they are) takes its default, as meshlabserver 2020.09 did.
Args ReadArgs(const std::vector<ParamSpec>& specs, const RichParameterList& par, MeshDocument& md) {
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
        a.set(n, given ? vcg::Point3f::Construct(par.getPoint3m(n)) : p.point);
        break;
      case ParamKind::OpenFile:
        a.set(n, given ? par.getOpenFileName(n) : p.path);
        break;
      case ParamKind::SaveFile:
        a.set(n, given ? par.getSaveFileName(n) : p.path);
        break;
      case ParamKind::Mesh:
        a.set(n, given ? md.getMesh(par.getMeshId(n)) : const_cast<MeshModel*>(p.mesh));
        break;
    }
  }
  return a;
}

}  // namespace

FilterConeLodPlugin::FilterConeLodPlugin() {
  for (int id = 0; id < int(Filters().size()); ++id) typeList.push_back(id);
  for (ActionIDType id : types()) actionList.push_back(new QAction(filterName(id), this));
}

QString FilterConeLodPlugin::pluginName() const { return "FilterConeLOD"; }

QString FilterConeLodPlugin::vendor() const { return "ConeLOD"; }

QString FilterConeLodPlugin::filterName(ActionIDType filter) const {
  const FilterSpec* f = Spec(filter);
  return f ? f->name : QString();
}

QString FilterConeLodPlugin::filterInfo(ActionIDType filter) const {
  const FilterSpec* f = Spec(filter);
  return f ? f->info : QString();
}

FilterPlugin::FilterClass FilterConeLodPlugin::getClass(const QAction* a) const {
  const FilterSpec* f = Spec(ID(a));
  switch (f ? f->menu : Menu::Measure) {
    case Menu::FaceColoring:
      return FilterPlugin::FaceColoring;
    case Menu::Measure:
      return FilterPlugin::Measure;
    case Menu::Remeshing:
      return FilterPlugin::Remeshing;
    case Menu::MeshCreation:
      return FilterPlugin::MeshCreation;
  }
  return FilterPlugin::Measure;
}

FilterPlugin::FilterArity FilterConeLodPlugin::filterArity(const QAction* a) const {
  const FilterSpec* f = Spec(ID(a));
  return f && f->arity == Arity::None ? NONE : SINGLE_MESH;
}

int FilterConeLodPlugin::getRequirements(const QAction* a) {
  const FilterSpec* f = Spec(ID(a));
  return f ? f->requirements : int(MeshModel::MM_NONE);
}

int FilterConeLodPlugin::postCondition(const QAction* a) const {
  const FilterSpec* f = Spec(ID(a));
  return f ? f->postConditions : int(MeshModel::MM_NONE);
}

RichParameterList FilterConeLodPlugin::initParameterList(const QAction* a, const MeshModel& m) {
  const FilterSpec* f = Spec(ID(a));
  return f ? MakeParams(f->params(nullptr, &m), nullptr) : RichParameterList();
}

// MeshLab's default passes *md.mm() on to the form above, also when the document is empty.
RichParameterList FilterConeLodPlugin::initParameterList(const QAction* a, const MeshDocument& md) {
  const FilterSpec* f = Spec(ID(a));
  return f ? MakeParams(f->params(&md, md.mm()), &md) : RichParameterList();
}

std::map<std::string, QVariant> FilterConeLodPlugin::applyFilter(const QAction* a, const RichParameterList& par,
                                                                 MeshDocument& md, unsigned int& postConditionMask,
                                                                 vcg::CallBackPos* cb) {
  const FilterSpec* f = Spec(ID(a));
  if (!f) throw MLException("ConeLOD: unknown filter");
  Report report([this](const std::string& line, bool isError) {
    log(isError ? GLLogStream::SYSTEM : GLLogStream::FILTER, line);
  });
  const QString message = RunFilter(*f, md, ReadArgs(f->params(&md, md.mm()), par, md), cb, report);
  if (!message.isEmpty()) throw MLException(message);
  if (f->showFaceColour) {
    const int shown = conelod_plugin::ShowFaceColour(md, glContext);
    if (shown != -1) postConditionMask = unsigned(shown);
  }
  std::map<std::string, QVariant> figures;
  for (const auto& kv : report.figures()) figures[kv.first] = QVariant(kv.second);
  return figures;
}

MESHLAB_PLUGIN_NAME_EXPORTER(FilterConeLodPlugin)
