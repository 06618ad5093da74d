// ConeLOD — the fidelity of each level of the .clod LOD, before and after the cluster DAG (issue 17),
// against MeshLab's Quadric Edge Collapse Decimation (vcglib's TriEdgeCollapseQuadric with the
// filter's defaults) at the same face count.
//
//   lod_fidelity MESH.ply [--samples N] [--dag-only] [--cluster-faces N] [--group-clusters N] [--cone DEG]
//                [--max-faces N] [--max-group-error F] [--lod-refresh-ratio R] [--fine-group-clusters N]
//                [--large-fine-group-clusters N] [--large-group-clusters N] [--large-group-count K]
//                [--level-ratio R]
//                [--coarse-level-ratio R] [--top-group-clusters N] [--cuts P,P,...] [--no-peers]
//                [--min-faces N] [--borders] [--locked-border-weight W] [--chunk-faces N] [--shuffle-faces S]
//                [--no-merge-small-groups]
//
// The input is welded by position first (coincident vertices made one), as the CLI welds it.
// "tree": the previous .clod levels (BuildConeHierarchy + BuildSimplifiedLevels with the defaults
// `conelod lod build` used: every level keeps the normal-cone groups of its hierarchy level).
// "dag": the cluster DAG's levels (BuildLodDag, the defaults of `conelod lod build` now: groups of
// clusters simplified with their borders locked). For every level: its faces, the RMS of the
// sampled distance between it and the input (larger of both ways, Metro-like, sampled_distance.h)
// as a fraction of the diagonal, the same for vcglib's QEM run on the input to that face count,
// and their ratio. Also the wall seconds of each build (one thread per core). --max-faces N: only
// the levels of at most N faces are compared (the coarse ones; MeshLab's QEM on a large input is slow);
// --min-faces N: only those of at least N faces (the fine ones, in another run).
// --max-group-error 1: the DAG without the cap on a group's collapse error (as before it had one).
// --level-ratio R: each group of the fine levels simplified to R of its faces (conelod lod build
// --level-ratio; 0.5); --coarse-level-ratio R: LodBuildParams::coarseLevelRatio (0.6; 0: the
// level ratio at every level); --large-group-clusters N / --large-group-count K:
// LodBuildParams::largeGroupClusters / largeGroupCount (24 / 8; 0: off);
// --fine-group-clusters N / --large-fine-group-clusters N /
// --top-group-clusters N: LodBuildParams'
// (24 / 64 / 6; 0: --group-clusters [12] there, or no large ones); --locked-border-weight W:
// LodBuildParams::lockedBorderWeight;
// --no-merge-small-groups: LodBuildParams::mergeSmallGroups off.
// --file [--precision E]: instead, the DAG's levels against the same levels read back from the .clod
// file written from it (positions quantized with precision E, default kDefaultLodPrecision): per level
// the RMS of both and their relative change (quantization and the codecs' round trip).
// Each level is also compared with our static collapse at its count (`conelod simplify --groups
// cone:auto`): where a level as a whole loses against it. --cuts P,...: instead of the levels,
// cuts of the file at these budgets (% of the input's faces; far eye, error in model units, no
// culling: scripts/lod_fidelity.py's cuts, measured here in-process) beside both, with the faces
// the cut takes from each level: where the cut loses against its levels; the header line gives
// every level's faces. --no-peers: the cuts alone (their faces and RMS; no static collapse, no
// MeshLab QEM: quick on the dragon).
// --borders: instead, per level k of the DAG its faces, groups and locked vertices (those two of
// its groups share, frozen while they are simplified), and how many of them were locked at level
// k - 1 too (a frozen vertex keeps its id, so a border locked twice is the same vertices): where
// a level's groups follow the borders of the level below instead of straddling them.
// --chunk-faces N: instead, the DAG built in spatial chunks of at most N faces (conelod lod build
// --memory; LodBuildParams::chunkFaces) against the DAG built whole: per level of the chunked DAG
// its faces and RMS, and the whole DAG's RMS at the same face count (interpolated in log-log
// between its two levels around that count), and their ratio. --shuffle-faces S: the compared DAG
// built on the input's faces shuffled (seed S; with --chunk-faces, in chunks too): the same surface
// in another face order, whose ratios to the whole DAG are the noise a single build's levels carry.
// With --cuts, --shuffle-faces S measures everything (the DAG, its cuts, both peers) on the
// shuffled faces: a few seeds give the spread of one build's cuts.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <vcg/complex/complex.h>
#include <wrap/io_trimesh/import_ply.h>

