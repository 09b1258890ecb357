/* Exact k nearest neighbours on a uniform grid (Paris et al. 2021, §4.1: the
 * graph G joins every sample to its k nearest samples).
 *
 * Why a grid rather than a k-d tree: the samples are a Poisson-sphere
 * sampling, nearly uniform at the scale of the neighbourhoods, so a grid
 * whose cells hold a few points each finds a point's neighbours without
 * tree descent or backtracking: gather every point within a squared radius
 * T (guessed from the previous query, doubled until at least k points are
 * found), then select the k smallest (Hoare's selection, expected linear).
 * The cells of one grid row within T form one contiguous run of points.
 * On 100 k samples with k = 40 it takes 0.13 s of CPU against 0.4–0.5 s for
 * FLANN's exact single k-d tree (bench/bench_knn.c).
 *
 * Exactness without tolerances. Points are ordered by (karst_i_dist2, index),
 * a total order, so the k nearest form one well-defined set even with ties.
 * Cells are left out of a gather only on lower bounds of that very computed
 * distance: every point of grid slab i along axis a has its coordinate
 * within the actual [min, max] of the slabs (recorded while sorting the
 * points into cells; the cell index floor((x − lo)/h) is monotone in x), and
 * because IEEE subtraction, squaring and addition are monotone in each
 * argument, ((bx² + by²) + bz²) built from per-axis gaps b to those bounds is
 * <= the computed squared distance of every point they bound. A cell is left
 * out only when this bound exceeds T, so a gather returns exactly the points
 * with computed d² <= T, and with k of them the k nearest are among them: no
 * rounding can change the result.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/math_internal.h"
#include "core/memory_internal.h"
#include "core/parallel_internal.h"
#include "graph/graph_internal.h"

/* Mean points per occupied cell, as a fraction of k: with q = k/24 points
 * per cell the k nearest lie within about two cells (4/3 π (2h)³ ρ ≈ 33 q).
 * Measured (instruction counts, 30 k uniform points, k = 100): k/50 and k/12
 * are within 10 % of k/24; smaller cells cost row overheads, larger ones
 * distance evaluations. Never below KNN_MIN_OCCUPANCY. */
#define KNN_OCCUPANCY_PER_NEIGHBOUR (1.0 / 24.0)
#define KNN_MIN_OCCUPANCY 1.0
/* Refinements of the cell size when the points fill only part of their
 * bounding box (mean occupancy of non-empty cells more than twice the
 * target): each shrinks the cells by the observed excess. */
#define KNN_REFINEMENTS 3
/* At most this many cells per point (bounds the grid's memory). */
#define KNN_MAX_CELLS_PER_POINT 8.0
/* Cells handed to a thread at a time (interleaved: a static split). */
#define KNN_CELL_BLOCK 64

typedef struct grid {
  double lo[3], h;
  int64_t dims[3];
  karst_int_t ncells;
  karst_int_t *start;   /* ncells + 1: points of cell c are [start[c], start[c + 1]) */
  double *sx, *sy, *sz; /* coordinates in cell order, one array per axis (see gather) */
  int32_t *sidx;        /* original index of each sorted point */
  /* Per axis and slab: the coordinates' bounds (+inf / -inf when empty),
   * the largest coordinate of the slabs up to i and the smallest of the
   * slabs from i on (bounds for the outward walks of gather). */
  double *smin[3], *smax[3], *upto_max[3], *from_min[3];
} grid_t;

static void grid_destroy(grid_t *g) {
  free(g->start), free(g->sx), free(g->sy), free(g->sz), free(g->sidx);
  for (int a = 0; a < 3; a++)
    free(g->smin[a]), free(g->smax[a]), free(g->upto_max[a]), free(g->from_min[a]);
  memset(g, 0, sizeof *g);
}

static int64_t cell_coord(const grid_t *g, double x, int a) {
  double f = floor((x - g->lo[a]) / g->h);
  return f < 0 ? 0 : (f >= (double)g->dims[a] ? g->dims[a] - 1 : (int64_t)f);
}

static double cells_for(const double ext[3], double h) {
  double c = 1;
  for (int a = 0; a < 3; a++)
    c *= floor(ext[a] / h) + 1;
  return c;
}

