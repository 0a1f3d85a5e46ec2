#include "mtled/thread_team.hpp"

#include <chrono>
#include <stdexcept>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace mtled {

namespace {
inline void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  _mm_pause();
#else
  std::this_thread::yield();
#endif
}
}  // namespace

ThreadTeam::ThreadTeam(int size) : size_(size) {
  if (size < 1) throw std::invalid_argument("ThreadTeam: size must be at least 1");
  workers_.reserve(static_cast<std::size_t>(size - 1));
  for (int thread = 1; thread < size; ++thread) workers_.emplace_back([this, thread] { work(thread); });
}

ThreadTeam::~ThreadTeam() {
  stop_.store(true, std::memory_order_relaxed);
  generation_.fetch_add(1, std::memory_order_release);
  generation_.notify_all();
  for (auto& worker : workers_) worker.join();
}

void ThreadTeam::wait_while_equal(const std::atomic<std::uint32_t>& word, std::uint32_t value) {
  // Three stages. A few microseconds of pauses: threads of a time step usually meet that soon. Then up to 2 ms
  // of yielding the core: on an idle machine the thread stays ready (a wake-up from sleep costs 20 us, and a
  // step has several such meetings), while a process sharing the core gets it at once. Then sleep.
  for (int spin = 0; spin < 1000; ++spin) {
    if (word.load(std::memory_order_acquire) != value) return;
    cpu_relax();
  }
  const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(2);
  for (int round = 0; word.load(std::memory_order_acquire) == value; ++round) {
    std::this_thread::yield();
    if (round % 16 == 15 && std::chrono::steady_clock::now() > until) break;
  }
  while (word.load(std::memory_order_acquire) == value) word.wait(value, std::memory_order_acquire);
}

void ThreadTeam::call(int thread) noexcept {
  try {
    function_->call(function_->object, thread);
  } catch (...) {
    if (!failed_.exchange(true)) error_ = std::current_exception();
  }
}

void ThreadTeam::dispatch(const Function& function) {
  function_ = &function;
  failed_.store(false, std::memory_order_relaxed);
  error_ = nullptr;
  unfinished_.store(static_cast<std::uint32_t>(size_ - 1), std::memory_order_relaxed);
  generation_.fetch_add(1, std::memory_order_release);
  generation_.notify_all();
  call(0);
  for (std::uint32_t left = unfinished_.load(std::memory_order_acquire); left != 0;
       left = unfinished_.load(std::memory_order_acquire))
    wait_while_equal(unfinished_, left);
  function_ = nullptr;
  if (failed_.load()) std::rethrow_exception(error_);
}

void ThreadTeam::work(int thread) {
  std::uint32_t seen = 0;
  for (;;) {
    wait_while_equal(generation_, seen);
    seen = generation_.load(std::memory_order_acquire);
    if (stop_.load(std::memory_order_relaxed)) return;
    call(thread);
    if (unfinished_.fetch_sub(1, std::memory_order_acq_rel) == 1) unfinished_.notify_one();
  }
}

void ThreadTeam::barrier() {
  if (size_ == 1) return;
  const std::uint32_t round = passed_.load(std::memory_order_acquire);
  if (arrived_.fetch_add(1, std::memory_order_acq_rel) + 1 == static_cast<std::uint32_t>(size_)) {
    arrived_.store(0, std::memory_order_relaxed);
    passed_.fetch_add(1, std::memory_order_release);
    passed_.notify_all();
    return;
  }
  wait_while_equal(passed_, round);
}

}  // namespace mtled
