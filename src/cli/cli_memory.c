/* The karst process's heap policy (docs/performance.md, "The CLI's heap"). On the project's
 * machine type a 4 KiB page fault costs about 14 µs, and a small run such as Karst-Synthesis's
 * scene takes about 1 400 of them after start-up: its arrays of 0.1–30 MB are mapped, freed and
 * mapped again from stage to stage, each time touched afresh. So the CLI, before a command runs:
 *  - keeps allocations below 32 MiB in glibc's heap (M_MMAP_THRESHOLD) and does not give the
 *    heap's free top back before it reaches 128 MiB (M_TRIM_THRESHOLD): a stage reuses what the
 *    previous one freed instead of faulting in new pages;
 *  - grows the heap at once by 16 + 64 MiB of address space (M_TOP_PAD; nothing is touched, so
 *    nothing is resident) and asks for transparent huge pages there (MADV_HUGEPAGE): one fault
 *    per 2 MiB instead of 512, which glibc's own glibc.malloc.hugetlb=1 tunable does too but
 *    only from the environment.
 * Larger arrays keep their own 2 MiB-aligned mappings (karst_i_alloc_large). Measured on
 * Karst-Synthesis's scene: 2 182 → 1 023 page faults, peak RSS 37 → 48 MiB, 30 alternated runs
 * median 188 → 174 ms. Only the CLI does this: the library leaves a host program's allocator as
 * it is. Nothing here can fail in a way that matters; without glibc it does nothing. */
#ifndef _DEFAULT_SOURCE
#define _DEFAULT_SOURCE /* sbrk */
#endif
#include <stdint.h>
#include <stdlib.h>

#include "cli.h"

#if defined(__GLIBC__) && defined(__linux__)
#include <malloc.h>
#include <sys/mman.h>
#include <unistd.h>
#endif

void cli_memory_policy(void) {
#if defined(__GLIBC__) && defined(__linux__) && defined(MADV_HUGEPAGE)
  const size_t huge = (size_t)2 << 20, first = (size_t)16 << 20;
  if (!mallopt(M_MMAP_THRESHOLD, 32 << 20) || !mallopt(M_TRIM_THRESHOLD, 128 << 20) ||
      !mallopt(M_TOP_PAD, 64 << 20))
    return;
  char *p = malloc(first); /* below the mmap threshold: from the heap, which grows past it */
  if (!p) return;
  char *top = sbrk(0);
  uintptr_t a = ((uintptr_t)p + huge - 1) & ~(uintptr_t)(huge - 1);
  /* Only when p lies in the brk heap just below its end (not under another allocator). */
  if (top != (char *)-1 && (uintptr_t)p < (uintptr_t)top &&
      (uintptr_t)top - (uintptr_t)p <= ((size_t)256 << 20) && a < (uintptr_t)top)
    (void)madvise((void *)a, (uintptr_t)top - a, MADV_HUGEPAGE);
  free(p);
#endif
}
