// ConeLOD — the vcg mesh type of the command-line tool and the tests, with PLY load/save.
// (MeshLab's plugin uses MeshLab's own CMeshO instead; the core does not depend on either.)
#pragma once

#include <string>

#include <vcg/complex/complex.h>
#include "conelod/ply_io.h"

namespace conelod {

class CVertex;
class CFace;
struct CUsedTypes : public vcg::UsedTypes<vcg::Use<CVertex>::AsVertexType, vcg::Use<CFace>::AsFaceType> {};
// Per-vertex texture coordinates hold what a PLY file has per vertex or per face corner (a face
// list is read as vertices split by their coordinates, ply_io.h).
class CVertex : public vcg::Vertex<CUsedTypes, vcg::vertex::Coord3f, vcg::vertex::Normal3f, vcg::vertex::Qualityf,
                                   vcg::vertex::Color4b, vcg::vertex::TexCoord2f, vcg::vertex::BitFlags> {};
class CFace : public vcg::Face<CUsedTypes, vcg::face::VertexRef, vcg::face::Normal3f, vcg::face::Qualityf,
                               vcg::face::Color4b, vcg::face::BitFlags> {};
class CMesh : public vcg::tri::TriMesh<std::vector<CVertex>, std::vector<CFace>> {
 public:
  // vcglib 2020.09's ~TriMesh leaves named attributes allocated (its ClearAttributes call is
  // commented out): free them here.
  ~CMesh() { ClearAttributes(); }
};

// Loads a PLY through the checked reader (ply_io.h). Returns "" or the error message; messages of a
// file that could not be opened or read start with "cannot read" (IsReadFailure).
inline std::string LoadPly(CMesh& m, const std::string& path, int* loadMask = nullptr) {
  return LoadPlyChecked(m, path, loadMask);
}

// Saves a binary PLY with per-face quality and colour (plus `extraMask`), replacing `path` only
// when the file is complete (ply_io.h).
inline std::string SavePly(CMesh& m, const std::string& path, int extraMask = 0) {
  return SavePlySafely(m, path, vcg::tri::io::Mask::IOM_FACEQUALITY | vcg::tri::io::Mask::IOM_FACECOLOR | extraMask);
}

// The same, written and synced into `out` but not yet in place: `out.commit()` does that (for
// commands that write two files, both or neither).
inline std::string SavePlyUncommitted(CMesh& m, const std::string& path, SafeFile& out, int extraMask = 0) {
  return WritePlyUncommitted(m, path,
                             vcg::tri::io::Mask::IOM_FACEQUALITY | vcg::tri::io::Mask::IOM_FACECOLOR | extraMask, out);
}

}  // namespace conelod
