/* Triangulated surfaces (TINs): building and checking a single-valued
 * z = f(x, y) from vertices and triangles, the uniform bucket grid that finds
 * the triangle under a point in O(1) expected, and the TIN halves of the
 * surface queries. Every decision about plan-view geometry (which side of an
 * edge, do two triangles overlap, does the segment cross this edge) is made with
 * an exact orientation predicate, so a valid mesh is never refused and a folded
 * one never accepted because of rounding. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "geology/surface_internal.h"

/* ------------------------------------------------------------------------ */
/* Exact orientation                                                         */
/* ------------------------------------------------------------------------ */

/* Relative error bound of the floating-point orientation determinant
 * (3 + 16 eps) eps, eps = 2^-53: Shewchuk (1997), "Adaptive precision
 * floating-point arithmetic and fast robust geometric predicates", ccwerrboundA.
 * Beyond it the sign of the rounded determinant is the exact one. */
#define ORIENT_ERRBOUND ((3.0 + 16.0 * 0x1p-53) * 0x1p-53)

/* a + b = s + e exactly (Knuth's two-sum). */
static void two_sum(double a, double b, double *s, double *e) {
  double x = a + b, bv = x - a, av = x - bv;
  *s = x;
  *e = (a - av) + (b - bv);
}

/* Exact sign of the determinant as the sum of its six products, each split
 * into two doubles with fma (exact unless a product underflows), accumulated
 * into a non-overlapping expansion by Shewchuk's Grow-Expansion; the sign of
 * the sum is that of its largest non-zero component. */
static int orient_exact(const double a[2], const double b[2], const double c[2]) {
  const double f[6][2] = {{a[0], b[1]},  {-a[0], c[1]}, {-c[0], b[1]},
                          {-a[1], b[0]}, {a[1], c[0]},  {b[0], c[1]}};
  double h[12];
  int m = 0;
  for (int k = 0; k < 6; k++) {
    double p = f[k][0] * f[k][1];
    double terms[2] = {p, fma(f[k][0], f[k][1], -p)};
    for (int r = 0; r < 2; r++) {
      double q = terms[r];
      for (int i = 0; i < m; i++)
        two_sum(q, h[i], &q, &h[i]);
      h[m++] = q;
    }
  }
  for (int i = m - 1; i >= 0; i--)
    if (h[i] != 0.0) return h[i] > 0 ? 1 : -1;
  return 0;
}

/* The rounded orientation determinant of (a, b, c) and the bound beyond which
 * its sign is exact (the filter of karst_i_orient2d, inlined in hot loops). */
static inline double orient_filter(const double a[2], const double b[2], const double c[2],
                                   double *bound) {
  double detl = (a[0] - c[0]) * (b[1] - c[1]);
  double detr = (a[1] - c[1]) * (b[0] - c[0]);
  *bound = ORIENT_ERRBOUND * (fabs(detl) + fabs(detr));
  return detl - detr;
}

/**
 * Sign of the orientation of (a, b, c) in plan view: 1 when c lies left of
 * a -> b (counter-clockwise), -1 right, 0 collinear; exact for finite inputs
 * whose products do not underflow. A floating-point filter decides almost every
 * call (Shewchuk 1997); the rest are summed exactly. O(1).
 */
static inline int orient(const double a[2], const double b[2], const double c[2]) {
  double detl = (a[0] - c[0]) * (b[1] - c[1]);
  double detr = (a[1] - c[1]) * (b[0] - c[0]);
  double det = detl - detr;
  double bound = ORIENT_ERRBOUND * (fabs(detl) + fabs(detr));
  if (det > bound) return 1;
  if (-det > bound) return -1;
  /* A rounded difference is 0 only when exact, so a zero product is exact. */
  if (detl == 0.0 && detr == 0.0) return 0;
  return orient_exact(a, b, c);
}

int karst_i_orient2d(const double a[2], const double b[2], const double c[2]) {
  return orient(a, b, c);
}

/* ------------------------------------------------------------------------ */
/* Messages                                                                  */
/* ------------------------------------------------------------------------ */

/* "PATH:LINE: " / "PATH: " / "" for vertex v of the input. */
static void vertex_where(const karst_i_tin_source_t *src, karst_int_t v, char *buf, size_t sz) {
  if (src && src->path && src->vline)
    snprintf(buf, sz, "%s:%ld: ", src->path, src->vline[v]);
  else if (src && src->path)
    snprintf(buf, sz, "%s: ", src->path);
  else
    buf[0] = '\0';
}

static void triangle_where(const karst_i_tin_source_t *src, karst_int_t t, char *buf, size_t sz) {
  if (src && src->path && src->tline)
    snprintf(buf, sz, "%s:%ld: ", src->path, src->tline[t]);
  else if (src && src->path)
    snprintf(buf, sz, "%s: ", src->path);
  else
    buf[0] = '\0';
}

/* Name of input vertex v: "vertex ID" (file id) or "vertex INDEX". */
static long long vertex_label(const karst_i_tin_source_t *src, karst_int_t v) {
  return src && src->vid ? (long long)src->vid[v] : (long long)v;
}

/* "TRGL 4 5 6" (file ids) or "triangle 3 (vertices 4, 5, 6)". */
static void triangle_label(const karst_i_tin_source_t *src, karst_int_t t, const karst_int_t *tri,
                           char *buf, size_t sz) {
  const karst_int_t *v = tri + 3 * t;
  if (src && src->vid)
    snprintf(buf, sz, "TRGL %lld %lld %lld", vertex_label(src, v[0]), vertex_label(src, v[1]),
             vertex_label(src, v[2]));
  else
    snprintf(buf, sz, "triangle %lld (vertices %lld, %lld, %lld)", (long long)t, (long long)v[0],
             (long long)v[1], (long long)v[2]);
}

/* " (line N)" when the source has lines. */
static void line_note(const karst_i_tin_source_t *src, const long *lines, karst_int_t k, char *buf,
                      size_t sz) {
  if (src && src->path && lines)
    snprintf(buf, sz, " (line %ld)", lines[k]);
  else
    buf[0] = '\0';
}

/* ------------------------------------------------------------------------ */
/* Building                                                                  */
/* ------------------------------------------------------------------------ */

typedef struct {
  double x, y, z;
  karst_int_t v;
} vsort_t;

static int cmp_vsort(const void *pa, const void *pb) {
  const vsort_t *a = pa, *b = pb;
  if (a->x != b->x) return a->x < b->x ? -1 : 1;
  if (a->y != b->y) return a->y < b->y ? -1 : 1;
  return a->v < b->v ? -1 : (a->v > b->v);
}

typedef struct {
  karst_int_t u, v; /* u < v */
  karst_int_t t;    /* triangle */
  int k;            /* edge k of t runs from corner k to corner k + 1 */
} edge_t;

static int cmp_edge(const void *pa, const void *pb) {
  const edge_t *a = pa, *b = pb;
  if (a->u != b->u) return a->u < b->u ? -1 : 1;
  if (a->v != b->v) return a->v < b->v ? -1 : 1;
  return a->t < b->t ? -1 : (a->t > b->t);
}

/* min and max of finite values, inlined (libm's fmin and fmax are calls that
 * also order NaNs, which these hot loops never see). */
static inline double min2(double a, double b) {
  return a < b ? a : b;
}
static inline double max2(double a, double b) {
  return a > b ? a : b;
}

static const double *tvert(const karst_surface_t *s, karst_int_t t, int k) {
  return s->tdata + 9 * t + 2 * k;
}

/* Where p lies with respect to the closed plan-view triangle t: 2 strictly
 * inside, 1 on its border, 0 outside. The three filtered determinants decide
 * unless one of them is within its rounding bound of 0. */
