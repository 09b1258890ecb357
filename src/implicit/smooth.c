/* The nodes the rock blocks of Paris et al. 2020 (§4.2) are made of: half-
 * spaces, their smooth intersection, the thick point / segment / polygon of
 * degenerate clusters, and the external field through which src/blocks/
 * plugs its replication operator into a tree. Conventions (negative inside,
 * 1-Lipschitz, clamped by the box) are in include/karst/implicit.h.
 *
 * The smooth intersection, and why its sign differs from the paper's text.
 * Paris et al. 2020 (§4.2) write f = max(a, b) - R k³/6 with
 * k = max(1 - |a - b|/R, 0), the cubic smooth minimum of Quilez with max in
 * place of min. With half-spaces negative inside (their h_k) that operator
 * is not 1-Lipschitz and does not round edges: for a >= b its gradient is
 * (1 + k²/2) ∇a - (k²/2) ∇b, of norm up to 1 + k² for opposite gradients (2
 * where a = b), and it lowers the field at an edge, i.e. adds rock beyond
 * it. The operator that makes the rounded edges of their Fig. 8 in a
 * negative-inside tree is its mirror -smin_R(-a, -b):
 *     smax_R(a, b) = max(a, b) + R k³/6.
 * Proof that it is 1-Lipschitz and C¹. Let a >= b, δ = a - b. For δ >= R it
 * is a, gradient ∇a. For 0 <= δ < R, k = 1 - δ/R, ∂k/∂a = -1/R, ∂k/∂b = 1/R,
 *     ∇f = ∇a + (R/6) 3k² (∇b - ∇a)/R = (1 - k²/2) ∇a + (k²/2) ∇b,
 * and since 0 <= k²/2 <= 1/2 this is a convex combination of ∇a and ∇b:
 * |∇f| <= max(|∇a|, |∇b|) <= 1 (for Lipschitz fields, the same argument on
 * the difference quotients along any segment). The weights are continuous:
 * at δ = R, k = 0 gives ∇a (matching max), at δ = 0 both orderings give
 * (∇a + ∇b)/2. Hence f is C¹ wherever a and b are, and
 * max(a, b) <= f <= max(a, b) + R/6.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "implicit/implicit_internal.h"

static double dot3(const double *a, const double *b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static void cross3(const double *a, const double *b, double *c) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}
static int finite3(const double *p) {
  return isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]);
}

/**
 * Smooth maximum smax_R(a, b) = max(a, b) + R k³/6, k = max(1 - |a - b|/R, 0)
 * (Paris et al. 2020, §4.2, in the negative-inside convention; see the top
 * of this file for the sign and the proof that it is 1-Lipschitz and C¹).
 * @param R blend radius >= 0 (m); 0 gives max(a, b). Time complexity: O(1).
 */
double karst_sdf_smooth_max(double a, double b, double R) {
  double m = a > b ? a : b;
  if (!(R > 0)) return m;
  double k = 1.0 - fabs(a - b) / R;
  return k > 0 ? m + R * k * k * k / 6.0 : m;
}

/**
 * Half-space primitive: h(p) = u.(p - o), u the outward normal made unit
 * here (Paris et al. 2020, §4.2, h_k). Exact signed distance to the plane.
 * @return KARST_SUCCESS, KARST_EINVAL (non-finite, zero normal), KARST_ENOMEM.
 * Time complexity: O(1) amortised.
 */
karst_error_t karst_sdf_plane(karst_ctx_t *ctx, karst_sdf_t *t, const double o[3],
                              const double u[3], karst_int_t *node) {
  if (!finite3(o) || !finite3(u))
    return karst_set_error(ctx, KARST_EINVAL, "plane: point or normal is not finite");
  double n = sqrt(dot3(u, u));
  if (!(n > 0) || !isfinite(n))
    return karst_set_error(ctx, KARST_EINVAL, "plane: normal (%g, %g, %g) has no direction", u[0],
                           u[1], u[2]);
  karst_i_node_t *nd = NULL;
  karst_error_t err = karst_i_sdf_new_node(ctx, t, KARST_SDF_PLANE, &nd, node);
  if (err) return err;
  for (int i = 0; i < 3; i++)
    nd->u.plane.u[i] = u[i] / n;
  nd->u.plane.d = dot3(nd->u.plane.u, o);
  nd->finite = 0;
  return KARST_SUCCESS;
}

