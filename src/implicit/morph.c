/* Cross-sections that change along a conduit (issue: a tube that turns into
 * a canyon does so gradually): mixtures of unit sections, their areas, and
 * the morphing sweep with its Lipschitz factor.
 *
 * The field. Let d_k be the signed distances of the unit sections (negative
 * inside), each contained in the disc of radius P_k = max |control point| and
 * at signed distance -ι_k from the origin (ι_k = -d_k(0)). At axial position l
 * of a sweep of length L, t = s(l/L) with s the smoothstep 3x² - 2x³ (|s'| <=
 * 1.5), weights w_k(t) = (1 - t) a_k + t b_k (Σ a_k = Σ b_k = 1) and scale ρ(t),
 *     F(q, l) = ρ M(q / ρ, t),   M(u, t) = Σ_k w_k(t) d_k(u).
 * In the plane, F is a convex combination of 1-Lipschitz fields: |∇_q F| <= 1.
 * Along the axis, ∂F/∂t = ρ'(t) (M - u.∇_u M) + ρ Σ_k (b_k - a_k) d_k(u).
 * (i) For the distance to a set S inside the disc of radius P, d - u.∇d =
 *     -π(u).n (π the nearest point of ∂S, n the unit normal), so
 *     |M - u.∇M| <= Σ w_k P_k <= P = max_k P_k.
 * (ii) |u| - P_k <= d_k(u) <= |u| - ι_k (the disc contains S; d_k is
 *     1-Lipschitz), and Σ (b_k - a_k) = 0, so Σ δ_k d_k = Σ δ_k (d_k - |u|) with
 *     δ = b - a is bounded by H = max(Σ_{δ>0} δ_k P_k - Σ_{δ<0} |δ_k| ι_k,
 *     Σ_{δ<0} |δ_k| P_k - Σ_{δ>0} δ_k ι_k) (0 when a = b).
 * Hence |∂F/∂l| <= β = (1.5/L)(max|ρ'| P + max ρ H). With the end slab
 * distance s (|∂s/∂l| = 1, ∂s/∂q = 0) and E(F, s) the exact extrusion (the
 * distance to the negative quadrant, 1-Lipschitz in (F, s)):
 *     |ΔE|² <= (|Δq| + β |Δl|)² + Δl² <= λ (|Δq|² + Δl²),
 * λ the largest eigenvalue of [[1, β], [β, 1 + β²]], so E is
 * K = sqrt(λ) = sqrt(1 + β²/4) + β/2 - Lipschitz, and E / K is 1-Lipschitz. Mitre
 * planes are combined by max afterwards, as for the plain sweep.
 *
 * The scale. The area of {F < 0} is ρ² A_M(t), A_M the area of the unit
 * mixture; ρ is tabulated as sqrt(A*(t_j) / A_M(t_j)) at t_j = j / 8 with the
 * target A* = (1 - t) A_a + t A_b linear in t, and interpolated linearly, so
 * max|ρ'| is the largest slope of the table and the area follows A*. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/parallel_internal.h"
#include "implicit/implicit_internal.h"

/* Largest |s'| of the smoothstep 3x² - 2x³ along the axis, per unit of l/L. */
#define SMOOTHSTEP_LIP 1.5
/* The integration grid extends this fraction beyond the sections' extent. */
#define AREA_GRID_MARGIN 0.02

static double smoothstep01(double x) {
  x = x < 0 ? 0 : (x > 1 ? 1 : x);
  return x * x * (3 - 2 * x);
}

/* Largest |control point| of a section. */
static double extent(const karst_section_t *s) {
  double r = 0;
  for (int i = 0; i < 2 * s->n; i++)
    r = fmax(r, hypot(s->cp[i][0], s->cp[i][1]));
  return r;
}

/**
 * Field of a mixture (see implicit.h). O(Σ pieces).
 */
