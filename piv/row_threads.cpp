#include "piv/row_threads.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace glasspiv {

int resolved_thread_count(int threads) {
  return threads > 0 ? threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

int for_each_row(int rows, int threads, const std::function<void(int, int)>& row_fn, const std::function<void()>& poll) {
  threads = std::max(1, std::min(resolved_thread_count(threads), rows));
  std::atomic<int> next_row{0};
  int running = threads;
  std::mutex m;
  std::condition_variable finished;
  // The first exception a row throws stops the hand-out of rows and is
  // rethrown on the calling thread once every worker has stopped.
  std::exception_ptr first_error;
  auto worker = [&](int thread) {
    try {
      for (int row = next_row.fetch_add(1); row < rows; row = next_row.fetch_add(1)) row_fn(row, thread);
    } catch (...) {
      next_row.store(rows);
      std::lock_guard<std::mutex> lock(m);
      if (!first_error) first_error = std::current_exception();
    }
    std::lock_guard<std::mutex> lock(m);
    if (--running == 0) finished.notify_all();
  };
  std::vector<std::thread> pool;
  pool.reserve(static_cast<std::size_t>(threads));
  for (int i = 0; i < threads; ++i) pool.emplace_back(worker, i);
  if (poll) {
    std::unique_lock<std::mutex> lock(m);
    while (running > 0) {
      lock.unlock();
      poll();
      lock.lock();
      finished.wait_for(lock, std::chrono::milliseconds(50), [&] { return running == 0; });
    }
    lock.unlock();
    poll();
  }
  for (std::thread& t : pool) t.join();
  if (first_error) std::rethrow_exception(first_error);
  return threads;
}

}  // namespace glasspiv
