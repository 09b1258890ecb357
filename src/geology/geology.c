/* The geological model of a scenario (include/karst/geology.h): surfaces, bedrock membership,
 * exclusion zones and insoluble strata, water tables per spring, fracture families with their
 * Fisher dispersion, realised discrete fracture networks, faults. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/math_internal.h"
#include "geology/geology_internal.h"
#include "geology/surface_internal.h"
#include "karst/surface.h"

#define DEG2RAD (M_PI / 180.0)

static double clamp(double x, double a, double b) {
  return x < a ? a : (x > b ? b : x);
}

/* Smooth step g(x) = 3x^2 - 2x^3 on [0, 1] (Paris et al. 2021, §4.2). */
static double smoothstep(double x) {
  x = clamp(x, 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

static double dot3(const double a[3], const double b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static int finite3(const double p[3]) {
  return isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]);
}

static const char *const zone_names[KARST_ZONE_COUNT] = {
#define KARST_X_NAME(code, name) name,
    KARST_ZONE_LIST(KARST_X_NAME)
#undef KARST_X_NAME
};

/** Name of a water-table zone; "unknown" out of range. O(1). */
const char *karst_zone_name(int zone) {
  return zone >= 0 && zone < KARST_ZONE_COUNT ? zone_names[zone] : "unknown";
}

static const char *const feature_names[KARST_GEOLOGY_FEATURE_COUNT] = {
#define KARST_X_NAME(code, name) name,
    KARST_GEOLOGY_FEATURE_LIST(KARST_X_NAME)
#undef KARST_X_NAME
};

/** Name of a geology.vtp feature kind; "unknown" out of range. O(1). */
const char *karst_geology_feature_name(int feature) {
  return feature >= 0 && feature < KARST_GEOLOGY_FEATURE_COUNT ? feature_names[feature] : "unknown";
}

/* ------------------------------------------------------------------------ */
/* Fields of the parsed scenario                                             */
/* ------------------------------------------------------------------------ */

/**
 * Terrain elevation at (x, y): the flat elevation, the terrain's surface file, or bilinear
 * interpolation of the grid (cell centres) clamped at the border — the grid surface of
 * src/geology/surface.c, asked through a view of the terrain's own elevations. O(1), O(1)
 * expected for a triangulated terrain.
 */
double karst_terrain_height(const karst_terrain_t *t, double x, double y) {
  if (t->surface) return karst_surface_z(t->surface, x, y);
  if (!t->is_grid || !t->z || t->ncols < 1 || t->nrows < 1) return t->elevation;
  karst_surface_t view;
  memset(&view, 0, sizeof view);
  view.kind = KARST_SURFACE_GRID;
  view.ncols = t->ncols, view.nrows = t->nrows;
  view.xll = t->xll, view.yll = t->yll, view.cs = t->cellsize;
  view.z = t->z;
  return karst_surface_z(&view, x, y);
}

/**
 * Unit normal of a plane from its dip direction and dip (degrees), with x east,
 * y north, z up: n = (sin δ sin α, sin δ cos α, cos δ). O(1).
 */
void karst_plane_normal(double dip_direction, double dip, double n[3]) {
  double a = dip_direction * DEG2RAD, d = dip * DEG2RAD;
  n[0] = sin(d) * sin(a);
  n[1] = sin(d) * cos(a);
  n[2] = cos(d);
}

/**
 * Elevation of a horizon at (x, y): the plane through (origin, elevation) whose
 * surface descends by tan(dip) per metre towards the dip direction, or the
 * horizon's surface file. O(1) (plane, grid), O(1) expected (triangulated).
 */
double karst_horizon_elevation(const karst_horizon_t *h, double x, double y) {
  if (h->surface) return karst_surface_z(h->surface, x, y);
  if (h->path) return NAN; /* a file that was not read */
  if (h->dip == 0.0) return h->elevation;
  double a = h->dip_direction * DEG2RAD;
  double along = (x - h->origin[0]) * sin(a) + (y - h->origin[1]) * cos(a);
  return h->elevation - along * tan(h->dip * DEG2RAD);
}

/** Elevation of a scenario surface at (x, y), NAN when not given. O(1) or O(1) expected. */
double karst_surface_def_z(const karst_surface_def_t *d, double x, double y) {
  karst_i_surf_t s = karst_i_surf_of_def(d);
  return karst_i_surf_z(&s, x, y);
}

static double perm_node(const karst_perm_node_t *n, double bg, const double p[3]) {
  switch (n->kind) {
  case KARST_PERM_SPHERE: {
    double dx = p[0] - n->center[0], dy = p[1] - n->center[1], dz = p[2] - n->center[2];
    double d = sqrt(dx * dx + dy * dy + dz * dz) - n->radius;
    if (d <= 0) return n->resistance;
    if (n->falloff <= 0) return bg;
    double s = smoothstep(d / n->falloff);
    return (1 - s) * n->resistance + s * bg;
  }
  case KARST_PERM_STRATUM:
    return (p[2] >= n->bottom && p[2] <= n->top) ? n->resistance : bg;
  case KARST_PERM_UNION:
  case KARST_PERM_INTERSECTION: {
    if (n->n_children == 0) return bg;
    double v = perm_node(&n->children[0], bg, p);
    for (int i = 1; i < n->n_children; i++) {
      double c = perm_node(&n->children[i], bg, p);
      v = n->kind == KARST_PERM_UNION ? karst_i_fmin(v, c) : karst_i_fmax(v, c);
    }
    return v;
  }
  case KARST_PERM_BLEND: {
    double sw = 0, sv = 0;
    for (int i = 0; i < n->n_children; i++) {
      double w = n->children[i].weight > 0 ? n->children[i].weight : 1.0;
      sw += w;
      sv += w * perm_node(&n->children[i], bg, p);
    }
    return sw > 0 ? sv / sw : bg;
  }
  }
  return bg;
}

/**
 * Resistance π(p) in [0, 1] (Paris et al. 2021, §4.2): leaves give their
 * resistance where they apply and the background elsewhere (a sphere blends
 * to the background over its falloff with the smooth step g); union takes
 * the minimum (most permeable wins), intersection the maximum, blend the
 * weighted mean. O(size of the tree).
 */
double karst_permeability_eval(const karst_permeability_t *perm, const double p[3]) {
  if (!perm->root) return perm->background;
  return clamp(perm_node(perm->root, perm->background, p), 0.0, 1.0);
}

/* ------------------------------------------------------------------------ */
/* Surfaces                                                                  */
/* ------------------------------------------------------------------------ */

karst_i_surf_t karst_i_surf_plane(double elevation, double dip, double dip_direction, double ox,
                                  double oy) {
  karst_i_surf_t s;
  memset(&s, 0, sizeof s);
  double a = dip_direction * DEG2RAD; /* the operations of karst_horizon_elevation */
  s.kind = KARST_I_SURF_PLANE;
  s.z0 = elevation, s.ox = ox, s.oy = oy;
  s.sa = sin(a), s.ca = cos(a), s.t = tan(dip * DEG2RAD);
  s.flat = dip == 0.0;
  return s;
}

karst_i_surf_t karst_i_surf_of_def(const karst_surface_def_t *d) {
  karst_i_surf_t s;
  memset(&s, 0, sizeof s);
  if (!d || !d->given) return s;
  if (d->path || d->surface) {
    s.kind = KARST_I_SURF_FILE;
    s.file = d->surface;
    return s;
  }
  return karst_i_surf_plane(d->elevation, d->dip, d->dip_direction, d->origin[0], d->origin[1]);
}

/* The terrain as a surface: its file, a view of its grid (built by karst_geology_create, which
 * owns it), or its flat plane. */
static karst_i_surf_t surf_of_terrain(const karst_terrain_t *t, const karst_surface_t *grid_view) {
  karst_i_surf_t s;
  memset(&s, 0, sizeof s);
  if (t->surface || grid_view) {
    s.kind = KARST_I_SURF_FILE;
    s.file = t->surface ? t->surface : grid_view;
    return s;
  }
  return karst_i_surf_plane(t->elevation, 0.0, 0.0, 0.0, 0.0);
}

int karst_i_surf_equal(const karst_i_surf_t *a, const karst_i_surf_t *b) {
  if (a->kind != b->kind) return 0;
  switch (a->kind) {
  case KARST_I_SURF_PLANE:
    return a->z0 == b->z0 && a->ox == b->ox && a->oy == b->oy && a->sa == b->sa && a->ca == b->ca &&
           a->t == b->t && a->flat == b->flat;
  case KARST_I_SURF_FILE:
    return a->file == b->file;
  default:
    return 1;
  }
}

static double plane_z(const karst_i_surf_t *s, double x, double y) {
  if (s->flat) return s->z0;
  return s->z0 - ((x - s->ox) * s->sa + (y - s->oy) * s->ca) * s->t;
}

double karst_i_surf_z(const karst_i_surf_t *s, double x, double y) {
  switch (s->kind) {
  case KARST_I_SURF_PLANE:
    return plane_z(s, x, y);
  case KARST_I_SURF_FILE:
    return s->file ? karst_surface_z(s->file, x, y) : NAN;
  default:
    return NAN;
  }
}

void karst_i_surf_range(const karst_i_surf_t *s, double x0, double x1, double y0, double y1,
                        double *zlo, double *zhi) {
  if (s->kind == KARST_I_SURF_PLANE) { /* a plane: the extremes are at corners */
    double z[4] = {plane_z(s, x0, y0), plane_z(s, x1, y0), plane_z(s, x0, y1), plane_z(s, x1, y1)};
    *zlo = karst_i_fmin(karst_i_fmin(z[0], z[1]), karst_i_fmin(z[2], z[3]));
    *zhi = karst_i_fmax(karst_i_fmax(z[0], z[1]), karst_i_fmax(z[2], z[3]));
  } else if (s->kind == KARST_I_SURF_FILE && s->file) {
    *zlo = karst_surface_min_rect(s->file, x0, x1, y0, y1);
    *zhi = karst_surface_max_rect(s->file, x0, x1, y0, y1);
  } else {
    *zlo = NAN, *zhi = NAN;
  }
}

/**
 * A cheap enclosing range of the surface over the rectangle: exact for a plane; for a file
 * surface its value at the centre ± its Lipschitz constant × the half-diagonal (|f(p) − f(c)| ≤
 * L |p − c|), or the exact range where the centre is not defined. O(1), where the exact range of
 * a triangulated surface costs a clipping of the triangles under the rectangle.
 */
void karst_i_surf_range_bound(const karst_i_surf_t *s, double x0, double x1, double y0, double y1,
                              double *zlo, double *zhi) {
  if (s->kind == KARST_I_SURF_FILE && s->file) {
    double zc = karst_surface_z(s->file, 0.5 * (x0 + x1), 0.5 * (y0 + y1));
    if (isfinite(zc)) {
      double d = karst_surface_lipschitz(s->file) * 0.5 * hypot(x1 - x0, y1 - y0);
      *zlo = zc - d, *zhi = zc + d;
      return;
    }
  }
  karst_i_surf_range(s, x0, x1, y0, y1, zlo, zhi);
}

/**
 * Whether [a, b] lies on one side of the surface, exactly. A plane is linear along the segment,
 * so its ends decide; a file surface is decided piece by piece by karst_surface_segment_below /
 * _above (the ends may touch it, the interior is strictly on one side). A file surface's
 * non-strict test is its strict one: they differ only for a segment running along the surface,
 * which the callers (stratum boundaries) need not tell apart.
 */
int karst_i_surf_segment_side(const karst_i_surf_t *s, const double a[3], const double b[3],
                              int above, int strict) {
  if (s->kind == KARST_I_SURF_PLANE) {
    /* Strictly inside (0, 1), ends may touch, but a segment lying in the plane is not strictly
     * on one side. */
    double qa = (a[2] - plane_z(s, a[0], a[1])) * (above ? -1.0 : 1.0);
    double qb = (b[2] - plane_z(s, b[0], b[1])) * (above ? -1.0 : 1.0);
    if (strict) return qa <= 0 && qb <= 0 && !(qa == 0 && qb == 0);
    return qa <= 0 && qb <= 0;
  }
  if (s->kind == KARST_I_SURF_FILE && s->file)
    return above ? karst_surface_segment_above(s->file, a, b)
                 : karst_surface_segment_below(s->file, a, b);
  return 0;
}

/* ------------------------------------------------------------------------ */
/* Exclusion zones                                                           */
/* ------------------------------------------------------------------------ */

/* Whether (x, y) is inside the polygon (even-odd rule, boundary counts as inside). */
static int point_in_polygon(const double *poly, int n, double x, double y) {
  int inside = 0;
  for (int i = 0, j = n - 1; i < n; j = i++) {
    double xi = poly[2 * i], yi = poly[2 * i + 1], xj = poly[2 * j], yj = poly[2 * j + 1];
    /* on the edge: collinear and within its box */
    double cr = (xj - xi) * (y - yi) - (yj - yi) * (x - xi);
    if (cr == 0 && x >= karst_i_fmin(xi, xj) && x <= karst_i_fmax(xi, xj) &&
        y >= karst_i_fmin(yi, yj) && y <= karst_i_fmax(yi, yj))
      return 1;
    if ((yi > y) != (yj > y) && x < (xj - xi) * (y - yi) / (yj - yi) + xi) inside = !inside;
  }
  return inside;
}

static double orient2(double ax, double ay, double bx, double by, double cx, double cy) {
  return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
}

/* Whether the 2-D segments [p, q] and [r, s] share a point (closed segments). */
static int segments_meet(double px, double py, double qx, double qy, double rx, double ry,
                         double sx, double sy) {
  double d1 = orient2(rx, ry, sx, sy, px, py), d2 = orient2(rx, ry, sx, sy, qx, qy);
  double d3 = orient2(px, py, qx, qy, rx, ry), d4 = orient2(px, py, qx, qy, sx, sy);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0)))
    return 1;
