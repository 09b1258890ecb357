/* Searches for other stages of the library only. */
#ifndef KARST_PATHS_INTERNAL_H
#define KARST_PATHS_INTERNAL_H

#include "karst/paths.h"

/**
 * karst_paths_dijkstra_routed that polls @p check(@p arg) every 256 settled vertices and stops
 * with KARST_EINTERRUPTED when it returns non-zero: the amplification stops a point's search
 * computed ahead as soon as an earlier point's paths meet what it has read (src/amplification/).
 * Without @p check the searches of karst_paths_dijkstra_routed run unchanged (the loop with the
 * poll is a separate instance).
 */
karst_error_t karst_i_paths_dijkstra_checked(karst_ctx_t *ctx, karst_search_t *s,
                                             const karst_route_t *route, karst_int_t n_sources,
                                             const karst_int_t *sources,
                                             const unsigned char *blocked,
                                             const unsigned char *is_target, karst_int_t stop_after,
                                             karst_int_t *last_target, int (*check)(void *),
                                             void *arg);

#endif
