// ConeLOD MeshLab plugin (see filter_conelod.h).
#include "filter_conelod.h"

#include <QElapsedTimer>
#include <exception>
#include <new>

#include "builtin_qem.h"
#include "conelod/cone_grouping.h"
#include "conelod/culling_cost.h"
#include "conelod/feature_simplify.h"
#include "conelod/mesh_check.h"
#include "conelod/pixel_budget.h"
#include "conelod/simplify_bridge.h"
#include "conelod/vcg_bridge.h"

using namespace conelod;

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

const char* const kBudgetSimplifiers[] = {"None (log the budget only)", "Feature-Preserving Edge Simplification",
                                          "Quadric Edge Collapse Decimation (MeshLab's, default parameters)"};

// The grouping parameters shared by the grouping and the culling-cost filters.
void AddGroupingParameters(RichParameterList& par) {
  const ConeGroupingParams d;
  par.addParam(RichFloat("ConeWeight", float(d.coneWeight), "Cone weight k_c",
                         "Weight of the cone term v_c = (pi - c)/pi, c = the merged group's cone half-angle. "
                         "The paper found this term matters most for culling."));
  par.addParam(RichFloat("ShapeWeight", float(d.shapeWeight), "Shape weight k_s",
                         "Weight of the shape term v_s = projected area / area of the enclosing circle "
                         "(round groups score higher)."));
  par.addParam(RichFloat("SizeWeight", float(d.sizeWeight), "Size weight k_n",
                         "Weight of the size term v_n = (N - n)/N (smaller groups score higher)."));
  par.addParam(RichFloat("ConeThresholdDeg", float(d.coneThresholdDeg), "Cone threshold (deg)",
                         "Level-1 limit on a group's cone half-angle, in degrees: pairs whose merged cone "
                         "would reach it are never merged. 180 or more: no limit."));
  par.addParam(RichFloat("ThresholdGrowth", float(d.thresholdGrowth), "Threshold growth per level",
                         "The cone threshold is multiplied by this factor at each level above the first (>= 1)."));
  par.addParam(RichInt("MaxLevels", d.maxLevels, "Max levels", "At most this many hierarchy levels."));
  par.addParam(RichInt("MinTopGroups", d.minTopGroups, "Min top-level groups",
                       "Merging stops once a level has this many groups (or fewer)."));
}

ConeGroupingParams ReadGroupingParameters(const RichParameterList& par) {
  ConeGroupingParams p;
  p.coneWeight = par.getFloat("ConeWeight");
  p.shapeWeight = par.getFloat("ShapeWeight");
  p.sizeWeight = par.getFloat("SizeWeight");
  p.coneThresholdDeg = par.getFloat("ConeThresholdDeg");
  p.thresholdGrowth = par.getFloat("ThresholdGrowth");
  p.maxLevels = par.getInt("MaxLevels");
  p.minTopGroups = par.getInt("MinTopGroups");
  return p;
}

Progress FromCallback(vcg::CallBackPos* cb) {
  if (!cb) return Progress();
  return [cb](int percent, const char* stage) { return cb(percent, stage); };
}

}  // namespace

FilterConeLodPlugin::FilterConeLodPlugin() {
  typeList << FP_CONE_GROUPING << FP_CULLING_COST << FP_FEATURE_SIMPLIFY << FP_PIXEL_BUDGET;
  for (FilterIDType tt : types()) actionList << new QAction(filterName(tt), this);
}

QString FilterConeLodPlugin::pluginName() const { return "FilterConeLOD"; }

QString FilterConeLodPlugin::filterName(FilterIDType filter) const {
  switch (filter) {
    case FP_CONE_GROUPING: return "Cone LOD: Normal Cone Face Grouping";
    case FP_CULLING_COST: return "Cone LOD: Cluster Culling Cost";
    case FP_FEATURE_SIMPLIFY: return "Cone LOD: Feature-Preserving Edge Simplification";
    case FP_PIXEL_BUDGET: return "Cone LOD: Face Budget from Screen Pixels";
  }
  return "";
}

