/* Shared by the cost and graph modules: the cost model of a scenario with its
 * per-run constants precomputed (fracture normals, quadrature step), so that
 * millions of edges do not redo trigonometry or walk the tree for them. */
#ifndef KARST_COST_INTERNAL_H
#define KARST_COST_INTERNAL_H

#include "karst/cost.h"
#include "karst/geology.h"

typedef struct karst_i_cost_model {
  const karst_geology_t *geo;
  const karst_scenario_t *sc; /**< the geology's */
  double perm_step;      /**< max quadrature sub-interval for cπ (m), INFINITY if π is constant */
  double prescribed_cos; /**< cos(KARST_COST_PRESCRIBED_MAX_ANGLE) */
  int horizons_planar;   /**< every horizon a plane: the horizon integral is exact */
  double horizon_rmin;   /**< smallest horizon radius (quadrature step of folded horizons) */
  int n_dfn;             /**< fracture families realised as discs */
  /** Closed boxes (lo[3], hi[3]) outside which every permeability primitive
   * returns the background, so that the tree is constant along an edge
   * missing all of them; n_perm_boxes < 0 when not known (then no shortcut). */
  double *perm_boxes;
  int n_perm_boxes;
  double perm_far; /**< π along any edge that misses every box (all primitives at background) */
} karst_i_cost_model_t;

/** Precompute what the scenario's edges share. Allocates the normals; ENOMEM on failure. */
karst_error_t karst_i_cost_model_init(karst_ctx_t *ctx, karst_i_cost_model_t *m,
                                      const karst_geology_t *geo);
void karst_i_cost_model_destroy(karst_i_cost_model_t *m);

/** karst_cost_edge with a precomputed model; thread-safe (reads only). */
double karst_i_cost_edge(const karst_i_cost_model_t *m, const double a[3], const double b[3]);

/** karst_i_cost_edge for end points already known to be in the bedrock. */
double karst_i_cost_edge_inside(const karst_i_cost_model_t *m, const double a[3],
                                const double b[3]);

#endif
