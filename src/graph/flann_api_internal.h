/* FLANN's C API as karst uses it (src/graph/knn_flann.c, src/blocks/neighbours_flann.c), loaded
 * on first use.
 *
 * FLANN serves only the alternative neighbour searches: sampling.knn = flann (the default grid
 * search returns the same sets, much faster) and the blocks' independent check. Linked into
 * libkarst, libflann and what it brings (libgomp, liblz4) cost every karst process several
 * milliseconds at start-up (measured on the 2-core project machine: an empty program linked with
 * -lflann starts in 12 ms, without it in 3 ms). So libkarst is not linked with it: the first
 * FLANN search opens the library with dlopen (its soname, KARST_FLANN_SONAME, fixed when karst
 * is configured) and looks up the functions below, typed from FLANN's own header, and its
 * default parameters. */
#ifndef KARST_FLANN_API_INTERNAL_H
#define KARST_FLANN_API_INTERNAL_H

#include <flann/flann.h>

#include "karst/common.h"

#define KARST_I_FLANN_FUNCTIONS(X)                                                                 \
  X(flann_build_index_double)                                                                      \
  X(flann_find_nearest_neighbors_index_double)                                                     \
  X(flann_free_index_double)                                                                       \
  X(flann_log_verbosity)                                                                           \
  X(flann_radius_search_double)

/** The loaded functions (karst_i_flann.flann_build_index_double(...) and so on) and FLANN's
 *  DEFAULT_FLANN_PARAMETERS. */
typedef struct {
#define KARST_I_FLANN_POINTER(name) __typeof__(name) *name;
  KARST_I_FLANN_FUNCTIONS(KARST_I_FLANN_POINTER)
#undef KARST_I_FLANN_POINTER
  const struct FLANNParameters *defaults;
} karst_i_flann_t;

extern karst_i_flann_t karst_i_flann;

/**
 * Load FLANN once per process (thread-safe); later calls return the first call's result.
 * @return KARST_SUCCESS, or KARST_ENOTIMPL with a message naming the library and dlopen's or
 *         dlsym's reason when FLANN cannot be loaded.
 */
karst_error_t karst_i_flann_load(karst_ctx_t *ctx);

#endif