QString FilterConeLodPlugin::filterInfo(FilterIDType filter) const {
  switch (filter) {
    case FP_CONE_GROUPING:
      return QString(
                 "Groups the faces into a hierarchy of edge-connected groups whose normals fit in a narrow "
                 "cone, so that a whole group can be back-face culled with one test. Adjacent faces (then "
                 "groups) are merged best pair first by v = k_c v_c + k_s v_s + k_n v_n, never letting a "
                 "group's cone half-angle reach the level's threshold, which grows by a factor per level. "
                 "Cones are the exact minimal cones of the normals.<br>"
                 "Writes per-face quality = group id at <i>DisplayLevel</i>, a distinct colour per group, and "
                 "the ids of every level in per-face attributes <tt>conelod_group_L1</tt>, "
                 "<tt>conelod_group_L2</tt>, ... The log lists groups and cone angles per level.<br>") +
             kPaperKamiya;
    case FP_CULLING_COST:
      return QString(
                 "Measures how much back-face culling work the normal-cone group hierarchy saves: over many "
                 "view directions uniform on the sphere, the number of group tests plus per-face tests in "
                 "visible groups, divided by the face count (per-face culling = 1). Two-state (the paper's "
                 "visible/invisible test) and three-state (fully front-facing groups skip their face "
                 "tests); the fraction of faces culled at group level against the ideal (all faces that "
                 "draw nothing). Orthographic views, or a perspective eye at <i>CameraDistance</i> "
                 "bounding-sphere radii. The mesh is not changed.<br>") +
             kPaperKamiya;
    case FP_FEATURE_SIMPLIFY:
      return QString(
                 "Simplifies the mesh by half-edge collapses (vertices never move) while keeping its sharp "
                 "features. An edge is a <i>feature edge</i> when its dihedral angle A - the angle the two "
                 "faces make at the edge, 180 deg on a flat region, 90 deg on a cube edge - is at most "
                 "<i>FeatureAngleDeg</i>; broken feature lines are extended by edge swaps; border edges are "
                 "feature lines too. Vertices with 1 or 3+ feature edges (corners) are never removed; vertices "
                 "on a feature line are removed only along it; the others go smoothest first (smallest "
                 "discrete Gaussian curvature), each into the neighbour whose collapse moves the surface "
                 "least. Stops at <i>TargetFaceNum</i> faces (when 0: <i>TargetPerc</i> x the faces) or when no "
                 "collapse keeps "
                 "every removed vertex within <i>MaxErrorDistance</i> of the result. With a target, the "
                 "error bound grows from tiny until the target is reached (<i>GrowErrorBound</i>, beyond the "
                 "paper). <i>MarkFeatures</i> selects and colours the feature vertices and makes the other "
                 "edges faux, so that the wireframe view shows the feature lines.<br>") +
             kPaperHayano;
    case FP_PIXEL_BUDGET:
      return QString(
                 "Counts the pixels the model covers on a screen of <i>Width</i> x <i>Height</i> (orthographic "
                 "view framed on the bounding sphere, from an axis or the worst of the six axis directions) "
                 "and logs the face budget <i>PixelFactor</i> x pixels: the paper found that 50 faces per "
                 "covered pixel display a scanned model without visible loss at 1920x1080, 1600x900, "
                 "1280x720 and 800x600. Optionally simplifies the mesh to the budget with the "
                 "feature-preserving simplifier or with MeshLab's Quadric Edge Collapse Decimation (its "
                 "default parameters). Says so when the budget is above the current face count.<br>") +
             kPaperMizuno;
  }
  return "";
}

MeshFilterInterface::FilterClass FilterConeLodPlugin::getClass(QAction* a) {
  switch (ID(a)) {
    case FP_CONE_GROUPING: return MeshFilterInterface::FaceColoring;
    case FP_CULLING_COST: return MeshFilterInterface::Measure;
    case FP_FEATURE_SIMPLIFY: return MeshFilterInterface::Remeshing;
    case FP_PIXEL_BUDGET: return MeshFilterInterface::Remeshing;
  }
  return MeshFilterInterface::Measure;
}

int FilterConeLodPlugin::getRequirements(QAction* a) {
  return ID(a) == FP_CONE_GROUPING ? (MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR) : MeshModel::MM_NONE;
}