/* Cell size giving at most `target` cells over the extents (bisection on h). */
static double cell_size(const double ext[3], double target) {
  double emax = karst_i_fmax(ext[0], karst_i_fmax(ext[1], ext[2]));
  if (!(emax > 0)) return 1.0;
  double hl = emax / (target + 1), hr = 2 * emax; /* cells(hl) > target >= cells(hr) = 1 */
  for (int it = 0; it < 60; it++) {
    double hm = 0.5 * (hl + hr);
    if (cells_for(ext, hm) > target)
      hl = hm;
    else
      hr = hm;
  }
  return hr;
}

static karst_error_t grid_build(karst_ctx_t *ctx, grid_t *g, const double *xyz, karst_int_t n,
                                int k) {
  int64_t *cid = malloc(sizeof(int64_t) * (size_t)n);
  karst_error_t err = KARST_SUCCESS;
  if (!cid) goto nomem;
  double hi[3], ext[3];
  for (int a = 0; a < 3; a++)
    g->lo[a] = INFINITY, hi[a] = -INFINITY;
  for (karst_int_t i = 0; i < n; i++)
    for (int a = 0; a < 3; a++)
      g->lo[a] = karst_i_fmin(g->lo[a], xyz[3 * i + a]),
      hi[a] = karst_i_fmax(hi[a], xyz[3 * i + a]);
  for (int a = 0; a < 3; a++)
    ext[a] = hi[a] - g->lo[a];
  double q = karst_i_fmax(KNN_MIN_OCCUPANCY, k * KNN_OCCUPANCY_PER_NEIGHBOUR);
  double target = karst_i_fmax(1.0, (double)n / q);
  for (int it = 0;; it++) {
    g->h = cell_size(ext, target);
    g->ncells = 1;
    for (int a = 0; a < 3; a++) {
      g->dims[a] = (int64_t)(floor(ext[a] / g->h) + 1);
      g->ncells *= g->dims[a];
    }
    free(g->start);
    g->start = karst_i_calloc_large((size_t)g->ncells + 1, sizeof(karst_int_t));
    if (!g->start) goto nomem;
    for (karst_int_t i = 0; i < n; i++) {
      const double *p = xyz + 3 * i;
      cid[i] = cell_coord(g, p[0], 0) +
               g->dims[0] * (cell_coord(g, p[1], 1) + g->dims[1] * cell_coord(g, p[2], 2));
      g->start[cid[i] + 1]++;
    }
    karst_int_t occupied = 0;
    for (karst_int_t c = 0; c < g->ncells; c++)
      occupied += g->start[c + 1] > 0;
    double mean = (double)n / (double)occupied;
    double cap = KNN_MAX_CELLS_PER_POINT * (double)n;
    if (it == KNN_REFINEMENTS || mean <= 2 * q || target >= cap) break;
    target = karst_i_fmin(cap, target * mean / q);
  }
  for (karst_int_t c = 0; c < g->ncells; c++)
    g->start[c + 1] += g->start[c];
  g->sx = karst_i_alloc_large(sizeof(double) * (size_t)n);
  g->sy = karst_i_alloc_large(sizeof(double) * (size_t)n);
  g->sz = karst_i_alloc_large(sizeof(double) * (size_t)n);
  g->sidx = karst_i_alloc_large(sizeof(int32_t) * (size_t)n);
  if (!g->sx || !g->sy || !g->sz || !g->sidx) goto nomem;
  for (int a = 0; a < 3; a++) {
    size_t d = (size_t)g->dims[a];
    g->smin[a] = malloc(sizeof(double) * d), g->smax[a] = malloc(sizeof(double) * d);
    g->upto_max[a] = malloc(sizeof(double) * d), g->from_min[a] = malloc(sizeof(double) * d);
    if (!g->smin[a] || !g->smax[a] || !g->upto_max[a] || !g->from_min[a]) goto nomem;
    for (size_t i = 0; i < d; i++)
      g->smin[a][i] = INFINITY, g->smax[a][i] = -INFINITY;
  }
  /* Stable counting sort: within a cell, points keep increasing index. */
  for (karst_int_t i = 0; i < n; i++) {
    karst_int_t s = g->start[cid[i]]++;
    g->sx[s] = xyz[3 * i], g->sy[s] = xyz[3 * i + 1], g->sz[s] = xyz[3 * i + 2];
    g->sidx[s] = (int32_t)i;
    int64_t c = cid[i],
            ca[3] = {c % g->dims[0], c / g->dims[0] % g->dims[1], c / g->dims[0] / g->dims[1]};
    for (int a = 0; a < 3; a++) {
      double x = xyz[3 * i + a];
      g->smin[a][ca[a]] = karst_i_fmin(g->smin[a][ca[a]], x);
      g->smax[a][ca[a]] = karst_i_fmax(g->smax[a][ca[a]], x);
    }
  }
  for (karst_int_t c = g->ncells; c > 0; c--)
    g->start[c] = g->start[c - 1];
  g->start[0] = 0;
  for (int a = 0; a < 3; a++) {
    int64_t d = g->dims[a];
    g->upto_max[a][0] = g->smax[a][0];
    for (int64_t i = 1; i < d; i++)
      g->upto_max[a][i] = karst_i_fmax(g->upto_max[a][i - 1], g->smax[a][i]);
    g->from_min[a][d - 1] = g->smin[a][d - 1];
    for (int64_t i = d - 2; i >= 0; i--)
      g->from_min[a][i] = karst_i_fmin(g->from_min[a][i + 1], g->smin[a][i]);
  }
  goto cleanup;
nomem:
  err = karst_set_error(ctx, KARST_ENOMEM, "no memory for the neighbour grid of %lld points",
                        (long long)n);
cleanup:
  free(cid);
  return err;
}

