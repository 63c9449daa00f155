#include "util/huge_pages.h"

#include <cstdint>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

namespace glasspiv {

namespace {
constexpr std::size_t kHugePage = std::size_t{2} << 20;
}  // namespace

void advise_huge_pages(void* data, std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  if (data == nullptr || bytes < 2 * kHugePage) return;  // too small to hold an aligned huge page
  const long page_size = sysconf(_SC_PAGESIZE);
  if (page_size <= 0) return;
  const auto page = static_cast<std::uintptr_t>(page_size);
  const auto first = reinterpret_cast<std::uintptr_t>(data);
  const std::uintptr_t begin = (first + page - 1) / page * page, end = (first + bytes) / page * page;
  // The range is memory this process owns: madvise can only decline (EINVAL
  // where THP is compiled out), which leaves ordinary pages.
  if (end > begin) (void)madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#else
  (void)data;
  (void)bytes;
#endif
}

void* allocate_huge(std::size_t bytes) {
  if (bytes == 0) return nullptr;
#if defined(__linux__)
  void* p = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED) throw std::bad_alloc();
  advise_huge_pages(p, bytes);
  return p;
#else
  return ::operator new(bytes);
#endif
}

void free_huge(void* data, std::size_t bytes) {
  if (data == nullptr) return;
#if defined(__linux__)
  munmap(data, bytes);
#else
  (void)bytes;
  ::operator delete(data);
#endif
}

}  // namespace glasspiv
