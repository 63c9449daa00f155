#include "render/parallel_rows.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

namespace glasspiv {

int parallel_rows(int rows, int threads, const std::function<void(int)>& row_fn,
                  const std::function<void(int, int)>& progress) {
  if (threads <= 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  threads = std::max(1, std::min(threads, rows));
  std::atomic<int> next_row{0}, rows_done{0};
  auto worker = [&]() {
    for (int row = next_row.fetch_add(1); row < rows; row = next_row.fetch_add(1)) {
      row_fn(row);
      rows_done.fetch_add(1);
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(static_cast<std::size_t>(threads));
  for (int i = 0; i < threads; ++i) pool.emplace_back(worker);
  if (progress) {
    int reported = -1;
    while (true) {
      const int done = rows_done.load();
      if (done != reported) progress(reported = done, rows);
      if (done >= rows) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  }
  for (std::thread& th : pool) th.join();
  return threads;
}

}  // namespace glasspiv