#include "conelod/grouping/cone_grouping.h"
#include "conelod/simplify/hierarchical_simplification.h"
#include "conelod/lod/lod_build.h"
#include "conelod/lod/lod_read.h"
#include "conelod/mesh/sampled_distance.h"
#include "conelod/vcg_bridge.h"
#include "meshlab_qem.h"

namespace {

using conelod_bench::QMesh;

conelod::IndexedMesh Vcg(QMesh& input, size_t targetFaces) {
  QMesh m;
  vcg::tri::Append<QMesh, QMesh>::MeshCopy(m, input);
  conelod_bench::RunMeshLabQem(m, targetFaces);
  return conelod::ToIndexedMesh(m);
}

// `conelod simplify --groups cone:auto --target-faces N` (the CLI's defaults): our static collapse.
conelod::IndexedMesh Ours(const conelod::IndexedMesh& input, const conelod::GroupHierarchy& h, size_t targetFaces) {
  const conelod::GroupQemParams p = conelod::OneTargetParams(targetFaces);
  conelod::GroupQemResult r;
  if (!conelod::SimplifyPreservingGroups(input, h.level(conelod::AutoGroupLevel(h, targetFaces)).faceGroup, p, r).ok())
    return conelod::IndexedMesh();
  return r.mesh;
}

double Rms(const conelod::IndexedMesh& a, const conelod::IndexedMesh& input, int samples, double diag) {
  conelod::HausdorffResult h;
  if (!conelod::SampledHausdorff(a, input, samples, h).ok()) return -1;
  return std::max(h.ab.rms, h.ba.rms) / diag;
}

// The mesh's faces in another order (seed S; Fisher-Yates on mt19937's raw output: the same order
// with any standard library).
void ShuffleFaces(conelod::IndexedMesh& m, unsigned seed) {
  std::mt19937 rng(seed);
  for (size_t i = m.faces.size(); i > 1; --i) std::swap(m.faces[i - 1], m.faces[size_t(rng()) % i]);
}

double Wall() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: lod_fidelity MESH.ply [--samples N]\n");
    return 2;
  }
  int samples = 200000;
  size_t maxFaces = 0;    // 0: every level
  size_t minFaces = 0;    // --min-faces N: only the levels of at least N faces (with --max-faces: a range)
  size_t chunkFaces = 0;  // --chunk-faces N: chunked against whole
  unsigned shuffle = 0;   // --shuffle-faces S: the compared build on the faces in another order
  bool tree = true, file = false;
  bool borders = false;  // --borders: the locked vertices per level
  bool peers = true;     // --no-peers: the cuts alone (no static collapse, no MeshLab QEM)
  bool meshlab = true;   // --no-meshlab: the levels beside our static collapse only
  conelod::LodBuildParams dagParams;
  std::vector<double> cuts;  // --cuts P,...: cuts at these budgets (% of the input's faces) instead of levels
  for (int i = 2; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--dag-only")) tree = false;
    if (!std::strcmp(argv[i], "--file")) file = true;
    if (!std::strcmp(argv[i], "--no-peers")) peers = false;
    if (!std::strcmp(argv[i], "--no-meshlab")) meshlab = false;
    if (!std::strcmp(argv[i], "--borders")) borders = true;
    if (!std::strcmp(argv[i], "--no-merge-small-groups")) dagParams.mergeSmallGroups = false;
    if (i + 1 >= argc) break;
    if (!std::strcmp(argv[i], "--samples")) samples = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--cluster-faces")) dagParams.clusterFaces = size_t(std::atoi(argv[i + 1]));
    if (!std::strcmp(argv[i], "--group-clusters")) dagParams.groupClusters = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--fine-group-clusters")) dagParams.fineGroupClusters = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--large-group-clusters")) dagParams.largeGroupClusters = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--large-group-count")) dagParams.largeGroupCount = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--large-fine-group-clusters")) dagParams.largeFineGroupClusters = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--max-group-error")) dagParams.maxGroupError = std::atof(argv[i + 1]);
    if (!std::strcmp(argv[i], "--lod-refresh-ratio")) dagParams.refreshRatio = std::atof(argv[i + 1]);
    if (!std::strcmp(argv[i], "--level-ratio")) dagParams.simplification.levelRatio = std::atof(argv[i + 1]);
    if (!std::strcmp(argv[i], "--coarse-level-ratio")) dagParams.coarseLevelRatio = std::atof(argv[i + 1]);
    if (!std::strcmp(argv[i], "--top-level-ratio")) dagParams.topLevelRatio = std::atof(argv[i + 1]);
    if (!std::strcmp(argv[i], "--top-group-clusters")) dagParams.topGroupClusters = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--top-face-share")) dagParams.topFaceShare = std::atof(argv[i + 1]);
    if (!std::strcmp(argv[i], "--locked-border-weight")) dagParams.lockedBorderWeight = std::atof(argv[i + 1]);
    if (!std::strcmp(argv[i], "--max-faces")) maxFaces = size_t(std::atoll(argv[i + 1]));
    if (!std::strcmp(argv[i], "--min-faces")) minFaces = size_t(std::atoll(argv[i + 1]));
    if (!std::strcmp(argv[i], "--chunk-faces")) chunkFaces = size_t(std::atoll(argv[i + 1]));
    if (!std::strcmp(argv[i], "--shuffle-faces")) shuffle = unsigned(std::atoi(argv[i + 1]));
    if (!std::strcmp(argv[i], "--cuts")) {
      tree = false;
      for (const char* c = argv[i + 1]; *c;) {
        char* end = nullptr;
        cuts.push_back(std::strtod(c, &end));
        c = *end ? end + 1 : end;
      }
    }
    if (!std::strcmp(argv[i], "--cone")) dagParams.grouping.coneThresholdDeg = std::atof(argv[i + 1]);
    if (!std::strcmp(argv[i], "--precision")) dagParams.precision = std::atof(argv[i + 1]);
  }
  QMesh qm;
  if (vcg::tri::io::ImporterPLY<QMesh>::Open(qm, argv[1]) != 0) {
    std::fprintf(stderr, "lod_fidelity: cannot read %s\n", argv[1]);
    return 1;
  }
  vcg::tri::Clean<QMesh>::RemoveUnreferencedVertex(qm);
  vcg::tri::Allocator<QMesh>::CompactEveryVector(qm);
  // Welded by position, as `conelod lod build` and `conelod simplify` weld it: the vrip dragon's
  // 2,100 coincident pairs close its 4,270 border edges into one closed surface, whose DAG differs.
  conelod::IndexedMesh input = conelod::WeldByPosition(conelod::ToIndexedMesh(qm)).mesh;
  const vcg::Box3d box = conelod::UsedVertexBox(input);
  const double diag = box.Diag();
  if (!cuts.empty() && shuffle > 0) ShuffleFaces(input, shuffle);  // the cuts of another build

  if (cuts.empty() && (chunkFaces > 0 || shuffle > 0)) {
    std::vector<double> wholeFaces, wholeRms;
    const conelod::IndexedMesh welded = conelod::WeldByPosition(input).mesh;  // as conelod lod build
    conelod::IndexedMesh shuffled;  // --shuffle-faces: the same faces in another order
    if (shuffle > 0) {
      shuffled = welded;
      ShuffleFaces(shuffled, shuffle);
    }
    for (int compared : {0, 1}) {
      const size_t chunk = compared ? chunkFaces : 0;
      conelod::LodBuildParams p = dagParams;
      p.chunkFaces = chunk;
      conelod::LodDag dag;
      size_t chunks = 1;
      const double w = Wall();
      if (!conelod::BuildLodDag(compared && shuffle ? shuffled : welded, p, dag, conelod::Progress(), &chunks).ok())
        return 1;
      std::printf("\n%s (%zu faces), DAG %s%s: %zu chunks, %.2f s wall\n", argv[1], input.faces.size(),
                  chunk ? "in chunks" : "whole", compared && shuffle ? ", faces shuffled" : "", chunks, Wall() - w);
      std::printf(compared ? "| level | faces | RMS | RMS (whole, same faces) | ratio |\n|---|---|---|---|---|\n"
                           : "| level | faces | RMS (whole) |\n|---|---|---|\n");
      for (size_t k = 1; k < dag.levels.size(); ++k) {
        conelod::IndexedMesh m;
        m.positions = dag.positions;
        m.faces = dag.levels[k].faces;
        if (maxFaces > 0 && m.faces.size() > maxFaces) continue;
        const double rms = Rms(m, input, samples, diag), f = double(m.faces.size());
        if (!compared) {
          wholeFaces.push_back(f);
          wholeRms.push_back(rms);
          std::printf("| %zu | %zu | %.4f |\n", k, m.faces.size(), 100 * rms);
          std::fflush(stdout);
          continue;
        }
        double same = -1;  // the whole DAG's RMS at f faces (its levels' faces decrease)
        for (size_t i = 0; i + 1 < wholeFaces.size(); ++i)
          if (wholeFaces[i] >= f && f >= wholeFaces[i + 1] && wholeRms[i] > 0 && wholeRms[i + 1] > 0) {
            const double t = std::log(f / wholeFaces[i]) / std::log(wholeFaces[i + 1] / wholeFaces[i]);
            same = std::exp(std::log(wholeRms[i]) + t * (std::log(wholeRms[i + 1]) - std::log(wholeRms[i])));
            break;
          }
        if (same > 0)
          std::printf("| %zu | %zu | %.4f | %.4f | %.3f |\n", k, m.faces.size(), 100 * rms, 100 * same, rms / same);
        else
          std::printf("| %zu | %zu | %.4f | (outside the whole DAG's levels) | |\n", k, m.faces.size(), 100 * rms);
        std::fflush(stdout);
      }
    }
    return 0;
  }
  if (borders) {
    conelod::LodDag dag;
    const double w = Wall();
    if (!conelod::BuildLodDag(input, dagParams, dag).ok()) return 1;
    std::printf("%s (%zu faces): DAG %.2f s wall, %zu levels\n", argv[1], input.faces.size(), Wall() - w,
                dag.levels.size());
    std::printf(
        "| level | faces | groups | locked vertices | also locked below | share | of those below, locked again |\n"
        "|---|---|---|---|---|---|---|\n");
    std::vector<uint8_t> below;  // per vertex: locked at the level below
    size_t lockedBelow = 0;
    for (size_t k = 0; k < dag.levels.size(); ++k) {
      const conelod::LodDag::Level& L = dag.levels[k];
      if (L.clusterGroup.empty() || L.clusterGroup[0] < 0) break;  // the top: no groups
      std::vector<int> owner(dag.positions.size(), -1);
      std::vector<uint8_t> locked(dag.positions.size(), 0);
      for (size_t f = 0; f < L.faces.size(); ++f) {
        const int g = L.clusterGroup[L.faceCluster[f]];
        for (uint32_t v : L.faces[f]) {
          if (owner[v] == -1)
            owner[v] = g;
          else if (owner[v] != g)
            locked[v] = 1;
        }
      }
      size_t n = 0, both = 0;
      for (size_t v = 0; v < locked.size(); ++v) {
        n += locked[v];
        both += locked[v] && v < below.size() && below[v];
      }
      const int groups = 1 + *std::max_element(L.clusterGroup.begin(), L.clusterGroup.end());
      if (k == 0)
        std::printf("| %zu | %zu | %d | %zu | | | |\n", k, L.faces.size(), groups, n);
      else
        std::printf("| %zu | %zu | %d | %zu | %zu | %.1f %% | %.1f %% |\n", k, L.faces.size(), groups, n, both,
                    n ? 100.0 * double(both) / double(n) : 0.0,
                    lockedBelow ? 100.0 * double(both) / double(lockedBelow) : 0.0);
      std::fflush(stdout);
      below.swap(locked);
      lockedBelow = n;
    }
    return 0;
  }
  if (file) {
    conelod::LodDag dag;
    const conelod::Status built = conelod::BuildLodDag(input, dagParams, dag);
    if (!built.ok()) {
      std::fprintf(stderr, "lod_fidelity: %s\n", built.message.c_str());
      return 2;
    }
    const std::string path = std::string(std::getenv("TMPDIR") ? std::getenv("TMPDIR") : "/tmp") + "/lod_fidelity_" +
                             std::to_string(::getpid()) + ".clod";
    conelod::LodBuildStats stats;
    conelod::Status st = conelod::WriteLodFile(input, dag, path, &stats, conelod::Progress(), dagParams.precision);
    std::unique_ptr<conelod::LodReader> reader;
    if (st.ok()) st = conelod::LodReader::Open(path, reader);
    std::remove(path.c_str());
    if (!st.ok()) {
      std::fprintf(stderr, "lod_fidelity: %s\n", st.message.c_str());
      return 1;
    }
    const conelod::LodFileInfo& info = reader->info();
    std::printf("%s (%zu faces): %llu bytes (%.2f per input face), precision %g (bound %.3g of the diagonal)\n",
                argv[1], input.faces.size(), (unsigned long long)stats.fileBytes,
                double(stats.fileBytes) / double(input.faces.size()), dagParams.precision,
                info.quantizationError / diag);
    std::printf("| level | faces | RMS (DAG) | RMS (file) | change |\n|---|---|---|---|---|\n");
    uint64_t first = info.nodeCount;
    for (int k = 0; k < info.levels; ++k) {
      first -= info.levelNodes[size_t(k)];
      conelod::LodCut cut;
      for (uint64_t id = first; id < first + info.levelNodes[size_t(k)]; ++id) cut.nodes.push_back(uint32_t(id));
      cut.culled.assign(cut.nodes.size(), 0);
      conelod::IndexedMesh fromFile, fromDag;
      if (!conelod::ExtractCutMesh(*reader, cut, true, fromFile).ok()) return 1;
      fromDag.positions = dag.positions;
      fromDag.faces = dag.levels[size_t(k)].faces;
      if (maxFaces > 0 && fromDag.faces.size() > maxFaces) continue;
      const double a = Rms(fromDag, input, samples, diag), b = Rms(fromFile, input, samples, diag);
      std::printf("| %d | %zu | %.5f | %.5f | %s |\n", k, fromFile.faces.size(), 100 * a, 100 * b,
                  k > 0 ? (std::to_string(100 * (b - a) / a).substr(0, 5) + " %").c_str() : "- (the input)");
      std::fflush(stdout);
    }
    return 0;
  }
  std::vector<std::pair<std::string, std::vector<conelod::IndexedMesh>>> runs;
  if (tree) {
    double w = Wall();
    conelod::GroupHierarchy h;
    std::vector<conelod::SimplifiedLevel> levels;
    if (!conelod::BuildConeHierarchy(input, conelod::ConeGroupingParams(), h).ok() ||
        !conelod::BuildSimplifiedLevels(input, h, conelod::HierarchicalSimplificationParams(), levels).ok())
      return 1;
    std::printf("tree: grouping + levels %.2f s wall\n", Wall() - w);
    std::vector<conelod::IndexedMesh> meshes;
    for (auto& l : levels) meshes.push_back(l.mesh);
    runs.emplace_back("tree", std::move(meshes));
  }
  {
    double w = Wall();
    conelod::LodDag dag;
    const conelod::Status built = conelod::BuildLodDag(input, dagParams, dag);
    if (!built.ok()) {
      std::fprintf(stderr, "lod_fidelity: %s\n", built.message.c_str());
      return 2;
    }
    std::printf("dag: cluster DAG %.2f s wall\n", Wall() - w);
    if (!cuts.empty()) {
      // Cuts of the file: far eye, by error alone, no culling (scripts/lod_fidelity.py's cuts).
      const std::string path = "/tmp/lod_fidelity_bench_" + std::to_string(long(Wall() * 1000)) + ".clod";
      conelod::LodBuildStats st;
      if (!conelod::WriteLodFile(input, dag, path, &st).ok()) return 1;
      std::unique_ptr<conelod::LodReader> reader;
      if (!conelod::LodReader::Open(path, reader).ok()) return 1;
      std::remove(path.c_str());
      conelod::GroupHierarchy h;
      if (peers && !conelod::BuildConeHierarchy(input, conelod::ConeGroupingParams(), h).ok()) return 1;
      std::string levelFaces;  // faces per level, finest first (where the cuts can stop)
      for (const auto& L : dag.levels) levelFaces += (levelFaces.empty() ? "" : " ") + std::to_string(L.faces.size());
      std::printf(
          "%s: %zu bytes, %zu levels (faces: %s)\n| budget | cut faces | fill | RMS cut | static | MeshLab | "
          "cut/static | "
          "cut/MeshLab | faces per level |\n|---|---|---|---|---|---|---|---|---|\n",
          argv[1], size_t(st.fileBytes), dag.levels.size(), levelFaces.c_str());
      for (double pct : cuts) {
        conelod::LodView v;
        v.eye = box.Center() + vcg::Point3d(0, 0, 100 * diag);
        v.cullBackFacing = false;
        v.priority = conelod::LodPriority::ObjectError;
        v.faceBudget = size_t(std::llround(pct / 100 * double(input.faces.size())));
        conelod::LodCut cut;
        conelod::IndexedMesh m;
        std::vector<int> faceLevel;
        if (!conelod::RefineLod(*reader, v, cut).ok() ||
            !conelod::ExtractCutMesh(*reader, cut, true, m, &faceLevel).ok())
          return 1;
        std::vector<size_t> perLevel(dag.levels.size(), 0);
        for (int l : faceLevel) ++perLevel[size_t(l)];
        std::string levels;
        for (size_t l = 0; l < perLevel.size(); ++l)
          if (perLevel[l])
            levels += (levels.empty() ? "" : " ") + std::to_string(l) + ":" + std::to_string(perLevel[l]);
        const double ours = Rms(m, input, samples, diag);
        const double stat = peers ? Rms(Ours(input, h, m.faces.size()), input, samples, diag) : NAN;
        const double ref = peers ? Rms(Vcg(qm, m.faces.size()), input, samples, diag) : NAN;
        char peer[128] = " | | |";  // (--no-peers: blank)
        if (peers)
          std::snprintf(peer, sizeof peer, "%.5f | %.5f | %.3f | %.3f", 100 * stat, 100 * ref, ours / stat, ours / ref);
        std::printf("| %g %% | %zu | %.1f %% | %.5f | %s | %s |\n", pct, m.faces.size(),
                    100.0 * double(m.faces.size()) / double(v.faceBudget), 100 * ours, peer, levels.c_str());
        std::fflush(stdout);
      }
      return 0;
    }
    std::vector<conelod::IndexedMesh> meshes;
    for (size_t k = 1; k < dag.levels.size(); ++k) {
      conelod::IndexedMesh m;
      m.positions = dag.positions;
      m.faces = dag.levels[k].faces;
      meshes.push_back(std::move(m));
    }
    runs.emplace_back("dag", std::move(meshes));
  }
  conelod::GroupHierarchy hierarchy;
  if (!conelod::BuildConeHierarchy(input, conelod::ConeGroupingParams(), hierarchy).ok()) return 1;
  for (const auto& run : runs) {
    std::printf("\n%s, %s (%zu faces): RMS distance to the input, %% of the diagonal\n", run.first.c_str(), argv[1],
                input.faces.size());
    std::printf(
        "| level | faces | RMS (%s) | RMS (MeshLab QEM) | ratio | RMS (ours static, cone:auto) | ratio |\n"
        "|---|---|---|---|---|---|---|\n",
        run.first.c_str());
    for (size_t k = 0; k < run.second.size(); ++k) {
      const conelod::IndexedMesh& m = run.second[k];
      if ((maxFaces > 0 && m.faces.size() > maxFaces) || m.faces.size() < minFaces) {
        std::printf("| %zu | %zu | | | |\n", k + 1, m.faces.size());
        continue;
      }
      const double ours = Rms(m, input, samples, diag);
      const double ref = meshlab ? Rms(Vcg(qm, m.faces.size()), input, samples, diag) : NAN;
      const double stat = Rms(Ours(input, hierarchy, m.faces.size()), input, samples, diag);
      std::printf("| %zu | %zu | %.5f | %.5f | %.3f | %.5f | %.3f |\n", k + 1, m.faces.size(), 100 * ours, 100 * ref,
                  ours / ref, 100 * stat, ours / stat);
      std::fflush(stdout);
    }
  }
  return 0;
}