double karst_section_mix_distance(const karst_section_mix_t *m, const double q[2]) {
  double s = 0, w = 0;
  for (int k = 0; k < m->n; k++) {
    s += m->weight[k] * karst_section_distance(&m->section[k], q);
    w += m->weight[k];
  }
  return s / w;
}

/* Area of the part of triangle x where the linear interpolant of v is negative. */
static double tri_neg_area(const double x[3][2], const double v[3]) {
  double poly[4][2];
  int m = 0;
  for (int i = 0; i < 3; i++) {
    int j = (i + 1) % 3;
    if (v[i] < 0) {
      poly[m][0] = x[i][0], poly[m][1] = x[i][1];
      m++;
    }
    if ((v[i] < 0) != (v[j] < 0)) {
      double t = v[i] / (v[i] - v[j]);
      poly[m][0] = x[i][0] + t * (x[j][0] - x[i][0]);
      poly[m][1] = x[i][1] + t * (x[j][1] - x[i][1]);
      m++;
    }
  }
  double a = 0;
  for (int i = 0; i < m; i++) {
    int j = (i + 1) % m;
    a += poly[i][0] * poly[j][1] - poly[j][0] * poly[i][1];
  }
  return 0.5 * fabs(a);
}

/* Area of {Σ w_k d_k < 0} for sections @p s (pointers), weights summing to 1. */
static double mix_area(const karst_section_t *const *s, const double *w, int n) {
  if (n == 1) return karst_section_area(s[0]);
  double ext = 0;
  for (int k = 0; k < n; k++)
    ext = fmax(ext, extent(s[k]));
  ext *= 1 + AREA_GRID_MARGIN;
  const int N = KARST_SECTION_MIX_AREA_CELLS;
  double h = 2 * ext / N;
  double *row0 = malloc((size_t)(N + 1) * 2 * sizeof *row0);
  if (!row0) return NAN;
  double *row1 = row0 + N + 1;
  double area = 0;
  for (int j = 0; j <= N; j++) {
    for (int i = 0; i <= N; i++) {
      double q[2] = {-ext + i * h, -ext + j * h}, v = 0;
      for (int k = 0; k < n; k++)
        v += w[k] * karst_section_distance(s[k], q);
      row1[i] = v;
    }
    if (j > 0)
      for (int i = 0; i < N; i++) {
        double x0 = -ext + i * h, y0 = -ext + (j - 1) * h;
        double ta[3][2] = {{x0, y0}, {x0 + h, y0}, {x0 + h, y0 + h}};
        double tb[3][2] = {{x0, y0}, {x0 + h, y0 + h}, {x0, y0 + h}};
        double va[3] = {row0[i], row0[i + 1], row1[i + 1]};
        double vb[3] = {row0[i], row1[i + 1], row1[i]};
        area += tri_neg_area(ta, va) + tri_neg_area(tb, vb);
      }
    double *tmp = row0;
    row0 = row1;
    row1 = tmp;
  }
  free(row0 < row1 ? row0 : row1);
  return area;
}

/**
 * Area of a mixture (see implicit.h). O(KARST_SECTION_MIX_AREA_CELLS² Σ pieces).
 */
double karst_section_mix_area(const karst_section_mix_t *m) {
  const karst_section_t *s[KARST_SECTION_MIX_MAX];
  double w[KARST_SECTION_MIX_MAX], sum = 0;
  for (int k = 0; k < m->n; k++)
    sum += m->weight[k];
  for (int k = 0; k < m->n; k++) {
    s[k] = &m->section[k];
    w[k] = m->weight[k] / sum;
  }
  return mix_area(s, w, m->n);
}

double karst_i_morph_mix_w(const karst_sdf_t *t, const karst_i_morph_t *m, const double *w,
                           const double q[2]) {
  double v = 0;
  for (int k = 0; k < m->n; k++)
    if (w[k] != 0) v += w[k] * karst_section_distance(&t->sections[m->sec[k]], q);
  return v;
}

