/* Geological surfaces z = f(x, y): planes, ESRI grids and the dispatch of every
 * query to the three kinds (TINs are in surface_tin.c). The grid is the terrain's
 * bilinear surface between cell centres, clamped at its border, evaluated with
 * the operations of karst_terrain_height so that a terrain read as a surface
 * gives the same elevations to the bit. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "geology/surface_internal.h"
#include "karst/scenario.h"
#include "scenario/scenario_internal.h"

/* Piece boundaries looked up at once by the segment tests; a segment crossing
 * more is split in halves (the answer does not depend on this number). */
#define SEGMENT_PIECES_BUF 128

static double clampd(double x, double a, double b) {
  return x < a ? a : (x > b ? b : x);
}

static karst_surface_t *surface_alloc(karst_surface_kind_t kind) {
  karst_surface_t *s = calloc(1, sizeof *s);
  if (s) s->kind = kind;
  return s;
}

/**
 * Release a surface and everything it owns.
 * @param s the surface, or NULL.
 * Time complexity: O(1).
 */
void karst_surface_free(karst_surface_t *s) {
  if (!s) return;
  free(s->path);
  free(s->name);
  if (!s->z_borrowed) free(s->z);
  free(s->xyz);
  free(s->tri);
  free(s->tdata);
  free(s->nbr);
  free(s->bnd);
  free(s->bstart);
  free(s->bitem);
  free(s);
}

/** The kind of @p s (plane, grid or TIN). O(1). */
karst_surface_kind_t karst_surface_kind(const karst_surface_t *s) {
  return s->kind;
}

/** The file @p s was read from as given to karst_surface_load, or NULL. O(1). */
const char *karst_surface_path(const karst_surface_t *s) {
  return s->path;
}

/** The TSurf object name (HEADER name:), or NULL. O(1). */
const char *karst_surface_name(const karst_surface_t *s) {
  return s->name;
}

/**
 * The vertices and triangles of a TIN as indexed: exact duplicates merged,
 * every triangle counter-clockwise seen from above.
 * @param s the surface; @param xyz, nv, tri, nt receive the arrays (owned by @p s).
 * @return 1 for a TIN, else 0 (outputs untouched).
 * Time complexity: O(1).
 */
int karst_surface_tin(const karst_surface_t *s, const double **xyz, karst_int_t *nv,
                      const karst_int_t **tri, karst_int_t *nt) {
  if (s->kind != KARST_SURFACE_TIN) return 0;
  *xyz = s->xyz;
  *nv = s->nv;
  *tri = s->tri;
  *nt = s->nt;
  return 1;
}

/* ------------------------------------------------------------------------ */
/* Plane                                                                     */
/* ------------------------------------------------------------------------ */

/**
 * A plane through (@p origin, @p elevation) whose surface descends by tan(dip)
 * per metre towards the dip direction: the convention of karst_horizon_elevation
 * and karst_plane_normal (x east, y north, dip direction clockwise from north),
 * with the same operations, so both give the same elevations to the bit.
 * @param ctx context for the message; @param elevation z at the origin (m);
 * @param dip degrees in [0, 90); @param dip_direction degrees (any finite value);
 * @param origin (x, y) of the given elevation; @param out receives the surface.
 * @return KARST_SUCCESS, KARST_EINVAL (a value not finite, dip outside [0, 90))
 *         or KARST_ENOMEM. Time complexity: O(1).
 */
karst_error_t karst_surface_create_plane(karst_ctx_t *ctx, double elevation, double dip,
                                         double dip_direction, const double origin[2],
                                         karst_surface_t **out) {
  *out = NULL;
  if (!isfinite(elevation) || !isfinite(dip_direction) || !isfinite(origin[0]) ||
      !isfinite(origin[1]))
    return karst_set_error(ctx, KARST_EINVAL,
                           "plane surface: elevation, dip direction and origin must be finite, got "
                           "%g, %g and (%g, %g)",
                           elevation, dip_direction, origin[0], origin[1]);
  if (!(dip >= 0.0 && dip < 90.0))
    return karst_set_error(ctx, KARST_EINVAL,
                           "plane surface: dip must be within [0, 90) degrees, got %g", dip);
  karst_surface_t *s = surface_alloc(KARST_SURFACE_PLANE);
  if (!s) return karst_set_error(ctx, KARST_ENOMEM, "plane surface: out of memory");
  const double d2r = M_PI / 180.0;
  s->z0 = elevation;
  s->dip = dip;
  s->ox = origin[0];
  s->oy = origin[1];
  s->sin_a = sin(dip_direction * d2r);
  s->cos_a = cos(dip_direction * d2r);
  s->tan_d = tan(dip * d2r);
  s->lipschitz = dip == 0.0 ? 0.0 : s->tan_d;
  s->lo[0] = s->lo[1] = -INFINITY;
  s->hi[0] = s->hi[1] = INFINITY;
  s->lo[2] = dip == 0.0 ? elevation : -INFINITY;
  s->hi[2] = dip == 0.0 ? elevation : INFINITY;
  *out = s;
  return KARST_SUCCESS;
}

static double plane_z(const karst_surface_t *s, double x, double y) {
  if (s->dip == 0.0) return s->z0;
  double along = (x - s->ox) * s->sin_a + (y - s->oy) * s->cos_a;
  return s->z0 - along * s->tan_d;
}

/* ------------------------------------------------------------------------ */
/* Grid                                                                      */
/* ------------------------------------------------------------------------ */

/* Largest |grad| of the bilinear surface. Inside a cell dz/dx is linear in v
 * alone and dz/dy linear in u alone, so |grad|^2 = gx(v)^2 + gy(u)^2 is largest
 * at a corner: sqrt(max(|dz south|, |dz north|)^2 + max(|dz west|, |dz east|)^2)
 * / cellsize. Clamping outside the grid only flattens the surface. O(cells). */