/* ------------------------------------------------------------------------ */
/* Search                                                                    */
/* ------------------------------------------------------------------------ */
typedef struct cand {
  double d;
  int32_t i;
} cand_t;

static int cand_less(const cand_t *a, const cand_t *b) {
  return karst_i_knn_less(a->d, a->i, b->d, b->i);
}

/* Move the k smallest of v[0 .. m) (k <= m) to v[0 .. k), the k-th smallest
 * to v[k − 1]: Hoare's selection (median-of-three pivot) with Lomuto's
 * partition written without branches on the comparison (the swap is always
 * made, the boundary advances by the comparison's 0 or 1), since at a few
 * dozen candidates a mispredicted branch per element costs more than the
 * stores. The keys are distinct because the indices are. Expected O(m). */
static void select_k(cand_t *v, karst_int_t m, karst_int_t k) {
  karst_int_t lo = 0, hi = m - 1, t = k - 1;
  while (hi - lo >= 16) {
    karst_int_t mid = lo + (hi - lo) / 2, pi;
    if (cand_less(&v[lo], &v[mid]))
      pi = cand_less(&v[mid], &v[hi]) ? mid : (cand_less(&v[lo], &v[hi]) ? hi : lo);
    else
      pi = cand_less(&v[lo], &v[hi]) ? lo : (cand_less(&v[mid], &v[hi]) ? hi : mid);
    cand_t p = v[pi];
    v[pi] = v[hi], v[hi] = p;
    karst_int_t j = lo;
    for (karst_int_t i = lo; i < hi; i++) {
      cand_t x = v[i];
      int lt = (x.d < p.d) | ((x.d == p.d) & (x.i < p.i));
      v[i] = v[j], v[j] = x;
      j += lt;
    }
    v[hi] = v[j], v[j] = p; /* v[lo .. j) < p = v[j] < v(j .. hi] */
    if (t == j) return;
    if (t < j)
      hi = j - 1;
    else
      lo = j + 1;
  }
  for (karst_int_t i = lo + 1; i <= hi; i++) {
    cand_t x = v[i];
    karst_int_t j = i - 1;
    while (j >= lo && cand_less(&x, &v[j]))
      v[j + 1] = v[j], j--;
    v[j + 1] = x;
  }
}

typedef struct search {
  karst_ctx_t *ctx;
  const grid_t *g;
  int k;
  double t0; /* first squared search radius of each thread */
  int32_t *nbr, *kidx;
  double *kd2;
  int failed[KARST_I_MAX_THREADS];
} search_t;

typedef struct buffer {
  cand_t *v;
  karst_int_t n, cap;
  double *d; /* squared distances of one run of cells (cap entries) */
} buffer_t;

/* Lower bound of |x − q| for every slab from s outwards on the side of s
 * away from slab c (the query's, where the bound is 0): monotone in s. */
