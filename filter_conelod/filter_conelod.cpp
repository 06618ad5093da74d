// ConeLOD MeshLab plugin (see filter_conelod.h).
#include "filter_conelod.h"

#include <QElapsedTimer>
#include <exception>
#include <new>

#include "conelod/cone_grouping.h"
#include "conelod/culling_cost.h"
#include "conelod/group_integrity.h"
#include "conelod/group_qem.h"
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

// Per-face quality of the live faces, in ToIndexedMesh order.
std::vector<float> FaceQualities(const CMeshO& m) {
  std::vector<float> q;
  q.reserve(size_t(m.fn));
  for (const auto& f : m.face)
    if (!f.IsD()) q.push_back(float(f.cQ()));
  return q;
}

const char* StopName(GroupQemStats::Stop s) {
  switch (s) {
    case GroupQemStats::Stop::TargetReached: return "target reached";
    case GroupQemStats::Stop::NoMoreCollapses: return "no allowed collapse left";
    case GroupQemStats::Stop::Cancelled: return "cancelled";
  }
  return "?";
}

}  // namespace

FilterConeLodPlugin::FilterConeLodPlugin() {
  typeList << FP_CONE_GROUPING << FP_CULLING_COST << FP_GROUP_QEM << FP_GROUP_INTEGRITY;
  for (FilterIDType tt : types()) actionList << new QAction(filterName(tt), this);
}

QString FilterConeLodPlugin::pluginName() const { return "FilterConeLOD"; }

QString FilterConeLodPlugin::filterName(FilterIDType filter) const {
  switch (filter) {
    case FP_CONE_GROUPING: return "Cone LOD: Normal Cone Face Grouping";
    case FP_CULLING_COST: return "Cone LOD: Cluster Culling Cost";
    case FP_GROUP_QEM: return "Cone LOD: Group-Preserving Quadric Edge Collapse";
    case FP_GROUP_INTEGRITY: return "Cone LOD: Group Integrity";
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
    case FP_GROUP_QEM:
      return QString(
                 "Quadric edge collapse simplification (Garland-Heckbert, as the built-in <i>Quadric Edge "
                 "Collapse Decimation</i>) that keeps face groups intact (the paper's section 6): "
                 "<b>condition 1</b> refuses every collapse that would split a group or remove its last faces; "
                 "<b>condition 2</b> refuses every collapse that would create a vertex where three or more "
                 "groups meet. Group contours still simplify (a contour edge collapses onto the contour; "
                 "group corners never move). <i>LockGroupBoundaries</i> keeps every contour vertex where it "
                 "is (crack-free refinement between groups, less reduction).<br>"
                 "Groups: the per-face quality (e.g. from <i>Cone LOD: Normal Cone Face Grouping</i>; equal "
                 "values = one group), or the normal-cone groups of a hierarchy level computed here (then "
                 "written to per-face quality and colour). Faces keep their quality, colour and attributes. "
                 "The log lists faces, groups before/after, groups split or vanished, and the time.<br>") +
             kPaperKamiya;
    case FP_GROUP_INTEGRITY:
      return QString(
                 "Measures whether the face groups of the current mesh are those of <i>ReferenceMesh</i> "
                 "(usually the mesh before a simplification), group ids being the per-face quality: groups "
                 "before and after, groups that vanished, groups split into more edge-connected pieces than "
                 "they had, groups already in several pieces in the reference (reported, not counted as "
                 "split). With the current mesh as reference it counts groups and their pieces. The meshes "
                 "are not changed.<br>") +
             kPaperKamiya;
  }
  return "";
}

MeshFilterInterface::FilterClass FilterConeLodPlugin::getClass(QAction* a) {
  switch (ID(a)) {
    case FP_CONE_GROUPING: return MeshFilterInterface::FaceColoring;
    case FP_CULLING_COST: return MeshFilterInterface::Measure;
    case FP_GROUP_QEM: return MeshFilterInterface::Remeshing;
    case FP_GROUP_INTEGRITY: return MeshFilterInterface::Measure;
  }
  return MeshFilterInterface::Measure;
}

