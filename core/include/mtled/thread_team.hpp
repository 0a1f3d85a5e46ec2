#pragma once
// The threads of the time step: a fixed team that splits each loop into contiguous equal shares (so a run's
// arithmetic, and its answer, depend only on the team size), and whose idle threads wait briefly and then
// sleep instead of spinning. OpenMP's default spin-waiting made two runs sharing two cores 25 times slower
// each: a waiting thread held the core its partner needed. One-time setup loops still use OpenMP.
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <exception>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

namespace mtled {

class ThreadTeam {
 public:
  // `size` threads in all: the caller of run() and size - 1 workers started here.
  explicit ThreadTeam(int size);
  ~ThreadTeam();
  ThreadTeam(const ThreadTeam&) = delete;
  ThreadTeam& operator=(const ThreadTeam&) = delete;

  int size() const { return size_; }

  // Runs task(thread) on every thread of the team at once, the caller being thread 0, and returns when all have
  // finished; rethrows the first exception a task threw. Not re-entrant: a task must not call run().
  template <class Task>
  void run(Task&& task) {
    if (size_ == 1) {
      task(0);
      return;
    }
    using Callable = std::remove_reference_t<Task>;
    Function function{const_cast<void*>(static_cast<const void*>(&task)),
                      [](void* t, int thread) { (*static_cast<Callable*>(t))(thread); }};
    dispatch(function);
  }

  // Inside a task: waits until every thread of the team has reached it.
  void barrier();

  // The contiguous share [begin, end) of 0 .. n - 1 that thread `thread` of `size` takes.
  static std::pair<std::int64_t, std::int64_t> share(std::int64_t n, int thread, int size) {
    return {n * thread / size, n * (thread + 1) / size};
  }
  // body(begin, end) over share `thread` of `size` of the points of some ranges (pairs first .. second - 1) taken in
  // order: share() of their count, one call per range the share meets.
  template <class Ranges, class Body>
  static void for_each_piece_of_share(const Ranges& ranges, int thread, int size, Body&& body) {
    std::int64_t n = 0;
    for (const auto& range : ranges) n += range.second - range.first;
    const auto [begin, end] = share(n, thread, size);
    std::int64_t offset = 0;  // of the current range among the ranges' points
    for (const auto& range : ranges) {
      const std::int64_t count = range.second - range.first;
      const std::int64_t from = std::max<std::int64_t>(begin - offset, 0), to = std::min<std::int64_t>(end - offset, count);
      using Value = decltype(range.first);
      if (from < to) body(static_cast<Value>(range.first + from), static_cast<Value>(range.first + to));
      offset += count;
    }
  }
  // run() of body(begin, end) over the threads' shares of 0 .. n - 1; on the caller alone, body(0, n), when a
  // share would hold fewer than `grain` items: waking the team costs microseconds, and every meeting of the
  // threads is a chance to wait for one that another process holds off its core.
  template <class Body>
  void for_each_share(std::int64_t n, Body&& body, std::int64_t grain = 1) {
    if (size_ == 1 || n < grain * size_) {
      body(std::int64_t{0}, n);
      return;
    }
    run([&](int thread) {
      const auto [begin, end] = share(n, thread, size_);
      body(begin, end);
    });
  }

 private:
  struct Function {
    void* object;
    void (*call)(void*, int);
  };
  void dispatch(const Function& function);
  void work(int thread);
  void call(int thread) noexcept;
  // Spins for a few microseconds (a step's threads usually meet sooner), then sleeps until `word` changes.
  static void wait_while_equal(const std::atomic<std::uint32_t>& word, std::uint32_t value);

  int size_;
  std::vector<std::thread> workers_;
  const Function* function_ = nullptr;
  std::atomic<std::uint32_t> generation_{0};  // a new task for the workers
  std::atomic<std::uint32_t> unfinished_{0};  // threads still inside the task
  std::atomic<std::uint32_t> arrived_{0};     // barrier: threads that reached it
  std::atomic<std::uint32_t> passed_{0};      // barrier: times it opened
  std::atomic<bool> stop_{false};
  std::exception_ptr error_;
  std::atomic<bool> failed_{false};
};

}  // namespace mtled