static inline int in_triangle(const karst_surface_t *s, karst_int_t t, const double p[2]) {
  const double *v0 = tvert(s, t, 0), *v1 = tvert(s, t, 1), *v2 = tvert(s, t, 2);
  double b0, b1, b2, d0, d1, d2;
  if ((d0 = orient_filter(v0, v1, p, &b0)) < -b0) return 0;
  if ((d1 = orient_filter(v1, v2, p, &b1)) < -b1) return 0;
  if ((d2 = orient_filter(v2, v0, p, &b2)) < -b2) return 0;
  if (d0 > b0 && d1 > b1 && d2 > b2) return 2;
  int o0 = orient(v0, v1, p), o1 = orient(v1, v2, p);
  int o2 = orient(v2, v0, p);
  if (o0 < 0 || o1 < 0 || o2 < 0) return 0;
  return o0 > 0 && o1 > 0 && o2 > 0 ? 2 : 1;
}

/* Interiors of two counter-clockwise triangles overlap: no edge line of either
 * leaves all three corners of the other on its closed outer side (the
 * separating-axis theorem for convex polygons, with touching allowed). */
static int interiors_overlap(const karst_surface_t *s, karst_int_t p, karst_int_t q) {
  for (int pass = 0; pass < 2; pass++) {
    karst_int_t A = pass ? q : p, B = pass ? p : q;
    for (int k = 0; k < 3; k++) {
      const double *e0 = tvert(s, A, k), *e1 = tvert(s, A, (k + 1) % 3);
      int outside = 1;
      for (int c = 0; c < 3 && outside; c++)
        if (orient(e0, e1, tvert(s, B, c)) > 0) outside = 0;
      if (outside) return 0;
    }
  }
  return 1;
}

/* Convex polygon clipping (Sutherland-Hodgman) against the half-plane
 * n . p >= c, for points (x, y, z) with z carried linearly. The crossing of an
 * edge is interpolated from its lexicographically smaller end, so the two
 * triangles of a shared edge produce the same point to the bit. */
static int clip_halfplane(const double (*in)[3], int n, double nx, double ny, double c,
                          double (*out)[3]) {
  int m = 0;
  for (int i = 0; i < n; i++) {
    const double *p = in[i], *q = in[(i + 1) % n];
    double dp = nx * p[0] + ny * p[1] - c, dq = nx * q[0] + ny * q[1] - c;
    if (dp >= 0) memcpy(out[m++], p, sizeof(double[3]));
    if ((dp < 0 && dq > 0) || (dp > 0 && dq < 0)) {
      const double *u = p, *w = q;
      double du = dp, dw = dq;
      if (w[0] < u[0] || (w[0] == u[0] && w[1] < u[1])) {
        u = q, w = p, du = dq, dw = dp;
      }
      double f = du / (du - dw);
      for (int k = 0; k < 3; k++)
        out[m][k] = u[k] + f * (w[k] - u[k]);
      if (nx != 0 && ny == 0) out[m][0] = c / nx; /* on an axis-parallel line exactly */
      if (ny != 0 && nx == 0) out[m][1] = c / ny;
      m++;
    }
  }
  return m;
}

/* Triangle t clipped to [x0, x1] x [y0, y1]: up to 7 corners (x, y, z). */
static int clip_to_rect(const karst_surface_t *s, karst_int_t t, double x0, double x1, double y0,
                        double y1, double (*poly)[3]) {
  double a[8][3], b[8][3];
  for (int k = 0; k < 3; k++) {
    const karst_int_t v = s->tri[3 * t + k];
    memcpy(a[k], s->xyz + 3 * v, sizeof(double[3]));
  }
  int n = 3;
  n = clip_halfplane((const double(*)[3])a, n, 1, 0, x0, b);
  n = clip_halfplane((const double(*)[3])b, n, -1, 0, -x1, a);
  n = clip_halfplane((const double(*)[3])a, n, 0, 1, y0, b);
  n = clip_halfplane((const double(*)[3])b, n, 0, -1, -y1, a);
  memcpy(poly, a, (size_t)n * sizeof a[0]);
  return n;
}

/* Row and column of the bucket holding (x, y) (inside the vertex box). The
 * same rounded expressions serve the insertion, so monotone rounding keeps a
 * point's bucket within the range its triangle was listed in. */
static karst_int_t bucket_col(const karst_surface_t *s, double x) {
  double f = (x - s->bx0) * s->binv;
  karst_int_t i = f > 0 ? (karst_int_t)f : 0;
  return i < s->bnx ? i : s->bnx - 1;
}

static karst_int_t bucket_row(const karst_surface_t *s, double y) {
  double f = (y - s->by0) * s->binv;
  karst_int_t j = f > 0 ? (karst_int_t)f : 0;
  return j < s->bny ? j : s->bny - 1;
}

/* x-range of triangle t within the strip y in [ya, yb]: corners inside it and
 * crossings of its edges with the strip's lines; 0 when it misses the strip. */
static int strip_xrange(const karst_surface_t *s, karst_int_t t, double ya, double yb, double *xlo,
                        double *xhi) {
  double lo = INFINITY, hi = -INFINITY;
  for (int k = 0; k < 3; k++) {
    const double *p = tvert(s, t, k), *q = tvert(s, t, (k + 1) % 3);
    if (p[1] >= ya && p[1] <= yb) lo = min2(lo, p[0]), hi = max2(hi, p[0]);
    if (p[1] == q[1]) continue;
    const double ys[2] = {ya, yb};
    for (int e = 0; e < 2; e++) {
      double c = ys[e];
      if ((c - p[1]) * (c - q[1]) <= 0) {
        double x = p[0] + (c - p[1]) * (q[0] - p[0]) / (q[1] - p[1]);
        lo = min2(lo, x), hi = max2(hi, x);
      }
    }
  }
  *xlo = lo, *xhi = hi;
  return lo <= hi;
}

/* Visit the buckets triangle t overlaps: fill = 0 counts into bstart, 1 lists. */
static void bucket_insert(karst_surface_t *s, karst_int_t t, int fill, karst_int_t *cursor) {
  const double *v = s->tdata + 9 * t;
  double ymin = min2(v[1], min2(v[3], v[5])), ymax = max2(v[1], max2(v[3], v[5]));
  double m = KARST_I_BUCKET_MARGIN * s->bcs;
  karst_int_t j0 = bucket_row(s, ymin - m), j1 = bucket_row(s, ymax + m);
  for (karst_int_t j = j0; j <= j1; j++) {
    double ya = s->by0 + (double)j * s->bcs - m, yb = s->by0 + (double)(j + 1) * s->bcs + m;
    double xlo, xhi;
    if (!strip_xrange(s, t, max2(ya, ymin), min2(yb, ymax), &xlo, &xhi)) continue;
    karst_int_t i0 = bucket_col(s, xlo - m), i1 = bucket_col(s, xhi + m);
    for (karst_int_t i = i0; i <= i1; i++) {
      karst_int_t b = j * s->bnx + i;
      if (fill)
        s->bitem[cursor[b]++] = t;
      else
        s->bstart[b + 1]++;
    }
  }
}