static double grid_max_slope(const karst_surface_t *s) {
  karst_int_t nc = s->ncols, nr = s->nrows;
  double best = 0;
  for (karst_int_t j = 0; j + 1 < nr || (nr == 1 && j == 0); j++) {
    karst_int_t j1 = nr > 1 ? j + 1 : j;
    for (karst_int_t i = 0; i + 1 < nc || (nc == 1 && i == 0); i++) {
      karst_int_t i1 = nc > 1 ? i + 1 : i;
      const double *lo = s->z + j * nc, *up = s->z + j1 * nc;
      double ex = fmax(fabs(lo[i1] - lo[i]), fabs(up[i1] - up[i]));
      double ey = fmax(fabs(up[i] - lo[i]), fabs(up[i1] - lo[i1]));
      best = fmax(best, hypot(ex, ey) / s->cs);
    }
  }
  return best;
}

/* Bounds of a grid: the cell edges it covers in x-y, and the range of its nodes
 * (the bilinear surface stays within it). */
static void grid_finish(karst_surface_t *s) {
  double h = 0.5 * s->cs;
  s->lo[0] = s->xll - h;
  s->hi[0] = s->xll + ((double)s->ncols - 0.5) * s->cs;
  s->lo[1] = s->yll - h;
  s->hi[1] = s->yll + ((double)s->nrows - 0.5) * s->cs;
  s->lo[2] = INFINITY;
  s->hi[2] = -INFINITY;
  for (karst_int_t k = 0; k < s->ncols * s->nrows; k++) {
    s->lo[2] = fmin(s->lo[2], s->z[k]);
    s->hi[2] = fmax(s->hi[2], s->z[k]);
  }
  s->lipschitz = grid_max_slope(s);
}

/**
 * A regular grid surface: elevations at cell centres (xll + i cs, yll + j cs),
 * @p z[j * ncols + i] with row 0 the southernmost, interpolated bilinearly and
 * clamped at the border (the terrain heightfield's surface).
 * @param ctx context; @param ncols, nrows sizes >= 1 (at most
 * KARST_HEIGHTFIELD_MAX_CELLS cells); @param xll_center, yll_center centre of
 * the south-west cell; @param cellsize > 0; @param z the elevations (copied);
 * @param out receives the surface.
 * @return KARST_SUCCESS, KARST_EINVAL (size, cell size or a value not finite,
 *         naming the cell), KARST_ERANGE (too many cells) or KARST_ENOMEM.
 * Time complexity: O(ncols nrows).
 */
static karst_error_t create_grid(karst_ctx_t *ctx, karst_int_t ncols, karst_int_t nrows,
                                 double xll_center, double yll_center, double cellsize,
                                 const double *z, int borrow, karst_surface_t **out);

karst_error_t karst_surface_create_grid(karst_ctx_t *ctx, karst_int_t ncols, karst_int_t nrows,
                                        double xll_center, double yll_center, double cellsize,
                                        const double *z, karst_surface_t **out) {
  return create_grid(ctx, ncols, nrows, xll_center, yll_center, cellsize, z, 0, out);
}

karst_error_t karst_i_surface_grid_view(karst_ctx_t *ctx, karst_int_t ncols, karst_int_t nrows,
                                        double xll_center, double yll_center, double cellsize,
                                        const double *z, karst_surface_t **out) {
  return create_grid(ctx, ncols, nrows, xll_center, yll_center, cellsize, z, 1, out);
}

static karst_error_t create_grid(karst_ctx_t *ctx, karst_int_t ncols, karst_int_t nrows,
                                 double xll_center, double yll_center, double cellsize,
                                 const double *z, int borrow, karst_surface_t **out) {
  *out = NULL;
  if (ncols < 1 || nrows < 1)
    return karst_set_error(ctx, KARST_EINVAL,
                           "grid surface: ncols and nrows must be >= 1, got %lld and %lld",
                           (long long)ncols, (long long)nrows);
  if (ncols > KARST_HEIGHTFIELD_MAX_CELLS / nrows)
    return karst_set_error(
        ctx, KARST_ERANGE, "grid surface: %lld x %lld cells, more than the limit of %lld",
        (long long)ncols, (long long)nrows, (long long)KARST_HEIGHTFIELD_MAX_CELLS);
  if (!(cellsize > 0) || !isfinite(cellsize) || !isfinite(xll_center) || !isfinite(yll_center))
    return karst_set_error(ctx, KARST_EINVAL,
                           "grid surface: cellsize must be finite and > 0 and the corner finite, "
                           "got cellsize %g at (%g, %g)",
                           cellsize, xll_center, yll_center);
  for (karst_int_t k = 0; k < ncols * nrows; k++)
    if (!isfinite(z[k]))
      return karst_set_error(ctx, KARST_EINVAL,
                             "grid surface: the elevation of column %lld, row %lld (from the "
                             "south) must be finite, got %g",
                             (long long)(k % ncols + 1), (long long)(k / ncols + 1), z[k]);
  karst_surface_t *s = surface_alloc(KARST_SURFACE_GRID);
  double *copy = borrow ? (double *)z : malloc((size_t)(ncols * nrows) * sizeof *copy);
  if (!s || !copy) {
    free(s);
    if (!borrow) free(copy);
    return karst_set_error(ctx, KARST_ENOMEM, "grid surface: out of memory for %lld cells",
                           (long long)(ncols * nrows));
  }
  if (!borrow) memcpy(copy, z, (size_t)(ncols * nrows) * sizeof *copy);
  s->z_borrowed = borrow;
  s->ncols = ncols;
  s->nrows = nrows;
  s->xll = xll_center;
  s->yll = yll_center;
  s->cs = cellsize;
  s->z = copy;
  grid_finish(s);
  *out = s;
  return KARST_SUCCESS;
}

/* Cell (i, j) and local coordinates (u, v) of (x, y), clamped at the border as
 * karst_terrain_height does; *cx, *cy are 1 where x, y lie outside the nodes. */
