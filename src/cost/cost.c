/* Geology-based cost functions and their line integral along graph edges
 * (Paris et al. 2021, §4 and §4.2), bedrock membership of points and
 * segments, and the lower bound of the cost per metre used by A*. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/math_internal.h"
#include "cost/cost_internal.h"
#include "geology/geology_internal.h"

/* Candidate break points of one edge kept on the stack. Horizons: with A
 * active horizons an exact integral needs A^2 + 2A of them, so at most
 * MAX_EXACT_HORIZONS = 7 active horizons are integrated exactly (more fall
 * back to composite Gauss–Legendre, see horizon_integral). Permeability:
 * break points beyond the buffer are ignored, which only costs accuracy. */
#define MAX_BREAKS 64
#define MAX_EXACT_HORIZONS 7

static double clampd(double x, double a, double b) {
  return x < a ? a : (x > b ? b : x);
}

static double dot3(const double a[3], const double b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* ------------------------------------------------------------------------ */
/* Bedrock membership: the geology's (include/karst/geology.h)               */
/* ------------------------------------------------------------------------ */

/** karst_geology_in_bedrock: the domain box, at or below the terrain, outside every exclusion. */
int karst_cost_in_bedrock(const karst_geology_t *g, const double p[3]) {
  return karst_geology_in_bedrock(g, p);
}

/** karst_geology_segment_in_bedrock: exact, see there. */
int karst_cost_segment_in_bedrock(const karst_geology_t *g, const double a[3], const double b[3]) {
  return karst_geology_segment_in_bedrock(g, a, b);
}

/* ------------------------------------------------------------------------ */
/* Pointwise terms                                                           */
/* ------------------------------------------------------------------------ */

/** Horizon term cL(p) (karst_geology_horizon_term: min_h g(d_h / r_h), 1 without horizons). */
double karst_cost_horizon_term(const karst_geology_t *g, const double p[3]) {
  return karst_geology_horizon_term(g, p);
}

/* Σ-or-min combination of the families' quadratic forms dᵀ T_k d, T_k = E[n nᵀ] of the family's
 * Fisher distribution (n nᵀ without dispersion). */
static double fracture_term(const karst_geology_t *g, const double d[3]) {
  const karst_scenario_t *sc = g->sc;
  const double len2 = dot3(d, d), wmax = g->fracture_wmax;
  const int use_min = sc->cost.fracture_combine == KARST_FRACTURE_MIN;
  double c = use_min ? wmax : 0.0;
  for (int k = 0; k < sc->n_fractures; k++) {
    const double *T = g->fracture_tensor + 9 * k, w = sc->fractures[k].weight;
    double q; /* E[(n·d̂)²] */
    if (len2 > 0) {
      q = 0;
      for (int a = 0; a < 3; a++)
        q += d[a] * (T[3 * a] * d[0] + T[3 * a + 1] * d[1] + T[3 * a + 2] * d[2]);
      q /= len2;
    } else {
      q = 1.0;
    }
    if (use_min) {
      const double x = wmax - w * (1.0 - q); /* never NaN: finite weights, q in [0, 1] */
      c = x < c ? x : c;
    } else
      c += w * q;
  }
  return c;
}

/**
 * Fracture term cF(d) = Σ_k w_k E[(n_k·d̂)²] with n_k the unit pole of family
 * k and d̂ = d/|d| (Paris et al. 2021, §4.2, as its text and Fig. 7 intend:
 * "edges with a direction parallel to a fracture plane have a smaller cost
 * value than orthogonal ones"). Without dispersion the expectation is
 * (μ_k·d̂)² for the mean pole μ_k (karst_plane_normal); with a Fisher
 * concentration κ it is d̂ᵀ T_k d̂, T_k = E[n nᵀ] = c μμᵀ + (1 − c)/2 (I − μμᵀ),
 * c = E[cos² θ] = 1 − 2 A(κ)/κ (karst_i_fisher_tensor), so a dispersed family
 * attracts less sharply. The paper prints Σ w_k (1 − (n_k·d̂)²), which with
 * n_k the plane normal is the squared in-plane component and would make paths
 * cross the planes; that formula is the right one for a vector lying in the
 * fracture (its 2-D trace), and its 3-D form for a plane of normal n_k is the
 * squared normal component used here: 0 along strike and dip, w_k across.
 *
 * With cost.fracture_combine = min: cF(d) = min_k [W − w_k (1 − E[(n_k·d̂)²])],
 * W = max_k w_k. Any sum is a quadratic form dᵀMd, whose minimum directions
 * form one eigenspace: two vertical families (N–S and E–W planes) would make
 * every horizontal direction cost the same, so a sum cannot favour both axes
 * over the diagonal (the rectilinear mazes of Fig. 15). The min is cheap
 * wherever d follows ANY one family. A zero direction gives Σ w_k (sum) or W
 * (min), the most expensive values.
 * Time complexity: O(number of fracture families).
 */
double karst_cost_fracture_term(const karst_geology_t *g, const double dir[3]) {
  return fracture_term(g, dir);
}

/**
 * Cost per metre c(p, d) = w0 + wL cL(p) + wF cF(d) + wπ π(p) (Paris et al.
 * 2021, §4.2, with the base cost w0 > 0 that keeps every path finite and
 * the A* heuristic meaningful). The factors of fractures (discs), faults and
 * prescribed paths apply to edges, not to points (see karst_cost_edge).
 * @param g the geology; @param p the point; @param dir the direction (any length).
 * @return the cost per metre. Time complexity: O(horizons + fractures + tree size).
 */
double karst_cost_point(const karst_geology_t *g, const double p[3], const double dir[3]) {
  const karst_cost_weights_t *w = &g->sc->cost;
  return w->w0 + w->horizon * karst_geology_horizon_term(g, p) +
         w->fracture * karst_cost_fracture_term(g, dir) +
         w->permeability * karst_geology_permeability(g, p);
}

/* ------------------------------------------------------------------------ */
/* Line integrals                                                            */
/* ------------------------------------------------------------------------ */

static void sort_small(double *v, int n) {
  for (int i = 1; i < n; i++) {
    double x = v[i];
    int j = i - 1;
    while (j >= 0 && v[j] > x)
      v[j + 1] = v[j], j--;
    v[j + 1] = x;
  }
}

static void push_break(double *v, int *n, double s) {
  if (s > 0.0 && s < 1.0 && *n < MAX_BREAKS) v[(*n)++] = s;
}

/* Mean of g∘clamp over a linear x from x0 to x1, i.e. (H(x1) − H(x0)) /
 * (x1 − x0) with H' = g on [0, 1], H(x) = x³ − x⁴/2, written as divided
 * differences so that x0 = x1 needs no special case and no tolerance. */
static double mean_g_linear(double x0, double x1) {
  if (x0 >= 1.0 && x1 >= 1.0) return 1.0;
  if (x0 > 1.0 || x1 > 1.0) { /* split at x = 1 */
    double f = (1.0 - x0) / (x1 - x0);
    double lo = x0 < 1.0 ? x0 : x1;
    double frac_lo = x0 < 1.0 ? f : 1.0 - f;
    return frac_lo * mean_g_linear(lo, 1.0) + (1.0 - frac_lo);
  }
  return (x1 * x1 + x1 * x0 + x0 * x0) - 0.5 * (x1 + x0) * (x1 * x1 + x0 * x0);
}

/* Gauss–Legendre nodes on [0, 1] and weights (sum 1). */
static const double GL2_X[2] = {0.21132486540518711775, 0.78867513459481288225};
static const double GL3_X[3] = {0.11270166537925831148, 0.5, 0.88729833462074168852};
static const double GL3_W[3] = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};

