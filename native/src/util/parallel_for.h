// The library's one thread pool: a parallel loop over chunks of an index range, with optional
// progress reports and cancellation (in the manner of pbrt-v4's ParallelFor with its
// ProgressReporter). Private to the library.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <type_traits>
#include <vector>

namespace sd {

/// Number of worker threads the library uses: every hardware thread (2 on the project's machines).
inline int default_thread_count() { return std::max(1u, std::thread::hardware_concurrency()); }

/// Interval between two progress reports of parallel_for.
constexpr std::chrono::milliseconds kProgressInterval{50};

/// How parallel_for runs.
struct ParallelOptions {
  explicit ParallelOptions(int threads = 0) : threads(threads) {}

  int threads;  ///< threads that run the body; 0: default_thread_count()
  /// Called on the calling thread only — which then runs no body, so that a callback that must
  /// take a lock (Python's GIL) never waits for a chunk — with (items done, item count): once
  /// before any work, about every kProgressInterval while the workers run, and once after the last
  /// item. Returning false cancels. Without it the calling thread is one of the `threads`.
  std::function<bool(std::size_t done, std::size_t total)> progress;
  /// Polled before every chunk (and by the reporting thread); true cancels.
  const std::atomic<bool>* cancel = nullptr;
};

/// What parallel_for did: every item (completed), or `done` items before it was cancelled.
struct ParallelOutcome {
  bool completed = true;
  std::size_t done = 0;
};

/// Polled by a body whose chunks run long (see parallel_for): true once the loop is stopping.
class StopQuery {
 public:
  StopQuery(const std::atomic<bool>& stop, const std::atomic<bool>* cancel) : stop_(stop), cancel_(cancel) {}
  bool operator()() const {
    return stop_.load(std::memory_order_relaxed) || (cancel_ != nullptr && cancel_->load(std::memory_order_relaxed));
  }

 private:
  const std::atomic<bool>& stop_;
  const std::atomic<bool>* cancel_;
};

/// Calls body(begin, end) on disjoint chunks [begin, end) of [0, count), at most `chunk` >= 1 items
/// each, handed out dynamically. Each worker calls its own copy of `body` (made when the worker
/// starts), so a mutable body may keep per-worker scratch buffers. Results written per item do not
/// depend on the thread count. When cancelled (options.cancel, or progress returning false) the
/// workers stop before their next chunk and the outcome says how many items were done. The first
/// exception thrown by a body or by the progress callback is rethrown once every worker has
/// stopped; the remaining chunks are skipped. A body taking a third argument, body(begin, end,
/// stopping) with a StopQuery, may poll it to leave a long chunk early: the loop is then reported
/// cancelled (or its exception rethrown) whatever it counted as done.
template <typename Body>
ParallelOutcome parallel_for(std::size_t count, std::size_t chunk, Body&& body,
                             const ParallelOptions& options = ParallelOptions()) {
  const auto flagged = [&] { return options.cancel != nullptr && options.cancel->load(std::memory_order_relaxed); };
  const auto report = [&](std::size_t done) { return !options.progress || options.progress(done, count); };
  if (flagged() || !report(0)) return {false, 0};

  std::atomic<std::size_t> next{0}, done{0};
  std::atomic<bool> stop{false};
  std::exception_ptr error;
  std::mutex mutex;
  std::condition_variable finished;
  int running = 0;
  auto work = [&] {
    try {
      std::decay_t<Body> own(body);
      while (!stop.load(std::memory_order_relaxed) && !flagged()) {
        const std::size_t begin = next.fetch_add(chunk);
        if (begin >= count) break;
        const std::size_t end = std::min(count, begin + chunk);
        if constexpr (std::is_invocable_v<std::decay_t<Body>&, std::size_t, std::size_t, const StopQuery&>) {
          own(begin, end, StopQuery(stop, options.cancel));
        } else {
          own(begin, end);
        }
        done.fetch_add(end - begin, std::memory_order_relaxed);
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex);
      if (!error) error = std::current_exception();
      stop = true;
    }
    std::lock_guard<std::mutex> lock(mutex);
    if (--running == 0) finished.notify_all();
  };
  auto start = [&](std::vector<std::thread>& pool) {
    std::lock_guard<std::mutex> lock(mutex);
    ++running;
    try {
      pool.emplace_back(work);
    } catch (...) {
      --running;
      throw;
    }
  };

  const bool reporting = static_cast<bool>(options.progress);
  chunk = std::max<std::size_t>(chunk, 1);
  const std::size_t chunks = (count + chunk - 1) / chunk;
  const int threads = options.threads > 0 ? options.threads : default_thread_count();
  const int workers = static_cast<int>(std::min<std::size_t>(threads, chunks));
  bool cancelled = false;
  std::vector<std::thread> pool;
  try {
    for (int i = reporting ? 0 : 1; i < workers; ++i) start(pool);
    if (!reporting && workers > 0) {
      {
        std::lock_guard<std::mutex> lock(mutex);
        ++running;
      }
      work();
    }
    while (reporting) {
      {
        std::unique_lock<std::mutex> lock(mutex);
        if (finished.wait_for(lock, kProgressInterval, [&] { return running == 0; })) break;
      }
      if (flagged() || !report(done.load())) {
        cancelled = true;
        stop = true;
        break;
      }
    }
  } catch (...) {
    stop = true;
    for (auto& t : pool) t.join();
    throw;
  }
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
  const std::size_t total = done.load();
  if (cancelled || total != count || flagged() || !report(count)) return {false, total};
  return {true, count};
}

}  // namespace sd
