// ConeLOD MeshLab plugin (see filter_conelod.h).
#include "filter_conelod.h"

#include <QElapsedTimer>
#include <QFileInfo>
#include <cmath>
#include <memory>
#include <exception>
#include <new>

#include "builtin_qem.h"
#include "conelod/cone_grouping.h"
#include "conelod/culling_cost.h"
#include "conelod/group_colors.h"
#include "conelod/group_integrity.h"
#include "conelod/group_qem.h"
#include "conelod/lod.h"
#include "conelod/feature_simplify.h"
#include "conelod/mesh_check.h"
#include "conelod/pixel_budget.h"
#include "conelod/simplify_bridge.h"
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
const char* const kPaperHayano =
    "M. Hayano, T. Matsuoka, K. Ueda, <i>Mesh Simplification Using Edge Operation with Feature Detection</i> "
    "(Ricoh Software Research Center).";
const char* const kPaperMizuno =
    "S. Mizuno, M. Okumoto, M. Takata, K. Joe, <i>Polygon reduction for effective 3D model rendering on "
    "different platforms</i>, IPSJ SIG Technical Report 2011-MPS-86.";

const char* const kBudgetSimplifiers[] = {"None (log the budget only)", "Feature-Preserving Edge Simplification",
                                          "Quadric Edge Collapse Decimation (MeshLab's, default parameters)"};
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

// The LOD file's simplification options (the grouping ones come from AddGroupingParameters).
// Names are those of the group-preserving QEM filter, which does each level's simplification.
void AddLodSimplificationParameters(RichParameterList& par) {
  const HierarchicalSimplificationParams d;
  par.addParam(RichFloat("LevelRatio", float(d.levelRatio), "Faces kept per level (0..1]",
                         "Each LOD level targets this fraction of the faces of the level below (level 1: of the "
                         "mesh); a level stops earlier when its groups allow no further collapse."));
  par.addParam(RichBool("LockGroupBoundaries", d.qem.lockGroupBoundaries, "Lock group boundaries",
                        "No vertex on a group boundary moves: neighbouring groups drawn at different levels "
                        "then meet without cracks, at the price of less reduction."));
  par.addParam(RichFloat("QualityThr", float(d.qem.qualityThr), "Quality threshold",
                         "Collapses creating faces of quality (2 area / longest edge^2) below this are penalised, "
                         "as in the built-in filter. 0: no penalty."));
  par.addParam(RichBool("OptimalPlacement", d.qem.optimalPlacement, "Optimal position of simplified vertices",
                        "The merged vertex goes where the quadric error is least; otherwise to the better endpoint."));
  par.addParam(RichBool("PreserveBoundary", d.qem.preserveBoundary, "Preserve Boundary of the mesh",
                        "Vertices on the mesh border never move."));
  par.addParam(RichFloat("BoundaryWeight", float(d.qem.boundaryWeight), "Boundary Preserving Weight",
                         "Weight of the quadrics that keep mesh borders (and group contours) in place."));
  par.addParam(RichBool("PreserveNormal", d.qem.preserveNormal, "Preserve Normal",
                        "Refuse collapses that turn a face's normal by more than about 78 degrees (fold-overs)."));
}

const char* const kLodViewModes[] = {"Perspective, framed from ViewDirection", "Perspective from Eye",
                                     "Orthographic along ViewDirection"};

