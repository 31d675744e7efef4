// Heap policy for the frame pipelines.
#pragma once

namespace faultline {

// Keeps freed heap memory in the process for the next frame instead of handing it back to the
// kernel. Every frame allocates and frees buffers of megabytes (decoded frames, corruption
// scratch, outputs); glibc's defaults map each such buffer fresh and unmap it on free, so each
// frame paid a page fault per 4 KB touched (~1 000 per 1600x900 BGR buffer, about 1 ms of kernel
// time). Blocks up to 32 MB now come from the heap, and the heap is trimmed only past 256 MB of
// free space at its top. Idempotent; does nothing where the C library is not glibc.
void keep_freed_memory();

}  // namespace faultline