/* Elevation of horizon h (its surface in the geology). */
static double plane_elevation(const karst_i_cost_model_t *m, int h, double x, double y) {
  return karst_i_surf_z(&m->geo->horizon[h], x, y);
}

/* ∫_0^1 cL(a + s(b − a)) ds. */
static double horizon_integral(const karst_i_cost_model_t *m, const double a[3], const double b[3],
                               double len) {
  const karst_scenario_t *sc = m->sc;
  if (!m->horizons_planar) { /* folded horizons: the offset is not linear along the edge */
    /* An edge that stays farther than every horizon's radius from it has cL = 1 all along: the
     * horizon's exact range over the edge's x-y box decides (most edges are far from any). */
    double zlo_e = karst_i_fmin(a[2], b[2]), zhi_e = karst_i_fmax(a[2], b[2]);
    double x0 = karst_i_fmin(a[0], b[0]), x1 = karst_i_fmax(a[0], b[0]),
           y0 = karst_i_fmin(a[1], b[1]), y1 = karst_i_fmax(a[1], b[1]);
    int near = 0;
    for (int h = 0; h < sc->n_horizons && !near; h++) {
      double lo, hi, r = sc->horizons[h].radius;
      karst_i_surf_range_bound(&m->geo->horizon[h], x0, x1, y0, y1, &lo, &hi);
      near = !(zlo_e >= hi + r || zhi_e <= lo - r); /* NAN (undefined there): near, to be safe */
    }
    if (!near) return 1.0;
    double n = ceil(len / (KARST_COST_STEP_FRACTION * m->horizon_rmin));
    n = clampd(n, 1.0, KARST_COST_MAX_SUBINTERVALS);
    double sum = 0.0, h = 1.0 / n;
    for (double i = 0; i < n; i++)
      for (int q = 0; q < 3; q++) {
        double s = (i + GL3_X[q]) * h, p[3];
        for (int k = 0; k < 3; k++)
          p[k] = a[k] + s * (b[k] - a[k]);
        sum += GL3_W[q] * h * karst_geology_horizon_term(m->geo, p);
      }
    return sum;
  }
  double al[MAX_EXACT_HORIZONS], be[MAX_EXACT_HORIZONS], r[MAX_EXACT_HORIZONS];
  int n_active = 0;
  double rmin = INFINITY;
  /* Along the segment the vertical offset to a planar horizon is linear in s:
   * u_h(s) = α_h + β_h s. Horizons whose zone |u| < r is never reached
   * contribute g = 1 and can be ignored inside the minimum. */
  for (int h = 0; h < sc->n_horizons; h++) {
    const karst_horizon_t *H = &sc->horizons[h];
    double ua = a[2] - plane_elevation(m, h, a[0], a[1]);
    double ub = b[2] - plane_elevation(m, h, b[0], b[1]);
    int touches = (ua <= 0 && ub >= 0) || (ua >= 0 && ub <= 0) ||
                  karst_i_fmin(fabs(ua), fabs(ub)) < H->radius;
    if (!touches) continue;
    rmin = karst_i_fmin(rmin, H->radius);
    if (n_active < MAX_EXACT_HORIZONS)
      al[n_active] = ua, be[n_active] = ub - ua, r[n_active] = H->radius;
    n_active++;
  }
  if (n_active == 0) return 1.0;
  if (n_active > MAX_EXACT_HORIZONS) {
    /* Rare fallback: composite 2-point Gauss–Legendre, exact on the cubic
     * pieces of g and O(h^2) at each kink of the minimum. */
    double n = ceil(len / (KARST_COST_STEP_FRACTION * rmin));
    n = clampd(n, 1.0, KARST_COST_MAX_SUBINTERVALS);
    double sum = 0.0, h = 1.0 / n;
    for (double i = 0; i < n; i++)
      for (int q = 0; q < 2; q++) {
        double s = (i + GL2_X[q]) * h, p[3];
        for (int k = 0; k < 3; k++)
          p[k] = a[k] + s * (b[k] - a[k]);
        sum += 0.5 * h * karst_geology_horizon_term(m->geo, p);
      }
    return sum;
  }
  /* Exact: X(s) = min_h |u_h(s)| / r_h is piecewise linear with kinks where
   * some u_h = 0 or |u_h| = r_h, or where two scaled offsets are equal; on
   * each piece g(min(X, 1)) is a cubic of a linear function, integrated in
   * closed form by mean_g_linear. */
  double br[MAX_BREAKS + 1];
  int nb = 0;
  br[nb++] = 0.0;
  for (int i = 0; i < n_active; i++) {
    if (be[i] != 0.0) {
      push_break(br, &nb, -al[i] / be[i]);
      push_break(br, &nb, (r[i] - al[i]) / be[i]);
      push_break(br, &nb, (-r[i] - al[i]) / be[i]);
    }
    for (int j = i + 1; j < n_active; j++)
      for (int sg = -1; sg <= 1; sg += 2) {
        double den = be[i] / r[i] - sg * be[j] / r[j];
        if (den != 0.0) push_break(br, &nb, (sg * al[j] / r[j] - al[i] / r[i]) / den);
      }
  }
  sort_small(br, nb);
  br[nb] = 1.0; /* 1 + A^2 + 2A <= 64 = MAX_BREAKS break points: none was dropped */
  double sum = 0.0, xprev = INFINITY;
  for (int i = 0; i < n_active; i++)
    xprev = karst_i_fmin(xprev, fabs(al[i]) / r[i]);
  for (int p = 0; p < nb; p++) {
    double s1 = br[p + 1], x1 = INFINITY;
    for (int i = 0; i < n_active; i++)
      x1 = karst_i_fmin(x1, fabs(al[i] + be[i] * s1) / r[i]);
    sum += (s1 - br[p]) * mean_g_linear(xprev, x1);
    xprev = x1;
  }
  return sum;
}

