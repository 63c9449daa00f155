#include "render/parallel_rows.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace glasspiv {

int parallel_rows(int rows, int threads, const std::function<void(int)>& row_fn,
                  const std::function<void(int, int)>& progress) {
  if (threads <= 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  threads = std::max(1, std::min(threads, rows));
  std::atomic<int> next_row{0}, rows_done{0};
  std::atomic<bool> stopped{false};
  // The last row wakes the reporting thread: a plain 50 ms sleep between
  // reports kept it up to 50 ms past the end of every call (the reflection
  // grid makes two such calls per band of 64 rows: the reactor's whole camera
  // traced in 6.1 s instead of 3.7, in 3.8 s instead of 1.2 without reflections).
  std::mutex finished_mutex;
  std::condition_variable finished;
  // The first exception a row throws: the other workers take no new row, and
  // it is rethrown here once every thread has stopped (an exception leaving a
  // std::thread's function would end the process).
  std::exception_ptr first_error;
  auto worker = [&]() {
    for (int row = next_row.fetch_add(1); row < rows && !stopped.load(); row = next_row.fetch_add(1)) {
      try {
        row_fn(row);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(finished_mutex);
        if (!first_error) first_error = std::current_exception();
        stopped.store(true);
        finished.notify_all();
        return;
      }
      if (rows_done.fetch_add(1) + 1 == rows) {
        const std::lock_guard<std::mutex> lock(finished_mutex);
        finished.notify_all();
      }
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(static_cast<std::size_t>(threads));
  for (int i = 0; i < threads; ++i) pool.emplace_back(worker);
  if (progress) {
    int reported = -1;
    while (!stopped.load()) {
      const int done = rows_done.load();
      if (done != reported) progress(reported = done, rows);
      if (done >= rows) break;
      std::unique_lock<std::mutex> lock(finished_mutex);
      finished.wait_for(lock, std::chrono::milliseconds(50),
                        [&] { return rows_done.load() >= rows || stopped.load(); });
    }
  }
  for (std::thread& th : pool) th.join();
  if (first_error) std::rethrow_exception(first_error);
  return threads;
}

}  // namespace glasspiv
