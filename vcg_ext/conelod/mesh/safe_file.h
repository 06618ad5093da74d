// ConeLOD — writing a file so that a failed write never loses what the user had.
//
// Every output of the tool and the plugin (.clod, PLY, images) goes through SafeFile: the bytes are
// written to a temporary file in the target's own folder, flushed and fsync'ed, and only then
// renamed over the target, so the target is either its old self or the complete new file. Nothing
// the user named is ever truncated or deleted: on failure only the temporary file is removed.
//
// What a target may be: a missing path in a writable folder, a regular file (replaced; its
// permission bits are kept), or a symbolic link to a regular file: the file the link points at is
// replaced (the temporary file goes into that file's folder) and the link itself stays. Anything
// else (a folder, a device node such as /dev/full, a FIFO, a socket, a dangling link) is refused
// before anything is written.
//
// The temporary file is named `.NAME.conelod-PID-HOST.XXXXXX` beside the target NAME (PID: the
// writing process, HOST: a hash of the host name, XXXXXX: mkstemp's). A writer killed with
// SIGKILL leaves it behind; the next SafeFile::open of the same target removes such leftovers when
// all of these hold: the name has exactly this pattern for this target, HOST is this host, no
// process PID runs here, the file is a regular file owned by this user and it has not been
// modified for 10 minutes. Temporaries of other targets, of running writers (a long `lod build`
// writes with pauses), of other hosts (a shared folder) and files of other programs (rsync's
// `.NAME.XXXXXX`) are never touched.
#pragma once

#include <cstdio>
#include <string>

namespace conelod {

// Removes the leftover temporary files of `target` as described above; returns how many.
// `minAgeSeconds`: how long a leftover must have been left unmodified (600 for SafeFile).
int RemoveStaleTemporaries(const std::string& target, long minAgeSeconds = 600);

// "" when `path` can be written as described above, else the reason. Creates and removes a
// temporary file in the target's folder to find out (a read-only file system, a full quota or a
// folder without write permission all show there). Call it before long work starts.
std::string CheckOutputPath(const std::string& path);

// "" when `path` names a regular file (a symbolic link followed) that can be opened for reading,
// else "cannot read 'PATH': " and why: missing, a folder, a FIFO, a device or a socket. Found out
// with stat(), without opening the file: opening a FIFO blocks until something writes to it, and
// reading a device may never end. Every input (PLY, .clod) is checked with it before it is opened.
// `existingOnly`: "" as well when stat() fails (a missing file), leaving that to the reader's message.
std::string CheckInputPath(const std::string& path, bool existingOnly = false);

class SafeFile {
 public:
  SafeFile() = default;
  SafeFile(const SafeFile&) = delete;
  SafeFile& operator=(const SafeFile&) = delete;
  ~SafeFile() { discard(); }

  // Creates the temporary file for `path` and opens file() on it. "" or the error.
  std::string open(const std::string& path);
  std::FILE* file() const { return file_; }
  // For writers that want a file name (vcglib's exporters): closes file() and returns the temporary
  // file's name, which the writer then overwrites.
  const std::string& ReleaseForWriter();
  // Flushes, fsyncs, closes and sets the permission bits of the temporary file: after it only the
  // rename is left, so that two files can be written both or neither (write both, sync both, then
  // commit both). "" or the error (the temporary file removed); commit() calls it when not done.
  std::string sync();
  // sync(), then renames the temporary file over the target. "" or the error; on error the target
  // is untouched and the temporary file removed.
  std::string commit();
  // Removes the temporary file (nothing when committed or never opened).
  void discard();

 private:
  std::string target_;  // the file that is replaced (a symbolic link resolved)
  std::string shown_;   // the path as the user gave it, for messages
  std::string temp_;
  std::FILE* file_ = nullptr;
  unsigned mode_ = 0644;
  bool synced_ = false;
};

}  // namespace conelod
