#pragma once
// The C library's allocator in a program linked with PETSc.

namespace lodestone {
inline namespace dist {

/// Blocks of this size and larger are mapped on their own and go back to
/// the system when freed: the largest mapping threshold glibc's allocator
/// adapts to by itself on 64-bit systems.
constexpr int kAllocatorMapThresholdBytes = 32 << 20;  // 32 MiB
/// Free memory at the top of the heap beyond this goes back to the system
/// (twice the mapping threshold, glibc's own rule when it adapts them).
constexpr int kAllocatorTrimThresholdBytes = 64 << 20;  // 64 MiB

/// Debian's PETSc pulls in SuperLU_DIST, whose library constructor sets
/// glibc's allocator, in every program that loads it, to map no block on its
/// own and never hand freed memory back (mallopt M_MMAP_MAX = 0,
/// M_TRIM_THRESHOLD = -1). A run then keeps the memory of every array it
/// ever freed, and its peak grows with the transients of particle emission,
/// reordering and field-problem set-up (desk_toy at full resolution: 1.51
/// GiB resident against 1.29 GiB estimated). Call first thing in main():
/// the allocator then maps and returns blocks from
/// kAllocatorMapThresholdBytes up and trims its heap beyond
/// kAllocatorTrimThresholdBytes, as a program without PETSc does once glibc
/// has adapted its thresholds (1.44 GiB for the same run, at the same
/// speed). No effect outside glibc.
void restoreAllocatorDefaults();

}  // namespace dist
}  // namespace lodestone