double karst_i_morph_sweep_w(const karst_sdf_t *t, const karst_i_morph_t *m, double l, double x,
                             double y) {
  double tt = smoothstep01(l / m->len);
  double pos = tt * KARST_I_MORPH_TAB;
  int j = (int)pos;
  if (j >= KARST_I_MORPH_TAB) j = KARST_I_MORPH_TAB - 1;
  double f = pos - j, rho = (1 - f) * m->rho[j] + f * m->rho[j + 1];
  double w[KARST_SECTION_MIX_MAX];
  for (int k = 0; k < m->n; k++)
    w[k] = (1 - tt) * m->wa[k] + tt * m->wb[k];
  double q[2] = {x / rho, y / rho};
  return rho * karst_i_morph_mix_w(t, m, w, q);
}

/* The canonical form of the unit mixture of tree sections @p sec with weights @p w: by section
 * index, zero weights dropped. Returns the count. */
static int canonical_mix(int n, const int *sec, const double *w, int *cs, double *cw) {
  int m = 0;
  for (int k = 0; k < n; k++) {
    if (w[k] == 0) continue;
    int at = m++;
    while (at > 0 && cs[at - 1] > sec[k]) {
      cs[at] = cs[at - 1], cw[at] = cw[at - 1];
      at--;
    }
    cs[at] = sec[k], cw[at] = w[k];
  }
  return m;
}

/* The tree's cache entry of a canonical mixture, or NULL. */
static karst_i_mix_area_t *find_mix(const karst_sdf_t *t, int m, const int *cs, const double *cw) {
  for (karst_int_t i = 0; i < t->n_mix_areas; i++) {
    karst_i_mix_area_t *c = &t->mix_areas[i];
    if (c->n != m) continue;
    int same = 1;
    for (int k = 0; k < m && same; k++)
      same = c->sec[k] == cs[k] && c->w[k] == cw[k];
    if (same) return c;
  }
  return NULL;
}

/* A new cache entry for a canonical mixture, its area not yet known (NAN). */
static karst_error_t add_mix(karst_ctx_t *ctx, karst_sdf_t *t, int m, const int *cs,
                             const double *cw, karst_i_mix_area_t **out) {
  if (karst_i_grow((void **)&t->mix_areas, &t->cap_mix_areas, t->n_mix_areas + 1,
                   sizeof *t->mix_areas))
    return karst_set_error(ctx, KARST_ENOMEM, "section mixture: out of memory");
  karst_i_mix_area_t *c = &t->mix_areas[t->n_mix_areas++];
  memset(c, 0, sizeof *c);
  c->n = m;
  memcpy(c->sec, cs, (size_t)m * sizeof *cs);
  memcpy(c->w, cw, (size_t)m * sizeof *cw);
  c->area = NAN;
  *out = c;
  return KARST_SUCCESS;
}

/* Integrate the area of a cache entry. */
static void integrate_mix(const karst_sdf_t *t, karst_i_mix_area_t *c) {
  const karst_section_t *s[KARST_SECTION_MIX_MAX];
  for (int k = 0; k < c->n; k++)
    s[k] = &t->sections[c->sec[k]];
  c->area = mix_area(s, c->w, c->n);
}

/* The area of the unit mixture of tree sections @p sec with weights @p w
 * (summing to 1), from the tree's cache or integrated and cached. */
static karst_error_t cached_area(karst_ctx_t *ctx, karst_sdf_t *t, int n, const int *sec,
                                 const double *w, double *out) {
  int cs[KARST_SECTION_MIX_MAX];
  double cw[KARST_SECTION_MIX_MAX];
  int m = canonical_mix(n, sec, w, cs, cw);
  if (m == 1) { /* one section: Green's theorem, exact and cheap */
    *out = karst_section_area(&t->sections[cs[0]]);
    return KARST_SUCCESS;
  }
  karst_i_mix_area_t *c = find_mix(t, m, cs, cw);
  if (!c) {
    karst_error_t err = add_mix(ctx, t, m, cs, cw, &c);
    if (err) return err;
    integrate_mix(t, c);
  }
  /* An entry integrated ahead of time (karst_i_morph_plan) is checked here too, when used. */
  double a = c->area;
  if (!(a > 0))
    return karst_set_error(ctx, isnan(a) ? KARST_ENOMEM : KARST_EINVAL,
                           "section mixture: enclosed area %g, must be > 0", a);
  *out = a;
  return KARST_SUCCESS;
}

