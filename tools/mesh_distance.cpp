// ConeLOD doc tool — the sampled distance, both ways, between an input mesh and results made from
// it (sampled_distance.h, in-process): for each RESULT, the larger RMS and the larger maximum of
// the two directions, in % of the input's bounding-box diagonal, one JSON line each. For the cases
// where MeshLab's Hausdorff Distance aborts (scripts/compare_qem.sh's measure on meshopt_simplify's
// 2 % dragon; docs/group_qem.md).
//
//   mesh_distance INPUT.ply RESULT.ply... [--samples N]   (N face samples a way [300000])
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "conelod/mesh/sampled_distance.h"
#include "conelod/vcg_bridge.h"
#include "conelod/vcg_mesh.h"

using namespace conelod;

namespace {

bool Load(const char* path, IndexedMesh& out) {
  CMesh m;
  const std::string err = LoadPly(m, path);
  if (!err.empty()) {
    std::fprintf(stderr, "mesh_distance: %s\n", err.c_str());
    return false;
  }
  out = ToIndexedMesh(m);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<const char*> files;
  int samples = 300000;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--samples") && i + 1 < argc)
      samples = std::atoi(argv[++i]);
    else
      files.push_back(argv[i]);
  }
  if (files.size() < 2 || samples <= 0 || samples > kMaxFaceSamples) {
    std::fprintf(stderr, "usage: mesh_distance INPUT.ply RESULT.ply... [--samples N (1..%d)]\n", kMaxFaceSamples);
    return 1;
  }
  IndexedMesh input;
  if (!Load(files[0], input)) return 2;
  for (size_t i = 1; i < files.size(); ++i) {
    IndexedMesh result;
    if (!Load(files[i], result)) return 2;
    HausdorffResult h;
    const Status s = SampledHausdorff(input, result, samples, h);
    if (!s.ok() || !(h.diagonal > 0)) {
      std::fprintf(stderr, "mesh_distance: %s: %s\n", files[i], s.ok() ? "no extent" : s.message.c_str());
      return 2;
    }
    std::printf("{\"file\": \"%s\", \"faces\": %zu, \"rms_pct\": %.6f, \"max_pct\": %.6f}\n", files[i],
                result.faces.size(), h.rmsPct(), h.maxPct());
  }
  return 0;
}
