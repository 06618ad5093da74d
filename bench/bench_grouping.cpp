// ConeLOD — benchmark of BuildConeHierarchy on real meshes: speed (faces/s, real time and CPU
// time, per thread count) and memory (peak RSS growth of the build against the RSS growth of
// loading the mesh).
//
// Usage: bench_grouping [google-benchmark flags] [--threads N[,M...]] [MESH.ply...]   (threads [1,2])
//   default meshes: <repo>/../shared/test_meshes/{stanford_bunny_bun_zipper,stanford_dragon_vrip_binary}.ply
//
// Memory is read from /proc/self/status. "Loaded mesh" is what loading costs in a real caller: the
// vcg mesh (LoadPly) plus the core's IndexedMesh (ToIndexedMesh), both kept alive. A build's peak
// is VmHWM after it minus VmRSS before it, the high-water mark having been reset by writing "5"
// to /proc/self/clear_refs (outside the timed region); it includes the GroupHierarchy being
// built, and the largest over the iterations is reported. Freed heap is handed back to the
// system (malloc_trim) before every reading, so that memory freed by an earlier step does not
// hide the growth of the next one. Target: build peak < 2x loaded mesh.
#include <malloc.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "conelod/grouping/cone_grouping.h"
#include "conelod/process_memory.h"
#include "conelod/vcg_bridge.h"
#include "conelod/vcg_mesh.h"

