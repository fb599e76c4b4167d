// A minimal parallel loop over both cores (or any thread count). Private to the library.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace sd {

/// Number of worker threads the library uses: every hardware thread (2 on the project's machines).
inline int default_thread_count() { return std::max(1u, std::thread::hardware_concurrency()); }

/// Calls body(begin, end) on disjoint chunks of [0, count) from `threads` threads (the caller is
/// one of them), chunks handed out dynamically. The first exception thrown by a body is rethrown
/// once every thread has stopped; the remaining chunks are skipped.
template <typename Body>
void parallel_for(size_t count, size_t chunk, Body&& body, int threads = default_thread_count()) {
  std::atomic<size_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto work = [&] {
    for (;;) {
      const size_t begin = next.fetch_add(chunk);
      if (begin >= count) return;
      try {
        body(begin, std::min(count, begin + chunk));
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
        next = count;
      }
    }
  };
  const int helpers = std::max(0, std::min<int>(threads, static_cast<int>((count + chunk - 1) / chunk)) - 1);
  std::vector<std::thread> pool;
  pool.reserve(helpers);
  for (int i = 0; i < helpers; ++i) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace sd
