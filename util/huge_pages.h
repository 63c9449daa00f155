#pragma once
// Transparent huge pages for large arrays about to be filled: the kernel then
// maps them 2 MiB at a time, one page fault where 4 KiB pages take 512, and on
// a virtual machine each fault is a trap to the hypervisor (a map build spent
// ~14 % of its time in them; bench/RESULTS.md). No I/O.
#include <cstddef>
#include <type_traits>
#include <utility>
#include <vector>

namespace glasspiv {

// Advises the kernel to back the whole pages inside [data, data + bytes) with
// transparent huge pages where it can (Linux: madvise MADV_HUGEPAGE). Call it
// before the memory is first written. Only advice: nothing changes in what the
// memory holds; a no-op for small ranges, on other systems, or where the
// kernel declines (huge pages off).
void advise_huge_pages(void* data, std::size_t bytes);

// v->reserve(n), the storage advised as above: for a vector about to be filled.
template <class T>
void reserve_huge(std::vector<T>* v, std::size_t n) {
  v->reserve(n);
  advise_huge_pages(v->data(), v->capacity() * sizeof(T));
}

// Memory of its own for `count` values, advised as above: an anonymous
// mapping where the system has them (given back whole when destroyed, whatever
// malloc's thresholds), else the heap. Uninitialised: written before read.
// Throws std::bad_alloc when there is no memory.
void* allocate_huge(std::size_t bytes);
void free_huge(void* data, std::size_t bytes);

template <class T>
class HugePageArray {
  static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>);

 public:
  HugePageArray() = default;
  explicit HugePageArray(std::size_t count)
      : data_(count > 0 ? static_cast<T*>(allocate_huge(count * sizeof(T))) : nullptr), count_(count) {}
  ~HugePageArray() { free_huge(data_, count_ * sizeof(T)); }
  HugePageArray(HugePageArray&& o) noexcept : data_(std::exchange(o.data_, nullptr)), count_(std::exchange(o.count_, 0)) {}
  HugePageArray& operator=(HugePageArray&& o) noexcept {
    std::swap(data_, o.data_);
    std::swap(count_, o.count_);
    return *this;
  }
  HugePageArray(const HugePageArray&) = delete;
  HugePageArray& operator=(const HugePageArray&) = delete;

  T* data() { return data_; }
  const T* data() const { return data_; }
  std::size_t size() const { return count_; }

 private:
  T* data_ = nullptr;
  std::size_t count_ = 0;
};

}  // namespace glasspiv
