// The .clod writer's time and CPU time at several thread counts, on one DAG (built once): the
// figures of docs/scale.md ("Threading"). Each round writes the file once per thread
// count (in turn, so that the machine's load falls on each alike) and checks that every file is
// the first one byte for byte. With --memory SIZE the DAG's levels are spilled to a temporary
// folder beside OUT (as `conelod lod build --memory` spills them) and the file is written from there.
//   lod_write_bench IN.ply OUT.clod [--memory SIZE_MB] [--rounds R] [--threads 1,2,...]
#include <sys/resource.h>

#include <time.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "conelod/lod/lod_build.h"
#include "conelod/lod/lod_spill.h"
#include "conelod/mesh/ply_format.h"
#include "conelod/mesh/weld.h"

using namespace conelod;

namespace {

double CpuSeconds() {
  rusage u;
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

// The calling thread's: the writer's serial part and its share of the parallel work (the wall
// time it would take on an idle machine, give or take the waits at the windows' ends).
double ThreadCpuSeconds() {
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

std::vector<char> ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<char>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3 || (argc - 3) % 2 != 0) {
    std::fprintf(stderr,
                 "usage: lod_write_bench IN.ply OUT.clod [--memory SIZE_MB] [--rounds R] [--threads 1,2,...]\n");
    return 2;
  }
  const std::string input = argv[1], output = argv[2];
  uint64_t memoryMb = 0;
  int rounds = 3;
  std::vector<int> threads = {1, 2};
  for (int i = 3; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--memory")) {
      memoryMb = std::strtoull(argv[i + 1], nullptr, 10);
    } else if (!std::strcmp(argv[i], "--rounds")) {
      rounds = std::atoi(argv[i + 1]);
    } else if (!std::strcmp(argv[i], "--threads")) {
      threads.clear();
      std::stringstream list(argv[i + 1]);
      for (std::string t; std::getline(list, t, ',');) threads.push_back(std::atoi(t.c_str()));
    } else {
      std::fprintf(stderr, "lod_write_bench: unknown option %s\n", argv[i]);
      return 2;
    }
  }
  if (std::ifstream(output).good()) {  // written and removed each round: never someone's file
    std::fprintf(stderr, "lod_write_bench: %s exists; give a new path\n", output.c_str());
    return 2;
  }
  if (rounds < 1 || threads.empty()) {
    std::fprintf(stderr, "lod_write_bench: --rounds and --threads need positive values\n");
    return 2;
  }
  PlyMesh ply;
  const std::string err = ReadPly(input, ply);
  if (!err.empty()) {
    std::fprintf(stderr, "lod_write_bench: %s\n", err.c_str());
    return 2;
  }
  IndexedMesh m;
  for (const auto& p : ply.positions) m.positions.emplace_back(p[0], p[1], p[2]);
  m.faces = ply.triangles;
  ply = PlyMesh();
  IndexedMesh welded = WeldByPosition(m).mesh;
  m = IndexedMesh();
  const size_t inputVertices = welded.positions.size(), inputFaces = welded.faces.size();
  const vcg::Box3d box = UsedVertexBox(welded);
  LodBuildParams params;
  params.simplification.threads = 0;
  params.chunkFaces = LodChunkFacesForMemory(memoryMb << 20);
  LodSpill spill;
  if (params.chunkFaces > 0) {
    const std::string e = spill.create(output);
    if (!e.empty()) {
      std::fprintf(stderr, "lod_write_bench: %s\n", e.c_str());
      return 1;
    }
  }
  LodDag dag;
  size_t chunks = 1;
  Status s =
      BuildLodDagOwned(std::move(welded), params, dag, Progress(), &chunks, params.chunkFaces > 0 ? &spill : nullptr);
  if (!s.ok()) {
    std::fprintf(stderr, "lod_write_bench: %s\n", s.message.c_str());
    return 1;
  }
  std::printf("%s: %zu faces, %zu chunks, %s\n", input.c_str(), inputFaces, chunks,
              params.chunkFaces > 0 ? "levels spilled" : "levels in memory");
  std::vector<char> first;
  int status = 0;
  for (int r = 0; r < rounds; ++r)
    for (int t : threads) {
      std::remove(output.c_str());
      const auto t0 = std::chrono::steady_clock::now();
      const double c0 = CpuSeconds(), m0 = ThreadCpuSeconds();
      s = WriteLodFileFrom(dag, params.chunkFaces > 0 ? &spill : nullptr, inputVertices, inputFaces, box, output,
                           nullptr, Progress(), params.precision, t);
      const double cpu = CpuSeconds() - c0, mainCpu = ThreadCpuSeconds() - m0;
      const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (!s.ok()) {
        std::fprintf(stderr, "lod_write_bench: %s\n", s.message.c_str());
        return 1;
      }
      std::vector<char> bytes = ReadBytes(output);
      if (first.empty()) first = bytes;
      const bool same = bytes == first;
      if (!same) status = 1;
      std::printf("round %d threads %d: write %.3f s, CPU %.3f s (calling thread %.3f s), %zu bytes%s\n", r, t, wall,
                  cpu, mainCpu, bytes.size(), same ? "" : " DIFFERENT");
      std::fflush(stdout);
    }
  std::remove(output.c_str());
  return status;
}
