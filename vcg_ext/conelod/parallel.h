// ConeLOD — the one way the core runs work on several threads: what "one thread per core" (a
// thread count of 0) means, and a pool of plain std::threads that share the work through an atomic
// counter. Every algorithm that runs on several threads (the feature simplification's set-up, first
// pass and parts; the hierarchical simplification's parts) goes through here.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <exception>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>

namespace conelod {

// The number of cores the system reports, at least 1.
inline unsigned CoreCount() { return std::max(1u, std::thread::hardware_concurrency()); }

namespace detail {
template <class Work, class Wait>
void RunThreads(unsigned threads, const Work& work, bool waitOnCaller, const Wait& whileWaiting, int waitMs) {
  threads = std::max(1u, threads);
  std::exception_ptr error;
  std::mutex errorMutex;
  std::atomic<unsigned> running(0);
  auto guarded = [&](unsigned thread) {
    try {
      work(thread);
    } catch (...) {
      std::lock_guard<std::mutex> lock(errorMutex);
      if (!error) error = std::current_exception();
    }
    running.fetch_sub(1);
  };
  std::vector<std::thread> pool;
  for (unsigned t = waitOnCaller ? 0 : 1; t < threads; ++t) {
    running.fetch_add(1);
    try {
      pool.emplace_back(guarded, t);
    } catch (const std::system_error&) {  // no more threads to be had: the started ones do the rest
      running.fetch_sub(1);
      break;
    }
  }
  if (!waitOnCaller || pool.empty()) {
    running.fetch_add(1);
    guarded(0);
  }
  if (waitOnCaller)
    while (running.load() > 0) {
      whileWaiting();
      std::this_thread::sleep_for(std::chrono::milliseconds(waitMs));
    }
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}
}  // namespace detail

// Runs work(thread) on `threads` threads (thread 0 is the calling thread) and returns when every
// one has returned. If no (more) threads can be started, the started ones — or the calling thread
// alone — do the work, so `work` must take its items from a shared counter rather than assume a
// thread count. An exception from a work function is rethrown here, after every thread stopped.
template <class Work>
void RunThreads(unsigned threads, const Work& work) {
  detail::RunThreads(
      threads, work, false, [] {}, 0);
}

// The same on new threads only, while the calling thread calls whileWaiting() every `waitMs`
// milliseconds until they are done (progress and cancellation belong to the calling thread:
// MeshLab's callbacks are not thread-safe).
template <class Work, class Wait>
void RunThreadsWhile(unsigned threads, const Work& work, const Wait& whileWaiting, int waitMs = 20) {
  detail::RunThreads(threads, work, true, whileWaiting, waitMs);
}

// Runs body(begin, end, thread) over [0, n) in chunks of `chunk`, on up to `threads` threads
// (thread 0 is this one). The bodies must touch disjoint data. After an exception the other
// threads take no new chunk; it is rethrown here.
template <class Body>
void ParallelChunks(size_t n, unsigned threads, size_t chunk, const Body& body) {
  threads = unsigned(std::max<size_t>(1, std::min<size_t>(threads, (n + chunk - 1) / chunk)));
  std::atomic<size_t> next(0);
  RunThreads(threads, [&](unsigned thread) {
    try {
      for (size_t begin; (begin = next.fetch_add(chunk)) < n;) body(begin, std::min(n, begin + chunk), thread);
    } catch (...) {
      next = n;
      throw;
    }
  });
}

// Runs body(i, scratch) for each i of [0, n), one item at a time from a shared counter, on up to
// `threads` threads (thread 0 is this one). Each thread has its own Scratch, made once (default
// constructed) and kept from one item to the next: buffers a body reuses rather than allocates per
// item. The bodies must touch disjoint data (apart from their scratch). After an exception the
// other threads take no new item; it is rethrown here.
template <class Scratch, class Body>
void ParallelItems(size_t n, unsigned threads, const Body& body) {
  threads = unsigned(std::max<size_t>(1, std::min<size_t>(threads, n)));
  std::atomic<size_t> next(0);
  RunThreads(threads, [&](unsigned) {
    Scratch scratch;
    try {
      for (size_t i; (i = next.fetch_add(1)) < n;) body(i, scratch);
    } catch (...) {
      next = n;
      throw;
    }
  });
}

}  // namespace conelod