int FilterConeLodPlugin::postCondition(QAction* a) const {
  switch (ID(a)) {
    case FP_CONE_GROUPING: return MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR;
    case FP_FEATURE_SIMPLIFY:
      return MeshModel::MM_GEOMETRY_AND_TOPOLOGY_CHANGE | MeshModel::MM_VERTCOLOR | MeshModel::MM_VERTFLAGSELECT |
             MeshModel::MM_FACEFLAG;
    case FP_PIXEL_BUDGET: return MeshModel::MM_GEOMETRY_AND_TOPOLOGY_CHANGE;
  }
  return MeshModel::MM_NONE;
}

void FilterConeLodPlugin::initParameterSet(QAction* a, MeshModel& m, RichParameterList& par) {
  switch (ID(a)) {
    case FP_CONE_GROUPING:
      AddGroupingParameters(par);
      par.addParam(RichInt("DisplayLevel", 1, "Display level",
                           "Hierarchy level shown as per-face quality and colour (1 = finest). A level above "
                           "the top is shown as the top level."));
      break;
    case FP_CULLING_COST:
      AddGroupingParameters(par);
      par.addParam(RichInt("Views", 1000, "View directions", "Number of view directions, uniform on the sphere."));
      par.addParam(RichFloat("CameraDistance", 0.0f, "Camera distance",
                             "0: orthographic views (the paper's test). Otherwise a perspective eye at this many "
                             "bounding-sphere radii (> 1) from the model's centre."));
      break;
    case FP_FEATURE_SIMPLIFY: {
      const FeatureSimplifyParams d;
      const float diag = m.cm.bbox.IsNull() ? 0.0f : m.cm.bbox.Diag();
      par.addParam(RichFloat("FeatureAngleDeg", float(d.featureAngleDeg), "Feature angle A_t (deg)",
                             "An edge is a feature edge when its dihedral angle A is at most this. A is the angle the "
                             "two faces make at the edge (the paper's definition): 180 on a flat region, 90 on a "
                             "cube edge, near 0 on a knife edge."));
      par.addParam(RichBool("ExtendFeatureLines", d.extendFeatureLines, "Extend feature lines",
                            "Close gaps in feature lines by edge swaps when the swapped edge is itself a feature "
                            "edge (the paper's 3.1)."));
      par.addParam(RichFloat("FeatureCurvature", float(d.featureCurvature), "Feature vertex curvature K_t",
                             "A vertex without feature edges whose |K| D^2 reaches this is a feature vertex (kept); "
                             "K = discrete Gaussian curvature, D = bounding-box diagonal. 0 = off."));
      par.addParam(RichFloat("CurvatureThreshold", float(d.curvatureThreshold), "Curvature threshold",
                             "Vertices whose |K| D^2 (smooth) or |M| D (on a feature line; M = turning angle over "
                             "half the two edges' length) reaches this are not removed: only the flatter parts are "
                             "simplified. 0 = no limit."));
      par.addParam(RichAbsPerc("MaxErrorDistance", 0.0f, 0.0f, diag, "Max error distance",
                               "Stop criterion: a collapse is applied only if every removed vertex of the original "
                               "mesh stays within this distance of the result (absolute, or % of the bounding-box "
                               "diagonal). 0 = off."));
      par.addParam(RichInt("TargetFaceNum", m.cm.fn / 2, "Target number of faces",
                           "Stop criterion: stop at this many faces. 0 = use TargetPerc."));
      par.addParam(RichFloat("TargetPerc", 0.5f, "Target fraction (0..1)",
                             "Used when TargetFaceNum is 0: the target is this fraction of the current face count. "
                             "0 (with TargetFaceNum 0) = no target: stop by MaxErrorDistance only."));
      par.addParam(RichBool("GrowErrorBound", d.growErrorBound, "Grow the error bound",
                            "With a target face count: simplify under an error bound that starts tiny and grows only "
                            "when no collapse fits (beyond the paper; much closer to the original). Off: the paper's "
                            "pure curvature order up to the target."));
      par.addParam(RichBool("MarkFeatures", true, "Mark the features",
                            "Select the feature vertices, colour the vertices (red: feature line, blue: feature "
                            "vertex) and make every non-feature edge faux, so that the wireframe view shows the "
                            "feature lines."));
      break;
    }
    case FP_PIXEL_BUDGET: {
      const PixelBudgetParams d;
      par.addParam(RichInt("Width", d.width, "Screen width (pixels)", "Width of the screen the model is shown on."));
      par.addParam(RichInt("Height", d.height, "Screen height (pixels)", "Height of the screen the model is shown on."));
      par.addParam(RichFloat("PixelFactor", float(d.pixelFactor), "Faces per covered pixel",
                             "The budget is this many faces per pixel the model covers (the paper's finding: 50)."));
      par.addParam(RichEnum("View", 0,
                            QStringList() << "Worst of the six axis directions" << "+X" << "-X" << "+Y" << "-Y"
                                          << "+Z" << "-Z" << "Direction below",
                            "View", "Direction the model is looked at (orthographic, framed on its bounding "
                            "sphere). The worst case counts the most pixels."));
      par.addParam(RichPoint3f("ViewDirection", vcg::Point3f(0, 0, -1), "View direction",
                               "Used when View is 'Direction below': the direction from the eye to the model."));
      par.addParam(RichEnum("Simplifier", 0,
                            QStringList() << kBudgetSimplifiers[0] << kBudgetSimplifiers[1] << kBudgetSimplifiers[2],
                            "Simplify to the budget with",
                            "None: only log the pixels and the budget. Otherwise the mesh is simplified to the budget "
                            "(when it has more faces)."));
      break;
    }
  }
}