static void grid_cell(const karst_surface_t *s, double x, double y, karst_int_t *i, karst_int_t *j,
                      double *u, double *v, int *cx, int *cy) {
  double rx = (x - s->xll) / s->cs, ry = (y - s->yll) / s->cs;
  double fx = clampd(rx, 0.0, (double)(s->ncols - 1));
  double fy = clampd(ry, 0.0, (double)(s->nrows - 1));
  *cx = rx != fx;
  *cy = ry != fy;
  *i = (karst_int_t)floor(fx);
  *j = (karst_int_t)floor(fy);
  if (*i >= s->ncols - 1) *i = s->ncols > 1 ? s->ncols - 2 : 0;
  if (*j >= s->nrows - 1) *j = s->nrows > 1 ? s->nrows - 2 : 0;
  *u = s->ncols > 1 ? fx - (double)*i : 0;
  *v = s->nrows > 1 ? fy - (double)*j : 0;
}

/* The cell of (x, y): its corner elevations z00 z10 z01 z11, (u, v) and the clamping flags. */
static void grid_corners(const karst_surface_t *s, double x, double y, double c[4], double *u,
                         double *v, int *cx, int *cy) {
  karst_int_t i, j;
  grid_cell(s, x, y, &i, &j, u, v, cx, cy);
  karst_int_t i1 = s->ncols > 1 ? i + 1 : i, j1 = s->nrows > 1 ? j + 1 : j;
  c[0] = s->z[j * s->ncols + i], c[1] = s->z[j * s->ncols + i1];
  c[2] = s->z[j1 * s->ncols + i], c[3] = s->z[j1 * s->ncols + i1];
}

static double grid_z(const karst_surface_t *s, double x, double y) {
  if (!isfinite(x) || !isfinite(y)) return NAN;
  double c[4], u, v;
  int cx, cy;
  grid_corners(s, x, y, c, &u, &v, &cx, &cy);
  return (1 - v) * ((1 - u) * c[0] + u * c[1]) + v * ((1 - u) * c[2] + u * c[3]);
}

static void grid_gradient(const karst_surface_t *s, double x, double y, double g[2]) {
  if (!isfinite(x) || !isfinite(y)) {
    g[0] = g[1] = NAN;
    return;
  }
  double c[4], u, v;
  int cx, cy;
  grid_corners(s, x, y, c, &u, &v, &cx, &cy);
  g[0] = cx ? 0.0 : ((1 - v) * (c[1] - c[0]) + v * (c[3] - c[2])) / s->cs;
  g[1] = cy ? 0.0 : ((1 - u) * (c[2] - c[0]) + u * (c[3] - c[1])) / s->cs;
}

/* Extreme (sign = 1: max, -1: min) of the grid over a rectangle. On each cell
 * the bilinear surface is linear along x and along y, and the clamped border
 * strips are linear along the one free axis, so the extreme is at a corner of
 * the rectangle cut by the node lines: the rectangle's corners, the crossings
 * of its edges with node lines and the nodes inside. O(1 + nodes inside). */
static double grid_extreme_rect(const karst_surface_t *s, double x0, double x1, double y0,
                                double y1, double sign) {
  double m = -INFINITY;
#define TAKE(x, y) m = fmax(m, sign * grid_z(s, (x), (y)))
  TAKE(x0, y0);
  TAKE(x1, y0);
  TAKE(x0, y1);
  TAKE(x1, y1);
  double cs = s->cs;
  double ilo = fmax(0.0, ceil((x0 - s->xll) / cs)),
         ihi = fmin(s->ncols - 1.0, floor((x1 - s->xll) / cs));
  double jlo = fmax(0.0, ceil((y0 - s->yll) / cs)),
         jhi = fmin(s->nrows - 1.0, floor((y1 - s->yll) / cs));
  for (double i = ilo; i <= ihi; i++) {
    double x = s->xll + i * cs;
    TAKE(x, y0);
    TAKE(x, y1);
    for (double j = jlo; j <= jhi; j++)
      m = fmax(m, sign * s->z[(karst_int_t)j * s->ncols + (karst_int_t)i]);
  }
  for (double j = jlo; j <= jhi; j++) {
    double y = s->yll + j * cs;
    TAKE(x0, y);
    TAKE(x1, y);
  }
#undef TAKE
  return sign * m;
}

/* Parameters t in (t0, t1) where a + t d crosses the node lines origin + i step,
 * i in [0, count), in increasing order of t: the first through *first, the
 * number through the return value; t_i = (origin + i step - a) / d. */
typedef struct line_run {
  double a, d, origin, step;
  karst_int_t i, last, inc; /* i runs to last by inc; i == last + inc: done */
} line_run_t;

static void line_run_init(line_run_t *r, double a, double d, double origin, double step,
                          karst_int_t count, double t0, double t1) {
  r->a = a, r->d = d, r->origin = origin, r->step = step;
  r->i = 0, r->last = -1, r->inc = 1; /* empty */
  if (d == 0.0 || count < 1) return;
  double xa = a + t0 * d, xb = a + t1 * d;
  double lo = fmin(xa, xb), hi = fmax(xa, xb);
  double flo = fmax(ceil((lo - origin) / step), 0.0);
  double fhi = fmin(floor((hi - origin) / step), (double)(count - 1));
  if (!(flo <= fhi)) return;
  karst_int_t ilo = (karst_int_t)flo, ihi = (karst_int_t)fhi;
  r->inc = d > 0 ? 1 : -1;
  r->i = d > 0 ? ilo : ihi;
  r->last = d > 0 ? ihi : ilo;
}

static double line_run_t_at(const line_run_t *r) {
  if (r->i == r->last + r->inc) return INFINITY;
  return (r->origin + (double)r->i * r->step - r->a) / r->d;
}

