// ConeLOD — libFuzzer target for the PLY input path (ply_format.h): any byte string must be read or
// refused with a message, never crash, read out of bounds or allocate more than the input
// justifies. A mesh that is read goes on as every command takes it: the input check
// (RequireValidForFaces), then the normal-cone grouping. Built and run by scripts/fuzz.sh (clang++
// -fsanitize=fuzzer,address,undefined) with seeds from tests/integration/bad_inputs.py and small
// generated meshes.
#include <cstddef>
#include <cstdint>
#include <string>

#include "conelod/grouping/cone_grouping.h"
#include "conelod/mesh/mesh_check.h"
#include "conelod/mesh/ply_format.h"

using namespace conelod;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  PlyMesh ply;
  if (!ParsePly(reinterpret_cast<const char*>(data), size, "fuzz.ply", ply).empty()) return 0;
  if (ply.triangles.size() > 20000) return 0;  // keep each run fast: the reader is what is fuzzed
  IndexedMesh mesh;
  for (const auto& p : ply.positions) mesh.positions.emplace_back(p[0], p[1], p[2]);
  mesh.faces.assign(ply.triangles.begin(), ply.triangles.end());
  if (!RequireValidForFaces(mesh).ok()) return 0;
  ConeGroupingParams params;
  params.maxLevels = 3;
  GroupHierarchy hierarchy;
  BuildConeHierarchy(mesh, params, hierarchy);
  return 0;
}
