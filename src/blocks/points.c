/* The points and the graph of a periodic tile (Paris et al. 2020, §4.1):
 * Poisson-disc sampling of the cube [0, s)³ on the torus, so that the
 * density has no seam across the faces, and the neighbour graph within the
 * graph radius under the minimum-image distance. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "blocks/blocks_internal.h"

/* Minimum-image difference b - a on the torus of side s, and the lattice
 * shift L with b + s L - a = that difference. */
static double wrap_diff(double a, double b, double s, int *L) {
  double d = b - a;
  *L = 0;
  if (d > 0.5 * s)
    d -= s, *L = -1;
  else if (d < -0.5 * s)
    d += s, *L = 1;
  return d;
}

static int64_t wrap_index(int64_t i, int64_t m) {
  i %= m;
  return i < 0 ? i + m : i;
}

/**
 * Periodic Poisson-disc sampling (dart throwing over a background grid, as
 * src/sampling/ does for the bedrock): the cube is cut into m³ cells of side
 * s/m <= r/√3, so each holds at most one point; each pass visits the empty
 * cells in a random order and throws one dart into each, kept when no point
 * lies within r under the minimum-image distance. Random sequential addition
 * reaches about 0.65 points per r³ after 8 passes.
 * @param passes dart passes (>= 1); @param rng the tile's sampling stream
 * @param xyz receives 3 n coordinates in [0, s)³ (malloc'd)
 * @return KARST_SUCCESS, KARST_EINVAL (r not within (0, s/2)), KARST_ERANGE
 *         (more than 2^27 cells), KARST_ENOMEM. Time: O(passes m³).
 */
karst_error_t karst_i_blocks_poisson(karst_ctx_t *ctx, double s, double r, int passes,
                                     karst_rng_t *rng, double **xyz, karst_int_t *n) {
  *xyz = NULL;
  *n = 0;
  if (!(s > 0) || !(r > 0) || !(r < 0.5 * s) || !isfinite(s))
    return karst_set_error(ctx, KARST_EINVAL,
                           "tile sampling: Poisson radius %g must be within (0, s/2) for a tile "
                           "of %g m",
                           r, s);
  int64_t m = (int64_t)floor(s * sqrt(3.0) / r);
  if (m < 1) m = 1;
  if ((double)m * m * m > (double)(1 << 27))
    return karst_set_error(ctx, KARST_ERANGE,
                           "tile sampling: %lld³ background cells for r = %g m in a %g m tile; "
                           "use a larger Poisson radius",
                           (long long)m, r, s);
  double cell = s / (double)m, r2 = r * r;
  int64_t nc = m * m * m, reach = (int64_t)ceil(r / cell);
  if (2 * reach + 1 > m) reach = (m - 1) / 2; /* small grids: every cell is a neighbour */
  int32_t *occ = malloc((size_t)nc * sizeof *occ);
  int64_t *order = malloc((size_t)nc * sizeof *order);
  double *pts = malloc((size_t)nc * 3 * sizeof *pts);
  /* neighbour cells that can hold a point closer than r (cell boxes nearer
   * than r), and the periodic index of every coordinate in [-reach, m + reach) */
  int64_t *nbr =
      malloc((size_t)(2 * reach + 1) * (2 * reach + 1) * (2 * reach + 1) * 3 * sizeof *nbr);
  int64_t *wrap = malloc((size_t)(m + 2 * reach) * sizeof *wrap);
  karst_error_t err = KARST_SUCCESS;
  if (!occ || !order || !pts || !nbr || !wrap) {
    err = karst_set_error(ctx, KARST_ENOMEM, "tile sampling: out of memory for %lld cells",
                          (long long)nc);
    goto cleanup;
  }
  int n_nbr = 0;
  for (int64_t dz = -reach; dz <= reach; dz++)
    for (int64_t dy = -reach; dy <= reach; dy++)
      for (int64_t dx = -reach; dx <= reach; dx++) {
        double g[3] = {(double)llabs(dx), (double)llabs(dy), (double)llabs(dz)}, d2 = 0;
        for (int a = 0; a < 3; a++)
          if (g[a] > 1) d2 += (g[a] - 1) * (g[a] - 1) * cell * cell;
        if (d2 >= r2) continue;
        nbr[3 * n_nbr] = dx, nbr[3 * n_nbr + 1] = dy, nbr[3 * n_nbr + 2] = dz;
        n_nbr++;
      }
  /* nearest cells first: a dart that fails (most do after the first pass)
   * meets its conflict early. Insertion sort of at most 125 offsets. */
  for (int i = 1; i < n_nbr; i++)
    for (int j = i; j > 0; j--) {
      int64_t *a = nbr + 3 * (j - 1), *b = nbr + 3 * j;
      int64_t da = llabs(a[0]) + llabs(a[1]) + llabs(a[2]),
              db = llabs(b[0]) + llabs(b[1]) + llabs(b[2]);
      if (da <= db) break;
      for (int k = 0; k < 3; k++) {
        int64_t t = a[k];
        a[k] = b[k], b[k] = t;
      }
    }
  for (int64_t i = 0; i < m + 2 * reach; i++)
    wrap[i] = wrap_index(i - reach, m);
  for (int64_t i = 0; i < nc; i++)
    occ[i] = -1;
  karst_int_t count = 0;
  for (int pass = 0; pass < passes; pass++) {
    int64_t ne = 0;
    for (int64_t i = 0; i < nc; i++)
      if (occ[i] < 0) order[ne++] = i;
    for (int64_t i = ne - 1; i > 0; i--) { /* Fisher–Yates */
      int64_t j = (int64_t)karst_rng_below(rng, (uint64_t)(i + 1));
      int64_t t = order[i];
      order[i] = order[j], order[j] = t;
    }
    for (int64_t e = 0; e < ne; e++) {
      int64_t c = order[e], ci[3] = {c % m, (c / m) % m, c / (m * m)};
      double p[3];
      for (int a = 0; a < 3; a++)
        p[a] = ((double)ci[a] + karst_rng_uniform(rng)) * cell;
      int ok = 1;
      for (int k = 0; k < n_nbr && ok; k++) {
        int64_t q =
            wrap[ci[0] + nbr[3 * k] + reach] +
            m * (wrap[ci[1] + nbr[3 * k + 1] + reach] + m * wrap[ci[2] + nbr[3 * k + 2] + reach]);
        if (occ[q] < 0) continue;
        const double *o = pts + 3 * occ[q];
        double d2 = 0;
        for (int a = 0; a < 3; a++) {
          int L;
          double d = wrap_diff(p[a], o[a], s, &L);
          d2 += d * d;
        }
        if (d2 < r2) ok = 0;
      }
      if (!ok) continue;
      memcpy(pts + 3 * count, p, sizeof p);
      occ[c] = (int32_t)count++;
    }
    if (karst_interrupted(ctx)) {
      err = karst_set_error(ctx, KARST_EINTERRUPTED, "tile sampling interrupted");
      goto cleanup;
    }
  }
  double *shrunk = realloc(pts, (size_t)(count ? count : 1) * 3 * sizeof *pts);
  if (shrunk) pts = shrunk;
  *xyz = pts;
  *n = count;
  pts = NULL;
cleanup:
  free(occ);
  free(order);
  free(pts);
  free(nbr);
  free(wrap);
  return err;
}