static double outer_gap(const grid_t *g, int a, int64_t s, int64_t c, double x) {
  if (s < c) return x - g->upto_max[a][s];
  if (s > c) return g->from_min[a][s] - x;
  return 0.0;
}

/* All points p != s with d²(p, s) <= T into b (0 on allocation failure).
 * Along each axis the slabs are taken outwards from the query's while their
 * outer bound is within T; a row of cells is scanned only where the bound
 * ((bx² + by²) + bz²) is <= T, which (the x bounds being monotone outwards)
 * is one contiguous run of cells, hence of points. These are exactly the
 * cells that can hold such a point, for the computed distances (see the file
 * comment). bx2 is scratch of dims[0] entries. */
static int gather(const grid_t *g, karst_int_t s, const int64_t cc[3], double T, buffer_t *b,
                  double *bx2) {
  const double q[3] = {g->sx[s], g->sy[s], g->sz[s]};
  int64_t lo[3], hi[3];
  for (int a = 0; a < 3; a++) {
    lo[a] = cc[a], hi[a] = cc[a];
    for (double gap; lo[a] > 0 && (gap = outer_gap(g, a, lo[a] - 1, cc[a], q[a]), gap * gap <= T);)
      lo[a]--;
    for (double gap;
         hi[a] < g->dims[a] - 1 && (gap = outer_gap(g, a, hi[a] + 1, cc[a], q[a]), gap * gap <= T);)
      hi[a]++;
  }
  for (int64_t ii = lo[0]; ii <= hi[0]; ii++) {
    double gap = outer_gap(g, 0, ii, cc[0], q[0]);
    bx2[ii] = gap * gap;
  }
  karst_int_t m = 0;
  for (int64_t kk = lo[2]; kk <= hi[2]; kk++) {
    double bz = outer_gap(g, 2, kk, cc[2], q[2]);
    bz *= bz;
    for (int64_t jj = lo[1]; jj <= hi[1]; jj++) {
      double by = outer_gap(g, 1, jj, cc[1], q[1]);
      by *= by;
      if (by + bz > T) continue;
      int64_t i0 = cc[0], i1 = cc[0];
      while (i0 > lo[0] && (bx2[i0 - 1] + by) + bz <= T)
        i0--;
      while (i1 < hi[0] && (bx2[i1 + 1] + by) + bz <= T)
        i1++;
      karst_int_t row = g->dims[0] * (jj + g->dims[1] * kk);
      karst_int_t p0 = g->start[row + i0], p1 = g->start[row + i1 + 1];
      if (m + (p1 - p0) > b->cap) {
        karst_int_t nc = 2 * (m + (p1 - p0));
        cand_t *v = realloc(b->v, sizeof(cand_t) * (size_t)nc);
        if (!v) return 0;
        b->v = v;
        double *d = realloc(b->d, sizeof(double) * (size_t)nc);
        if (!d) return 0;
        b->d = d, b->cap = nc;
      }
      /* The distances of the run first, in a loop the compiler vectorises (the coordinates are
       * one array per axis). */
      double *restrict dr = b->d;
      const double *restrict px = g->sx + p0, *restrict py = g->sy + p0, *restrict pz = g->sz + p0;
      const karst_int_t len = p1 - p0;
      for (karst_int_t t = 0; t < len; t++)
        dr[t] = karst_i_dist2_xyz(px[t], py[t], pz[t], q);
      cand_t *out = b->v;
      const int32_t *restrict idx = g->sidx + p0;
      for (karst_int_t t = 0; t < len; t++) { /* written always, kept when within T */
        out[m].d = dr[t], out[m].i = idx[t];
        m += dr[t] <= T;
      }
      if (s >= p0 && s < p1) /* the query itself, at d = 0 <= T: drop it, keeping the order */
        for (karst_int_t t = m - 1;; t--)
          if (out[t].i == g->sidx[s]) {
            memmove(out + t, out + t + 1, sizeof(cand_t) * (size_t)(m - 1 - t));
            m--;
            break;
          }
    }
  }
  b->n = m;
  return 1;
}