static karst_error_t build_buckets(karst_ctx_t *ctx, karst_surface_t *s, double area) {
  double W = s->hi[0] - s->lo[0], H = s->hi[1] - s->lo[1];
  double cs = sqrt(area / (double)s->nt / KARST_SURFACE_BUCKETS_PER_TRIANGLE);
  /* At most cap buckets, also for a TIN covering little of its box or a thin one. */
  double cap = 4.0 * KARST_SURFACE_BUCKETS_PER_TRIANGLE * (double)s->nt + 64.0;
  if (!(cs >= fmax(W, H) / cap)) cs = fmax(W, H) / cap;
  while (ceil(W / cs) * ceil(H / cs) > cap)
    cs *= 1.25;
  s->bcs = cs;
  s->binv = 1.0 / cs;
  s->bx0 = s->lo[0];
  s->by0 = s->lo[1];
  s->bnx = (karst_int_t)fmax(1.0, ceil(W / cs));
  s->bny = (karst_int_t)fmax(1.0, ceil(H / cs));
  karst_int_t nb = s->bnx * s->bny;
  s->bstart = calloc((size_t)nb + 1, sizeof *s->bstart);
  karst_int_t *cursor = malloc((size_t)nb * sizeof *cursor);
  if (!s->bstart || !cursor) goto nomem;
  for (karst_int_t t = 0; t < s->nt; t++)
    bucket_insert(s, t, 0, NULL);
  for (karst_int_t b = 0; b < nb; b++)
    s->bstart[b + 1] += s->bstart[b];
  s->bitem = malloc((size_t)(s->bstart[nb] > 0 ? s->bstart[nb] : 1) * sizeof *s->bitem);
  if (!s->bitem) goto nomem;
  memcpy(cursor, s->bstart, (size_t)nb * sizeof *cursor);
  for (karst_int_t t = 0; t < s->nt; t++)
    bucket_insert(s, t, 1, cursor);
  /* Within a bucket, the triangle holding its centre first: it covers much of
   * the bucket, so a query tests about 1.6 triangles instead of 2.4 on a
   * regular mesh. */
  for (karst_int_t b = 0; b < nb; b++) {
    double c[2] = {s->bx0 + ((double)(b % s->bnx) + 0.5) * s->bcs,
                   s->by0 + ((double)(b / s->bnx) + 0.5) * s->bcs};
    for (karst_int_t k = s->bstart[b]; k < s->bstart[b + 1]; k++)
      if (in_triangle(s, s->bitem[k], c)) {
        karst_int_t t = s->bitem[k];
        memmove(s->bitem + s->bstart[b] + 1, s->bitem + s->bstart[b],
                (size_t)(k - s->bstart[b]) * sizeof *s->bitem);
        s->bitem[s->bstart[b]] = t;
        break;
      }
  }
  free(cursor);
  return KARST_SUCCESS;
nomem:
  free(cursor);
  return karst_set_error(ctx, KARST_ENOMEM, "TIN: out of memory for the spatial index");
}

/* Any two triangles that share a bucket, are not neighbours across an edge and
 * overlap in plan view make the surface multi-valued. */
static karst_error_t check_overlaps(karst_ctx_t *ctx, const karst_surface_t *s,
                                    const karst_i_tin_source_t *src, const karst_int_t *itri) {
  karst_int_t nb = s->bnx * s->bny;
  double pairs = 0;
  for (karst_int_t b = 0; b < nb; b++) {
    double k = (double)(s->bstart[b + 1] - s->bstart[b]);
    pairs += 0.5 * k * (k - 1);
  }
  if (pairs > (double)KARST_SURFACE_MAX_OVERLAP_PAIRS)
    return karst_set_error(ctx, KARST_ERANGE,
                           "%s: the triangles are too irregular to check for overlaps (%.3g "
                           "candidate pairs, more than the limit of %lld): remesh the surface "
                           "with well-shaped triangles",
                           src && src->path ? src->path : "TIN", pairs,
                           (long long)KARST_SURFACE_MAX_OVERLAP_PAIRS);
  for (karst_int_t b = 0; b < nb; b++) {
    for (karst_int_t x = s->bstart[b]; x < s->bstart[b + 1]; x++) {
      karst_int_t p = s->bitem[x];
      for (karst_int_t y = x + 1; y < s->bstart[b + 1]; y++) {
        karst_int_t q = s->bitem[y];
        const karst_int_t *np = s->nbr + 3 * p;
        if (np[0] == q || np[1] == q || np[2] == q) continue; /* checked by their edge */
        if (!interiors_overlap(s, p, q)) continue;
        double poly[8][3], (*tmp)[3] = poly;
        double a[8][3];
        for (int k = 0; k < 3; k++) {
          memcpy(a[k], tvert(s, p, k), sizeof(double[2]));
          a[k][2] = 0;
        }
        int n = 3;
        for (int k = 0; k < 3 && n > 0; k++) {
          const double *e0 = tvert(s, q, k), *e1 = tvert(s, q, (k + 1) % 3);
          double nx = -(e1[1] - e0[1]), ny = e1[0] - e0[0];
          n = clip_halfplane((const double(*)[3])a, n, nx, ny, nx * e0[0] + ny * e0[1], tmp);
          memcpy(a, tmp, (size_t)n * sizeof a[0]);
        }
        double cx = 0, cy = 0;
        for (int k = 0; k < n; k++)
          cx += a[k][0] / n, cy += a[k][1] / n;
        char w[1100], lp[160], lq[160], note[48];
        triangle_where(src, p, w, sizeof w);
        triangle_label(src, p, itri, lp, sizeof lp);
        triangle_label(src, q, itri, lq, sizeof lq);
        line_note(src, src ? src->tline : NULL, q, note, sizeof note);
        return karst_set_error(ctx, KARST_EINVAL,
                               "%s%s and %s%s overlap in plan view around (%.10g, %.10g): the "
                               "surface is multi-valued (folded over itself or given twice); a "
                               "surface must be single-valued z = f(x, y)",
                               w, lp, lq, note, cx, cy);
      }
    }
  }
  return KARST_SUCCESS;
}

/**
 * Build a TIN surface and check that it is a single-valued z = f(x, y) over
 * its plan-view footprint: every coordinate finite and within
 * KARST_SURFACE_MAX_COORD; every triangle with three distinct vertices that
 * are not collinear in plan view (no vertical triangle); vertices at the same
 * x-y merged when their z agree (a vertex repeated by another TFACE) and an
 * error when they differ (a vertical step); no edge in more than two
 * triangles; the two triangles of an edge on opposite sides of it (no fold);
 * no two triangles overlapping in plan view (the exact check runs over the
 * pairs that share a bucket of the index). Triangles are turned
 * counter-clockwise seen from above. Vertices used by no triangle are dropped.
 * @param ctx context; @param nv, xyz vertices; @param nt, tri triangles
 * (0-based); @param src where they were read, for messages "FILE:LINE: ..."
 * (NULL: "vertex 3", "triangle 7 (vertices ...)"); @param out the surface.
 * @return KARST_SUCCESS, KARST_EINVAL (bad geometry, naming the vertex or
 *         triangle and its line), KARST_ERANGE (a limit) or KARST_ENOMEM.
 * Time complexity: O(n log n) for n = nv + nt (sorting the vertices; edges
 * are sorted in O(n)), plus the overlap check, O(n) expected on a
 * well-shaped mesh.
 */
