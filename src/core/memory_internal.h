/* Allocation of the large arrays (graph arcs, neighbour tables, search
 * records, sampling grids): on Linux they are asked to be backed by 2 MiB
 * pages. A search over a 1.5-million-vertex graph walks 2.5 GB of arcs in
 * heap order, so with 4 KiB pages nearly every arc list costs a TLB miss, and
 * first touching the arrays costs one page fault per 4 KiB. On the 2-core
 * project machine (a virtual machine) a 4 KiB fault costs about 14 µs, so an
 * array of a few MiB filled once costs milliseconds in faults alone: from
 * 1 MiB on, the array is rounded up to whole 2 MiB pages (at most 1 MiB more
 * resident, once per array) and faults once per 2 MiB. */
#ifndef KARST_MEMORY_INTERNAL_H
#define KARST_MEMORY_INTERNAL_H

#include <stddef.h>

/**
 * Like malloc(bytes) (release with free()), but an array of 1 MiB or more
 * is rounded up to whole 2 MiB pages, aligned to 2 MiB and advised as a transparent-huge-page
 * candidate (madvise MADV_HUGEPAGE; the advice is only a hint and its failure is ignored). Returns
 * NULL when out of memory, as malloc does.
 */
void *karst_i_alloc_large(size_t bytes);

/**
 * Like calloc(count, size) (release with free()), with the page advice of
 * karst_i_alloc_large. Returns NULL when out of memory or when count × size
 * overflows.
 */
void *karst_i_calloc_large(size_t count, size_t size);

/**
 * Like realloc(p, bytes) for an array that grows (release with free()): the
 * first @p used bytes are kept; from 1 MiB on the new block comes from
 * karst_i_alloc_large (the old one is copied and freed). On failure returns
 * NULL and leaves @p p as it was.
 */
void *karst_i_realloc_large(void *p, size_t used, size_t bytes);

#endif