bool FilterConeLodPlugin::fail(const QString& message) {
  errorMessage = message;
  Log(GLLogStream::SYSTEM, ("ConeLOD error: " + message).toStdString());
  return false;
}

bool FilterConeLodPlugin::applyFilter(QAction* a, MeshDocument& md, const RichParameterList& par,
                                      vcg::CallBackPos* cb) {
  // Never let an exception reach MeshLab: it would lose the user's unsaved work.
  try {
    MeshModel* mm = md.mm();
    if (!mm) return fail("no current mesh");
    switch (ID(a)) {
      case FP_CONE_GROUPING: return applyConeGrouping(*mm, par, cb);
      case FP_CULLING_COST: return applyCullingCost(*mm, par, cb);
      case FP_FEATURE_SIMPLIFY: return applyFeatureSimplify(*mm, par, cb);
      case FP_PIXEL_BUDGET: return applyPixelBudget(*mm, par, cb);
    }
    return fail("unknown filter");
  } catch (const std::bad_alloc&) {
    return fail("not enough memory for this mesh; the mesh was not changed");
  } catch (const std::exception& e) {
    return fail(QString("internal error: %1; the mesh was not changed").arg(e.what()));
  }
}

bool FilterConeLodPlugin::applyConeGrouping(MeshModel& mm, const RichParameterList& par, vcg::CallBackPos* cb) {
  const ConeGroupingParams params = ReadGroupingParameters(par);
  int displayLevel = par.getInt("DisplayLevel");
  if (displayLevel < 1) return fail("DisplayLevel must be >= 1");

  std::vector<size_t> faceOf;
  const IndexedMesh im = ToIndexedMesh(mm.cm, &faceOf);
  GroupHierarchy h;
  QElapsedTimer timer;
  timer.start();
  const Status s = BuildConeHierarchy(im, params, h, FromCallback(cb));
  if (!s.ok()) return fail(QString::fromStdString(s.message) + " (the mesh was not changed)");
  const double seconds = timer.elapsed() / 1000.0;
  if (displayLevel > h.levelCount()) {
    Log("DisplayLevel %d is above the %d levels built: showing level %d", displayLevel, h.levelCount(),
        h.levelCount());
    displayLevel = h.levelCount();
  }

  mm.updateDataMask(MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR);
  WriteGroupResults(mm.cm, faceOf, h, displayLevel);

  Log("Normal cone grouping: %d faces, %d levels in %.3f s; quality and colour = groups of level %d",
      int(im.faceCount()), h.levelCount(), seconds, displayLevel);
  Log("level  limit_deg  groups  max_cone_deg  mean_cone_deg  uncullable");
  for (int l = 1; l <= h.levelCount(); ++l) {
    const GroupLevel& lv = h.level(l);
    Log("%5d  %9.1f  %6d  %12.2f  %13.2f  %10d", l, lv.thresholdDeg, int(lv.groups.size()), lv.maxConeDeg(),
        lv.meanConeDeg(), lv.uncullableGroups());
  }
  return true;
}

