// The time step's thread team: every thread runs each task once, the shares cover a range exactly once and in
// order, the barrier separates phases, a task's exception reaches the caller, and the team can be reused.
#include <gtest/gtest.h>

#include <atomic>
#include <numeric>
#include <stdexcept>
#include <vector>

#include "mtled/thread_team.hpp"

namespace mtled {
namespace {

TEST(ThreadTeam, SharesCoverTheRangeOnceInOrder) {
  for (int size : {1, 2, 3, 7})
    for (std::int64_t n : {0, 1, 2, 5, 100, 1001}) {
      std::int64_t next = 0;
      for (int thread = 0; thread < size; ++thread) {
        const auto [begin, end] = ThreadTeam::share(n, thread, size);
        EXPECT_EQ(begin, next);
        EXPECT_LE(end - begin, n / size + 1);
        next = end;
      }
      EXPECT_EQ(next, n) << "size " << size;
    }
}

TEST(ThreadTeam, EveryThreadRunsEachTaskOnce) {
  for (int size : {1, 2, 4}) {
    ThreadTeam team(size);
    EXPECT_EQ(team.size(), size);
    for (int round = 0; round < 200; ++round) {
      std::vector<int> runs(static_cast<std::size_t>(size), 0);
      team.run([&](int thread) { ++runs[static_cast<std::size_t>(thread)]; });
      for (int r : runs) ASSERT_EQ(r, 1) << "size " << size << " round " << round;
    }
  }
}

TEST(ThreadTeam, ForEachShareVisitsEveryIndexOnce) {
  ThreadTeam team(3);
  std::vector<int> visits(10007, 0);
  team.for_each_share(static_cast<std::int64_t>(visits.size()), [&](std::int64_t begin, std::int64_t end) {
    for (auto i = begin; i < end; ++i) ++visits[static_cast<std::size_t>(i)];
  });
  EXPECT_EQ(std::accumulate(visits.begin(), visits.end(), 0), static_cast<int>(visits.size()));
  for (int v : visits) ASSERT_EQ(v, 1);
}

// Each phase reads what every thread wrote in the previous one: without the barrier a fast thread would read
// its neighbour's old value.
TEST(ThreadTeam, BarrierSeparatesPhases) {
  constexpr int kSize = 3, kPhases = 500;
  ThreadTeam team(kSize);
  std::vector<std::atomic<int>> value(kSize);
  std::atomic<int> errors{0};
  team.run([&](int thread) {
    for (int phase = 0; phase < kPhases; ++phase) {
      value[static_cast<std::size_t>(thread)].store(phase, std::memory_order_relaxed);
      team.barrier();
      for (int other = 0; other < kSize; ++other)
        if (value[static_cast<std::size_t>(other)].load(std::memory_order_relaxed) != phase) ++errors;
      team.barrier();
    }
  });
  EXPECT_EQ(errors.load(), 0);
}

TEST(ThreadTeam, ATaskExceptionReachesTheCallerAndTheTeamStaysUsable) {
  ThreadTeam team(2);
  EXPECT_THROW(team.run([](int thread) {
    if (thread == 1) throw std::runtime_error("worker failed");
  }),
               std::runtime_error);
  int runs = 0;
  team.run([&](int thread) {
    if (thread == 0) ++runs;
  });
  EXPECT_EQ(runs, 1);
}

}  // namespace
}  // namespace mtled
