/* Shared by the files of the surface code (src/geology/surface*.c) and the GOCAD
 * TSurf reader (src/io/read_tsurf.c); not part of the public API. */
#ifndef KARST_GEOLOGY_SURFACE_INTERNAL_H
#define KARST_GEOLOGY_SURFACE_INTERNAL_H

#include "karst/surface.h"

/**
 * A triangle of a TIN's spatial index is also listed in a bucket it misses by
 * less than this fraction of a bucket, so that rounding in the clipped extent of
 * a triangle can never leave it out of a bucket it touches (a superset of
 * buckets costs a little speed, never a wrong answer). Default 1e-9.
 */
#define KARST_I_BUCKET_MARGIN 1e-9

struct karst_surface {
  karst_surface_kind_t kind;
  char *path; /* file read, or NULL */
  char *name; /* TSurf object name, or NULL */
  double lo[3], hi[3];
  double lipschitz;
  /* plane: z = z0 - ((x - ox) sin a + (y - oy) cos a) tan d, as karst_horizon_elevation */
  double z0, ox, oy, sin_a, cos_a, tan_d, dip;
  /* grid: cell centres xll + i cs, yll + j cs; z[j * ncols + i], row 0 southernmost */
  karst_int_t ncols, nrows;
  double xll, yll, cs;
  double *z;
  int z_borrowed; /* z belongs to the caller (karst_i_surface_grid_view): not freed */
  /* TIN */
  karst_int_t nv, nt;
  double *xyz;      /* 3 nv */
  karst_int_t *tri; /* 3 nt, counter-clockwise in plan view */
  double *tdata;    /* 9 nt: x0 y0 x1 y1 x2 y2, z0, dz/dx, dz/dy of each triangle */
  karst_int_t *nbr; /* 3 nt: triangle across the edge from vertex k to k+1, or -1 */
  karst_int_t nbnd; /* border edges (one triangle only) ... */
  karst_int_t *bnd; /* ... as 2 nbnd vertex indices */
  /* bucket grid over [bx0, bx0 + bnx bcs] x [by0, by0 + bny bcs] */
  karst_int_t bnx, bny;
  double bx0, by0, bcs, binv;
  karst_int_t *bstart; /* bnx bny + 1 offsets into bitem */
  karst_int_t *bitem;  /* triangle indices, the one holding the bucket's centre first */
};

/**
 * A grid surface over the caller's elevations (not copied: @p z must outlive it), e.g. the
 * terrain a scenario already holds, so that a large heightfield is not stored twice.
 */
karst_error_t karst_i_surface_grid_view(karst_ctx_t *ctx, karst_int_t ncols, karst_int_t nrows,
                                        double xll_center, double yll_center, double cellsize,
                                        const double *z, karst_surface_t **out);

/** Where the vertices and triangles of a TIN came from, to name them in messages. */
typedef struct karst_i_tin_source {
  const char *path;       /* file, or NULL when built in code */
  const long *vline;      /* line of each vertex's VRTX / PVRTX, or NULL */
  const long *tline;      /* line of each TRGL, or NULL */
  const karst_int_t *vid; /* id of each vertex in the file, or NULL (the index is named) */
} karst_i_tin_source_t;

/**
 * Build and check a TIN (see karst_surface_create_tin); messages name the
 * file and line of the offending VRTX or TRGL through @p src.
 */
karst_error_t karst_i_surface_tin(karst_ctx_t *ctx, karst_int_t nv, const double *xyz,
                                  karst_int_t nt, const karst_int_t *tri,
                                  const karst_i_tin_source_t *src, karst_surface_t **out);

/** Triangle of a TIN whose closed plan-view area holds (x, y), lowest index first, or -1. */
karst_int_t karst_i_tin_locate(const karst_surface_t *s, double x, double y);
/** The same by scanning every triangle (the reference for the index's tests). O(nt). */
karst_int_t karst_i_tin_locate_brute(const karst_surface_t *s, double x, double y);
/** Sign (-1, 0, 1) of the orientation of (a, b, c) in plan view, exact (Shewchuk 1997). */
int karst_i_orient2d(const double a[2], const double b[2], const double c[2]);

/* TIN halves of the public queries (src/geology/surface_tin.c). */
int karst_i_tin_pieces(const karst_surface_t *s, const double a[3], const double b[3], double t0,
                       double t1, double *t, int max_t);
double karst_i_tin_extreme_rect(const karst_surface_t *s, double x0, double x1, double y0,
                                double y1, double sign);
karst_error_t karst_i_tin_check_covers(karst_ctx_t *ctx, const karst_surface_t *s,
                                       const double lo[2], const double hi[2], const char *what);
karst_error_t karst_i_tin_triangulate(karst_ctx_t *ctx, const karst_surface_t *s,
                                      const double lo[2], const double hi[2], double **xyz,
                                      karst_int_t *nv, karst_int_t **tri, karst_int_t *nt);

/* ------------------------------------------------------------------------ */
/* GOCAD TSurf                                                               */
/* ------------------------------------------------------------------------ */

/** What karst_i_tsurf_read returns: the geometry with its lines, and the metadata kept. */
typedef struct karst_i_tsurf {
  karst_int_t nv, nt;
  double *xyz;      /* 3 nv, z up (ZPOSITIVE Depth negated), metres (AXIS_UNIT applied) */
  karst_int_t *vid; /* id of each vertex in the file */
  long *vline;      /* line of each VRTX / PVRTX */
  karst_int_t *tri; /* 3 nt vertex indices (ATOM ids resolved to the vertex they repeat) */
  long *tline;      /* line of each TRGL */
  int *tpart;       /* TFACE part of each triangle, 0-based, counted over the whole file */
  int nparts;       /* TFACE parts */
  int nobjects;     /* GOCAD TSurf objects in the file */
  int zdepth;       /* 1 when the (first) object said ZPOSITIVE Depth */
  karst_int_t natoms;
  karst_int_t nbstones, nborders;
  char *name; /* HEADER name of the first object, or NULL */
  int nprops; /* PROPERTIES of the first object (kept when every object has the same) */
  char **prop_names;
  int *prop_esize;
  int prop_stride; /* sum of the ESIZES */
  double *props;   /* prop_stride values per vertex (NO_DATA_VALUES -> NAN), or NULL */
} karst_i_tsurf_t;

/**
 * Read a GOCAD TSurf file (one or more TSurf objects, each with TFACE parts).
 * Errors read "FILE:LINE: message" with the offending value. On failure @p ts
 * is left empty. Time complexity: O(file size) expected.
 */
karst_error_t karst_i_tsurf_read(karst_ctx_t *ctx, const char *path, karst_i_tsurf_t *ts);
/** Release what karst_i_tsurf_read allocated (a zeroed struct is allowed). */
void karst_i_tsurf_destroy(karst_i_tsurf_t *ts);

#endif
