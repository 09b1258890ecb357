#include "core/memory_internal.h"

#include <stdlib.h>
#if defined(__linux__)
#include <sys/mman.h>
#endif

#define KARST_I_HUGE_PAGE ((size_t)2 << 20)

void *karst_i_alloc_large(size_t bytes) {
  if (bytes < 2 * KARST_I_HUGE_PAGE) return malloc(bytes > 0 ? bytes : 1);
  size_t rounded = (bytes + KARST_I_HUGE_PAGE - 1) / KARST_I_HUGE_PAGE * KARST_I_HUGE_PAGE;
  if (rounded < bytes) return NULL; /* overflow */
  void *p = aligned_alloc(KARST_I_HUGE_PAGE, rounded);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  if (p) (void)madvise(p, rounded, MADV_HUGEPAGE);
#endif
  return p;
}