/**
 * Smooth intersection of @p n children folded from the left (Paris et al.
 * 2020, §4.2), see implicit.h.
 * @param R blend radius >= 0 (m), finite
 * @param box caller's box containing the solid, or NULL
 * @return KARST_SUCCESS, KARST_EINVAL (no children, unknown child, bad R or
 *         box), KARST_ENOMEM; the tree is unchanged on failure.
 * Time complexity: O(n) amortised.
 */
karst_error_t karst_sdf_smooth_intersection(karst_ctx_t *ctx, karst_sdf_t *t, karst_int_t n,
                                            const karst_int_t *children, double R,
                                            const double box[6], karst_int_t *node) {
  if (n < 1 || !children)
    return karst_set_error(ctx, KARST_EINVAL, "smooth intersection: needs at least one child");
  if (!(R >= 0) || !isfinite(R))
    return karst_set_error(ctx, KARST_EINVAL,
                           "smooth intersection: radius %g must be >= 0 and finite", R);
  for (karst_int_t i = 0; i < n; i++)
    if (children[i] < 0 || children[i] >= t->n_nodes)
      return karst_set_error(ctx, KARST_EINVAL,
                             "smooth intersection: child %lld is node %lld, which does not exist",
                             (long long)i, (long long)children[i]);
  if (box)
    for (int a = 0; a < 3; a++)
      if (!isfinite(box[a]) || !isfinite(box[a + 3]) || !(box[a] <= box[a + 3]))
        return karst_set_error(ctx, KARST_EINVAL,
                               "smooth intersection: box axis %d is [%g, %g], not a finite range",
                               a, box[a], box[a + 3]);
  if (karst_i_grow((void **)&t->kids, &t->cap_kids, t->n_kids + n, sizeof *t->kids))
    return karst_set_error(ctx, KARST_ENOMEM, "smooth intersection: out of memory");
  karst_int_t first = t->n_kids;
  memcpy(t->kids + first, children, (size_t)n * sizeof *children);
  double b[6] = {-INFINITY, -INFINITY, -INFINITY, INFINITY, INFINITY, INFINITY};
  int finite = 0;
  for (karst_int_t i = 0; i < n; i++) {
    const karst_i_node_t *c = &t->nodes[children[i]];
    if (!c->finite) continue;
    finite = 1;
    for (int a = 0; a < 3; a++) {
      if (c->box[a] > b[a]) b[a] = c->box[a];
      if (c->box[a + 3] < b[a + 3]) b[a + 3] = c->box[a + 3];
    }
  }
  karst_i_node_t *nd = NULL;
  karst_error_t err = karst_i_sdf_new_node(ctx, t, KARST_SDF_SMOOTH_INTERSECTION, &nd, node);
  if (err) return err;
  t->n_kids += n;
  nd->u.sint.first = first;
  nd->u.sint.n = n;
  nd->u.sint.R = R;
  nd->label = t->nodes[children[0]].label;
  if (box) {
    memcpy(nd->box, box, sizeof nd->box);
    karst_i_pad_box(nd->box);
    nd->finite = 1;
  } else if (finite) {
    for (int a = 0; a < 3; a++)
      if (b[a] > b[a + 3]) b[a + 3] = b[a]; /* empty: a point */
    memcpy(nd->box, b, sizeof nd->box);
    nd->finite = 1;
  }
  return KARST_SUCCESS;
}

double karst_i_eval_smooth_intersection(const karst_sdf_t *t, const karst_i_node_t *nd,
                                        const double p[3], double ub, int *label,
                                        karst_int_t *touched) {
  /* The fold never decreases (smax >= max), so it may stop once at ub. Half-
   * spaces, the common children, are evaluated in place. */
  const karst_int_t *k = t->kids + nd->u.sint.first;
  double R = nd->u.sint.R, v = -INFINITY;
  int lab = nd->label;
  for (karst_int_t i = 0; i < nd->u.sint.n; i++) {
    const karst_i_node_t *c = &t->nodes[k[i]];
    double f;
    if (c->kind == KARST_SDF_PLANE) {
      f = dot3(c->u.plane.u, p) - c->u.plane.d;
    } else {
      int l;
      f = karst_i_sdf_eval(t, k[i], p, ub, &l, touched);
      if (i == 0) lab = l;
    }
    v = i == 0 ? f : karst_sdf_smooth_max(v, f, R);
    if (v >= ub) break;
  }
  *label = lab;
  return v;
}

