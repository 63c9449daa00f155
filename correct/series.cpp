#include "correct/series.h"

#include <stdexcept>

namespace glasspiv {

std::vector<std::size_t> shard_frames(std::size_t frame_count, int k, int n) {
  if (n < 1 || k < 0 || k >= n) throw std::invalid_argument("shard: need 0 <= K < N");
  std::vector<std::size_t> out;
  for (std::size_t i = static_cast<std::size_t>(k); i < frame_count; i += static_cast<std::size_t>(n)) out.push_back(i);
  return out;
}

}  // namespace glasspiv