karst_error_t karst_i_surface_tin(karst_ctx_t *ctx, karst_int_t nv, const double *xyz,
                                  karst_int_t nt, const karst_int_t *tri,
                                  const karst_i_tin_source_t *src, karst_surface_t **out) {
  karst_error_t err = KARST_SUCCESS;
  karst_surface_t *s = NULL;
  vsort_t *vs = NULL;
  edge_t *edges = NULL;
  karst_int_t *rep = NULL, *newidx = NULL, *orig = NULL, *first_edge = NULL;
  char w[1100], lab[160], note[48];
  const char *file = src && src->path ? src->path : "TIN";
  *out = NULL;
  if (nt < 1)
    return karst_set_error(ctx, KARST_EINVAL,
                           "%s: a triangulated surface needs at least one triangle, got %lld", file,
                           (long long)nt);
  if (nv > KARST_SURFACE_MAX_VERTICES || nt > KARST_SURFACE_MAX_TRIANGLES)
    return karst_set_error(ctx, KARST_ERANGE,
                           "%s: %lld vertices and %lld triangles, more than the limits of %lld "
                           "and %lld",
                           file, (long long)nv, (long long)nt,
                           (long long)KARST_SURFACE_MAX_VERTICES,
                           (long long)KARST_SURFACE_MAX_TRIANGLES);
  for (karst_int_t v = 0; v < nv; v++)
    for (int c = 0; c < 3; c++) {
      double x = xyz[3 * v + c];
      if (!isfinite(x) || fabs(x) > KARST_SURFACE_MAX_COORD) {
        vertex_where(src, v, w, sizeof w);
        return karst_set_error(ctx, KARST_EINVAL,
                               "%svertex %lld: %c must be a finite number within +-%g m, got %g", w,
                               vertex_label(src, v), "xyz"[c], KARST_SURFACE_MAX_COORD, x);
      }
    }
  for (karst_int_t t = 0; t < nt; t++) {
    const karst_int_t *tv = tri + 3 * t;
    for (int k = 0; k < 3; k++)
      if (tv[k] < 0 || tv[k] >= nv) {
        triangle_where(src, t, w, sizeof w);
        return karst_set_error(ctx, KARST_EINVAL,
                               "%striangle %lld: vertex index %lld is outside [0, %lld)", w,
                               (long long)t, (long long)tv[k], (long long)nv);
      }
    for (int k = 0; k < 3; k++)
      if (tv[k] == tv[(k + 1) % 3]) {
        triangle_where(src, t, w, sizeof w);
        triangle_label(src, t, tri, lab, sizeof lab);
        return karst_set_error(ctx, KARST_EINVAL,
                               "%s%s names vertex %lld twice: a triangle needs three vertices", w,
                               lab, vertex_label(src, tv[k]));
      }
  }

  /* Merge vertices at the same x-y: the same point when z agrees, else a step. */
  rep = malloc((size_t)nv * sizeof *rep);
  newidx = malloc((size_t)nv * sizeof *newidx);
  vs = malloc((size_t)nv * sizeof *vs);
  if (!rep || !newidx || !vs) goto nomem;
  for (karst_int_t v = 0; v < nv; v++)
    rep[v] = -1;
  for (karst_int_t t = 0; t < 3 * nt; t++)
    rep[tri[t]] = tri[t];
  karst_int_t nused = 0;
  for (karst_int_t v = 0; v < nv; v++)
    if (rep[v] >= 0) vs[nused++] = (vsort_t){xyz[3 * v], xyz[3 * v + 1], xyz[3 * v + 2], v};
  qsort(vs, (size_t)nused, sizeof *vs, cmp_vsort);
  for (karst_int_t k = 0, first = 0; k < nused; k++) {
    if (k > 0 && (vs[k].x != vs[first].x || vs[k].y != vs[first].y)) first = k;
    if (vs[k].z != vs[first].z) {
      karst_int_t a = vs[first].v, b = vs[k].v;
      vertex_where(src, b, w, sizeof w);
      line_note(src, src ? src->vline : NULL, a, note, sizeof note);
      err = karst_set_error(ctx, KARST_EINVAL,
                            "%svertex %lld at (%.10g, %.10g) has z = %.10g but vertex %lld%s at "
                            "the same x-y has z = %.10g: a vertical step; a surface must be "
                            "single-valued z = f(x, y)",
                            w, vertex_label(src, b), vs[k].x, vs[k].y, vs[k].z,
                            vertex_label(src, a), note, vs[first].z);
      goto cleanup;
    }
    rep[vs[k].v] = vs[first].v; /* the first in file order among equals */
  }
  free(vs);
  vs = NULL;

  s = calloc(1, sizeof *s);
  if (!s) goto nomem;
  s->kind = KARST_SURFACE_TIN;
  karst_int_t nkeep = 0;
  for (karst_int_t v = 0; v < nv; v++)
    newidx[v] = rep[v] == v ? nkeep++ : -1;
  s->nv = nkeep;
  s->nt = nt;
  s->xyz = malloc((size_t)nkeep * 3 * sizeof *s->xyz);
  s->tri = malloc((size_t)nt * 3 * sizeof *s->tri);
  s->tdata = malloc((size_t)nt * 9 * sizeof *s->tdata);
  s->nbr = malloc((size_t)nt * 3 * sizeof *s->nbr);
  orig = malloc((size_t)nkeep * sizeof *orig);
  if (!s->xyz || !s->tri || !s->tdata || !s->nbr || !orig) goto nomem;
  for (karst_int_t v = 0; v < nv; v++)
    if (newidx[v] >= 0) {
      memcpy(s->xyz + 3 * newidx[v], xyz + 3 * v, 3 * sizeof(double));
      orig[newidx[v]] = v;
    }
  s->lo[0] = s->lo[1] = s->lo[2] = INFINITY;
  s->hi[0] = s->hi[1] = s->hi[2] = -INFINITY;
  for (karst_int_t v = 0; v < nkeep; v++)
    for (int c = 0; c < 3; c++) {
      s->lo[c] = fmin(s->lo[c], s->xyz[3 * v + c]);
      s->hi[c] = fmax(s->hi[c], s->xyz[3 * v + c]);
    }

  /* Triangles: distinct points, not vertical, counter-clockwise. */
  double area = 0;
  for (karst_int_t t = 0; t < nt; t++) {
    karst_int_t *T = s->tri + 3 * t;
    for (int k = 0; k < 3; k++)
      T[k] = newidx[rep[tri[3 * t + k]]];
    for (int k = 0; k < 3; k++)
      if (T[k] == T[(k + 1) % 3]) {
        triangle_where(src, t, w, sizeof w);
        triangle_label(src, t, tri, lab, sizeof lab);
        const double *p = s->xyz + 3 * T[k];
        err = karst_set_error(ctx, KARST_EINVAL,
                              "%s%s: vertices %lld and %lld are the same point (%.10g, %.10g, "
                              "%.10g): a triangle needs three distinct points",
                              w, lab, vertex_label(src, tri[3 * t + k]),
                              vertex_label(src, tri[3 * t + (k + 1) % 3]), p[0], p[1], p[2]);
        goto cleanup;
      }
    const double *P[3] = {s->xyz + 3 * T[0], s->xyz + 3 * T[1], s->xyz + 3 * T[2]};
    int o = orient(P[0], P[1], P[2]);
    if (o == 0) {
      triangle_where(src, t, w, sizeof w);
      triangle_label(src, t, tri, lab, sizeof lab);
      err = karst_set_error(ctx, KARST_EINVAL,
                            "%s%s is vertical: its corners (%.10g, %.10g, %.10g), (%.10g, %.10g, "
                            "%.10g) and (%.10g, %.10g, %.10g) are collinear in plan view; a "
                            "surface must be single-valued z = f(x, y)",
                            w, lab, P[0][0], P[0][1], P[0][2], P[1][0], P[1][1], P[1][2], P[2][0],
                            P[2][1], P[2][2]);
      goto cleanup;
    }
    if (o < 0) {
      karst_int_t tmp = T[1];
      T[1] = T[2];
      T[2] = tmp;
      const double *tp = P[1];
      P[1] = P[2];
      P[2] = tp;
    }
    double *d = s->tdata + 9 * t;
    for (int k = 0; k < 3; k++)
      d[2 * k] = P[k][0], d[2 * k + 1] = P[k][1];
    double ux = P[1][0] - P[0][0], uy = P[1][1] - P[0][1], uz = P[1][2] - P[0][2];
    double vx = P[2][0] - P[0][0], vy = P[2][1] - P[0][1], vz = P[2][2] - P[0][2];
    double det = ux * vy - uy * vx; /* > 0 up to rounding; the sign test above is exact */
    d[6] = P[0][2];
    d[7] = (uz * vy - uy * vz) / det;
    d[8] = (ux * vz - uz * vx) / det;
    double slope = hypot(d[7], d[8]);
    if (!(det > 0) || !(slope <= KARST_SURFACE_MAX_SLOPE)) { /* nearly vertical */
      triangle_where(src, t, w, sizeof w);
      triangle_label(src, t, tri, lab, sizeof lab);
      err = karst_set_error(ctx, KARST_EINVAL,
                            "%s%s is vertical: its slope %.3g is steeper than %g (its plan-view "
                            "area is %.3g m^2); a surface must be single-valued z = f(x, y)",
                            w, lab, slope, KARST_SURFACE_MAX_SLOPE, 0.5 * det);
      goto cleanup;
    }
    area += 0.5 * det;
    s->lipschitz = fmax(s->lipschitz, slope);
  }

  /* Edges: at most two triangles each, on opposite sides. They are sorted by
   * their lower vertex with a counting sort, then within a vertex's few edges. */
  edges = malloc((size_t)nt * 3 * sizeof *edges);
  first_edge = calloc((size_t)nkeep + 1, sizeof *first_edge);
  if (!edges || !first_edge) goto nomem;
  for (karst_int_t t = 0; t < nt; t++)
    for (int k = 0; k < 3; k++) {
      karst_int_t a = s->tri[3 * t + k], b = s->tri[3 * t + (k + 1) % 3];
      first_edge[(a < b ? a : b) + 1]++;
      s->nbr[3 * t + k] = -1;
    }
  for (karst_int_t v = 0; v < nkeep; v++)
    first_edge[v + 1] += first_edge[v];
  for (karst_int_t t = 0; t < nt; t++)
    for (int k = 0; k < 3; k++) {
      karst_int_t a = s->tri[3 * t + k], b = s->tri[3 * t + (k + 1) % 3];
      karst_int_t u = a < b ? a : b;
      edges[first_edge[u]++] = (edge_t){u, a < b ? b : a, t, k};
    }
  for (karst_int_t v = nkeep; v > 0; v--) /* back to the starts */
    first_edge[v] = first_edge[v - 1];
  first_edge[0] = 0;
  for (karst_int_t v = 0; v < nkeep; v++) {
    edge_t *E = edges + first_edge[v];
    karst_int_t n = first_edge[v + 1] - first_edge[v];
    if (n > 16)
      qsort(E, (size_t)n, sizeof *E, cmp_edge); /* a vertex of high degree */
    else
      for (karst_int_t i = 1; i < n; i++) /* insertion sort; t ascends already */
        for (karst_int_t j = i; j > 0 && cmp_edge(E + j - 1, E + j) > 0; j--) {
          edge_t w = E[j];
          E[j] = E[j - 1];
          E[j - 1] = w;
        }
  }
  karst_int_t ne = 3 * nt, nbnd = 0;
  for (karst_int_t e = 0; e < ne;) {
    karst_int_t f = e + 1;
    while (f < ne && edges[f].u == edges[e].u && edges[f].v == edges[e].v)
      f++;
    const edge_t *E = edges + e;
    if (f - e > 2) {
      char l2[160], l3[160], n2[48], n3[48];
      triangle_where(src, E[0].t, w, sizeof w);
      triangle_label(src, E[0].t, tri, lab, sizeof lab);
      triangle_label(src, E[1].t, tri, l2, sizeof l2);
      triangle_label(src, E[2].t, tri, l3, sizeof l3);
      line_note(src, src ? src->tline : NULL, E[1].t, n2, sizeof n2);
      line_note(src, src ? src->tline : NULL, E[2].t, n3, sizeof n3);
      err = karst_set_error(ctx, KARST_EINVAL,
                            "%sthe edge between vertices %lld and %lld belongs to %lld triangles "
                            "(%s, %s%s, %s%s%s): the surface is not a manifold; a surface must be "
                            "single-valued z = f(x, y)",
                            w, vertex_label(src, orig[E->u]), vertex_label(src, orig[E->v]),
                            (long long)(f - e), lab, l2, n2, l3, n3, f - e > 3 ? ", ..." : "");
      goto cleanup;
    }
    if (f - e == 2) {
      const karst_int_t *T0 = s->tri + 3 * E[0].t, *T1 = s->tri + 3 * E[1].t;
      if (T0[E[0].k] == T1[E[1].k]) { /* the same direction: both on one side */
        char l2[160];
        triangle_where(src, E[0].t, w, sizeof w);
        triangle_label(src, E[0].t, tri, lab, sizeof lab);
        triangle_label(src, E[1].t, tri, l2, sizeof l2);
        line_note(src, src ? src->tline : NULL, E[1].t, note, sizeof note);
        err = karst_set_error(ctx, KARST_EINVAL,
                              "%s%s and %s%s lie on the same side of their shared edge (vertices "
                              "%lld and %lld) in plan view: the surface folds over itself; a "
                              "surface must be single-valued z = f(x, y)",
                              w, lab, l2, note, vertex_label(src, orig[E->u]),
                              vertex_label(src, orig[E->v]));
        goto cleanup;
      }
      s->nbr[3 * E[0].t + E[0].k] = E[1].t;
      s->nbr[3 * E[1].t + E[1].k] = E[0].t;
    } else {
      nbnd++;
    }
    e = f;
  }
  s->bnd = malloc((size_t)(nbnd > 0 ? nbnd : 1) * 2 * sizeof *s->bnd);
  if (!s->bnd) goto nomem;
  for (karst_int_t t = 0; t < nt; t++)
    for (int k = 0; k < 3; k++)
      if (s->nbr[3 * t + k] < 0) {
        s->bnd[2 * s->nbnd] = s->tri[3 * t + k];
        s->bnd[2 * s->nbnd + 1] = s->tri[3 * t + (k + 1) % 3];
        s->nbnd++;
      }

  if ((err = build_buckets(ctx, s, area))) goto cleanup;
  if ((err = check_overlaps(ctx, s, src, tri))) goto cleanup;
  *out = s;
  s = NULL;
  goto cleanup;
nomem:
  err = karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory for %lld vertices and %lld triangles",
                        file, (long long)nv, (long long)nt);
