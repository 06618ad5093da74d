// ConeLOD benchmarks — feature-preserving simplification (feature_simplify.h) and the pixel
// budget (pixel_budget.h) on the real meshes. The mesh is loaded once; each iteration runs the
// core on it.
//   build/bench/feature_budget_bench [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <map>
#include <string>

#include "conelod/feature/feature_simplify.h"
#include "conelod/budget/pixel_budget.h"
#include "conelod/vcg_bridge.h"
#include "conelod/vcg_mesh.h"

namespace {

const conelod::IndexedMesh& Mesh(const std::string& name) {
  static std::map<std::string, conelod::IndexedMesh> cache;
  auto it = cache.find(name);
  if (it != cache.end()) return it->second;
  const char* env = std::getenv("CONELOD_TEST_MESHES");
  conelod::CMesh m;
  const std::string err = conelod::LoadPly(m, std::string(env ? env : CONELOD_TEST_MESHES) + "/" + name);
  if (!err.empty()) std::abort();
  return cache[name] = conelod::ToIndexedMesh(m);
}

// args: mesh index, target percent, grow (1) or the paper's pure order (0), threads (0 = one per
// core, the default; only the growing bound's first pass uses them). Time is the wall clock, CPU
// the whole process's (all threads).
const char* const kMeshes[] = {"stanford_bunny_bun_zipper.ply", "fandisk.ply", "mech_holes_shark.ply"};

void BM_FeatureSimplify(benchmark::State& state) {
  const conelod::IndexedMesh& m = Mesh(kMeshes[state.range(0)]);
  conelod::FeatureSimplifyParams p;
  p.targetFaceCount = m.faceCount() * size_t(state.range(1)) / 100;
  p.growErrorBound = state.range(2) != 0;
  p.threads = unsigned(state.range(3));
  size_t out = 0;
  for (auto _ : state) {
    conelod::FeatureSimplifyResult r;
    if (!conelod::FeatureSimplify(m, p, r).ok()) state.SkipWithError("failed");
    out = r.facesOut;
  }
  state.SetLabel(std::string(kMeshes[state.range(0)]) + " -> " + std::to_string(out) + " faces" +
                 (p.growErrorBound ? "" : " (paper order)") + (p.threads == 1 ? ", 1 thread" : ""));
  state.counters["faces_per_s"] =
      benchmark::Counter(double(m.faceCount()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_FeatureSimplify)
    ->Args({0, 10, 1, 0})
    ->Args({0, 10, 1, 1})
    ->Args({0, 50, 1, 0})
    ->Args({0, 10, 0, 0})
    ->Args({0, 50, 0, 0})
    ->Args({1, 10, 1, 0})
    ->Args({2, 10, 1, 0})
    ->MeasureProcessCPUTime()
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

void BM_DetectFeatures(benchmark::State& state) {
  const conelod::IndexedMesh& m = Mesh(kMeshes[state.range(0)]);
  conelod::FeatureSimplifyParams p;
  for (auto _ : state) {
    conelod::FeatureInfo info;
    if (!conelod::DetectFeatures(m, p, info).ok()) state.SkipWithError("failed");
  }
  state.SetLabel(kMeshes[state.range(0)]);
}
BENCHMARK(BM_DetectFeatures)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// args: width, height (worst of the six axis directions, the bunny)
void BM_PixelBudget(benchmark::State& state) {
  const conelod::IndexedMesh& m = Mesh(kMeshes[0]);
  conelod::PixelBudgetParams p;
  p.width = int(state.range(0));
  p.height = int(state.range(1));
  size_t pixels = 0;
  for (auto _ : state) {
    conelod::PixelBudgetResult r;
    if (!conelod::ComputePixelBudget(m, p, r).ok()) state.SkipWithError("failed");
    pixels = r.coveredPixels;
  }
  state.SetLabel(std::to_string(pixels) + " pixels, 6 views");
}
BENCHMARK(BM_PixelBudget)->Args({1920, 1080})->Args({800, 600})->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
