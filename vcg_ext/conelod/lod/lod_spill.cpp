// ConeLOD — the out-of-core LOD build's temporary folder (lod_spill.h).
#include "conelod/lod/lod_spill.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>

namespace conelod {

constexpr uint64_t LodSpill::kNone;

namespace {

// The folder of the spill being used, for RemoveLodSpillsOnSignal (one at a time: a second spill
// while one is registered is removed by its destructor only).
char g_folder[4096];
std::atomic<int> g_registered(0);
std::atomic<size_t> g_chunks(0);  // chunk files K0 .. K(n-1) of the streamed build

void Name(char* out, const char* folder, char prefix, size_t i, bool number) {  // FOLDER/Xi, no snprintf
  size_t n = 0;
  while (folder[n]) {
    out[n] = folder[n];
    ++n;
  }
  out[n++] = '/';
  out[n++] = prefix;
  if (number) {
    char digits[24];
    int d = 0;
    do {
      digits[d++] = char('0' + i % 10);
      i /= 10;
    } while (i);
    while (d) out[n++] = digits[--d];
  }
  out[n] = 0;
}

void LevelName(char* out, const char* folder, int k) {  // FOLDER/Lkk, without snprintf
  size_t n = 0;
  while (folder[n]) {
    out[n] = folder[n];
    ++n;
  }
  out[n++] = '/';
  out[n++] = 'L';
  out[n++] = char('0' + k / 10);
  out[n++] = char('0' + k % 10);
  out[n] = 0;
}

struct FileCloser {
  void operator()(std::FILE* f) const {
    if (f) std::fclose(f);
  }
};

}  // namespace

void RemoveLodSpillsOnSignal() {
  int one = 1;
  if (!g_registered.compare_exchange_strong(one, 0)) return;
  char name[sizeof g_folder + 32];
  for (int k = 0; k < 64; ++k) {
    LevelName(name, g_folder, k);
    ::unlink(name);
  }
  Name(name, g_folder, 'R', 0, false);
  ::unlink(name);
  {
    size_t n = 0;
    while (name[n]) ++n;
    name[n] = 'W';  // FOLDER/RW: the welded positions on their way (lod_stream.cpp)
    name[n + 1] = 0;
    ::unlink(name);
  }
  for (size_t k = 0; k < 64; ++k) {
    Name(name, g_folder, 'C', k, true);
    ::unlink(name);
  }
  const size_t chunks = g_chunks.load();
  for (size_t i = 0; i < chunks; ++i) {
    Name(name, g_folder, 'K', i, true);
    ::unlink(name);
  }
  ::rmdir(g_folder);
}

std::string LodSpill::create(const std::string& outputPath) {
  remove();
  const size_t slash = outputPath.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "." : (slash == 0 ? "/" : outputPath.substr(0, slash));
  const std::string name = slash == std::string::npos ? outputPath : outputPath.substr(slash + 1);
  std::string pattern = dir + "/." + name + ".conelod-lod-" + std::to_string(long(::getpid())) + ".XXXXXX";
  std::vector<char> buf(pattern.begin(), pattern.end());
  buf.push_back(0);
  if (!::mkdtemp(buf.data()))
    return "cannot write '" + pattern + "' (the temporary folder of --memory): " + std::strerror(errno);
  folder_ = buf.data();
  int zero = 0;
  if (folder_.size() + 1 < sizeof g_folder && g_registered.load() == 0) {
    std::memcpy(g_folder, folder_.c_str(), folder_.size() + 1);
    g_registered.compare_exchange_strong(zero, 1);
  }
  return "";
}

void LodSpill::remove() {
  if (folder_.empty()) return;
  if (g_registered.load() && folder_ == g_folder) g_registered.store(0);
  for (size_t k = 0; k < faces_.size(); ++k)
    if (faces_[k] != kNone) std::remove(file(k).c_str());
  std::remove(raw().c_str());
  std::remove((raw() + "W").c_str());
  for (size_t k = 0; k < faces_.size(); ++k) std::remove(clusters(k).c_str());
  for (size_t i = 0; i < chunks_; ++i) std::remove(chunk(i).c_str());
  chunks_ = 0;
  partEnds_.clear();
  ::rmdir(folder_.c_str());
  folder_.clear();
  faces_.clear();
  boxes_.clear();
}

void LodSpill::setChunks(size_t n) {
  chunks_ = n;
  if (g_registered.load() && folder_ == g_folder) g_chunks.store(n);
}

std::string LodSpill::chunk(size_t i) const { return folder_ + "/K" + std::to_string(i); }

std::string LodSpill::clusters(size_t k) const { return folder_ + "/C" + std::to_string(k); }

Status LodSpill::setParts(size_t k, const std::vector<uint64_t>& ends) {
  if (!has(k) || ends.empty() || ends.back() != faces_[k] || !std::is_sorted(ends.begin(), ends.end()))
    return Status::Invalid("internal error: bad parts of a spilled LOD level");
  if (partEnds_.size() <= k) partEnds_.resize(k + 1);
  partEnds_[k] = ends;
  return Status::Ok();
}

void LodSpill::drop(size_t k) {
  if (!has(k)) return;
  std::remove(file(k).c_str());
  std::remove(clusters(k).c_str());
  faces_[k] = kNone;
  boxes_[k] = vcg::Box3f();
  if (k < partEnds_.size()) partEnds_[k].clear();
}

Status LodSpill::append(size_t k, const std::vector<std::array<uint32_t, 3>>& faces,
                        const std::vector<uint32_t>& faceCluster, const std::vector<vcg::Point3f>& positions) {
  if (folder_.empty() || k >= 64 || faces.size() != faceCluster.size())
    return Status::Invalid("internal error: a LOD level cannot be spilled");
  if (faces_.size() <= k) {
    faces_.resize(k + 1, kNone);
    boxes_.resize(k + 1);
  }
  if (faces_[k] == kNone) faces_[k] = 0;
  for (const auto& t : faces)
    for (uint32_t v : t) boxes_[k].Add(positions[v]);
  const size_t n = faces.size();
  const std::string a = file(k), b = clusters(k);
  std::unique_ptr<std::FILE, FileCloser> f(std::fopen(a.c_str(), "ab"));
  bool ok = f != nullptr;
  if (ok && n) ok = std::fwrite(faces.data(), sizeof faces[0], n, f.get()) == n;
  if (f && std::fclose(f.release()) != 0) ok = false;
  if (!ok) return Status::Invalid("cannot write '" + a + "': " + std::strerror(errno));
  f.reset(std::fopen(b.c_str(), "ab"));
  ok = f != nullptr;
  if (ok && n) ok = std::fwrite(faceCluster.data(), sizeof faceCluster[0], n, f.get()) == n;
  if (f && std::fclose(f.release()) != 0) ok = false;
  if (!ok) return Status::Invalid("cannot write '" + b + "': " + std::strerror(errno));
  faces_[k] += n;
  if (partEnds_.size() <= k) partEnds_.resize(k + 1);
  if (n) partEnds_[k].push_back(faces_[k]);
  return Status::Ok();
}

Status LodSpill::finish(size_t k) {  // level k's file: its faces, then the side file's faceCluster
  if (!has(k)) return Status::Invalid("internal error: a LOD level was not spilled");
  const std::string a = file(k), b = clusters(k);
  std::unique_ptr<std::FILE, FileCloser> out(std::fopen(a.c_str(), "ab")), in(std::fopen(b.c_str(), "rb"));
  bool ok = out && (in || faces_[k] == 0);
  std::vector<char> buf(size_t(1) << 20);
  while (ok && in) {
    const size_t n = std::fread(buf.data(), 1, buf.size(), in.get());
    if (n && std::fwrite(buf.data(), 1, n, out.get()) != n) ok = false;
    if (n < buf.size()) break;
  }
  if (ok && in && std::ferror(in.get())) ok = false;
  if (out && std::fclose(out.release()) != 0) ok = false;
  in.reset();
  std::remove(b.c_str());
  if (!ok) return Status::Invalid("cannot write '" + a + "': " + std::strerror(errno));
  return Status::Ok();
}

std::string LodSpill::file(size_t k) const {
  char name[8];
  std::snprintf(name, sizeof name, "/L%02d", int(k));
  return folder_ + name;
}

Status LodSpill::put(size_t k, LodDag::Level& L, const std::vector<vcg::Point3f>& positions) {
  if (folder_.empty() || k >= 64 || L.faces.size() != L.faceCluster.size())
    return Status::Invalid("internal error: a LOD level cannot be spilled");
  if (faces_.size() <= k) {
    faces_.resize(k + 1, kNone);
    boxes_.resize(k + 1);
  }
  vcg::Box3f box;
  for (const auto& t : L.faces)
    for (uint32_t v : t) box.Add(positions[v]);
  const std::string path = file(k);
  std::unique_ptr<std::FILE, FileCloser> f(std::fopen(path.c_str(), "wb"));
  const size_t n = L.faces.size();
  bool ok = f != nullptr;
  if (ok && n) ok = std::fwrite(L.faces.data(), sizeof L.faces[0], n, f.get()) == n;
  if (ok && n) ok = std::fwrite(L.faceCluster.data(), sizeof L.faceCluster[0], n, f.get()) == n;
  if (f && std::fclose(f.release()) != 0) ok = false;
  faces_[k] = n;  // so that remove() deletes it, whatever happened
  if (!ok) return Status::Invalid("cannot write '" + path + "': " + std::strerror(errno));
  boxes_[k] = box;
  if (k < partEnds_.size()) partEnds_[k].clear();  // one part
  std::vector<std::array<uint32_t, 3>>().swap(L.faces);
  std::vector<uint32_t>().swap(L.faceCluster);
  return Status::Ok();
}

Status LodSpill::get(size_t k, size_t part, std::vector<std::array<uint32_t, 3>>& faces,
                     std::vector<uint32_t>& faceCluster) const {
  if (parts(k) == 1 && part == 0) return get(k, faces, faceCluster);
  if (!has(k) || part >= parts(k)) return Status::Invalid("internal error: a LOD level was not spilled");
  return get(k, part ? partEnds_[k][part - 1] : 0, partEnds_[k][part], faces, faceCluster);
}

Status LodSpill::get(size_t k, uint64_t begin, uint64_t end, std::vector<std::array<uint32_t, 3>>& faces,
                     std::vector<uint32_t>& faceCluster) const {
  if (!has(k) || begin > end || end > faces_[k]) return Status::Invalid("internal error: a LOD level was not spilled");
  const uint64_t total = faces_[k];
  const std::string path = file(k);
  std::unique_ptr<std::FILE, FileCloser> f(std::fopen(path.c_str(), "rb"));
  const size_t n = size_t(end - begin);
  faces.resize(n);
  faceCluster.resize(n);
  bool ok = f != nullptr;
  if (ok) ok = fseeko(f.get(), off_t(begin * sizeof faces[0]), SEEK_SET) == 0;
  if (ok && n) ok = std::fread(faces.data(), sizeof faces[0], n, f.get()) == n;
  if (ok) ok = fseeko(f.get(), off_t(total * sizeof faces[0] + begin * sizeof faceCluster[0]), SEEK_SET) == 0;
  if (ok && n) ok = std::fread(faceCluster.data(), sizeof faceCluster[0], n, f.get()) == n;
  if (!ok) return Status::Invalid("cannot read '" + path + "' (the temporary folder of --memory)");
  return Status::Ok();
}

Status LodSpill::get(size_t k, std::vector<std::array<uint32_t, 3>>& faces, std::vector<uint32_t>& faceCluster) const {
  if (!has(k)) return Status::Invalid("internal error: a LOD level was not spilled");
  const std::string path = file(k);
  std::unique_ptr<std::FILE, FileCloser> f(std::fopen(path.c_str(), "rb"));
  const size_t n = size_t(faces_[k]);
  faces.resize(n);
  faceCluster.resize(n);
  bool ok = f != nullptr;
  if (ok && n) ok = std::fread(faces.data(), sizeof faces[0], n, f.get()) == n;
  if (ok && n) ok = std::fread(faceCluster.data(), sizeof faceCluster[0], n, f.get()) == n;
  if (!ok) return Status::Invalid("cannot read '" + path + "' (the temporary folder of --memory)");
  return Status::Ok();
}

}  // namespace conelod