// Independent of the current mesh: the extract reads everything from the file.
void AddLodExtractParameters(RichParameterList& par) {
  par.addParam(RichOpenFile("FileName", "out.clod", QStringList() << "ConeLOD file (*.clod)", "LOD file",
                            "The .clod file to read (Cone LOD: Export LOD File or conelod lod build); a relative "
                            "path is relative to the current directory."));
  par.addParam(RichEnum("ViewMode", 0, QStringList() << kLodViewModes[0] << kLodViewModes[1] << kLodViewModes[2],
                        "View", "Framed: a perspective eye on the line through the model's centre along "
                        "ViewDirection, CameraDistance bounding-sphere radii away. Eye: a perspective eye at Eye. "
                        "Orthographic: parallel projection along ViewDirection."));
  par.addParam(RichPoint3f("Eye", vcg::Point3f(0, 0, 0), "Eye position",
                           "Used when View is 'Perspective from Eye': the eye in model coordinates (Get / View "
                           "Pos. takes the current camera)."));
  par.addParam(RichPoint3f("ViewDirection", vcg::Point3f(0, 0, -1), "View direction",
                           "Direction from the eye into the scene (the default looks down -Z, from the +Z side)."));
  par.addParam(RichFloat("CameraDistance", 3.0f, "Camera distance",
                         "Framed view: the eye's distance from the model's centre, in bounding-sphere radii (> 1)."));
  par.addParam(RichInt("FaceBudget", 100000, "Face budget",
                       "Refine until the layer would exceed this many faces (the coarsest level is always "
                       "complete). 0: no limit, down to the input's own faces."));
  const LodView d;
  par.addParam(RichBool("CullBackFacing", d.cullBackFacing, "Refine back-facing groups last",
                        "Groups that face away from the eye entirely (one normal-cone test each) are refined only "
                        "after every other group (as conelod lod extract does unless --no-cull)."));
  par.addParam(RichBool("DropBackFacing", false, "Leave back-facing groups out",
                        "The back-facing groups are not written to the layer (conelod lod extract --drop-culled)."));
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
  typeList << FP_CONE_GROUPING << FP_CULLING_COST << FP_GROUP_QEM << FP_GROUP_INTEGRITY << FP_FEATURE_SIMPLIFY << FP_PIXEL_BUDGET << FP_PCA_PARTITION << FP_PROGRESSIVE_MESH
           << FP_LOD_EXPORT << FP_LOD_EXTRACT;
  for (FilterIDType tt : types()) actionList << new QAction(filterName(tt), this);
}

QString FilterConeLodPlugin::pluginName() const { return "FilterConeLOD"; }

QString FilterConeLodPlugin::filterName(FilterIDType filter) const {
  switch (filter) {
    case FP_CONE_GROUPING: return "Cone LOD: Normal Cone Face Grouping";
    case FP_CULLING_COST: return "Cone LOD: Cluster Culling Cost";
    case FP_GROUP_QEM: return "Cone LOD: Group-Preserving Quadric Edge Collapse";
    case FP_GROUP_INTEGRITY: return "Cone LOD: Group Integrity";
    case FP_FEATURE_SIMPLIFY: return "Cone LOD: Feature-Preserving Edge Simplification";
    case FP_PIXEL_BUDGET: return "Cone LOD: Face Budget from Screen Pixels";
    case FP_PCA_PARTITION: return "Cone LOD: PCA Recursive Face Partition";
    case FP_PROGRESSIVE_MESH: return "Cone LOD: Progressive Cluster Mesh";
    case FP_LOD_EXPORT: return "Cone LOD: Export LOD File";
    case FP_LOD_EXTRACT: return "Cone LOD: Extract View-Dependent LOD";
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
    case FP_LOD_EXPORT:
      return QString(
                 "Writes the current mesh as a streamable level-of-detail file (<tt>.clod</tt>, the paper's "
                 "sections 7-8): the faces are grouped by normal cones (the grouping parameters are those of "
                 "<i>Cone LOD: Normal Cone Face Grouping</i>), the mesh is simplified once per hierarchy level "
                 "while keeping that level's groups intact (each level keeps <i>LevelRatio</i> of the faces of "
                 "the level below, with the options of <i>Cone LOD: Group-Preserving Quadric Edge Collapse</i>), "
                 "and every group of every level is written as a node of a chunk file with its normal cone, "
                 "bounding sphere and geometry. A viewer (<tt>conelod-viewer</tt>) or <i>Cone LOD: Extract "
                 "View-Dependent LOD</i> reads only the nodes it needs. A relative <i>FileName</i> is relative "
                 "to the current directory. The mesh is not changed; on failure no file is left.<br>") +
             kPaperKamiya;
    case FP_LOD_EXTRACT:
      return QString(
                 "Reads a <tt>.clod</tt> file (<i>Cone LOD: Export LOD File</i>, <tt>conelod lod build</tt>) and "
                 "adds a new layer with the view-dependent mesh for one view: starting from the coarsest level, "
                 "groups are refined breadth-first in the order of the paper's priority f(g) = (1 - cos(angle(e, "
                 "n) + c)) / 2 (e: towards the eye, n: cone axis, c: cone half-angle), adjacent groups never more "
                 "than one level apart, until <i>FaceBudget</i> faces. The view: framed from "
                 "<i>ViewDirection</i> at <i>CameraDistance</i> bounding-sphere radii, the eye position "
                 "<i>Eye</i> (the dialog's Get / View Pos. fills in the current camera position), or "
                 "orthographic along <i>ViewDirection</i>. With <i>CullBackFacing</i>, back-facing groups are "
                 "refined last; with <i>DropBackFacing</i> they are left out of the layer. Per-face quality = LOD level of the face (0 = the "
                 "input's own faces), a distinct colour per level (those of conelod lod extract). The current mesh is not "
                 "changed.<br>") +
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
    case FP_FEATURE_SIMPLIFY: return MeshFilterInterface::Remeshing;
    case FP_PIXEL_BUDGET: return MeshFilterInterface::Remeshing;
    case FP_PCA_PARTITION: return MeshFilterInterface::FaceColoring;
    case FP_PROGRESSIVE_MESH: return MeshFilterInterface::Remeshing;
    case FP_LOD_EXPORT: return MeshFilterInterface::Remeshing;
    case FP_LOD_EXTRACT: return MeshFilterInterface::MeshCreation;
  }
  return MeshFilterInterface::Measure;
}

