// ConeLOD benchmark — the recursive PCA partition (pca_partition.h): time to build the full tree
// (down to single triangles) and its memory against the loaded mesh, on the bunny and the dragon
// of the paper's Table 1 (paper: 1.992 s and 23.125 s on a 2 GHz Pentium 4).
//
//   bench_partition [--benchmark_filter=dragon]      (meshes: CONELOD_TEST_MESHES or the built-in path)
//
// Counters: faces; nodes; depth; tree_MB (the tree's arrays); peak_extra_MB (the most heap the
// build held at once, tree and work arrays, counted by the replaced operator new below); mesh_MB
// (the heap the loaded mesh holds as the CLI keeps it: the vcg mesh plus the indexed copy the core
// runs on) with vcg_mesh_MB and indexed_MB apart; the ratios peak/mesh and tree/mesh. One thread.
#include <benchmark/benchmark.h>

#include <malloc.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <new>
#include <string>

#include "conelod/pca/pca_partition.h"
#include "conelod/vcg_bridge.h"
#include "conelod/vcg_mesh.h"

namespace {

std::string MeshPath(const std::string& name) {
  const char* env = std::getenv("CONELOD_TEST_MESHES");
  return std::string(env ? env : CONELOD_BENCH_MESHES) + "/" + name;
}

// Heap accounting: every C++ allocation of the process goes through these.
std::atomic<size_t> g_heap{0}, g_peak{0};
size_t HeapNow() { return g_heap.load(); }
void ResetPeak() { g_peak = g_heap.load(); }
size_t Peak() { return g_peak.load(); }

struct Loaded {
  conelod::CMesh mesh;
  conelod::IndexedMesh indexed;
  double meshBytes = 0, indexedBytes = 0;  // heap held by each
};

// Meshes stay loaded across benchmarks (loading the dragon takes longer than building its tree).
Loaded* Load(const std::string& name) {
  static std::map<std::string, std::unique_ptr<Loaded>> cache;
  auto& slot = cache[name];
  if (!slot) {
    slot.reset(new Loaded);
    const size_t before = HeapNow();
    const std::string err = conelod::LoadPly(slot->mesh, MeshPath(name));
    if (!err.empty()) {
      std::fprintf(stderr, "%s\n", err.c_str());
      std::exit(1);
    }
    const size_t loaded = HeapNow();
    slot->indexed = conelod::ToIndexedMesh(slot->mesh);
    slot->meshBytes = double(loaded - before);
    slot->indexedBytes = double(HeapNow() - loaded);
  }
  return slot.get();
}

void FullTree(benchmark::State& state, const std::string& name) {
  Loaded* m = Load(name);
  conelod::PcaTree tree;
  double peakExtra = 0;
  for (auto _ : state) {
    tree = conelod::PcaTree();
    const size_t before = HeapNow();
    ResetPeak();
    const conelod::Status s = conelod::BuildPcaTree(m->indexed, conelod::PcaPartitionParams(), tree);
    peakExtra = double(Peak() - before);
    if (!s.ok()) {
      state.SkipWithError(s.message.c_str());
      return;
    }
    benchmark::DoNotOptimize(tree.nodes.data());
  }
  const double mb = 1.0 / (1024 * 1024);
  state.counters["faces"] = double(m->indexed.faceCount());
  state.counters["nodes"] = double(tree.nodes.size());
  state.counters["depth"] = tree.maxDepth;
  state.counters["tree_MB"] = double(tree.memoryBytes()) * mb;
  const double meshBytes = m->meshBytes + m->indexedBytes;
  state.counters["peak_extra_MB"] = peakExtra * mb;
  state.counters["mesh_MB"] = meshBytes * mb;
  state.counters["vcg_mesh_MB"] = m->meshBytes * mb;
  state.counters["indexed_MB"] = m->indexedBytes * mb;
  state.counters["peak_vs_mesh"] = peakExtra / meshBytes;
  state.counters["tree_vs_mesh"] = double(tree.memoryBytes()) / meshBytes;
  state.counters["faces_per_s"] =
      benchmark::Counter(double(m->indexed.faceCount()), benchmark::Counter::kIsIterationInvariantRate);
}

void CutAt1000(benchmark::State& state, const std::string& name) {
  Loaded* m = Load(name);
  conelod::PcaPartitionParams p;
  p.targetClusters = 1000;
  for (auto _ : state) {
    conelod::PcaTree tree;
    if (!conelod::BuildPcaTree(m->indexed, p, tree).ok()) {
      state.SkipWithError("failed");
      return;
    }
    benchmark::DoNotOptimize(tree.nodes.data());
  }
}

}  // namespace

BENCHMARK_CAPTURE(FullTree, bunny, std::string("stanford_bunny_bun_zipper.ply"))
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2);
BENCHMARK_CAPTURE(FullTree, dragon, std::string("stanford_dragon_vrip_binary.ply"))
    ->Unit(benchmark::kMillisecond)
    ->MinTime(5);
BENCHMARK_CAPTURE(CutAt1000, bunny, std::string("stanford_bunny_bun_zipper.ply"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(CutAt1000, dragon, std::string("stanford_dragon_vrip_binary.ply"))->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();

// The replaced global allocation functions (all other forms forward to these in libstdc++).
void* operator new(size_t n) {
  void* p = std::malloc(n ? n : 1);
  if (!p) throw std::bad_alloc();
  const size_t now = g_heap += malloc_usable_size(p);
  size_t peak = g_peak.load();
  while (now > peak && !g_peak.compare_exchange_weak(peak, now)) {
  }
  return p;
}
void operator delete(void* p) noexcept {
  if (!p) return;
  g_heap -= malloc_usable_size(p);
  std::free(p);
}
void operator delete(void* p, size_t) noexcept { operator delete(p); }
void* operator new[](size_t n) { return operator new(n); }
void operator delete[](void* p) noexcept { operator delete(p); }
void operator delete[](void* p, size_t) noexcept { operator delete(p); }