/* Whether the permeability tree is constant along [a, b] (conservative:
 * 0 may be returned for a constant node, never 1 for a varying one). */
static int perm_constant(const karst_perm_node_t *n, const double a[3], const double b[3]) {
  switch (n->kind) {
  case KARST_PERM_SPHERE: {
    double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double ac[3] = {a[0] - n->center[0], a[1] - n->center[1], a[2] - n->center[2]};
    double bc[3] = {b[0] - n->center[0], b[1] - n->center[1], b[2] - n->center[2]};
    double dd = dot3(d, d), s = dd > 0 ? clampd(-dot3(ac, d) / dd, 0.0, 1.0) : 0.0;
    double c[3] = {ac[0] + s * d[0], ac[1] + s * d[1], ac[2] + s * d[2]};
    double dmin = sqrt(dot3(c, c)), dmax = karst_i_fmax(sqrt(dot3(ac, ac)), sqrt(dot3(bc, bc)));
    if (dmax <= n->radius) return 1; /* entirely inside: resistance */
    if (n->falloff > 0) return dmin >= n->radius + n->falloff;
    return dmin > n->radius; /* entirely outside: background */
  }
  case KARST_PERM_STRATUM: {
    int ina = a[2] >= n->bottom && a[2] <= n->top, inb = b[2] >= n->bottom && b[2] <= n->top;
    if (ina && inb) return 1;
    return (a[2] < n->bottom && b[2] < n->bottom) || (a[2] > n->top && b[2] > n->top);
  }
  default:
    for (int i = 0; i < n->n_children; i++)
      if (!perm_constant(&n->children[i], a, b)) return 0;
    return 1;
  }
}