bool FilterConeLodPlugin::applyCullingCost(MeshModel& mm, const RichParameterList& par, vcg::CallBackPos* cb) {
  const ConeGroupingParams params = ReadGroupingParameters(par);
  CullingCostParams cp;
  cp.views = par.getInt("Views");
  cp.cameraDistance = par.getFloat("CameraDistance");

  const IndexedMesh im = ToIndexedMesh(mm.cm);
  GroupHierarchy h;
  Status s = BuildConeHierarchy(im, params, h, SubProgress(FromCallback(cb), 0, 50));
  if (!s.ok()) return fail(QString::fromStdString(s.message));
  CullingCostResult r;
  s = EvaluateCullingCost(im, h, cp, r, SubProgress(FromCallback(cb), 50, 100));
  if (!s.ok()) return fail(QString::fromStdString(s.message));

  Log("Cluster culling cost over %d %s views: %d faces, %d levels (%d groups at level 1, %d at the top)", r.views,
      r.perspective ? "perspective" : "orthographic", int(im.faceCount()), h.levelCount(),
      int(h.level(1).groups.size()), int(h.level(h.levelCount()).groups.size()));
  Log("two_state_cost %.4f (min %.4f, max %.4f)", r.twoState.mean, r.twoState.min, r.twoState.max);
  Log("three_state_cost %.4f (min %.4f, max %.4f)", r.threeState.mean, r.threeState.min, r.threeState.max);
  Log("rejected_fraction %.4f  ideal_fraction %.4f  (%.1f%% of the ideal culled at group level)",
      r.rejectedFraction, r.idealFraction, r.idealFraction > 0 ? 100 * r.rejectedFraction / r.idealFraction : 0.0);
  Log("front_accepted_fraction %.4f  mean_group_tests %.1f", r.frontAcceptedFraction, r.meanGroupTests);
  return true;
}

bool FilterConeLodPlugin::applyFeatureSimplify(MeshModel& mm, const RichParameterList& par, vcg::CallBackPos* cb) {
  FeatureSimplifyParams params;
  params.featureAngleDeg = par.getFloat("FeatureAngleDeg");
  params.extendFeatureLines = par.getBool("ExtendFeatureLines");
  params.featureCurvature = par.getFloat("FeatureCurvature");
  params.curvatureThreshold = par.getFloat("CurvatureThreshold");
  params.maxErrorDistance = par.getAbsPerc("MaxErrorDistance");
  params.growErrorBound = par.getBool("GrowErrorBound");
  const int targetFaces = par.getInt("TargetFaceNum");
  const float targetPerc = par.getFloat("TargetPerc");
  if (targetFaces < 0 || targetPerc < 0 || targetPerc > 1)
    return fail("TargetFaceNum must be >= 0 and TargetPerc between 0 and 1 (the mesh was not changed)");
  params.targetFaceCount = targetFaces > 0 ? size_t(targetFaces) : size_t(std::lround(double(mm.cm.fn) * targetPerc));
  if (targetFaces == 0 && targetPerc > 0 && params.targetFaceCount == 0) params.targetFaceCount = 1;
  const bool mark = par.getBool("MarkFeatures");

  std::vector<size_t> faceOf;
  const IndexedMesh im = ToIndexedMesh(mm.cm, &faceOf);
  FeatureSimplifyResult r;
  QElapsedTimer timer;
  timer.start();
  const Status s = FeatureSimplify(im, params, r, FromCallback(cb));
  if (!s.ok()) return fail(QString::fromStdString(s.message) + " (the mesh was not changed)");
  const double seconds = timer.elapsed() / 1000.0;

  if (mark) mm.updateDataMask(MeshModel::MM_VERTCOLOR);
  mm.clearDataMask(MeshModel::MM_FACEFACETOPO | MeshModel::MM_VERTFACETOPO);
  WriteSimplifiedMesh(mm.cm, faceOf, r, mark);
  mm.UpdateBoxAndNormals();

  Log("Feature-preserving simplification: %d -> %d faces in %.3f s (%d collapses)%s", int(r.facesIn),
      int(r.facesOut), seconds, int(r.collapses),
      params.targetFaceCount == 0 ? ""
      : r.targetReached           ? ", target reached"
                                  : ", target NOT reached: no allowed collapse left");
  Log("faces_out %d", int(r.facesOut));
  Log("feature_edges %d (%d made by extension swaps) -> feature_edges_out %d", int(r.featureEdgesIn),
      int(r.swapEdges), int(r.featureEdges.size()));
  Log("feature_vertices %d (kept), feature-line vertices %d, smooth vertices %d", int(r.featureVertices),
      int(r.lineVerticesIn), int(r.smoothVerticesIn));
  if (r.finalErrorBound > 0)
    Log("error bound at the end %g (%.4f %% of the diagonal)", r.finalErrorBound,
        100.0 * r.finalErrorBound / std::max(1e-30, BoundingBoxDiagonal(im)));
  if (mark) Log("feature vertices selected and coloured; non-feature edges faux (wireframe shows the feature lines)");
  return true;
}

