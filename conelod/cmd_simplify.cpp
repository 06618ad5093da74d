// ConeLOD CLI — `conelod simplify`: group-preserving quadric edge collapse (Kamiya, Suzuki,
// Kawachi §6), one target or one simplified mesh per level of the normal-cone hierarchy (--hierarchy).
#include <cstdio>
#include <cstdlib>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "cli_common.h"
#include "commands.h"
#include "conelod/grouping/cone_grouping.h"
#include "conelod/grouping/group_colors.h"
#include "conelod/simplify/group_integrity.h"
#include "conelod/simplify/group_qem.h"
#include "conelod/simplify/hierarchical_simplification.h"
#include "conelod/simplify/partitioned_simplify.h"
#include "conelod/mesh/mesh_check.h"
#include "conelod/pca/pca_partition.h"
#include "conelod/mesh/sampled_distance.h"
#include "conelod/stage_log.h"

namespace conelod {
namespace cli {
namespace {

void WriteStats(Json& j, const GroupQemStats& s) {
  j.field("collapses", s.collapses)
      .field("passes", s.passes)
      .field("collapses_in_passes", s.collapsesInPasses)
      .field("evaluations", s.evaluations)
      .field("stop", ToString(s.stop))
      .field("max_collapse_error", s.maxCollapseError);
  j.key("refused")
      .BeginObject()
      .field("topology", s.refusedTopology)
      .field("condition1", s.refusedCondition1)
      .field("condition2", s.refusedCondition2)
      .field("lock", s.refusedLock)
      .field("fixed", s.refusedFixed)
      .field("geometry", s.refusedGeometry)
      .field("cone", s.refusedCone)
      .EndObject();
}

// Per-face quality and colour of the saved mesh: the face's group.
void WriteGroupsToFaces(CMesh& mesh, const std::vector<int>& faceGroup, bool setQuality) {
  for (size_t f = 0; f < mesh.face.size(); ++f) {
    if (setQuality) mesh.face[f].Q() = float(faceGroup[f]);
    mesh.face[f].C() = GroupColor(faceGroup[f]);
  }
}

}  // namespace

const char* kSimplifyUsage =
    "conelod simplify IN.ply (--target-faces N | --target-ratio F | --max-error E) [--groups SOURCE]\n"
    "                 [--mode integrity|paper] [--keep-cones] [options] [-o OUT.ply] [--json]\n"
    "conelod simplify IN.ply --hierarchy [--level-ratio R] [options] [-o PREFIX] [--json]\n"
    "  Quadric edge collapse that keeps the face groups intact (Kamiya-Suzuki-Kawachi, §6).\n"
    "  --mode integrity    (default) every group stays one non-empty piece; contours and group\n"
    "                      corners move and merge like any vertex (as accurate as plain QEM)\n"
    "  --mode paper        the paper's condition 1 (no group split or removed) and condition 2 (no\n"
    "                      new vertex where 3+ groups meet), group corners fixed\n"
    "  OUT.ply keeps per-face quality = group id (colour = group). --hierarchy simplifies once per\n"
    "  level of the normal-cone hierarchy, each level from the one below (PREFIX_L<k>.ply).\n"
    "  --groups quality    per-face quality of IN.ply (default; equal values = one group)\n"
    "  --groups cone:L     level L of the normal-cone hierarchy, default grouping parameters\n"
    "  --groups cone:auto  the finest level with >= 8 faces per group at the target (top level if none)\n"
    "  --groups pca:K      the K clusters of the recursive PCA face partition\n"
    "  --keep-cones        (cone groups) refuse collapses that widen a group's normal cone past its\n"
    "                      level's threshold; the count of cones over it is always reported\n"
    "  --keep-components   never remove a component; by default, when no allowed collapse is left\n"
    "                      above the target, whole components made of whole groups are removed,\n"
    "                      smallest first (JSON components_removed, groups_removed)\n"
    "  --target-ratio F    target = F x faces (0 < F <= 1)     --max-error E  fraction of bbox diag\n"
    "  A cone level L that cannot reach the target (no lock, --max-error or --keep-cones) exits 2 naming\n"
    "  the faces reached and the level that would (the JSON is still printed, OUT.ply written).\n"
    "options (defaults in brackets): --no-condition1 (with --no-condition2: plain QEM) --lock-boundaries\n"
    "  --quality-thr Q [0.3]  --no-optimal-placement  --preserve-boundary  --boundary-weight W [1]\n"
    "  --no-preserve-normal (allow face flips)\n"
    "collapse order (one target): ranked passes as meshoptimizer's, then the greedy queue from\n"
    "  25000 faces, for the last eighth or after a stalled pass; inputs of at most 100000 faces run\n"
    "  the queue alone (default; --passes says the same)\n"
    "  --queue: one greedy queue throughout (the order before issue 25; --hierarchy: unless --passes)\n"
    "  --refresh-ratio R [0.8; --hierarchy: 0]: memoryless steps, the quadrics built again from the\n"
    "  faces left each time these fall to R times the last step's (0: the input's quadrics\n"
    "  throughout; 0 by default with --max-error and --mode paper, whose bound is to the input)\n"
    "attributes (per-vertex colour, normals, texture coordinates in IN.ply): kept in OUT.ply (and in\n"
    "  every --hierarchy level, each from the one below) and interpolated at each new vertex\n"
    "  (Garland-Heckbert 1998 attribute planes); a texture, colour or normal seam vertex stays in\n"
    "  place or goes into another seam vertex, its faces never taking a value from across a seam\n"
    "  (chart junctions and small charts go at a cost). --attribute-weight W [1]: how much an attribute change\n"
    "  costs against geometric error (0: the attribute-free collapse order)\n"
    "with --hierarchy: --level-ratio R [0.5]; --faces-per-part P [100000]: a level of at least 2P\n"
    "  faces is cut into 2-8 parts along group contours, simplified side by side (0: never);\n"
    "  --threads N [0: one per core; the result does not depend on it]; --samples N: also the\n"
    "  sampled Hausdorff distance of each level to the input, N face samples [0: off]\n"
    "one target, big meshes (docs/group_qem.md, \"Big meshes in parts\"): a mesh of at least\n"
    "  --partition-above F [2000000; 0: never] faces is cut into parts of about --faces-per-part P\n"
    "  [1000000] faces along group contours, simplified side by side on --threads N threads [0: one\n"
    "  per core; the result does not depend on it] with their shared vertices held, then a final\n"
    "  pass over the whole mesh reaches the target (not with attributes: those run in one piece)\n";

int CmdSimplify(int argc, char** argv) {
  Args a(argc, argv,
         {"-o", "--target-faces", "--target-ratio", "--max-error", "--groups", "--quality-thr", "--boundary-weight",
          "--level-ratio", "--threads", "--faces-per-part", "--samples", "--mode", "--attribute-weight",
          "--partition-above", "--refresh-ratio"},
         {"--json", "--no-condition1", "--no-condition2", "--lock-boundaries", "--no-optimal-placement",
          "--preserve-boundary", "--no-preserve-normal", "--hierarchy", "--keep-cones", "--keep-components", "--passes",
          "--queue"});
  GroupQemParams p = OneTargetParams(0);
  const int targetFaces = a.integer("--target-faces", 0);
  const double targetRatio = a.num("--target-ratio", 0);
  p.maxError = a.num("--max-error", 0);
  p.qualityThr = a.num("--quality-thr", p.qualityThr);
  p.boundaryWeight = a.num("--boundary-weight", p.boundaryWeight);
  const double levelRatio = a.num("--level-ratio", 0.5);
  const double attributeWeight = a.num("--attribute-weight", 1.0);
  HierarchicalSimplificationParams hp;
  PartitionParams pp;
  if (!a.has("--hierarchy") && !a.has("--faces-per-part")) hp.facesPerPart = pp.facesPerPart;
  const std::string partsError = ReadPartsOptions(a, hp);
  const int partitionAbove = a.integer("--partition-above", int(pp.minFaces));
  const int samples = a.integer("--samples", 0);
  p.condition1 = !a.has("--no-condition1");
  p.condition2 = !a.has("--no-condition2");
  p.lockGroupBoundaries = a.has("--lock-boundaries");
  p.optimalPlacement = !a.has("--no-optimal-placement");
  p.preserveBoundary = a.has("--preserve-boundary");
  p.preserveNormal = !a.has("--no-preserve-normal");
  p.keepCones = a.has("--keep-cones");
  p.removeComponents = !a.has("--keep-components");
  // One target: passes, then the queue (issue 25); --hierarchy keeps the queue unless asked.
  p.passes = a.has("--hierarchy") ? a.has("--passes") : !a.has("--queue");
  // --hierarchy: each level is simplified from the one below, already a memoryless step (as the
  // LOD file's levels), unless asked.
  p.refreshRatio = a.num("--refresh-ratio", a.has("--hierarchy") ? 0.0 : p.refreshRatio);
  const std::string mode = a.str("--mode", "integrity");
  if (mode == "paper")
    p.mode = GroupMode::Paper;
  else if (mode != "integrity")
    return Fail(kUsage, "--mode must be integrity or paper (got '" + mode + "')");
  // A --max-error bound and paper mode are to the input: its quadrics to the end, unless asked.
  if (!a.has("--refresh-ratio") && BoundToInput(p)) p.refreshRatio = 0;
  const bool hierarchy = a.has("--hierarchy");
  const bool json = a.has("--json");
  if (!a.ok()) return Fail(kUsage, a.error() + "\n" + kSimplifyUsage);
  if (a.positional().size() != 1) return Fail(kUsage, std::string("expected one input mesh\n") + kSimplifyUsage);
  if (targetFaces < 0) return Fail(kUsage, "--target-faces must be >= 0");
  if (!(attributeWeight >= 0)) return Fail(kUsage, "--attribute-weight must be >= 0");
  if (!(p.refreshRatio >= 0 && p.refreshRatio < 1))
    return Fail(kUsage, "--refresh-ratio must be at least 0 and under 1 (0: the input's quadrics throughout)");
  if (!partsError.empty()) return Fail(kUsage, partsError);
  if (partitionAbove < 0) return Fail(kUsage, "--partition-above must be a whole number >= 0 (0: never in parts)");
  if (samples < 0 || samples > kMaxFaceSamples)
    return Fail(kUsage, "--samples must be from 0 to " + std::to_string(kMaxFaceSamples));
  if (a.has("--passes") && a.has("--queue"))
    return Fail(kUsage, "--passes and --queue are two collapse orders: give one");
  if (hierarchy && a.has("--keep-components"))
    return Fail(kUsage, "--hierarchy never removes components: --keep-components goes with one target");
  if (!hierarchy && a.has("--samples")) return Fail(kUsage, "--samples goes with --hierarchy");
  if (hierarchy && a.has("--partition-above"))
    return Fail(kUsage, "--partition-above goes with one target (--hierarchy cuts levels by --faces-per-part)");
  pp.threads = hp.threads;
  pp.facesPerPart = hp.facesPerPart;
  pp.minFaces = hp.facesPerPart == 0 ? 0 : size_t(partitionAbove);
  if (a.has("--target-ratio") && !(targetRatio > 0 && targetRatio <= 1))
    return Fail(kUsage, "--target-ratio must be in (0, 1]");
  if (!hierarchy && !targetFaces && !a.has("--target-ratio") && !a.has("--max-error"))
    return Fail(kUsage, std::string("give --target-faces, --target-ratio or --max-error\n") + kSimplifyUsage);
  std::string source = a.str("--groups", hierarchy ? "cone:1" : "quality");
  int coneLevel = 0, pcaClusters = 0;
  const bool autoLevel = source == "cone:auto";
  if (autoLevel) {
    if (hierarchy) return Fail(kUsage, "--hierarchy simplifies every level: cone:auto goes with one target");
    if (!targetFaces && !a.has("--target-ratio"))
      return Fail(kUsage,
                  "--groups cone:auto chooses the level for a face count: give --target-faces or --target-ratio");
    coneLevel = -1;
  } else if (source.compare(0, 5, "cone:") == 0) {
    char* end = nullptr;
    coneLevel = int(std::strtol(source.c_str() + 5, &end, 10));
    if (*end || coneLevel < 1) return Fail(kUsage, "--groups cone:L needs a level L >= 1 (or cone:auto)");
  } else if (source.compare(0, 4, "pca:") == 0) {
    char* end = nullptr;
    pcaClusters = int(std::strtol(source.c_str() + 4, &end, 10));
    if (*end || pcaClusters < 1) return Fail(kUsage, "--groups pca:K needs a cluster count K >= 1");
    if (hierarchy) return Fail(kUsage, "--hierarchy simplifies the levels of the normal-cone hierarchy: use cone:L");
  } else if (source != "quality") {
    return Fail(kUsage, "--groups must be quality, cone:L or pca:K\n" + std::string(kSimplifyUsage));
  }
  if (hierarchy && source == "quality")
    return Fail(kUsage, "--hierarchy simplifies the levels of the normal-cone hierarchy: drop --groups quality");
  if (p.keepCones && coneLevel == 0)
    return Fail(kUsage, "--keep-cones keeps the normal cones of cone groups: use --groups cone:L or cone:auto");
  const std::string& input = a.positional()[0];

  // Read straight into the indexed mesh (no vcglib mesh beside the collapse's data: `ply` keeps
  // only the face quality and the attributes the output needs; the output's vcglib mesh is made of
  // the simplified mesh alone, SimplifiedMeshFromPly).
  StageLog::Laps stages;  // CONELOD_STAGES: one line per stage on stderr
  PlyMesh ply;
  int loadMask = 0;
  std::string err = LoadPlyData(input, ply, &loadMask);
  if (!err.empty()) return FailLoad(err);
  stages.Mark("read");
  // Attributes: per face corner, so that texture, colour and normal seams keep their values
  // (attribute_quadric.h); with --hierarchy each level's from the level below's.
  const int attributeMask = AttributeMask(loadMask);
  VertexAttributes layout;
  if (attributeMask) layout = AttributesOf(ply, attributeMask);
  std::vector<std::array<uint32_t, 3>> inputFaces;  // kept for the corner attributes only
  std::vector<uint32_t> representative;
  // Welded by position (weld.h): a seam the file repeats is no border to the groups nor to the
  // collapse; the output has one vertex per position (attributes: one per position and value).
  IndexedMesh im;
  {
    IndexedMesh read;
    read.positions.reserve(ply.positions.size());
    for (const auto& q : ply.positions) read.positions.emplace_back(q[0], q[1], q[2]);
    std::vector<std::array<float, 3>>().swap(ply.positions);
    read.faces.swap(ply.triangles);
    WeldResult w = WeldByPosition(read);
    im = std::move(w.mesh);
    representative = std::move(w.representative);
    if (attributeMask) inputFaces.swap(read.faces);
  }
#if defined(__GLIBC__)
  // The file's arrays and the weld's tables are freed: back to the system, so that the grouping's
  // arrays (the run's first peak) do not sit beside them (the dragon: 31 -> 21 MiB resident here).
  malloc_trim(0);
#endif
  Status s = RequireValidForFaces(im);
  if (!s.ok()) return Fail(kBadInput, input + ": " + s.message);
  stages.Mark("weld, check");

  // Group ids per face of `im`.
  std::vector<int> groups;
  GroupHierarchy h;
  if (a.has("--target-ratio"))
    p.targetFaces = std::max<size_t>(1, size_t(targetRatio * double(im.faceCount())));
  else
    p.targetFaces = size_t(targetFaces);
  if (coneLevel != 0) {
    s = BuildConeHierarchy(im, CollapseGroupingParams(p.targetFaces, autoLevel, hp.threads), h);
    if (!s.ok()) return Fail(kBadInput, input + ": " + s.message);
    if (!hierarchy && coneLevel > h.levelCount())
      return Fail(kUsage, "--groups " + source + ": the normal-cone hierarchy of this mesh has " +
                              std::to_string(h.levelCount()) + " levels");
    if (autoLevel) coneLevel = AutoGroupLevel(h, p.targetFaces);
    if (!hierarchy) {
      groups = h.level(coneLevel).faceGroup;
      if (p.keepCones) p.coneBound = LevelConeBounds(h, coneLevel);
    }
  } else if (pcaClusters > 0) {
    // The cut of the recursive PCA partition at K clusters (built best-first, down to K only).
    PcaPartitionParams pp;
    pp.targetClusters = pcaClusters;
    PcaTree tree;
    s = BuildPcaTree(im, pp, tree);
    if (!s.ok()) return Fail(kBadInput, input + ": " + s.message);
    FaceClustersOfCut(tree, CutByCount(tree, pcaClusters), groups);
  } else {
    if (!(loadMask & vcg::tri::io::Mask::IOM_FACEQUALITY))
      return Fail(kBadInput, input + " has no per-face quality to use as group ids: group it first (conelod group " +
                                 input + " -o grouped.ply) or pass --groups cone:1");
    const std::vector<float>& quality = ply.faceQuality;  // per face of `im` (the weld keeps the faces)
    std::vector<std::vector<int>> ids;
    s = GroupIdsFromValues({&quality}, ids);
    if (!s.ok()) return Fail(kBadInput, input + ": " + s.message);
    groups = std::move(ids[0]);
  }
  // Cone and PCA groups are written as the faces' quality: the file's is not needed.
  if (coneLevel != 0 || pcaClusters > 0) std::vector<float>().swap(ply.faceQuality);

  if (hierarchy) {
    hp.qem = p;
    hp.qem.removeComponents = false;  // each level must keep every group of the level below
    hp.levelRatio = levelRatio;
    std::vector<SimplifiedLevel> levels;
    HierarchyAttributes levelAttributes;
    if (attributeMask) {
      levelAttributes.layout = layout;
      levelAttributes.layout.values.clear();
      levelAttributes.inputCorners = CornerAttributes(inputFaces, layout);
      levelAttributes.weight = attributeWeight;
      levelAttributes.seamMoves = true;
      std::vector<std::array<uint32_t, 3>>().swap(inputFaces);
    }
    Timer timer;
    s = BuildSimplifiedLevels(im, h, hp, levels, Progress(), attributeMask ? &levelAttributes : nullptr);
    const double seconds = timer.seconds();
    if (!s.ok()) return Fail(kBadInput, input + ": " + s.message);
    Json j;
    j.BeginObject()
        .field("input", input)
        .field("faces_in", im.faceCount())
        .field("seconds", seconds)
        .field("mode", ToString(p.mode))
        .field("keep_cones", p.keepCones);
    if (attributeMask) j.field("attributes", DescribeAttributes(layout)).field("attribute_weight", attributeWeight);
    j.key("levels").BeginArray();
    if (!json)
      std::printf("%s: %zu faces, %d levels in %.3f s\n%5s %8s %8s %8s %8s %8s %9s%s\n", input.c_str(), im.faceCount(),
                  int(levels.size()), seconds, "level", "groups", "target", "faces", "split", "vanished", "intact%",
                  samples > 0 ? "  hausdorff%  mean%" : "");
    for (const SimplifiedLevel& L : levels) {
      GroupIntegrity gi;
      MeasureGroupIntegrity(im, h.level(L.level).faceGroup, L.mesh, L.faceGroup, gi);
      j.BeginObject()
          .field("level", L.level)
          .field("groups_before", gi.groupsBefore)
          .field("groups_after", gi.groupsAfter)
          .field("target_faces", L.targetFaces)
          .field("faces_out", L.mesh.faceCount())
          .field("groups_split", gi.groupsSplit)
          .field("groups_vanished", gi.groupsVanished);
      const double limitDeg = std::min(h.level(L.level).thresholdDeg, 180.0);
      j.field("cone_limit_deg", limitDeg)
          .field("cones_over_threshold", CountConesOverLimit(L.mesh, L.faceGroup, limitDeg));
      HausdorffResult hd;
      if (samples > 0) {
        s = SampledHausdorff(im, L.mesh, samples, hd);
        if (!s.ok()) return Fail(kBadInput, "distance: " + s.message);
        j.field("hausdorff", hd.hausdorff)
            .field("mean_distance_from_input", hd.ab.mean)
            .field("mean_distance_to_input", hd.ba.mean)
            .field("diagonal", hd.diagonal);
      }
      WriteStats(j, L.stats);
      j.EndObject();
      if (!json)
        std::printf("%5d %8d %8zu %8zu %8d %8d %9.2f", L.level, gi.groupsBefore, L.targetFaces, L.mesh.faceCount(),
                    gi.groupsSplit, gi.groupsVanished, 100 * gi.intact());
      if (!json && samples > 0)
        std::printf("  %10.4f %6.4f", 100 * hd.hausdorff / hd.diagonal, 100 * hd.ab.mean / hd.diagonal);
      if (!json) std::printf("\n");
      if (a.has("-o")) {
        CMesh copy;
        std::vector<uint32_t> sourceVertex = L.sourceVertex;
        MapToRepresentatives(representative, sourceVertex);
        SimplifiedMeshFromPly(ply, L.mesh, L.sourceFace, sourceVertex, copy);
        if (attributeMask) SetCornerAttributes(copy, layout, L.corner);
        WriteGroupsToFaces(copy, L.faceGroup, true);
        const std::string path = a.str("-o") + "_L" + std::to_string(L.level) + ".ply";
        err = SavePly(copy, path, attributeMask);
        if (!err.empty()) return Fail(kIoError, err);
      }
    }
    j.endArray().EndObject();
    if (json) std::printf("%s\n", j.str().c_str());
    return kOk;
  }

  // What the report needs of the hierarchy; then it is freed: the collapse's own arrays are the
  // run's peak, and the hierarchy's levels would sit under them unused.
  const double coneLimitDeg = coneLevel > 0 ? std::min(h.level(coneLevel).thresholdDeg, 180.0) : 0;
  const size_t levelGroups = coneLevel > 0 ? h.level(coneLevel).groups.size() : 0;
  const int wouldLevel = coneLevel > 0 ? AutoGroupLevel(h, p.targetFaces) : 0;
  h = GroupHierarchy();
#if defined(__GLIBC__)
  // What the grouping freed goes back to the system, rather than staying resident in the heap
  // under the collapse's arrays (the dragon: 66 -> 30 MB resident here, peak 3-4 MB lower).
  malloc_trim(0);
#endif

  stages.Mark("groups");
  GroupQemResult r;
  Timer timer;
  AttributeQuadrics attributes;
  if (attributeMask) {
    s = attributes.Init(im, layout, CornerAttributes(inputFaces, layout), attributeWeight);
    attributes.AllowSeamMoves(true);  // junctions and small charts may go (docs/attributes.md)
    std::vector<std::array<uint32_t, 3>>().swap(inputFaces);
    if (!s.ok()) return Fail(kBadInput, input + ": " + s.message);
  }
  // The groups' pieces in the input, counted now: in one piece and without attributes the
  // collapse takes the input over and frees it once copied (the run's peak is the collapse's).
  const GroupPieces piecesBefore = CountGroupPieces(im, groups);
  const size_t facesIn = im.faceCount();
  PartitionStats partition;
  if (attributeMask || PartitionCount(im.faceCount(), p, pp) <= 1) {
    if (attributeMask && PartitionCount(im.faceCount(), p, pp) > 1)
      std::fprintf(stderr, "conelod: note: %s has attributes: simplified in one piece, on one thread\n", input.c_str());
    if (attributeMask)
      s = SimplifyPreservingGroups(im, groups, p, r, Progress(), {}, nullptr, &attributes);
    else
      s = SimplifyPreservingGroups(std::move(im), groups, p, r, Progress());
  } else {
    s = SimplifyPartitioned(im, groups, p, pp, r, Progress(), &partition);
  }
  const double seconds = timer.seconds();
  if (!s.ok()) return Fail(kBadInput, input + ": " + s.message);
  stages.Mark("simplify");

  std::vector<int> groupsAfter(r.sourceFace.size());
  for (size_t f = 0; f < r.sourceFace.size(); ++f) groupsAfter[f] = groups[r.sourceFace[f]];
  GroupIntegrity gi;
  MeasureGroupIntegrity(piecesBefore, r.mesh, groupsAfter, gi);
  gi.groupsRemoved = int(r.stats.groupsRemoved);
  const std::string floorReason = DescribeFloor(r.stats, p);
  // Cone groups: the cones now wider than their level's threshold; and, when the target was
  // missed, the level that would reach it.
  const int conesOver = coneLevel > 0 ? CountConesOverLimit(r.mesh, groupsAfter, coneLimitDeg) : 0;
  const bool targetReached = p.targetFaces == 0 || r.mesh.faceCount() <= p.targetFaces;
  std::string unreachable;
  // (Not with cone:auto, whose stop is reported as any other, nor without condition 1 (no group
  // then stops anything), nor with the lock, a maximum error or --keep-cones: those stop early by
  // choice.)
  if (coneLevel > 0 && !autoLevel && !targetReached && p.condition1 && !p.lockGroupBoundaries && !(p.maxError > 0) &&
      !p.keepCones) {
    const int would = wouldLevel;
    unreachable = input + ": the target of " + std::to_string(p.targetFaces) + " faces cannot be reached with " +
                  std::to_string(levelGroups) + " groups (level " + std::to_string(coneLevel) + "): stopped at " +
                  std::to_string(r.mesh.faceCount()) + " faces (" + ToString(r.stats.stop) + "); " +
                  (would > coneLevel ? "level " + std::to_string(would) + " (--groups cone:" + std::to_string(would) +
                                           ", or cone:auto) would reach it"
                                     : std::string("no coarser level has fewer groups per face: try a larger target"));
  }

  stages.Mark("integrity, cones");
  if (a.has("-o")) {
    // Each corner's attributes at its vertex's new position.
    std::vector<float> corner(attributeMask ? 3 * r.mesh.faceCount() * size_t(layout.channels()) : 0);
    for (size_t f = 0; attributeMask && f < r.mesh.faceCount(); ++f)
      for (int k = 0; k < 3; ++k) {
        const uint32_t o = r.mesh.faces[f][size_t(k)];
        const auto& q = r.mesh.positions[o];
        attributes.Evaluate(r.sourceFace[f], k, r.sourceVertex[o], vcg::Point3d(q[0], q[1], q[2]),
                            corner.data() + (3 * f + size_t(k)) * size_t(layout.channels()));
      }
    MapToRepresentatives(representative, r.sourceVertex);
    CMesh mesh;
    SimplifiedMeshFromPly(ply, r.mesh, r.sourceFace, r.sourceVertex, mesh);
    if (attributeMask) SetCornerAttributes(mesh, layout, corner);
    WriteGroupsToFaces(mesh, groupsAfter, coneLevel > 0 || pcaClusters > 0);  // quality source: faces keep theirs
    err = SavePly(mesh, a.str("-o"), attributeMask);
    if (!err.empty()) return Fail(kIoError, err);
    stages.Mark("write");
  }

  if (json) {
    Json j;
    j.BeginObject()
        .field("input", input)
        .field("group_source", source)
        .field("faces_in", facesIn)
        .field("faces_out", r.mesh.faceCount())
        .field("target_faces", p.targetFaces)
        .field("groups_before", gi.groupsBefore)
        .field("groups_after", gi.groupsAfter)
        .field("groups_split", gi.groupsSplit)
        .field("groups_vanished", gi.groupsVanished)
        .field("groups_disconnected_in", gi.groupsDisconnectedBefore)
        .field("integrity", gi.intact())
        .field("seconds", seconds)
        .field("condition1", p.condition1)
        .field("condition2", p.condition2)
        .field("lock_boundaries", p.lockGroupBoundaries)
        .field("mode", ToString(p.mode))
        .field("keep_cones", p.keepCones)
        .field("target_reached", targetReached)
        .field("components_removed", r.stats.componentsRemoved)
        .field("groups_removed", r.stats.groupsRemoved)
        .field("faces_removed_with_components", r.stats.facesRemovedWithComponents)
        .field("keep_components", !p.removeComponents)
        .field("edge_flips", r.stats.edgeFlips)
        .field("collapses_unblocked", r.stats.collapsesUnblocked);
    if (!floorReason.empty()) j.field("floor", r.mesh.faceCount()).field("floor_reason", floorReason);
    if (attributeMask)
      j.field("attributes", DescribeAttributes(layout))
          .field("attribute_weight", attributeWeight)
          .field("seam_vertices", attributes.seamVertices());
    if (coneLevel > 0)
      j.field("group_level", coneLevel)
          .field("group_level_automatic", autoLevel)
          .field("cone_limit_deg", coneLimitDeg)
          .field("cones_over_threshold", conesOver);
    if (!unreachable.empty()) j.field("message", unreachable);
    if (partition.parts > 1)
      j.field("parts", partition.parts)
          .field("frozen_vertices", partition.frozenVertices)
          .field("faces_after_parts", partition.facesAfterParts)
          .field("final_pass_collapses", partition.finalPassCollapses)
          .field("parts_seconds", partition.partsSeconds)
          .field("parts_cpu_seconds", partition.partsCpuSeconds)
          .field("largest_part_cpu_seconds", partition.largestPartCpuSeconds)
          .field("final_pass_seconds", partition.finalSeconds);
    WriteStats(j, r.stats);
    if (a.has("-o")) j.field("output", a.str("-o"));
    j.EndObject();
    std::printf("%s\n", j.str().c_str());
  } else {
    std::printf("%s: %zu -> %zu faces (target %zu, %s) in %.3f s, %zu collapses\n", input.c_str(), facesIn,
                r.mesh.faceCount(), p.targetFaces, ToString(r.stats.stop), seconds, r.stats.collapses);
    if (partition.parts > 1)
      std::printf(
          "in %d parts (%zu shared vertices held) side by side: %zu faces in %.3f s (CPU %.3f s, largest part "
          "%.3f s); final pass: %zu collapses in %.3f s\n",
          partition.parts, partition.frozenVertices, partition.facesAfterParts, partition.partsSeconds,
          partition.partsCpuSeconds, partition.largestPartCpuSeconds, partition.finalPassCollapses,
          partition.finalSeconds);
    std::printf("groups (%s): %d before, %d after, %d split, %d vanished: %.2f%% intact\n", source.c_str(),
                gi.groupsBefore, gi.groupsAfter, gi.groupsSplit, gi.groupsVanished, 100 * gi.intact());
    if (gi.groupsDisconnectedBefore)
      std::printf("note: %d groups were already in several pieces in the input; each piece is kept as it is\n",
                  gi.groupsDisconnectedBefore);
    if (r.stats.componentsRemoved > 0)
      std::printf(
          "removed %zu whole component(s), %zu faces, with their %zu group(s), smallest first, to reach the "
          "target (--keep-components refuses it)\n",
          r.stats.componentsRemoved, r.stats.facesRemovedWithComponents, r.stats.groupsRemoved);
    if (r.stats.edgeFlips > 0)
      std::printf("flipped %zu edge(s) inside groups to unblock %zu collapse(s) refused by the link condition\n",
                  r.stats.edgeFlips, r.stats.collapsesUnblocked);
    if (!floorReason.empty())
      std::printf("target not reached (floor %zu): %s\n", r.mesh.faceCount(), floorReason.c_str());
    if (coneLevel > 0)
      std::printf("normal cones: %d of %d groups over the level-%d threshold of %.1f deg%s%s\n", conesOver,
                  gi.groupsAfter, coneLevel, coneLimitDeg, autoLevel ? " (level chosen for the target)" : "",
                  p.keepCones ? " (--keep-cones)" : "");
    std::printf(
        "refused evaluations (%s mode): topology %zu, %s %zu, condition 2 %zu, lock %zu, fixed %zu, "
        "geometry %zu, cone %zu\n",
        ToString(p.mode), r.stats.refusedTopology, p.mode == GroupMode::Paper ? "condition 1" : "integrity",
        r.stats.refusedCondition1, r.stats.refusedCondition2, r.stats.refusedLock, r.stats.refusedFixed,
        r.stats.refusedGeometry, r.stats.refusedCone);
    if (attributeMask)
      std::printf(
          "attributes: %s, interpolated (weight %g); %zu seam vertices (moved at a cost; their texture stays in its "
          "charts)\n",
          DescribeAttributes(layout).c_str(), attributeWeight, attributes.seamVertices());
    if (a.has("-o")) std::printf("wrote %s (quality and colour = group)\n", a.str("-o").c_str());
  }
  if (!unreachable.empty()) return Fail(kBadInput, unreachable);
  return kOk;
}

}  // namespace cli
}  // namespace conelod
