/* Private pieces of src/amplification/, exposed for the unit tests. */
#ifndef KARST_AMPLIFICATION_INTERNAL_H
#define KARST_AMPLIFICATION_INTERNAL_H

#include "karst.h"

/**
 * Snap points to graph vertices: snap[i] is the vertex v with in_net[v] == 0 nearest to point
 * i (pts[3i..3i+2]) in Euclidean distance, the smaller index among equally near ones (what a
 * scan of every vertex in ascending order with a strict '<' returns), -1 when every vertex is
 * in the network. A uniform grid of the free vertices (about two per cell) searched in shells:
 * O(n + n_pts) expected, where the scan was O(n × n_pts).
 * @return KARST_SUCCESS or KARST_ENOMEM (snap[] then all -1).
 */
karst_error_t karst_i_amplification_snap(karst_ctx_t *ctx, karst_int_t n, const double *xyz,
                                         const unsigned char *in_net, const double *pts, int n_pts,
                                         karst_int_t *snap);

#endif