#define ON(ax, ay, bx, by, cx, cy)                                                                 \
  (cx >= karst_i_fmin(ax, bx) && cx <= karst_i_fmax(ax, bx) && cy >= karst_i_fmin(ay, by) &&       \
   cy <= karst_i_fmax(ay, by))
  if (d1 == 0 && ON(rx, ry, sx, sy, px, py)) return 1;
  if (d2 == 0 && ON(rx, ry, sx, sy, qx, qy)) return 1;
  if (d3 == 0 && ON(px, py, qx, qy, rx, ry)) return 1;
  if (d4 == 0 && ON(px, py, qx, qy, sx, sy)) return 1;
#undef ON
  return 0;
}

int karst_i_point_in_exclusion(const karst_exclusion_t *e, const double p[3]) {
  switch (e->kind) {
  case KARST_EXCLUSION_BOX:
    for (int k = 0; k < 3; k++)
      if (!(p[k] >= e->min[k] && p[k] <= e->max[k])) return 0;
    return 1;
  case KARST_EXCLUSION_SPHERE: {
    double d[3] = {p[0] - e->center[0], p[1] - e->center[1], p[2] - e->center[2]};
    return dot3(d, d) <= e->radius * e->radius;
  }
  case KARST_EXCLUSION_PRISM:
    return p[2] >= e->bottom && p[2] <= e->top &&
           point_in_polygon(e->polygon, e->n_vertices, p[0], p[1]);
  }
  return 0;
}

