// ConeLOD CLI — `conelod partition` and `conelod progressive`: the recursive PCA face partition
// and its progressive cluster mesh (Tsuji, Zha, Kurazume, Hasegawa).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "cli_common.h"
#include "commands.h"
#include "conelod/grouping/cluster_shape.h"
#include "conelod/mesh/manifold_check.h"
#include "conelod/pca/pca_partition.h"
#include "conelod/pca/progressive_cluster_mesh.h"
#include "conelod/mesh/sampled_distance.h"
#include "conelod/simplify_bridge.h"

namespace conelod {
namespace cli {

const char* kPartitionUsage =
    "conelod partition IN.ply [--clusters K] [-o OUT.ply] [--max-error E] [--min-faces N] [--max-depth D]\n"
    "                  [--full] [--verify] [--json]\n"
    "  Recursive PCA face partition (Tsuji-Zha-Kurazume-Hasegawa): a binary tree of edge-connected\n"
    "  face clusters, each split by the plane through its area centroid across its face-based\n"
    "  principal axis; the cluster of largest error (lambda_min) is split first.\n"
    "  --clusters K   stop at K clusters [100]; 0: no limit (down to single triangles)\n"
    "  --max-error E  do not split a cluster whose RMS distance to its plane is <= E (model units) [0: off]\n"
    "  --min-faces N  do not split a cluster of N faces or fewer [1]\n"
    "  --max-depth D  do not split a cluster at depth D (root = 0) [0: off]\n"
    "  --full         build the whole tree down to single triangles, then cut it at K clusters\n"
    "  --verify       check every node of the tree (face ranges, edge-connectivity): every cut is sound\n"
    "  -o OUT.ply     per-face quality = cluster id, a colour per cluster, attribute conelod_pca_cluster\n";

const char* kProgressiveUsage =
    "conelod progressive IN.ply --clusters K -o OUT.ply [--max-normal-turn DEG] [--samples N] [--json]\n"
    "  The progressive cluster mesh (Tsuji et al. §4): builds the full PCA tree, undoes its splits in\n"
    "  order of increasing error down to K clusters, and removes every vertex that touches fewer than\n"
    "  3 clusters by a half-edge collapse onto its nearest neighbour along the cluster boundary.\n"
    "  Writes the coarse mesh (per-face quality and colour = cluster) and reports its validity and\n"
    "  its sampled Hausdorff distance to the input. A file's vertex colour, normals and texture\n"
    "  coordinates are kept: each coarse vertex takes the attribute quadric's value at its position\n"
    "  of the vertices it took over (normals normalised; a texture seam's vertex keeps its own).\n"
    "  --max-normal-turn DEG  a collapse may turn a face's normal by less than this [90]\n"
    "  --samples N            face samples per direction for the distance [200000]; 0: skip it\n";

const char* kClusterShapeUsage =
    "conelod cluster-shape IN.ply [--json]\n"
    "  Shape of the clusters given by the per-face quality of IN.ply (as `partition -o` or `group -o`\n"
    "  write it): boundary length against the sqrt(pi A K) that K round clusters would need (1 =\n"
    "  round, larger = ragged), area-weighted compactness 4 pi area / perimeter^2, edge-connectivity.\n";

namespace {

const char* kClusterAttribute = "conelod_pca_cluster";

double ItemErrorRms(const PcaTree& tree, PcaItem item) {
  return IsFaceItem(item) ? 0.0 : std::sqrt(double(tree.nodes[size_t(item)].eigenvalues[0]));
}

}  // namespace

int CmdPartition(int argc, char** argv) {
  Args a(argc, argv, {"--clusters", "-o", "--max-error", "--min-faces", "--max-depth"},
         {"--full", "--verify", "--json"});
  PcaPartitionParams params;
  const int clusters = a.integer("--clusters", 100);
  params.maxErrorRms = a.num("--max-error", params.maxErrorRms);
  params.minFaces = a.integer("--min-faces", params.minFaces);
  params.maxDepth = a.integer("--max-depth", params.maxDepth);
  const bool full = a.has("--full");
  if (!a.ok()) return Fail(kUsage, a.error() + "\n" + kPartitionUsage);
  if (a.positional().size() != 1) return Fail(kUsage, std::string("expected one input mesh\n") + kPartitionUsage);
  if (clusters < 0) return Fail(kUsage, "--clusters must be >= 0 (0: no limit)");
  if (full && (params.maxErrorRms > 0 || params.minFaces > 1 || params.maxDepth > 0))
    return Fail(kUsage, "--full builds the whole tree: it takes no stop criterion");
  params.targetClusters = full ? 0 : clusters;
  const Status valid = ValidateParams(params);
  if (!valid.ok()) return Fail(kUsage, valid.message);

  CMesh mesh;
  IndexedMesh im;
  std::vector<size_t> faceOf;
  std::string err = LoadInput(a.positional()[0], mesh, im, faceOf);
  if (!err.empty()) return FailLoad(err);

  PcaTree tree;
  Timer timer;
  const Status s = BuildPcaTree(im, params, tree);
  const double seconds = timer.seconds();
  if (!s.ok()) return Fail(kBadInput, a.positional()[0] + ": " + s.message);
  const std::vector<PcaItem> cut = CutByCount(tree, clusters > 0 ? clusters : tree.faceCount);
  std::vector<int> faceCluster;
  FaceClustersOfCut(tree, cut, faceCluster);
  const FaceAdjacency adj = BuildFaceAdjacency(im);
  const bool connected = GroupsAreEdgeConnected(adj, faceCluster);
  std::string verify;
  if (a.has("--verify")) verify = VerifyPcaTree(im, adj, tree);

  double maxError = 0, meanError = 0, totalArea = 0;
  size_t largest = 0;
  for (PcaItem item : cut) {
    maxError = std::max(maxError, ItemErrorRms(tree, item));
    largest = std::max(largest, size_t(tree.itemFaceCount(item)));
  }
  for (PcaItem item : cut) {  // area-weighted mean over clusters (single faces: error 0)
    if (IsFaceItem(item)) continue;
    meanError += ItemErrorRms(tree, item) * tree.nodes[size_t(item)].area;
  }
  totalArea = tree.nodes[0].area;
  meanError = totalArea > 0 ? meanError / totalArea : 0;

  if (a.has("-o")) {
    WriteFaceClusters(mesh, faceOf, faceCluster, kClusterAttribute);
    err = SavePly(mesh, a.str("-o"));
    if (!err.empty()) return Fail(kIoError, err);
  }
  if (a.has("--json")) {
    Json j;
    j.BeginObject()
        .field("input", a.positional()[0])
        .field("faces", im.faceCount())
        .field("components", tree.componentCount)
        .field("clusters", cut.size())
        .field("seconds", seconds)
        .field("all_connected", connected)
        .field("tree_nodes", tree.nodes.size())
        .field("tree_depth", tree.maxDepth)
        .field("tree_bytes", tree.memoryBytes())
        .field("full_tree", full)
        .field("max_error_rms", maxError)
        .field("mean_error_rms", meanError)
        .field("largest_cluster_faces", largest);
    if (a.has("--verify")) j.field("tree_valid", verify.empty());
    if (a.has("-o")) j.field("output", a.str("-o"));
    j.EndObject();
    std::printf("%s\n", j.str().c_str());
  } else {
    std::printf("%s: %zu faces, %d component(s); PCA tree of %zu nodes, depth %d, built in %.3f s%s\n",
                a.positional()[0].c_str(), im.faceCount(), tree.componentCount, tree.nodes.size(), tree.maxDepth,
                seconds, full ? " (full tree)" : "");
    std::printf("%zu clusters (largest %zu faces), every one edge-connected: %s\n", cut.size(), largest,
                connected ? "yes" : "NO");
    std::printf("cluster error sqrt(lambda_min): max %.6g, area-weighted mean %.6g\n", maxError, meanError);
    if (a.has("--verify")) std::printf("tree check: %s\n", verify.empty() ? "every node sound" : verify.c_str());
    if (a.has("-o")) std::printf("wrote %s (quality and colour = cluster)\n", a.str("-o").c_str());
  }
  if (!verify.empty()) return Fail(kBadInput, "tree check failed: " + verify);
  return connected ? kOk : Fail(kBadInput, "a cluster is not edge-connected");
}

int CmdProgressive(int argc, char** argv) {
  Args a(argc, argv, {"--clusters", "-o", "--max-normal-turn", "--samples"}, {"--json"});
  ProgressiveMeshParams params;
  params.targetClusters = a.integer("--clusters", params.targetClusters);
  params.maxNormalTurnDeg = a.num("--max-normal-turn", params.maxNormalTurnDeg);
  const int samples = a.integer("--samples", 200000);
  if (!a.ok()) return Fail(kUsage, a.error() + "\n" + kProgressiveUsage);
  if (a.positional().size() != 1 || !a.has("-o"))
    return Fail(kUsage, std::string("expected one input mesh and -o OUT.ply\n") + kProgressiveUsage);
  const Status valid = ValidateParams(params);
  if (!valid.ok()) return Fail(kUsage, valid.message);
  if (samples < 0 || samples > kMaxFaceSamples)
    return Fail(kUsage, "--samples must be from 0 to " + std::to_string(kMaxFaceSamples));

  CMesh mesh;
  IndexedMesh im;
  std::vector<size_t> faceOf;
  int loadMask = 0;
  std::string err = LoadInput(a.positional()[0], mesh, im, faceOf, &loadMask);
  if (!err.empty()) return FailLoad(err);

  Timer timer;
  double treeSeconds = 0;
  ProgressiveMeshResult r;
  Status s = BuildProgressiveClusterMeshOf(im, params, r, Progress(), &treeSeconds);
  if (!s.ok()) return Fail(kBadInput, a.positional()[0] + ": " + s.message);
  const double seconds = timer.seconds();

  const ManifoldReport in = CheckManifold(im), outCheck = CheckManifold(r.mesh);
  HausdorffResult h;
  size_t against = 0;
  if (samples > 0) {
    s = SampledHausdorff(im, r.mesh, samples, h);
    if (!s.ok()) return Fail(kBadInput, "distance: " + s.message);
    against = CountFacesAgainstSurface(r.mesh, im);
  }

  CMesh coarse;
  AppendIndexedMesh(coarse, r.mesh);
  for (size_t f = 0; f < coarse.face.size(); ++f) {
    coarse.face[f].Q() = float(r.faceCluster[f]);
    coarse.face[f].C() = GroupColor(r.faceCluster[f]);
  }
  // Issue 26: the file's colour, normals and texture coordinates. The collapses are half-edge
  // collapses (vertices kept in place), so each coarse vertex takes, as in feature-simplify, the
  // extended quadric's value at its position of the input vertices whose collapses ended in it
  // (normals normalised; a texture seam's vertex keeps its own coordinates).
  const int attributeMask = AttributeMask(loadMask);
  if (attributeMask) {
    FeatureSimplifyResult carried;  // what the means read: the survivors and the kept vertices
    carried.survivor = r.survivor;
    carried.inputVertex = r.vertexOrigin;
    if (loadMask & vcg::tri::io::Mask::IOM_VERTCOLOR) MeanSurvivorColours(mesh, carried);
    MeanSurvivorNormalsAndTexCoords(
        mesh, carried, (loadMask & vcg::tri::io::Mask::IOM_VERTNORMAL) != 0,
        (loadMask & (vcg::tri::io::Mask::IOM_VERTTEXCOORD | vcg::tri::io::Mask::IOM_WEDGTEXCOORD)) != 0);
    std::vector<const CVertex*> vertexOfIndex;
    for (const auto& v : mesh.vert)
      if (!v.IsD()) vertexOfIndex.push_back(&v);
    for (size_t o = 0; o < coarse.vert.size(); ++o) {
      const CVertex& in = *vertexOfIndex[r.vertexOrigin[o]];
      coarse.vert[o].C() = in.cC();
      coarse.vert[o].N() = in.cN();
      coarse.vert[o].T() = in.cT();
    }
    coarse.textures = mesh.textures;
  }
  err = SavePly(coarse, a.str("-o"), attributeMask);
  if (!err.empty()) return Fail(kIoError, err);

  const double pct = h.diagonal > 0 ? 100 * h.hausdorff / h.diagonal : 0;
  if (a.has("--json")) {
    Json j;
    j.BeginObject()
        .field("input", a.positional()[0])
        .field("input_faces", im.faceCount())
        .field("clusters", r.clusters)
        .field("faces", r.mesh.faceCount())
        .field("vertices", r.mesh.vertexCount())
        .field("seconds", seconds)
        .field("tree_seconds", treeSeconds)
        .field("collapses", r.collapses)
        .field("blocked_vertices", r.blockedVertices)
        .field("locked_vertices", r.lockedVertices)
        .field("input_manifold", in.valid())
        .field("manifold", outCheck.valid())
        .field("non_manifold_edges", outCheck.nonManifoldEdges)
        .field("non_manifold_vertices", outCheck.nonManifoldVertices)
        .field("misoriented_edges", outCheck.misorientedEdges)
        .field("degenerate_faces", outCheck.degenerateFaces)
        .field("border_edges", outCheck.borderEdges)
        .field("input_border_edges", in.borderEdges);
    if (samples > 0) {
      j.field("hausdorff", h.hausdorff)
          .field("hausdorff_percent", pct)
          .field("diagonal", h.diagonal)
          .field("mean_distance_to_input", h.ba.mean)
          .field("mean_distance_from_input", h.ab.mean)
          .field("rms_distance_from_input", h.ab.rms)
          .field("faces_against_surface", against);
    }
    j.field("output", a.str("-o"));
    j.EndObject();
    std::printf("%s\n", j.str().c_str());
  } else {
    std::printf("%s: %zu faces -> %zu faces, %zu vertices at %d clusters in %.3f s (tree %.3f s)\n",
                a.positional()[0].c_str(), im.faceCount(), r.mesh.faceCount(), r.mesh.vertexCount(), r.clusters,
                seconds, treeSeconds);
    std::printf("collapses %zu; vertices left touching < 3 clusters: %zu (no allowed collapse); locked: %zu\n",
                r.collapses, r.blockedVertices, r.lockedVertices);
    std::printf("2-manifold: %s (non-manifold edges %zu, vertices %zu, misoriented edges %zu); input: %s\n",
                outCheck.valid() ? "yes" : "NO", outCheck.nonManifoldEdges, outCheck.nonManifoldVertices,
                outCheck.misorientedEdges, in.valid() ? "yes" : "no");
    if (samples > 0)
      std::printf(
          "Hausdorff distance %.6g (%.3f%% of the diagonal); mean from input %.6g, to input %.6g; "
          "faces against the surface %zu\n",
          h.hausdorff, pct, h.ab.mean, h.ba.mean, against);
    std::printf("wrote %s\n", a.str("-o").c_str());
  }
  return kOk;
}

int CmdClusterShape(int argc, char** argv) {
  Args a(argc, argv, {}, {"--json"});
  if (!a.ok()) return Fail(kUsage, a.error() + "\n" + kClusterShapeUsage);
  if (a.positional().size() != 1) return Fail(kUsage, std::string("expected one input mesh\n") + kClusterShapeUsage);
  CMesh mesh;
  int mask = 0;
  std::string err = LoadPly(mesh, a.positional()[0], &mask);
  if (!err.empty()) return FailLoad(err);
  if (!(mask & vcg::tri::io::Mask::IOM_FACEQUALITY))
    return Fail(kBadInput, a.positional()[0] + ": no per-face quality to read the clusters from");
  std::vector<size_t> faceOf;
  const IndexedMesh im = ToIndexedMesh(mesh, &faceOf);
  // Cluster ids are labels: renumbered 0..K-1 in order of appearance, so an id of 2e9 costs no more
  // than an id of 2. -1 marks a face in no cluster; anything else that is no whole number >= 0 is refused.
  std::vector<int> faceCluster(im.faceCount());
  std::map<float, int> idOf;
  for (size_t i = 0; i < faceOf.size(); ++i) {
    const float q = mesh.face[faceOf[i]].Q();
    if (q == -1) {
      faceCluster[i] = -1;
      continue;
    }
    if (!(q >= 0 && q == std::floor(q) && q < 2147483648.0f))
      return Fail(kBadInput, a.positional()[0] + ": face " + std::to_string(faceOf[i]) + " has quality " +
                                 std::to_string(q) + ": cluster ids must be whole numbers >= 0 (-1: no cluster)");
    faceCluster[i] = idOf.emplace(q, int(idOf.size())).first->second;
  }
  const ClusterShape shape = MeasureClusterShape(im, faceCluster);
  const bool connected = GroupsAreEdgeConnected(BuildFaceAdjacency(im), faceCluster);
  if (a.has("--json")) {
    Json j;
    j.BeginObject()
        .field("input", a.positional()[0])
        .field("faces", im.faceCount())
        .field("clusters", shape.clusters)
        .field("boundary_length", shape.boundaryLength)
        .field("boundary_ratio", shape.boundaryRatio)
        .field("mean_compactness", shape.meanCompactness)
        .field("all_connected", connected)
        .EndObject();
    std::printf("%s\n", j.str().c_str());
  } else {
    std::printf("%s: %zu faces in %d clusters (all edge-connected: %s)\n", a.positional()[0].c_str(), im.faceCount(),
                shape.clusters, connected ? "yes" : "NO");
    std::printf("boundary length %.6g = %.3f x that of round clusters; area-weighted compactness %.3f\n",
                shape.boundaryLength, shape.boundaryRatio, shape.meanCompactness);
  }
  return kOk;
}

}  // namespace cli
}  // namespace conelod