/* Grid piece boundaries in (t0, t1): node lines in x and in y, merged. */
static int grid_pieces(const karst_surface_t *s, const double a[3], const double b[3], double t0,
                       double t1, double *t, int max_t) {
  line_run_t rx, ry;
  line_run_init(&rx, a[0], b[0] - a[0], s->xll, s->cs, s->ncols, t0, t1);
  line_run_init(&ry, a[1], b[1] - a[1], s->yll, s->cs, s->nrows, t0, t1);
  long n = 0;
  double prev = t0;
  for (;;) {
    double tx = line_run_t_at(&rx), ty = line_run_t_at(&ry);
    double tn = fmin(tx, ty);
    if (tn == INFINITY) break;
    if (tx == tn) rx.i += rx.inc;
    if (ty == tn) ry.i += ry.inc;
    if (!(tn > prev && tn < t1)) continue; /* rounding at an end, or equal to the last */
    if (n < max_t) t[n] = tn;
    n++;
    prev = tn;
  }
  return n <= max_t ? (int)n : -1;
}

/* ------------------------------------------------------------------------ */
/* Queries                                                                   */
/* ------------------------------------------------------------------------ */

/**
 * Elevation of the surface at (x, y): the plane; the grid's bilinear surface,
 * clamped at its border (karst_terrain_height's operations); on a TIN the
 * linear interpolation in the triangle holding (x, y), found through the
 * bucket grid.
 * @return z in metres; NAN outside a TIN's triangles or for non-finite (x, y)
 *         on a grid or a TIN.
 * Time complexity: O(1) (TIN: O(1) expected, the triangles of one bucket).
 */
double karst_surface_z(const karst_surface_t *s, double x, double y) {
  switch (s->kind) {
  case KARST_SURFACE_PLANE:
    return plane_z(s, x, y);
  case KARST_SURFACE_GRID:
    return grid_z(s, x, y);
  case KARST_SURFACE_TIN: {
    karst_int_t t = karst_i_tin_locate(s, x, y);
    if (t < 0) return NAN;
    const double *d = s->tdata + 9 * t;
    return d[6] + d[7] * (x - d[0]) + d[8] * (y - d[1]);
  }
  }
  return NAN;
}

/**
 * Gradient g = (dz/dx, dz/dy) at (x, y): constant on a plane and on each
 * triangle of a TIN; on a grid the derivative of the bilinear cell (zero along
 * an axis where the grid is clamped). On a cell or triangle edge the piece
 * that karst_surface_z uses is the one differentiated.
 * @param g receives the gradient; NAN outside a TIN.
 * Time complexity: O(1) (TIN: O(1) expected).
 */
void karst_surface_gradient(const karst_surface_t *s, double x, double y, double g[2]) {
  switch (s->kind) {
  case KARST_SURFACE_PLANE:
    g[0] = s->dip == 0.0 ? 0.0 : -s->sin_a * s->tan_d;
    g[1] = s->dip == 0.0 ? 0.0 : -s->cos_a * s->tan_d;
    return;
  case KARST_SURFACE_GRID:
    grid_gradient(s, x, y, g);
    return;
  case KARST_SURFACE_TIN: {
    karst_int_t t = karst_i_tin_locate(s, x, y);
    g[0] = t < 0 ? NAN : s->tdata[9 * t + 7];
    g[1] = t < 0 ? NAN : s->tdata[9 * t + 8];
    return;
  }
  }
}

/**
 * Bounding box of the surface: x-y where it is given (infinite for a plane;
 * the cell edges of a grid; the vertices of a TIN) and its z range (a dipping
 * plane: infinite; a grid: its nodes, which bound the bilinear surface; a TIN:
 * its vertices). O(1).
 */
void karst_surface_bounds(const karst_surface_t *s, double lo[3], double hi[3]) {
  for (int k = 0; k < 3; k++) {
    lo[k] = s->lo[k];
    hi[k] = s->hi[k];
  }
}

/**
 * Lipschitz constant of z = f(x, y): tan(dip) for a plane, the largest corner
 * slope of a grid cell (exact for the bilinear surface), the steepest triangle
 * of a TIN. Used to bound the implicit terrain (Paris et al. 2021, Appendix A).
 * Time complexity: O(1) (computed when the surface is built).
 */
double karst_surface_lipschitz(const karst_surface_t *s) {
  return s->lipschitz;
}

static double extreme_rect(const karst_surface_t *s, double x0, double x1, double y0, double y1,
                           double sign) {
  if (!(x0 <= x1) || !(y0 <= y1) || !isfinite(x0) || !isfinite(x1) || !isfinite(y0) ||
      !isfinite(y1))
    return NAN;
  switch (s->kind) {
  case KARST_SURFACE_PLANE: /* linear: the extremes are at corners */
    return sign * fmax(fmax(sign * plane_z(s, x0, y0), sign * plane_z(s, x1, y0)),
                       fmax(sign * plane_z(s, x0, y1), sign * plane_z(s, x1, y1)));
  case KARST_SURFACE_GRID:
    return grid_extreme_rect(s, x0, x1, y0, y1, sign);
  case KARST_SURFACE_TIN:
    return karst_i_tin_extreme_rect(s, x0, x1, y0, y1, sign);
  }
  return NAN;
}

/**
 * Exact largest elevation over the closed rectangle [x0, x1] x [y0, y1]. Each
 * kind is linear on pieces along both axes, so the maximum is at a corner of
 * the rectangle cut into those pieces: the rectangle's corners (plane); the
 * corners, the crossings of its edges with node lines and the nodes inside
 * (grid); the vertices of each triangle clipped to the rectangle (TIN, over
 * the part where it is defined).
 * @return the maximum, or NAN for an empty or non-finite rectangle or one that
 *         no triangle of a TIN reaches.
 * Time complexity: O(1) for a plane, O(1 + nodes inside) for a grid,
 * O(1 + triangles meeting the rectangle) expected for a TIN.
 */
double karst_surface_max_rect(const karst_surface_t *s, double x0, double x1, double y0,
                              double y1) {
  return extreme_rect(s, x0, x1, y0, y1, 1.0);
}

/** Exact smallest elevation over a rectangle: as karst_surface_max_rect. */
double karst_surface_min_rect(const karst_surface_t *s, double x0, double x1, double y0,
                              double y1) {
  return extreme_rect(s, x0, x1, y0, y1, -1.0);
}

