#pragma once
// The crossings of a transport map's rows, gathered in row order while the
// rows finish in any order on several threads (render/transport_map.cpp). No I/O.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include "render/reflection_grid.h"
#include "render/transport_map.h"

namespace glasspiv {

// One row's crossings as the map stores them (a struct of arrays).
struct RowCrossings {
  std::vector<float> s, t, w, ds_dcol, ds_drow, dt_dcol, dt_drow;
  std::vector<std::uint8_t> tag;

  void push(const GridCrossing& c);
  void clear();
  std::size_t size() const { return w.size(); }
};

// Takes each row's crossings when the row is finished, on any thread, and
// keeps them in row order. A row finished while one above it is still being
// traced waits in a spare buffer; the others are copied at once into chunks of
// memory of their own (util/huge_pages.h), so the rows make no allocations of
// their own and page faults come 2 MiB at a time. At the end each chunk is
// moved into the map's arrays and given back: the build holds its crossings
// once beside the map, plus one chunk.
class CrossingSink {
 public:
  explicit CrossingSink(int rows);
  ~CrossingSink();
  CrossingSink(const CrossingSink&) = delete;
  CrossingSink& operator=(const CrossingSink&) = delete;

  // Row `row`'s crossings, each row once; *crossings comes back empty with
  // some capacity (the caller's reusable buffer). Thread-safe.
  void commit(int row, RowCrossings* crossings);
  // The crossings of the rows in order so far (every row's, once all are in).
  std::size_t size() const;
  // Once every row is in: appends the crossings to map's crossing arrays
  // (s_mm ... tag), in row order, giving each chunk back as it is copied; the
  // arrays are copied on up to `threads` threads (<= 0: hardware
  // concurrency), each array by one. Throws std::logic_error when a row is
  // missing.
  void move_into(TransportMap* map, int threads = 1);

 private:
  struct Chunk;
  void append(const RowCrossings& c);  // the mutex held

  mutable std::mutex mutex_;
  int rows_ = 0, next_ = 0;  // rows below next_ are in the chunks
  std::vector<RowCrossings> waiting_;
  std::vector<std::uint8_t> ready_;  // rows waiting
  std::vector<RowCrossings> spare_;  // emptied buffers that kept their capacity
  std::vector<std::unique_ptr<Chunk>> chunks_;
  std::size_t total_ = 0;
};

}  // namespace glasspiv