/* Check a mixture and add its sections to the tree, merging them into the
 * list @p sec (n entries) with weights (normalised) in column @p col of @p w. */
static karst_error_t merge_mix(karst_ctx_t *ctx, karst_sdf_t *t, const karst_section_mix_t *m,
                               const char *what, int *sec, int *n,
                               double w[2][KARST_SECTION_MIX_MAX], int col) {
  if (!m || m->n < 1 || m->n > KARST_SECTION_MIX_MAX)
    return karst_set_error(ctx, KARST_EINVAL, "%s: a mixture has 1..%d sections, got %d", what,
                           KARST_SECTION_MIX_MAX, m ? m->n : 0);
  double sum = 0;
  for (int k = 0; k < m->n; k++) {
    if (!(m->weight[k] > 0) || !isfinite(m->weight[k]))
      return karst_set_error(ctx, KARST_EINVAL, "%s: section %d has weight %g, must be > 0", what,
                             k, m->weight[k]);
    sum += m->weight[k];
  }
  for (int k = 0; k < m->n; k++) {
    karst_error_t err = karst_section_check(ctx, &m->section[k]);
    if (err) return err;
    int idx, at = -1;
    if ((err = karst_i_sdf_add_section(ctx, t, &m->section[k], &idx))) return err;
    for (int i = 0; i < *n; i++)
      if (sec[i] == idx) at = i;
    if (at < 0) {
      if (*n == KARST_SECTION_MIX_MAX)
        return karst_set_error(ctx, KARST_EINVAL, "%s: the two ends use more than %d sections",
                               what, KARST_SECTION_MIX_MAX);
      at = (*n)++;
      sec[at] = idx;
      w[0][at] = w[1][at] = 0;
    }
    w[col][at] += m->weight[k] / sum;
  }
  return KARST_SUCCESS;
}

/* Largest extent P and the bound H of |Σ (b_k - a_k) d_k| (file comment). */
static void morph_bounds(const karst_sdf_t *t, const karst_i_morph_t *m, double *P, double *H) {
  double pos_p = 0, pos_i = 0, neg_p = 0, neg_i = 0;
  *P = 0;
  for (int k = 0; k < m->n; k++) {
    const karst_section_t *s = &t->sections[m->sec[k]];
    double Pk = extent(s), o[2] = {0, 0}, ik = -karst_section_distance(s, o);
    *P = fmax(*P, Pk);
    double d = m->wb[k] - m->wa[k];
    if (d > 0) pos_p += d * Pk, pos_i += d * ik;
    if (d < 0) neg_p += -d * Pk, neg_i += -d * ik;
  }
  *H = fmax(0.0, fmax(pos_p - neg_i, neg_p - pos_i));
}

/* Hull points of all the sections of a morph (for the box and the bound). */
static int hull_points(const karst_sdf_t *t, const karst_i_morph_t *m, double (*cp)[2]) {
  int ncp = 0;
  for (int k = 0; k < m->n; k++) {
    const karst_section_t *s = &t->sections[m->sec[k]];
    for (int i = 0; i < 2 * s->n; i++) {
      cp[ncp][0] = s->cp[i][0], cp[ncp][1] = s->cp[i][1];
      ncp++;
    }
  }
  return ncp;
}

/* The sections of a morphing sweep from mixture ma to mb, added to the tree, and its weights at
 * either end (m->sec, m->n, m->wa, m->wb). */
