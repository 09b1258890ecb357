/* Shared by the modules that query the geology in their inner loops (sampling, costs, routing):
 * the model's layout, and the surface evaluation behind every geological surface. */
#ifndef KARST_GEOLOGY_INTERNAL_H
#define KARST_GEOLOGY_INTERNAL_H

#include "karst/geology.h"

/* ------------------------------------------------------------------------ */
/* Surfaces z = f(x, y)                                                      */
/* ------------------------------------------------------------------------ */

typedef enum {
  KARST_I_SURF_NONE = 0,  /* not given */
  KARST_I_SURF_PLANE = 1, /* z0 − tan(dip) × distance along the dip direction from (ox, oy) */
  KARST_I_SURF_FILE = 2   /* a grid or triangulated surface (include/karst/surface.h) */
} karst_i_surf_kind_t;

/** One geological surface with its evaluation constants. */
typedef struct karst_i_surf {
  int kind;                         /**< karst_i_surf_kind_t */
  double z0, ox, oy, sa, ca, t;     /**< plane: elevation at (ox, oy), sin/cos of the dip
                                         direction, tan of the dip */
  int flat;                         /**< plane with dip 0: z = z0 */
  const karst_terrain_t *grid;      /**< KARST_I_SURF_GRID */
  const struct karst_surface *file; /**< KARST_I_SURF_FILE */
} karst_i_surf_t;

/** A plane surface (karst_horizon_elevation's convention). */
karst_i_surf_t karst_i_surf_plane(double elevation, double dip, double dip_direction, double ox,
                                  double oy);
/** The surface of a scenario surface definition (KARST_I_SURF_NONE when not given). */
karst_i_surf_t karst_i_surf_of_def(const karst_surface_def_t *d);

/** Whether two surfaces are the same (same kind and parameters, or the same grid or file). */
int karst_i_surf_equal(const karst_i_surf_t *a, const karst_i_surf_t *b);
/** z at (x, y); NAN for KARST_I_SURF_NONE or outside a file surface. */
double karst_i_surf_z(const karst_i_surf_t *s, double x, double y);
/** Exact range of z over the rectangle [x0, x1] x [y0, y1]. */
void karst_i_surf_range(const karst_i_surf_t *s, double x0, double x1, double y0, double y1,
                        double *zlo, double *zhi);
/** An enclosing (not always tight) range of z over the rectangle, in O(1): exact for a plane,
 *  the centre ± Lipschitz × half-diagonal for a file surface. */
void karst_i_surf_range_bound(const karst_i_surf_t *s, double x0, double x1, double y0, double y1,
                              double *zlo, double *zhi);
/**
 * Sign of the segment [a, b] against the surface, exactly: returns 1 when z(t) − f(t) < 0 for
 * every t in (0, 1) (@p strict) or <= 0 for every t in [0, 1] (!strict), else 0. With @p above,
 * the same for f(t) − z(t).
 */
int karst_i_surf_segment_side(const karst_i_surf_t *s, const double a[3], const double b[3],
                              int above, int strict);

/* ------------------------------------------------------------------------ */
/* The model                                                                 */
/* ------------------------------------------------------------------------ */

struct karst_geology {
  const karst_scenario_t *sc;
  karst_i_surf_t terrain;
  struct karst_surface *terrain_view; /* the grid surface over a heightfield's elevations */
  int n_horizons;
  karst_i_surf_t *horizon; /* one per scenario horizon */
  int n_springs;
  int *spring_key;             /* key-point index of each spring */
  int *key_spring;             /* per key point: its spring index, or -1 */
  karst_i_surf_t *water_table; /* one per spring */
  int n_strata;
  karst_i_surf_t *stratum_top, *stratum_bottom; /* NONE: the terrain / the domain bottom */
  int n_insoluble;
  double band; /* routing.water_table_band */
  /* Fracture families: the mean-pole tensors E[n nᵀ] of their Fisher distributions. */
  double *fracture_tensor; /* 9 per family */
  double fracture_wmax;    /* the largest family weight (fracture_combine: min starts there) */
  /* Realised discs of every discrete fracture network, and a uniform grid over them. */
  karst_disc_t *discs;
  karst_int_t n_discs;
  double disc_cell, disc_origin[3];
  int64_t disc_dims[3];
  karst_int_t *disc_start; /* CSR over the cells of the disc grid: disc_start[c] .. [c + 1] */
  karst_int_t *disc_list;
  /* Faults: unit normals. */
  double *fault_normal; /* 3 per fault */
};

/** Whether [a, b] crosses a closed exclusion box / sphere / prism. */
int karst_i_segment_hits_exclusion(const karst_exclusion_t *e, const double a[3],
                                   const double b[3]);
/** Whether p lies in the closed exclusion zone. */
int karst_i_point_in_exclusion(const karst_exclusion_t *e, const double p[3]);

/** karst_geology_segment_in_bedrock for end points already known to be in the bedrock
 *  (karst_geology_in_bedrock of each is 1): the tests of the segment's interior alone. */
int karst_i_geology_segment_between(const karst_geology_t *g, const double a[3], const double b[3]);

/** Mean-pole tensor E[n nᵀ] (row-major 3 x 3) of a Fisher distribution of concentration κ about
 *  the unit pole @p mu; κ = 0 (no dispersion) or INFINITY gives mu muᵀ. */
void karst_i_fisher_tensor(const double mu[3], double kappa, double T[9]);
/** Draw a unit pole from the Fisher distribution of concentration κ about @p mu (Wood 1994). */
void karst_i_fisher_draw(karst_rng_t *rng, const double mu[3], double kappa, double n[3]);

/** Discs of the realised fracture networks whose grid cell holds @p p: calls @p fn on each
 *  until it returns non-zero (then returns that value), else 0. */
int karst_i_geology_discs_at(const karst_geology_t *g, const double p[3],
                             int (*fn)(const karst_disc_t *d, void *arg), void *arg);

#endif