namespace {

using namespace conelod;

double SettledRss() {
  malloc_trim(0);
  return double(ProcessStatusBytes("VmRSS"));
}

bool ResetPeakRss() {
  std::ofstream out("/proc/self/clear_refs");
  out << "5";
  out.close();
  return bool(out);
}

struct Loaded {
  std::string path, name;
  CMesh vcgMesh;
  IndexedMesh mesh;
  double loadBytes = 0;     // RSS growth of LoadPly + ToIndexedMesh
  double indexedBytes = 0;  // the IndexedMesh's own arrays
  std::string error;
  // Results of the last benchmark run on this mesh, per thread count.
  struct Result {
    bool ran = false, peakReset = false;
    int levels = 0, level1Groups = 0;
    double secondsPerBuild = 0, cpuSecondsPerBuild = 0, facesPerSecond = 0, buildPeakBytes = 0;
  };
  std::map<int, Result> results;
};

double ProcessCpuSeconds() {
  rusage u;
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

void BM_BuildConeHierarchy(benchmark::State& state, Loaded* m, int threads) {
  ConeGroupingParams params;
  params.chunkFaces = kGroupingChunkFaces;  // as `conelod group`
  params.threads = threads;
  Loaded::Result& r = m->results[threads];
  double seconds = 0, cpu = 0, peak = 0;
  for (auto _ : state) {
    // Memory is measured per build, outside the timed region: heap left over by the previous
    // iteration is handed back first, so each build's growth is its own.
    state.PauseTiming();
    const double rssBefore = SettledRss();
    r.peakReset = ResetPeakRss();
    state.ResumeTiming();
    GroupHierarchy h;
    const double cpu0 = ProcessCpuSeconds();
    const auto t0 = std::chrono::steady_clock::now();
    const Status s = BuildConeHierarchy(m->mesh, params, h);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    cpu += ProcessCpuSeconds() - cpu0;
    state.PauseTiming();
    peak = std::max(peak, double(ProcessStatusBytes("VmHWM")) - rssBefore);
    state.ResumeTiming();
    if (!s.ok()) {
      m->error = s.message;
      state.SkipWithError(s.message.c_str());
      break;
    }
    r.levels = h.levelCount();
    r.level1Groups = h.levelCount() > 0 ? int(h.level(1).groups.size()) : 0;
  }
  if (!m->error.empty()) return;
  const double faces = double(m->mesh.faceCount());
  r.ran = true;
  r.secondsPerBuild = seconds / double(state.iterations());
  r.cpuSecondsPerBuild = cpu / double(state.iterations());
  r.facesPerSecond = faces / r.secondsPerBuild;
  r.buildPeakBytes = peak;
  state.counters["faces"] = faces;
  state.counters["faces_per_s"] = r.facesPerSecond;
  state.counters["cpu_ms"] = 1e3 * r.cpuSecondsPerBuild;
  state.counters["load_MiB"] = m->loadBytes / (1 << 20);
  state.counters["build_peak_MiB"] = peak / (1 << 20);
  state.counters["peak_over_load"] = m->loadBytes > 0 ? peak / m->loadBytes : 0;
}

std::string BaseName(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  const size_t dot = name.rfind('.');
  return dot == std::string::npos ? name : name.substr(0, dot);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);  // removes the --benchmark_* flags it knows
  // --threads N[,M...]: the thread counts to run (ConeGroupingParams::threads) [1,2].
  std::vector<int> threadCounts;
  std::vector<std::string> paths;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--threads" && i + 1 < argc) {
      std::stringstream list(argv[++i]);
      for (std::string item; std::getline(list, item, ',');) {
        char* end = nullptr;
        const long t = std::strtol(item.c_str(), &end, 10);
        if (item.empty() || *end || t < 0 || t > 1024) {
          std::fprintf(stderr, "bench_grouping: --threads takes counts from 0 (one per core) to 1024, as 1,2\n");
          return 1;
        }
        threadCounts.push_back(int(t));
      }
    } else {
      paths.push_back(arg);
    }
  }
  if (threadCounts.empty()) threadCounts = {1, 2};
  if (paths.empty()) {
    const std::string dir = std::string(CONELOD_SOURCE_DIR) + "/../shared/test_meshes/";
    paths = {dir + "stanford_bunny_bun_zipper.ply", dir + "stanford_dragon_vrip_binary.ply"};
  }

  std::vector<std::unique_ptr<Loaded>> meshes;
  for (const std::string& path : paths) {
    std::unique_ptr<Loaded> m(new Loaded);
    m->path = path;
    m->name = BaseName(path);
    const double before = SettledRss();
    const std::string err = LoadPly(m->vcgMesh, path);
    if (!err.empty()) {
      std::fprintf(stderr, "bench_grouping: %s\n", err.c_str());
      return 1;
    }
    m->mesh = ToIndexedMesh(m->vcgMesh);
    m->loadBytes = SettledRss() - before;
    m->indexedBytes = double(m->mesh.positions.capacity() * sizeof(m->mesh.positions[0]) +
                             m->mesh.faces.capacity() * sizeof(m->mesh.faces[0]));
    meshes.push_back(std::move(m));
  }
  for (auto& m : meshes)
    for (const int t : threadCounts)
      benchmark::RegisterBenchmark(("BuildConeHierarchy/" + m->name + "/threads:" + std::to_string(t)).c_str(),
                                   BM_BuildConeHierarchy, m.get(), t)
          ->UseRealTime()
          ->Unit(benchmark::kMillisecond)
          ->MinTime(3.0);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();

  std::printf(
      "\nBuildConeHierarchy, default parameters. Memory: RSS growth in MiB; target: build peak < 2x loaded "
      "mesh. CPU: user + system of the process per build.\n");
  std::printf("%-30s %7s %9s %7s %9s %12s %10s %10s %10s %11s %10s %7s\n", "mesh", "threads", "faces", "levels",
              "L1 groups", "ms/build", "CPU ms", "faces/s", "load MiB", "(indexed)", "peak MiB", "ratio");
  bool allOk = true;
  for (const auto& m : meshes) {
    if (!m->error.empty()) {
      std::printf("%-30s %s\n", m->name.c_str(), m->error.c_str());
      continue;
    }
    for (const int t : threadCounts) {
      const Loaded::Result& r = m->results[t];
      if (!r.ran) {
        std::printf("%-30s %7d not run (filtered out)\n", m->name.c_str(), t);
        continue;
      }
      const double ratio = m->loadBytes > 0 ? r.buildPeakBytes / m->loadBytes : 0;
      allOk = allOk && ratio < 2.0 && r.peakReset;
      std::printf("%-30s %7d %9zu %7d %9d %12.1f %10.1f %10.0f %10.1f %11.1f %10.1f %6.2fx%s\n", m->name.c_str(), t,
                  m->mesh.faceCount(), r.levels, r.level1Groups, 1e3 * r.secondsPerBuild, 1e3 * r.cpuSecondsPerBuild,
                  r.facesPerSecond, m->loadBytes / (1 << 20), m->indexedBytes / (1 << 20), r.buildPeakBytes / (1 << 20),
                  ratio, r.peakReset ? "" : "  (peak not reset: clear_refs failed)");
    }
  }
  std::printf("memory target (peak < 2x loaded mesh): %s\n", allOk ? "met" : "NOT met");
  return 0;
}