static int edge_cmp(const void *pa, const void *pb) {
  const karst_i_edge_t *a = pa, *b = pb;
  if (a->u != b->u) return a->u < b->u ? -1 : 1;
  if (a->v != b->v) return a->v < b->v ? -1 : 1;
  for (int k = 0; k < 3; k++)
    if (a->L[k] != b->L[k]) return a->L[k] < b->L[k] ? -1 : 1;
  return 0;
}

void karst_i_blocks_sort_edges(karst_i_edge_t *e, karst_int_t n) {
  if (n > 1) qsort(e, (size_t)n, sizeof *e, edge_cmp);
}

static karst_error_t push_edge(karst_ctx_t *ctx, karst_i_edge_t **e, karst_int_t *n,
                               karst_int_t *cap, int32_t u, int32_t v, const int L[3]) {
  if (*n == *cap) {
    karst_int_t c = *cap ? 2 * *cap : 1024;
    karst_i_edge_t *q = realloc(*e, (size_t)c * sizeof *q);
    if (!q) return karst_set_error(ctx, KARST_ENOMEM, "tile graph: out of memory");
    *e = q, *cap = c;
  }
  karst_i_edge_t *x = &(*e)[(*n)++];
  memset(x, 0, sizeof *x);
  x->u = u, x->v = v;
  for (int a = 0; a < 3; a++)
    x->L[a] = (int8_t)L[a];
  x->fam[0] = x->fam[1] = -1;
  return KARST_SUCCESS;
}

/**
 * Periodic radius graph by a uniform grid of g³ cells of side s/g >= radius
 * (g >= 3, so the 27 cells around a point are distinct): each pair closer
 * than @p radius (minimum image) once, with u < v, sorted by (u, v).
 * @return KARST_SUCCESS, KARST_EINVAL (radius not within (0, s/3)),
 *         KARST_ENOMEM. Time: O(n × points per 27 cells).
 */