/* Andrew's monotone chain on 2-D points (x, y pairs): the counter-clockwise
 * hull, written over the first *m pairs. */
static int cmp2(const void *pa, const void *pb) {
  const double *a = pa, *b = pb;
  if (a[0] != b[0]) return a[0] < b[0] ? -1 : 1;
  if (a[1] != b[1]) return a[1] < b[1] ? -1 : 1;
  return 0;
}
static double turn(const double *o, const double *a, const double *b) {
  return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}
static karst_int_t hull2(double *q, karst_int_t n, double *h) {
  qsort(q, (size_t)n, 2 * sizeof *q, cmp2);
  karst_int_t m = 0;
  for (karst_int_t i = 0; i < n; i++) {
    while (m >= 2 && turn(h + 2 * (m - 2), h + 2 * (m - 1), q + 2 * i) <= 0)
      m--;
    h[2 * m] = q[2 * i], h[2 * m + 1] = q[2 * i + 1], m++;
  }
  for (karst_int_t i = n - 2, lo = m + 1; i >= 0; i--) {
    while (m >= lo && turn(h + 2 * (m - 2), h + 2 * (m - 1), q + 2 * i) <= 0)
      m--;
    h[2 * m] = q[2 * i], h[2 * m + 1] = q[2 * i + 1], m++;
  }
  return m > 1 ? m - 1 : m; /* the last point repeats the first */
}

/**
 * Thick point, segment or convex polygon (Paris et al. 2020, §4.2): the
 * exact distance to the convex hull of @p n coplanar points minus @p radius.
 * @param xyz 3 n coordinates (finite), n >= 1
 * @param radius thickness > 0 (m); @param flat_tol the distance (m) under
 *        which points count as coincident, collinear or coplanar
 * @return KARST_SUCCESS, KARST_EINVAL (non-finite, bad radius, points not
 *         coplanar within flat_tol), KARST_ENOMEM.
 * Time complexity: O(n log n).
 */
