// ConeLOD CLI — small helpers shared by the subcommands: argument parsing, JSON output, timing,
// loading a mesh into the core's form.
#pragma once

#include <chrono>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "conelod/grouping/cone_grouping.h"
#include "conelod/simplify/hierarchical_simplification.h"
#include "conelod/mesh/attributes.h"
#include "conelod/mesh/indexed_mesh.h"
#include "conelod/mesh/ply_format.h"
#include "conelod/vcg_bridge.h"
#include "conelod/vcg_mesh.h"

namespace conelod {
namespace cli {

// Exit codes: scripts tell a usage mistake from bad input from an I/O failure.
enum Exit { kOk = 0, kUsage = 1, kBadInput = 2, kIoError = 3, kOutOfMemory = 4 };

// "--name value" and "--flag" options plus positional arguments. Options are declared up front
// so that a misspelt option is an error, not silently ignored.
class Args {
 public:
  Args(int argc, char** argv, const std::vector<std::string>& valueOptions,
       const std::vector<std::string>& flagOptions);
  bool ok() const { return error_.empty(); }
  const std::string& error() const { return error_; }
  const std::vector<std::string>& positional() const { return positional_; }
  bool has(const std::string& name) const { return values_.count(name) > 0; }
  std::string str(const std::string& name, const std::string& def = "") const;
  // Numeric getters record an error (see ok()) when the value does not parse.
  double num(const std::string& name, double def);
  int integer(const std::string& name, int def);

 private:
  std::map<std::string, std::string> values_;
  std::vector<std::string> positional_;
  std::string error_;
};

// A flat JSON object writer: enough for our outputs (numbers, strings, bools, arrays of objects).
class Json {
 public:
  Json& key(const std::string& k);
  Json& value(double v);
  Json& precise(double v);  // all 17 digits (a value a reader must reproduce bit for bit)
  Json& value(long long v);
  Json& value(int v) { return value((long long)v); }
  Json& value(size_t v) { return value((long long)v); }
  Json& value(bool v);
  Json& value(const std::string& v);
  Json& value(const char* v) { return value(std::string(v)); }
  Json& BeginObject();
  Json& EndObject();
  Json& BeginArray();
  Json& endArray();
  template <class T>
  Json& field(const std::string& k, const T& v) {
    return key(k).value(v);
  }
  const std::string& str() const { return out_; }

 private:
  void separator();
  std::string out_;
  std::vector<bool> first_{true};
  bool afterKey_ = false;
};

class Timer {
 public:
  Timer() : start_(std::chrono::steady_clock::now()) {}
  double seconds() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }

 private:
  std::chrono::steady_clock::time_point start_;
};

// Loads `path` into `mesh` and its indexed form (`loadMask`: LoadPly's). Returns "" or an error message.
std::string LoadInput(const std::string& path, CMesh& mesh, IndexedMesh& indexed, std::vector<size_t>& faceOfIndex,
                      int* loadMask = nullptr);

// AttributesOf and CornerAttributes below for the file's data as LoadPlyData (ply_io.h) gives it (the values
// are those of LoadPly's mesh: colours as bytes); `triangles`: the file's faces (ply.triangles,
// which the caller may have moved elsewhere).
VertexAttributes AttributesOf(const PlyMesh& ply, int loadMask);
std::vector<float> CornerAttributes(const std::vector<std::array<uint32_t, 3>>& triangles,
                                    const VertexAttributes& perVertex);
// The attributes a loaded mesh keeps from its file (`loadMask` from LoadPly), as float channels per
// live vertex in ToIndexedMesh's order: colour (RGB, or RGBA when some alpha is not 255), normals,
// texture coordinates. Empty (no channel) for a geometry-only file.
VertexAttributes AttributesOf(const CMesh& mesh, int loadMask);
// The attribute values of each face corner of the faces `faceOf` lists (3 f + k), from the
// attributes of the vertices they use (`perVertex`: AttributesOf's result).
std::vector<float> CornerAttributes(const CMesh& mesh, const std::vector<size_t>& faceOf,
                                    const VertexAttributes& perVertex);
// Gives face i's corner k of `mesh` (compacted) the values corner[(3 i + k) * channels]: a vertex
// whose corners differ (a seam) is repeated, once per distinct value.
void SetCornerAttributes(CMesh& mesh, const VertexAttributes& layout, const std::vector<float>& corner);
// "colour, normals, texture coordinates" (what `layout` holds), for messages.
std::string DescribeAttributes(const VertexAttributes& layout);

int Fail(int code, const std::string& message);  // prints "conelod: message" to stderr
// Fail for a LoadInput/LoadPly error: kIoError when the file could not be read, kBadInput when it
// was read and is malformed.
int FailLoad(const std::string& message);
// "" when every output the command line names can be written (checked before the work starts:
// safe_file.h's CheckOutputPath on -o and --mask; `simplify --hierarchy -o P` writes P_L1.ply, ...).
std::string CheckOutputs(const std::string& command, int argc, char** argv);

// The grouping options shared by `group`, `cull-cost` and `lod build`.
extern const std::vector<std::string> kGroupingOptions;
ConeGroupingParams ReadGroupingParams(Args& a);
// --threads N (0 = one per core, at most 1024; `fallback` when absent): "" or the error to print.
std::string ReadThreadsOption(Args& a, int fallback, int& threads);
// --threads N (as above) and --faces-per-part P (>= 0; `zeroMeans` says what 0 does), the
// current values as fallbacks, changed only when both are valid. Returns "" or a usage message.
std::string ReadPartsOptions(Args& a, int& threads, size_t& facesPerPart, const char* zeroMeans);
// The same for the hierarchical simplification, shared by `lod build` and `simplify --hierarchy`.
std::string ReadPartsOptions(Args& a, HierarchicalSimplificationParams& p);
std::vector<std::string> With(std::vector<std::string> v, const std::vector<std::string>& more);  // v + more

}  // namespace cli
}  // namespace conelod
