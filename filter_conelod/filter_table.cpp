// ConeLOD MeshLab plugin — the filter table (see filter_table.h).
#include "filter_table.h"

#include <QElapsedTimer>
#include <QDir>
#include <QFile>
#include <QFileInfo>
#include <QTemporaryDir>
#include <QRegularExpression>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <exception>
#include <limits>
#include <memory>
#include <new>
#include <stdexcept>

#include "builtin_qem.h"
#include "conelod/grouping/cone_grouping.h"
#include "conelod/grouping/culling_cost.h"
#include "conelod/feature/feature_simplify.h"
#include "conelod/grouping/group_colors.h"
#include "conelod/simplify/group_integrity.h"
#include "conelod/simplify/group_qem.h"
#include "conelod/lod/lod_build.h"
#include "conelod/lod/lod_read.h"
#include "conelod/mesh/manifold_check.h"
#include "conelod/mesh/mesh_check.h"
#include "conelod/pca/pca_partition.h"
#include "conelod/budget/pixel_budget.h"
#include "conelod/pca/progressive_cluster_mesh.h"
#include "conelod/mesh/safe_file.h"
#include "conelod/mesh/sampled_distance.h"
#include "conelod/simplify_bridge.h"
#include "conelod/vcg_bridge.h"

#include <vcg/complex/algorithms/update/bounding.h>
#include <vcg/complex/algorithms/update/normal.h>
#include <vcg/complex/algorithms/update/topology.h>