/* Parameters in (0, 1) where a primitive of the tree has a kink or a jump. */
static void perm_breaks(const karst_perm_node_t *n, const double a[3], const double b[3],
                        double *br, int *nb) {
  if (n->kind == KARST_PERM_SPHERE) {
    double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double ac[3] = {a[0] - n->center[0], a[1] - n->center[1], a[2] - n->center[2]};
    double A = dot3(d, d), B = 2 * dot3(d, ac);
    if (A <= 0) return;
    for (int q = 0; q < 2; q++) {
      double rho = n->radius + (q ? n->falloff : 0.0);
      if (q && !(n->falloff > 0)) break;
      double C = dot3(ac, ac) - rho * rho, disc = B * B - 4 * A * C;
      if (disc < 0) continue;
      double sq = sqrt(disc);
      push_break(br, nb, (-B - sq) / (2 * A));
      push_break(br, nb, (-B + sq) / (2 * A));
    }
  } else if (n->kind == KARST_PERM_STRATUM) {
    double dz = b[2] - a[2];
    if (dz != 0) {
      push_break(br, nb, (n->bottom - a[2]) / dz);
      push_break(br, nb, (n->top - a[2]) / dz);
    }
  } else {
    for (int i = 0; i < n->n_children; i++)
      perm_breaks(&n->children[i], a, b, br, nb);
  }
}

/* Whether the bounding box of [a, b] misses every primitive's support box:
 * then every primitive gives the background all along the edge, and so does
 * the tree (a cheap test that spares perm_constant for most edges). */
static int misses_perm_boxes(const karst_i_cost_model_t *m, const double a[3], const double b[3]) {
  if (m->n_perm_boxes < 0) return 0;
  double lo[3], hi[3]; /* the edge's box (finite coordinates: no fmin/fmax calls) */
  for (int i = 0; i < 3; i++)
    lo[i] = a[i] < b[i] ? a[i] : b[i], hi[i] = a[i] < b[i] ? b[i] : a[i];
  for (int i = 0; i < m->n_perm_boxes; i++) {
    const double *B = m->perm_boxes + 6 * i;
    if (lo[0] <= B[3] && hi[0] >= B[0] && lo[1] <= B[4] && hi[1] >= B[1] && lo[2] <= B[5] &&
        hi[2] >= B[2])
      return 0;
  }
  return 1;
}

/* ∫_0^1 π(a + s(b − a)) ds: exact where π is constant along the edge; else
 * composite 3-point Gauss–Legendre on the pieces between the kinks and jumps
 * of the primitives (sphere radius and radius + falloff, stratum bounds), with
 * sub-intervals no longer than m->perm_step metres. Inside a piece the
 * integrand is smooth, and the 3-point rule errs by h^7 f^(6)(ξ) / 2016000 per
 * sub-interval of length h; with h = KARST_COST_STEP_FRACTION times the
 * feature size that is below 1e-6 relative for a smooth-step falloff. The
 * remaining non-smooth points are where union/intersection children cross
 * (a kink: O(h^3) per crossing). */
static double perm_integral(const karst_i_cost_model_t *m, const double a[3], const double b[3],
                            double len) {
  const karst_permeability_t *perm = &m->sc->permeability;
  if (!perm->root) return perm->background;
  if (misses_perm_boxes(m, a, b)) return m->perm_far;
  if (perm_constant(perm->root, a, b)) return karst_permeability_eval(perm, a);
  double br[MAX_BREAKS + 1];
  int nb = 0;
  br[nb++] = 0.0;
  perm_breaks(perm->root, a, b, br, &nb);
  sort_small(br, nb);
  br[nb] = 1.0;
  double sum = 0.0;
  for (int p = 0; p < nb; p++) {
    double s0 = br[p], w = br[p + 1] - s0;
    if (!(w > 0)) continue;
    double n = ceil(w * len / m->perm_step);
    n = clampd(n, 1.0, KARST_COST_MAX_SUBINTERVALS);
    double h = w / n;
    for (double i = 0; i < n; i++)
      for (int q = 0; q < 3; q++) {
        double s = s0 + (i + GL3_X[q]) * h, x[3];
        for (int k = 0; k < 3; k++)
          x[k] = a[k] + s * (b[k] - a[k]);
        sum += GL3_W[q] * h * karst_permeability_eval(perm, x);
      }
  }
  return sum;
}

