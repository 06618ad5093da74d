// ConeLOD — libFuzzer target for the .clod reader (lod_read.h): any byte string must open cleanly or be
// refused with a Status, never crash, read out of bounds or allocate more than the input justifies.
// Opened inputs are refined at two budgets, for two eyes, and by the error in model units, extracted (with their
// attribute streams, version 5: one value per vertex, or the fuzzer stops), their texture image read, and their
// geometry evicted.
// Built and run by scripts/fuzz.sh (clang++ -fsanitize=fuzzer,address,undefined), with a seed
// corpus written by `conelod lod build` from small generated meshes.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "conelod/lod/lod_read.h"

using namespace conelod;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::unique_ptr<LodReader> reader;
  if (!LodReader::OpenMemory(std::vector<uint8_t>(data, data + size), reader).ok()) return 0;
  const LodFileInfo& info = reader->info();
  const vcg::Point3f c = info.box.Center();
  const double d = 3.0 * (info.box.Diag() + 1e-3);
  const vcg::Point3d eyes[2] = {vcg::Point3d(c[0], c[1], c[2] + d), vcg::Point3d(c[0] - d, c[1], c[2])};
  for (int i = 0; i < 3; ++i) {
    LodView view;
    view.eye = eyes[i % 2];
    view.faceBudget = i == 0 ? size_t(info.inputFaces / 4) : i == 1 ? size_t(1) << 40 : size_t(info.inputFaces / 3);
    view.cullBackFacing = i == 0;
    // The third: by the error in model units (its gain reads the records below each group, and
    // its fill undoes expansions: lod_refine.cpp).
    if (i == 2) view.priority = LodPriority::ObjectError;
    LodCut cut;
    if (!RefineLod(*reader, view, cut).ok()) return 0;
    IndexedMesh mesh;
    std::vector<int> level;
    LodAttributes attributes;
    if (!ExtractCutMesh(*reader, cut, i == 1, mesh, &level, nullptr, &attributes).ok()) return 0;
    if (attributes.colors.size() != (info.colors ? mesh.positions.size() : 0) ||
        attributes.normals.size() != (info.normals ? mesh.positions.size() : 0) ||
        attributes.texCoords.size() != (info.texCoords ? mesh.positions.size() : 0))
      __builtin_trap();  // a stream that does not match its vertices: a reader bug
    for (uint32_t id : cut.nodes) reader->EvictGeometry(id);
  }
  // The texture image (its TEXR chunk), when the file names one: read whole and checked.
  if (info.textureBytes) {
    LodTexture texture;
    if (reader->LoadTexture(texture).ok() && texture.bytes.size() != info.textureBytes) __builtin_trap();
  }
  // Random access by id, as a viewer would after a jump.
  for (uint64_t id = 0; id < info.nodeCount; id += 1 + info.nodeCount / 8) {
    if (!reader->LoadNode(uint32_t(id)).ok()) return 0;
    if (!reader->LoadChildren(uint32_t(id)).ok()) return 0;
    if (!reader->LoadGeometry(uint32_t(id)).ok()) return 0;
  }
  (void)reader->residentBytes();
  return 0;
}
