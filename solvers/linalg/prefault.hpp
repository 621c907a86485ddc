#pragma once
/// Fresh memory about to be written whole (the block build's 200 MB on a million DOFs) faulted in
/// with one call instead of one page fault per 4 KB page on first touch: the kernel still zeroes
/// the pages, but the per-page traps were about a quarter of the SBSR build's time on press_1m
/// (docs/setup_at_scale.md). Contents are kept; where the call is not available (not Linux, or a
/// kernel before 5.14) nothing is done and the pages fault in as they are written.
/// A's blocks, which every product streams, also ask for transparent huge pages: on 4 KB pages the
/// stream paid a page walk and a restart of the hardware prefetch every 4 KB (docs/a_product.md).
#include <cstddef>
#include <cstdint>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace cb {

/// Faults in the whole pages of [data, data + bytes) for writing; false when the system did not.
inline bool prefault_for_writing(void* data, std::size_t bytes)
{
#if defined(__linux__)
#ifndef MADV_POPULATE_WRITE
#define MADV_POPULATE_WRITE 23  // Linux 5.14; older C headers lack the name
#endif
    constexpr std::size_t page = 4096;
    const std::size_t head = (page - reinterpret_cast<std::uintptr_t>(data) % page) % page;  // to the first whole page
    if (bytes <= head) return false;
    const std::size_t length = (bytes - head) / page * page;
    if (length == 0) return false;
    return madvise(static_cast<char*>(data) + head, length, MADV_POPULATE_WRITE) == 0;
#else
    (void)data;
    (void)bytes;
    return false;
#endif
}

/// The 2 MB pages wholly inside the `bytes` from `address`, as offsets [begin, end) from it; false
/// when there are none (fewer than two huge pages' bytes). The address is only read as a number.
inline bool huge_page_interior(std::uintptr_t address, std::size_t bytes, std::size_t& begin, std::size_t& end)
{
    constexpr std::size_t huge = std::size_t{2} << 20;
    if (bytes < 2 * huge) return false;
    const std::size_t misalign = address & (huge - 1);
    begin = (huge - misalign) & (huge - 1);
    end = bytes - ((misalign + bytes) & (huge - 1));
    return end > begin;
}

/// Asks for transparent huge pages on a buffer not yet written: its first touch (or the prefault)
/// then maps 2 MB pages. Only a hint; false when not given (no whole huge page, not Linux).
inline bool advise_huge_pages(void* data, std::size_t bytes)
{
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    std::size_t begin = 0, end = 0;
    if (!huge_page_interior(reinterpret_cast<std::uintptr_t>(data), bytes, begin, end)) return false;
    return madvise(static_cast<char*>(data) + begin, end - begin, MADV_HUGEPAGE) == 0;
#else
    (void)data;
    (void)bytes;
    return false;
#endif
}

/// prefault_for_writing() on huge pages where the system gives them.
inline bool prefault_huge_for_writing(void* data, std::size_t bytes)
{
    advise_huge_pages(data, bytes);
    return prefault_for_writing(data, bytes);
}

}  // namespace cb