cleanup:
  karst_surface_free(s);
  free(vs);
  free(edges);
  free(first_edge);
  free(rep);
  free(newidx);
  free(orig);
  return err;
}

/**
 * A triangulated surface from arrays: @p nv vertices (x, y, z) and @p nt
 * triangles of 0-based vertex indices in any winding, checked as a
 * single-valued z = f(x, y) (see karst_i_surface_tin for the rules: finite
 * coordinates, no vertical or repeated-vertex triangle, no edge in more than two
 * triangles, no fold, no overlap in plan view; equal points merged).
 * @return KARST_SUCCESS, KARST_EINVAL naming the vertex or triangle,
 *         KARST_ERANGE or KARST_ENOMEM.
 * Time complexity: O(n log n) for n = nv + nt, the overlap check O(n) expected.
 */
karst_error_t karst_surface_create_tin(karst_ctx_t *ctx, karst_int_t nv, const double *xyz,
                                       karst_int_t nt, const karst_int_t *tri,
                                       karst_surface_t **out) {
  return karst_i_surface_tin(ctx, nv, xyz, nt, tri, NULL, out);
}

/* ------------------------------------------------------------------------ */
/* Point location                                                            */
/* ------------------------------------------------------------------------ */

/**
 * The triangle whose closed plan-view area holds (x, y), the lowest index when
 * (x, y) lies on a shared edge or vertex, or -1 outside the TIN. The bucket of
 * (x, y) lists every triangle that meets it, the one holding the bucket's
 * centre first; a triangle holding the point strictly inside (exact orientation
 * tests) is the only one and ends the scan, a point on borders scans them all.
 * Time complexity: O(1) expected (the triangles of one bucket).
 */
