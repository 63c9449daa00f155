#pragma once
// Transparent huge pages for a large array about to be filled: the kernel then
// maps it 2 MiB at a time, one page fault where 4 KiB pages take 512, and on a
// virtual machine each fault is a trap to the hypervisor (a map build spent
// ~14 % of its time in them; bench/RESULTS.md). No I/O.
#include <cstddef>
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

}  // namespace glasspiv