namespace conelod_plugin {

using conelod::Status;

// ---------------------------------------------------------------------------------------------
// Parameters, values, report

Bound AtLeast(double min, const char* note) {
  return Bound{min, std::numeric_limits<double>::infinity(), false, false, note};
}
Bound Above(double min, const char* note) {
  return Bound{min, std::numeric_limits<double>::infinity(), true, false, note};
}
Bound Between(double min, double max, const char* note) { return Bound{min, max, false, false, note}; }
Bound AboveUpTo(double min, double max, const char* note) { return Bound{min, max, true, false, note}; }
static Bound Inside(double min, double max, const char* note = nullptr) { return Bound{min, max, true, true, note}; }

static ParamSpec Spec(ParamKind kind, const char* name, const char* label, const char* help) {
  ParamSpec p;
  p.kind = kind;
  p.name = name;
  p.label = label;
  p.help = help;
  return p;
}

ParamSpec BoolParam(const char* name, bool value, const char* label, const char* help) {
  ParamSpec p = Spec(ParamKind::Bool, name, label, help);
  p.number = value ? 1 : 0;
  return p;
}

ParamSpec IntParam(const char* name, int value, const char* label, const char* help, Bound bound) {
  ParamSpec p = Spec(ParamKind::Int, name, label, help);
  p.number = value;
  p.bound = bound;
  return p;
}

ParamSpec FloatParam(const char* name, double value, const char* label, const char* help, Bound bound) {
  ParamSpec p = Spec(ParamKind::Float, name, label, help);
  p.number = value;
  p.bound = bound;
  return p;
}

ParamSpec AbsPercParam(const char* name, double value, double absMax, const char* label, const char* help,
                       Bound bound) {
  ParamSpec p = Spec(ParamKind::AbsPerc, name, label, help);
  p.number = value;
  p.absMax = absMax;
  p.bound = bound;
  return p;
}

ParamSpec EnumParam(const char* name, int value, QStringList choices, const char* label, const char* help) {
  ParamSpec p = Spec(ParamKind::Enum, name, label, help);
  p.number = value;
  p.choices = std::move(choices);
  return p;
}

ParamSpec PositionParam(const char* name, vcg::Point3f value, const char* label, const char* help) {
  ParamSpec p = Spec(ParamKind::Position, name, label, help);
  p.point = value;
  return p;
}

ParamSpec DirectionParam(const char* name, vcg::Point3f value, const char* label, const char* help) {
  ParamSpec p = Spec(ParamKind::Direction, name, label, help);
  p.point = value;
  return p;
}

ParamSpec OpenFileParam(const char* name, QStringList types, const char* label, const char* help) {
  ParamSpec p = Spec(ParamKind::OpenFile, name, label, help);
  p.choices = std::move(types);
  return p;
}

ParamSpec SaveFileParam(const char* name, QString type, const char* label, const char* help) {
  ParamSpec p = Spec(ParamKind::SaveFile, name, label, help);
  p.choices = QStringList() << type;
  return p;
}

ParamSpec MeshParam(const char* name, const MeshModel* value, const char* label, const char* help) {
  ParamSpec p = Spec(ParamKind::Mesh, name, label, help);
  p.mesh = value;
  return p;
}

template <class Map>
static const typename Map::mapped_type& Find(const Map& map, const char* name) {
  const auto it = map.find(QString(name));
  if (it == map.end()) throw std::logic_error(std::string("the filter reads an undeclared parameter ") + name);
  return it->second;
}

double Args::number(const char* name) const { return Find(numbers_, name); }
vcg::Point3d Args::point(const char* name) const { return vcg::Point3d::Construct(Find(points_, name)); }
QString Args::path(const char* name) const { return Find(paths_, name); }
MeshModel* Args::mesh(const char* name) const { return Find(meshes_, name); }

void Report::log(const char* format, ...) {
  va_list args, again;
  va_start(args, format);
  va_copy(again, args);
  const int n = std::vsnprintf(nullptr, 0, format, args);
  va_end(args);
  std::string line(size_t(std::max(n, 0)), '\0');
  if (n > 0) std::vsnprintf(&line[0], line.size() + 1, format, again);
  va_end(again);
  if (sink_) sink_(line, false);
}

conelod::Progress FilterCall::progress() const {
  vcg::CallBackPos* callback = cb;
  if (!callback) return conelod::Progress();
  return [callback](int percent, const char* stage) { return callback(percent, stage); };
}

namespace {

const char* const kPaperKamiya =
    "M. Kamiya, H. Suzuki, K. Kawachi, <i>LODs for efficient displaying triangle meshes</i> "
    "(University of Tokyo).";
const char* const kPaperHayano =
    "M. Hayano, T. Matsuoka, K. Ueda, <i>Mesh Simplification Using Edge Operation with Feature Detection</i> "
    "(Ricoh Software Research Center).";
const char* const kPaperMizuno =
    "S. Mizuno, M. Okumoto, M. Takata, K. Joe, <i>Polygon reduction for effective 3D model rendering on "
    "different platforms</i>, IPSJ SIG Technical Report 2011-MPS-86.";
const char* const kPaperTsuji =
    "T. Tsuji, H. Zha, R. Kurazume, T. Hasegawa, <i>Face clusters partitioning for hierarchical data "
    "structure and high speed rendering</i> (Kyushu University).";

const char* const kUnchanged = "the mesh was not changed";

Status Invalid(const QString& message) { return Status::Invalid(message.toStdString()); }

// "'Target fraction (0..1)'": how messages name a parameter (by the label the dialog shows).
QString Quoted(const ParamSpec& p) { return "'" + p.label + "'"; }

std::vector<ParamSpec> ParamsOf(const FilterSpec& f, MeshDocument& doc) { return f.params(&doc, doc.mm()); }

// The quoted label of `name` among the filter's parameters (the name itself if it has none).
QString Label(const FilterCall& c, const char* name) {
  for (const ParamSpec& p : c.params)
    if (p.name == name) return Quoted(p);
  return QString("'%1'").arg(name);
}

double Diagonal(const MeshModel* m) { return m && !m->cm.bbox.IsNull() ? double(m->cm.bbox.Diag()) : 0.0; }

// What a filter's collapse does not interpolate, said in the log so that nobody takes it for
// interpolated: a kept vertex's or corner's own attributes stay (conelod simplify interpolates
// them). colour / wedge: false when the filter colours the vertices itself or interpolates them
// (Group-Preserving Quadric Edge Collapse: LayerAttributes).
void LogKeptAttributes(Report& out, const MeshModel& mm, bool colour = true, bool wedge = true,
                       bool vertexTexCoords = true) {
  if (colour && mm.hasDataMask(MeshModel::MM_VERTCOLOR))
    out.log(
        "vertex colours: each kept vertex keeps its own colour, not interpolated (conelod simplify "
        "interpolates colour, normals and texture coordinates)");
  if (vertexTexCoords && mm.hasDataMask(MeshModel::MM_VERTTEXCOORD))
    out.log("vertex texture coordinates: each kept vertex keeps its own, not interpolated");
  if (wedge && mm.hasDataMask(MeshModel::MM_WEDGTEXCOORD))
    out.log(
        "wedge texture coordinates: not kept consistent: a kept corner keeps its coordinates after its vertex "
        "moved, so the texture may stretch or tear (Quadric Edge Collapse Decimation (with texture) and "
        "conelod simplify keep them)");
}

// The layer's attributes the group-preserving collapse interpolates (attribute_quadric.h): the
// vertex colour (RGB, RGBA when some alpha is not 255) and the wedge texture coordinates, per face
// corner of ToIndexedMesh(m, &faceOf)'s faces (the welded mesh keeps their order). Normals are
// not among them: the filter recomputes them from the new faces (UpdateBoxAndNormals).
void LayerAttributes(const MeshModel& mm, const std::vector<size_t>& faceOf, conelod::VertexAttributes& layout,
                     std::vector<float>& corner) {
  layout = conelod::VertexAttributes();
  corner.clear();
  const CMeshO& m = mm.cm;
  if (mm.hasDataMask(MeshModel::MM_VERTCOLOR)) {
    bool alpha = false;
    for (const auto& v : m.vert) alpha |= !v.IsD() && v.cC()[3] != 255;
    layout.colorChannels = alpha ? 4 : 3;
  }
  layout.texCoords = mm.hasDataMask(MeshModel::MM_WEDGTEXCOORD);
  if (layout.empty()) return;
  corner.reserve(3 * faceOf.size() * size_t(layout.channels()));
  for (size_t f : faceOf)
    for (int k = 0; k < 3; ++k) {
      const auto& face = m.face[f];
      for (int c = 0; c < layout.colorChannels; ++c) corner.push_back(face.cV(k)->cC()[c] / 255.0f);
      if (layout.texCoords) {
        corner.push_back(float(face.cWT(k).U()));
        corner.push_back(float(face.cWT(k).V()));
      }
    }
}

// After ApplySimplifiedMesh: the attributes of every corner at its vertex's new position (face o
// of the layer is face o of r; weldedVertex: r.sourceVertex before MapToRepresentatives). A vertex
// takes the colour of its first corner (they differ only at a colour seam, which never moves).
void SetLayerAttributes(CMeshO& m, const conelod::VertexAttributes& layout, const conelod::AttributeQuadrics& aq,
                        const conelod::GroupQemResult& r, const std::vector<uint32_t>& weldedVertex) {
  std::vector<float> value(size_t(layout.channels()));
  std::vector<char> coloured(m.vert.size(), 0);
  for (size_t o = 0; o < r.sourceFace.size() && o < m.face.size(); ++o)
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = r.mesh.faces[o][size_t(k)];
      const auto& q = r.mesh.positions[v];
      aq.Evaluate(r.sourceFace[o], k, weldedVertex[v], vcg::Point3d(q[0], q[1], q[2]), value.data());
      auto& face = m.face[o];
      const size_t vi = size_t(vcg::tri::Index(m, face.V(k)));
      if (layout.colorChannels && !coloured[vi]) {
        coloured[vi] = 1;
        vcg::Color4b rgba = face.V(k)->C();  // RGB: the alpha stays
        for (int c = 0; c < std::min(4, layout.colorChannels); ++c)
          rgba[c] = (unsigned char)std::lround(std::min(1.0f, std::max(0.0f, value[size_t(c)])) * 255.0f);
        face.V(k)->C() = rgba;
      }
      if (layout.texCoords) {
        face.WT(k).U() = value[size_t(layout.texCoordOffset())];
        face.WT(k).V() = value[size_t(layout.texCoordOffset()) + 1];
      }
    }
}

// Per-face quality of the live faces, in ToIndexedMesh order.
std::vector<float> FaceQualities(const CMeshO& m) {
  std::vector<float> q;
  q.reserve(size_t(m.fn));
  for (const auto& f : m.face)
    if (!f.IsD()) q.push_back(float(f.cQ()));
  return q;
}

// The path of a file parameter; refused when empty (no hidden default file is ever read or
// written). MeshLab 2020.09 passes on only a file chosen with "...", so there the message says so.
Status RequirePath(const FilterCall& c, const char* name, QString& path) {
  path = c.args.path(name).trimmed();
  if (!path.isEmpty()) return Status::Ok();
  if (kDialogPassesTypedPaths)
    return Invalid(Label(c, name) + " is empty: type the path of the file or choose it with the '...' button");
  return Invalid(Label(c, name) +
                 " is empty: choose the file with the '...' button beside the box (MeshLab 2020.09 does not pass "
                 "on a path typed into the box)");
}

// What the dialog's file box takes, in this MeshLab's words. MeshLab 2020.09's box
// (IOFileWidget) passes on the file last chosen with its "..." button (whose file dialog takes a
// typed name too) and never the text of the box itself: a path typed or edited there is ignored.
const char* const kLodFileHow =
    kDialogPassesTypedPaths ? "type a path into the box or choose one with '...'"
                            : "choose the file with the '...' button beside the box (its file dialog also takes a "
                              "typed name); MeshLab 2020.09 ignores a path typed or edited in the box itself";
const QString kLodFileHelp = QString("Where to write the .clod file. No default: ") + kLodFileHow +
                             ". A relative path is relative to MeshLab's current directory (meshlabserver: where it "
                             "was started); the log gives the full path.";

// A message about a file that names it ("PATH: why"), once.
QString NameFile(const QString& path, const std::string& why) {
  const QString message = QString::fromStdString(why);
  return message.contains(path) ? message : path + ": " + message;
}

// ---------------------------------------------------------------------------------------------
// Parameters shared by several filters

// The grouping parameters of the grouping, culling-cost and LOD-export filters.
void AddGroupingParams(std::vector<ParamSpec>& p) {
  const conelod::ConeGroupingParams d;
  p.push_back(FloatParam("ConeWeight", d.coneWeight, "Cone weight k_c",
                         "Weight of the cone term v_c = (pi - c)/pi, c = the merged group's cone half-angle. "
                         "The paper found this term matters most for culling.",
                         AtLeast(0)));
  p.push_back(FloatParam("ShapeWeight", d.shapeWeight, "Shape weight k_s",
                         "Weight of the shape term v_s = projected area / area of the enclosing circle "
                         "(round groups score higher).",
                         AtLeast(0)));
  p.push_back(FloatParam("SizeWeight", d.sizeWeight, "Size weight k_n",
                         "Weight of the size term v_n = (N - n)/N (smaller groups score higher).", AtLeast(0)));
  p.push_back(FloatParam("ConeThresholdDeg", d.coneThresholdDeg, "Cone threshold (deg)",
                         "Level-1 limit on a group's cone half-angle, in degrees: pairs whose merged cone "
                         "would reach it are never merged. 180 or more: no limit.",
                         Above(0, "180 or more: no limit")));
  p.push_back(FloatParam("ThresholdGrowth", d.thresholdGrowth, "Threshold growth per level",
                         "The cone threshold is multiplied by this factor at each level above the first (>= 1).",
                         AtLeast(1)));
  p.push_back(IntParam("MaxLevels", d.maxLevels, "Max levels", "At most this many hierarchy levels.", Between(1, 64)));
  p.push_back(IntParam("MinTopGroups", d.minTopGroups, "Min top-level groups",
                       "Merging stops once a level has this many groups (or fewer).", AtLeast(1)));
}

conelod::ConeGroupingParams ReadGroupingParams(const Args& a) {
  conelod::ConeGroupingParams p;
  p.chunkFaces = conelod::kGroupingChunkFaces;
  p.coneWeight = a.number("ConeWeight");
  p.shapeWeight = a.number("ShapeWeight");
  p.sizeWeight = a.number("SizeWeight");
  p.coneThresholdDeg = a.number("ConeThresholdDeg");
  p.thresholdGrowth = a.number("ThresholdGrowth");
  p.maxLevels = a.integer("MaxLevels");
  p.minTopGroups = a.integer("MinTopGroups");
  p.threads = 0;  // every core: the groups are the same for every thread count (cone_grouping.h)
  return p;
}

// The collapse options shared by the group-preserving QEM and the LOD export (which runs it per level).
void AddCollapseOptionParams(std::vector<ParamSpec>& p, const conelod::GroupQemParams& d,
                             const char* boundaryWeightHelp) {
  p.push_back(FloatParam("QualityThr", d.qualityThr, "Quality threshold",
                         "Collapses creating faces of quality (2 area / longest edge^2) below this are penalised, "
                         "as in the built-in filter. 0: no penalty.",
                         Between(0, 1)));
  p.push_back(BoolParam("OptimalPlacement", d.optimalPlacement, "Optimal position of simplified vertices",
                        "The merged vertex goes where the quadric error is least; otherwise to the better endpoint."));
  p.push_back(BoolParam("PreserveBoundary", d.preserveBoundary, "Preserve Boundary of the mesh",
                        "Vertices on the mesh border never move."));
  p.push_back(
      FloatParam("BoundaryWeight", d.boundaryWeight, "Boundary Preserving Weight", boundaryWeightHelp, AtLeast(0)));
  p.push_back(BoolParam("PreserveNormal", d.preserveNormal, "Preserve Normal",
                        "Refuse collapses that turn a face's normal by more than about 78 degrees (fold-overs)."));
}

void ReadCollapseOptions(const Args& a, conelod::GroupQemParams& q) {
  q.qualityThr = a.number("QualityThr");
  q.optimalPlacement = a.flag("OptimalPlacement");
  q.preserveBoundary = a.flag("PreserveBoundary");
  q.boundaryWeight = a.number("BoundaryWeight");
  q.preserveNormal = a.flag("PreserveNormal");
}

// The face-count target of both simplifications: 'Target number of faces' when it is > 0,
// otherwise 'Target fraction' x the faces (rounded, at least 1), 0 (no target) when both are 0.
void AddFaceTargetParams(std::vector<ParamSpec>& p) {
  p.push_back(IntParam("TargetFaceNum", 0, "Target number of faces",
                       "Stop at this many faces. 0: the target is the fraction below.",
                       AtLeast(0, "0: use the target fraction")));
  p.push_back(FloatParam("TargetPerc", 0.5, "Target fraction (0..1)",
                         "Used when the target number of faces is 0: the target is this fraction of the current "
                         "face count (0.1 = 10 %). 0 with a target number of 0: no face-count target.",
                         Between(0, 1)));
}

size_t FaceTarget(const Args& a, int faces) {
  const int count = a.integer("TargetFaceNum");
  const double fraction = a.number("TargetPerc");
  if (count > 0) return size_t(count);
  if (fraction > 0) return std::max<size_t>(1, size_t(std::llround(fraction * double(faces))));
  return 0;
}

// ---------------------------------------------------------------------------------------------
// Cone LOD: Normal Cone Face Grouping

std::vector<ParamSpec> ConeGroupingSpecs(const MeshDocument*, const MeshModel*) {
  std::vector<ParamSpec> p;
  AddGroupingParams(p);
  p.push_back(IntParam("DisplayLevel", 1, "Display level",
                       "Hierarchy level shown as per-face quality and colour (1 = finest). A level above "
                       "the top is shown as the top level.",
                       AtLeast(1)));
  return p;
}

Status ApplyConeGrouping(FilterCall& c) {
  MeshModel& mm = *c.mesh;
  int displayLevel = c.args.integer("DisplayLevel");
  std::vector<size_t> faceOf;
  // Welded by position: a seam the mesh repeats is no border to the groups (the layer keeps its vertices).
  const conelod::IndexedMesh im = conelod::ToWeldedIndexedMesh(mm.cm, &faceOf);
  conelod::GroupHierarchy h;
  QElapsedTimer timer;
  timer.start();
  const Status s = conelod::BuildConeHierarchy(im, ReadGroupingParams(c.args), h, c.progress());
  if (!s.ok()) return s;
  const double seconds = timer.elapsed() / 1000.0;
  if (displayLevel > h.levelCount()) {
    c.report.log("%s %d is above the %d levels built: showing level %d", qUtf8Printable(Label(c, "DisplayLevel")),
                 displayLevel, h.levelCount(), h.levelCount());
    displayLevel = h.levelCount();
  }

  mm.updateDataMask(MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR);
  conelod::WriteGroupResults(mm.cm, faceOf, h, displayLevel);

  c.report.log("Normal cone grouping: %d faces, %d levels in %.3f s; quality and colour = groups of level %d",
               int(im.faceCount()), h.levelCount(), seconds, displayLevel);
  for (int l = 1; l <= h.levelCount(); ++l) {
    const conelod::GroupLevel& lv = h.level(l);
    c.report.log("level %d: groups %d, max_cone_deg %.2f, mean_cone_deg %.2f, limit_deg %.1f, uncullable %d", l,
                 int(lv.groups.size()), lv.maxConeDeg(), lv.meanConeDeg(), lv.thresholdDeg, lv.uncullableGroups());
  }
  c.report.figure("levels", h.levelCount());
  c.report.figure("level1_groups", double(h.level(1).groups.size()));
  return Status::Ok();
}

// ---------------------------------------------------------------------------------------------
// Cone LOD: Cluster Culling Cost

std::vector<ParamSpec> CullingCostSpecs(const MeshDocument*, const MeshModel*) {
  std::vector<ParamSpec> p;
  AddGroupingParams(p);
  p.push_back(
      IntParam("Views", 1000, "View directions", "Number of view directions, uniform on the sphere.", Between(1, 1e7)));
  p.push_back(FloatParam("CameraDistance", 0.0, "Camera distance",
                         "0: orthographic views (the paper's test). Otherwise a perspective eye at this many "
                         "bounding-sphere radii (> 1) from the model's centre."));
  return p;
}

Status ApplyCullingCost(FilterCall& c) {
  conelod::CullingCostParams cp;
  cp.views = c.args.integer("Views");
  cp.cameraDistance = c.args.number("CameraDistance");
  if (!(cp.cameraDistance == 0 || (cp.cameraDistance > 1 && std::isfinite(cp.cameraDistance))))
    return Invalid(Label(c, "CameraDistance") + " must be 0 (orthographic views) or > 1 (bounding-sphere radii)");

  const conelod::IndexedMesh im = conelod::ToWeldedIndexedMesh(c.mesh->cm);
  conelod::GroupHierarchy h;
  Status s = conelod::BuildConeHierarchy(im, ReadGroupingParams(c.args), h, conelod::SubProgress(c.progress(), 0, 50));
  if (!s.ok()) return s;
  conelod::CullingCostResult r;
  s = conelod::EvaluateCullingCost(im, h, cp, r, conelod::SubProgress(c.progress(), 50, 100));
  if (!s.ok()) return s;

  Report& out = c.report;
  out.log("Cluster culling cost over %d %s views: %d faces, %d levels (%d groups at level 1, %d at the top)", r.views,
          r.perspective ? "perspective" : "orthographic", int(im.faceCount()), h.levelCount(),
          int(h.level(1).groups.size()), int(h.level(h.levelCount()).groups.size()));
  out.log("two_state_cost %.4f (min %.4f, max %.4f)", r.twoState.mean, r.twoState.min, r.twoState.max);
  out.log("three_state_cost %.4f (min %.4f, max %.4f)", r.threeState.mean, r.threeState.min, r.threeState.max);
  out.log("rejected_fraction %.4f  ideal_fraction %.4f  (%.1f%% of the ideal culled at group level)",
          r.rejectedFraction, r.idealFraction, r.idealFraction > 0 ? 100 * r.rejectedFraction / r.idealFraction : 0.0);
  out.log("front_accepted_fraction %.4f  mean_group_tests %.1f", r.frontAcceptedFraction, r.meanGroupTests);
  out.figure("two_state_cost", r.twoState.mean);
  out.figure("three_state_cost", r.threeState.mean);
  out.figure("rejected_fraction", r.rejectedFraction);
  out.figure("ideal_fraction", r.idealFraction);
  return Status::Ok();
}

// ---------------------------------------------------------------------------------------------
// Cone LOD: Group-Preserving Quadric Edge Collapse

std::vector<ParamSpec> GroupQemSpecs(const MeshDocument*, const MeshModel*) {
  const conelod::GroupQemParams d;
  std::vector<ParamSpec> p;
  AddFaceTargetParams(p);
  p.push_back(FloatParam("MaxErrorPerc", 0.0, "Max error (% of bbox diagonal)",
                         "If non zero, no collapse whose quadric error (RMS distance) exceeds this percentage of "
                         "the bounding-box diagonal is done. 0: no limit.",
                         AtLeast(0, "0: no limit")));
  // The default is the normal cone groups (conelod simplify --groups cone:auto): a freshly loaded
  // mesh has no group ids, and a per-face quality it came with (a scan's confidence) is no grouping.
  p.push_back(EnumParam("GroupSource", 1,
                        QStringList() << "Per-face quality"
                                      << "Normal cone groups",
                        "Groups",
                        "Normal cone groups (the default): computed now with the default grouping parameters, "
                        "at the normal cone level below. Per-face quality: the group ids already on the mesh "
                        "(e.g. from Cone LOD: Normal Cone Face Grouping; equal values = one group)."));
  p.push_back(IntParam("GroupLevel", 0, "Normal cone level (0 = automatic)",
                       "Hierarchy level of the normal cone groups (1 = finest); used when Groups is Normal cone "
                       "groups. 0: automatic, the finest level whose groups leave at least 8 faces per group at "
                       "the target (the top level when none does).",
                       AtLeast(0, "0: automatic")));
  p.push_back(EnumParam("Mode", d.mode == conelod::GroupMode::Paper ? 1 : 0,
                        QStringList() << "Integrity"
                                      << "Paper",
                        "Group mode",
                        "Integrity: every group stays one non-empty piece, and group contours and corners move and "
                        "merge like any vertex (as accurate as the built-in Quadric Edge Collapse). Paper: "
                        "conditions 1 and 2 of Kamiya, Suzuki and Kawachi, group corners fixed."));
  p.push_back(BoolParam("Condition1", d.condition1, "Condition 1: keep groups whole",
                        "Refuse collapses that split a group or remove its last faces (in Integrity mode, the "
                        "exact integrity test). Off, with condition 2 off: the plain collapse."));
  p.push_back(BoolParam("Condition2", d.condition2, "Condition 2: no new group corners",
                        "Paper mode: refuse collapses that create a vertex where 3 or more groups meet."));
  p.push_back(BoolParam("KeepCones", d.keepCones, "Keep normal cones",
                        "Normal cone groups: refuse collapses that would widen a group's normal cone past its "
                        "level's threshold (the groups stay as cullable as they were built)."));
  p.push_back(BoolParam("LockGroupBoundaries", d.lockGroupBoundaries, "Lock group boundaries",
                        "No vertex on a group boundary moves: group contours stay exactly as they are."));
  p.push_back(BoolParam("KeepComponents", false, "Keep every component",
                        "Off (default): when no allowed collapse is left above the target, whole connected "
                        "components made of whole groups are removed, smallest first, until the target is reached "
                        "(as the built-in filter drops small pieces); no group is ever split. On: no component is "
                        "removed, and the run stops at the floor it reached."));
  AddCollapseOptionParams(p, d, "Weight of the quadrics that keep mesh borders (and group contours) in place.");
  p.push_back(FloatParam("AttributeWeight", 0.0, "Attribute weight",
                         "The layer's vertex colour and wedge texture coordinates are interpolated at each new "
                         "vertex (texture seams never move). How much an attribute change costs against geometric "
                         "error, as conelod simplify --attribute-weight: 1 = a full-scale change as much as a "
                         "distance of 0.3 % of the diagonal. 0 (the default): the attribute-free collapse order, so "
                         "that a colour MeshLab gave the layer (a scan's intensity read as grey) does not change the "
                         "geometry; the attributes are still interpolated.",
                         AtLeast(0)));
  return p;
}

Status ApplyGroupQem(FilterCall& c) {
  MeshModel& mm = *c.mesh;
  // As `conelod simplify` by default: passes then the queue, memoryless steps, components may go
  // and flips unblock only where the target is not reached otherwise (issue 25).
  conelod::GroupQemParams p = conelod::OneTargetParams(FaceTarget(c.args, mm.cm.fn));
  p.maxError = c.args.number("MaxErrorPerc") / 100.0;
  p.condition1 = c.args.flag("Condition1");
  p.condition2 = c.args.flag("Condition2");
  p.lockGroupBoundaries = c.args.flag("LockGroupBoundaries");
  p.mode = c.args.integer("Mode") == 1 ? conelod::GroupMode::Paper : conelod::GroupMode::Integrity;
  p.keepCones = c.args.flag("KeepCones");
  p.removeComponents = !c.args.flag("KeepComponents");
  if (conelod::BoundToInput(p)) p.refreshRatio = 0;  // as the CLI
  const double attributeWeight = c.args.number("AttributeWeight");
  if (!(attributeWeight >= 0) || !std::isfinite(attributeWeight))
    return Invalid(Label(c, "AttributeWeight") + " must be >= 0");
  ReadCollapseOptions(c.args, p);
  if (p.targetFaces == 0 && p.maxError == 0)
    return Invalid("give a target: " + Label(c, "TargetFaceNum") + ", " + Label(c, "TargetPerc") + " or " +
                   Label(c, "MaxErrorPerc"));
  const bool coneSource = c.args.integer("GroupSource") == 1;
  int level = c.args.integer("GroupLevel");
  if (coneSource && level == 0 && p.targetFaces == 0)
    return Invalid(Label(c, "GroupLevel") + " 0 (automatic) chooses the level for a face count: give " +
                   Label(c, "TargetFaceNum") + " or " + Label(c, "TargetPerc"));
  if (p.keepCones && !coneSource)
    return Invalid(Label(c, "KeepCones") + " keeps the cones of normal cone groups: set " + Label(c, "GroupSource") +
                   " to Normal cone groups");

  std::vector<size_t> faceOf;
  std::vector<uint32_t> representative;
  // Welded by position (weld.h): a seam the mesh repeats is no border to the groups nor to the
  // collapse; the layer gets the simplified mesh with one vertex per position.
  const conelod::IndexedMesh im = conelod::ToWeldedIndexedMesh(mm.cm, &faceOf, &representative);
  Status s = conelod::RequireValidForFaces(im);
  if (!s.ok()) return s;
  QElapsedTimer timer;
  timer.start();
  std::vector<int> groups;
  conelod::Progress progress = c.progress();
  conelod::GroupHierarchy h;
  const bool automatic = coneSource && level == 0;
  if (coneSource) {
    // Every core: the groups are the same for every thread count.
    s = conelod::BuildConeHierarchy(im, conelod::CollapseGroupingParams(p.targetFaces, automatic, 0), h,
                                    conelod::SubProgress(progress, 0, 30));
    if (!s.ok()) return s;
    if (automatic) {
      level = conelod::AutoGroupLevel(h, p.targetFaces);
    } else if (level > h.levelCount()) {
      c.report.log("%s %d is above the %d levels built: using level %d", qUtf8Printable(Label(c, "GroupLevel")), level,
                   h.levelCount(), h.levelCount());
      level = h.levelCount();
    }
    groups = h.level(level).faceGroup;
    if (p.keepCones) p.coneBound = conelod::LevelConeBounds(h, level);
    progress = conelod::SubProgress(progress, 30, 100);
  } else {
    if (!mm.hasDataMask(MeshModel::MM_FACEQUALITY))
      return Invalid(
          "the mesh has no per-face quality to use as group ids: run Cone LOD: Normal Cone Face Grouping "
          "first, or set " +
          Label(c, "GroupSource") + " to Normal cone groups");
    const std::vector<float> q = FaceQualities(mm.cm);
    std::vector<std::vector<int>> ids;
    s = conelod::GroupIdsFromValues({&q}, ids);
    if (!s.ok()) return s;
    groups = std::move(ids[0]);
  }
  conelod::VertexAttributes layout;
  conelod::AttributeQuadrics attributes;
  {
    std::vector<float> corner;
    LayerAttributes(mm, faceOf, layout, corner);
    if (!layout.empty()) {
      s = attributes.Init(im, layout, std::move(corner), attributeWeight);
      if (!s.ok()) return s;
      attributes.AllowSeamMoves(true);  // junctions and small charts may go, as in conelod simplify
    }
  }
  conelod::GroupQemResult r;
  s = conelod::SimplifyPreservingGroups(im, groups, p, r, progress, {}, nullptr,
                                        layout.empty() ? nullptr : &attributes);
  if (!s.ok()) return s;
  const double seconds = timer.elapsed() / 1000.0;

  std::vector<int> groupsAfter(r.sourceFace.size());
  for (size_t f = 0; f < r.sourceFace.size(); ++f) groupsAfter[f] = groups[r.sourceFace[f]];
  conelod::GroupIntegrity gi;
  conelod::MeasureGroupIntegrity(im, groups, r.mesh, groupsAfter, gi);
  gi.groupsRemoved = int(r.stats.groupsRemoved);
  // A normal cone level that cannot reach the target: the mesh stays as it was, and the message
  // says what was reached and which level would reach it.
  // (Not with the automatic level, whose stop is logged as any other, nor without condition 1
  // (no group then stops anything), nor with the lock, a maximum error or KeepCones: those stop
  // early by choice.)
  if (coneSource && !automatic && p.targetFaces > 0 && r.mesh.faceCount() > p.targetFaces && p.condition1 &&
      !p.lockGroupBoundaries && p.maxError == 0 && !p.keepCones) {
    const int would = conelod::AutoGroupLevel(h, p.targetFaces);
    const std::string message =
        "the target of " + std::to_string(p.targetFaces) + " faces cannot be reached with the " +
        std::to_string(h.level(level).groups.size()) + " normal cone groups of level " + std::to_string(level) +
        ": stopped at " + std::to_string(r.mesh.faceCount()) + " faces (" + conelod::ToString(r.stats.stop) + "); " +
        (would > level
             ? Label(c, "GroupLevel").toStdString() + " " + std::to_string(would) + " (or 0, automatic) would reach it"
             : std::string("no coarser level has fewer groups: try a larger target"));
    c.report.log("%s", message.c_str());
    return Invalid(QString::fromStdString(message));
  }
  const double coneLimitDeg = coneSource ? std::min(h.level(level).thresholdDeg, 180.0) : 0;
  const int conesOver = coneSource ? conelod::CountConesOverLimit(r.mesh, groupsAfter, coneLimitDeg) : 0;

  // The groups' colours are shown after the filter (FilterSpec::showFaceColour): normal cone groups
  // get a colour each, as do per-face quality groups on a mesh without face colours.
  const bool hadFaceColour = mm.hasDataMask(MeshModel::MM_FACECOLOR);
  mm.updateDataMask(MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR);
  const std::vector<uint32_t> weldedVertex = r.sourceVertex;
  conelod::MapToRepresentatives(representative, r.sourceVertex);
  conelod::ApplySimplifiedMesh(mm.cm, faceOf, r.mesh, r.sourceFace, r.sourceVertex);
  if (!layout.empty()) SetLayerAttributes(mm.cm, layout, attributes, r, weldedVertex);
  for (size_t f = 0; f < groupsAfter.size(); ++f) {  // faces are in the same order as the groups after compaction
    if (coneSource) mm.cm.face[f].Q() = CMeshO::FaceType::QualityType(groupsAfter[f]);
    if (coneSource || !hadFaceColour) mm.cm.face[f].C() = conelod::GroupColor(groupsAfter[f]);
  }
  if (mm.hasDataMask(MeshModel::MM_FACEFACETOPO)) vcg::tri::UpdateTopology<CMeshO>::FaceFace(mm.cm);
  if (mm.hasDataMask(MeshModel::MM_VERTFACETOPO)) vcg::tri::UpdateTopology<CMeshO>::VertexFace(mm.cm);
  UpdateBoxAndNormals(mm);

  Report& out = c.report;
  const std::string source =
      (coneSource ? "normal cone groups, level " + std::to_string(level) + (automatic ? " (automatic)" : "")
                  : std::string("per-face quality groups")) +
      ", " + conelod::ToString(p.mode) + " mode";
  out.log("Group-preserving QEM (%s): faces_in %d faces_out %d target %d (%s) seconds %.3f", source.c_str(),
          int(im.faceCount()), int(r.mesh.faceCount()), int(p.targetFaces), conelod::ToString(r.stats.stop), seconds);
  out.log(
      "groups_before %d groups_after %d groups_split %d groups_vanished %d groups_disconnected_in %d "
      "integrity_percent %.2f",
      gi.groupsBefore, gi.groupsAfter, gi.groupsSplit, gi.groupsVanished, gi.groupsDisconnectedBefore,
      100 * gi.intact());
  if (gi.groupsDisconnectedBefore)
    out.log("%d groups were already in several pieces in the input: each piece was kept as it was",
            gi.groupsDisconnectedBefore);
  out.log("components_removed %d groups_removed %d faces_removed_with_components %d%s", int(r.stats.componentsRemoved),
          int(r.stats.groupsRemoved), int(r.stats.facesRemovedWithComponents),
          r.stats.componentsRemoved > 0
              ? " (whole components of whole groups, smallest first; KeepComponents refuses it)"
              : "");
  if (r.stats.edgeFlips > 0)
    out.log("edge_flips %d collapses_unblocked %d (edges flipped inside groups where the link condition refused)",
            int(r.stats.edgeFlips), int(r.stats.collapsesUnblocked));
  const std::string floorReason = conelod::DescribeFloor(r.stats, p);
  if (!floorReason.empty()) out.log("target_reached false floor %d: %s", int(r.mesh.faceCount()), floorReason.c_str());
  if (coneSource)
    out.log("cones_over_threshold %d of %d groups (level %d threshold %.1f deg%s)", conesOver, gi.groupsAfter, level,
            coneLimitDeg, p.keepCones ? qUtf8Printable(", " + Label(c, "KeepCones")) : "");
  out.log(
      "collapses %d; refused evaluations: topology %d, condition 1 %d, condition 2 %d, lock %d, fixed %d, "
      "geometry %d, cone %d",
      int(r.stats.collapses), int(r.stats.refusedTopology), int(r.stats.refusedCondition1),
      int(r.stats.refusedCondition2), int(r.stats.refusedLock), int(r.stats.refusedFixed), int(r.stats.refusedGeometry),
      int(r.stats.refusedCone));
  if (!layout.empty())
    out.log(
        "attributes interpolated at each new vertex (attribute weight %g): %s%s%s; %d seam vertices (moved at a cost; "
        "their texture stays in its charts)",
        attributeWeight, layout.colorChannels ? "vertex colours" : "",
        layout.colorChannels && layout.texCoords ? ", " : "",
        layout.texCoords ? "wedge texture coordinates (seams kept)" : "", int(attributes.seamVertices()));
  LogKeptAttributes(out, mm, layout.colorChannels == 0, !layout.texCoords);
  out.figure("faces_out", double(r.mesh.faceCount()));
  out.figure("groups_before", gi.groupsBefore);
  out.figure("groups_after", gi.groupsAfter);
  out.figure("integrity_percent", 100 * gi.intact());
  out.figure("components_removed", double(r.stats.componentsRemoved));
  out.figure("groups_removed", double(r.stats.groupsRemoved));
  if (coneSource) {
    out.figure("group_level", level);
    out.figure("cones_over_threshold", conesOver);
  }
  return Status::Ok();
}

// ---------------------------------------------------------------------------------------------
// Cone LOD: Group Integrity

std::vector<ParamSpec> GroupIntegritySpecs(const MeshDocument* doc, const MeshModel* current) {
  // The default reference: the first other layer (the copy made before an in-place simplification).
  const MeshModel* reference = current;
  for (const MeshModel* m : doc ? Layers(*doc) : std::vector<const MeshModel*>())
    if (m != current) {
      reference = m;
      break;
    }
  return {MeshParam("ReferenceMesh", reference, "Reference mesh",
                    "The mesh whose groups (per-face quality) are the reference: the mesh before the "
                    "simplification, kept as a layer of its own (Filters > Mesh Layer > Duplicate Current Layer "
                    "before simplifying). The current mesh is measured against it.")};
}

Status ApplyGroupIntegrity(FilterCall& c) {
  MeshModel* cur = c.mesh;
  MeshModel* ref = c.args.mesh("ReferenceMesh");
  for (MeshModel* m : {ref, cur})
    if (!m->hasDataMask(MeshModel::MM_FACEQUALITY))
      return Invalid(QString("layer '%1' has no per-face quality to read group ids from").arg(m->label()));
  const conelod::IndexedMesh curMesh = conelod::ToIndexedMesh(cur->cm);
  const std::vector<float> qc = FaceQualities(cur->cm);
  Report& out = c.report;
  if (ref == cur) {
    // Comparing a layer with itself would always say 100 %: count its groups instead, and say how
    // to compare with the mesh before a simplification.
    std::vector<std::vector<int>> ids;
    Status s = conelod::GroupIdsFromValues({&qc}, ids);
    if (!s.ok()) return s;
    const conelod::GroupPieces pieces = conelod::CountGroupPieces(curMesh, ids[0]);
    const int inPieces = int(std::count_if(pieces.pieces.begin(), pieces.pieces.end(), [](int n) { return n > 1; }));
    out.log(
        "Group integrity: the reference mesh is '%s' itself, so there is nothing to compare (a mesh simplified "
        "in place keeps no copy of itself before). To measure a simplification, duplicate the layer first "
        "(Filters > Mesh Layer > Duplicate Current Layer), simplify one of the two and pick the other as %s.",
        qUtf8Printable(cur->label()), qUtf8Printable(Label(c, "ReferenceMesh")));
    out.log("groups %d groups_in_several_pieces %d", int(pieces.ids.size()), inPieces);
    out.figure("groups", double(pieces.ids.size()));
    out.figure("groups_in_several_pieces", inPieces);
    return Status::Ok();
  }
  const conelod::IndexedMesh refMesh = conelod::ToIndexedMesh(ref->cm);
  const std::vector<float> qr = FaceQualities(ref->cm);
  std::vector<std::vector<int>> ids;
  Status s = conelod::GroupIdsFromValues({&qr, &qc}, ids);
  if (!s.ok()) return s;
  conelod::GroupIntegrity gi;
  s = conelod::MeasureGroupIntegrity(refMesh, ids[0], curMesh, ids[1], gi);
  if (!s.ok()) return s;
  out.log("Group integrity of '%s' against '%s' (group id = per-face quality):", qUtf8Printable(cur->label()),
          qUtf8Printable(ref->label()));
  out.log(
      "groups_before %d groups_after %d groups_split %d groups_vanished %d groups_disconnected_before %d "
      "groups_disconnected_after %d groups_new %d integrity_percent %.2f",
      gi.groupsBefore, gi.groupsAfter, gi.groupsSplit, gi.groupsVanished, gi.groupsDisconnectedBefore,
      gi.groupsDisconnectedAfter, gi.groupsNew, 100 * gi.intact());
  auto list = [](const std::vector<int>& v) {
    QStringList l;
    for (int id : v) l << QString::number(id);
    return l.join(" ");
  };
  if (!gi.splitIds.empty()) out.log("split groups (first ones): %s", qUtf8Printable(list(gi.splitIds)));
  if (!gi.vanishedIds.empty()) out.log("vanished groups (first ones): %s", qUtf8Printable(list(gi.vanishedIds)));
  out.figure("groups_before", gi.groupsBefore);
  out.figure("groups_after", gi.groupsAfter);
  out.figure("groups_split", gi.groupsSplit);
  out.figure("groups_vanished", gi.groupsVanished);
  out.figure("integrity_percent", 100 * gi.intact());
  return Status::Ok();
}

// ---------------------------------------------------------------------------------------------
// Cone LOD: Feature-Preserving Edge Simplification

std::vector<ParamSpec> FeatureSimplifySpecs(const MeshDocument*, const MeshModel* m) {
  const conelod::FeatureSimplifyParams d;
  std::vector<ParamSpec> p;
  p.push_back(FloatParam("FeatureAngleDeg", d.featureAngleDeg, "Feature angle A_t (deg)",
                         "An edge is a feature edge when its dihedral angle A is at most this. A is the angle the "
                         "two faces make at the edge (the paper's definition): 180 on a flat region, 90 on a "
                         "cube edge, near 0 on a knife edge.",
                         Between(0, 180)));
  p.push_back(BoolParam("ExtendFeatureLines", d.extendFeatureLines, "Extend feature lines",
                        "Close gaps in feature lines by edge swaps when the swapped edge is itself a feature "
                        "edge (the paper's 3.1)."));
  p.push_back(FloatParam("FeatureCurvature", d.featureCurvature, "Feature vertex curvature K_t",
                         "A vertex without feature edges whose |K| D^2 reaches this is a feature vertex (kept); "
                         "K = discrete Gaussian curvature, D = bounding-box diagonal. 0 = off.",
                         AtLeast(0, "0: off")));
  p.push_back(FloatParam("CurvatureThreshold", d.curvatureThreshold, "Curvature threshold",
                         "Vertices whose |K| D^2 (smooth) or |M| D (on a feature line; M = turning angle over "
                         "half the two edges' length) reaches this are not removed: only the flatter parts are "
                         "simplified. 0 = no limit.",
                         AtLeast(0, "0: no limit")));
  p.push_back(AbsPercParam("MaxErrorDistance", 0.0, Diagonal(m), "Max error distance",
                           "Stop criterion: a collapse is applied only if every removed vertex of the original "
                           "mesh stays within this distance of the result (absolute, or % of the bounding-box "
                           "diagonal). 0 = off.",
                           AtLeast(0, "0: off")));
  AddFaceTargetParams(p);
  p.push_back(BoolParam("GrowErrorBound", d.growErrorBound, "Grow the error bound",
                        "With a target face count: simplify under an error bound that starts tiny and grows only "
                        "when no collapse fits (beyond the paper; much closer to the original). Off: the paper's "
                        "pure curvature order up to the target."));
  p.push_back(BoolParam("MarkFeatures", true, "Mark the features",
                        "Select the feature vertices, colour the vertices (red: feature line, blue: feature "
                        "vertex) and make every non-feature edge faux: the layer's wireframe in Polygonal "
                        "Modality (layer dialog) then draws the feature lines only."));
  return p;
}

Status ApplyFeatureSimplify(FilterCall& c) {
  MeshModel& mm = *c.mesh;
  conelod::FeatureSimplifyParams params;
  params.featureAngleDeg = c.args.number("FeatureAngleDeg");
  params.extendFeatureLines = c.args.flag("ExtendFeatureLines");
  params.featureCurvature = c.args.number("FeatureCurvature");
  params.curvatureThreshold = c.args.number("CurvatureThreshold");
  params.maxErrorDistance = c.args.number("MaxErrorDistance");
  params.growErrorBound = c.args.flag("GrowErrorBound");
  params.targetFaceCount = FaceTarget(c.args, mm.cm.fn);
  const bool mark = c.args.flag("MarkFeatures");
  if (params.targetFaceCount == 0 && params.maxErrorDistance == 0)
    return Invalid("give a stop criterion: " + Label(c, "TargetFaceNum") + ", " + Label(c, "TargetPerc") + " or " +
                   Label(c, "MaxErrorDistance"));

  std::vector<size_t> faceOf;
  const conelod::IndexedMesh im = conelod::ToIndexedMesh(mm.cm, &faceOf);
  // Wedge texture coordinates: their seams are feature lines (a seam vertex goes only along its
  // seam, junctions and seam ends stay), so that no collapse drags coordinates across a seam.
  const bool wedges = mm.hasDataMask(MeshModel::MM_WEDGTEXCOORD);
  if (wedges) params.seamEdges = conelod::WedgeSeamEdges(mm.cm, faceOf, im);
  conelod::FeatureSimplifyResult r;
  QElapsedTimer timer;
  timer.start();
  const Status s = conelod::FeatureSimplify(im, params, r, c.progress());
  if (!s.ok()) return s;
  const double seconds = timer.elapsed() / 1000.0;

  // The wedge texture coordinates: off the seams each kept vertex the quadric's value at its
  // position, on them its own side's values.
  if (wedges) {
    const size_t seamVertices = conelod::SurvivorWedgeTexCoords(mm.cm, faceOf, r);
    c.report.log(
        "wedge texture coordinates: %d seam edges kept as feature lines (never crossed by a collapse); each kept "
        "vertex off the seams takes the coordinates that the attribute quadric of the vertices its collapses took "
        "over gives at its position, the %d on a seam keep each side's own",
        int(params.seamEdges.size()), int(seamVertices));
  }
  // The vertex normals, as conelod feature-simplify: each kept vertex the normalised quadric mean
  // of the layer's normals of the vertices it took over (not recomputed from the new faces).
  conelod::MeanSurvivorNormalsAndTexCoords(mm.cm, r, true, false);
  c.report.log(
      "vertex normals: each kept vertex takes the normal (normalised) that the attribute quadric of the vertices "
      "its collapses took over gives at its position (as conelod feature-simplify); not recomputed from the new "
      "faces");
  // Per-vertex texture coordinates (without wedges): as conelod feature-simplify, off the seams
  // (positions held by two vertices) the quadric's value.
  const bool vertexTexCoords = !wedges && mm.hasDataMask(MeshModel::MM_VERTTEXCOORD);
  if (vertexTexCoords) {
    const size_t kept = conelod::MeanSurvivorNormalsAndTexCoords(mm.cm, r, false, true);
    c.report.log(
        "vertex texture coordinates: each kept vertex takes the coordinates that the attribute quadric of the "
        "vertices its collapses took over gives at its position; the %d on a seam (a position held by two "
        "vertices) keep their own",
        int(kept));
  }
  // The vertex colour: the marks, or each kept vertex the mean of those it took over.
  LogKeptAttributes(c.report, mm, false, false, !vertexTexCoords);
  if (!mark && mm.hasDataMask(MeshModel::MM_VERTCOLOR)) {
    conelod::MeanSurvivorColours(mm.cm, r);
    c.report.log(
        "vertex colours: each kept vertex takes the colour that the attribute quadric of the vertices its "
        "collapses took over gives at its position (as conelod feature-simplify)");
  }
  if (mark) mm.updateDataMask(MeshModel::MM_VERTCOLOR);
  mm.clearDataMask(MeshModel::MM_FACEFACETOPO | MeshModel::MM_VERTFACETOPO);
  conelod::WriteSimplifiedMesh(mm.cm, faceOf, r, mark);
  vcg::tri::UpdateBounding<CMeshO>::Box(mm.cm);  // the face normals only: the vertex normals are the means above
  vcg::tri::UpdateNormal<CMeshO>::PerFaceNormalized(mm.cm);

  Report& out = c.report;
  out.log("Feature-preserving simplification: %d -> %d faces in %.3f s (%d collapses%s)%s", int(r.facesIn),
          int(r.facesOut), seconds, int(r.collapses),
          r.parts > 1 ? (", in " + std::to_string(r.parts) + " parts on every core").c_str() : "",
          params.targetFaceCount == 0 ? ""
          : r.targetReached           ? ", target reached"
                                      : ", target NOT reached: no allowed collapse left");
  out.log("faces_out %d", int(r.facesOut));
  out.log("feature_edges %d (%d made by extension swaps) -> feature_edges_out %d", int(r.featureEdgesIn),
          int(r.swapEdges), int(r.featureEdges.size()));
  out.log("feature_vertices %d (kept), feature-line vertices %d, smooth vertices %d", int(r.featureVertices),
          int(r.lineVerticesIn), int(r.smoothVerticesIn));
  if (r.finalErrorBound > 0)
    out.log("error bound at the end %g (%.4f %% of the diagonal)", r.finalErrorBound,
            100.0 * r.finalErrorBound / std::max(1e-30, conelod::BoundingBoxDiagonal(im)));
  if (mark)
    out.log(
        "feature vertices selected and coloured (red: on a feature line, blue: feature vertex); the other "
        "edges are faux, so the layer's wireframe in Polygonal Modality (layer dialog, wireframe) draws the "
        "feature lines only; the default wireframe draws every edge");
  out.figure("faces_out", double(r.facesOut));
  out.figure("feature_edges", double(r.featureEdgesIn));
  return Status::Ok();
}

// ---------------------------------------------------------------------------------------------
// Cone LOD: Face Budget from Screen Pixels

const char* const kBudgetSimplifiers[] = {"None (log the budget only)", "Feature-Preserving Edge Simplification",
                                          "Quadric Edge Collapse Decimation (MeshLab's, default parameters)"};

std::vector<ParamSpec> PixelBudgetSpecs(const MeshDocument*, const MeshModel*) {
  const conelod::PixelBudgetParams d;
  std::vector<ParamSpec> p;
  p.push_back(
      IntParam("Width", d.width, "Screen width (pixels)", "Width of the screen the model is shown on.", AtLeast(1)));
  p.push_back(IntParam("Height", d.height, "Screen height (pixels)", "Height of the screen the model is shown on.",
                       AtLeast(1)));
  p.push_back(FloatParam("PixelFactor", d.pixelFactor, "Faces per covered pixel",
                         "The budget is this many faces per pixel the model covers (the paper's finding: 50).",
                         Above(0)));
  p.push_back(EnumParam("View", 0,
                        QStringList() << "Worst of the six axis directions"
                                      << "+X"
                                      << "-X"
                                      << "+Y"
                                      << "-Y"
                                      << "+Z"
                                      << "-Z"
                                      << "Direction below",
                        "View",
                        "Direction the model is looked at (orthographic, framed on its bounding sphere). The worst "
                        "case counts the most pixels."));
  p.push_back(DirectionParam("ViewDirection", vcg::Point3f(0, 0, -1), "View direction",
                             "Used when View is 'Direction below': the direction from the eye to the model."));
  p.push_back(EnumParam("Simplifier", 0,
                        QStringList() << kBudgetSimplifiers[0] << kBudgetSimplifiers[1] << kBudgetSimplifiers[2],
                        "Simplify to the budget with",
                        "None: only log the pixels and the budget. Otherwise the mesh is simplified to the budget "
                        "(when it has more faces)."));
  return p;
}

Status ApplyPixelBudget(FilterCall& c) {
  MeshModel& mm = *c.mesh;
  conelod::PixelBudgetParams params;
  params.width = c.args.integer("Width");
  params.height = c.args.integer("Height");
  params.pixelFactor = c.args.number("PixelFactor");
  const int view = c.args.integer("View");
  params.view = view == 7 ? conelod::BudgetView::Direction : conelod::BudgetView(view);
  params.direction = c.args.point("ViewDirection");
  const int simplifier = c.args.integer("Simplifier");

  const conelod::IndexedMesh im = conelod::ToIndexedMesh(mm.cm);
  conelod::PixelBudgetResult r;
  Status s =
      conelod::ComputePixelBudget(im, params, r, conelod::SubProgress(c.progress(), 0, simplifier == 0 ? 100 : 10));
  if (!s.ok()) return s;
  Report& out = c.report;
  out.log("Face budget at %d x %d, view %s: covered_pixels %d (%.1f %% of the screen)", params.width, params.height,
          conelod::BudgetViewName(params.view, params.direction).c_str(), int(r.coveredPixels),
          100.0 * double(r.coveredPixels) / (double(params.width) * params.height));
  out.log("target_faces %d (= %g x %d pixels); the mesh has %d faces", int(r.targetFaces), params.pixelFactor,
          int(r.coveredPixels), int(r.currentFaces));
  out.figure("covered_pixels", double(r.coveredPixels));
  out.figure("target_faces", double(r.targetFaces));
  if (r.aboveCurrent) {
    out.log("The budget is ABOVE the current face count: no reduction is needed%s",
            simplifier ? " (the mesh was not changed)" : "");
    return Status::Ok();
  }
  if (simplifier == 0) return Status::Ok();
  const int target = std::max(1, int(r.targetFaces));
  if (simplifier == 1) {
    std::vector<size_t> faceOf;
    const conelod::IndexedMesh again = conelod::ToIndexedMesh(mm.cm, &faceOf);
    conelod::FeatureSimplifyParams fp;
    fp.targetFaceCount = size_t(target);
    conelod::FeatureSimplifyResult fr;
    s = conelod::FeatureSimplify(again, fp, fr, conelod::SubProgress(c.progress(), 10, 100));
    if (!s.ok()) return s;
    mm.clearDataMask(MeshModel::MM_FACEFACETOPO | MeshModel::MM_VERTFACETOPO);
    conelod::WriteSimplifiedMesh(mm.cm, faceOf, fr, false);
    UpdateBoxAndNormals(mm);
  } else {
    RunBuiltinQuadric(mm, target, c.cb);
  }
  out.log("Simplified to the budget with %s: faces_out %d", kBudgetSimplifiers[simplifier], mm.cm.fn);
  out.figure("faces_out", mm.cm.fn);
  return Status::Ok();
}

// ---------------------------------------------------------------------------------------------
// Cone LOD: PCA Recursive Face Partition

std::vector<ParamSpec> PcaPartitionSpecs(const MeshDocument*, const MeshModel* m) {
  const conelod::PcaPartitionParams d;
  std::vector<ParamSpec> p;
  p.push_back(IntParam("TargetClusters", 64, "Target clusters",
                       "Split until there are this many clusters, largest error first (0: no limit, down "
                       "to single triangles). A mesh with several components has at least one cluster "
                       "per component.",
                       AtLeast(0, "0: no limit")));
  p.push_back(AbsPercParam("MaxError", 0.0, Diagonal(m) * 0.1, "Max error",
                           "Clusters whose RMS distance to their best-fit plane (the square root of the "
                           "smallest eigenvalue of their face-based covariance) is at most this length "
                           "are not split. 0: no limit.",
                           AtLeast(0, "0: no limit")));
  p.push_back(IntParam("MinFaces", d.minFaces, "Min faces",
                       "Clusters of this many faces or fewer are not split (1: down to triangles).", AtLeast(1)));
  p.push_back(IntParam("MaxDepth", d.maxDepth, "Max depth",
                       "Clusters at this depth of the binary tree are not split (the whole mesh is depth "
                       "0). 0: no limit.",
                       AtLeast(0, "0: no limit")));
  return p;
}

Status ApplyPcaPartition(FilterCall& c) {
  MeshModel& mm = *c.mesh;
  conelod::PcaPartitionParams params;
  params.targetClusters = c.args.integer("TargetClusters");
  params.maxErrorRms = c.args.number("MaxError");
  params.minFaces = c.args.integer("MinFaces");
  params.maxDepth = c.args.integer("MaxDepth");

  std::vector<size_t> faceOf;
  const conelod::IndexedMesh im = conelod::ToIndexedMesh(mm.cm, &faceOf);
  conelod::PcaTree tree;
  QElapsedTimer timer;
  timer.start();
  const Status s = conelod::BuildPcaTree(im, params, tree, c.progress());
  if (!s.ok()) return s;
  const double seconds = timer.elapsed() / 1000.0;
  const std::vector<conelod::PcaItem> cut =
      conelod::CutByCount(tree, params.targetClusters > 0 ? params.targetClusters : tree.faceCount);
  std::vector<int> faceCluster;
  conelod::FaceClustersOfCut(tree, cut, faceCluster);
  const bool connected = conelod::GroupsAreEdgeConnected(conelod::BuildFaceAdjacency(im), faceCluster);

  mm.updateDataMask(MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR);
  conelod::WriteFaceClusters(mm.cm, faceOf, faceCluster, "conelod_pca_cluster");

  uint32_t smallest = UINT32_MAX, largest = 0;
  double maxError = 0, meanError = 0;
  for (conelod::PcaItem item : cut) {
    const uint32_t n = tree.itemFaceCount(item);
    smallest = std::min(smallest, n);
    largest = std::max(largest, n);
    if (conelod::IsFaceItem(item)) continue;
    const conelod::PcaNode& node = tree.nodes[size_t(item)];
    const double e = std::sqrt(double(node.eigenvalues[0]));
    maxError = std::max(maxError, e);
    meanError += e * node.area;
  }
  meanError = tree.nodes[0].area > 0 ? meanError / tree.nodes[0].area : 0;
  Report& out = c.report;
  out.log("PCA recursive face partition: %d faces, %d component(s), tree of %d nodes (depth %d) in %.3f s",
          int(im.faceCount()), tree.componentCount, int(tree.nodes.size()), tree.maxDepth, seconds);
  out.log("pca_clusters %d", int(cut.size()));
  out.log("faces_per_cluster min %u  mean %.1f  max %u", smallest, double(im.faceCount()) / cut.size(), largest);
  out.log("error_rms max %.6g  area_weighted_mean %.6g  (RMS distance of a cluster to its plane)", maxError, meanError);
  out.log("all_connected %d", connected ? 1 : 0);
  out.figure("pca_clusters", double(cut.size()));
  out.figure("all_connected", connected ? 1 : 0);
  return Status::Ok();
}

// ---------------------------------------------------------------------------------------------
// Cone LOD: Progressive Cluster Mesh

// Issue 26: the source layer's vertex colour, normals and per-vertex texture coordinates given to
// the progressive mesh's layer as conelod progressive does: its collapses are half-edge collapses
// (vertices kept in place), so each coarse vertex takes the extended quadric's value at its
// position of the input vertices whose collapses ended in it (conelod::SurvivorQuadricMeans;
// normals normalised; a per-vertex texture seam's vertex, a position held by two vertices, keeps
// its own coordinates; a vertex whose faces have no area keeps its own values). The source layer
// is not changed. Wedge texture coordinates are not carried (the log says so).
void CarryProgressiveAttributes(const MeshModel& mm, const conelod::ProgressiveMeshResult& r, MeshModel& layer,
                                Report& out) {
  using FaceType = CMeshO::FaceType;
  const CMeshO& src = mm.cm;
  std::vector<const CMeshO::VertexType*> vertexOfIndex;
  for (const auto& v : src.vert)
    if (!v.IsD()) vertexOfIndex.push_back(&v);
  CMeshO& dst = layer.cm;
  if (dst.vert.size() != r.vertexOrigin.size()) return;  // not the layer AppendIndexedMesh made
  std::vector<double> means, weight;
  const bool colour = mm.hasDataMask(MeshModel::MM_VERTCOLOR);
  if (colour) {
    layer.updateDataMask(MeshModel::MM_VERTCOLOR);
    conelod::SurvivorQuadricMeans(
        src, r.survivor, r.vertexOrigin, 4, [](const FaceType& f, int j, int k) { return double(f.cV(j)->cC()[k]); },
        means, weight);
    for (size_t o = 0; o < dst.vert.size(); ++o) {
      auto& c = dst.vert[o].C();
      c = vertexOfIndex[r.vertexOrigin[o]]->cC();
      if (weight[o] > 0)
        for (int k = 0; k < 4; ++k)
          c[k] = (unsigned char)std::min(255L, std::max(0L, std::lround(means[o * 4 + size_t(k)])));
    }
  }
  conelod::SurvivorQuadricMeans(
      src, r.survivor, r.vertexOrigin, 3, [](const FaceType& f, int j, int k) { return double(f.cV(j)->cN()[k]); },
      means, weight);
  for (size_t o = 0; o < dst.vert.size(); ++o) {
    const vcg::Point3d n(means[3 * o], means[3 * o + 1], means[3 * o + 2]);
    const double len = n.Norm();
    auto& out = dst.vert[o].N();
    if (weight[o] > 0 && len > 0 && std::isfinite(len))
      out = CMeshO::VertexType::NormalType(n[0] / len, n[1] / len, n[2] / len);
    else
      out = vertexOfIndex[r.vertexOrigin[o]]->cN();
  }
  const bool wedges = mm.hasDataMask(MeshModel::MM_WEDGTEXCOORD);
  const bool vertexTexCoords = !wedges && mm.hasDataMask(MeshModel::MM_VERTTEXCOORD);
  size_t seamKept = 0;
  if (vertexTexCoords) {
    layer.updateDataMask(MeshModel::MM_VERTTEXCOORD);
    const std::vector<char> seam = conelod::SeamVertices(vertexOfIndex);  // of the source
    conelod::SurvivorQuadricMeans(
        src, r.survivor, r.vertexOrigin, 2,
        [](const FaceType& f, int j, int k) { return double(k == 0 ? f.cV(j)->cT().U() : f.cV(j)->cT().V()); }, means,
        weight);
    for (size_t o = 0; o < dst.vert.size(); ++o) {
      auto& t = dst.vert[o].T();
      t = vertexOfIndex[r.vertexOrigin[o]]->cT();
      if (seam[r.vertexOrigin[o]]) {
        ++seamKept;
        continue;
      }
      if (weight[o] > 0 && std::isfinite(means[2 * o]) && std::isfinite(means[2 * o + 1])) {
        t.U() = float(means[2 * o]);
        t.V() = float(means[2 * o + 1]);
      }
    }
    dst.textures = src.textures;
  }
  out.log("attributes carried to the new layer (as conelod progressive): %s%s%s",
          colour ? "vertex colours (the attribute quadric's value at each kept vertex), " : "",
          "vertex normals (the same, normalised)",
          vertexTexCoords
              ? (", vertex texture coordinates (the same, " + std::to_string(seamKept) + " on a seam keep their own)")
                    .c_str()
              : "");
  if (wedges)
    out.log(
        "wedge texture coordinates: not carried (the new layer has none; conelod progressive reads them as "
        "vertices split along the seams and keeps them)");
}

std::vector<ParamSpec> ProgressiveMeshSpecs(const MeshDocument*, const MeshModel*) {
  const conelod::ProgressiveMeshParams d;
  return {IntParam("TargetClusters", d.targetClusters, "Target clusters",
                   "Merge the finest clusters back down to this many clusters (never fewer than the "
                   "connected components).",
                   AtLeast(1)),
          FloatParam("MaxNormalTurnDeg", d.maxNormalTurnDeg, "Max normal turn (deg)",
                     "A collapse may not turn the normal of any face by this angle or more (in (0, "
                     "180) degrees): no face ever flips.",
                     Inside(0, 180))};
}

Status ApplyProgressiveMesh(FilterCall& c) {
  MeshModel& mm = *c.mesh;
  conelod::ProgressiveMeshParams params;
  params.targetClusters = c.args.integer("TargetClusters");
  params.maxNormalTurnDeg = c.args.number("MaxNormalTurnDeg");

  const conelod::IndexedMesh im = conelod::ToIndexedMesh(mm.cm);
  QElapsedTimer timer;
  timer.start();
  conelod::ProgressiveMeshResult r;  // its PCA tree and all, independent of the model's scale
  Status s = conelod::BuildProgressiveClusterMeshOf(im, params, r, conelod::SubProgress(c.progress(), 0, 90));
  if (!s.ok()) return s;
  const double seconds = timer.elapsed() / 1000.0;
  conelod::HausdorffResult h;
  s = conelod::SampledHausdorff(im, r.mesh, 100000, h);
  const conelod::ManifoldReport check = conelod::CheckManifold(r.mesh);

  MeshModel* layer = c.doc.addNewMesh("", QString("%1 (%2 clusters)").arg(mm.label()).arg(r.clusters), true);
  if (!layer) return Invalid("could not add a layer");
  layer->updateDataMask(MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR);
  conelod::AppendIndexedMesh(layer->cm, r.mesh);
  for (size_t f = 0; f < layer->cm.face.size(); ++f) {
    layer->cm.face[f].Q() = CMeshO::FaceType::QualityType(r.faceCluster[f]);
    layer->cm.face[f].C() = conelod::GroupColor(r.faceCluster[f]);
  }
  vcg::tri::UpdateBounding<CMeshO>::Box(layer->cm);
  vcg::tri::UpdateNormal<CMeshO>::PerVertexNormalizedPerFaceNormalized(layer->cm);
  CarryProgressiveAttributes(mm, r, *layer, c.report);
  if (c.cb) c.cb(100, "progressive mesh: done");

  Report& out = c.report;
  out.log("Progressive cluster mesh: %d faces -> %d faces, %d vertices at %d clusters in %.3f s (new layer)",
          int(im.faceCount()), int(r.mesh.faceCount()), int(r.mesh.vertexCount()), r.clusters, seconds);
  out.log("progressive_faces %d", int(r.mesh.faceCount()));
  out.log("progressive_vertices %d", int(r.mesh.vertexCount()));
  out.log("collapses %d  blocked_vertices %d  locked_vertices %d", int(r.collapses), int(r.blockedVertices),
          int(r.lockedVertices));
  out.log("non_manifold_edges %d  non_manifold_vertices %d  misoriented_edges %d", int(check.nonManifoldEdges),
          int(check.nonManifoldVertices), int(check.misorientedEdges));
  if (s.ok())
    out.log("hausdorff %.6g  hausdorff_percent %.4f  (sampled, %% of the bounding-box diagonal)", h.hausdorff,
            h.diagonal > 0 ? 100 * h.hausdorff / h.diagonal : 0.0);
  out.figure("progressive_faces", double(r.mesh.faceCount()));
  out.figure("progressive_vertices", double(r.mesh.vertexCount()));
  return Status::Ok();
}

// ---------------------------------------------------------------------------------------------
// Cone LOD: Export LOD File

// The parameters of the DAG build, those of conelod lod build (lod_build.h): the cone threshold and
// its growth (the other grouping parameters play no part in the DAG), cluster and group sizes,
// the level ratio and the collapse options of every group.
std::vector<ParamSpec> LodExportSpecs(const MeshDocument*, const MeshModel*) {
  const conelod::LodBuildParams d;
  std::vector<ParamSpec> p;
  p.push_back(SaveFileParam("FileName", "ConeLOD file (*.clod)", "LOD file", ""));
  p.back().help = kLodFileHelp;
  p.push_back(FloatParam("ConeThresholdDeg", d.grouping.coneThresholdDeg, "Cone threshold (deg)",
                         "Level-0 clusters: the normals of a cluster stay within a cone of this half-angle, in "
                         "degrees (at most 90 is used).",
                         Above(0)));
  p.push_back(FloatParam("ThresholdGrowth", d.grouping.thresholdGrowth, "Threshold growth per level",
                         "The clusters of each level above 0 take the cone threshold times this factor per level "
                         "(>= 1; at most 90 degrees).",
                         AtLeast(1)));
  p.push_back(IntParam("ClusterFaces", int(d.clusterFaces), "Faces per cluster",
                       "Target faces of a cluster (a node of the file), at every level.", Between(4, 65536)));
  p.push_back(IntParam("GroupClusters", d.groupClusters, "Clusters per group",
                       "Neighbouring clusters gathered into one group, simplified together with its outer "
                       "border locked and re-cut into the next level's clusters (24 on the levels above 3/8 of "
                       "the input's faces, 64 on those of them with 262,144 faces or more, 24 on the others with "
                       "24,576 faces or more, 6 on the top ones).",
                       Between(2, 64)));
  p.push_back(FloatParam("LevelRatio", d.simplification.levelRatio, "Faces kept per level (0..1)",
                         "Each group of the fine levels (above 3/8 of the input's faces) is simplified to this "
                         "fraction of its faces (so each level has about this fraction of the faces of the level "
                         "below), those of the coarser levels to at least 0.6 of theirs; a group stops earlier "
                         "when its locked border leaves no cheap collapse.",
                         Inside(0, 1)));
  AddCollapseOptionParams(p, d.simplification.qem,
                          "Weight of the quadrics that keep mesh borders in place (Preserve Boundary).");
  p.push_back(FloatParam("Precision", conelod::kDefaultLodPrecision, "Position precision",
                         "Positions are quantized on one grid so that the file stays small: no vertex moves by "
                         "more than this fraction of the bounding box diagonal (the default, 5e-6, keeps the RMS "
                         "error of every simplified level within 1 % of the unquantized one's).",
                         Between(conelod::kMinLodPrecision, conelod::kMaxLodPrecision)));
  return p;
}

Status ApplyLodExport(FilterCall& c) {
  QString path;
  Status s = RequirePath(c, "FileName", path);
  if (!s.ok()) return s;
  const QString fullPath = QFileInfo(path).absoluteFilePath();
  const std::string pathError = conelod::CheckOutputPath(path.toStdString());  // before the work, not after
  if (!pathError.empty()) return Status::Invalid(pathError);
  conelod::LodBuildParams params;
  params.grouping.coneThresholdDeg = c.args.number("ConeThresholdDeg");
  params.grouping.thresholdGrowth = c.args.number("ThresholdGrowth");
  params.clusterFaces = size_t(c.args.integer("ClusterFaces"));
  params.groupClusters = c.args.integer("GroupClusters");
  params.simplification.levelRatio = c.args.number("LevelRatio");
  ReadCollapseOptions(c.args, params.simplification.qem);
  params.precision = c.args.number("Precision");

  const conelod::IndexedMesh im = conelod::ToIndexedMesh(c.mesh->cm);
  s = conelod::RequireValidForFaces(im);
  if (!s.ok()) return s;
  const bool replaced = QFileInfo::exists(fullPath);
  conelod::LodBuildStats stats;
  s = conelod::BuildLodFile(im, params, path.toStdString(), &stats, c.progress());
  if (!s.ok()) return Invalid(NameFile(fullPath, s.message));

  Report& out = c.report;
  out.log(
      "LOD file %s%s: %d faces, %d levels, %d nodes, %.1f KiB in %.3f s (grouping %.3f s, simplification "
      "%.3f s, writing %.3f s)",
      qUtf8Printable(fullPath), replaced ? " (replaced the file that was there)" : "", int(stats.inputFaces),
      stats.levels, int(stats.nodes), stats.fileBytes / 1024.0, stats.seconds, stats.groupingSeconds,
      stats.simplifySeconds, stats.writeSeconds);
  for (size_t l = 0; l < stats.levelFaces.size(); ++l)
    out.log("lod level %d: faces %d nodes %d", int(l), int(stats.levelFaces[l]),
            l < stats.levelNodes.size() ? int(stats.levelNodes[l]) : 0);
  if (stats.mergedVertices || stats.droppedVertices)
    out.log("vertices at one position welded: %d; unreferenced vertices left out: %d", int(stats.mergedVertices),
            int(stats.droppedVertices));
  out.log("lod_levels %d", stats.levels);
  out.log("lod_nodes %d", int(stats.nodes));
  out.log("lod_file_bytes %lld", (long long)stats.fileBytes);
  out.log("lod_quantization_error %g", stats.quantizationError);
  out.figure("lod_levels", stats.levels);
  out.figure("lod_nodes", double(stats.nodes));
  out.figure("lod_file_bytes", double(stats.fileBytes));
  return Status::Ok();
}

// ---------------------------------------------------------------------------------------------
// Cone LOD: Extract View-Dependent LOD

const char* const kLodViewModes[] = {"Perspective, framed from the view direction", "Perspective from the eye position",
                                     "Orthographic along the view direction"};

// Independent of the current mesh: the extract reads everything from the file.
std::vector<ParamSpec> LodExtractSpecs(const MeshDocument*, const MeshModel*) {
  const conelod::LodView d;
  ParamSpec file = OpenFileParam("FileName", QStringList() << "ConeLOD file (*.clod)", "LOD file", "");
  file.help = QString("The .clod file to read (Cone LOD: Export LOD File or conelod lod build). No default: ") +
              kLodFileHow + ". A relative path is relative to MeshLab's current directory.";
  return {
      file,
      EnumParam("ViewMode", 0, QStringList() << kLodViewModes[0] << kLodViewModes[1] << kLodViewModes[2], "View",
                "Framed: a perspective eye on the line through the model's centre along the view direction, "
                "Camera distance bounding-sphere radii away. Eye: a perspective eye at the eye position. "
                "Orthographic: parallel projection along the view direction."),
      PositionParam(
          "Eye", vcg::Point3f(0, 0, 0), "Eye position",
          "Used when View is 'Perspective from the eye position': the eye in model coordinates (Get / View Pos. "
          "takes the current camera)."),
      DirectionParam("ViewDirection", vcg::Point3f(0, 0, -1), "View direction",
                     "Direction from the eye into the scene (the default looks down -Z, from the +Z side)."),
      FloatParam("CameraDistance", 3.0, "Camera distance",
                 "Framed view: the eye's distance from the model's centre, in bounding-sphere radii (> 1)."),
      IntParam("FaceBudget", 100000, "Face budget",
               "Refine until the layer would exceed this many faces (the coarsest level is always complete). 0: "
               "no limit, down to the input's own faces.",
               AtLeast(0, "0: no limit")),
      BoolParam("CullBackFacing", d.cullBackFacing, "Refine back-facing groups last",
                "Groups that face away from the eye entirely (one normal-cone test each) are refined only after "
                "every other group (as conelod lod extract does unless --no-cull)."),
      BoolParam("DropBackFacing", false, "Leave back-facing groups out",
                "The back-facing groups are not written to the layer (conelod lod extract --drop-culled)."),
  };
}

// MeshLab 2020.09 reads a layer's texture from a file (kLayersHoldTextureImages): the .clod's image
// (its TEXR chunk) goes beside the .clod under its stored name when no file has that name there,
// or is found there when the file there holds the same bytes; else (another file of that name, a
// folder that cannot be written) into a new folder of the system's temporary folder. Nothing is
// overwritten. `path`: the image's absolute path; `how`: what was done, for the log.
Status ProvideLodTextureFile(const QString& clodPath, const conelod::LodTexture& tex, QString& path, QString& how) {
  const QByteArray bytes(reinterpret_cast<const char*>(tex.bytes.data()), int(tex.bytes.size()));
  auto write = [&](const QString& target, std::string& err) {
    conelod::SafeFile out;
    err = out.open(target.toStdString());
    if (err.empty() && std::fwrite(bytes.constData(), 1, size_t(bytes.size()), out.file()) != size_t(bytes.size()))
      err = "cannot write '" + target.toStdString() + "'";
    if (err.empty()) err = out.commit();
    return err.empty();
  };
  const QString name = QString::fromStdString(tex.name);
  const QString beside = QFileInfo(clodPath).absoluteDir().absoluteFilePath(name);
  std::string err;
  QString why;
  if (QFileInfo(beside).exists() || QFileInfo(beside).isSymLink()) {
    QFile existing(beside);
    if (QFileInfo(beside).isFile() && existing.open(QIODevice::ReadOnly) && existing.readAll() == bytes) {
      path = beside;
      how = "found beside the .clod as " + beside + " (the same bytes)";
      return Status::Ok();
    }
    why = beside + " exists with other content and is left as it is";
  } else if (write(beside, err)) {
    path = beside;
    how = "written beside the .clod as " + beside + " (no file had that name)";
    return Status::Ok();
  } else {
    why = "cannot write beside the .clod: " + QString::fromStdString(err);
  }
  QTemporaryDir folder(QDir::temp().absoluteFilePath("conelod-texture-XXXXXX"));
  if (!folder.isValid()) return Invalid("cannot create a folder for the texture image in " + QDir::tempPath());
  folder.setAutoRemove(false);  // the layer names the image; MeshLab reads it when it draws or saves
  const QString temp = QDir(folder.path()).absoluteFilePath(name);
  if (!write(temp, err)) {
    QDir(folder.path()).removeRecursively();
    return Invalid("cannot write the texture image: " + QString::fromStdString(err));
  }
  path = temp;
  how = "written to " + temp + " (" + why + ")";
  return Status::Ok();
}

Status ApplyLodExtract(FilterCall& c) {
  QString path;
  Status s = RequirePath(c, "FileName", path);
  if (!s.ok()) return s;
  const QString fullPath = QFileInfo(path).absoluteFilePath();
  const int mode = c.args.integer("ViewMode");
  const int budget = c.args.integer("FaceBudget");
  const double distance = c.args.number("CameraDistance");
  vcg::Point3d dir = c.args.point("ViewDirection");
  if (mode != 1 && !(dir.Norm() > 0 && std::isfinite(dir.Norm())))
    return Invalid(Label(c, "ViewDirection") + " must be a non-zero vector");
  if (mode == 0 && !(distance > 1 && std::isfinite(distance)))
    return Invalid(Label(c, "CameraDistance") + " must be > 1 (bounding-sphere radii)");
  const vcg::Point3d eyeParam = c.args.point("Eye");
  if (mode == 1 && !std::isfinite(eyeParam.Norm())) return Invalid(Label(c, "Eye") + " must be finite");
  const bool cull = c.args.flag("CullBackFacing"), drop = c.args.flag("DropBackFacing");

  QElapsedTimer timer;
  timer.start();
  if (c.cb) c.cb(0, "reading the LOD file");
  std::unique_ptr<conelod::LodReader> reader;
  auto failed = [&](const Status& st) { return Invalid(NameFile(fullPath, st.message)); };
  const std::string notRegular = conelod::CheckInputPath(path.toStdString(), true);  // a FIFO blocks open()
  if (!notRegular.empty()) return Invalid(QString::fromStdString(notRegular));
  s = conelod::LodReader::Open(path.toStdString(), reader);
  if (!s.ok()) return failed(s);
  const conelod::LodFileInfo& info = reader->info();

  conelod::LodView view;
  dir.Normalize();
  const vcg::Point3d centre = vcg::Point3d::Construct(info.box.Center());
  const double radius = 0.5 * double(info.box.Diag());
  view.orthographic = mode == 2;
  view.viewDir = dir;
  view.eye = mode == 1 ? eyeParam : centre - dir * (distance * radius);
  view.faceBudget = budget == 0 ? size_t(-1) : size_t(budget);
  view.cullBackFacing = cull;
  conelod::LodCut cut;
  if (c.cb) c.cb(10, "refining");
  s = conelod::RefineLod(*reader, view, cut);
  if (!s.ok()) return failed(s);
  if (c.cb) c.cb(80, "extracting the cut");
  conelod::IndexedMesh mesh;
  std::vector<int> faceLevel;
  conelod::LodAttributes attributes;  // the file's vertex colours and normals (version 5)
  s = conelod::ExtractCutMesh(*reader, cut, !drop, mesh, &faceLevel, nullptr, &attributes);
  if (!s.ok()) return failed(s);
  // The texture image of a textured file (its TEXR chunk), read, and for MeshLab 2020.09 written
  // to a file, before the layer is added: a failure leaves the document as it was.
  const bool textured = !attributes.texCoords.empty();
  conelod::LodTexture texture;
  QImage textureImage;
  QString textureName, textureHow;
  if (textured && info.textureBytes) {
    s = reader->LoadTexture(texture);
    if (!s.ok()) return failed(s);
    if (kLayersHoldTextureImages) {
      textureImage = QImage::fromData(texture.bytes.data(), int(texture.bytes.size()));
      textureName = QString::fromStdString(texture.name);
      textureHow = textureImage.isNull() ? QString("not given: Qt cannot decode its %1 bytes (%2)")
                                               .arg(texture.bytes.size())
                                               .arg(QString::fromStdString(texture.mime))
                                         : QString(
                                               "held in memory by the layer (%1 x %2, from the file's %3 bytes; "
                                               "saving the layer writes it beside the mesh)")
                                               .arg(textureImage.width())
                                               .arg(textureImage.height())
                                               .arg(texture.bytes.size());
    } else {
      s = ProvideLodTextureFile(fullPath, texture, textureName, textureHow);
      if (!s.ok()) return s;
    }
  }
  const double seconds = timer.elapsed() / 1000.0;

  MeshModel* layer = c.doc.addNewMesh(
      "", QString("%1 (LOD, %2 faces)").arg(QFileInfo(path).completeBaseName()).arg(mesh.faceCount()), true);
  if (!layer) return Invalid("could not add a layer");
  layer->updateDataMask(MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR);
  conelod::AppendIndexedMesh(layer->cm, mesh);
  std::vector<size_t> facesPerLevel(size_t(std::max(info.levels, 1)), 0);
  for (size_t f = 0; f < layer->cm.face.size(); ++f) {
    const int level = faceLevel[f];
    layer->cm.face[f].Q() = CMeshO::FaceType::QualityType(level);
    layer->cm.face[f].C() = conelod::GroupColor(level);  // as conelod lod extract colours its output
    if (level >= 0 && size_t(level) < facesPerLevel.size()) ++facesPerLevel[size_t(level)];
  }
  vcg::tri::UpdateBounding<CMeshO>::Box(layer->cm);
  vcg::tri::UpdateNormal<CMeshO>::PerVertexNormalizedPerFaceNormalized(layer->cm);
  // The file's attributes (AppendIndexedMesh keeps the vertex order): vertex colours, and the
  // stored normals in place of the computed ones.
  if (!attributes.colors.empty()) {
    layer->updateDataMask(MeshModel::MM_VERTCOLOR);
    for (size_t v = 0; v < layer->cm.vert.size(); ++v) {
      const auto& col = attributes.colors[v];
      layer->cm.vert[v].C() = vcg::Color4b(col[0], col[1], col[2], col[3]);
    }
  }
  if (!attributes.normals.empty())
    for (size_t v = 0; v < layer->cm.vert.size(); ++v) {
      const vcg::Point3f n = conelod::DecodeLodNormal(attributes.normals[v]);
      layer->cm.vert[v].N() = CMeshO::VertexType::NormalType(n[0], n[1], n[2]);
    }
  // Texture coordinates per face corner (wedge, as MeshLab's texture filters and its PLY reader
  // hold them): each corner its vertex's (the file has one vertex per position and UV, so a seam's
  // corners keep their own chart's), texture 0: the image above.
  if (textured) {
    layer->updateDataMask(MeshModel::MM_WEDGTEXCOORD);
    std::vector<vcg::TexCoord2f> uv(layer->cm.vert.size());
    for (size_t v = 0; v < uv.size(); ++v) {
      float t[2];
      conelod::DecodeLodTexCoord(attributes.texCoords[v], attributes.uvMin, attributes.uvMax, t);
      uv[v] = vcg::TexCoord2f(t[0], t[1]);
      uv[v].N() = 0;
    }
    for (auto& f : layer->cm.face)
      for (int k = 0; k < 3; ++k) f.WT(k) = uv[size_t(vcg::tri::Index(layer->cm, f.V(k)))];
    if (!textureName.isEmpty() && (!kLayersHoldTextureImages || !textureImage.isNull()))
      AddLayerTexture(*layer, textureName.toStdString(), textureImage);
  }
  if (c.cb) c.cb(100, "view-dependent LOD: done");

  Report& out = c.report;
  const vcg::Point3d& e = view.eye;
  out.log("View-dependent LOD of %s (%s, budget %s%s%s): %d faces, %d vertices from %d nodes in %.3f s (new layer)",
          qUtf8Printable(fullPath), kLodViewModes[mode], budget == 0 ? "none" : qUtf8Printable(QString::number(budget)),
          cull ? ", back-facing groups refined last" : "", drop ? ", back-facing groups left out" : "",
          int(mesh.faceCount()), int(mesh.vertexCount()), int(cut.nodes.size()), seconds);
  if (mode == 2)
    out.log("orthographic view direction (%g, %g, %g)", dir[0], dir[1], dir[2]);
  else
    out.log("eye (%g, %g, %g)", e[0], e[1], e[2]);
  if (info.colors || info.normals)
    out.log("the file's per-vertex %s%s%s given to the layer", info.colors ? "colours" : "",
            info.colors && info.normals ? " and " : "", info.normals ? "normals" : "");
  if (textured)
    out.log("the file's texture coordinates given to the layer per face corner (wedge); %s",
            info.textureBytes
                ? qUtf8Printable("its texture image " + QString::fromStdString(texture.name) + ": " + textureHow)
                : "the file stores no texture image");
  for (size_t l = 0; l < facesPerLevel.size(); ++l)
    if (facesPerLevel[l]) out.log("faces at level %d: %d", int(l), int(facesPerLevel[l]));
  out.log("lod_faces %d", int(mesh.faceCount()));
  out.log("lod_cut_faces %d", int(cut.faces));
  out.log("lod_groups_culled %d", int(cut.groupsCulled));
  out.log("lod_refinements %d", int(cut.refinements));
  out.log("lod_max_level_difference %d", cut.maxLevelDifference);
  out.log("lod_resident_bytes %lld (the file: %lld)", (long long)reader->residentBytes(), (long long)info.fileBytes);
  out.figure("lod_faces", double(mesh.faceCount()));
  out.figure("lod_max_level_difference", cut.maxLevelDifference);
  return Status::Ok();
}

// ---------------------------------------------------------------------------------------------
// The table

std::vector<FilterSpec> MakeFilters() {
  const int quality = MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR;
  const int geometry = MeshModel::MM_GEOMETRY_AND_TOPOLOGY_CHANGE;
  std::vector<FilterSpec> t;
  t.push_back({"Cone LOD: Normal Cone Face Grouping", Menu::FaceColoring, Arity::SingleMesh, quality, quality,
               QString("Groups the faces into a hierarchy of edge-connected groups whose normals fit in a narrow "
                       "cone, so that a whole group can be back-face culled with one test. Adjacent faces (then "
                       "groups) are merged best pair first by v = k_c v_c + k_s v_s + k_n v_n, never letting a "
                       "group's cone half-angle reach the level's threshold, which grows by a factor per level. "
                       "Cones are the exact minimal cones of the normals.<br>"
                       "Writes per-face quality = group id at <i>Display level</i>, a distinct colour per group, "
                       "and the ids of every level in per-face attributes <tt>conelod_group_L1</tt>, "
                       "<tt>conelod_group_L2</tt>, ... The log lists groups and cone angles per level.<br>") +
                   kPaperKamiya,
               kUnchanged, ConeGroupingSpecs, ApplyConeGrouping});
  t.push_back({"Cone LOD: Cluster Culling Cost", Menu::Measure, Arity::SingleMesh, MeshModel::MM_NONE,
               MeshModel::MM_NONE,
               QString("Measures how much back-face culling work the normal-cone group hierarchy saves: over many "
                       "view directions uniform on the sphere, the number of group tests plus per-face tests in "
                       "visible groups, divided by the face count (per-face culling = 1). Two-state (the paper's "
                       "visible/invisible test) and three-state (fully front-facing groups skip their face "
                       "tests); the fraction of faces culled at group level against the ideal (all faces that "
                       "draw nothing). Orthographic views, or a perspective eye at <i>Camera distance</i> "
                       "bounding-sphere radii. The mesh is not changed.<br>") +
                   kPaperKamiya,
               kUnchanged, CullingCostSpecs, ApplyCullingCost});
  t.push_back({"Cone LOD: Group-Preserving Quadric Edge Collapse", Menu::Remeshing, Arity::SingleMesh,
               MeshModel::MM_NONE, geometry | quality,
               QString("Quadric edge collapse simplification (Garland-Heckbert, as the built-in <i>Quadric Edge "
                       "Collapse Decimation</i>) that keeps face groups intact (the paper's section 6): "
                       "<b>condition 1</b> refuses every collapse that would split a group or remove its last "
                       "faces; <b>condition 2</b> refuses every collapse that would create a vertex where three or "
                       "more groups meet. Group contours still simplify (a contour edge collapses onto the "
                       "contour; group corners never move). <i>Lock group boundaries</i> keeps every contour "
                       "vertex where it is (crack-free refinement between groups, less reduction).<br>"
                       "Target: <i>Target number of faces</i>, or when it is 0 <i>Target fraction</i> of the "
                       "faces, and/or <i>Max error</i>.<br>"
                       "Groups: by default the normal-cone groups computed here, at the finest hierarchy level "
                       "that leaves at least 8 faces per group at the target (<i>Normal cone level</i> 0; "
                       "<tt>conelod simplify --groups cone:auto</tt>), written to per-face quality and colour and "
                       "shown in face colour; or, with <i>Groups</i> = Per-face quality, the group ids already on "
                       "the mesh (e.g. from <i>Cone LOD: Normal Cone Face Grouping</i>; equal values = one group), "
                       "whose faces keep their quality and colour. Faces keep their attributes. "
                       "The layer's vertex colour and wedge texture coordinates are interpolated at each new vertex "
                       "(attribute quadrics, as <tt>conelod simplify</tt>; texture seams never move; "
                       "<i>Attribute weight</i>); normals are recomputed. "
                       "The log lists faces, groups before/after, groups split or vanished, and the time.<br>") +
                   kPaperKamiya,
               kUnchanged, GroupQemSpecs, ApplyGroupQem});
  t.back().showFaceColour = true;
  t.push_back({"Cone LOD: Group Integrity", Menu::Measure, Arity::SingleMesh, MeshModel::MM_NONE, MeshModel::MM_NONE,
               QString("Measures whether the face groups of the current mesh are those of <i>Reference mesh</i> "
                       "(the mesh before a simplification, kept as another layer), group ids being the per-face "
                       "quality: groups before and after, groups that vanished, groups split into more "
                       "edge-connected pieces than they had, groups already in several pieces in the reference "
                       "(reported, not counted as split). A mesh simplified in place has no copy of itself "
                       "before: duplicate the layer first. With the current mesh as reference nothing is "
                       "compared: the log counts its groups and those in several pieces. The meshes are not "
                       "changed.<br>") +
                   kPaperKamiya,
               "the meshes were not changed", GroupIntegritySpecs, ApplyGroupIntegrity});
  t.push_back({"Cone LOD: Feature-Preserving Edge Simplification", Menu::Remeshing, Arity::SingleMesh,
               MeshModel::MM_NONE,
               geometry | MeshModel::MM_VERTCOLOR | MeshModel::MM_VERTFLAGSELECT | MeshModel::MM_FACEFLAG,
               QString("Simplifies the mesh by half-edge collapses (vertices never move) while keeping its sharp "
                       "features. An edge is a <i>feature edge</i> when its dihedral angle A - the angle the two "
                       "faces make at the edge, 180 deg on a flat region, 90 deg on a cube edge - is at most "
                       "<i>Feature angle</i>; broken feature lines are extended by edge swaps; border edges are "
                       "feature lines too. Vertices with 1 or 3+ feature edges (corners) are never removed; "
                       "vertices on a feature line are removed only along it; the others go smoothest first "
                       "(smallest discrete Gaussian curvature), each into the neighbour whose collapse moves the "
                       "surface least. Stops at <i>Target number of faces</i> (when 0: <i>Target fraction</i> x "
                       "the faces) or when no collapse keeps every removed vertex within <i>Max error "
                       "distance</i> of the result. With a target, the error bound grows from tiny until the "
                       "target is reached (<i>Grow the error bound</i>, beyond the paper). <i>Mark the "
                       "features</i> selects and colours the feature vertices and makes the other edges faux: "
                       "the layer's wireframe in <i>Polygonal Modality</i> (layer dialog) then draws the feature "
                       "lines only (the default wireframe draws every edge).<br>") +
                   kPaperHayano,
               kUnchanged, FeatureSimplifySpecs, ApplyFeatureSimplify});
  t.push_back({"Cone LOD: Face Budget from Screen Pixels", Menu::Remeshing, Arity::SingleMesh, MeshModel::MM_NONE,
               geometry,
               QString("Counts the pixels the model covers on a screen of <i>Width</i> x <i>Height</i> "
                       "(orthographic view framed on the bounding sphere, from an axis or the worst of the six axis "
                       "directions) and logs the face budget <i>Faces per covered pixel</i> x pixels: the paper "
                       "found that 50 faces per covered pixel display a scanned model without visible loss at "
                       "1920x1080, 1600x900, 1280x720 and 800x600. Optionally simplifies the mesh to the budget "
                       "with the feature-preserving simplifier or with MeshLab's Quadric Edge Collapse Decimation "
                       "(its default parameters). Says so when the budget is above the current face count.<br>") +
                   kPaperMizuno,
               kUnchanged, PixelBudgetSpecs, ApplyPixelBudget});
  t.push_back({"Cone LOD: PCA Recursive Face Partition", Menu::FaceColoring, Arity::SingleMesh, quality, quality,
               QString("Splits the mesh recursively into edge-connected face clusters: each cluster is cut by the "
                       "plane through its area centroid perpendicular to its principal axis, found by a "
                       "<i>face-based</i> PCA (the covariance of the surface, exact per triangle, so that uneven "
                       "vertex density does not bias it); the two halves grow from the faces farthest along the "
                       "axis, and faces reached by neither join the half they touch, so both halves stay "
                       "connected. The cluster of largest error (the smallest eigenvalue, the variance across the "
                       "cluster) is split first, until <i>Target clusters</i> clusters or another stop criterion. "
                       "Several connected components are the first split.<br>"
                       "Writes per-face quality = cluster id, a distinct colour per cluster and the per-face "
                       "attribute <tt>conelod_pca_cluster</tt>; the log gives the cluster figures.<br>") +
                   kPaperTsuji,
               kUnchanged, PcaPartitionSpecs, ApplyPcaPartition});
  t.push_back({"Cone LOD: Progressive Cluster Mesh", Menu::Remeshing, Arity::SingleMesh, MeshModel::MM_NONE,
               MeshModel::MM_NONE,
               QString("Builds the PCA partition tree down to single triangles, then undoes its splits in order of "
                       "increasing error down to <i>Target clusters</i> clusters; after each merge every vertex "
                       "that touches fewer than 3 clusters (the mesh border counting as one) is removed by a "
                       "half-edge collapse onto its nearest neighbour along the cluster boundary. The result, a "
                       "coarse mesh whose vertices are the cluster corners, is added as a new layer with per-face "
                       "quality = cluster id and a colour per cluster. Collapses never break the 2-manifold, flip "
                       "or turn a face by more than <i>Max normal turn</i>, or remove a cluster; non-manifold parts "
                       "of the input are left as they are. The current mesh is not changed.<br>") +
                   kPaperTsuji,
               "the mesh was not changed and no layer was added", ProgressiveMeshSpecs, ApplyProgressiveMesh});
  t.push_back({"Cone LOD: Export LOD File", Menu::Remeshing, Arity::SingleMesh, MeshModel::MM_NONE, MeshModel::MM_NONE,
               QString("Writes the current mesh as a streamable level-of-detail file (<tt>.clod</tt>, the paper's "
                       "sections 7-8) whose every cut is crack-free, as <tt>conelod lod build</tt> does: the mesh "
                       "is cut into clusters of about <i>Faces per cluster</i> faces whose normals stay within the "
                       "<i>Cone threshold</i>; <i>Clusters per group</i> neighbouring clusters (12 by default) "
                       "are gathered into a group, each group is simplified to <i>Faces kept per level</i> of its "
                       "faces with its border locked (with the collapse options of <i>Cone LOD: Group-Preserving "
                       "Quadric Edge Collapse</i>) and re-cut into the next level's clusters, level after level "
                       "until the mesh no longer shrinks. Every cluster is a node with its normal cone, bounding "
                       "sphere, error and geometry. A viewer (<tt>conelod-viewer</tt>) or <i>Cone LOD: Extract "
                       "View-Dependent LOD</i> reads only the nodes it needs. <i>LOD file</i> has no default: ") +
                   kLodFileHow +
                   QString(" (a relative path is relative to MeshLab's current directory; the log gives the full "
                           "path). The mesh is not changed; on failure no file is left.<br>") +
                   kPaperKamiya,
               "no file was written", LodExportSpecs, ApplyLodExport});
  t.push_back({"Cone LOD: Extract View-Dependent LOD", Menu::MeshCreation, Arity::None, MeshModel::MM_NONE,
               MeshModel::MM_NONE,
               QString("Reads a <tt>.clod</tt> file (<i>Cone LOD: Export LOD File</i>, <tt>conelod lod build</tt>) "
                       "and adds a new layer with the view-dependent mesh for one view: starting from the coarsest "
                       "clusters, a group is refined (its clusters replaced by the finer clusters it was simplified "
                       "from) while the layer stays within <i>Face budget</i> faces, the group whose error seen from "
                       "the eye (error / distance; orthographic: the error) is largest first. Each group was "
                       "simplified with its border locked, so the layer is a watertight cut of the file: it covers "
                       "the mesh exactly once and clusters of different levels meet at the very same vertices, "
                       "without cracks, whatever the levels side by side (neighbours may be several levels apart: "
                       "the log's <tt>lod_max_level_difference</tt>). The view: framed "
                       "from <i>View direction</i> at <i>Camera distance</i> bounding-sphere radii, "
                       "the <i>Eye position</i> (the dialog's Get / View Pos. fills in the current camera position), "
                       "or orthographic along <i>View direction</i>. With <i>Refine back-facing groups last</i>, "
                       "back-facing groups are refined last; with <i>Leave back-facing groups out</i> they are left "
                       "out of the layer. Per-face quality = LOD level of the face (0 = the input's own faces), a "
                       "distinct colour per level (those of conelod lod extract). A file with attributes gives "
                       "the layer its per-vertex colours and normals, and its texture coordinates per face corner "
                       "with the texture image stored in the file (MeshLab 2022.02 and later: held by the layer; "
                       "2020.09: written beside the <tt>.clod</tt> when no file has its name there, else into a "
                       "temporary folder; never over an existing file; the log says where). "
                       "<i>LOD file</i> has no default: ") +
                   kLodFileHow + QString(". The current mesh is not changed.<br>") + kPaperKamiya,
               "no layer was added", LodExtractSpecs, ApplyLodExtract});
  return t;
}

// Checks every parameter against its ParamSpec; the message names the dialog's label.
Status CheckArgs(const std::vector<ParamSpec>& specs, const Args& args) {
  for (const ParamSpec& p : specs) {
    const QByteArray name = p.name.toUtf8();
    switch (p.kind) {
      case ParamKind::Int:
      case ParamKind::Float:
      case ParamKind::AbsPerc: {
        const double v = args.number(name.constData());
        const Bound& b = p.bound;
        if (!std::isfinite(v)) return Invalid(Quoted(p) + " must be a finite number");
        const bool low = b.minOpen ? !(v > b.min) : !(v >= b.min);
        const bool high = b.maxOpen ? !(v < b.max) : !(v <= b.max);
        if (!low && !high) break;
        QString rule;
        auto num = [](double x) { return QString::number(x, 'g', 10); };
        if (std::isinf(b.max))
          rule = (b.minOpen ? "> " : ">= ") + num(b.min);
        else if (std::isinf(b.min))
          rule = (b.maxOpen ? "< " : "<= ") + num(b.max);
        else if (!b.minOpen && !b.maxOpen)
          rule = "between " + num(b.min) + " and " + num(b.max);
        else
          rule = QString("in %1%2, %3%4").arg(b.minOpen ? "(" : "[", num(b.min), num(b.max), b.maxOpen ? ")" : "]");
        return Invalid(Quoted(p) + " must be " + rule + (b.note ? QString(" (") + b.note + ")" : QString()) + ", not " +
                       num(v));
      }
      case ParamKind::Enum: {
        const double v = args.number(name.constData());
        if (!(v >= 0 && v < p.choices.size()))
          return Invalid(Quoted(p) + " must be one of its " + QString::number(p.choices.size()) + " choices (0 to " +
                         QString::number(p.choices.size() - 1) + "), not " + QString::number(v));
        break;
      }
      case ParamKind::Position:
      case ParamKind::Direction: {
        const vcg::Point3d v = args.point(name.constData());
        if (!(std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2])))
          return Invalid(Quoted(p) + " must have finite coordinates");
        break;
      }
      case ParamKind::Mesh:
        if (!args.mesh(name.constData())) return Invalid(Quoted(p) + " is not a layer of this document");
        break;
      case ParamKind::Bool:
      case ParamKind::OpenFile:
      case ParamKind::SaveFile:
        break;
    }
  }
  return Status::Ok();
}