/* Next squared radius to try after the k-th squared distance d2 of the
 * previous query: neighbouring queries have similar radii, a radius a little
 * too large only costs a few more candidates, one too small a second gather.
 * Measured (instruction counts, 30 k uniform points, k = 100): 1.15 is 8 %
 * cheaper than 1.3, 1.05 and 1.5 are 15 % dearer. */
#define KNN_RADIUS2_SLACK 1.15

static void task_search(void *arg, int tid, int nth) {
  search_t *S = arg;
  const grid_t *g = S->g;
  int k = S->k;
  buffer_t b = {NULL, 0, 0, NULL};
  double T = S->t0, *bx2 = malloc(sizeof(double) * (size_t)g->dims[0]);
  if (!bx2) {
    S->failed[tid] = 1;
    goto cleanup;
  }
  for (karst_int_t blk = tid; blk * KNN_CELL_BLOCK < g->ncells; blk += nth) {
    if (karst_interrupted(S->ctx)) {
      S->failed[tid] = 2;
      goto cleanup;
    }
    karst_int_t c1 =
        (blk + 1) * KNN_CELL_BLOCK < g->ncells ? (blk + 1) * KNN_CELL_BLOCK : g->ncells;
    for (karst_int_t c = blk * KNN_CELL_BLOCK; c < c1; c++) {
      if (g->start[c] == g->start[c + 1]) continue;
      int64_t cc[3] = {c % g->dims[0], c / g->dims[0] % g->dims[1], c / g->dims[0] / g->dims[1]};
      for (karst_int_t s = g->start[c]; s < g->start[c + 1]; s++) {
        /* With m >= k points within T, the k nearest are among them (every
         * other point is farther than T); otherwise widen T. */
        for (;;) {
          if (!gather(g, s, cc, T, &b, bx2)) {
            S->failed[tid] = 1;
            goto cleanup;
          }
          if (b.n >= k) break;
          T = T > 0 ? 2 * T : g->h * g->h;
        }
        select_k(b.v, b.n, k);
        int32_t v = g->sidx[s];
        int32_t *out = S->nbr + (size_t)v * (size_t)k;
        for (int j = 0; j < k; j++)
          out[j] = b.v[j].i;
        S->kd2[v] = b.v[k - 1].d, S->kidx[v] = b.v[k - 1].i;
        T = KNN_RADIUS2_SLACK * b.v[k - 1].d;
      }
    }
  }
cleanup:
  free(b.v);
  free(b.d);
  free(bx2);
}

/**
 * Exact k nearest neighbours of every point on a uniform grid (see the file
 * comment; declared in graph_internal.h).
 * Time complexity: O(n) to build the grid, then O(k) cells and O(k log k)
 * per query for nearly uniform points such as a Poisson sampling; strongly
 * clustered points degrade towards O(n) per query, never the result.
 */
karst_error_t karst_i_knn(karst_ctx_t *ctx, const double *xyz, karst_int_t n, int k, int nthreads,
                          int32_t *nbr, double *kd2, int32_t *kidx) {
  grid_t g;
  memset(&g, 0, sizeof g);
  karst_error_t err = grid_build(ctx, &g, xyz, n, k);
  if (err != KARST_SUCCESS) goto cleanup;
  /* First radius: the k-th distance if the points filled their occupied
   * cells evenly, 4/3 π R³ ρ = k. */
  karst_int_t occupied = 0;
  for (karst_int_t c = 0; c < g.ncells; c++)
    occupied += g.start[c + 1] > g.start[c];
  double rho = (double)n / ((double)occupied * g.h * g.h * g.h);
  double r0 = cbrt(3.0 * k / (4.0 * M_PI * rho));
  search_t S = {ctx, &g, k, KNN_RADIUS2_SLACK * r0 * r0, nbr, kidx, kd2, {0}};
  karst_i_parallel_run(nthreads, task_search, &S);
  for (int t = 0; t < KARST_I_MAX_THREADS; t++) {
    if (S.failed[t] == 1) {
      err = karst_set_error(ctx, KARST_ENOMEM, "no memory for the neighbour search");
      goto cleanup;
    }
    if (S.failed[t] == 2) {
      err = karst_set_error(ctx, KARST_EINTERRUPTED, "neighbour search interrupted");
      goto cleanup;
    }
  }
  karst_progress(ctx, "neighbours", (double)n, (double)n);
cleanup:
  grid_destroy(&g);
  return err;
}