static karst_error_t morph_mixtures(karst_ctx_t *ctx, karst_sdf_t *t, const karst_section_mix_t *ma,
                                    const karst_section_mix_t *mb, karst_i_morph_t *m) {
  double w[2][KARST_SECTION_MIX_MAX];
  karst_error_t err;
  if ((err = merge_mix(ctx, t, ma, "morphing sweep", m->sec, &m->n, w, 0)) ||
      (err = merge_mix(ctx, t, mb, "morphing sweep", m->sec, &m->n, w, 1)))
    return err;
  memcpy(m->wa, w[0], sizeof m->wa);
  memcpy(m->wb, w[1], sizeof m->wb);
  return KARST_SUCCESS;
}

/* The weights of the unit mixture at table point j of a morph. */
static void table_weights(const karst_i_morph_t *m, int j, double *wj) {
  double tt = (double)j / KARST_I_MORPH_TAB;
  for (int k = 0; k < m->n; k++)
    wj[k] = (1 - tt) * m->wa[k] + tt * m->wb[k];
}

karst_error_t karst_i_morph_plan(karst_ctx_t *ctx, karst_sdf_t *t, const karst_section_mix_t *ma,
                                 const karst_section_mix_t *mb) {
  karst_i_morph_t m;
  memset(&m, 0, sizeof m);
  karst_error_t err = morph_mixtures(ctx, t, ma, mb, &m);
  if (err) return err;
  for (int j = 0; j <= KARST_I_MORPH_TAB; j++) {
    double wj[KARST_SECTION_MIX_MAX], cw[KARST_SECTION_MIX_MAX];
    int cs[KARST_SECTION_MIX_MAX];
    table_weights(&m, j, wj);
    int n = canonical_mix(m.n, m.sec, wj, cs, cw);
    karst_i_mix_area_t *c;
    if (n > 1 && !find_mix(t, n, cs, cw) && (err = add_mix(ctx, t, n, cs, cw, &c))) return err;
  }
  return KARST_SUCCESS;
}

typedef struct {
  karst_sdf_t *t;
  karst_int_t first, n; /* cache entries to integrate */
} integrate_job_t;

static void task_integrate(void *arg, int tid, int nth) {
  integrate_job_t *J = arg;
  for (karst_int_t i = tid; i < J->n; i += nth)
    integrate_mix(J->t, &J->t->mix_areas[J->first + i]);
}

void karst_i_morph_integrate(karst_sdf_t *t, karst_int_t first, int nthreads) {
  integrate_job_t J = {t, first, t->n_mix_areas - first};
  if (J.n > 0) karst_i_parallel_run(nthreads, task_integrate, &J);
}

/**
 * Morphing sweep (see implicit.h and the proof at the top of this file).
 * Time complexity: O(pieces) per evaluation; building integrates each new
 * unit mixture once (O(KARST_SECTION_MIX_AREA_CELLS² pieces)).
 */
