// ConeLOD MeshLab plugin (see filter_conelod.h).
#include "filter_conelod.h"

#include <QElapsedTimer>
#include <exception>
#include <new>

#include "conelod/cone_grouping.h"
#include "conelod/culling_cost.h"
#include "conelod/mesh_check.h"
#include "conelod/vcg_bridge.h"

using namespace conelod;

namespace {

const char* const kPaperKamiya =
    "M. Kamiya, H. Suzuki, K. Kawachi, <i>LODs for efficient displaying triangle meshes</i> "
    "(University of Tokyo).";

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
  typeList << FP_CONE_GROUPING << FP_CULLING_COST;
  for (FilterIDType tt : types()) actionList << new QAction(filterName(tt), this);
}

QString FilterConeLodPlugin::pluginName() const { return "FilterConeLOD"; }

QString FilterConeLodPlugin::filterName(FilterIDType filter) const {
  switch (filter) {
    case FP_CONE_GROUPING: return "Cone LOD: Normal Cone Face Grouping";
    case FP_CULLING_COST: return "Cone LOD: Cluster Culling Cost";
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
  }
  return "";
}

MeshFilterInterface::FilterClass FilterConeLodPlugin::getClass(QAction* a) {
  switch (ID(a)) {
    case FP_CONE_GROUPING: return MeshFilterInterface::FaceColoring;
    case FP_CULLING_COST: return MeshFilterInterface::Measure;
  }
  return MeshFilterInterface::Measure;
}

int FilterConeLodPlugin::getRequirements(QAction* a) {
  return ID(a) == FP_CONE_GROUPING ? (MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR) : MeshModel::MM_NONE;
}

int FilterConeLodPlugin::postCondition(QAction* a) const {
  return ID(a) == FP_CONE_GROUPING ? (MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR) : MeshModel::MM_NONE;
}

void FilterConeLodPlugin::initParameterSet(QAction* a, MeshModel& /*m*/, RichParameterList& par) {
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
  }
}

bool FilterConeLodPlugin::fail(const QString& message) {
  errorMessage = message;
  Log(GLLogStream::SYSTEM, ("ConeLOD error: " + message).toStdString());
  return false;
}

bool FilterConeLodPlugin::applyFilter(QAction* a, MeshDocument& md, const RichParameterList& par,
                                      vcg::CallBackPos* cb) {
  errorMessage.clear();
  // Never let an exception reach MeshLab: it would lose the user's unsaved work.
  try {
    MeshModel* mm = md.mm();
    if (!mm) return fail("no current mesh");
    switch (ID(a)) {
      case FP_CONE_GROUPING: return applyConeGrouping(*mm, par, cb);
      case FP_CULLING_COST: return applyCullingCost(*mm, par, cb);
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
  for (int l = 1; l <= h.levelCount(); ++l) {
    const GroupLevel& lv = h.level(l);
    Log("level %d: groups %d, max_cone_deg %.2f, mean_cone_deg %.2f, limit_deg %.1f, uncullable %d", l,
        int(lv.groups.size()), lv.maxConeDeg(), lv.meanConeDeg(), lv.thresholdDeg, lv.uncullableGroups());
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

MESHLAB_PLUGIN_NAME_EXPORTER(FilterConeLodPlugin)
