/**
 * @file surface.h
 * @brief Geological surfaces z = f(x, y) of the geology module: the terrain, each
 *        horizon, each water table, a stratum's top and bottom. A surface is a
 *        plane (elevation, dip, dip direction), a regular grid (ESRI ASCII .asc,
 *        bilinear between cell centres, clamped at its border like the terrain) or
 *        a triangulated surface (GOCAD TSurf .ts, linear on each triangle, undefined
 *        outside its triangles). Every surface is single-valued: a folded horizon is
 *        any z = f(x, y); an overturned one is refused when loaded.
 *
 * Queries are const and thread-safe. On a TIN they go through a uniform bucket
 * grid over the triangles (O(1) expected per query). Along a segment every
 * surface is piecewise simple: linear on each triangle of a TIN and on a plane,
 * a quadratic in the segment parameter on each grid cell, so segment tests and
 * integrals are decided exactly piece by piece (karst_surface_segment_pieces).
 * Lengths are metres, angles degrees; x east, y north, z up.
 */
#ifndef KARST_SURFACE_H
#define KARST_SURFACE_H

#include "karst/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Largest surface file read, in bytes (2 GiB, as for heightfields). */
#define KARST_SURFACE_MAX_BYTES (2LL << 30)
/** Most vertices of a triangulated surface (5e7: about 7 GB once indexed). */
#define KARST_SURFACE_MAX_VERTICES 50000000LL
/** Most triangles of a triangulated surface (5e7: about 7 GB once indexed). */
#define KARST_SURFACE_MAX_TRIANGLES 50000000LL
/**
 * Largest |coordinate| of a TIN vertex, in metres (1e9). Projected and local
 * coordinates on Earth stay below 1e8 m; a larger value is a unit or format
 * error, and the bound keeps the exact orientation tests free of overflow.
 */
#define KARST_SURFACE_MAX_COORD 1e9
/**
 * Steepest slope |grad z| of a TIN triangle (1e6, 89.99994 degrees): a steeper
 * one is refused as vertical, since its elevations would carry errors of its
 * slope times the rounding of its coordinates.
 */
#define KARST_SURFACE_MAX_SLOPE 1e6
/**
 * Bucket cells of a TIN's spatial index per triangle (2): the cell size is
 * sqrt(mean triangle area / KARST_SURFACE_BUCKETS_PER_TRIANGLE), so a query
 * scans about three triangles on a regular mesh (see bench/bench_surface.c).
 */
#define KARST_SURFACE_BUCKETS_PER_TRIANGLE 2.0
/**
 * Most pairs of triangles that share a bucket which the overlap check of a TIN
 * examines (2e8, a few seconds). A well-shaped mesh needs about 10 pairs per
 * triangle; a mesh of long slivers fanning over one another can need the square
 * of its size, and is then refused with a message rather than checked for hours.
 */
#define KARST_SURFACE_MAX_OVERLAP_PAIRS 200000000LL

typedef struct karst_surface karst_surface_t;

typedef enum {
  KARST_SURFACE_PLANE = 0, /**< z = elevation at origin, tilted by dip towards dip_direction */
  KARST_SURFACE_GRID = 1,  /**< ESRI ASCII grid, bilinear between cell centres */
  KARST_SURFACE_TIN = 2    /**< triangulated surface (GOCAD TSurf), linear per triangle */
} karst_surface_kind_t;

/** A plane through (origin, elevation) descending by tan(dip) per metre towards dip_direction. */
karst_error_t karst_surface_create_plane(karst_ctx_t *ctx, double elevation, double dip,
                                         double dip_direction, const double origin[2],
                                         karst_surface_t **out);
/** A grid of @p ncols x @p nrows elevations, row 0 southernmost, cell centres from (xll, yll). */
karst_error_t karst_surface_create_grid(karst_ctx_t *ctx, karst_int_t ncols, karst_int_t nrows,
                                        double xll_center, double yll_center, double cellsize,
                                        const double *z, karst_surface_t **out);
/** A TIN of @p nv vertices (x, y, z triples) and @p nt triangles (0-based vertex triples). */
karst_error_t karst_surface_create_tin(karst_ctx_t *ctx, karst_int_t nv, const double *xyz,
                                       karst_int_t nt, const karst_int_t *tri,
                                       karst_surface_t **out);
/** Read a surface file: a GOCAD TSurf (.ts) or an ESRI ASCII grid (.asc), by content. */
karst_error_t karst_surface_load(karst_ctx_t *ctx, const char *path, karst_surface_t **out);
/** Release a surface (NULL is allowed). */
void karst_surface_free(karst_surface_t *s);

karst_surface_kind_t karst_surface_kind(const karst_surface_t *s);
/** The file the surface was read from, or NULL when built in code. */
const char *karst_surface_path(const karst_surface_t *s);
/** The object's name (TSurf HEADER name), or NULL. */
const char *karst_surface_name(const karst_surface_t *s);
/** Vertices and triangles of a TIN (CCW in plan view, duplicates merged); 0 for other kinds. */
int karst_surface_tin(const karst_surface_t *s, const double **xyz, karst_int_t *nv,
                      const karst_int_t **tri, karst_int_t *nt);

/** Elevation at (x, y); NAN outside a TIN's triangles (a grid is clamped at its border). */
double karst_surface_z(const karst_surface_t *s, double x, double y);
/** Gradient (dz/dx, dz/dy) at (x, y); NAN outside a TIN. */
void karst_surface_gradient(const karst_surface_t *s, double x, double y, double g[2]);
/** Error unless the surface is defined over the whole rectangle [lo, hi] (x-y). */
karst_error_t karst_surface_check_covers(karst_ctx_t *ctx, const karst_surface_t *s,
                                         const double lo[2], const double hi[2], const char *what);
/** Bounding box of where the surface is given (infinite x-y for a plane) and its z range. */
void karst_surface_bounds(const karst_surface_t *s, double lo[3], double hi[3]);
/** Lipschitz constant: the largest slope |grad z| anywhere. */
double karst_surface_lipschitz(const karst_surface_t *s);
/** Exact largest elevation over the rectangle [x0, x1] x [y0, y1] (NAN where nowhere defined). */
double karst_surface_max_rect(const karst_surface_t *s, double x0, double x1, double y0, double y1);
/** Exact smallest elevation over the rectangle [x0, x1] x [y0, y1] (NAN where nowhere defined). */
double karst_surface_min_rect(const karst_surface_t *s, double x0, double x1, double y0, double y1);
/**
 * Sorted distinct parameters in (0, 1) where the x-y trace of [a, b] crosses a
 * piece boundary of the surface; the count, or -1 when more than @p max_t.
 */
int karst_surface_segment_pieces(const karst_surface_t *s, const double a[3], const double b[3],
                                 double *t, int max_t);
/** 1 when every interior point of [a, b] is strictly below the surface and its ends at or below. */
int karst_surface_segment_below(const karst_surface_t *s, const double a[3], const double b[3]);
/** 1 when every interior point of [a, b] is strictly above the surface and its ends at or above. */
int karst_surface_segment_above(const karst_surface_t *s, const double a[3], const double b[3]);
/** Triangles of the surface clipped to the rectangle [lo, hi] (arrays to free() by the caller). */
karst_error_t karst_surface_triangulate(karst_ctx_t *ctx, const karst_surface_t *s,
                                        const double lo[2], const double hi[2], double max_edge,
                                        double **xyz, karst_int_t *nv, karst_int_t **tri,
                                        karst_int_t *nt);

#ifdef __cplusplus
}
#endif
#endif /* KARST_SURFACE_H */