int FilterConeLodPlugin::getRequirements(QAction* a) {
  return ID(a) == FP_CONE_GROUPING ? (MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR) : MeshModel::MM_NONE;
}

int FilterConeLodPlugin::postCondition(QAction* a) const {
  switch (ID(a)) {
    case FP_CONE_GROUPING: return MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR;
    case FP_GROUP_QEM: return MeshModel::MM_GEOMETRY_AND_TOPOLOGY_CHANGE | MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR;
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
    case FP_GROUP_QEM: {
      const GroupQemParams d;
      par.addParam(RichInt("TargetFaceNum", m.cm.fn / 2, "Target number of faces",
                           "The simplification stops at this many faces (or earlier when no collapse is left "
                           "that keeps the groups intact)."));
      par.addParam(RichFloat("TargetPerc", 0.f, "Percentage reduction (0..1)",
                             "If non zero, the target is this fraction of the current face count (0.1 = 10%)."));
      par.addParam(RichFloat("MaxErrorPerc", 0.f, "Max error (% of bbox diagonal)",
                             "If non zero, no collapse whose quadric error (RMS distance) exceeds this percentage of "
                             "the bounding-box diagonal is done. 0: no limit."));
      par.addParam(RichEnum("GroupSource", 0, QStringList() << "Per-face quality" << "Normal cone groups",
                            "Groups", "Per-face quality: the ids already on the mesh (e.g. from Cone LOD: Normal "
                            "Cone Face Grouping). Normal cone groups: computed now at GroupLevel with the default "
                            "grouping parameters."));
      par.addParam(RichInt("GroupLevel", 1, "Normal cone level",
                           "Hierarchy level of the normal cone groups (1 = finest); used with GroupSource = Normal "
                           "cone groups."));
      par.addParam(RichBool("Condition1", d.condition1, "Condition 1: keep groups whole",
                            "Refuse collapses that split a group or remove its last faces."));
      par.addParam(RichBool("Condition2", d.condition2, "Condition 2: no new group corners",
                            "Refuse collapses that create a vertex where 3 or more groups meet."));
      par.addParam(RichBool("LockGroupBoundaries", d.lockGroupBoundaries, "Lock group boundaries",
                            "No vertex on a group boundary moves: group contours stay exactly as they are."));
      par.addParam(RichFloat("QualityThr", float(d.qualityThr), "Quality threshold",
                             "Collapses creating faces of quality (2 area / longest edge^2) below this are "
                             "penalised, as in the built-in filter. 0: no penalty."));
      par.addParam(RichBool("OptimalPlacement", d.optimalPlacement, "Optimal position of simplified vertices",
                            "The merged vertex goes where the quadric error is least; otherwise to the better "
                            "endpoint."));
      par.addParam(RichBool("PreserveBoundary", d.preserveBoundary, "Preserve Boundary of the mesh",
                            "Vertices on the mesh border never move."));
      par.addParam(RichFloat("BoundaryWeight", float(d.boundaryWeight), "Boundary Preserving Weight",
                             "Weight of the quadrics that keep mesh borders (and group contours) in place."));
      par.addParam(RichBool("PreserveNormal", d.preserveNormal, "Preserve Normal",
                            "Refuse collapses that turn a face's normal by more than about 78 degrees (fold-overs)."));
      break;
    }
  }
}