karst_error_t karst_i_blocks_radius_graph(karst_ctx_t *ctx, const double *xyz, karst_int_t n,
                                          double s, double radius, karst_i_edge_t **edges,
                                          karst_int_t *n_edges) {
  *edges = NULL;
  *n_edges = 0;
  if (!(radius > 0) || !(radius < s / 3))
    return karst_set_error(ctx, KARST_EINVAL,
                           "tile graph: radius %g must be within (0, s/3) for a tile of %g m",
                           radius, s);
  int64_t g = (int64_t)floor(s / radius);
  if (g > 1024) g = 1024;
  int64_t nc = g * g * g;
  karst_int_t *start = calloc((size_t)nc + 1, sizeof *start), *idx = NULL, *cell = NULL;
  karst_i_edge_t *e = NULL;
  karst_int_t ne = 0, cap = 0;
  karst_error_t err = KARST_SUCCESS;
  idx = malloc((size_t)(n ? n : 1) * sizeof *idx);
  cell = malloc((size_t)(n ? n : 1) * sizeof *cell);
  if (!start || !idx || !cell) {
    err = karst_set_error(ctx, KARST_ENOMEM, "tile graph: out of memory");
    goto cleanup;
  }
  for (karst_int_t i = 0; i < n; i++) {
    int64_t c[3];
    for (int a = 0; a < 3; a++) {
      c[a] = (int64_t)floor(xyz[3 * i + a] / s * (double)g);
      if (c[a] < 0) c[a] = 0;
      if (c[a] >= g) c[a] = g - 1;
    }
    cell[i] = c[0] + g * (c[1] + g * c[2]);
    start[cell[i] + 1]++;
  }
  for (int64_t c = 0; c < nc; c++)
    start[c + 1] += start[c];
  {
    karst_int_t *fill = malloc((size_t)nc * sizeof *fill);
    if (!fill) {
      err = karst_set_error(ctx, KARST_ENOMEM, "tile graph: out of memory");
      goto cleanup;
    }
    memcpy(fill, start, (size_t)nc * sizeof *fill);
    for (karst_int_t i = 0; i < n; i++)
      idx[fill[cell[i]]++] = i;
    free(fill);
  }
  double r2 = radius * radius;
  for (karst_int_t i = 0; i < n; i++) {
    int64_t c = cell[i], ci[3] = {c % g, (c / g) % g, c / (g * g)};
    for (int dz = -1; dz <= 1; dz++)
      for (int dy = -1; dy <= 1; dy++)
        for (int dx = -1; dx <= 1; dx++) {
          int64_t k = wrap_index(ci[0] + dx, g) +
                      g * (wrap_index(ci[1] + dy, g) + g * wrap_index(ci[2] + dz, g));
          for (karst_int_t q = start[k]; q < start[k + 1]; q++) {
            karst_int_t j = idx[q];
            if (j <= i) continue;
            int L[3];
            double d2 = 0;
            for (int a = 0; a < 3; a++) {
              double d = wrap_diff(xyz[3 * i + a], xyz[3 * j + a], s, &L[a]);
              d2 += d * d;
            }
            if (d2 < r2 && (err = push_edge(ctx, &e, &ne, &cap, (int32_t)i, (int32_t)j, L)))
              goto cleanup;
          }
        }
  }
  karst_i_blocks_sort_edges(e, ne);
  *edges = e;
  *n_edges = ne;
  e = NULL;
cleanup:
  free(start);
  free(idx);
  free(cell);
  free(e);
  return err;
}

/**
 * Exact segment–disc intersection (Paris et al. 2020, §4.1: an edge is kept
 * when no disc meets it). With h the signed heights of a and b above the
 * disc's plane, the closed segment meets the plane when h_a and h_b do not
 * have the same strict sign, at t = h_a / (h_a - h_b); it meets the disc when
 * that point lies within the radius. A segment in the plane (h_a = h_b = 0)
 * is not cut: it does not cross the fracture.
 * Time complexity: O(1).
 */
int karst_i_blocks_segment_disc(const double a[3], const double b[3], const double c[3],
                                const double n[3], double radius, double *t) {
  double ha = 0, hb = 0;
  for (int k = 0; k < 3; k++)
    ha += n[k] * (a[k] - c[k]), hb += n[k] * (b[k] - c[k]);
  if ((ha > 0 && hb > 0) || (ha < 0 && hb < 0) || (ha == 0 && hb == 0)) return 0;
  double tt = ha / (ha - hb), d2 = 0;
  for (int k = 0; k < 3; k++) {
    double x = a[k] + tt * (b[k] - a[k]) - c[k];
    d2 += x * x;
  }
  if (!(d2 <= radius * radius)) return 0;
  if (t) *t = tt;
  return 1;
}
