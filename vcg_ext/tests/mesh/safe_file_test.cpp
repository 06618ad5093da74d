// Tests of writing through a temporary file (safe_file.h): leftovers of killed writers, two files
// both or neither, inputs that are not regular files.
#include "conelod/mesh/safe_file.h"

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <set>
#include <string>

#include <dirent.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

using namespace conelod;

namespace {

struct Folder {
  std::string path;
  Folder() {
    char name[] = "/tmp/conelod_safe_file_XXXXXX";
    path = mkdtemp(name) ? name : "";
  }
  ~Folder() {
    if (path.empty()) return;
    for (const std::string& n : names()) unlink((path + "/" + n).c_str());
    rmdir(path.c_str());
  }
  std::set<std::string> names() const {
    std::set<std::string> out;
    DIR* d = opendir(path.c_str());
    if (!d) return out;
    while (const dirent* e = readdir(d))
      if (std::string(e->d_name) != "." && std::string(e->d_name) != "..") out.insert(e->d_name);
    closedir(d);
    return out;
  }
  // Creates the file `name` last modified `ageSeconds` ago.
  void make(const std::string& name, long ageSeconds) const {
    const std::string p = path + "/" + name;
    std::ofstream(p) << "partial";
    struct timeval t[2];
    gettimeofday(&t[0], nullptr);
    t[0].tv_sec -= ageSeconds;
    t[1] = t[0];
    utimes(p.c_str(), t);
  }
};

// The id of a process that has ended (a child, reaped).
pid_t EndedProcess() {
  const pid_t child = fork();
  if (child == 0) _exit(0);
  int status = 0;
  waitpid(child, &status, 0);
  return child;
}

}  // namespace

// A writer killed with SIGKILL leaves its temporary file; the next write of the same target
// removes it once its writer is gone and it has been left for 10 minutes, and nothing else.
TEST(SafeFile, RemovesStaleTemporariesOfTheSameTargetOnly) {
  Folder dir;
  ASSERT_FALSE(dir.path.empty());
  const std::string target = dir.path + "/out.ply";
  // The name this host and process give a temporary file: ".out.ply.conelod-PID-HOST.XXXXXX".
  std::string host;
  {
    SafeFile probe;
    ASSERT_EQ(probe.open(target), "");
    const std::string temp = probe.ReleaseForWriter();
    const std::string mine = ".out.ply.conelod-" + std::to_string(getpid()) + "-";
    const std::string base = temp.substr(temp.rfind('/') + 1);
    ASSERT_EQ(base.compare(0, mine.size(), mine), 0) << base;
    host = base.substr(mine.size(), 8);
    probe.discard();
  }
  const std::string dead = std::to_string(EndedProcess());
  const std::string mine = std::to_string(getpid());
  const long old = 11 * 60, fresh = 60;
  dir.make(".out.ply.conelod-" + dead + "-" + host + ".AbC123", old);        // stale: removed
  dir.make(".out.ply.conelod-" + dead + "-" + host + ".XyZ789", old);        // stale: removed
  dir.make(".out.ply.conelod-" + dead + "-" + host + ".Fresh1", fresh);      // too recent
  dir.make(".out.ply.conelod-" + mine + "-" + host + ".Alive1", old);        // its writer runs
  dir.make(".out.ply.conelod-" + dead + "-" + "0badc0de" + ".Other1", old);  // another host
  dir.make(".out.ply.AbCdEf", old);                                          // not ours (rsync's)
  dir.make(".out.ply.conelod-" + dead + "-" + host + ".AbC123.bak", old);    // not our pattern
  dir.make(".other.ply.conelod-" + dead + "-" + host + ".AbC123", old);      // another target
  dir.make("out.ply.conelod-" + dead + "-" + host + ".AbC123", old);         // not hidden
  const std::set<std::string> before = dir.names();
  SafeFile out;
  ASSERT_EQ(out.open(target), "");
  std::fputs("new", out.file());
  ASSERT_EQ(out.commit(), "");
  std::set<std::string> expected = before;
  expected.erase(".out.ply.conelod-" + dead + "-" + host + ".AbC123");
  expected.erase(".out.ply.conelod-" + dead + "-" + host + ".XyZ789");
  expected.insert("out.ply");
  EXPECT_EQ(dir.names(), expected);
}

// Two files written both or neither: when the second cannot be written, the first, synced but
// not committed, is discarded and its target keeps its old content.
TEST(SafeFile, SyncedButUncommittedFileLeavesTheTarget) {
  Folder dir;
  const std::string first = dir.path + "/mask.pgm";
  std::ofstream(first) << "old";
  {
    SafeFile a;
    ASSERT_EQ(a.open(first), "");
    std::fputs("new", a.file());
    ASSERT_EQ(a.sync(), "");
    SafeFile b;
    EXPECT_NE(b.open(dir.path + "/no/such/folder/out.ply"), "");
  }  // a goes out of scope uncommitted
  std::ifstream in(first);
  std::string content;
  in >> content;
  EXPECT_EQ(content, "old");
  EXPECT_EQ(dir.names(), std::set<std::string>{"mask.pgm"});
}

TEST(SafeFile, CheckInputPathRefusesWhatIsNotARegularFile) {
  Folder dir;
  const std::string fifo = dir.path + "/pipe.ply", file = dir.path + "/m.ply";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  std::ofstream(file) << "ply";
  EXPECT_EQ(CheckInputPath(file), "");
  EXPECT_EQ(CheckInputPath(fifo), "cannot read '" + fifo + "': it is a FIFO (named pipe): only a regular file is read");
  EXPECT_EQ(CheckInputPath(dir.path), "cannot read '" + dir.path + "': it is a folder");
  EXPECT_EQ(CheckInputPath("/dev/null"), "cannot read '/dev/null': it is a device: only a regular file is read");
  EXPECT_NE(CheckInputPath(dir.path + "/missing.ply").find("No such file"), std::string::npos);
  EXPECT_EQ(CheckInputPath(dir.path + "/missing.ply", true), "");  // left to the reader
}