/* Distance from p to the segment [a, b]. */
static double point_segment_distance(const double p[3], const double a[3], const double b[3]) {
  double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  double ap[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
  double dd = dot3(d, d), s = dd > 0 ? clampd(dot3(ap, d) / dd, 0.0, 1.0) : 0.0;
  double e[3] = {ap[0] - s * d[0], ap[1] - s * d[1], ap[2] - s * d[2]};
  return sqrt(dot3(e, e));
}

static int on_prescribed_path(const karst_i_cost_model_t *m, const double a[3], const double b[3],
                              double len) {
  const karst_scenario_t *sc = m->sc;
  double tol = sc->sampling.feature_radius;
  for (int i = 0; i < sc->n_prescribed; i++) {
    int ka = sc->prescribed[i].a, kb = sc->prescribed[i].b;
    if (ka < 0 || kb < 0 || ka >= sc->n_key_points || kb >= sc->n_key_points) continue;
    const double *P = sc->key_points[ka].p, *Q = sc->key_points[kb].p;
    double pq[3] = {Q[0] - P[0], Q[1] - P[1], Q[2] - P[2]},
           ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double lpq = sqrt(dot3(pq, pq));
    if (lpq == 0 || len == 0) continue;
    if (fabs(dot3(pq, ab)) < m->prescribed_cos * lpq * len) continue;
    if (point_segment_distance(a, P, Q) <= tol && point_segment_distance(b, P, Q) <= tol) return 1;
  }
  return 0;
}

/* The support boxes of the permeability primitives: a sphere returns the
 * background from radius + falloff on (the smooth step is 1 there), a
 * stratum outside [bottom, top]. Unknown node kinds or a tree deeper than
 * the walk's stack leave n_perm_boxes = -1 (no shortcut). */
static karst_error_t perm_support_boxes(karst_ctx_t *ctx, karst_i_cost_model_t *m) {
  const karst_perm_node_t *root = m->sc->permeability.root;
  if (!root) return KARST_SUCCESS;
  const karst_perm_node_t *stack[64];
  int top = 0, n = 0, cap = 0;
  stack[top++] = root;
  while (top > 0) {
    const karst_perm_node_t *nd = stack[--top];
    double B[6] = {-INFINITY, -INFINITY, -INFINITY, INFINITY, INFINITY, INFINITY};
    if (nd->kind == KARST_PERM_SPHERE) {
      double r = nd->radius + (nd->falloff > 0 ? nd->falloff : 0.0);
      for (int a = 0; a < 3; a++)
        B[a] = nd->center[a] - r, B[3 + a] = nd->center[a] + r;
    } else if (nd->kind == KARST_PERM_STRATUM) {
      B[2] = nd->bottom, B[5] = nd->top;
    } else if (nd->kind == KARST_PERM_UNION || nd->kind == KARST_PERM_INTERSECTION ||
               nd->kind == KARST_PERM_BLEND) {
      for (int i = 0; i < nd->n_children; i++) {
        if (top == 64) goto unknown;
        stack[top++] = &nd->children[i];
      }
      continue;
    } else {
      goto unknown;
    }
    for (int a = 0; a < 6; a++)
      if (isnan(B[a])) goto unknown;
    if (n == cap) {
      cap = cap ? 2 * cap : 8;
      double *nb = realloc(m->perm_boxes, sizeof(double) * 6 * (size_t)cap);
      if (!nb) return karst_set_error(ctx, KARST_ENOMEM, "no memory for the permeability boxes");
      m->perm_boxes = nb;
    }
    memcpy(m->perm_boxes + 6 * n++, B, sizeof B);
  }
  /* Every box is bounded in z: above all of them each primitive returns the
   * background, as it does all along an edge missing the boxes, and the
   * tree combines the same values the same way there. */
  double far[3] = {0.0, 0.0, -INFINITY};
  for (int i = 0; i < n; i++)
    far[2] = karst_i_fmax(far[2], m->perm_boxes[6 * i + 5]);
  far[2] = n > 0 ? far[2] + 1.0 + fabs(far[2]) : 0.0; /* strictly above */
  if (!isfinite(far[2])) goto unknown;
  m->perm_far = karst_permeability_eval(&m->sc->permeability, far);
  m->n_perm_boxes = n;
  return KARST_SUCCESS;
unknown:
  m->n_perm_boxes = -1;
  return KARST_SUCCESS;
}

karst_error_t karst_i_cost_model_init(karst_ctx_t *ctx, karst_i_cost_model_t *m,
                                      const karst_geology_t *geo) {
  const karst_scenario_t *sc = geo->sc;
  m->geo = geo;
  m->sc = sc;
  m->perm_boxes = NULL;
  m->n_perm_boxes = -1;
  m->prescribed_cos = cos(KARST_COST_PRESCRIBED_MAX_ANGLE * M_PI / 180.0);
  m->horizons_planar = 1;
  m->horizon_rmin = INFINITY;
  for (int h = 0; h < sc->n_horizons; h++) {
    m->horizons_planar &= geo->horizon[h].kind == KARST_I_SURF_PLANE;
    m->horizon_rmin = karst_i_fmin(m->horizon_rmin, sc->horizons[h].radius);
  }
  m->n_dfn = 0;
  for (int k = 0; k < sc->n_fractures; k++)
    m->n_dfn += sc->fractures[k].dfn;
  /* Smallest permeability feature, for the quadrature step. */
  double fmin_size = INFINITY;
  const karst_perm_node_t *stack[64];
  int top = 0;
  if (sc->permeability.root) stack[top++] = sc->permeability.root;
  while (top > 0) {
    const karst_perm_node_t *n = stack[--top];
    if (n->kind == KARST_PERM_SPHERE) {
      if (n->radius > 0) fmin_size = karst_i_fmin(fmin_size, n->radius);
      if (n->falloff > 0) fmin_size = karst_i_fmin(fmin_size, n->falloff);
    } else if (n->kind == KARST_PERM_STRATUM) {
      if (n->top > n->bottom) fmin_size = karst_i_fmin(fmin_size, n->top - n->bottom);
    }
    for (int i = 0; i < n->n_children; i++) {
      if (top < 64)
        stack[top++] = &n->children[i];
      else
        fmin_size = karst_i_fmin(
            fmin_size, sc->sampling.feature_radius); /* tree too large to walk here: be cautious */
    }
  }
  m->perm_step = KARST_COST_STEP_FRACTION * fmin_size;
  if (!(m->perm_step > 0)) m->perm_step = INFINITY;
  karst_error_t err = perm_support_boxes(ctx, m);
  if (err != KARST_SUCCESS) karst_i_cost_model_destroy(m);
  return err;
}

void karst_i_cost_model_destroy(karst_i_cost_model_t *m) {
  free(m->perm_boxes);
  m->perm_boxes = NULL;
  m->n_perm_boxes = -1;
}

double karst_i_cost_edge(const karst_i_cost_model_t *m, const double a[3], const double b[3]) {
  if (!karst_geology_in_bedrock(m->geo, a) || !karst_geology_in_bedrock(m->geo, b)) return INFINITY;
  return karst_i_cost_edge_inside(m, a, b);
}

/* The factor a plane of unit normal n gives an edge of direction d (|d| = len) that runs in it:
 * f along the plane, 1 across it, f + (1 − f)(n·d̂)² between (the form of the fracture term). */
static double plane_factor(double f, const double n[3], const double d[3], double len) {
  double nd = dot3(n, d) / len;
  return f + (1.0 - f) * nd * nd;
}

typedef struct {
  const karst_scenario_t *sc;
  const double *a, *b, *d;
  double len, best;
} disc_query_t;

/* An edge lies in a disc of a fracture network when both its ends are within the family's
 * influence distance of the disc's plane and its midpoint projects inside the disc. */
static int disc_visit(const karst_disc_t *dc, void *arg) {
  disc_query_t *q = arg;
  const karst_fracture_t *fr = &q->sc->fractures[dc->family];
  double ea = 0, eb = 0, m[3];
  for (int k = 0; k < 3; k++) {
    ea += dc->n[k] * (q->a[k] - dc->c[k]);
    eb += dc->n[k] * (q->b[k] - dc->c[k]);
    m[k] = 0.5 * (q->a[k] + q->b[k]) - dc->c[k];
  }
  if (!(fabs(ea) <= fr->influence && fabs(eb) <= fr->influence)) return 0;
  double h = dot3(dc->n, m), r2 = dot3(m, m) - h * h;
  if (!(r2 <= dc->r * dc->r)) return 0;
  double f = plane_factor(fr->factor, dc->n, q->d, q->len);
  if (f < q->best) q->best = f;
  return 0;
}

/* The cost factor of the faults on edge [a, b] (conduits), and the crossing costs added
 * (barriers). A conduit fault's damage zone is the slab |n·(p − c)| <= w/2 within the disc
 * radius (measured at the middle of the edge's part inside the slab): the part of the edge inside
 * it, a fraction φ, costs plane_factor times its cost, so the edge's factor is 1 − φ (1 − f).
 * A barrier adds crossing_cost when the edge crosses the plane (its ends on opposite sides, or
 * one on it) within the radius. */
static void fault_terms(const karst_i_cost_model_t *m, const double a[3], const double b[3],
                        const double d[3], double len, double *factor, double *added) {
  const karst_scenario_t *sc = m->sc;
  *factor = 1.0, *added = 0.0;
  for (int i = 0; i < sc->n_faults; i++) {
    const karst_fault_t *F = &sc->faults[i];
    const double *n = m->geo->fault_normal + 3 * i;
    double ea = 0, eb = 0;
    for (int k = 0; k < 3; k++)
      ea += n[k] * (a[k] - F->center[k]), eb += n[k] * (b[k] - F->center[k]);
    if (F->barrier) {
      if ((ea > 0 && eb > 0) || (ea < 0 && eb < 0) || (ea == 0 && eb == 0)) continue;
      double t = ea == eb ? 0.0 : ea / (ea - eb), x[3];
      for (int k = 0; k < 3; k++)
        x[k] = a[k] + t * d[k] - F->center[k];
      if (isfinite(F->radius) && !(dot3(x, x) <= F->radius * F->radius)) continue;
      *added += F->crossing_cost;
      continue;
    }
    double hw = 0.5 * F->damage_zone, t0 = 0.0, t1 = 1.0;
    if (ea == eb) {
      if (fabs(ea) > hw) continue;
    } else {
      double u = (-hw - ea) / (eb - ea), v = (hw - ea) / (eb - ea);
      if (u > v) {
        double w = u;
        u = v, v = w;
      }
      t0 = karst_i_fmax(t0, u), t1 = karst_i_fmin(t1, v);
      if (!(t1 > t0)) continue;
    }
    if (isfinite(F->radius)) {
      double tm = 0.5 * (t0 + t1), x[3];
      for (int k = 0; k < 3; k++)
        x[k] = a[k] + tm * d[k] - F->center[k];
      double h = dot3(n, x);
      if (!(dot3(x, x) - h * h <= F->radius * F->radius)) continue;
    }
    double f = plane_factor(F->factor, n, d, len);
    *factor = karst_i_fmin(*factor, 1.0 - (t1 - t0) * (1.0 - f));
  }
}

double karst_i_cost_edge_inside(const karst_i_cost_model_t *m, const double a[3],
                                const double b[3]) {
  const karst_scenario_t *sc = m->sc;
  if (!karst_i_geology_segment_between(m->geo, a, b)) return INFINITY;
  double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  double len = sqrt(dot3(d, d));
  if (len == 0.0) return 0.0;
  const karst_cost_weights_t *w = &sc->cost;
  double per_metre = w->w0;
  if (w->fracture != 0) per_metre += w->fracture * fracture_term(m->geo, d);
  if (w->horizon != 0) per_metre += w->horizon * horizon_integral(m, a, b, len);
  if (w->permeability != 0) per_metre += w->permeability * perm_integral(m, a, b, len);
  double c = len * per_metre, factor = 1.0, added = 0.0;
  if (m->n_dfn > 0) {
    double mid[3] = {0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])};
    disc_query_t q = {sc, a, b, d, len, 1.0};
    karst_i_geology_discs_at(m->geo, mid, disc_visit, &q);
    factor = q.best;
  }
  if (sc->n_faults > 0) {
    double f;
    fault_terms(m, a, b, d, len, &f, &added);
    factor = karst_i_fmin(factor, f); /* the smallest factor applies (see the lower bound) */
  }
  c = c * factor + added;
  if (sc->n_prescribed > 0 && on_prescribed_path(m, a, b, len)) c *= w->prescribed;
  return c;
}