/* Piece boundaries in (t0, t1) of the parameter of [a, b]. */
static int pieces_range(const karst_surface_t *s, const double a[3], const double b[3], double t0,
                        double t1, double *t, int max_t) {
  switch (s->kind) {
  case KARST_SURFACE_PLANE:
    return 0;
  case KARST_SURFACE_GRID:
    return grid_pieces(s, a, b, t0, t1, t, max_t);
  case KARST_SURFACE_TIN:
    return karst_i_tin_pieces(s, a, b, t0, t1, t, max_t);
  }
  return 0;
}

/**
 * Where the surface changes formula along a segment: the sorted, distinct
 * parameters t in (0, 1) at which the x-y trace of a + t (b - a) crosses a node
 * line of a grid (the clamped border included) or an edge or vertex of a TIN
 * (entering and leaving it included). Between two consecutive parameters the
 * surface restricted to the segment is linear in t (plane, TIN) or a quadratic
 * (grid: the bilinear uv term), so callers can integrate and test signs exactly.
 * A plane has none. On a TIN, which edges are crossed is decided with exact
 * orientation tests; the parameters themselves are rounded, and an edge shared
 * by two triangles gives one parameter.
 * @param a, b the segment's ends; @param t receives the parameters;
 * @param max_t room in @p t.
 * @return the number of parameters, or -1 when there are more than @p max_t
 *         (split the segment and ask for each half); 0 for non-finite ends.
 * Time complexity: O(1 + pieces) for a grid; O(1 + buckets crossed x triangles
 * per bucket) expected for a TIN.
 */
int karst_surface_segment_pieces(const karst_surface_t *s, const double a[3], const double b[3],
                                 double *t, int max_t) {
  for (int k = 0; k < 2; k++)
    if (!isfinite(a[k]) || !isfinite(b[k])) return 0;
  return pieces_range(s, a, b, 0.0, 1.0, t, max_t);
}

/* q(t) = sign (z of the segment - z of the surface) at parameter t. */
static double q_at(const karst_surface_t *s, const double a[3], const double b[3], double t,
                   double sign) {
  double x = a[0] + t * (b[0] - a[0]), y = a[1] + t * (b[1] - a[1]);
  return sign * (a[2] + t * (b[2] - a[2]) - karst_surface_z(s, x, y));
}

/* Whether q < 0 on the open piece (p0, p1) and at its ends, where an end may
 * be 0 when @p touch0 / @p touch1 allows it. Plane and TIN: q is linear on the
 * piece; grid: quadratic, fixed by q at p0, the middle and p1. */
static int piece_below(const karst_surface_t *s, const double a[3], const double b[3], double p0,
                       double p1, int touch0, int touch1, double sign) {
  double q0, q1, qm = 0.0;
  if (s->kind == KARST_SURFACE_TIN) {
    double pm = 0.5 * (p0 + p1);
    karst_int_t tr = karst_i_tin_locate(s, a[0] + pm * (b[0] - a[0]), a[1] + pm * (b[1] - a[1]));
    if (tr < 0) return 0; /* the surface is not defined there */
    const double *d = s->tdata + 9 * tr;
    double qq[2], pp[2] = {p0, p1};
    for (int k = 0; k < 2; k++) {
      double x = a[0] + pp[k] * (b[0] - a[0]), y = a[1] + pp[k] * (b[1] - a[1]);
      double f = d[6] + d[7] * (x - d[0]) + d[8] * (y - d[1]);
      qq[k] = sign * (a[2] + pp[k] * (b[2] - a[2]) - f);
    }
    q0 = qq[0], q1 = qq[1];
  } else {
    q0 = q_at(s, a, b, p0, sign);
    q1 = q_at(s, a, b, p1, sign);
    if (s->kind == KARST_SURFACE_GRID) qm = q_at(s, a, b, 0.5 * (p0 + p1), sign);
  }
  if (!(touch0 ? q0 <= 0 : q0 < 0) || !(touch1 ? q1 <= 0 : q1 < 0)) return 0;
  if (s->kind != KARST_SURFACE_GRID) return !(q0 == 0 && q1 == 0); /* linear */
  if (!(qm < 0)) return 0;
  /* q(u) = q0 + B u + A u^2 on u in [0, 1]; with both ends <= 0 and the middle
   * < 0, an interior point >= 0 needs a concave q whose vertex is inside. */
  double A = 2 * q0 - 4 * qm + 2 * q1, B = -3 * q0 + 4 * qm - q1;
  if (A < 0) {
    double u = -B / (2 * A);
    if (u > 0 && u < 1 && q0 + B * u + A * u * u >= 0) return 0;
  }
  return 1;
}

static int below_range(const karst_surface_t *s, const double a[3], const double b[3], double t0,
                       double t1, int touch0, int touch1, double sign) {
  double buf[SEGMENT_PIECES_BUF];
  int n = pieces_range(s, a, b, t0, t1, buf, SEGMENT_PIECES_BUF);
  if (n < 0) {
    double tm = 0.5 * (t0 + t1);
    return below_range(s, a, b, t0, tm, touch0, 0, sign) &&
           below_range(s, a, b, tm, t1, 0, touch1, sign);
  }
  double p0 = t0;
  for (int k = 0; k <= n; k++) {
    double p1 = k < n ? buf[k] : t1;
    if (!piece_below(s, a, b, p0, p1, k == 0 && touch0, k == n && touch1, sign)) return 0;
    p0 = p1;
  }
  return 1;
}

static int segment_side(const karst_surface_t *s, const double a[3], const double b[3],
                        double sign) {
  for (int k = 0; k < 3; k++)
    if (!isfinite(a[k]) || !isfinite(b[k])) return 0;
  return below_range(s, a, b, 0.0, 1.0, 1, 1, sign);
}

