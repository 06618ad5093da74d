// ConeLOD — where a long build's wall time goes: with the environment variable CONELOD_STAGES set,
// the LOD build, the grouping and `conelod simplify` print one line per stage to stderr ("conelod-stage
// SECONDS_SINCE_START SECONDS NAME"), so that a run on many cores shows which stages do not shrink with the threads
// (docs/scale.md, "Threading figures"). Without the variable nothing is printed and a mark costs
// one clock read. Marks are made on the calling thread only.
#pragma once

#include <chrono>
#include <cstdio>
#include <cstdlib>

namespace conelod {

class StageLog {
 public:
  using Clock = std::chrono::steady_clock;

  static bool On() {
    static const bool on = std::getenv("CONELOD_STAGES") != nullptr;
    return on;
  }
  // The time since the first mark of the process.
  static double Now() { return std::chrono::duration<double>(Clock::now() - Start()).count(); }
  // A stage that took `seconds`, ending now.
  static void Print(const char* name, double seconds, int level = -1) {
    if (!On()) return;
    if (level >= 0)
      std::fprintf(stderr, "conelod-stage %9.3f %8.3f %s %d\n", Now(), seconds, name, level);
    else
      std::fprintf(stderr, "conelod-stage %9.3f %8.3f %s\n", Now(), seconds, name);
  }

  // Times a stage from its construction to Lap()/its destruction.
  class Scope {
   public:
    explicit Scope(const char* name, int level = -1) : name_(name), level_(level), t0_(Clock::now()) { Start(); }
    ~Scope() { Lap(); }
    void Lap() {
      if (!name_) return;
      Print(name_, std::chrono::duration<double>(Clock::now() - t0_).count(), level_);
      name_ = nullptr;
    }

   private:
    const char* name_;
    int level_;
    Clock::time_point t0_;
  };

  // Successive stages: each Mark() prints the time since the previous one (or the construction).
  class Laps {
   public:
    Laps() : t_(Clock::now()) { Start(); }
    void Mark(const char* name, int level = -1) {
      const Clock::time_point now = Clock::now();
      Print(name, std::chrono::duration<double>(now - t_).count(), level);
      t_ = now;
    }

   private:
    Clock::time_point t_;
  };

  // Adds up the time of a stage met many times (a level's chunks); printed by Flush().
  class Sum {
   public:
    explicit Sum(const char* name) : name_(name) {}
    void Begin() { t0_ = Clock::now(); }
    void End() { total_ += std::chrono::duration<double>(Clock::now() - t0_).count(); }
    void Flush(int level = -1) {
      if (total_ > 0) Print(name_, total_, level);
      total_ = 0;
    }

   private:
    const char* name_;
    Clock::time_point t0_;
    double total_ = 0;
  };

 private:
  static Clock::time_point Start() {
    static const Clock::time_point t = Clock::now();
    return t;
  }
};

}  // namespace conelod
