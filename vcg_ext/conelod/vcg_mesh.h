// ConeLOD — the vcg mesh type of the command-line tool and the tests, with PLY load/save.
// (MeshLab's plugin uses MeshLab's own CMeshO instead; the core does not depend on either.)
#pragma once

#include <string>

#include <vcg/complex/complex.h>
#include <wrap/io_trimesh/export_ply.h>
#include <wrap/io_trimesh/import_ply.h>

namespace conelod {

class CVertex;
class CFace;
struct CUsedTypes : public vcg::UsedTypes<vcg::Use<CVertex>::AsVertexType, vcg::Use<CFace>::AsFaceType> {};
class CVertex : public vcg::Vertex<CUsedTypes, vcg::vertex::Coord3f, vcg::vertex::Normal3f, vcg::vertex::Qualityf,
                                   vcg::vertex::Color4b, vcg::vertex::BitFlags> {};
class CFace : public vcg::Face<CUsedTypes, vcg::face::VertexRef, vcg::face::Normal3f, vcg::face::Qualityf,
                               vcg::face::Color4b, vcg::face::BitFlags> {};
class CMesh : public vcg::tri::TriMesh<std::vector<CVertex>, std::vector<CFace>> {
 public:
  // vcglib 2020.09's ~TriMesh leaves named attributes allocated (its ClearAttributes call is
  // commented out): free them here.
  ~CMesh() { ClearAttributes(); }
};

// Loads a PLY (or any format vcg's PLY importer reads). Returns "" or the error message.
inline std::string LoadPly(CMesh& m, const std::string& path, int* loadMask = nullptr) {
  int mask = 0;
  const int err = vcg::tri::io::ImporterPLY<CMesh>::Open(m, path.c_str(), mask);
  if (loadMask) *loadMask = mask;
  if (err != 0 && vcg::tri::io::ImporterPLY<CMesh>::ErrorCritical(err))
    return std::string("cannot read '") + path + "': " + vcg::tri::io::ImporterPLY<CMesh>::ErrorMsg(err);
  return "";
}

// Saves a binary PLY with per-face quality and colour (and vertex colour if the input had it).
inline std::string SavePly(CMesh& m, const std::string& path, int extraMask = 0) {
  const int mask = vcg::tri::io::Mask::IOM_FACEQUALITY | vcg::tri::io::Mask::IOM_FACECOLOR | extraMask;
  const int err = vcg::tri::io::ExporterPLY<CMesh>::Save(m, path.c_str(), mask, true);
  if (err != 0) return std::string("cannot write '") + path + "': " + vcg::tri::io::ExporterPLY<CMesh>::ErrorMsg(err);
  return "";
}

}  // namespace conelod