/**
 * Exact test that the segment [a, b] lies below the surface: its ends at or
 * below it (z <= f) and every point between them strictly below (z < f), so a
 * segment may leave a point on the surface but not run along it. Piece by
 * piece (karst_surface_segment_pieces) the difference z - f is linear (plane,
 * TIN) or a quadratic (grid), whose sign on the piece is decided from its
 * values at the ends and, for a quadratic, its vertex: no sampling step and no
 * tolerance (the generalisation of the grid test of src/cost/cost.c). Where
 * the trace leaves a TIN the surface is undefined and the answer is 0.
 * @return 1 or 0 (also for non-finite ends).
 * Time complexity: O(1 + pieces), TIN pieces found in O(1) expected each.
 */
int karst_surface_segment_below(const karst_surface_t *s, const double a[3], const double b[3]) {
  return segment_side(s, a, b, 1.0);
}

/** The mirror of karst_surface_segment_below: ends at or above, interior strictly above. */
int karst_surface_segment_above(const karst_surface_t *s, const double a[3], const double b[3]) {
  return segment_side(s, a, b, -1.0);
}

/**
 * Check that the surface is defined over the whole closed rectangle [lo, hi]
 * (the domain's x-y extent). A plane always is. A grid must span it with its
 * cells (edges, not centres), short by at most KARST_SCENARIO_GRID_COVER_SLACK
 * of a cell, the terrain's rule. A TIN must hold every point of it in a
 * triangle: no corner may be outside and no border edge of the TIN may run
 * through the rectangle's interior (a notch or a hole).
 * @param what names the surface in the message ("water table of spring S1").
 * @return KARST_SUCCESS or KARST_ERANGE with "FILE: WHAT ... falls short ..."
 *         naming where and by how much; KARST_EINVAL for a bad rectangle.
 * Time complexity: O(1) for a plane or grid; O(border edges) for a TIN.
 */
karst_error_t karst_surface_check_covers(karst_ctx_t *ctx, const karst_surface_t *s,
                                         const double lo[2], const double hi[2], const char *what) {
  const char *name = s->path ? s->path : "(surface built in code)";
  if (!what) what = "surface";
  for (int k = 0; k < 2; k++)
    if (!isfinite(lo[k]) || !isfinite(hi[k]) || !(lo[k] <= hi[k]))
      return karst_set_error(ctx, KARST_EINVAL,
                             "%s: %s: the extent to cover must be finite with lo <= hi, got "
                             "[%g, %g] in %c",
                             name, what, lo[k], hi[k], "xy"[k]);
  if (s->kind == KARST_SURFACE_PLANE) return KARST_SUCCESS;
  if (s->kind == KARST_SURFACE_TIN) return karst_i_tin_check_covers(ctx, s, lo, hi, what);
  double slack = KARST_SCENARIO_GRID_COVER_SLACK * s->cs;
  char msg[512];
  size_t len = 0;
  static const char *const side[4] = {"west", "east", "south", "north"};
  double short_by[4] = {s->lo[0] - lo[0], hi[0] - s->hi[0], s->lo[1] - lo[1], hi[1] - s->hi[1]};
  const double at[4] = {lo[0], hi[0], lo[1], hi[1]};
  msg[0] = '\0';
  for (int k = 0; k < 4; k++)
    if (short_by[k] > slack && len < sizeof msg)
      len += (size_t)snprintf(msg + len, sizeof msg - len, "%s%g m in the %s (%c = %g m)",
                              len ? ", " : "", short_by[k], side[k], "xxyy"[k], at[k]);
  if (len == 0) return KARST_SUCCESS;
  return karst_set_error(ctx, KARST_ERANGE,
                         "%s: the %s grid covers x in [%g, %g], y in [%g, %g] m (cell edges) but "
                         "must cover x in [%g, %g], y in [%g, %g] m: it falls short by %s",
                         name, what, s->lo[0], s->hi[0], s->lo[1], s->hi[1], lo[0], hi[0], lo[1],
                         hi[1], msg);
}

/* ------------------------------------------------------------------------ */
/* Triangulation for display                                                 */
/* ------------------------------------------------------------------------ */

/* Break values of [lo, hi]: the ends, the node lines between them (grid), each
 * interval cut in equal parts no longer than max_edge. *n receives the count. */
static karst_error_t axis_breaks(karst_ctx_t *ctx, double lo, double hi, const double *nodes,
                                 karst_int_t nnodes, double max_edge, double **out,
                                 karst_int_t *n) {
  karst_int_t cap = 2 + nnodes, m = 0;
  double *base = malloc((size_t)cap * sizeof *base);
  if (!base) return karst_set_error(ctx, KARST_ENOMEM, "surface triangulation: out of memory");
  base[m++] = lo;
  for (karst_int_t k = 0; k < nnodes; k++)
    if (nodes[k] > lo && nodes[k] < hi) base[m++] = nodes[k];
  if (hi > lo) base[m++] = hi;
  karst_int_t total = 1;
  for (karst_int_t k = 0; k + 1 < m; k++) {
    double parts =
        max_edge > 0 && isfinite(max_edge) ? ceil((base[k + 1] - base[k]) / max_edge) : 1;
    if (!(parts <= (double)KARST_SURFACE_MAX_TRIANGLES))
      parts = (double)KARST_SURFACE_MAX_TRIANGLES + 1;
    total += parts < 1 ? 1 : (karst_int_t)parts;
    if (total > KARST_SURFACE_MAX_TRIANGLES) {
      free(base);
      return karst_set_error(ctx, KARST_ERANGE,
                             "surface triangulation: max_edge = %g m cuts [%g, %g] into more "
                             "than %lld parts",
                             max_edge, lo, hi, (long long)KARST_SURFACE_MAX_TRIANGLES);
    }
  }
  double *v = malloc((size_t)total * sizeof *v);
  if (!v) {
    free(base);
    return karst_set_error(ctx, KARST_ENOMEM, "surface triangulation: out of memory");
  }
  karst_int_t c = 0;
  v[c++] = base[0];
  for (karst_int_t k = 0; k + 1 < m; k++) {
    double parts =
        max_edge > 0 && isfinite(max_edge) ? ceil((base[k + 1] - base[k]) / max_edge) : 1;
    karst_int_t p = parts < 1 ? 1 : (karst_int_t)parts;
    for (karst_int_t q = 1; q < p; q++)
      v[c++] = base[k] + (base[k + 1] - base[k]) * (double)q / (double)p;
    v[c++] = base[k + 1];
  }
  free(base);
  *out = v;
  *n = c;
  return KARST_SUCCESS;
}

