#pragma once
/// Fresh memory about to be written whole (the block build's 200 MB on a million DOFs) faulted in
/// with one call instead of one page fault per 4 KB page on first touch: the kernel still zeroes
/// the pages, but the per-page traps were about a quarter of the SBSR build's time on press_1m
/// (docs/setup_at_scale.md). Contents are kept; where the call is not available (not Linux, or a
/// kernel before 5.14) nothing is done and the pages fault in as they are written.
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

}  // namespace cb