karst_int_t karst_i_tin_locate(const karst_surface_t *s, double x, double y) {
  if (!(x >= s->lo[0] && x <= s->hi[0] && y >= s->lo[1] && y <= s->hi[1])) return -1;
  const double p[2] = {x, y};
  karst_int_t b = bucket_row(s, y) * s->bnx + bucket_col(s, x), best = -1;
  for (karst_int_t k = s->bstart[b]; k < s->bstart[b + 1]; k++) {
    karst_int_t t = s->bitem[k];
    int r = in_triangle(s, t, p);
    if (r == 2) return t; /* strictly inside: no other triangle holds p */
    if (r == 1 && (best < 0 || t < best)) best = t;
  }
  return best;
}

/** karst_i_tin_locate by scanning every triangle (the reference of its test). O(nt). */
karst_int_t karst_i_tin_locate_brute(const karst_surface_t *s, double x, double y) {
  const double p[2] = {x, y};
  if (!isfinite(x) || !isfinite(y)) return -1;
  for (karst_int_t t = 0; t < s->nt; t++)
    if (in_triangle(s, t, p)) return t;
  return -1;
}

/* ------------------------------------------------------------------------ */
/* Segment pieces                                                            */
/* ------------------------------------------------------------------------ */

/* Triangles remembered per call of karst_i_tin_pieces so that one listed in
 * several buckets is examined once (beyond, a repeat only costs time: its
 * parameters are already in the list). */
#define PIECES_SEEN_MAX 64

/* Insert v into the sorted distinct list t[0..*n); -1 when full. */
static int insert_sorted(double *t, int *n, int max_t, double v) {
  int lo = 0, hi = *n;
  while (lo < hi) {
    int mid = (lo + hi) / 2;
    if (t[mid] < v)
      lo = mid + 1;
    else
      hi = mid;
  }
  if (lo < *n && t[lo] == v) return 0;
  if (*n >= max_t) return -1;
  memmove(t + lo + 1, t + lo, (size_t)(*n - lo) * sizeof *t);
  t[lo] = v;
  (*n)++;
  return 0;
}

/* Parameter along A + t D where the trace crosses the edge (u, v), computed
 * from its lower-numbered end so that both triangles of the edge give the same
 * value to the bit. */
static double crossing(const karst_surface_t *s, karst_int_t u, karst_int_t v, const double A[2],
                       const double D[2]) {
  if (u > v) {
    karst_int_t w = u;
    u = v, v = w;
  }
  const double *E0 = s->xyz + 3 * u, *E1 = s->xyz + 3 * v;
  double ex = E1[0] - E0[0], ey = E1[1] - E0[1];
  return ((E0[0] - A[0]) * ey - (E0[1] - A[1]) * ex) / (D[0] * ey - D[1] * ex);
}

/* The trace walked from triangle T, which holds P0, across the edge by which
 * it leaves each triangle (decided by exact sides of the line through A, B),
 * recording each crossing in (t0, t1) until the triangle that holds P1:
 * O(pieces). The count, -1 when t is full, or -2 when the walk cannot decide:
 * the line meets a vertex (or runs along an edge) or the trace leaves the TIN,
 * and the bucket scan does the range instead. */
static int walk_pieces(const karst_surface_t *s, const double A[2], const double B[2],
                       const double P0[2], const double P1[2], double t0, double t1, karst_int_t T,
                       double *t, int max_t) {
  const double D[2] = {B[0] - A[0], B[1] - A[1]};
  int n = 0;
  for (karst_int_t step = 0; step <= s->nt && T >= 0; step++) {
    const karst_int_t *V = s->tri + 3 * T;
    int side[3], k = -1;
    for (int c = 0; c < 3; c++)
      if ((side[c] = orient(A, B, s->xyz + 3 * V[c])) == 0) return -2;
    for (int c = 0; c < 3; c++)
      if (side[c] < 0 && side[(c + 1) % 3] > 0) k = c; /* the edge the line leaves by */
    if (k < 0) return -2;
    const double *e0 = s->xyz + 3 * V[k], *e1 = s->xyz + 3 * V[(k + 1) % 3];
    if (orient(e0, e1, P1) >= 0) return n; /* P1 is in T: done */
    if (orient(e0, e1, P0) > 0) {          /* the exit lies beyond P0 */
      double te = crossing(s, V[k], V[(k + 1) % 3], A, D);
      if (te > t0 && te < t1 && insert_sorted(t, &n, max_t, te)) return -1;
    }
    T = s->nbr[3 * T + k];
  }
  return -2;
}

/* Break parameters contributed by triangle tr: its corners on the trace's line
 * and its edges the trace crosses properly (both decided exactly). */
static int triangle_breaks(const karst_surface_t *s, karst_int_t tr, const double A[2],
                           const double B[2], double t0, double t1, double *t, int *n, int max_t) {
  const karst_int_t *T = s->tri + 3 * tr;
  const double D[2] = {B[0] - A[0], B[1] - A[1]};
  const double dd = D[0] * D[0] + D[1] * D[1];
  int side[3];
  for (int k = 0; k < 3; k++) {
    const double *V = s->xyz + 3 * T[k];
    side[k] = orient(A, B, V);
    if (side[k] == 0) {
      double tv = ((V[0] - A[0]) * D[0] + (V[1] - A[1]) * D[1]) / dd;
      if (tv > t0 && tv < t1 && insert_sorted(t, n, max_t, tv)) return -1;
    }
  }
  for (int k = 0; k < 3; k++) {
    int k1 = (k + 1) % 3;
    if (side[k] * side[k1] >= 0) continue; /* not strictly on both sides of the line */
    karst_int_t u = T[k], v = T[k1];
    if (u > v) u = T[k1], v = T[k];
    const double *E0 = s->xyz + 3 * u, *E1 = s->xyz + 3 * v;
    int r0 = orient(E0, E1, A), r1 = orient(E0, E1, B);
    if (r0 * r1 >= 0) continue; /* the crossing is not strictly between a and b */
    double te = crossing(s, T[k], T[k1], A, D);
    if (te > t0 && te < t1 && insert_sorted(t, n, max_t, te)) return -1;
  }
  return 0;
}

/**
 * Piece boundaries of a TIN along [a, b] with parameters in (t0, t1) (see
 * karst_surface_segment_pieces): nothing when both ends lie in one triangle; a
 * walk across the triangles from the one under the start when the trace meets
 * no vertex and stays in the TIN; else the triangles of the buckets the trace
 * crosses contribute the corners on it and the edges it crosses.
 * Time complexity: O(1 + pieces) for the walk, O(buckets crossed x triangles
 * per bucket) expected for the scan.
 */
