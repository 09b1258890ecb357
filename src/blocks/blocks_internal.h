/* Private pieces shared by the files of src/blocks/. */
#ifndef KARST_BLOCKS_INTERNAL_H
#define KARST_BLOCKS_INTERNAL_H

#include <stdint.h>

#include "karst/blocks.h"

/* Points closer to a plane than this fraction of the tile size count as on
 * it when a cluster's bounding planes are checked, and a polytope vertex
 * supports a face within it (rounding of sums of a few tile-sized terms). */
#define KARST_I_BLOCKS_PLANE_TOL 1e-9
/* Clusters whose points lie within this fraction of the Poisson radius of a
 * plane, line or point are degenerate (thick primitives, §4.2). */
#define KARST_I_BLOCKS_FLAT_REL 1e-3
/* A segment is taken to touch an authored block where its field falls below
 * this fraction of the Poisson radius (sphere tracing, 1-Lipschitz field). */
#define KARST_I_BLOCKS_TRACE_REL 1e-6
/* Far from every block the replication field is capped at this fraction of
 * the tile size (min with a positive constant: same zero set, 1-Lipschitz). */
#define KARST_I_BLOCKS_CAP_REL 0.25
/* A disc that a cluster wraps around grows in its plane by this factor per
 * step until the cluster falls apart (tile.c, make_clusters). */
#define KARST_I_BLOCKS_GROWTH 2.0
/* Newton steps projecting an anchor on the terrain surface (replicate.c). */
#define KARST_I_BLOCKS_PROJECT_STEPS 4
/* Step (m) of the central differences of the terrain gradient at anchors. */
#define KARST_I_BLOCKS_GRAD_STEP 0.05

/* An undirected edge of the periodic graph: x_v + s L is the image of v near
 * x_u. A cut records, for each end, the plane family that cut it on that
 * side and its lattice translate in that end's tile frame. */
typedef struct karst_i_edge {
  int32_t u, v;
  int8_t L[3];
  uint8_t cut;    /* 0 kept, 1 cut by a plane family, 2 removed (authored) */
  int32_t fam[2]; /* plane family at u, at v (-1 none) */
  int8_t M[2][3]; /* its translate in u's frame, in v's frame */
} karst_i_edge_t;

/* Radius neighbour graph of points in the periodic cube [0, s)³ (grid
 * search): every pair closer than @p radius once, u < v, in a deterministic
 * order. *edges is malloc'd. radius must be < s/3. */
karst_error_t karst_i_blocks_radius_graph(karst_ctx_t *ctx, const double *xyz, karst_int_t n,
                                          double s, double radius, karst_i_edge_t **edges,
                                          karst_int_t *n_edges);
/* The same pairs through FLANN's radius search on the points and their
 * periodic ghosts (neighbours_flann.c), sorted like the grid search's. */
karst_error_t karst_i_blocks_radius_graph_flann(karst_ctx_t *ctx, const double *xyz, karst_int_t n,
                                                double s, double radius, karst_i_edge_t **edges,
                                                karst_int_t *n_edges);
/* Sort edges by (u, v, L) (the canonical order both searches return). */
void karst_i_blocks_sort_edges(karst_i_edge_t *e, karst_int_t n);

/* Periodic Poisson-disc sampling of [0, s)³ with smallest distance r. */
karst_error_t karst_i_blocks_poisson(karst_ctx_t *ctx, double s, double r, int passes,
                                     karst_rng_t *rng, double **xyz, karst_int_t *n);

/* Exact segment–disc test: 1 when the closed segment a b meets the closed
 * disc, with *t its parameter on the segment. A segment lying in the disc's
 * plane does not cut it. */
int karst_i_blocks_segment_disc(const double a[3], const double b[3], const double c[3],
                                const double n[3], double radius, double *t);

/* Field of block i at p (tile frame), with the evaluation contract of
 * implicit_internal.h (exact below ub); *label (may be NULL) gets its label. */
double karst_i_blocks_block_eval(const karst_blocks_tile_t *t, karst_int_t i, const double p[3],
                                 double ub, int *label);

#endif