/* Clip the parameter interval [*t0, *t1] of a + t d to lo <= coordinate <= hi (Liang–Barsky);
 * returns 0 when it becomes empty. */
static int clip_slab(double a, double d, double lo, double hi, double *t0, double *t1) {
  if (d == 0) return a >= lo && a <= hi;
  double u = (lo - a) / d, v = (hi - a) / d;
  if (u > v) {
    double w = u;
    u = v, v = w;
  }
  if (u > *t0) *t0 = u;
  if (v < *t1) *t1 = v;
  return *t0 <= *t1;
}

/**
 * Whether the segment [a, b] meets the closed exclusion zone: slab clipping for a box, the
 * distance from the centre to the segment for a sphere, and for a prism the part of the
 * segment within its z range tested against the polygon (an end inside, or an edge crossed).
 * O(1), O(polygon vertices) for a prism.
 */
int karst_i_segment_hits_exclusion(const karst_exclusion_t *e, const double a[3],
                                   const double b[3]) {
  double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  switch (e->kind) {
  case KARST_EXCLUSION_BOX: {
    double t0 = 0, t1 = 1;
    for (int k = 0; k < 3; k++)
      if (!clip_slab(a[k], d[k], e->min[k], e->max[k], &t0, &t1)) return 0;
    return 1;
  }
  case KARST_EXCLUSION_SPHERE: {
    double ac[3] = {a[0] - e->center[0], a[1] - e->center[1], a[2] - e->center[2]};
    double dd = dot3(d, d), t = dd > 0 ? clamp(-dot3(ac, d) / dd, 0.0, 1.0) : 0.0;
    double c[3] = {ac[0] + t * d[0], ac[1] + t * d[1], ac[2] + t * d[2]};
    return dot3(c, c) <= e->radius * e->radius;
  }
  case KARST_EXCLUSION_PRISM: {
    double t0 = 0, t1 = 1;
    if (!clip_slab(a[2], d[2], e->bottom, e->top, &t0, &t1)) return 0;
    double px = a[0] + t0 * d[0], py = a[1] + t0 * d[1];
    double qx = a[0] + t1 * d[0], qy = a[1] + t1 * d[1];
    if (point_in_polygon(e->polygon, e->n_vertices, px, py) ||
        point_in_polygon(e->polygon, e->n_vertices, qx, qy))
      return 1;
    for (int i = 0, j = e->n_vertices - 1; i < e->n_vertices; j = i++)
      if (segments_meet(px, py, qx, qy, e->polygon[2 * j], e->polygon[2 * j + 1], e->polygon[2 * i],
                        e->polygon[2 * i + 1]))
        return 1;
    return 0;
  }
  }
  return 0;
}

/* ------------------------------------------------------------------------ */
/* Fisher distribution of poles                                              */
/* ------------------------------------------------------------------------ */

/* E[cos² θ] of the Fisher distribution, density ∝ e^{κ cos θ} on the sphere: with A(κ) =
 * E[cos θ] = coth κ − 1/κ, integrating by parts gives E[cos² θ] = 1 − 2 A(κ) / κ (Fisher, Lewis
 * & Embleton 1987, §4.4). Series for small κ (E = 1/3 + 2κ²/45 + O(κ⁴)) where the closed form
 * cancels. */