int karst_i_tin_pieces(const karst_surface_t *s, const double a[3], const double b[3], double t0,
                       double t1, double *t, int max_t) {
  const double A[2] = {a[0], a[1]}, B[2] = {b[0], b[1]};
  double P0[2], P1[2];
  for (int k = 0; k < 2; k++) {
    P0[k] = a[k] + t0 * (b[k] - a[k]);
    P1[k] = a[k] + t1 * (b[k] - a[k]);
  }
  if (A[0] == B[0] && A[1] == B[1]) return 0; /* vertical: one x-y point */
  /* Both ends in one (convex) triangle: the trace between them crosses nothing.
   * Graph edges are often shorter than triangles, so this is the common case. */
  karst_int_t e0 = karst_i_tin_locate(s, P0[0], P0[1]);
  if (e0 >= 0 && e0 == karst_i_tin_locate(s, P1[0], P1[1])) return 0;
  if (e0 >= 0) {
    int w = walk_pieces(s, A, B, P0, P1, t0, t1, e0, t, max_t);
    if (w != -2) return w;
  }
  double xmin = max2(min2(P0[0], P1[0]), s->lo[0]), xmax = min2(max2(P0[0], P1[0]), s->hi[0]);
  double ymin = max2(min2(P0[1], P1[1]), s->lo[1]), ymax = min2(max2(P0[1], P1[1]), s->hi[1]);
  if (!(xmin <= xmax && ymin <= ymax)) return 0; /* outside the TIN's box */
  int n = 0, nseen = 0;
  karst_int_t seen[PIECES_SEEN_MAX];
  double m = KARST_I_BUCKET_MARGIN * s->bcs;
  karst_int_t j0 = bucket_row(s, ymin - m), j1 = bucket_row(s, ymax + m);
  double dx = P1[0] - P0[0], dy = P1[1] - P0[1];
  for (karst_int_t j = j0; j <= j1; j++) {
    /* x-range of the trace within the row (widened by the margin) */
    double ya = s->by0 + (double)j * s->bcs - m, yb = s->by0 + (double)(j + 1) * s->bcs + m;
    double xa = P0[0], xb = P1[0];
    if (dy != 0) {
      double ua = (ya - P0[1]) / dy, ub = (yb - P0[1]) / dy;
      double ulo = max2(0.0, min2(ua, ub)), uhi = min2(1.0, max2(ua, ub));
      if (ulo > uhi) continue;
      xa = P0[0] + ulo * dx, xb = P0[0] + uhi * dx;
    }
    karst_int_t i0 = bucket_col(s, max2(min2(xa, xb) - m, xmin - m));
    karst_int_t i1 = bucket_col(s, min2(max2(xa, xb) + m, xmax + m));
    for (karst_int_t i = i0; i <= i1; i++) {
      karst_int_t bk = j * s->bnx + i;
      for (karst_int_t k = s->bstart[bk]; k < s->bstart[bk + 1]; k++) {
        karst_int_t tr = s->bitem[k];
        const double *d = s->tdata + 9 * tr;
        if (max2(d[0], max2(d[2], d[4])) < xmin - m || min2(d[0], min2(d[2], d[4])) > xmax + m ||
            max2(d[1], max2(d[3], d[5])) < ymin - m || min2(d[1], min2(d[3], d[5])) > ymax + m)
          continue;  /* its box misses the trace's: nothing to add */
        int dup = 0; /* a triangle listed in several buckets of the trace is done once */
        for (int q = 0; q < nseen && !dup; q++)
          dup = seen[q] == tr;
        if (dup) continue;
        if (nseen < PIECES_SEEN_MAX) seen[nseen++] = tr;
        if (triangle_breaks(s, tr, A, B, t0, t1, t, &n, max_t)) return -1;
      }
    }
  }
  return n;
}

/* ------------------------------------------------------------------------ */
/* Extremes over a rectangle, coverage, display                              */
/* ------------------------------------------------------------------------ */

/**
 * Exact extreme (sign 1: max, -1: min) of a TIN over [x0, x1] x [y0, y1]: each
 * triangle of the buckets the rectangle meets, clipped to it, is linear, so
 * its extreme is at a corner of the clipped polygon. NAN when no triangle
 * meets the rectangle.
 * Time complexity: O(buckets and triangles meeting the rectangle).
 */
double karst_i_tin_extreme_rect(const karst_surface_t *s, double x0, double x1, double y0,
                                double y1, double sign) {
  double m = -INFINITY;
  if (x1 < s->lo[0] || x0 > s->hi[0] || y1 < s->lo[1] || y0 > s->hi[1]) return NAN;
  karst_int_t i0 = bucket_col(s, fmax(x0, s->lo[0])), i1 = bucket_col(s, fmin(x1, s->hi[0]));
  karst_int_t j0 = bucket_row(s, fmax(y0, s->lo[1])), j1 = bucket_row(s, fmin(y1, s->hi[1]));
  for (karst_int_t j = j0; j <= j1; j++)
    for (karst_int_t i = i0; i <= i1; i++) {
      karst_int_t bk = j * s->bnx + i;
      for (karst_int_t k = s->bstart[bk]; k < s->bstart[bk + 1]; k++) {
        karst_int_t t = s->bitem[k];
        const double *d = s->tdata + 9 * t;
        double poly[8][3];
        int n = clip_to_rect(s, t, x0, x1, y0, y1, poly);
        for (int c = 0; c < n; c++) /* z from the plane: exact corners stay exact */
          m = fmax(m, sign * (d[6] + d[7] * (poly[c][0] - d[0]) + d[8] * (poly[c][1] - d[1])));
      }
    }
  return m == -INFINITY ? NAN : sign * m;
}

/* Distance from p to the segment [u, v] in plan view, and the nearest point. */
static double point_segment(const double p[2], const double *u, const double *v, double q[2]) {
  double ex = v[0] - u[0], ey = v[1] - u[1], ee = ex * ex + ey * ey;
  double f = ee > 0 ? ((p[0] - u[0]) * ex + (p[1] - u[1]) * ey) / ee : 0;
  f = f < 0 ? 0 : (f > 1 ? 1 : f);
  q[0] = u[0] + f * ex, q[1] = u[1] + f * ey;
  return hypot(p[0] - q[0], p[1] - q[1]);
}

/**
 * Coverage of [lo, hi] by a TIN (see karst_surface_check_covers): the
 * triangles are closed and do not overlap, so the rectangle is covered when its
 * corners are, no border edge of the TIN passes through its open interior, and
 * its centre is. The message names each corner left out with the distance to
 * the nearest point of the surface, or the border edge that cuts in and how far
 * inside the rectangle it runs.
 * Time complexity: O(border edges) plus O(1) expected point locations.
 */