bool FilterConeLodPlugin::applyPixelBudget(MeshModel& mm, const RichParameterList& par, vcg::CallBackPos* cb) {
  PixelBudgetParams params;
  params.width = par.getInt("Width");
  params.height = par.getInt("Height");
  params.pixelFactor = par.getFloat("PixelFactor");
  const int view = par.getEnum("View");
  if (view < 0 || view > 7) return fail("View must be one of the listed directions (the mesh was not changed)");
  params.view = view == 7 ? BudgetView::Direction : BudgetView(view);
  params.direction = vcg::Point3d::Construct(par.getPoint3f("ViewDirection"));
  const int simplifier = par.getEnum("Simplifier");
  if (simplifier < 0 || simplifier > 2) return fail("Simplifier must be 0, 1 or 2 (the mesh was not changed)");

  const IndexedMesh im = ToIndexedMesh(mm.cm);
  PixelBudgetResult r;
  Status s = ComputePixelBudget(im, params, r, SubProgress(FromCallback(cb), 0, simplifier == 0 ? 100 : 10));
  if (!s.ok()) return fail(QString::fromStdString(s.message) + " (the mesh was not changed)");
  Log("Face budget at %d x %d, view %s: covered_pixels %d (%.1f %% of the screen)", params.width, params.height,
      BudgetViewName(params.view, params.direction).c_str(), int(r.coveredPixels),
      100.0 * double(r.coveredPixels) / (double(params.width) * params.height));
  Log("target_faces %d (= %g x %d pixels); the mesh has %d faces", int(r.targetFaces), params.pixelFactor,
      int(r.coveredPixels), int(r.currentFaces));
  if (r.aboveCurrent) {
    Log("The budget is ABOVE the current face count: no reduction is needed%s",
        simplifier ? " (the mesh was not changed)" : "");
    return true;
  }
  if (simplifier == 0) return true;
  const int target = std::max(1, int(r.targetFaces));
  if (simplifier == 1) {
    std::vector<size_t> faceOf;
    const IndexedMesh again = ToIndexedMesh(mm.cm, &faceOf);
    FeatureSimplifyParams fp;
    fp.targetFaceCount = size_t(target);
    FeatureSimplifyResult fr;
    s = FeatureSimplify(again, fp, fr, SubProgress(FromCallback(cb), 10, 100));
    if (!s.ok()) return fail(QString::fromStdString(s.message) + " (the mesh was not changed)");
    mm.clearDataMask(MeshModel::MM_FACEFACETOPO | MeshModel::MM_VERTFACETOPO);
    WriteSimplifiedMesh(mm.cm, faceOf, fr, false);
    mm.UpdateBoxAndNormals();
  } else {
    conelod_plugin::RunBuiltinQuadric(mm, target, cb);
  }
  Log("Simplified to the budget with %s: faces_out %d", kBudgetSimplifiers[simplifier], mm.cm.fn);
  return true;
}

MESHLAB_PLUGIN_NAME_EXPORTER(FilterConeLodPlugin)
