#pragma once
// The piv library's row-parallel loop: rows handed to std::threads one at a
// time, each row writing only its own outputs, so results do not depend on
// the thread count. (render/ has its own; piv does not depend on render.)
#include <functional>

namespace glasspiv {

// Calls row_fn(row, thread) once for every row in [0, rows), thread in
// [0, used threads), on `threads` threads (<= 0: hardware concurrency; never
// more than rows). While they run, the calling thread calls poll (if set)
// about every 50 ms and once at the end. If row_fn throws, no further row is
// started and the first exception is rethrown on the calling thread once the
// workers have stopped. Returns the number of threads used.
int for_each_row(int rows, int threads, const std::function<void(int row, int thread)>& row_fn,
                 const std::function<void()>& poll = {});

// The threads for_each_row would use for `threads` (<= 0: hardware concurrency), at least 1.
int resolved_thread_count(int threads);

}  // namespace glasspiv
