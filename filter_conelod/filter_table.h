// ConeLOD MeshLab plugin — the filters, written once for every MeshLab version.
//
// Each filter is one row of a table (FilterSpec): its name, menu, help, parameters (ParamSpec:
// the key scripts use, the dialog's label, the default and the values it accepts) and one
// function that reads the parameters, calls the core in vcg_ext/conelod and writes the results
// into the document. An adapter per MeshLab plugin API (adapter_2020/: MeshFilterInterface;
// adapter_2022/: FilterPlugin, 2022.02 to 2025.07) turns the table into a plugin; nothing here
// names either interface.
//
// RunFilter is the one place where a filter can fail: it checks every parameter against its
// ParamSpec first (messages name the dialog's labels), runs the filter, catches exceptions, and
// turns a failure into one message that says what was left untouched ("the mesh was not
// changed"), also written to the log (meshlabserver shows only the log). Filters change the
// document only after their core call succeeded, so a failure leaves the mesh as it was.
#pragma once

#include <QString>
#include <QStringList>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "conelod/status.h"
#include "meshlab_api.h"

namespace conelod_plugin {

enum class ParamKind { Bool, Int, Float, AbsPerc, Enum, Position, Direction, OpenFile, SaveFile, Mesh };

// What a numeric parameter accepts: [min, max], either end open or absent.
struct Bound {
  double min = -std::numeric_limits<double>::infinity(), max = std::numeric_limits<double>::infinity();
  bool minOpen = false, maxOpen = false;
  const char* note = nullptr;  // appended to the message, e.g. "0: no limit"
};
Bound AtLeast(double min, const char* note = nullptr);
Bound Above(double min, const char* note = nullptr);
Bound Between(double min, double max, const char* note = nullptr);
Bound AboveUpTo(double min, double max, const char* note = nullptr);  // (min, max]

struct ParamSpec {
  ParamKind kind = ParamKind::Float;
  QString name;                     // the key of scripts (.mlx) and PyMeshLab (lowercased): never changes
  QString label;                    // what the dialog shows: messages name it
  QString help;                     // the dialog's tooltip
  double number = 0;                // default of Bool (0/1), Int, Float, AbsPerc (absolute), Enum
  double absMax = 0;                // AbsPerc: the length that 100 % stands for in the dialog
  vcg::Point3f point{0, 0, 0};      // default of Position, Direction
  QString path;                     // default of OpenFile, SaveFile
  QStringList choices;              // Enum: its entries; OpenFile/SaveFile: the file types
  const MeshModel* mesh = nullptr;  // default of Mesh
  Bound bound;                      // numbers: what the filter accepts
};

ParamSpec BoolParam(const char* name, bool value, const char* label, const char* help);
ParamSpec IntParam(const char* name, int value, const char* label, const char* help, Bound bound = Bound());
ParamSpec FloatParam(const char* name, double value, const char* label, const char* help, Bound bound = Bound());
ParamSpec AbsPercParam(const char* name, double value, double absMax, const char* label, const char* help,
                       Bound bound = Bound());
ParamSpec EnumParam(const char* name, int value, QStringList choices, const char* label, const char* help);
ParamSpec PositionParam(const char* name, vcg::Point3f value, const char* label, const char* help);
ParamSpec DirectionParam(const char* name, vcg::Point3f value, const char* label, const char* help);
ParamSpec OpenFileParam(const char* name, QStringList types, const char* label, const char* help);
ParamSpec SaveFileParam(const char* name, QString type, const char* label, const char* help);
ParamSpec MeshParam(const char* name, const MeshModel* value, const char* label, const char* help);

// The parameter values of one run, read by the adapter from MeshLab's parameter list.
class Args {
 public:
  void set(const QString& name, double number) { numbers_[name] = number; }
  void set(const QString& name, const vcg::Point3f& p) { points_[name] = p; }
  void set(const QString& name, const QString& path) { paths_[name] = path; }
  void set(const QString& name, MeshModel* mesh) { meshes_[name] = mesh; }

  // A name the filter did not declare is a programming error: std::logic_error.
  bool flag(const char* name) const { return number(name) != 0; }
  int integer(const char* name) const { return int(number(name)); }
  double number(const char* name) const;
  vcg::Point3d point(const char* name) const;
  QString path(const char* name) const;
  MeshModel* mesh(const char* name) const;

 private:
  std::map<QString, double> numbers_;
  std::map<QString, vcg::Point3f> points_;
  std::map<QString, QString> paths_;
  std::map<QString, MeshModel*> meshes_;
};

// What a run tells the user: log lines (passed on at once) and named figures (kept for the
// 2022+ adapter, which returns them to the caller, e.g. to PyMeshLab's apply_filter).
class Report {
 public:
  // sink(line, isError): errors go to the log's system level, the rest to the filter level.
  using Sink = std::function<void(const std::string& line, bool isError)>;
  explicit Report(Sink sink) : sink_(std::move(sink)) {}
  void log(const char* format, ...) __attribute__((format(printf, 2, 3)));
  void error(const std::string& line) {
    if (sink_) sink_(line, true);
  }
  void figure(const std::string& key, double value) { figures_[key] = value; }
  const std::map<std::string, double>& figures() const { return figures_; }

 private:
  Sink sink_;
  std::map<std::string, double> figures_;
};

// One run of one filter.
struct FilterCall {
  MeshDocument& doc;
  MeshModel* mesh;  // the current layer; null only for filters that need none
  const Args& args;
  vcg::CallBackPos* cb;  // MeshLab's progress callback (may be null)
  Report& report;
  const std::vector<ParamSpec>& params;  // the filter's parameters (for their labels)
  conelod::Progress progress() const;    // cb as the core's progress
};

// The menus our filters go to (the adapters map them to their API's FilterClass).
enum class Menu { FaceColoring, Measure, Remeshing, MeshCreation };
// What a filter works on: no layer (it reads a file) or the current layer.
enum class Arity { None, SingleMesh };

struct FilterSpec {
  QString name;  // "Cone LOD: ...": scripts name filters by it, never changes
  Menu menu;
  Arity arity;
  int requirements;       // MeshModel::MM_* the filter needs enabled before it runs
  int postConditions;     // MeshModel::MM_* it changes
  QString info;           // HTML help, ending with the paper
  const char* untouched;  // what a failure leaves as it was: "the mesh was not changed"
  // The parameters and their defaults, which may depend on the document (null when MeshLab
  // gives only a mesh) and its current mesh (null in an empty document).
  std::vector<ParamSpec> (*params)(const MeshDocument* doc, const MeshModel* current);
  conelod::Status (*apply)(FilterCall& call);
  // After a success the GUI shows the current mesh in face colour (the groups' colours). The
  // FaceColoring menus do that by themselves as long as the faces stay (MeshLab refreshes what
  // the post-conditions name); a filter that changes the faces needs the adapter's help, since
  // MeshLab then refreshes every attribute and keeps the vertex colour shown.
  bool showFaceColour = false;
};

// Every filter, in the order of the menu; a filter's index is its action id.
const std::vector<FilterSpec>& Filters();

// Runs filter `f` with `args`; returns an empty string on success, otherwise the message (also
// logged as "ConeLOD error: ..."). Never throws.
QString RunFilter(const FilterSpec& f, MeshDocument& doc, const Args& args, vcg::CallBackPos* cb, Report& report);

}  // namespace conelod_plugin