static double fisher_cos2(double kappa) {
  if (!(kappa > 0) || isinf(kappa)) return 1.0;                    /* no dispersion */
  if (kappa < 1e-3) return 1.0 / 3.0 + 2.0 * kappa * kappa / 45.0; /* nearly uniform */
  double A = 1.0 / tanh(kappa) - 1.0 / kappa;
  return 1.0 - 2.0 * A / kappa;
}

void karst_i_fisher_tensor(const double mu[3], double kappa, double T[9]) {
  double c2 = fisher_cos2(kappa), s2 = 0.5 * (1.0 - c2);
  /* E[n nᵀ] = c2 μμᵀ + s2 (I − μμᵀ): symmetric about μ, the transverse variance shared equally. */
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++)
      T[3 * i + j] = c2 * mu[i] * mu[j] + s2 * ((i == j) - mu[i] * mu[j]);
}

/* An orthonormal pair (u, v) completing the unit vector n. */
static void complete_frame(const double n[3], double u[3], double v[3]) {
  double a[3] = {1, 0, 0};
  if (fabs(n[0]) > 0.9) a[0] = 0, a[1] = 1;
  double d = dot3(a, n);
  for (int k = 0; k < 3; k++)
    u[k] = a[k] - d * n[k];
  double l = sqrt(dot3(u, u));
  for (int k = 0; k < 3; k++)
    u[k] /= l;
  v[0] = n[1] * u[2] - n[2] * u[1];
  v[1] = n[2] * u[0] - n[0] * u[2];
  v[2] = n[0] * u[1] - n[1] * u[0];
}

/**
 * A pole from the Fisher distribution about @p mu (Wood 1994, "Simulation of the von Mises
 * Fisher distribution", the exact inverse of the distribution of w = cos θ for p = 3):
 * w = 1 + log(u + (1 − u) e^{−2κ}) / κ, azimuth uniform. κ = 0 (no dispersion) or INFINITY
 * returns @p mu. Two draws either way, so the stream does not depend on κ.
 */
void karst_i_fisher_draw(karst_rng_t *rng, const double mu[3], double kappa, double n[3]) {
  double u1 = karst_rng_uniform(rng), u2 = karst_rng_uniform(rng);
  if (!(kappa > 0) || isinf(kappa)) {
    memcpy(n, mu, 3 * sizeof *n);
    return;
  }
  double w;
  w = 1.0 + log(u1 + (1.0 - u1) * exp(-2.0 * kappa)) / kappa;
  w = clamp(w, -1.0, 1.0);
  double s = sqrt(karst_i_fmax(0.0, 1.0 - w * w)), phi = 2.0 * M_PI * u2, u[3], v[3];
  complete_frame(mu, u, v);
  for (int k = 0; k < 3; k++)
    n[k] = w * mu[k] + s * (cos(phi) * u[k] + sin(phi) * v[k]);
}

/* ------------------------------------------------------------------------ */
/* The model                                                                 */
/* ------------------------------------------------------------------------ */

const karst_scenario_t *karst_geology_scenario(const karst_geology_t *g) {
  return g->sc;
}

double karst_geology_terrain(const karst_geology_t *g, double x, double y) {
  return karst_i_surf_z(&g->terrain, x, y);
}

static int in_box(const karst_scenario_t *sc, const double p[3]) {
  for (int i = 0; i < 3; i++)
    if (!(p[i] >= sc->domain_min[i] && p[i] <= sc->domain_max[i])) return 0;
  return 1;
}

/* Top and bottom of stratum i at (x, y). */
static void stratum_bounds(const karst_geology_t *g, int i, double x, double y, double *lo,
                           double *hi) {
  const karst_i_surf_t *t = &g->stratum_top[i], *b = &g->stratum_bottom[i];
  *hi = t->kind ? karst_i_surf_z(t, x, y) : karst_i_surf_z(&g->terrain, x, y);
  *lo = b->kind ? karst_i_surf_z(b, x, y) : g->sc->domain_min[2];
}

karst_excluded_t karst_geology_exclusion_at(const karst_geology_t *g, const double p[3],
                                            int *index) {
  const karst_scenario_t *sc = g->sc;
  for (int i = 0; i < sc->n_exclusions; i++)
    if (karst_i_point_in_exclusion(&sc->exclusions[i], p)) {
      if (index) *index = i;
      return KARST_EXCLUDED_ZONE;
    }
  for (int i = 0; g->n_insoluble > 0 && i < g->n_strata; i++) {
    if (sc->strata[i].soluble) continue;
    double lo, hi;
    stratum_bounds(g, i, p[0], p[1], &lo, &hi);
    /* The open layer: a contact (a spring at the base of the limestone) is not inside. */
    if (p[2] > lo && p[2] < hi) {
      if (index) *index = i;
      return KARST_EXCLUDED_STRATUM;
    }
  }
  if (index) *index = -1;
  return KARST_EXCLUDED_NONE;
}

int karst_geology_stratum_at(const karst_geology_t *g, const double p[3]) {
  for (int i = 0; i < g->n_strata; i++) {
    double lo, hi;
    stratum_bounds(g, i, p[0], p[1], &lo, &hi);
    if (p[2] >= lo && p[2] <= hi) return i;
  }
  return -1;
}

/**
 * Whether @p p lies in the karstifiable bedrock: inside the closed domain box,
 * at or below the terrain, z <= h(x, y) (Paris et al. 2021, §4: the bedrock H),
 * outside every exclusion zone and every insoluble stratum. The ground itself
 * belongs to the bedrock so that a key point placed exactly on it (a swallow
 * hole, a spring) is accepted; random samples are still drawn strictly below it.
 * @return 1 inside, 0 outside (also for non-finite coordinates).
 * Time complexity: O(1 + exclusions + insoluble strata).
 */
int karst_geology_in_bedrock(const karst_geology_t *g, const double p[3]) {
  if (!finite3(p) || !in_box(g->sc, p)) return 0;
  if (!(p[2] <= karst_i_surf_z(&g->terrain, p[0], p[1]))) return 0;
  if ((g->sc->n_exclusions > 0 || g->n_insoluble > 0) &&
      karst_geology_exclusion_at(g, p, NULL) != KARST_EXCLUDED_NONE)
    return 0;
  return 1;
}

