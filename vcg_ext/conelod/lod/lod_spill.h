// ConeLOD — the out-of-core LOD build's temporary folder (issue 27; docs/scale.md): the finished
// levels of the cluster DAG are spilled there as soon as the level above them is built, and the
// writer reads them back one at a time, so the faces of only one or two levels are in memory at
// once. Internal to lod_dag.cpp / lod_writer.cpp (BuildLodFile with LodBuildParams::chunkFaces).
//
// The folder is `.NAME.conelod-lod-PID.XXXXXX` beside the output NAME (mkdtemp). It is removed
// with everything in it when the LodSpill is destroyed: after success, after a failure, when an
// exception unwinds through the build; RemoveLodSpillsOnSignal() removes it from a signal handler
// (`conelod lod build` calls it on SIGINT, SIGTERM and SIGHUP). Only SIGKILL leaves it behind.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <vcg/space/box3.h>

#include "conelod/lod/lod_build.h"
#include "conelod/status.h"

namespace conelod {

class LodSpill {
 public:
  LodSpill() = default;
  LodSpill(const LodSpill&) = delete;
  LodSpill& operator=(const LodSpill&) = delete;
  ~LodSpill() { remove(); }

  // Creates the folder beside `outputPath`. "" or "cannot write 'FOLDER': why".
  std::string create(const std::string& outputPath);
  const std::string& folder() const { return folder_; }
  // Removes the level files and the folder (nothing when never created).
  void remove();

  // Writes level k's faces and faceCluster to the folder and frees them in L (its per-cluster
  // fields stay); also records the box of the positions its faces use (the writer's grid).
  Status put(size_t k, LodDag::Level& L, const std::vector<vcg::Point3f>& positions);
  bool has(size_t k) const { return k < faces_.size() && faces_[k] != kNone; }
  uint64_t faceCount(size_t k) const { return faces_[k]; }
  const vcg::Box3f& box(size_t k) const { return boxes_[k]; }
  // Reads level k's faces and faceCluster back: all of them, or those of one part (a level
  // written by put() has one part; one written by append(), a part per call).
  Status get(size_t k, std::vector<std::array<uint32_t, 3>>& faces, std::vector<uint32_t>& faceCluster) const;
  Status get(size_t k, size_t part, std::vector<std::array<uint32_t, 3>>& faces,
             std::vector<uint32_t>& faceCluster) const;
  size_t parts(size_t k) const { return k < partEnds_.size() && !partEnds_[k].empty() ? partEnds_[k].size() : 1; }

  // The streamed build (BuildLodFileFromPly): level k written a part at a time (append, then
  // finish once before get), and the other files it keeps in the folder: the input's faces as
  // read (raw()) and one file of faces per kd chunk (chunk(i), i < chunks()).
  Status append(size_t k, const std::vector<std::array<uint32_t, 3>>& faces, const std::vector<uint32_t>& faceCluster,
                const std::vector<vcg::Point3f>& positions);
  Status finish(size_t k);
  // Faces [begin, end) of a finished level k, with their faceCluster.
  Status get(size_t k, uint64_t begin, uint64_t end, std::vector<std::array<uint32_t, 3>>& faces,
             std::vector<uint32_t>& faceCluster) const;
  // Redraws level k's parts: their ends (increasing, the last one faceCount(k)), so that each part
  // holds whole groups (the writer reads a level a part at a time).
  Status setParts(size_t k, const std::vector<uint64_t>& ends);
  // Forgets level k and removes its file (the DAG holds it again, or it is built anew).
  void drop(size_t k);
  std::string raw() const { return folder_ + "/R"; }
  void setChunks(size_t n);
  size_t chunks() const { return chunks_; }
  std::string chunk(size_t i) const;

 private:
  static constexpr uint64_t kNone = ~uint64_t(0);
  std::string file(size_t k) const;
  std::string folder_;
  std::vector<uint64_t> faces_;
  std::vector<vcg::Box3f> boxes_;
  size_t chunks_ = 0;
  std::vector<std::vector<uint64_t>> partEnds_;  // per level written by append(): each part's end
  std::string clusters(size_t k) const;          // append's faceCluster side file of level k
};

// BuildLodDag of a mesh it takes (its positions and faces become the DAG's level 0 without a
// copy; `mesh` is left empty), spilling each finished level to `spill` when given (its faces are
// then in the spill, not in the DAG). The DAG is the one BuildLodDag builds from the same mesh
// (with the same `attributes`, per vertex of `mesh`, optional).
Status BuildLodDagOwned(IndexedMesh&& mesh, const LodBuildParams& params, LodDag& out, const Progress& progress,
                        size_t* chunks, LodSpill* spill, const LodAttributes* attributes = nullptr);

// The streamed build's DAG (BuildLodFileFromPly, lod_stream.cpp): the welded input's faces are in
// the spill's chunk files (chunk(i): the faces of kd chunk i, global vertex ids, in input order),
// never whole in memory. Each chunk's level-0 clusters, groups and level-1 faces are made from
// its file on its own, chunk after chunk (its groups side by side on the threads), and its level
// 0 and its level 1 go to the spill. Each level above is then built from the spill a kd chunk at a
// time too (its faces read back, grouped and simplified alone, frozen where another chunk uses
// them), while the chunks have not merged into one; from there on as BuildLodDag builds them. The chunks
// are kd leaves at one depth, numbered as KdChunks numbers them, so that with the same chunks the
// DAG is BuildLodDag's with the same chunkFaces (a level 0 that does not shrink is kept, where
// BuildLodDag would merge the chunks and build it again).
struct LodChunkedInput {
  std::vector<vcg::Point3f> positions;  // the welded input's, every one used (taken)
  std::vector<uint8_t> border;          // per vertex: nonzero when faces of two chunks use it (taken)
  std::vector<uint64_t> chunkFaces;     // faces per chunk file: 2^depth chunks
  int depth = 0;
  size_t inputFaces = 0;
  vcg::Box3d box;  // of positions
};
Status BuildLodDagFromChunks(LodChunkedInput& in, const LodBuildParams& params, LodDag& out, const Progress& progress,
                             LodSpill& spill);

// WriteLodFile of a DAG whose levels may be in `spill` (null: all in the DAG): the same bytes (threads:
// WriteLodFile's). inputVertices: the DAG's input vertices (all used); box: their box (UsedVertexBox).
Status WriteLodFileFrom(const LodDag& dag, const LodSpill* spill, size_t inputVertices, size_t inputFaces,
                        const vcg::Box3d& box, const std::string& path, LodBuildStats* stats, const Progress& progress,
                        double precision, int threads);

// Async-signal-safe: removes the level files and the folder of the spill being used, if any.
void RemoveLodSpillsOnSignal();

}  // namespace conelod