/**
 * Cost of the straight edge [a, b]: the line integral ∫ c(p(t), d) dt of the
 * cost per metre along the segment (Paris et al. 2021, §4, the functional χ
 * restricted to one segment); times the factor of the fracture disc it lies in
 * (the smallest, docs/generation.md) and of the conduit faults whose damage
 * zone it runs through, plus the crossing cost of the barrier faults it
 * crosses; times cost.prescribed when the edge lies on a prescribed path (both
 * ends within sampling.feature_radius of the key-point pair's segment and at
 * most KARST_COST_PRESCRIBED_MAX_ANGLE degrees from it). The fracture term
 * depends on the direction only and is exact. The horizon term is integrated
 * exactly for planar horizons (piecewise closed form of the smooth step, see
 * horizon_integral) and by composite 3-point Gauss–Legendre for folded ones.
 * The permeability term is exact where π is constant along the edge and
 * otherwise uses composite Gauss–Legendre with sub-intervals of at most
 * KARST_COST_STEP_FRACTION times the smallest permeability feature, split at
 * the primitives' kinks (see perm_integral).
 * @param g the geology; @param a, b the end points.
 * @return the cost (>= 0), INFINITY when the segment leaves the bedrock or a
 *         coordinate is not finite.
 * Time complexity: O(horizons^2 + fractures + faults + discs near the edge +
 * tree size × quadrature points).
 */