// A core message that names a parameter by its key ("ConeThresholdDeg must be > 0") names it by
// the dialog's label instead.
QString WithLabels(QString message, const std::vector<ParamSpec>& specs) {
  for (const ParamSpec& p : specs)
    message.replace(QRegularExpression("\\b" + QRegularExpression::escape(p.name) + "\\b"), Quoted(p));
  return message;
}

}  // namespace

const std::vector<FilterSpec>& Filters() {
  static const std::vector<FilterSpec> table = MakeFilters();
  return table;
}

QString RunFilter(const FilterSpec& f, MeshDocument& doc, const Args& args, vcg::CallBackPos* cb, Report& report) {
  QString message;
  std::vector<ParamSpec> specs;
  try {
    specs = ParamsOf(f, doc);
    Status s = CheckArgs(specs, args);
    if (s.ok() && f.arity != Arity::None && !doc.mm()) s = Status::Invalid("there is no current mesh");
    if (s.ok()) {
      FilterCall call{doc, doc.mm(), args, cb, report, specs};
      s = f.apply(call);
    }
    if (!s.ok()) message = WithLabels(QString::fromStdString(s.message), specs);
  } catch (const std::bad_alloc&) {
    message = "not enough memory for this mesh";
  } catch (const std::exception& e) {
    message = QString("internal error: %1").arg(e.what());
  }
  if (message.isEmpty()) return message;
  message += QString(" (%1)").arg(f.untouched);
  report.error("ConeLOD error: " + message.toStdString());
  return message;
}

}  // namespace conelod_plugin
