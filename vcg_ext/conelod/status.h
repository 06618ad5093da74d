// ConeLOD — status and progress types shared by the whole core.
//
// The core reports bad input with a returned Status (never an exception, never an assert):
// a MeshLab filter turns the message into its errorMessage, the CLI prints it. Progress goes
// through one rising 0-100 scale; a callback that returns false asks the core to stop, and the
// core then returns Status::Cancelled() without having touched the caller's mesh.
#pragma once

#include <functional>
#include <string>
#include <utility>

namespace conelod {

struct Status {
  enum class Code { Ok, InvalidInput, Cancelled, OutOfMemory };
  Code code = Code::Ok;
  std::string message;

  static Status Ok() { return Status(); }
  static Status Invalid(std::string msg) { return Status{Code::InvalidInput, std::move(msg)}; }
  static Status Cancelled() { return Status{Code::Cancelled, "cancelled by the progress callback"}; }
  static Status OutOfMemory(std::string msg) { return Status{Code::OutOfMemory, std::move(msg)}; }
  bool ok() const { return code == Code::Ok; }
};

// percent in [0,100], rising; stage is a short human-readable label. Return false to cancel.
using Progress = std::function<bool(int percent, const char* stage)>;

// Maps a sub-task's 0-100 onto [begin,end] of the caller's scale.
inline Progress SubProgress(const Progress& parent, int begin, int end) {
  if (!parent) return Progress();
  return [parent, begin, end](int p, const char* s) { return parent(begin + (end - begin) * p / 100, s); };
}

}  // namespace conelod