karst_error_t karst_i_tin_check_covers(karst_ctx_t *ctx, const karst_surface_t *s,
                                       const double lo[2], const double hi[2], const char *what) {
  const char *name = s->path ? s->path : "(surface built in code)";
  static const char *const corner_name[4] = {"south-west", "south-east", "north-west",
                                             "north-east"};
  char msg[900];
  size_t len = 0;
  msg[0] = '\0';
  for (int c = 0; c < 4; c++) {
    const double p[2] = {c & 1 ? hi[0] : lo[0], c & 2 ? hi[1] : lo[1]};
    if (karst_i_tin_locate(s, p[0], p[1]) >= 0) continue;
    double best = INFINITY, q[2] = {NAN, NAN};
    for (karst_int_t e = 0; e < s->nbnd; e++) {
      double r[2];
      double d = point_segment(p, s->xyz + 3 * s->bnd[2 * e], s->xyz + 3 * s->bnd[2 * e + 1], r);
      if (d < best) best = d, q[0] = r[0], q[1] = r[1];
    }
    if (len < sizeof msg)
      len += (size_t)snprintf(msg + len, sizeof msg - len,
                              "%sthe %s corner (%g, %g) by %.4g m (the nearest point of the "
                              "surface is (%.10g, %.10g))",
                              len ? "; " : "", corner_name[c], p[0], p[1], best, q[0], q[1]);
  }
  if (len > 0)
    return karst_set_error(ctx, KARST_ERANGE,
                           "%s: the %s surface (vertices over x in [%.10g, %.10g], y in [%.10g, "
                           "%.10g] m) must cover x in [%g, %g], y in [%g, %g] m but falls short "
                           "at %s",
                           name, what, s->lo[0], s->hi[0], s->lo[1], s->hi[1], lo[0], hi[0], lo[1],
                           hi[1], msg);
  if (lo[0] < hi[0] && lo[1] < hi[1]) {
    for (karst_int_t e = 0; e < s->nbnd; e++) {
      const double *u = s->xyz + 3 * s->bnd[2 * e], *v = s->xyz + 3 * s->bnd[2 * e + 1];
      /* Liang-Barsky with strict bounds: the part of the edge in the open rectangle */
      double f0 = 0, f1 = 1;
      int inside = 1;
      for (int k = 0; k < 2 && inside; k++) {
        double d = v[k] - u[k];
        if (d == 0) {
          inside = u[k] > lo[k] && u[k] < hi[k];
          continue;
        }
        double fa = (lo[k] - u[k]) / d, fb = (hi[k] - u[k]) / d;
        f0 = fmax(f0, fmin(fa, fb));
        f1 = fmin(f1, fmax(fa, fb));
      }
      if (!inside || !(f0 < f1)) continue;
      double fm = 0.5 * (f0 + f1);
      double mx = u[0] + fm * (v[0] - u[0]), my = u[1] + fm * (v[1] - u[1]);
      double depth = fmin(fmin(mx - lo[0], hi[0] - mx), fmin(my - lo[1], hi[1] - my));
      return karst_set_error(ctx, KARST_ERANGE,
                             "%s: the %s surface must cover x in [%g, %g], y in [%g, %g] m but "
                             "has a gap: its border (the edge from (%.10g, %.10g) to (%.10g, "
                             "%.10g)) runs through the extent at (%.10g, %.10g), %.4g m inside it",
                             name, what, lo[0], hi[0], lo[1], hi[1], u[0], u[1], v[0], v[1], mx, my,
                             depth);
    }
  }
  double cx = 0.5 * (lo[0] + hi[0]), cy = 0.5 * (lo[1] + hi[1]);
  if (karst_i_tin_locate(s, cx, cy) < 0)
    return karst_set_error(ctx, KARST_ERANGE,
                           "%s: the %s surface must cover x in [%g, %g], y in [%g, %g] m but does "
                           "not reach its centre (%g, %g)",
                           name, what, lo[0], hi[0], lo[1], hi[1], cx, cy);
  return KARST_SUCCESS;
}

/* Open-addressing map from the bits of a point to its output index. */
typedef struct {
  karst_int_t cap, n;
  karst_int_t *slot; /* index + 1, 0 empty */
  double *pts;       /* 3 per output point */
  karst_int_t ptcap;
} ptmap_t;

static uint64_t point_hash(const double p[3]) {
  uint64_t h = 0x9E3779B97F4A7C15ull, w;
  for (int k = 0; k < 3; k++) {
    double v = p[k] == 0 ? 0.0 : p[k]; /* -0 and 0 are one point */
    memcpy(&w, &v, sizeof w);
    h = (h ^ w) * 0xBF58476D1CE4E5B9ull;
    h ^= h >> 31;
  }
  return h;
}

static int ptmap_grow(ptmap_t *m) {
  karst_int_t ncap = m->cap ? 2 * m->cap : 1024;
  karst_int_t *slot = calloc((size_t)ncap, sizeof *slot);
  if (!slot) return -1;
  for (karst_int_t i = 0; i < m->n; i++) {
    size_t h = (size_t)(point_hash(m->pts + 3 * i) & (uint64_t)(ncap - 1));
    while (slot[h])
      h = (h + 1) & (size_t)(ncap - 1);
    slot[h] = i + 1;
  }
  free(m->slot);
  m->slot = slot;
  m->cap = ncap;
  return 0;
}

/* Index of point p in the output, added when new; -1 when out of memory. */
static karst_int_t ptmap_get(ptmap_t *m, const double p[3]) {
  if (2 * (m->n + 1) > m->cap && ptmap_grow(m)) return -1;
  size_t h = (size_t)(point_hash(p) & (uint64_t)(m->cap - 1));
  while (m->slot[h]) {
    const double *q = m->pts + 3 * (m->slot[h] - 1);
    if (q[0] == p[0] && q[1] == p[1] && q[2] == p[2]) return m->slot[h] - 1;
    h = (h + 1) & (size_t)(m->cap - 1);
  }
  if (m->n == m->ptcap) {
    karst_int_t nc = m->ptcap ? 2 * m->ptcap : 1024;
    double *np = realloc(m->pts, (size_t)nc * 3 * sizeof *np);
    if (!np) return -1;
    m->pts = np;
    m->ptcap = nc;
  }
  memcpy(m->pts + 3 * m->n, p, 3 * sizeof(double));
  m->slot[h] = m->n + 1;
  return m->n++;
}

/**
 * A TIN clipped to [lo, hi] for display (see karst_surface_triangulate): each
 * triangle meeting the rectangle is clipped to it and the convex polygon fanned
 * from its first corner; points are merged by their exact coordinates (the
 * clipping gives both triangles of an edge the same point).
 * Time complexity: O(nt) (each triangle's box is tested), O(output) memory.
 */
karst_error_t karst_i_tin_triangulate(karst_ctx_t *ctx, const karst_surface_t *s,
                                      const double lo[2], const double hi[2], double **xyz,
                                      karst_int_t *nv, karst_int_t **tri, karst_int_t *nt) {
  ptmap_t pm = {0, 0, NULL, NULL, 0};
  karst_int_t *T = NULL, tcap = 0, m = 0;
  for (karst_int_t t = 0; t < s->nt; t++) {
    const double *d = s->tdata + 9 * t;
    if (fmax(d[0], fmax(d[2], d[4])) < lo[0] || fmin(d[0], fmin(d[2], d[4])) > hi[0] ||
        fmax(d[1], fmax(d[3], d[5])) < lo[1] || fmin(d[1], fmin(d[3], d[5])) > hi[1])
      continue;
    double poly[8][3];
    int n = clip_to_rect(s, t, lo[0], hi[0], lo[1], hi[1], poly);
    karst_int_t idx[8];
    for (int c = 0; c < n; c++)
      if ((idx[c] = ptmap_get(&pm, poly[c])) < 0) goto nomem;
    for (int c = 1; c + 1 < n; c++) {
      if (orient(poly[0], poly[c], poly[c + 1]) <= 0) continue; /* a sliver cut away */
      if (m == tcap) {
        karst_int_t nc = tcap ? 2 * tcap : 1024;
        karst_int_t *nT = realloc(T, (size_t)nc * 3 * sizeof *nT);
        if (!nT) goto nomem;
        T = nT;
        tcap = nc;
      }
      T[3 * m] = idx[0], T[3 * m + 1] = idx[c], T[3 * m + 2] = idx[c + 1];
      m++;
    }
  }
  free(pm.slot);
  *xyz = pm.pts ? pm.pts : malloc(sizeof(double));
  *tri = T ? T : malloc(sizeof(karst_int_t));
  if (!*xyz || !*tri) {
    free(*xyz);
    free(*tri);
    *xyz = NULL;
    *tri = NULL;
    return karst_set_error(ctx, KARST_ENOMEM, "surface triangulation: out of memory");
  }
  *nv = pm.n;
  *nt = m;
  return KARST_SUCCESS;
nomem:
  free(pm.slot);
  free(pm.pts);
  free(T);
  return karst_set_error(ctx, KARST_ENOMEM, "surface triangulation: out of memory");
}