/* Whether [a, b] avoids the open insoluble stratum i: with top >= bottom everywhere, the set of
 * t where z(t) >= top(t) and the set where z(t) <= bottom(t) are closed and cover [0, 1] when the
 * segment never enters the layer, so by connectedness one of them is all of [0, 1]. */
static int segment_avoids_stratum(const karst_geology_t *g, int i, const double a[3],
                                  const double b[3]) {
  karst_i_surf_t top = g->stratum_top[i].kind ? g->stratum_top[i] : g->terrain;
  const karst_i_surf_t *bot = &g->stratum_bottom[i];
  if (karst_i_surf_segment_side(&top, a, b, 1, 0)) return 1; /* on or above the top */
  if (!bot->kind) return 0; /* the layer reaches the domain bottom: below the top means inside */
  return karst_i_surf_segment_side(bot, a, b, 0, 0); /* on or below the bottom */
}

/**
 * Whether the whole segment [a, b] lies in the bedrock. The box is convex, so
 * its test is on the end points; the terrain is decided exactly on the
 * surface's pieces (karst_i_surf_segment_side: every interior point strictly
 * below the ground, the ends may touch it); the segment must miss every
 * closed exclusion zone and every open insoluble stratum.
 * @return 1 when every point is in the bedrock, else 0.
 * Time complexity: O(1 + grid lines crossed + exclusions + strata).
 */
int karst_geology_segment_in_bedrock(const karst_geology_t *g, const double a[3],
                                     const double b[3]) {
  return karst_geology_in_bedrock(g, a) && karst_geology_in_bedrock(g, b) &&
         karst_i_geology_segment_between(g, a, b);
}

/* The segment tests of karst_geology_segment_in_bedrock once both ends are in the bedrock (the
 * graph knows it of every sample: the edge costs skip the two end tests, about 2 % of a run). */
int karst_i_geology_segment_between(const karst_geology_t *g, const double a[3],
                                    const double b[3]) {
  if (!karst_i_surf_segment_side(&g->terrain, a, b, 0, 1)) return 0;
  const karst_scenario_t *sc = g->sc;
  for (int i = 0; i < sc->n_exclusions; i++)
    if (karst_i_segment_hits_exclusion(&sc->exclusions[i], a, b)) return 0;
  for (int i = 0; g->n_insoluble > 0 && i < g->n_strata; i++)
    if (!sc->strata[i].soluble && !segment_avoids_stratum(g, i, a, b)) return 0;
  return 1;
}

/**
 * Horizon term cL(p) = g(d(p, L) / r) (Paris et al. 2021, §4.2) with d the
 * vertical distance to a horizon and r its radius; with several horizons the
 * strongest, min_h g(d_h / r_h), which is continuous in p. 1 without horizons.
 * O(horizons).
 */
double karst_geology_horizon_term(const karst_geology_t *g, const double p[3]) {
  double c = 1.0;
  for (int h = 0; h < g->n_horizons; h++) {
    double z = karst_i_surf_z(&g->horizon[h], p[0], p[1]);
    if (!isfinite(z)) continue;
    c = karst_i_fmin(c, smoothstep(fabs(p[2] - z) / g->sc->horizons[h].radius));
  }
  return c;
}

double karst_geology_permeability(const karst_geology_t *g, const double p[3]) {
  return karst_permeability_eval(&g->sc->permeability, p);
}

int karst_geology_n_springs(const karst_geology_t *g) {
  return g->n_springs;
}
int karst_geology_spring_key(const karst_geology_t *g, int spring) {
  return spring >= 0 && spring < g->n_springs ? g->spring_key[spring] : -1;
}
int karst_geology_spring_of_key(const karst_geology_t *g, int key) {
  return key >= 0 && key < g->sc->n_key_points ? g->key_spring[key] : -1;
}

double karst_geology_water_table(const karst_geology_t *g, int spring, double x, double y) {
  if (spring < 0 || spring >= g->n_springs) return NAN;
  return karst_i_surf_z(&g->water_table[spring], x, y);
}

/** Zone of p against spring @p spring's water table W: vadose above W + band, phreatic below
 *  W − band, epiphreatic within. O(1). */
karst_zone_t karst_geology_zone(const karst_geology_t *g, int spring, const double p[3]) {
  double d = p[2] - karst_geology_water_table(g, spring, p[0], p[1]);
  if (d > g->band) return KARST_ZONE_VADOSE;
  if (d < -g->band) return KARST_ZONE_PHREATIC;
  return KARST_ZONE_EPIPHREATIC;
}

const karst_disc_t *karst_geology_discs(const karst_geology_t *g, karst_int_t *n) {
  if (n) *n = g->n_discs;
  return g->discs;
}

/* ------------------------------------------------------------------------ */
/* Discrete fracture networks                                               */
/* ------------------------------------------------------------------------ */

/* Mean of r² under p(r) ∝ r^-a on [r0, r1] (a > 1). */
static double powerlaw_mean_r2(double a, double r0, double r1) {
  if (r0 == r1) return r0 * r0;
  double z =
      fabs(a - 1.0) < 1e-12 ? log(r1 / r0) : (pow(r1, 1.0 - a) - pow(r0, 1.0 - a)) / (1.0 - a);
  double m =
      fabs(a - 3.0) < 1e-12 ? log(r1 / r0) : (pow(r1, 3.0 - a) - pow(r0, 3.0 - a)) / (3.0 - a);
  return m / z;
}

/* A radius from p(r) ∝ r^-a on [r0, r1] by inversion of its distribution function. */
static double powerlaw_draw(karst_rng_t *rng, double a, double r0, double r1) {
  double u = karst_rng_uniform(rng);
  if (r0 == r1) return r0;
  if (fabs(a - 1.0) < 1e-12) return r0 * pow(r1 / r0, u);
  double e = 1.0 - a, lo = pow(r0, e), hi = pow(r1, e);
  return clamp(pow(lo + u * (hi - lo), 1.0 / e), r0, r1);
}

