#include "core/memory_internal.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#if defined(__linux__)
#include <sys/mman.h>
#endif

#define KARST_I_HUGE_PAGE ((size_t)2 << 20)

void *karst_i_alloc_large(size_t bytes) {
  if (bytes < KARST_I_HUGE_PAGE / 2) return malloc(bytes > 0 ? bytes : 1);
  size_t rounded = (bytes + KARST_I_HUGE_PAGE - 1) / KARST_I_HUGE_PAGE * KARST_I_HUGE_PAGE;
  if (rounded < bytes) return NULL; /* overflow */
  void *p = aligned_alloc(KARST_I_HUGE_PAGE, rounded);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  if (p) (void)madvise(p, rounded, MADV_HUGEPAGE);
#endif
  return p;
}

void *karst_i_realloc_large(void *p, size_t used, size_t bytes) {
  if (bytes < KARST_I_HUGE_PAGE / 2) return realloc(p, bytes > 0 ? bytes : 1);
  void *q = karst_i_alloc_large(bytes);
  if (!q) return NULL;
  if (p) memcpy(q, p, used < bytes ? used : bytes);
  free(p);
  return q;
}

void *karst_i_calloc_large(size_t count, size_t size) {
  if (size > 0 && count > SIZE_MAX / size) return NULL;
  size_t bytes = count * size;
  if (bytes < KARST_I_HUGE_PAGE / 2) return calloc(count > 0 ? count : 1, size > 0 ? size : 1);
  void *p = karst_i_alloc_large(bytes);
  if (p) memset(p, 0, bytes);
  return p;
}