karst_error_t karst_sdf_sweep_morph(karst_ctx_t *ctx, karst_sdf_t *t, const double a[3],
                                    const double b[3], const karst_section_mix_t *ma, double area_a,
                                    const karst_section_mix_t *mb, double area_b,
                                    const double up[3], const karst_sweep_end_t ends[2], int label,
                                    karst_int_t *node) {
  if (!(area_a > 0) || !isfinite(area_a) || !(area_b > 0) || !isfinite(area_b))
    return karst_set_error(ctx, KARST_EINVAL, "morphing sweep: areas %g and %g m² must be > 0",
                           area_a, area_b);
  karst_i_morph_t m;
  memset(&m, 0, sizeof m);
  karst_error_t err = morph_mixtures(ctx, t, ma, mb, &m);
  if (err) return err;
  double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  m.len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  if (!(m.len > 0) || !isfinite(m.len))
    return karst_set_error(ctx, KARST_EINVAL,
                           "sweep: segment (%g, %g, %g)-(%g, %g, %g) has zero length", a[0], a[1],
                           a[2], b[0], b[1], b[2]);
  double rho_max = 0, slope = 0;
  for (int j = 0; j <= KARST_I_MORPH_TAB; j++) {
    double tt = (double)j / KARST_I_MORPH_TAB, wj[KARST_SECTION_MIX_MAX], am;
    table_weights(&m, j, wj);
    if ((err = cached_area(ctx, t, m.n, m.sec, wj, &am))) return err;
    m.rho[j] = sqrt(((1 - tt) * area_a + tt * area_b) / am);
    rho_max = fmax(rho_max, m.rho[j]);
    if (j > 0) slope = fmax(slope, fabs(m.rho[j] - m.rho[j - 1]) * KARST_I_MORPH_TAB);
  }
  double P, H;
  morph_bounds(t, &m, &P, &H);
  double beta = SMOOTHSTEP_LIP / m.len * (slope * P + rho_max * H);
  m.k = sqrt(1 + 0.25 * beta * beta) + 0.5 * beta;
  double cp[KARST_SECTION_MIX_MAX * 2 * KARST_SECTION_MAX_PIECES][2];
  int ncp = hull_points(t, &m, cp);
  if (karst_i_grow((void **)&t->morphs, &t->cap_morphs, t->n_morphs + 1, sizeof *t->morphs))
    return karst_set_error(ctx, KARST_ENOMEM, "morphing sweep: out of memory");
  t->morphs[t->n_morphs] = m;
  err = karst_i_sweep_create(ctx, t, a, b, (const double(*)[2])cp, ncp, rho_max, m.sec[0],
                             (int)t->n_morphs + 1, up, ends, label, node);
  if (!err) t->n_morphs++;
  return err;
}

/**
 * Revolved mixture (see implicit.h): the mixture is scaled to @p area and
 * revolved as karst_sdf_revolve does a section. Time complexity: O(pieces)
 * per evaluation.
 */
karst_error_t karst_sdf_revolve_mix(karst_ctx_t *ctx, karst_sdf_t *t, const double o[3],
                                    const double axis[3], const double side[3], const double up[3],
                                    const karst_section_mix_t *mix, double area,
                                    const double n[2][3], int label, karst_int_t *node) {
  return karst_i_revolve_mix_offset(ctx, t, o, axis, side, up, mix, area, n, 0, label, node);
}

karst_error_t karst_i_revolve_mix_offset(karst_ctx_t *ctx, karst_sdf_t *t, const double o[3],
                                         const double axis[3], const double side[3],
                                         const double up[3], const karst_section_mix_t *mix,
                                         double area, const double n[2][3], double offset,
                                         int label, karst_int_t *node) {
  if (!(area > 0) || !isfinite(area))
    return karst_set_error(ctx, KARST_EINVAL, "revolve: area %g m² must be > 0", area);
  karst_i_morph_t m;
  memset(&m, 0, sizeof m);
  double w[2][KARST_SECTION_MIX_MAX];
  karst_error_t err = merge_mix(ctx, t, mix, "revolve", m.sec, &m.n, w, 0);
  if (err) return err;
  memcpy(m.wa, w[0], sizeof m.wa);
  memcpy(m.wb, w[0], sizeof m.wb);
  double am;
  if ((err = cached_area(ctx, t, m.n, m.sec, m.wa, &am))) return err;
  double scale = sqrt(area / am);
  for (int j = 0; j <= KARST_I_MORPH_TAB; j++)
    m.rho[j] = scale;
  m.len = 1;
  m.k = 1;
  double cp[KARST_SECTION_MIX_MAX * 2 * KARST_SECTION_MAX_PIECES][2];
  int ncp = hull_points(t, &m, cp);
  if (karst_i_grow((void **)&t->morphs, &t->cap_morphs, t->n_morphs + 1, sizeof *t->morphs))
    return karst_set_error(ctx, KARST_ENOMEM, "revolve: out of memory");
  t->morphs[t->n_morphs] = m;
  err = karst_i_revolve_create(ctx, t, o, axis, side, up, (const double(*)[2])cp, ncp, scale,
                               m.sec[0], (int)t->n_morphs + 1, n, offset, label, node);
  if (!err) t->n_morphs++;
  return err;
}