/* A Poisson(λ) count: Knuth's product method for small λ, the normal approximation rounded
 * (with continuity correction) beyond 1000, where its relative error is below 1 %. */
static karst_int_t poisson_draw(karst_rng_t *rng, double lambda) {
  if (!(lambda > 0)) return 0;
  if (lambda > 1000) {
    double x = lambda + sqrt(lambda) * karst_rng_gaussian(rng);
    return x < 0 ? 0 : (karst_int_t)floor(x + 0.5);
  }
  double L = exp(-lambda), p = 1.0;
  karst_int_t k = 0;
  do {
    k++;
    p *= karst_rng_uniform(rng);
  } while (p > L);
  return k - 1;
}

/** Most discs a scenario may realise (all families): beyond, the DFN is refused (it would be a
 *  different model than a few conduits' worth of cost reductions). */
#define KARST_GEOLOGY_MAX_DISCS 2000000
/** Most cells of the disc grid. */
#define DISC_GRID_MAX_CELLS (1 << 21)

/* Stream of the fracture-network draws (karst_rng_derive's substream; see generate_internal.h). */
#define GEOLOGY_STREAM 7

/* Realise the discrete fracture networks: per family, a Poisson number of discs with mean
 * P32 · V' / E[π r²] (so the expected fracture area per unit volume is P32), centres uniform in
 * the domain box grown by r_max on every side (V' its volume: discs cutting the domain from
 * outside are counted), poles from the family's Fisher distribution, radii from its power law.
 * Families are drawn in order from one stream. */
static karst_error_t realise_dfn(karst_ctx_t *ctx, karst_geology_t *g, uint64_t seed,
                                 uint64_t realisation) {
  const karst_scenario_t *sc = g->sc;
  karst_rng_t rng;
  karst_rng_derive(&rng, seed, realisation, GEOLOGY_STREAM);
  karst_int_t cap = 0;
  for (int f = 0; f < sc->n_fractures; f++) {
    const karst_fracture_t *fr = &sc->fractures[f];
    if (!fr->dfn) continue;
    double lo[3], hi[3], vol = 1.0;
    for (int k = 0; k < 3; k++) {
      lo[k] = sc->domain_min[k] - fr->r_max, hi[k] = sc->domain_max[k] + fr->r_max;
      vol *= hi[k] - lo[k];
    }
    double mean =
        fr->p32 * vol / (M_PI * powerlaw_mean_r2(fr->size_exponent, fr->r_min, fr->r_max));
    if (!(mean <= KARST_GEOLOGY_MAX_DISCS))
      return karst_scenario_fail_at(
          ctx, sc, fr->line, fr->column, KARST_ERANGE,
          "fractures: this family's network would hold about %.3g discs (p32 %g m²/m³ "
          "over %.3g m³ with radii %g-%g m), more than the %d allowed; lower p32 or "
          "raise r_min",
          mean, fr->p32, vol, fr->r_min, fr->r_max, KARST_GEOLOGY_MAX_DISCS);
    karst_int_t m = poisson_draw(&rng, mean);
    if (g->n_discs + m > KARST_GEOLOGY_MAX_DISCS)
      return karst_scenario_fail_at(ctx, sc, fr->line, fr->column, KARST_ERANGE,
                                    "fractures: the networks hold more than %d discs",
                                    KARST_GEOLOGY_MAX_DISCS);
    if (g->n_discs + m > cap) {
      cap = (g->n_discs + m) * 2;
      karst_disc_t *nd = realloc(g->discs, (size_t)cap * sizeof *nd);
      if (!nd)
        return karst_set_error(ctx, KARST_ENOMEM, "no memory for %lld fracture discs",
                               (long long)cap);
      g->discs = nd;
    }
    double mu[3];
    karst_plane_normal(fr->dip_direction, fr->dip, mu);
    for (karst_int_t i = 0; i < m; i++) {
      karst_disc_t *d = &g->discs[g->n_discs++];
      memset(d, 0, sizeof *d); /* padding too: the discs are compared byte for byte */
      for (int k = 0; k < 3; k++)
        d->c[k] = karst_rng_uniform_range(&rng, lo[k], hi[k]);
      karst_i_fisher_draw(&rng, mu, fr->kappa, d->n);
      if (d->n[2] < 0)
        for (int k = 0; k < 3; k++)
          d->n[k] = -d->n[k];
      d->r = powerlaw_draw(&rng, fr->size_exponent, fr->r_min, fr->r_max);
      d->family = f;
    }
  }
  return KARST_SUCCESS;
}

/* Half-extent, along axis k, of a disc of radius r and normal n (its bounding box). */
static double disc_half_extent(const karst_disc_t *d, int k) {
  return d->r * sqrt(karst_i_fmax(0.0, 1.0 - d->n[k] * d->n[k]));
}

/* A uniform grid over the domain whose cells list the discs whose box, grown by the family's
 * influence distance, meets them (CSR, two passes). */