void FilterConeLodPlugin::initParameterSet(QAction* a, MeshDocument& md, RichParameterList& par) {
  if (ID(a) == FP_GROUP_INTEGRITY) {
    par.addParam(RichMesh("ReferenceMesh", md.mm(), &md, "Reference mesh",
                          "The mesh whose groups (per-face quality) are the reference, e.g. the mesh before "
                          "simplification. The current mesh is measured against it."));
    return;
  }
  if (md.mm()) initParameterSet(a, *md.mm(), par);
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
      case FP_GROUP_QEM: return applyGroupQem(*mm, par, cb);
      case FP_GROUP_INTEGRITY: return applyGroupIntegrity(md, par);
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

bool FilterConeLodPlugin::applyGroupQem(MeshModel& mm, const RichParameterList& par, vcg::CallBackPos* cb) {
  GroupQemParams p;
  const float perc = par.getFloat("TargetPerc");
  const int targetFaceNum = par.getInt("TargetFaceNum");
  if (perc < 0 || perc > 1) return fail("TargetPerc must be between 0 and 1");
  if (targetFaceNum < 0) return fail("TargetFaceNum must be >= 0");
  p.targetFaces = perc > 0 ? std::max<size_t>(1, size_t(double(perc) * mm.cm.fn)) : size_t(targetFaceNum);
  p.maxError = par.getFloat("MaxErrorPerc") / 100.0;
  p.condition1 = par.getBool("Condition1");
  p.condition2 = par.getBool("Condition2");
  p.lockGroupBoundaries = par.getBool("LockGroupBoundaries");
  p.qualityThr = par.getFloat("QualityThr");
  p.optimalPlacement = par.getBool("OptimalPlacement");
  p.preserveBoundary = par.getBool("PreserveBoundary");
  p.boundaryWeight = par.getFloat("BoundaryWeight");
  p.preserveNormal = par.getBool("PreserveNormal");
  Status s = ValidateParams(p);
  if (!s.ok()) return fail(QString::fromStdString(s.message));

  std::vector<size_t> faceOf;
  const IndexedMesh im = ToIndexedMesh(mm.cm, &faceOf);
  s = RequireValidForFaces(CheckMesh(im, false));
  if (!s.ok()) return fail(QString::fromStdString(s.message) + " (the mesh was not changed)");
  QElapsedTimer timer;
  timer.start();
  std::vector<int> groups;
  const bool coneSource = par.getEnum("GroupSource") == 1;
  int level = par.getInt("GroupLevel");
  Progress progress = FromCallback(cb);
  if (coneSource) {
    GroupHierarchy h;
    s = BuildConeHierarchy(im, ConeGroupingParams(), h, SubProgress(progress, 0, 30));
    if (!s.ok()) return fail(QString::fromStdString(s.message) + " (the mesh was not changed)");
    if (level < 1 || level > h.levelCount()) {
      Log("GroupLevel %d is outside the %d levels built: using level %d", level, h.levelCount(),
          std::min(std::max(level, 1), h.levelCount()));
      level = std::min(std::max(level, 1), h.levelCount());
    }
    groups = h.level(level).faceGroup;
    progress = SubProgress(progress, 30, 100);
  } else {
    if (!mm.hasDataMask(MeshModel::MM_FACEQUALITY))
      return fail("the mesh has no per-face quality to use as group ids: run Cone LOD: Normal Cone Face Grouping "
                  "first, or set GroupSource to Normal cone groups (the mesh was not changed)");
    const std::vector<float> q = FaceQualities(mm.cm);
    std::vector<std::vector<int>> ids;
    s = GroupIdsFromValues({&q}, ids);
    if (!s.ok()) return fail(QString::fromStdString(s.message) + " (the mesh was not changed)");
    groups = std::move(ids[0]);
  }
  GroupQemResult r;
  s = SimplifyPreservingGroups(im, groups, p, r, progress);
  if (!s.ok()) return fail(QString::fromStdString(s.message) + " (the mesh was not changed)");
  const double seconds = timer.elapsed() / 1000.0;

  std::vector<int> groupsAfter(r.sourceFace.size());
  for (size_t f = 0; f < r.sourceFace.size(); ++f) groupsAfter[f] = groups[r.sourceFace[f]];
  GroupIntegrity gi;
  MeasureGroupIntegrity(im, groups, r.mesh, groupsAfter, gi);

  mm.updateDataMask(MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR);
  ApplySimplifiedMesh(mm.cm, faceOf, r.mesh, r.sourceFace, r.sourceVertex);
  if (coneSource)  // faces are in the same order as the groups after compaction
    for (size_t f = 0; f < groupsAfter.size(); ++f) {
      mm.cm.face[f].Q() = CMeshO::FaceType::QualityType(groupsAfter[f]);
      mm.cm.face[f].C() = GroupColor(groupsAfter[f]);
    }
  if (mm.hasDataMask(MeshModel::MM_FACEFACETOPO)) vcg::tri::UpdateTopology<CMeshO>::FaceFace(mm.cm);
  if (mm.hasDataMask(MeshModel::MM_VERTFACETOPO)) vcg::tri::UpdateTopology<CMeshO>::VertexFace(mm.cm);
  mm.UpdateBoxAndNormals();

  const std::string source = coneSource ? "normal cone groups, level " + std::to_string(level) : "per-face quality groups";
  Log("Group-preserving QEM (%s): faces_in %d faces_out %d target %d (%s) seconds %.3f", source.c_str(),
      int(im.faceCount()), int(r.mesh.faceCount()), int(p.targetFaces), StopName(r.stats.stop), seconds);
  Log("groups_before %d groups_after %d groups_split %d groups_vanished %d groups_disconnected_in %d "
      "integrity_percent %.2f",
      gi.groupsBefore, gi.groupsAfter, gi.groupsSplit, gi.groupsVanished, gi.groupsDisconnectedBefore,
      100 * gi.intact());
  if (gi.groupsDisconnectedBefore)
    Log("%d groups were already in several pieces in the input: each piece was kept as it was",
        gi.groupsDisconnectedBefore);
  Log("collapses %d; refused evaluations: topology %d, condition 1 %d, condition 2 %d, lock %d, fixed %d, geometry %d",
      int(r.stats.collapses), int(r.stats.refusedTopology), int(r.stats.refusedCondition1),
      int(r.stats.refusedCondition2), int(r.stats.refusedLock), int(r.stats.refusedFixed),
      int(r.stats.refusedGeometry));
  return true;
}

bool FilterConeLodPlugin::applyGroupIntegrity(MeshDocument& md, const RichParameterList& par) {
  MeshModel* cur = md.mm();
  MeshModel* ref = par.getMesh("ReferenceMesh");
  if (!ref) return fail("ReferenceMesh is not a mesh of this document");
  for (MeshModel* m : {ref, cur})
    if (!m->hasDataMask(MeshModel::MM_FACEQUALITY))
      return fail(QString("layer '%1' has no per-face quality to read group ids from").arg(m->label()));
  const IndexedMesh refMesh = ToIndexedMesh(ref->cm), curMesh = ToIndexedMesh(cur->cm);
  const std::vector<float> qr = FaceQualities(ref->cm), qc = FaceQualities(cur->cm);
  std::vector<std::vector<int>> ids;
  Status s = GroupIdsFromValues({&qr, &qc}, ids);
  if (!s.ok()) return fail(QString::fromStdString(s.message));
  GroupIntegrity gi;
  s = MeasureGroupIntegrity(refMesh, ids[0], curMesh, ids[1], gi);
  if (!s.ok()) return fail(QString::fromStdString(s.message));
  Log("Group integrity of '%s' against '%s' (group id = per-face quality):", qUtf8Printable(cur->label()),
      qUtf8Printable(ref->label()));
  Log("groups_before %d groups_after %d groups_split %d groups_vanished %d groups_disconnected_before %d "
      "groups_disconnected_after %d groups_new %d integrity_percent %.2f",
      gi.groupsBefore, gi.groupsAfter, gi.groupsSplit, gi.groupsVanished, gi.groupsDisconnectedBefore,
      gi.groupsDisconnectedAfter, gi.groupsNew, 100 * gi.intact());
  auto list = [](const std::vector<int>& v) {
    QStringList l;
    for (int id : v) l << QString::number(id);
    return l.join(" ");
  };
  if (!gi.splitIds.empty()) Log("split groups (first ones): %s", qUtf8Printable(list(gi.splitIds)));
  if (!gi.vanishedIds.empty()) Log("vanished groups (first ones): %s", qUtf8Printable(list(gi.vanishedIds)));
  return true;
}

MESHLAB_PLUGIN_NAME_EXPORTER(FilterConeLodPlugin)
