// ConeLOD doc tool — the accuracy of `conelod simplify` in parts (partitioned_simplify.h) against
// the serial run, at the same target, groups and options (docs/group_qem.md, "Big meshes in
// parts"). Loads the mesh, welds it, groups it at the automatic cone level for the target (as
// `--groups cone:auto`), runs SimplifyPreservingGroups and SimplifyPartitioned (forced into parts
// with about --faces-per-part faces each), and prints one JSON line: faces, seconds, the larger RMS
// of the two one-sided sampled distances to the input (% of the input's diagonal) of each, their
// ratio, and the group integrity of the parts' result.
//
//   partition_accuracy MESH.ply --target-ratio F [--faces-per-part P] [--threads N] [--samples S]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "conelod/grouping/cone_grouping.h"
#include "conelod/mesh/sampled_distance.h"
#include "conelod/simplify/group_integrity.h"
#include "conelod/simplify/partitioned_simplify.h"
#include "conelod/vcg_bridge.h"
#include "conelod/vcg_mesh.h"

using namespace conelod;

namespace {

double Rms(const IndexedMesh& input, const IndexedMesh& out, int samples) {
  HausdorffResult h;
  if (!SampledHausdorff(input, out, samples, h).ok() || h.diagonal <= 0) return -1;
  return h.rmsPct();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: partition_accuracy MESH.ply --target-ratio F [--faces-per-part P] [--threads N] "
                 "[--samples S]\n");
    return 1;
  }
  double ratio = 0.1;
  PartitionParams pp;
  pp.minFaces = 1;
  int samples = 1000000;
  for (int i = 2; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--target-ratio"))
      ratio = std::atof(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--faces-per-part"))
      pp.facesPerPart = size_t(std::atol(argv[i + 1]));
    else if (!std::strcmp(argv[i], "--threads"))
      pp.threads = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--samples"))
      samples = std::atoi(argv[i + 1]);
    else {
      std::fprintf(stderr, "partition_accuracy: unknown option %s\n", argv[i]);
      return 1;
    }
  }
  if (!(ratio > 0 && ratio <= 1) || pp.facesPerPart == 0 || samples <= 0) {
    std::fprintf(stderr, "partition_accuracy: bad option value\n");
    return 1;
  }
  CMesh cm;
  const std::string err = LoadPly(cm, argv[1]);
  if (!err.empty()) {
    std::fprintf(stderr, "partition_accuracy: %s\n", err.c_str());
    return 2;
  }
  const IndexedMesh m = ToWeldedIndexedMesh(cm);
  cm.Clear();
  // As the CLI: ranked passes, memoryless steps, components may go, flips to unblock.
  GroupQemParams q = OneTargetParams(std::max<size_t>(1, size_t(ratio * double(m.faces.size()))));
  GroupHierarchy h;
  if (!BuildConeHierarchy(m, CollapseGroupingParams(q.targetFaces, true, 0), h).ok()) return 2;  // as cone:auto
  const int level = AutoGroupLevel(h, q.targetFaces);
  const std::vector<int> groups = h.level(level).faceGroup;
  h = GroupHierarchy();

  GroupQemResult serial, parts;
  PartitionStats st;
  auto t0 = std::chrono::steady_clock::now();
  if (!SimplifyPreservingGroups(m, groups, q, serial).ok()) return 2;
  auto t1 = std::chrono::steady_clock::now();
  if (!SimplifyPartitioned(m, groups, q, pp, parts, Progress(), &st).ok()) return 2;
  auto t2 = std::chrono::steady_clock::now();
  std::vector<int> after(parts.sourceFace.size());
  for (size_t f = 0; f < after.size(); ++f) after[f] = groups[parts.sourceFace[f]];
  GroupIntegrity gi;
  MeasureGroupIntegrity(m, groups, parts.mesh, after, gi);
  const double rs = Rms(m, serial.mesh, samples), rp = Rms(m, parts.mesh, samples);
  std::printf(
      "{\"mesh\": \"%s\", \"faces_in\": %zu, \"target\": %zu, \"group_level\": %d, \"parts\": %d, "
      "\"frozen_vertices\": %zu, \"faces_after_parts\": %zu, \"serial_faces\": %zu, \"parts_faces\": %zu, "
      "\"serial_seconds\": %.2f, \"parts_seconds\": %.2f, \"serial_rms_pct\": %.6f, \"parts_rms_pct\": %.6f, "
      "\"rms_ratio\": %.4f, \"groups_split\": %d, \"groups_vanished\": %d, \"groups_removed\": %zu}\n",
      argv[1], m.faces.size(), q.targetFaces, level, st.parts, st.frozenVertices, st.facesAfterParts,
      serial.mesh.faces.size(), parts.mesh.faces.size(), std::chrono::duration<double>(t1 - t0).count(),
      std::chrono::duration<double>(t2 - t1).count(), rs, rp, rp / rs, gi.groupsSplit, gi.groupsVanished,
      parts.stats.groupsRemoved);
  return 0;
}