/* Plane and grid: a tensor grid of the rectangle through the node lines, each
 * cell two triangles, z from the surface (exact at grid nodes). */
static karst_error_t tensor_triangulate(karst_ctx_t *ctx, const karst_surface_t *s,
                                        const double lo[2], const double hi[2], double max_edge,
                                        double **xyz, karst_int_t *nv, karst_int_t **tri,
                                        karst_int_t *nt) {
  karst_error_t err = KARST_SUCCESS;
  double *xs = NULL, *ys = NULL, *nodes = NULL, *V = NULL;
  karst_int_t nx = 0, ny = 0, *T = NULL;
  for (int axis = 0; axis < 2; axis++) {
    karst_int_t nn = 0;
    free(nodes);
    nodes = NULL;
    if (s->kind == KARST_SURFACE_GRID) {
      nn = axis == 0 ? s->ncols : s->nrows;
      nodes = malloc((size_t)nn * sizeof *nodes);
      if (!nodes) {
        err = karst_set_error(ctx, KARST_ENOMEM, "surface triangulation: out of memory");
        goto cleanup;
      }
      for (karst_int_t k = 0; k < nn; k++)
        nodes[k] = (axis == 0 ? s->xll : s->yll) + (double)k * s->cs;
    }
    err = axis_breaks(ctx, lo[axis], hi[axis], nodes, nn, max_edge, axis == 0 ? &xs : &ys,
                      axis == 0 ? &nx : &ny);
    if (err) goto cleanup;
  }
  karst_int_t cells = (nx - 1) * (ny - 1);
  if (nx > 1 && ny > 1 && (nx - 1) > KARST_SURFACE_MAX_TRIANGLES / 2 / (ny - 1)) {
    err = karst_set_error(ctx, KARST_ERANGE,
                          "surface triangulation: max_edge = %g m makes more than %lld triangles",
                          max_edge, (long long)KARST_SURFACE_MAX_TRIANGLES);
    goto cleanup;
  }
  V = malloc((size_t)(nx * ny) * 3 * sizeof *V);
  T = malloc((size_t)(cells > 0 ? cells : 1) * 6 * sizeof *T);
  if (!V || !T) {
    err = karst_set_error(ctx, KARST_ENOMEM, "surface triangulation: out of memory");
    goto cleanup;
  }
  for (karst_int_t j = 0; j < ny; j++)
    for (karst_int_t i = 0; i < nx; i++) {
      double *p = V + 3 * (j * nx + i);
      p[0] = xs[i], p[1] = ys[j], p[2] = karst_surface_z(s, xs[i], ys[j]);
    }
  karst_int_t m = 0;
  for (karst_int_t j = 0; j + 1 < ny; j++)
    for (karst_int_t i = 0; i + 1 < nx; i++) {
      karst_int_t v00 = j * nx + i, v10 = v00 + 1, v01 = v00 + nx, v11 = v01 + 1;
      karst_int_t q[6] = {v00, v10, v11, v00, v11, v01};
      memcpy(T + 3 * m, q, sizeof q);
      m += 2;
    }
  *xyz = V;
  *nv = nx * ny;
  *tri = T;
  *nt = m;
  V = NULL;
  T = NULL;
cleanup:
  free(xs);
  free(ys);
  free(nodes);
  free(V);
  free(T);
  return err;
}

/**
 * Triangles of the surface over the rectangle [lo, hi], for display (the
 * geology.vtp of a run): a plane or a grid as a tensor grid through the
 * rectangle's edges and the grid's node lines, cut so that no cell side is
 * longer than @p max_edge (<= 0 or infinite: no cut), exact at the grid nodes;
 * a TIN as its own triangles clipped to the rectangle (each clipped polygon
 * fanned into triangles, shared points merged). Triangles are counter-clockwise
 * seen from above.
 * @param xyz, nv, tri, nt receive malloc'd arrays (3 nv coordinates, 3 nt
 *        0-based vertex indices) that the caller frees; untouched on failure.
 * @return KARST_SUCCESS, KARST_EINVAL (a bad rectangle), KARST_ERANGE (too many
 *         triangles) or KARST_ENOMEM.
 * Time complexity: O(output) for a plane or grid; O(triangles meeting the
 * rectangle) expected for a TIN.
 */
karst_error_t karst_surface_triangulate(karst_ctx_t *ctx, const karst_surface_t *s,
                                        const double lo[2], const double hi[2], double max_edge,
                                        double **xyz, karst_int_t *nv, karst_int_t **tri,
                                        karst_int_t *nt) {
  for (int k = 0; k < 2; k++)
    if (!isfinite(lo[k]) || !isfinite(hi[k]) || !(lo[k] <= hi[k]))
      return karst_set_error(ctx, KARST_EINVAL,
                             "surface triangulation: the rectangle must be finite with lo <= hi, "
                             "got [%g, %g] in %c",
                             lo[k], hi[k], "xy"[k]);
  if (s->kind == KARST_SURFACE_TIN)
    return karst_i_tin_triangulate(ctx, s, lo, hi, xyz, nv, tri, nt);
  return tensor_triangulate(ctx, s, lo, hi, max_edge, xyz, nv, tri, nt);
}

/* ------------------------------------------------------------------------ */
/* Files                                                                     */
/* ------------------------------------------------------------------------ */

typedef enum { FMT_UNKNOWN, FMT_TSURF, FMT_GRID } surface_format_t;