MeshFilterInterface::FILTER_ARITY FilterConeLodPlugin::filterArity(QAction* a) const {
  return ID(a) == FP_LOD_EXTRACT ? NONE : SINGLE_MESH;  // the extract reads a file, not a layer
}

int FilterConeLodPlugin::getRequirements(QAction* a) {
  return (ID(a) == FP_CONE_GROUPING || ID(a) == FP_PCA_PARTITION) ? (MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR)
                                                                   : MeshModel::MM_NONE;
}

int FilterConeLodPlugin::postCondition(QAction* a) const {
  switch (ID(a)) {
    case FP_CONE_GROUPING: return MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR;
    case FP_GROUP_QEM: return MeshModel::MM_GEOMETRY_AND_TOPOLOGY_CHANGE | MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR;
    case FP_FEATURE_SIMPLIFY:
      return MeshModel::MM_GEOMETRY_AND_TOPOLOGY_CHANGE | MeshModel::MM_VERTCOLOR | MeshModel::MM_VERTFLAGSELECT |
             MeshModel::MM_FACEFLAG;
    case FP_PIXEL_BUDGET: return MeshModel::MM_GEOMETRY_AND_TOPOLOGY_CHANGE;
  }
  return MeshModel::MM_NONE;
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
    case FP_LOD_EXPORT:
      par.addParam(RichSaveFile("FileName", "out.clod", "ConeLOD file (*.clod)", "LOD file",
                                "Where to write the .clod file; a relative path is relative to the current "
                                "directory (meshlabserver: where it was started)."));
      AddGroupingParameters(par);
      AddLodSimplificationParameters(par);
      break;
    case FP_LOD_EXTRACT:
      AddLodExtractParameters(par);
      break;
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

void FilterConeLodPlugin::initParameterSet(QAction* a, MeshDocument& md, RichParameterList& par) {
  if (ID(a) == FP_LOD_EXTRACT) return AddLodExtractParameters(par);
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
  errorMessage.clear();
  // Never let an exception reach MeshLab: it would lose the user's unsaved work.
  try {
    if (ID(a) == FP_LOD_EXTRACT) return applyLodExtract(md, par, cb);  // needs no current mesh
    MeshModel* mm = md.mm();
    if (!mm) return fail("no current mesh");
    switch (ID(a)) {
      case FP_CONE_GROUPING: return applyConeGrouping(*mm, par, cb);
      case FP_CULLING_COST: return applyCullingCost(*mm, par, cb);
      case FP_GROUP_QEM: return applyGroupQem(*mm, par, cb);
      case FP_GROUP_INTEGRITY: return applyGroupIntegrity(md, par);
      case FP_FEATURE_SIMPLIFY: return applyFeatureSimplify(*mm, par, cb);
      case FP_PIXEL_BUDGET: return applyPixelBudget(*mm, par, cb);
      case FP_PCA_PARTITION: return applyPcaPartition(*mm, par, cb);
      case FP_PROGRESSIVE_MESH: return applyProgressiveMesh(md, *mm, par, cb);
      case FP_LOD_EXPORT: return applyLodExport(*mm, par, cb);
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
  s = RequireValidForFaces(im);
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

  Log("Feature-preserving simplification: %d -> %d faces in %.3f s (%d collapses%s)%s", int(r.facesIn),
      int(r.facesOut), seconds, int(r.collapses),
      r.parts > 1 ? (", in " + std::to_string(r.parts) + " parts on every core").c_str() : "",
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

bool FilterConeLodPlugin::applyLodExport(MeshModel& mm, const RichParameterList& par, vcg::CallBackPos* cb) {
  const QString path = par.getSaveFileName("FileName");
  if (path.trimmed().isEmpty()) return fail("FileName is empty: give the .clod file to write");
  LodBuildParams params;
  params.grouping = ReadGroupingParameters(par);
  params.simplification.levelRatio = par.getFloat("LevelRatio");
  GroupQemParams& q = params.simplification.qem;
  q.lockGroupBoundaries = par.getBool("LockGroupBoundaries");
  q.qualityThr = par.getFloat("QualityThr");
  q.optimalPlacement = par.getBool("OptimalPlacement");
  q.preserveBoundary = par.getBool("PreserveBoundary");
  q.boundaryWeight = par.getFloat("BoundaryWeight");
  q.preserveNormal = par.getBool("PreserveNormal");
  if (!(params.simplification.levelRatio > 0 && params.simplification.levelRatio <= 1))
    return fail("LevelRatio must be in (0, 1]");

  const IndexedMesh im = ToIndexedMesh(mm.cm);
  Status s = ValidateParams(params.grouping);
  if (!s.ok()) return fail(QString::fromStdString(s.message));
  s = RequireValidForFaces(im);
  if (!s.ok()) return fail(QString::fromStdString(s.message) + " (no file was written)");
  LodBuildStats stats;
  s = BuildLodFile(im, params, path.toStdString(), &stats, FromCallback(cb));
  if (!s.ok()) return fail(QString("%1: %2 (no file was written)").arg(path, QString::fromStdString(s.message)));

  Log("LOD file %s: %d faces, %d levels, %d nodes, %.1f KiB in %.3f s (grouping %.3f s, simplification %.3f s, "
      "writing %.3f s)",
      qUtf8Printable(path), int(stats.inputFaces), stats.levels, int(stats.nodes), stats.fileBytes / 1024.0,
      stats.seconds, stats.groupingSeconds, stats.simplifySeconds, stats.writeSeconds);
  for (size_t l = 0; l < stats.levelFaces.size(); ++l)
    Log("lod level %d: faces %d nodes %d", int(l), int(stats.levelFaces[l]),
        l < stats.levelNodes.size() ? int(stats.levelNodes[l]) : 0);
  Log("lod_levels %d", stats.levels);
  Log("lod_nodes %d", int(stats.nodes));
  Log("lod_file_bytes %lld", (long long)stats.fileBytes);
  return true;
}

bool FilterConeLodPlugin::applyLodExtract(MeshDocument& md, const RichParameterList& par, vcg::CallBackPos* cb) {
  const QString path = par.getOpenFileName("FileName");
  const int mode = par.getEnum("ViewMode");
  if (mode < 0 || mode > 2) return fail("ViewMode must be 0, 1 or 2");
  const int budget = par.getInt("FaceBudget");
  if (budget < 0) return fail("FaceBudget must be >= 0 (0: no limit)");
  const float distance = par.getFloat("CameraDistance");
  vcg::Point3d dir = vcg::Point3d::Construct(par.getPoint3f("ViewDirection"));
  if (mode != 1 && !(dir.Norm() > 0 && std::isfinite(dir.Norm())))
    return fail("ViewDirection must be a non-zero vector");
  if (mode == 0 && !(distance > 1)) return fail("CameraDistance must be > 1 (bounding-sphere radii)");
  const vcg::Point3d eyeParam = vcg::Point3d::Construct(par.getPoint3f("Eye"));
  if (mode == 1 && !(std::isfinite(eyeParam.Norm()))) return fail("Eye must be finite");
  const bool cull = par.getBool("CullBackFacing"), drop = par.getBool("DropBackFacing");

  QElapsedTimer timer;
  timer.start();
  if (cb) cb(0, "reading the LOD file");
  std::unique_ptr<LodReader> reader;
  Status s = LodReader::Open(path.toStdString(), reader);
  if (!s.ok()) return fail(QString("%1: %2 (no layer was added)").arg(path, QString::fromStdString(s.message)));
  const LodFileInfo& info = reader->info();

  LodView view;
  dir.Normalize();
  const vcg::Point3d centre = vcg::Point3d::Construct(info.box.Center());
  const double radius = 0.5 * double(info.box.Diag());
  view.orthographic = mode == 2;
  view.viewDir = dir;
  view.eye = mode == 1 ? eyeParam : centre - dir * (double(distance) * radius);
  view.faceBudget = budget == 0 ? size_t(-1) : size_t(budget);
  view.cullBackFacing = cull;
  LodCut cut;
  if (cb) cb(10, "refining");
  s = RefineLod(*reader, view, cut);
  if (!s.ok()) return fail(QString("%1: %2 (no layer was added)").arg(path, QString::fromStdString(s.message)));
  if (cb) cb(80, "extracting the cut");
  IndexedMesh mesh;
  std::vector<int> faceLevel;
  s = ExtractCutMesh(*reader, cut, !drop, mesh, &faceLevel);
  if (!s.ok()) return fail(QString("%1: %2 (no layer was added)").arg(path, QString::fromStdString(s.message)));
  const double seconds = timer.elapsed() / 1000.0;

  MeshModel* out = md.addNewMesh("", QString("%1 (LOD, %2 faces)").arg(QFileInfo(path).completeBaseName()).arg(mesh.faceCount()), true);
  if (!out) return fail("could not add a layer");
  out->updateDataMask(MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR);
  AppendIndexedMesh(out->cm, mesh);
  std::vector<size_t> facesPerLevel(size_t(std::max(info.levels, 1)), 0);
  for (size_t f = 0; f < out->cm.face.size(); ++f) {
    const int level = faceLevel[f];
    out->cm.face[f].Q() = CMeshO::FaceType::QualityType(level);
    out->cm.face[f].C() = GroupColor(level);  // as conelod lod extract colours its output
    if (level >= 0 && size_t(level) < facesPerLevel.size()) ++facesPerLevel[size_t(level)];
  }
  vcg::tri::UpdateBounding<CMeshO>::Box(out->cm);
  vcg::tri::UpdateNormal<CMeshO>::PerVertexNormalizedPerFaceNormalized(out->cm);
  if (cb) cb(100, "view-dependent LOD: done");

  const vcg::Point3d& e = view.eye;
  Log("View-dependent LOD of %s (%s, budget %s%s%s): %d faces, %d vertices from %d nodes in %.3f s (new layer)",
      qUtf8Printable(path), kLodViewModes[mode], budget == 0 ? "none" : qUtf8Printable(QString::number(budget)),
      cull ? ", back-facing groups refined last" : "", drop ? ", back-facing groups left out" : "",
      int(mesh.faceCount()), int(mesh.vertexCount()),
      int(cut.nodes.size()), seconds);
  if (mode == 2)
    Log("orthographic view direction (%g, %g, %g)", dir[0], dir[1], dir[2]);
  else
    Log("eye (%g, %g, %g)", e[0], e[1], e[2]);
  for (size_t l = 0; l < facesPerLevel.size(); ++l)
    if (facesPerLevel[l]) Log("faces at level %d: %d", int(l), int(facesPerLevel[l]));
  Log("lod_faces %d", int(mesh.faceCount()));
  Log("lod_cut_faces %d", int(cut.faces));
  Log("lod_groups_culled %d", int(cut.groupsCulled));
  Log("lod_refinements %d", int(cut.refinements));
  Log("lod_max_level_difference %d", cut.maxLevelDifference);
  Log("lod_resident_bytes %lld (the file: %lld)", (long long)reader->residentBytes(), (long long)info.fileBytes);
  return true;
}

MESHLAB_PLUGIN_NAME_EXPORTER(FilterConeLodPlugin)