karst_error_t karst_sdf_thick(karst_ctx_t *ctx, karst_sdf_t *t, karst_int_t n, const double *xyz,
                              double radius, double flat_tol, int label, karst_int_t *node) {
  karst_error_t err = KARST_SUCCESS;
  double *q = NULL;
  if (n < 1 || !xyz) return karst_set_error(ctx, KARST_EINVAL, "thick primitive: no points");
  if (!(radius > 0) || !isfinite(radius) || !(flat_tol >= 0) || !isfinite(flat_tol))
    return karst_set_error(ctx, KARST_EINVAL,
                           "thick primitive: radius %g must be > 0 and tolerance %g >= 0", radius,
                           flat_tol);
  for (karst_int_t i = 0; i < n; i++)
    if (!finite3(xyz + 3 * i))
      return karst_set_error(ctx, KARST_EINVAL, "thick primitive: point %lld is not finite",
                             (long long)i);
  /* p1 farthest from p0, p2 farthest from the line p0 p1 */
  const double *p0 = xyz;
  karst_int_t i1 = 0, i2 = 0;
  double d1 = 0, d2 = 0, e1[3] = {0}, nrm[3] = {0}, e2[3] = {0};
  for (karst_int_t i = 0; i < n; i++) {
    double v[3] = {xyz[3 * i] - p0[0], xyz[3 * i + 1] - p0[1], xyz[3 * i + 2] - p0[2]};
    double d = sqrt(dot3(v, v));
    if (d > d1) d1 = d, i1 = i;
  }
  int dim = d1 > flat_tol;
  if (dim) {
    for (int a = 0; a < 3; a++)
      e1[a] = (xyz[3 * i1 + a] - p0[a]) / d1;
    for (karst_int_t i = 0; i < n; i++) {
      double v[3] = {xyz[3 * i] - p0[0], xyz[3 * i + 1] - p0[1], xyz[3 * i + 2] - p0[2]}, c[3];
      cross3(e1, v, c);
      double d = sqrt(dot3(c, c));
      if (d > d2) d2 = d, i2 = i;
    }
    if (d2 > flat_tol) {
      dim = 2;
      double v[3] = {xyz[3 * i2] - p0[0], xyz[3 * i2 + 1] - p0[1], xyz[3 * i2 + 2] - p0[2]};
      cross3(e1, v, nrm);
      double l = sqrt(dot3(nrm, nrm));
      for (int a = 0; a < 3; a++)
        nrm[a] /= l;
      cross3(nrm, e1, e2);
      for (karst_int_t i = 0; i < n; i++) {
        double w[3] = {xyz[3 * i] - p0[0], xyz[3 * i + 1] - p0[1], xyz[3 * i + 2] - p0[2]};
        double h = dot3(w, nrm);
        if (!(fabs(h) <= flat_tol))
          return karst_set_error(ctx, KARST_EINVAL,
                                 "thick primitive: point %lld is %g m off the plane of the others "
                                 "(tolerance %g m); the points span a volume",
                                 (long long)i, h, flat_tol);
      }
    }
  }
  /* the stored points: dim 0 the centroid, dim 1 the two extreme points,
   * dim 2 the 2-D hull in the (e1, e2) frame */
  double pts[6];
  karst_int_t store = 0;
  if (dim == 0) {
    memset(pts, 0, sizeof pts);
    for (karst_int_t i = 0; i < n; i++)
      for (int a = 0; a < 3; a++)
        pts[a] += xyz[3 * i + a] / (double)n;
    store = 3;
  } else if (dim == 1) {
    double lo = INFINITY, hi = -INFINITY;
    for (karst_int_t i = 0; i < n; i++) {
      double w[3] = {xyz[3 * i] - p0[0], xyz[3 * i + 1] - p0[1], xyz[3 * i + 2] - p0[2]};
      double s = dot3(w, e1);
      if (s < lo) lo = s;
      if (s > hi) hi = s;
    }
    for (int a = 0; a < 3; a++)
      pts[a] = p0[a] + lo * e1[a], pts[3 + a] = p0[a] + hi * e1[a];
    store = 6;
  }
  karst_int_t m = 0;
  if (dim == 2) {
    q = malloc((size_t)(4 * n + 4) * sizeof *q);
    if (!q) return karst_set_error(ctx, KARST_ENOMEM, "thick primitive: out of memory");
    for (karst_int_t i = 0; i < n; i++) {
      double w[3] = {xyz[3 * i] - p0[0], xyz[3 * i + 1] - p0[1], xyz[3 * i + 2] - p0[2]};
      q[2 * i] = dot3(w, e1), q[2 * i + 1] = dot3(w, e2);
    }
    m = hull2(q, n, q + 2 * n);
    store = 2 * m;
  }
  if (karst_i_grow((void **)&t->coords, &t->cap_coords, t->n_coords + store, sizeof *t->coords)) {
    err = karst_set_error(ctx, KARST_ENOMEM, "thick primitive: out of memory");
    goto cleanup;
  }
  karst_int_t first = t->n_coords;
  memcpy(t->coords + first, dim == 2 ? q + 2 * n : pts, (size_t)store * sizeof *t->coords);
  karst_i_node_t *nd = NULL;
  if ((err = karst_i_sdf_new_node(ctx, t, KARST_SDF_THICK, &nd, node))) goto cleanup;
  t->n_coords += store;
  nd->u.thick.first = first;
  nd->u.thick.n = (int)(dim == 2 ? m : dim + 1);
  nd->u.thick.dim = dim;
  nd->u.thick.radius = radius;
  memcpy(nd->u.thick.o, p0, sizeof nd->u.thick.o);
  memcpy(nd->u.thick.e1, e1, sizeof e1);
  memcpy(nd->u.thick.e2, e2, sizeof e2);
  memcpy(nd->u.thick.nrm, nrm, sizeof nrm);
  nd->label = label;
  nd->finite = 1;
  for (int a = 0; a < 3; a++)
    nd->box[a] = INFINITY, nd->box[a + 3] = -INFINITY;
  for (karst_int_t i = 0; i < n; i++)
    for (int a = 0; a < 3; a++) {
      if (xyz[3 * i + a] - radius - flat_tol < nd->box[a])
        nd->box[a] = xyz[3 * i + a] - radius - flat_tol;
      if (xyz[3 * i + a] + radius + flat_tol > nd->box[a + 3])
        nd->box[a + 3] = xyz[3 * i + a] + radius + flat_tol;
    }
  karst_i_pad_box(nd->box);
cleanup:
  free(q);
  return err;
}