/* Format from the first word of the file, else from the extension. */
static karst_error_t sniff_format(karst_ctx_t *ctx, const char *path, surface_format_t *fmt,
                                  char *first, size_t firstsz) {
  FILE *fp = NULL;
  karst_error_t err = karst_i_open_regular(ctx, path, "surface", KARST_SURFACE_MAX_BYTES, &fp);
  if (err) return err;
  char buf[256];
  size_t n = fread(buf, 1, sizeof buf - 1, fp);
  int rerr = ferror(fp);
  fclose(fp);
  if (rerr) return karst_set_error(ctx, KARST_EIO, "%s: cannot read: %s", path, strerror(errno));
  buf[n] = '\0';
  const char *p = buf;
  if ((unsigned char)p[0] == 0xEF && (unsigned char)p[1] == 0xBB && (unsigned char)p[2] == 0xBF)
    p += 3; /* UTF-8 byte order mark */
  while (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n')
    p++;
  size_t w = 0;
  while (p[w] && p[w] != ' ' && p[w] != '\t' && p[w] != '\r' && p[w] != '\n' && w + 1 < firstsz) {
    unsigned char c = (unsigned char)p[w];
    first[w] = (c < 32 || c >= 127) ? '?' : (char)c;
    w++;
  }
  first[w] = '\0';
  static const char *const grid_words[] = {"ncols",     "nrows",     "xllcorner", "xllcenter",
                                           "yllcorner", "yllcenter", "cellsize",  "nodata_value"};
  *fmt = FMT_UNKNOWN;
  if (strcmp(first, "GOCAD") == 0) *fmt = FMT_TSURF;
  for (size_t k = 0; k < sizeof grid_words / sizeof grid_words[0]; k++)
    if (strcasecmp(first, grid_words[k]) == 0) *fmt = FMT_GRID;
  if (*fmt == FMT_UNKNOWN) {
    const char *dot = strrchr(path, '.');
    const char *slash = strrchr(path, '/');
    if (dot && (!slash || dot > slash)) {
      if (strcasecmp(dot, ".ts") == 0 || strcasecmp(dot, ".tsurf") == 0) *fmt = FMT_TSURF;
      if (strcasecmp(dot, ".asc") == 0) *fmt = FMT_GRID;
    }
  }
  return KARST_SUCCESS;
}

static karst_error_t load_grid(karst_ctx_t *ctx, const char *path, karst_surface_t **out) {
  karst_terrain_t t;
  memset(&t, 0, sizeof t);
  karst_error_t err = karst_terrain_load_grid(ctx, path, &t);
  if (err) return err;
  karst_surface_t *s = surface_alloc(KARST_SURFACE_GRID);
  if (!s) {
    free(t.z);
    free(t.path);
    return karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path);
  }
  s->path = t.path;
  s->ncols = t.ncols;
  s->nrows = t.nrows;
  s->xll = t.xll;
  s->yll = t.yll;
  s->cs = t.cellsize;
  s->z = t.z;
  grid_finish(s);
  *out = s;
  return KARST_SUCCESS;
}

static karst_error_t load_tsurf(karst_ctx_t *ctx, const char *path, karst_surface_t **out) {
  karst_i_tsurf_t ts;
  memset(&ts, 0, sizeof ts);
  karst_error_t err = karst_i_tsurf_read(ctx, path, &ts);
  if (err) return err;
  karst_i_tin_source_t src = {path, ts.vline, ts.tline, ts.vid};
  karst_surface_t *s = NULL;
  err = karst_i_surface_tin(ctx, ts.nv, ts.xyz, ts.nt, ts.tri, &src, &s);
  if (!err) {
    s->path = strdup(path);
    if (!s->path) err = karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path);
    s->name = ts.name;
    ts.name = NULL;
  }
  if (err) {
    karst_surface_free(s);
    s = NULL;
  }
  karst_i_tsurf_destroy(&ts);
  *out = s;
  return err;
}

/**
 * Read a surface from a file, recognised by its first word: "GOCAD" for a GOCAD
 * TSurf (read by src/io/read_tsurf.c, then checked as karst_surface_create_tin
 * does, messages naming the file's lines), an ESRI ASCII grid header word
 * (ncols ...) for a grid (read by karst_terrain_load_grid, the terrain's
 * reader). A file that starts otherwise is read by its extension's reader
 * (.ts, .asc), whose message says what was expected.
 * @param ctx context; errors read "FILE:LINE: message" with the value.
 * @param path the file; must be a regular file of at most KARST_SURFACE_MAX_BYTES.
 * @param out receives the surface (karst_surface_path gives @p path).
 * @return KARST_SUCCESS, KARST_EIO (missing, not a regular file, unreadable),
 *         KARST_EPARSE (malformed, unknown format), KARST_EINVAL (bad geometry),
 *         KARST_ERANGE (too large) or KARST_ENOMEM.
 * Time complexity: O(file size) for a grid; O(file size + n log n) for a TIN
 * of n triangles (sorting edges and vertices), with the overlap check O(n)
 * expected.
 */
karst_error_t karst_surface_load(karst_ctx_t *ctx, const char *path, karst_surface_t **out) {
  *out = NULL;
  surface_format_t fmt = FMT_UNKNOWN;
  char first[48];
  karst_error_t err = sniff_format(ctx, path, &fmt, first, sizeof first);
  if (err) return err;
  if (fmt == FMT_TSURF) return load_tsurf(ctx, path, out);
  if (fmt == FMT_GRID) return load_grid(ctx, path, out);
  if (first[0] == '\0')
    return karst_set_error(ctx, KARST_EPARSE,
                           "%s:1: empty file: expected a GOCAD TSurf ('GOCAD TSurf 1') or an ESRI "
                           "ASCII grid ('ncols N')",
                           path);
  return karst_set_error(ctx, KARST_EPARSE,
                         "%s:1: not a surface file: expected a GOCAD TSurf (first line 'GOCAD "
                         "TSurf 1') or an ESRI ASCII grid (first line 'ncols N'), got '%s'",
                         path, first);
}