double karst_cost_edge(const karst_geology_t *g, const double a[3], const double b[3]) {
  karst_i_cost_model_t m;
  if (karst_i_cost_model_init(NULL, &m, g) != KARST_SUCCESS) return NAN;
  double c = karst_i_cost_edge(&m, a, b);
  karst_i_cost_model_destroy(&m);
  return c;
}

/* Smallest eigenvalue of a symmetric 3x3 matrix by cyclic Jacobi rotations
 * (Golub & Van Loan, §8.5): unconditionally convergent, and accurate to a
 * few ulps of the matrix norm, unlike the closed-form cubic roots whose
 * acos loses accuracy near repeated eigenvalues. */
static double sym3_min_eigenvalue(double A[3][3]) {
  for (int sweep = 0; sweep < 50; sweep++) {
    double off = A[0][1] * A[0][1] + A[0][2] * A[0][2] + A[1][2] * A[1][2];
    if (off == 0.0) break;
    for (int p = 0; p < 2; p++)
      for (int q = p + 1; q < 3; q++) {
        if (A[p][q] == 0.0) continue;
        double theta = (A[q][q] - A[p][p]) / (2 * A[p][q]);
        double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1));
        double c = 1 / sqrt(t * t + 1), s = t * c;
        for (int k = 0; k < 3; k++) { /* A <- J^T A J, rotation in the (p, q) plane */
          double akp = A[k][p], akq = A[k][q];
          A[k][p] = c * akp - s * akq;
          A[k][q] = s * akp + c * akq;
        }
        for (int k = 0; k < 3; k++) {
          double apk = A[p][k], aqk = A[q][k];
          A[p][k] = c * apk - s * aqk;
          A[q][k] = s * apk + c * aqk;
        }
        A[p][q] = A[q][p] = 0.0;
      }
  }
  return karst_i_fmin(A[0][0], karst_i_fmin(A[1][1], A[2][2]));
}

