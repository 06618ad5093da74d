// ConeLOD — writing a file through a temporary file and a rename (safe_file.h).
#include "conelod/mesh/safe_file.h"

#include <cerrno>
#include <climits>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <vector>

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

namespace conelod {
namespace {

std::string Reason(int err) { return std::strerror(err); }

std::string FolderOf(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

std::string BaseOf(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

// The file to replace for `path` (a symbolic link resolved) and its permission bits, or an error.
std::string ResolveTarget(const std::string& path, std::string& target, unsigned& mode) {
  if (path.empty()) return "no output file given";
  if (path.back() == '/') return "'" + path + "' is a folder, not a file";
  struct stat st;
  if (lstat(path.c_str(), &st) != 0) {
    if (errno != ENOENT) return "cannot write '" + path + "': " + Reason(errno);
    target = path;
    const mode_t mask = umask(0);
    umask(mask);
    mode = 0666u & ~unsigned(mask);
    return "";
  }
  target = path;
  if (S_ISLNK(st.st_mode)) {
    char* real = realpath(path.c_str(), nullptr);
    if (!real) return "'" + path + "' is a symbolic link to a missing file: give the file itself";
    target = real;
    std::free(real);
    if (stat(target.c_str(), &st) != 0) return "cannot write '" + path + "': " + Reason(errno);
  }
  if (!S_ISREG(st.st_mode)) {
    const char* what = S_ISDIR(st.st_mode)                          ? "a folder"
                       : S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode) ? "a device"
                       : S_ISFIFO(st.st_mode)                       ? "a FIFO"
                       : S_ISSOCK(st.st_mode)                       ? "a socket"
                                                                    : "not a regular file";
    return "'" + path + "' is " + what + (target != path ? " (through a symbolic link)" : "") +
           ": only a regular file is written";
  }
  if (access(target.c_str(), W_OK) != 0) return "cannot write '" + path + "': " + Reason(errno);
  mode = unsigned(st.st_mode) & 07777u;
  return "";
}

// 8 hex digits of a hash of the host name (FNV-1a): whose process ids a temporary file names.
std::string HostTag() {
  char host[256] = {0};
  if (gethostname(host, sizeof host - 1) != 0) host[0] = '\0';
  uint32_t h = 2166136261u;
  for (const char* c = host; *c; ++c) h = (h ^ uint32_t((unsigned char)*c)) * 16777619u;
  char tag[16];
  std::snprintf(tag, sizeof tag, "%08x", h);
  return tag;
}

// ".NAME.conelod-" : the start of the names of every temporary file of `target`.
std::string TempPrefix(const std::string& target) { return "." + BaseOf(target) + ".conelod-"; }

// Creates a temporary file beside `target`; returns its descriptor (or -1 with `error` set).
int MakeTemp(const std::string& target, const std::string& shown, std::string& temp, std::string& error) {
  std::string name =
      FolderOf(target) + "/" + TempPrefix(target) + std::to_string(long(getpid())) + "-" + HostTag() + ".XXXXXX";
  std::vector<char> buf(name.begin(), name.end());
  buf.push_back('\0');
  const int fd = mkstemp(buf.data());
  if (fd < 0) {
    error = "cannot write '" + shown + "': " + Reason(errno) + " (in folder '" + FolderOf(target) + "')";
    return -1;
  }
  temp.assign(buf.data());
  return fd;
}

}  // namespace

int RemoveStaleTemporaries(const std::string& target, long minAgeSeconds) {
  const std::string folder = FolderOf(target), prefix = TempPrefix(target), host = HostTag();
  DIR* dir = opendir(folder.c_str());
  if (!dir) return 0;
  std::vector<std::string> stale;
  const time_t now = time(nullptr);
  while (const dirent* e = readdir(dir)) {
    const std::string name = e->d_name;
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    // The rest must be exactly PID-HOST.XXXXXX.
    const std::string rest = name.substr(prefix.size());
    const size_t dash = rest.find('-');
    if (dash == 0 || dash == std::string::npos || dash > 9) continue;
    const std::string pid = rest.substr(0, dash);
    if (pid.find_first_not_of("0123456789") != std::string::npos) continue;
    if (rest.size() != dash + 1 + 8 + 1 + 6 || rest.compare(dash + 1, 8, host) != 0 || rest[dash + 9] != '.') continue;
    const std::string random = rest.substr(dash + 10);
    if (random.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789") != std::string::npos)
      continue;
    const long id = std::strtol(pid.c_str(), nullptr, 10);
    if (id <= 0 || id == long(getpid())) continue;
    if (kill(pid_t(id), 0) == 0 || errno != ESRCH) continue;  // running (or not ours to ask): kept
    const std::string path = folder + "/" + name;
    struct stat st;
    if (lstat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode) || st.st_uid != geteuid()) continue;
    if (now - st.st_mtime < minAgeSeconds) continue;
    stale.push_back(path);
  }
  closedir(dir);
  int removed = 0;
  for (const std::string& path : stale) removed += unlink(path.c_str()) == 0 ? 1 : 0;
  return removed;
}

std::string CheckInputPath(const std::string& path, bool existingOnly) {
  const std::string prefix = "cannot read '" + path + "': ";
  struct stat st;
  if (stat(path.c_str(), &st) != 0) return existingOnly ? "" : prefix + Reason(errno);
  if (S_ISREG(st.st_mode)) return "";
  if (S_ISDIR(st.st_mode)) return prefix + "it is a folder";
  const char* what = S_ISFIFO(st.st_mode)                         ? "a FIFO (named pipe)"
                     : S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode) ? "a device"
                     : S_ISSOCK(st.st_mode)                       ? "a socket"
                                                                  : "not a regular file";
  return prefix + "it is " + what + ": only a regular file is read";
}

std::string CheckOutputPath(const std::string& path) {
  std::string target, temp, error;
  unsigned mode = 0;
  error = ResolveTarget(path, target, mode);
  if (!error.empty()) return error;
  const int fd = MakeTemp(target, path, temp, error);
  if (fd < 0) return error;
  close(fd);
  unlink(temp.c_str());
  return "";
}

std::string SafeFile::open(const std::string& path) {
  discard();
  shown_ = path;
  std::string error = ResolveTarget(path, target_, mode_);
  if (!error.empty()) return error;
  RemoveStaleTemporaries(target_);
  const int fd = MakeTemp(target_, path, temp_, error);
  if (fd < 0) return error;
  file_ = fdopen(fd, "wb");
  if (!file_) {
    error = "cannot write '" + path + "': " + Reason(errno);
    close(fd);
    discard();
    return error;
  }
  std::setvbuf(file_, nullptr, _IOFBF, 1 << 20);
  return "";
}

const std::string& SafeFile::ReleaseForWriter() {
  if (file_) std::fclose(file_);
  file_ = nullptr;
  return temp_;
}

std::string SafeFile::sync() {
  if (temp_.empty()) return "cannot write '" + shown_ + "': not opened";
  if (synced_) return "";
  std::string error;
  auto failed = [&](const char* step, int err) {
    error = "cannot write '" + shown_ + "': " + Reason(err) + " (" + step + ")";
  };
  if (file_) {
    if (std::fflush(file_) != 0 || std::ferror(file_))
      failed("write", errno ? errno : EIO);
    else if (fsync(fileno(file_)) != 0)
      failed("fsync", errno);
    if (std::fclose(file_) != 0 && error.empty()) failed("close", errno);
    file_ = nullptr;
  } else {
    const int fd = ::open(temp_.c_str(), O_RDONLY);
    if (fd < 0)
      failed("reopen", errno);
    else {
      if (fsync(fd) != 0) failed("fsync", errno);
      close(fd);
    }
  }
  if (error.empty() && chmod(temp_.c_str(), mode_t(mode_)) != 0) failed("chmod", errno);
  if (!error.empty()) {
    discard();
    return error;
  }
  synced_ = true;
  return "";
}

std::string SafeFile::commit() {
  std::string error = sync();
  if (!error.empty()) return error;
  if (rename(temp_.c_str(), target_.c_str()) != 0) {
    error = "cannot write '" + shown_ + "': " + Reason(errno) + " (rename)";
    discard();
    return error;
  }
  temp_.clear();
  synced_ = false;
  const int dir = ::open(FolderOf(target_).c_str(), O_RDONLY);  // makes the rename itself durable
  if (dir >= 0) {
    fsync(dir);
    close(dir);
  }
  return "";
}

void SafeFile::discard() {
  if (file_) std::fclose(file_);
  file_ = nullptr;
  if (!temp_.empty()) unlink(temp_.c_str());
  temp_.clear();
  synced_ = false;
}

}  // namespace conelod
