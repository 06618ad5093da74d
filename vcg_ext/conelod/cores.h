// ConeLOD — what "one thread per core" (a thread count of 0) means, for every algorithm that
// runs on several threads.
#pragma once

#include <algorithm>
#include <thread>

namespace conelod {

// The number of cores the system reports, at least 1.
inline unsigned CoreCount() { return std::max(1u, std::thread::hardware_concurrency()); }

}  // namespace conelod
