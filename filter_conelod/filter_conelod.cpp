// ConeLOD MeshLab plugin (see filter_conelod.h).
#include "filter_conelod.h"

#include <QElapsedTimer>
#include <exception>
#include <new>

#include "conelod/cone_grouping.h"
#include "conelod/culling_cost.h"
#include "conelod/manifold_check.h"
#include "conelod/mesh_check.h"
#include "conelod/pca_partition.h"
#include "conelod/progressive_cluster_mesh.h"
#include "conelod/sampled_distance.h"
#include "conelod/vcg_bridge.h"

#include <vcg/complex/algorithms/update/bounding.h>
#include <vcg/complex/algorithms/update/normal.h>

using namespace conelod;

namespace {

const char* const kPaperKamiya =
    "M. Kamiya, H. Suzuki, K. Kawachi, <i>LODs for efficient displaying triangle meshes</i> "
    "(University of Tokyo).";
const char* const kPaperTsuji =
    "T. Tsuji, H. Zha, R. Kurazume, T. Hasegawa, <i>Face clusters partitioning for hierarchical data "
    "structure and high speed rendering</i> (Kyushu University).";

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
  typeList << FP_CONE_GROUPING << FP_CULLING_COST << FP_PCA_PARTITION << FP_PROGRESSIVE_MESH;
  for (FilterIDType tt : types()) actionList << new QAction(filterName(tt), this);
}

QString FilterConeLodPlugin::pluginName() const { return "FilterConeLOD"; }

QString FilterConeLodPlugin::filterName(FilterIDType filter) const {
  switch (filter) {
    case FP_CONE_GROUPING: return "Cone LOD: Normal Cone Face Grouping";
    case FP_CULLING_COST: return "Cone LOD: Cluster Culling Cost";
    case FP_PCA_PARTITION: return "Cone LOD: PCA Recursive Face Partition";
    case FP_PROGRESSIVE_MESH: return "Cone LOD: Progressive Cluster Mesh";
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
    case FP_PCA_PARTITION:
      return QString(
                 "Splits the mesh recursively into edge-connected face clusters: each cluster is cut by the "
                 "plane through its area centroid perpendicular to its principal axis, found by a "
                 "<i>face-based</i> PCA (the covariance of the surface, exact per triangle, so that uneven "
                 "vertex density does not bias it); the two halves grow from the faces farthest along the "
                 "axis, and faces reached by neither join the half they touch, so both halves stay "
                 "connected. The cluster of largest error (the smallest eigenvalue, the variance across the "
                 "cluster) is split first, until <i>TargetClusters</i> clusters or another stop criterion. "
                 "Several connected components are the first split.<br>"
                 "Writes per-face quality = cluster id, a distinct colour per cluster and the per-face "
                 "attribute <tt>conelod_pca_cluster</tt>; the log gives the cluster figures.<br>") +
             kPaperTsuji;
    case FP_PROGRESSIVE_MESH:
      return QString(
                 "Builds the PCA partition tree down to single triangles, then undoes its splits in order of "
                 "increasing error down to <i>TargetClusters</i> clusters; after each merge every vertex that "
                 "touches fewer than 3 clusters (the mesh border counting as one) is removed by a half-edge "
                 "collapse onto its nearest neighbour along the cluster boundary. The result, a coarse mesh "
                 "whose vertices are the cluster corners, is added as a new layer with per-face quality = "
                 "cluster id and a colour per cluster. Collapses never break the 2-manifold, flip or turn a "
                 "face by more than <i>MaxNormalTurnDeg</i>, or remove a cluster; non-manifold parts of the "
                 "input are left as they are. The current mesh is not changed.<br>") +
             kPaperTsuji;
  }
  return "";
}

MeshFilterInterface::FilterClass FilterConeLodPlugin::getClass(QAction* a) {
  switch (ID(a)) {
    case FP_CONE_GROUPING: return MeshFilterInterface::FaceColoring;
    case FP_CULLING_COST: return MeshFilterInterface::Measure;
    case FP_PCA_PARTITION: return MeshFilterInterface::FaceColoring;
    case FP_PROGRESSIVE_MESH: return MeshFilterInterface::Remeshing;
  }
  return MeshFilterInterface::Measure;
}

