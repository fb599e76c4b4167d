// Tests of the library's one thread pool, parallel_for (a private header): the
// contract the bake and its Python binding rely on.
#include "util/parallel_for.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

namespace sd {
namespace {

using Clock = std::chrono::steady_clock;

TEST(ParallelFor, RunsEveryItemOnceForAnyThreadCount) {
  for (int threads : {1, 2, 5, 0}) {
    std::vector<std::atomic<int>> visits(1000);
    const ParallelOutcome outcome = parallel_for(
        visits.size(), 7,
        [&](std::size_t begin, std::size_t end) {
          EXPECT_LE(end - begin, 7u);
          for (std::size_t i = begin; i < end; ++i) ++visits[i];
        },
        ParallelOptions(threads));
    EXPECT_TRUE(outcome.completed);
    EXPECT_EQ(outcome.done, visits.size());
    for (const auto& v : visits) EXPECT_EQ(v.load(), 1) << threads << " threads";
  }
  EXPECT_TRUE(parallel_for(0, 4, [](std::size_t, std::size_t) { FAIL(); }).completed);
}

TEST(ParallelFor, ReportsOnTheCallingThreadOnlyWhichRunsNoBody) {
  const auto caller = std::this_thread::get_id();
  std::mutex mutex;
  std::set<std::thread::id> body_threads;
  std::vector<std::size_t> reports;
  ParallelOptions options(2);
  options.progress = [&](std::size_t done, std::size_t total) {
    EXPECT_EQ(std::this_thread::get_id(), caller);
    EXPECT_EQ(total, 40u);
    reports.push_back(done);
    return true;
  };
  const ParallelOutcome outcome = parallel_for(
      40, 1,
      [&](std::size_t, std::size_t) {
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
        std::lock_guard<std::mutex> lock(mutex);
        body_threads.insert(std::this_thread::get_id());
      },
      options);
  EXPECT_TRUE(outcome.completed);
  EXPECT_EQ(body_threads.count(caller), 0u);
  EXPECT_EQ(body_threads.size(), 2u);
  // 40 × 5 ms on 2 threads: about 100 ms, so at least one report between the first and the last.
  ASSERT_GE(reports.size(), 3u);
  EXPECT_EQ(reports.front(), 0u);
  EXPECT_EQ(reports.back(), 40u);
  for (std::size_t i = 1; i < reports.size(); ++i) EXPECT_GE(reports[i], reports[i - 1]);
}

TEST(ParallelFor, WithoutProgressTheCallerIsOneOfTheThreads) {
  const auto caller = std::this_thread::get_id();
  std::atomic<int> on_caller{0};
  parallel_for(
      16, 1, [&](std::size_t, std::size_t) { on_caller += std::this_thread::get_id() == caller; },
      ParallelOptions(1));
  EXPECT_EQ(on_caller.load(), 16);
}

TEST(ParallelFor, EachWorkerOwnsACopyOfTheBody) {
  std::mutex mutex;
  std::vector<const int*> scratch_addresses;
  parallel_for(
      300, 1,
      [&, scratch = 0](std::size_t, std::size_t) mutable {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
        std::lock_guard<std::mutex> lock(mutex);
        if (scratch++ == 0) scratch_addresses.push_back(&scratch);
      },
      ParallelOptions(3));
  // One copy per worker: three distinct scratch variables, each first used once.
  EXPECT_EQ(scratch_addresses.size(), 3u);
  EXPECT_EQ(std::set<const int*>(scratch_addresses.begin(), scratch_addresses.end()).size(), 3u);
}

TEST(ParallelFor, CancelFlagStopsWithinASecond) {
  std::atomic<bool> cancel{false};
  ParallelOptions options(2);
  options.cancel = &cancel;
  std::thread canceller([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    cancel = true;
  });
  const auto start = Clock::now();
  // 100 000 items of 1 ms: about 50 s unless cancelled.
  const ParallelOutcome outcome = parallel_for(
      100000, 1, [](std::size_t, std::size_t) { std::this_thread::sleep_for(std::chrono::milliseconds(1)); },
      options);
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  canceller.join();
  EXPECT_FALSE(outcome.completed);
  EXPECT_GT(outcome.done, 0u);
  EXPECT_LT(outcome.done, 100000u);
  EXPECT_LT(seconds, 1.0);
  // A flag raised before the start runs nothing.
  EXPECT_EQ(parallel_for(10, 1, [](std::size_t, std::size_t) { FAIL(); }, options).done, 0u);
}

TEST(ParallelFor, ProgressReturningFalseCancels) {
  ParallelOptions options(2);
  int calls = 0;
  options.progress = [&](std::size_t, std::size_t) { return ++calls < 2; };
  const ParallelOutcome outcome = parallel_for(
      100000, 1, [](std::size_t, std::size_t) { std::this_thread::sleep_for(std::chrono::milliseconds(1)); },
      options);
  EXPECT_FALSE(outcome.completed);
  EXPECT_LT(outcome.done, 100000u);
  EXPECT_EQ(calls, 2);
}

TEST(ParallelFor, ExceptionsAreRethrownOnceEveryWorkerStopped) {
  std::atomic<int> running{0};
  std::atomic<std::size_t> done{0};
  auto body = [&](std::size_t begin, std::size_t) {
    ++running;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    --running;
    ++done;
    if (begin == 20) throw std::runtime_error("item 20");
  };
  try {
    parallel_for(10000, 1, body, ParallelOptions(3));
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "item 20");
    EXPECT_EQ(running.load(), 0);
    EXPECT_LT(done.load(), 10000u);  // the remaining chunks are skipped
  }

  struct Stop {};
  ParallelOptions options(2);
  options.progress = [](std::size_t done_so_far, std::size_t) {
    if (done_so_far > 0) throw Stop{};
    return true;
  };
  done = 0;
  auto quiet_body = [&](std::size_t, std::size_t) {
    ++running;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    --running;
    ++done;
  };
  EXPECT_THROW(parallel_for(10000, 1, quiet_body, options), Stop);
  EXPECT_EQ(running.load(), 0);
  EXPECT_LT(done.load(), 10000u);
}

}  // namespace
}  // namespace sd
