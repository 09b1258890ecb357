/* Geological fields of a scenario: terrain height, horizons, fracture planes
 * and the permeability construction tree (Paris et al. 2021, §4.2). */
#include <math.h>

#include "karst/scenario.h"

static double clamp(double x, double a, double b) {
  return x < a ? a : (x > b ? b : x);
}

/* Smooth step g(x) = 3x^2 - 2x^3 on [0, 1] (Paris et al. 2021, §4.2). */
static double smoothstep(double x) {
  x = clamp(x, 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

/**
 * Terrain elevation at (x, y): the flat elevation, or bilinear interpolation
 * of the grid (cell centres), clamped at the border. O(1).
 */
double karst_terrain_height(const karst_terrain_t *t, double x, double y) {
  if (!t->is_grid || !t->z || t->ncols < 1 || t->nrows < 1) return t->elevation;
  double fx = clamp((x - t->xll) / t->cellsize, 0.0, (double)(t->ncols - 1));
  double fy = clamp((y - t->yll) / t->cellsize, 0.0, (double)(t->nrows - 1));
  karst_int_t i = (karst_int_t)floor(fx), j = (karst_int_t)floor(fy);
  if (i >= t->ncols - 1) i = t->ncols > 1 ? t->ncols - 2 : 0;
  if (j >= t->nrows - 1) j = t->nrows > 1 ? t->nrows - 2 : 0;
  double u = t->ncols > 1 ? fx - i : 0, v = t->nrows > 1 ? fy - j : 0;
  karst_int_t i1 = t->ncols > 1 ? i + 1 : i, j1 = t->nrows > 1 ? j + 1 : j;
  const double *z = t->z;
  double z00 = z[j * t->ncols + i], z10 = z[j * t->ncols + i1];
  double z01 = z[j1 * t->ncols + i], z11 = z[j1 * t->ncols + i1];
  return (1 - v) * ((1 - u) * z00 + u * z10) + v * ((1 - u) * z01 + u * z11);
}

/**
 * Unit normal of a plane from its dip direction and dip (degrees), with x east,
 * y north, z up: n = (sin δ sin α, sin δ cos α, cos δ). O(1).
 */
void karst_plane_normal(double dip_direction, double dip, double n[3]) {
  const double d2r = M_PI / 180.0;
  double a = dip_direction * d2r, d = dip * d2r;
  n[0] = sin(d) * sin(a);
  n[1] = sin(d) * cos(a);
  n[2] = cos(d);
}

/**
 * Elevation of a (possibly dipping) horizon at (x, y): the plane through
 * (origin, elevation) whose surface descends by tan(dip) per metre towards
 * the dip direction. O(1).
 */
double karst_horizon_elevation(const karst_horizon_t *h, double x, double y) {
  if (h->dip == 0.0) return h->elevation;
  const double d2r = M_PI / 180.0;
  double a = h->dip_direction * d2r;
  double along = (x - h->origin[0]) * sin(a) + (y - h->origin[1]) * cos(a);
  return h->elevation - along * tan(h->dip * d2r);
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
      v = n->kind == KARST_PERM_UNION ? fmin(v, c) : fmax(v, c);
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