/* Distance from q to the segment a b (3-D). */
static double seg_dist(const double *a, const double *b, const double *q) {
  double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]},
         aq[3] = {q[0] - a[0], q[1] - a[1], q[2] - a[2]};
  double l2 = dot3(ab, ab), s = l2 > 0 ? dot3(aq, ab) / l2 : 0;
  s = s < 0 ? 0 : s > 1 ? 1 : s;
  double d[3] = {aq[0] - s * ab[0], aq[1] - s * ab[1], aq[2] - s * ab[2]};
  return sqrt(dot3(d, d));
}

double karst_i_eval_thick(const karst_sdf_t *t, const karst_i_node_t *nd, const double p[3]) {
  const double *c = t->coords + nd->u.thick.first;
  if (nd->u.thick.dim == 0) {
    double d[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
    return sqrt(dot3(d, d)) - nd->u.thick.radius;
  }
  if (nd->u.thick.dim == 1) return seg_dist(c, c + 3, p) - nd->u.thick.radius;
  double w[3] = {p[0] - nd->u.thick.o[0], p[1] - nd->u.thick.o[1], p[2] - nd->u.thick.o[2]};
  double x = dot3(w, nd->u.thick.e1), y = dot3(w, nd->u.thick.e2), h = dot3(w, nd->u.thick.nrm);
  int m = nd->u.thick.n, inside = 1;
  double best = INFINITY;
  for (int i = 0; i < m; i++) {
    const double *a = c + 2 * i, *b = c + 2 * ((i + 1) % m);
    double ex = b[0] - a[0], ey = b[1] - a[1], qx = x - a[0], qy = y - a[1];
    if (ex * qy - ey * qx < 0) inside = 0;
    double l2 = ex * ex + ey * ey, s = l2 > 0 ? (qx * ex + qy * ey) / l2 : 0;
    s = s < 0 ? 0 : s > 1 ? 1 : s;
    double dx = qx - s * ex, dy = qy - s * ey, d = dx * dx + dy * dy;
    if (d < best) best = d;
  }
  double planar = inside ? 0 : best; /* dim 2 hulls have at least three vertices */
  return sqrt(planar + h * h) - nd->u.thick.radius;
}

/**
 * External field node (see implicit.h for the contract the callback keeps).
 * @param box NULL (unbounded) or a finite box containing the solid
 * @return KARST_SUCCESS, KARST_EINVAL (no callback, bad box), KARST_ENOMEM.
 * Time complexity: O(1) amortised.
 */
karst_error_t karst_sdf_external(karst_ctx_t *ctx, karst_sdf_t *t, karst_sdf_field_fn fn,
                                 const void *arg, const double box[6], int label,
                                 karst_int_t *node) {
  if (!fn) return karst_set_error(ctx, KARST_EINVAL, "external field: no callback given");
  if (box)
    for (int a = 0; a < 3; a++)
      if (!isfinite(box[a]) || !isfinite(box[a + 3]) || !(box[a] <= box[a + 3]))
        return karst_set_error(ctx, KARST_EINVAL,
                               "external field: box axis %d is [%g, %g], not a finite range", a,
                               box[a], box[a + 3]);
  karst_i_node_t *nd = NULL;
  karst_error_t err = karst_i_sdf_new_node(ctx, t, KARST_SDF_EXTERNAL, &nd, node);
  if (err) return err;
  nd->u.ext.fn = fn;
  nd->u.ext.arg = arg;
  nd->label = label;
  if (box) {
    memcpy(nd->box, box, sizeof nd->box);
    karst_i_pad_box(nd->box);
    nd->finite = 1;
  }
  return KARST_SUCCESS;
}
