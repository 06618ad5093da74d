// ConeLOD CLI — `conelod group` and `conelod cull-cost`: normal-cone face grouping (Kamiya, Suzuki, Kawachi) and
// the culling-cost experiment of the paper's §5.
#include <algorithm>
#include <atomic>
#include <cstdio>

#include "cli_common.h"
#include "commands.h"
#include "conelod/mesh/weld.h"
#include "conelod/grouping/cone_grouping.h"
#include "conelod/grouping/group_colors.h"
#include "conelod/mesh/mesh_check.h"
#include "conelod/grouping/culling_cost.h"
#include "conelod/parallel.h"
#include "conelod/pca/pca_partition.h"

namespace conelod {
namespace cli {
namespace {

void WriteParams(Json& j, const ConeGroupingParams& p) {
  j.key("params")
      .BeginObject()
      .field("cone_weight", p.coneWeight)
      .field("shape_weight", p.shapeWeight)
      .field("size_weight", p.sizeWeight)
      .field("threshold_deg", p.coneThresholdDeg)
      .field("growth", p.thresholdGrowth)
      .field("max_levels", p.maxLevels)
      .field("min_top_groups", p.minTopGroups)
      .field("strict_greedy", p.strictGreedy)
      .EndObject();
}

}  // namespace

const char* kGroupUsage =
    "conelod group IN.ply [-o OUT.ply] [--level L] [grouping options] [--threads N] [--json]\n"
    "  Groups faces by normal cones into a hierarchy (Kamiya-Suzuki-Kawachi). Writes OUT.ply with\n"
    "  per-face quality = group id at level L (default 1) and a distinct colour per group.\n"
    "grouping options (defaults in brackets):\n"
    "  --cone-weight K    k_c [1]     --shape-weight K  k_s [0.5]    --size-weight K  k_n [0.5]\n"
    "  --threshold DEG    level-1 limit on the cone half-angle [15]; >= 180: no limit\n"
    "  --growth F         the limit grows by this factor per level [1.6]\n"
    "  --max-levels N     [8]         --min-top-groups N  stop at this many groups [8]\n"
    "  --strict-greedy    merge the best pair of the whole level first at every step (the paper's\n"
    "                     order, about 2x slower); default: level 1 merges local maxima first\n"
    "  --threads N        threads [0: one per core]; the output is the same for every N\n";

const char* kCullCostUsage =
    "conelod cull-cost IN.ply [--views N] [--camera-distance R] [grouping options | --pca K [--pca-levels L]]\n"
    "                  [--json]\n"
    "  Builds the hierarchy (options as for `group`) and measures the cost of hierarchical\n"
    "  back-face culling over N view directions uniform on the sphere [1000]: orthographic, or a\n"
    "  perspective eye at R bounding-sphere radii (R > 1) from the model's centre.\n"
    "  --pca K         groups = the K clusters of the recursive PCA partition (`conelod partition`),\n"
    "                  each with its exact normal cone, instead of normal-cone grouping\n"
    "  --pca-levels L  L nested levels: K clusters, then K/4, K/16, ... [1]\n";

int CmdGroup(int argc, char** argv) {
  Args a(argc, argv, With(kGroupingOptions, {"-o", "--level", "--threads"}), {"--json", "--strict-greedy"});
  ConeGroupingParams params = ReadGroupingParams(a);
  const int displayLevel = a.integer("--level", 1);
  if (!a.ok()) return Fail(kUsage, a.error() + "\n" + kGroupUsage);
  const std::string threadsError = ReadThreadsOption(a, 0, params.threads);
  if (!threadsError.empty()) return Fail(kUsage, threadsError + "\n" + kGroupUsage);
  const unsigned threads = params.threads > 0 ? unsigned(params.threads) : CoreCount();
  if (a.positional().size() != 1) return Fail(kUsage, std::string("expected one input mesh\n") + kGroupUsage);
  const bool json = a.has("--json");

  // The file's data as read; the vcg mesh only for what vcglib's exporter must write (texture
  // coordinates): everything else is written straight from the data (SavePlyFaceValues, the same
  // bytes), without the vcg mesh's copy of the input.
  PlyMesh ply;
  int loadMask = 0;
  std::string err = LoadPlyData(a.positional()[0], ply, &loadMask);
  if (!err.empty()) return FailLoad(err);
  const int attributeMask = AttributeMask(loadMask);
  const bool direct = PlyFaceValuesWritable(ply, attributeMask);
  CMesh mesh;
  IndexedMesh im;
  if (direct) {
    im.positions.resize(ply.positions.size());
    ParallelChunks(ply.positions.size(), threads, size_t(1) << 16, [&](size_t begin, size_t end, unsigned) {
      for (size_t v = begin; v < end; ++v)
        im.positions[v] = vcg::Point3f(ply.positions[v][0], ply.positions[v][1], ply.positions[v][2]);
    });
    im.faces = ply.triangles;  // the file's faces, in its order: the groups are per file face
  } else {
    MeshFromPlyData(ply, loadMask & vcg::tri::io::Mask::IOM_WEDGTEXCOORD, mesh);
    ply = PlyMesh();
    std::vector<size_t> faceOf;  // the identity: a mesh as read has no deleted face
    im = ToIndexedMesh(mesh, &faceOf);
  }
  // A seam the file repeats is no border to the groups (faces keep their order).
  WeldByPositionInPlace(im, nullptr, nullptr, threads);

  // BuildConeHierarchy's checks, before the adjacency reads the faces' indices.
  Status s = ValidateParams(params);
  if (s.ok()) s = RequireValidForFaces(im);
  if (!s.ok()) return Fail(kBadInput, a.positional()[0] + ": " + s.message);
  // One face adjacency for the build and the checks after it (timed with the build, which would
  // make it otherwise).
  GroupHierarchy h;
  Timer timer;
  const FaceAdjacency adj = BuildFaceAdjacency(im, threads);
  s = BuildConeHierarchy(im, params, h, Progress(), &adj);
  const double seconds = timer.seconds();
  if (!s.ok()) return Fail(kBadInput, a.positional()[0] + ": " + s.message);
  if (displayLevel < 1 || displayLevel > h.levelCount())
    return Fail(kUsage, "--level must be between 1 and " + std::to_string(h.levelCount()) + " (levels built)");

  // The output file and the levels' connectivity checks are independent: on two threads.
  std::vector<char> connected;
  std::atomic<int> nextTask(a.has("-o") ? -1 : 0);
  RunThreads(std::min(threads, 2u), [&](unsigned) {
    for (int task; (task = nextTask.fetch_add(1)) < 1;) {
      if (task < 0) {
        const GroupLevel& shown = h.level(displayLevel);
        if (direct) {  // per face: its group's colour, and its group id as quality (WriteGroupResults)
          std::vector<vcg::Color4b> colour(shown.groups.size());
          std::vector<float> quality(shown.groups.size());
          for (size_t g = 0; g < shown.groups.size(); ++g) {
            colour[g] = GroupColor(int(g));
            quality[g] = float(g);
          }
          err = SavePlyFaceValues(ply, attributeMask, shown.faceGroup, colour, quality, a.str("-o"));
        } else {
          std::vector<size_t> faceOf(im.faces.size());
          for (size_t f = 0; f < faceOf.size(); ++f) faceOf[f] = f;
          WriteGroupResults(mesh, faceOf, h, displayLevel);
          err = SavePly(mesh, a.str("-o"), attributeMask);  // the mesh as read, with its groups
        }
      } else {
        connected = LevelsAreEdgeConnected(adj, h);
      }
    }
  });
  if (!err.empty()) return Fail(kIoError, err);

  if (json) {
    Json j;
    j.BeginObject().field("input", a.positional()[0]).field("faces", im.faceCount()).field("seconds", seconds);
    j.field("faces_per_second", seconds > 0 ? double(im.faceCount()) / seconds : 0.0).field("threads", int(threads));
    WriteParams(j, params);
    j.key("levels").BeginArray();
    for (int l = 1; l <= h.levelCount(); ++l) {
      const GroupLevel& lv = h.level(l);
      j.BeginObject()
          .field("level", l)
          .field("groups", lv.groups.size())
          .field("max_cone_deg", lv.maxConeDeg())
          .field("mean_cone_deg", lv.meanConeDeg())
          .field("threshold_deg", lv.thresholdDeg)
          .field("uncullable_groups", lv.uncullableGroups())
          .field("all_connected", connected[size_t(l - 1)] != 0)
          .EndObject();
    }
    j.endArray();
    if (a.has("-o")) j.field("output", a.str("-o")).field("display_level", displayLevel);
    j.EndObject();
    std::printf("%s\n", j.str().c_str());
  } else {
    std::printf("%s: %zu faces, %d levels in %.3f s (%.0f faces/s)\n", a.positional()[0].c_str(), im.faceCount(),
                h.levelCount(), seconds, seconds > 0 ? double(im.faceCount()) / seconds : 0.0);
    std::printf("%5s %10s %8s %13s %14s %10s %9s\n", "level", "limit_deg", "groups", "max_cone_deg", "mean_cone_deg",
                "uncullable", "connected");
    for (int l = 1; l <= h.levelCount(); ++l) {
      const GroupLevel& lv = h.level(l);
      std::printf("%5d %10.1f %8zu %13.2f %14.2f %10d %9s\n", l, lv.thresholdDeg, lv.groups.size(), lv.maxConeDeg(),
                  lv.meanConeDeg(), lv.uncullableGroups(), connected[size_t(l - 1)] ? "yes" : "NO");
    }
    if (a.has("-o"))
      std::printf("wrote %s (quality and colour = group at level %d)\n", a.str("-o").c_str(), displayLevel);
  }
  return kOk;
}

int CmdCullCost(int argc, char** argv) {
  Args a(argc, argv, With(kGroupingOptions, {"--views", "--camera-distance", "--pca", "--pca-levels"}),
         {"--json", "--strict-greedy"});
  ConeGroupingParams params = ReadGroupingParams(a);
  CullingCostParams cp;
  cp.views = a.integer("--views", cp.views);
  cp.cameraDistance = a.num("--camera-distance", cp.cameraDistance);
  const bool pca = a.has("--pca");
  const int pcaClusters = a.integer("--pca", 0), pcaLevels = a.integer("--pca-levels", 1);
  if (!a.ok()) return Fail(kUsage, a.error() + "\n" + kCullCostUsage);
  if (a.positional().size() != 1) return Fail(kUsage, std::string("expected one input mesh\n") + kCullCostUsage);
  if (pca) {
    for (const auto& o : kGroupingOptions)
      if (a.has(o)) return Fail(kUsage, o + " is a normal-cone grouping option: it does not go with --pca");
    if (a.has("--strict-greedy"))
      return Fail(kUsage, "--strict-greedy is a normal-cone grouping option: it does not go with --pca");
    if (pcaClusters < 1) return Fail(kUsage, "--pca needs a cluster count >= 1");
    if (pcaLevels < 1 || pcaLevels > 16) return Fail(kUsage, "--pca-levels must be between 1 and 16");
  } else if (a.has("--pca-levels")) {
    return Fail(kUsage, "--pca-levels goes with --pca");
  }

  CMesh mesh;
  IndexedMesh im;
  std::vector<size_t> faceOf;
  const std::string err = LoadInput(a.positional()[0], mesh, im, faceOf);
  if (!err.empty()) return FailLoad(err);
  im = WeldByPosition(im).mesh;  // as `conelod group`: the groups see no false border

  GroupHierarchy h;
  Timer timer;
  Status s;
  std::vector<int> pcaCounts;
  if (pca) {
    // The PCA tree, best-first to K clusters; the levels are nested cuts of it.
    PcaPartitionParams pp;
    pp.targetClusters = pcaClusters;
    PcaTree tree;
    s = BuildPcaTree(im, pp, tree);
    if (s.ok()) {
      for (int l = 0, k = pcaClusters; l < pcaLevels && k >= 1; ++l, k /= 4)
        if (pcaCounts.empty() || k < pcaCounts.back()) pcaCounts.push_back(k);
      s = PcaGroupHierarchy(im, tree, pcaCounts, h);
    }
  } else {
    s = BuildConeHierarchy(im, params, h);
  }
  const double groupSeconds = timer.seconds();
  if (!s.ok()) return Fail(kBadInput, a.positional()[0] + ": " + s.message);
  CullingCostResult r;
  Timer costTimer;
  s = EvaluateCullingCost(im, h, cp, r);
  if (!s.ok()) return Fail(kUsage, s.message);

  if (a.has("--json")) {
    Json j;
    j.BeginObject()
        .field("input", a.positional()[0])
        .field("faces", im.faceCount())
        .field("views", r.views)
        .field("perspective", r.perspective)
        .field("camera_distance", r.cameraDistance)
        .field("two_state_cost", r.twoState.mean)
        .field("two_state_min", r.twoState.min)
        .field("two_state_max", r.twoState.max)
        .field("three_state_cost", r.threeState.mean)
        .field("three_state_min", r.threeState.min)
        .field("three_state_max", r.threeState.max)
        .field("rejected_fraction", r.rejectedFraction)
        .field("ideal_fraction", r.idealFraction)
        .field("culled_of_ideal", r.idealFraction > 0 ? r.rejectedFraction / r.idealFraction : 0.0)
        .field("front_accepted_fraction", r.frontAcceptedFraction)
        .field("mean_group_tests", r.meanGroupTests)
        .field("levels", h.levelCount())
        .field("level1_groups", h.level(1).groups.size())
        .field("top_groups", h.level(h.levelCount()).groups.size())
        .field("grouping_seconds", groupSeconds)
        .field("cost_seconds", costTimer.seconds());
    if (pca) {
      j.field("grouping", "pca").field("pca_clusters", int(h.level(1).groups.size()));
      j.key("params").BeginObject().field("pca", pcaClusters).field("pca_levels", pcaLevels).EndObject();
    } else {
      j.field("grouping", "normal_cone");
      WriteParams(j, params);
    }
    j.EndObject();
    std::printf("%s\n", j.str().c_str());
  } else {
    std::printf("%s: %zu faces, %d levels of %s (%zu groups at level 1, %zu at the top), %d %s views\n",
                a.positional()[0].c_str(), im.faceCount(), h.levelCount(), pca ? "PCA clusters" : "normal-cone groups",
                h.level(1).groups.size(), h.level(h.levelCount()).groups.size(), r.views,
                r.perspective ? "perspective" : "orthographic");
    std::printf("culling cost (tests / faces; per-face culling = 1):\n");
    std::printf("  %-12s mean %.4f  min %.4f  max %.4f\n", "two-state", r.twoState.mean, r.twoState.min,
                r.twoState.max);
    std::printf("  %-12s mean %.4f  min %.4f  max %.4f\n", "three-state", r.threeState.mean, r.threeState.min,
                r.threeState.max);
    std::printf(
        "faces culled at group level: %.4f of all faces; faces that draw nothing (ideal): %.4f (%.1f%% of ideal)\n",
        r.rejectedFraction, r.idealFraction, r.idealFraction > 0 ? 100 * r.rejectedFraction / r.idealFraction : 0.0);
    std::printf("faces accepted by a fully-front group test (three-state): %.4f\n", r.frontAcceptedFraction);
  }
  return kOk;
}

}  // namespace cli
}  // namespace conelod