/**
 * A lower bound L of the cost per metre, valid for every point and direction,
 * so that |a − b| · L never overestimates the least cost between a and b (an
 * admissible, consistent A* heuristic, Hart, Nilsson & Raphael 1968).
 *
 * Proof. c(p, d) = w0 + wL cL(p) + wF cF(d) + wπ π(p) with all weights >= 0.
 * (i) cL = g(·) >= 0 since g >= 0 on [0, 1] and g = 1 beyond; without horizons
 * cL = 1. (ii) For unit d, cF(d) = Σ w_k dᵀ T_k d = dᵀ M d with
 * M = Σ w_k T_k (T_k = E[n nᵀ] of family k, n_k n_kᵀ without dispersion), and
 * dᵀ M d >= λmin(M) by the Rayleigh quotient, attained by the eigenvector of
 * λmin. With cost.fracture_combine = min, cF(d) = min_k [W − w_k + w_k dᵀT_k d]
 * >= min_k [W − w_k + w_k λmin(T_k)] >= 0 (W = max w_k), where T_k has the
 * eigenvalues c_k along its pole and (1 − c_k)/2 across it
 * (karst_i_fisher_tensor), so λmin(T_k) = min(c_k, (1 − c_k)/2): 0 without
 * dispersion, which makes the bound 0 in the plane of the heaviest family.
 * (iii) π is clamped to [0, 1]; every node returns a leaf resistance, the
 * background, a smooth-step mix of the two, their min, max or a weighted
 * mean, so π >= πmin = min(background, leaf resistances). Hence c(p, d) >=
 * w0 + wL·[no horizon] + wF cFmin + wπ πmin. An edge's cost is a
 * quadrature of c with positive weights summing to its length (or exact),
 * so it is >= length × that bound. (iv) The edge factors: a fracture disc's
 * f + (1 − f)(n·d̂)² >= f, a conduit fault's 1 − φ (1 − f_eff) >= f_eff >= f
 * (φ in [0, 1]), a barrier only adds; the factors of several faults are not
 * multiplied (the smallest applies), so the edge is >= length × bound × fmin,
 * fmin the smallest disc or fault factor. A prescribed edge multiplies by
 * cost.prescribed, hence the factor min(1, prescribed) when prescribed paths
 * exist. The routing factors of the vadose and phreatic stages are >= 1
 * (docs/generation.md), so the bound holds for them too. The result is
 * reduced by the relative KARST_COST_LB_MARGIN so that rounding (Jacobi error
 * ~1e-15 ‖M‖, summation of edge costs) cannot break it.
 * @param sc the scenario.
 * @return the bound (>= 0).
 * Time complexity: O(fractures + faults + tree size).
 */
double karst_cost_lower_bound_per_metre(const karst_scenario_t *sc) {
  const karst_cost_weights_t *w = &sc->cost;
  double M[3][3] = {{0}}, W = 0.0;
  for (int k = 0; k < sc->n_fractures; k++)
    W = karst_i_fmax(W, sc->fractures[k].weight);
  double cf_min = sc->n_fractures > 0 ? W : 0.0;
  for (int k = 0; k < sc->n_fractures; k++) {
    double n[3], T[9], wk = sc->fractures[k].weight;
    karst_plane_normal(sc->fractures[k].dip_direction, sc->fractures[k].dip, n);
    karst_i_fisher_tensor(n, sc->fractures[k].kappa, T);
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++)
        M[i][j] += wk * T[3 * i + j];
    double c = T[0] * n[0] * n[0] + T[4] * n[1] * n[1] + T[8] * n[2] * n[2] +
               2 * (T[1] * n[0] * n[1] + T[2] * n[0] * n[2] + T[5] * n[1] * n[2]);
    double lam = karst_i_fmax(0.0, karst_i_fmin(c, 0.5 * (1.0 - c)));
    cf_min = karst_i_fmin(cf_min, W - wk + wk * lam);
  }
  if (sc->cost.fracture_combine != KARST_FRACTURE_MIN)
    cf_min = sc->n_fractures > 0 ? karst_i_fmax(0.0, sym3_min_eigenvalue(M)) : 0.0;
  cf_min = karst_i_fmax(0.0, cf_min);
  double pi_min = sc->permeability.background;
  const karst_perm_node_t *stack[64];
  int top = 0;
  if (sc->permeability.root) stack[top++] = sc->permeability.root;
  while (top > 0) {
    const karst_perm_node_t *n = stack[--top];
    if (n->kind == KARST_PERM_SPHERE || n->kind == KARST_PERM_STRATUM)
      pi_min = karst_i_fmin(pi_min, n->resistance);
    for (int i = 0; i < n->n_children; i++) {
      if (top < 64)
        stack[top++] = &n->children[i];
      else
        pi_min = 0.0; /* tree too large to walk here: 0 is always safe */
    }
  }
  pi_min = clampd(pi_min, 0.0, 1.0);
  double lb = w->w0 + w->horizon * (sc->n_horizons == 0 ? 1.0 : 0.0) + w->fracture * cf_min +
              w->permeability * pi_min;
  double fmin_edge = 1.0;
  for (int k = 0; k < sc->n_fractures; k++)
    if (sc->fractures[k].dfn) fmin_edge = karst_i_fmin(fmin_edge, sc->fractures[k].factor);
  for (int i = 0; i < sc->n_faults; i++)
    if (!sc->faults[i].barrier) fmin_edge = karst_i_fmin(fmin_edge, sc->faults[i].factor);
  lb *= clampd(fmin_edge, 0.0, 1.0);
  if (sc->n_prescribed > 0 && w->prescribed < 1.0) lb *= w->prescribed;
  lb *= 1.0 - KARST_COST_LB_MARGIN;
  return lb > 0 ? lb : 0.0;
}