static karst_error_t index_discs(karst_ctx_t *ctx, karst_geology_t *g) {
  const karst_scenario_t *sc = g->sc;
  if (g->n_discs == 0) return KARST_SUCCESS;
  double ext[3], vol = 1.0, rsum = 0.0;
  for (int k = 0; k < 3; k++)
    ext[k] = sc->domain_max[k] - sc->domain_min[k], vol *= ext[k];
  for (karst_int_t i = 0; i < g->n_discs; i++)
    rsum += g->discs[i].r;
  /* Cells about the mean radius, but no more than DISC_GRID_MAX_CELLS of them. */
  double cell = karst_i_fmax(rsum / (double)g->n_discs, cbrt(vol / DISC_GRID_MAX_CELLS));
  size_t cells = 1;
  for (int k = 0; k < 3; k++) {
    g->disc_origin[k] = sc->domain_min[k];
    g->disc_dims[k] = (int64_t)karst_i_fmax(1.0, ceil(ext[k] / cell));
    cells *= (size_t)g->disc_dims[k];
  }
  g->disc_cell = cell;
  g->disc_start = calloc(cells + 1, sizeof *g->disc_start);
  if (!g->disc_start)
    return karst_set_error(ctx, KARST_ENOMEM, "no memory for the fracture disc grid");
  for (int pass = 0; pass < 2; pass++) {
    for (karst_int_t i = 0; i < g->n_discs; i++) {
      const karst_disc_t *d = &g->discs[i];
      double infl = sc->fractures[d->family].influence;
      int64_t lo[3], hi[3];
      for (int k = 0; k < 3; k++) {
        double e = disc_half_extent(d, k) + infl;
        double l = floor((d->c[k] - e - g->disc_origin[k]) / cell),
               h = floor((d->c[k] + e - g->disc_origin[k]) / cell);
        lo[k] = (int64_t)karst_i_fmax(0.0, l);
        hi[k] = (int64_t)karst_i_fmin((double)(g->disc_dims[k] - 1), h);
        if (lo[k] > hi[k]) goto next;
      }
      for (int64_t z = lo[2]; z <= hi[2]; z++)
        for (int64_t y = lo[1]; y <= hi[1]; y++)
          for (int64_t x = lo[0]; x <= hi[0]; x++) {
            size_t c = (size_t)(x + g->disc_dims[0] * (y + g->disc_dims[1] * z));
            if (pass == 0)
              g->disc_start[c + 1]++;
            else
              g->disc_list[g->disc_start[c]++] = i;
          }
    next:;
    }
    if (pass == 0) {
      for (size_t c = 0; c < cells; c++)
        g->disc_start[c + 1] += g->disc_start[c];
      g->disc_list = malloc((size_t)(g->disc_start[cells] > 0 ? g->disc_start[cells] : 1) *
                            sizeof *g->disc_list);
      if (!g->disc_list)
        return karst_set_error(ctx, KARST_ENOMEM, "no memory for the fracture disc grid");
    } else { /* the second pass advanced every start to the next cell's: shift back */
      for (size_t c = cells; c > 0; c--)
        g->disc_start[c] = g->disc_start[c - 1];
      g->disc_start[0] = 0;
    }
  }
  return KARST_SUCCESS;
}

int karst_i_geology_discs_at(const karst_geology_t *g, const double p[3],
                             int (*fn)(const karst_disc_t *d, void *arg), void *arg) {
  if (!g->disc_start) return 0;
  int64_t c[3];
  for (int k = 0; k < 3; k++) {
    double f = floor((p[k] - g->disc_origin[k]) / g->disc_cell);
    if (!(f >= 0 && f < (double)g->disc_dims[k])) return 0;
    c[k] = (int64_t)f;
  }
  size_t cell = (size_t)(c[0] + g->disc_dims[0] * (c[1] + g->disc_dims[1] * c[2]));
  for (karst_int_t i = g->disc_start[cell]; i < g->disc_start[cell + 1]; i++) {
    int r = fn(&g->discs[g->disc_list[i]], arg);
    if (r) return r;
  }
  return 0;
}

/* ------------------------------------------------------------------------ */
/* Building the model                                                        */
/* ------------------------------------------------------------------------ */

void karst_geology_free(karst_geology_t *g) {
  if (!g) return;
  karst_surface_free(g->terrain_view);
  free(g->horizon);
  free(g->spring_key);
  free(g->key_spring);
  free(g->water_table);
  free(g->stratum_top);
  free(g->stratum_bottom);
  free(g->fracture_tensor);
  free(g->discs);
  free(g->disc_start);
  free(g->disc_list);
  free(g->fault_normal);
  free(g);
}

/* A surface must be defined over the whole domain footprint (a file surface may fall short). */
static karst_error_t check_surface_covers(karst_ctx_t *ctx, const karst_scenario_t *sc,
                                          const karst_i_surf_t *s, const char *what, int line,
                                          int col) {
  if (s->kind != KARST_I_SURF_FILE) return KARST_SUCCESS;
  double xs[3] = {sc->domain_min[0], 0.5 * (sc->domain_min[0] + sc->domain_max[0]),
                  sc->domain_max[0]};
  double ys[3] = {sc->domain_min[1], 0.5 * (sc->domain_min[1] + sc->domain_max[1]),
                  sc->domain_max[1]};
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++)
      if (!isfinite(karst_i_surf_z(s, xs[i], ys[j])))
        return karst_scenario_fail_at(
            ctx, sc, line, col, KARST_ERANGE,
            "%s is not defined at (%g, %g), inside the domain; it must cover the "
            "domain's x-y extent",
            what, xs[i], ys[j]);
  return KARST_SUCCESS;
}

static karst_error_t check_key_points(karst_ctx_t *ctx, const karst_geology_t *g) {
  const karst_scenario_t *sc = g->sc;
  for (int i = 0; i < sc->n_key_points; i++) {
    const karst_keypoint_t *kp = &sc->key_points[i];
    int idx = -1;
    karst_excluded_t ex = karst_geology_exclusion_at(g, kp->p, &idx);
    if (ex == KARST_EXCLUDED_ZONE) {
      const karst_exclusion_t *e = &sc->exclusions[idx];
      char nm[KARST_SCENARIO_NAME_MAX + 8] = "";
      if (e->name[0]) snprintf(nm, sizeof nm, " '%s'", e->name);
      return karst_scenario_fail_at(
          ctx, sc, kp->line, kp->column, KARST_EINVAL,
          "key_points[%d] '%s' at (%g, %g, %g) is inside exclusions[%d]%s (line %d), "
          "which holds no conduit; move it out or shrink the zone",
          i, kp->name, kp->p[0], kp->p[1], kp->p[2], idx, nm, e->line);
    }
    if (ex == KARST_EXCLUDED_STRATUM) {
      const karst_stratum_t *s = &sc->strata[idx];
      double lo, hi;
      stratum_bounds(g, idx, kp->p[0], kp->p[1], &lo, &hi);
      return karst_scenario_fail_at(
          ctx, sc, kp->line, kp->column, KARST_EINVAL,
          "key_points[%d] '%s' at z = %g m is inside the insoluble stratum '%s' "
          "(line %d; %g to %g m there), which holds no conduit",
          i, kp->name, kp->p[2], s->name, s->line, lo, hi);
    }
  }
  return KARST_SUCCESS;
}

/**
 * Build the geological model of @p sc (see geology.h).
 * Time complexity: O(horizons + springs + strata + discs × cells each disc meets).
 */