int FilterConeLodPlugin::getRequirements(QAction* a) {
  return (ID(a) == FP_CONE_GROUPING || ID(a) == FP_PCA_PARTITION) ? (MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR)
                                                                   : MeshModel::MM_NONE;
}

int FilterConeLodPlugin::postCondition(QAction* a) const {
  return (ID(a) == FP_CONE_GROUPING || ID(a) == FP_PCA_PARTITION) ? (MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR)
                                                                   : MeshModel::MM_NONE;
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
    case FP_PCA_PARTITION: {
      const PcaPartitionParams d;
      par.addParam(RichInt("TargetClusters", 64, "Target clusters",
                           "Split until there are this many clusters, largest error first (0: no limit, down "
                           "to single triangles). A mesh with several components has at least one cluster "
                           "per component."));
      par.addParam(RichAbsPerc("MaxError", 0.0f, 0.0f, m.cm.bbox.Diag() * 0.1f, "Max error",
                               "Clusters whose RMS distance to their best-fit plane (the square root of the "
                               "smallest eigenvalue of their face-based covariance) is at most this length "
                               "are not split. 0: no limit."));
      par.addParam(RichInt("MinFaces", d.minFaces, "Min faces",
                           "Clusters of this many faces or fewer are not split (1: down to triangles)."));
      par.addParam(RichInt("MaxDepth", d.maxDepth, "Max depth",
                           "Clusters at this depth of the binary tree are not split (the whole mesh is depth "
                           "0). 0: no limit."));
      break;
    }
    case FP_PROGRESSIVE_MESH: {
      const ProgressiveMeshParams d;
      par.addParam(RichInt("TargetClusters", d.targetClusters, "Target clusters",
                           "Merge the finest clusters back down to this many clusters (never fewer than the "
                           "connected components)."));
      par.addParam(RichFloat("MaxNormalTurnDeg", float(d.maxNormalTurnDeg), "Max normal turn (deg)",
                             "A collapse may not turn the normal of any face by this angle or more (in (0, "
                             "180) degrees): no face ever flips."));
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
      case FP_PCA_PARTITION: return applyPcaPartition(*mm, par, cb);
      case FP_PROGRESSIVE_MESH: return applyProgressiveMesh(md, *mm, par, cb);
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

bool FilterConeLodPlugin::applyPcaPartition(MeshModel& mm, const RichParameterList& par, vcg::CallBackPos* cb) {
  PcaPartitionParams params;
  params.targetClusters = par.getInt("TargetClusters");
  params.maxErrorRms = par.getAbsPerc("MaxError");
  params.minFaces = par.getInt("MinFaces");
  params.maxDepth = par.getInt("MaxDepth");

  std::vector<size_t> faceOf;
  const IndexedMesh im = ToIndexedMesh(mm.cm, &faceOf);
  PcaTree tree;
  QElapsedTimer timer;
  timer.start();
  const Status s = BuildPcaTree(im, params, tree, FromCallback(cb));
  if (!s.ok()) return fail(QString::fromStdString(s.message) + " (the mesh was not changed)");
  const double seconds = timer.elapsed() / 1000.0;
  const std::vector<PcaItem> cut = CutByCount(tree, params.targetClusters > 0 ? params.targetClusters : tree.faceCount);
  std::vector<int> faceCluster;
  FaceClustersOfCut(tree, cut, faceCluster);
  const bool connected = GroupsAreEdgeConnected(BuildFaceAdjacency(im), faceCluster);

  mm.updateDataMask(MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR);
  WriteFaceClusters(mm.cm, faceOf, faceCluster, "conelod_pca_cluster");

  uint32_t smallest = UINT32_MAX, largest = 0;
  double maxError = 0, meanError = 0;
  for (PcaItem item : cut) {
    const uint32_t n = tree.itemFaceCount(item);
    smallest = std::min(smallest, n);
    largest = std::max(largest, n);
    if (IsFaceItem(item)) continue;
    const PcaNode& node = tree.nodes[size_t(item)];
    const double e = std::sqrt(double(node.eigenvalues[0]));
    maxError = std::max(maxError, e);
    meanError += e * node.area;
  }
  meanError = tree.nodes[0].area > 0 ? meanError / tree.nodes[0].area : 0;
  Log("PCA recursive face partition: %d faces, %d component(s), tree of %d nodes (depth %d) in %.3f s",
      int(im.faceCount()), tree.componentCount, int(tree.nodes.size()), tree.maxDepth, seconds);
  Log("pca_clusters %d", int(cut.size()));
  Log("faces_per_cluster min %u  mean %.1f  max %u", smallest, double(im.faceCount()) / cut.size(), largest);
  Log("error_rms max %.6g  area_weighted_mean %.6g  (RMS distance of a cluster to its plane)", maxError, meanError);
  Log("all_connected %d", connected ? 1 : 0);
  return true;
}

bool FilterConeLodPlugin::applyProgressiveMesh(MeshDocument& md, MeshModel& mm, const RichParameterList& par,
                                               vcg::CallBackPos* cb) {
  ProgressiveMeshParams params;
  params.targetClusters = par.getInt("TargetClusters");
  params.maxNormalTurnDeg = par.getFloat("MaxNormalTurnDeg");
  const Status valid = ValidateParams(params);
  if (!valid.ok()) return fail(QString::fromStdString(valid.message) + " (the mesh was not changed)");

  const IndexedMesh im = ToIndexedMesh(mm.cm);
  QElapsedTimer timer;
  timer.start();
  PcaTree tree;
  Status s = BuildPcaTree(im, PcaPartitionParams(), tree, SubProgress(FromCallback(cb), 0, 40));
  if (!s.ok()) return fail(QString::fromStdString(s.message) + " (the mesh was not changed)");
  ProgressiveMeshResult r;
  s = BuildProgressiveClusterMesh(im, tree, params, r, SubProgress(FromCallback(cb), 40, 90));
  if (!s.ok()) return fail(QString::fromStdString(s.message) + " (the mesh was not changed)");
  const double seconds = timer.elapsed() / 1000.0;
  HausdorffResult h;
  s = SampledHausdorff(im, r.mesh, 100000, h);
  const ManifoldReport check = CheckManifold(r.mesh);

  MeshModel* out = md.addNewMesh("", QString("%1 (%2 clusters)").arg(mm.label()).arg(r.clusters), true);
  if (!out) return fail("could not add a layer (the mesh was not changed)");
  out->updateDataMask(MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR);
  AppendIndexedMesh(out->cm, r.mesh);
  for (size_t f = 0; f < out->cm.face.size(); ++f) {
    out->cm.face[f].Q() = CMeshO::FaceType::QualityType(r.faceCluster[f]);
    out->cm.face[f].C() = GroupColor(r.faceCluster[f]);
  }
  vcg::tri::UpdateBounding<CMeshO>::Box(out->cm);
  vcg::tri::UpdateNormal<CMeshO>::PerVertexNormalizedPerFaceNormalized(out->cm);
  if (cb) cb(100, "progressive mesh: done");

  Log("Progressive cluster mesh: %d faces -> %d faces, %d vertices at %d clusters in %.3f s (new layer)",
      int(im.faceCount()), int(r.mesh.faceCount()), int(r.mesh.vertexCount()), r.clusters, seconds);
  Log("progressive_faces %d", int(r.mesh.faceCount()));
  Log("progressive_vertices %d", int(r.mesh.vertexCount()));
  Log("collapses %d  blocked_vertices %d  locked_vertices %d", int(r.collapses), int(r.blockedVertices),
      int(r.lockedVertices));
  Log("non_manifold_edges %d  non_manifold_vertices %d  misoriented_edges %d", int(check.nonManifoldEdges),
      int(check.nonManifoldVertices), int(check.misorientedEdges));
  if (s.ok())
    Log("hausdorff %.6g  hausdorff_percent %.4f  (sampled, %% of the bounding-box diagonal)", h.hausdorff,
        h.diagonal > 0 ? 100 * h.hausdorff / h.diagonal : 0.0);
  return true;
}

MESHLAB_PLUGIN_NAME_EXPORTER(FilterConeLodPlugin)
