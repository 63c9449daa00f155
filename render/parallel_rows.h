#pragma once
// Row-parallel loop of the image builders (transport map, setup render): rows
// are handed to std::threads dynamically, each row writes only its own output,
// so results do not depend on the thread count. The calling thread reports
// progress. No I/O.
#include <functional>

namespace glasspiv {

// Calls row_fn(row) once for every row in [0, rows) on `threads` threads
// (<= 0: hardware concurrency; never more than rows). progress, if set, is
// called from the calling thread with (rows done, rows) about every 50 ms and
// once at the end; it must not throw. If row_fn throws, no further row is
// started, the threads are joined and the first exception is rethrown on the
// calling thread (progress is then not called at the end). Returns the number
// of threads used.
int parallel_rows(int rows, int threads, const std::function<void(int)>& row_fn,
                  const std::function<void(int, int)>& progress = {});

}  // namespace glasspiv