karst_error_t karst_geology_create(karst_ctx_t *ctx, const karst_scenario_t *sc, uint64_t seed,
                                   uint64_t realisation, karst_geology_t **out) {
  karst_error_t err = KARST_SUCCESS;
  *out = NULL;
  if (!sc) return karst_set_error(ctx, KARST_EINVAL, "geology: no scenario");
  karst_geology_t *g = calloc(1, sizeof *g);
  if (!g) return karst_set_error(ctx, KARST_ENOMEM, "geology: out of memory");
  g->sc = sc;
  g->band = sc->routing.water_table_band;
  const karst_terrain_t *tr = &sc->terrain;
  if (!tr->surface && tr->is_grid && tr->z && tr->ncols > 0 && tr->nrows > 0 &&
      (err = karst_i_surface_grid_view(ctx, tr->ncols, tr->nrows, tr->xll, tr->yll, tr->cellsize,
                                       tr->z, &g->terrain_view)))
    goto cleanup;
  g->terrain = surf_of_terrain(tr, g->terrain_view);
  size_t nk = (size_t)(sc->n_key_points > 0 ? sc->n_key_points : 1);
  g->key_spring = malloc(nk * sizeof *g->key_spring);
  g->spring_key = malloc(nk * sizeof *g->spring_key);
  g->water_table = calloc(nk, sizeof *g->water_table);
  g->horizon = calloc((size_t)(sc->n_horizons > 0 ? sc->n_horizons : 1), sizeof *g->horizon);
  g->stratum_top = calloc((size_t)(sc->n_strata > 0 ? sc->n_strata : 1), sizeof *g->stratum_top);
  g->stratum_bottom =
      calloc((size_t)(sc->n_strata > 0 ? sc->n_strata : 1), sizeof *g->stratum_bottom);
  g->fracture_tensor =
      calloc((size_t)(sc->n_fractures > 0 ? 9 * sc->n_fractures : 1), sizeof(double));
  g->fault_normal = calloc((size_t)(sc->n_faults > 0 ? 3 * sc->n_faults : 1), sizeof(double));
  if (!g->key_spring || !g->spring_key || !g->water_table || !g->horizon || !g->stratum_top ||
      !g->stratum_bottom || !g->fracture_tensor || !g->fault_normal) {
    err = karst_set_error(ctx, KARST_ENOMEM, "geology: out of memory");
    goto cleanup;
  }
  g->n_horizons = sc->n_horizons;
  for (int h = 0; h < sc->n_horizons; h++) {
    const karst_horizon_t *H = &sc->horizons[h];
    if (H->path || H->surface) {
      memset(&g->horizon[h], 0, sizeof g->horizon[h]);
      g->horizon[h].kind = KARST_I_SURF_FILE;
      g->horizon[h].file = H->surface;
    } else {
      g->horizon[h] =
          karst_i_surf_plane(H->elevation, H->dip, H->dip_direction, H->origin[0], H->origin[1]);
    }
    char what[96];
    snprintf(what, sizeof what, "horizons[%d]", h);
    if ((err = check_surface_covers(ctx, sc, &g->horizon[h], what, H->line, H->column)))
      goto cleanup;
  }
  for (int k = 0; k < sc->n_key_points; k++) {
    const karst_keypoint_t *kp = &sc->key_points[k];
    g->key_spring[k] = -1;
    if (kp->type != KARST_KEYPOINT_SPRING) continue;
    int s = g->n_springs++;
    g->spring_key[s] = k;
    g->key_spring[k] = s;
    /* Its own, else its generation's base level (generations[].water_table), else the
     * scenario's, else the plane through it. */
    const karst_surface_def_t *gen_wt =
        kp->generation > 0 && kp->generation <= sc->n_generations &&
                sc->generations[kp->generation - 1].water_table.given
            ? &sc->generations[kp->generation - 1].water_table
            : NULL;
    const karst_surface_def_t *def = kp->water_table.given   ? &kp->water_table
                                     : gen_wt                ? gen_wt
                                     : sc->water_table.given ? &sc->water_table
                                                             : NULL;
    g->water_table[s] =
        def ? karst_i_surf_of_def(def) : karst_i_surf_plane(kp->p[2], 0.0, 0.0, kp->p[0], kp->p[1]);
    char what[160];
    snprintf(what, sizeof what, "the water table of spring '%s'", kp->name);
    if ((err = check_surface_covers(ctx, sc, &g->water_table[s], what, def ? def->line : kp->line,
                                    def ? def->column : kp->column)))
      goto cleanup;
  }
  g->n_strata = sc->n_strata;
  for (int i = 0; i < sc->n_strata; i++) {
    const karst_stratum_t *st = &sc->strata[i];
    g->stratum_top[i] = karst_i_surf_of_def(&st->top);
    g->stratum_bottom[i] = karst_i_surf_of_def(&st->bottom);
    g->n_insoluble += !st->soluble;
    char what[160];
    snprintf(what, sizeof what, "the top of stratum '%s'", st->name);
    if ((err =
             check_surface_covers(ctx, sc, &g->stratum_top[i], what, st->top.line, st->top.column)))
      goto cleanup;
    snprintf(what, sizeof what, "the bottom of stratum '%s'", st->name);
    if ((err = check_surface_covers(ctx, sc, &g->stratum_bottom[i], what, st->bottom.line,
                                    st->bottom.column)))
      goto cleanup;
  }
  for (int f = 0; f < sc->n_fractures; f++) {
    double mu[3];
    karst_plane_normal(sc->fractures[f].dip_direction, sc->fractures[f].dip, mu);
    karst_i_fisher_tensor(mu, sc->fractures[f].kappa, g->fracture_tensor + 9 * f);
    g->fracture_wmax = karst_i_fmax(g->fracture_wmax, sc->fractures[f].weight);
  }
  for (int f = 0; f < sc->n_faults; f++)
    karst_plane_normal(sc->faults[f].dip_direction, sc->faults[f].dip, g->fault_normal + 3 * f);
  if ((err = check_key_points(ctx, g))) goto cleanup;
  if ((err = realise_dfn(ctx, g, seed, realisation))) goto cleanup;
  if ((err = index_discs(ctx, g))) goto cleanup;
  *out = g;
  g = NULL;
cleanup:
  karst_geology_free(g);
  return err;
}
