// ConeLOD CLI — `conelod info`: what the input checks see in a mesh.
#include <cstdio>

#include "cli_common.h"
#include "commands.h"
#include "conelod/mesh/mesh_check.h"

namespace conelod {
namespace cli {

const char* kInfoUsage =
    "conelod info IN.ply [--json]\n"
    "  Vertices, faces, components, border and non-manifold edges, and the problems the filters check.\n";

int CmdInfo(int argc, char** argv) {
  Args a(argc, argv, {}, {"--json"});
  if (!a.ok()) return Fail(kUsage, a.error() + "\n" + kInfoUsage);
  if (a.positional().size() != 1) return Fail(kUsage, std::string("expected one input mesh\n") + kInfoUsage);
  CMesh mesh;
  IndexedMesh im;
  std::vector<size_t> faceOf;
  const std::string err = LoadInput(a.positional()[0], mesh, im, faceOf);
  if (!err.empty()) return FailLoad(err);
  const MeshReport r = CheckMesh(im);
  const Status valid = RequireValidForFaces(r);
  if (a.has("--json")) {
    Json j;
    j.BeginObject()
        .field("input", a.positional()[0])
        .field("vertices", r.vertices)
        .field("faces", r.faces)
        .field("components", r.components)
        .field("border_edges", r.borderEdges)
        .field("non_manifold_edges", r.nonManifoldEdges)
        .field("unreferenced_vertices", r.unreferencedVertices)
        .field("degenerate_faces", r.degenerateFaces)
        .field("non_finite_vertices", r.nonFiniteVertices)
        .field("huge_vertices", r.hugeVertices)
        .field("bad_index_faces", r.badIndexFaces)
        .field("usable", valid.ok());
    if (!valid.ok()) j.field("problem", valid.message);
    j.EndObject();
    std::printf("%s\n", j.str().c_str());
  } else {
    std::printf(
        "%s\n  vertices %zu (unreferenced %zu, non-finite %zu)\n  faces %zu (zero-area %zu, bad index %zu)\n"
        "  components %d\n  border edges %zu\n  non-manifold edges %zu\n  %s%s\n",
        a.positional()[0].c_str(), r.vertices, r.unreferencedVertices, r.nonFiniteVertices, r.faces, r.degenerateFaces,
        r.badIndexFaces, r.components, r.borderEdges, r.nonManifoldEdges,
        valid.ok() ? "usable by the face filters" : "NOT usable: ", valid.ok() ? "" : valid.message.c_str());
  }
  return kOk;
}

}  // namespace cli
}  // namespace conelod
