#include "render/crossing_sink.h"

#include <algorithm>
#include <cassert>
#include <stdexcept>

#include "render/parallel_rows.h"
#include "util/huge_pages.h"

namespace glasspiv {

void RowCrossings::push(const GridCrossing& c) {
  s.push_back(c.s_mm);
  t.push_back(c.t_mm);
  w.push_back(c.weight);
  tag.push_back(c.tag);
  ds_dcol.push_back(c.ds_dcol);
  ds_drow.push_back(c.ds_drow);
  dt_dcol.push_back(c.dt_dcol);
  dt_drow.push_back(c.dt_drow);
}

void RowCrossings::clear() {
  for (auto* v : {&s, &t, &w, &ds_dcol, &ds_drow, &dt_dcol, &dt_drow}) v->clear();
  tag.clear();
}

namespace {
// Chunk sizes in crossings: small first (a preview's map needs little), then
// doubling up to a cap that bounds what the final copy holds beside the map
// (7.25 MiB at 2^18).
constexpr std::size_t kFirstChunk = std::size_t{1} << 16, kMaxChunk = std::size_t{1} << 18;
constexpr int kFloatArrays = 7;  // s, t, w, ds_dcol, ds_drow, dt_dcol, dt_drow
}  // namespace

struct CrossingSink::Chunk {
  explicit Chunk(std::size_t n) : values(kFloatArrays * n), tags(n), capacity(n) {}
  float* array(int i) { return values.data() + static_cast<std::size_t>(i) * capacity; }

  HugePageArray<float> values;  // the float arrays one after the other, `capacity` values each
  HugePageArray<std::uint8_t> tags;
  std::size_t capacity, size = 0;
};

CrossingSink::CrossingSink(int rows)
    : rows_(std::max(rows, 0)),
      waiting_(static_cast<std::size_t>(rows_)),
      ready_(static_cast<std::size_t>(rows_), 0) {}

CrossingSink::~CrossingSink() = default;

void CrossingSink::append(const RowCrossings& c) {
  const std::vector<float>* from[kFloatArrays] = {&c.s, &c.t, &c.w, &c.ds_dcol, &c.ds_drow, &c.dt_dcol, &c.dt_drow};
  for (std::size_t done = 0; done < c.size();) {
    if (chunks_.empty() || chunks_.back()->size == chunks_.back()->capacity)
      chunks_.push_back(
          std::make_unique<Chunk>(chunks_.empty() ? kFirstChunk : std::min(2 * chunks_.back()->capacity, kMaxChunk)));
    Chunk& chunk = *chunks_.back();
    const std::size_t n = std::min(c.size() - done, chunk.capacity - chunk.size);
    for (int i = 0; i < kFloatArrays; ++i) std::copy_n(from[i]->data() + done, n, chunk.array(i) + chunk.size);
    std::copy_n(c.tag.data() + done, n, chunk.tags.data() + chunk.size);
    chunk.size += n;
    done += n;
  }
  total_ += c.size();
}

void CrossingSink::commit(int row, RowCrossings* crossings) {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (row < next_ || row >= rows_ || ready_[static_cast<std::size_t>(row)])
    throw std::logic_error("CrossingSink: a row committed twice or out of range");
  if (row != next_) {
    // Kept as it is; the caller goes on with a spare buffer.
    RowCrossings spare;
    if (!spare_.empty()) {
      spare = std::move(spare_.back());
      spare_.pop_back();
    }
    std::swap(waiting_[static_cast<std::size_t>(row)], *crossings);
    std::swap(*crossings, spare);
    ready_[static_cast<std::size_t>(row)] = 1;
    return;
  }
  append(*crossings);
  crossings->clear();
  for (++next_; next_ < rows_ && ready_[static_cast<std::size_t>(next_)]; ++next_) {
    RowCrossings& w = waiting_[static_cast<std::size_t>(next_)];
    append(w);
    w.clear();
    spare_.push_back(std::move(w));
    ready_[static_cast<std::size_t>(next_)] = 0;
  }
}

std::size_t CrossingSink::size() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return total_;
}

void CrossingSink::move_into(TransportMap* map, int threads) {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (next_ != rows_) throw std::logic_error("CrossingSink: not every row was committed");
  std::vector<float>* to[kFloatArrays] = {&map->s_mm,    &map->t_mm,    &map->weight, &map->ds_dcol,
                                          &map->ds_drow, &map->dt_dcol, &map->dt_drow};
  for (std::vector<float>* v : to) reserve_huge(v, v->size() + total_);
  reserve_huge(&map->tag, map->tag.size() + total_);
  for (std::unique_ptr<Chunk>& chunk : chunks_) {
    // The arrays side by side: the copy is mostly first touches of the map's
    // pages, which the kernel serves on each thread at once.
    parallel_rows(kFloatArrays + 1, threads, [&](int i) {
      if (i < kFloatArrays)
        to[i]->insert(to[i]->end(), chunk->array(i), chunk->array(i) + chunk->size);
      else
        map->tag.insert(map->tag.end(), chunk->tags.data(), chunk->tags.data() + chunk->size);
    });
    chunk.reset();  // given back before the next is copied
  }
  chunks_.clear();
  spare_.clear();
}

}  // namespace glasspiv
