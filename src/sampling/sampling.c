/* Adaptive Poisson-sphere sampling of the bedrock (Paris et al. 2021, §4.1).
 *
 * Method: grid-accelerated dart throwing with a bounded number of darts per
 * cell (in the spirit of Dunbar & Humphreys 2006 and Gamito & Maddock 2009,
 * "Accurate multidimensional Poisson-disk sampling"): the background grid has
 * cells of size r/√3, whose diagonal is r, so a cell holds at most one sample
 * of radius r and a conflict can only come from the 117 cells whose distance
 * to the cell is below r. Cells are visited in a random order, for
 * KARST_SAMPLING_DART_PASSES passes, one dart per empty cell per pass, which
 * makes the whole sampling O(cells) = O(volume / r^3); a cell leaves the
 * passes once a sample's ball covers it. The fill, most of the work, runs
 * on ctx->nthreads threads by tiles of cells with their own random streams
 * (see "Fill" below), with a result independent of the thread count.
 *
 * Two radii: feature samples (key points, prescribed paths, horizons, water
 * table, permeable volumes) keep sampling.feature_radius r_f from one another
 * and live in a sparse hash grid (they occupy thin layers or small volumes);
 * fill samples keep sampling.fill_radius r_c from one another and
 * min(r_f, r_c) from feature samples, and live in a dense grid over the box.
 */
#include <assert.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "core/math_internal.h"
#include "core/memory_internal.h"
#include "core/parallel_internal.h"
#include "geology/geology_internal.h"
#include "karst/sampling.h"

/* Largest background grid (cells) that may be allocated: 2^31 (8 GiB of
 * indices) is far beyond what max_samples allows; it only guards overflow. */
#define MAX_GRID_CELLS ((double)INT32_MAX)

/* Cells of the 5 x 5 x 5 block around a fill cell that come closer than the fill radius to it:
 * all but the centre and the 8 corners (see karst_sampling_run). */
#define FILL_OFFSETS 116
/* The first offsets, nearest first, that include every cell whose sample can cover the cell
 * (cell_covered): the 26 at (|di|, |dj|, |dk|) <= 1, rounded up to whole groups of four (see
 * fill_conflict). */
#define FILL_COVER_OFFSETS 28

/* ------------------------------------------------------------------------ */
/* Column grid of feature samples                                            */
/* ------------------------------------------------------------------------ */
/* Feature samples fill thin layers (horizons, water table) or small volumes,
 * so they are kept per vertical column of the background grid: a dense 2-D
 * array of chain heads (4 bytes per column) and one chain per column. A
 * conflict query walks the 5 x 5 columns around the point, comparing z
 * first. */
typedef struct cgrid {
  double cell, origin[3];
  int64_t dims[3];
  int32_t *head; /* per column (i + dims[0] j), -1 = empty */
  double *xyz;   /* entries */
  int32_t *next;
  size_t n, ncap;
  /* t[a][i], 0 < i < dims[a] (a = 0, 1): the least coordinate x with cgrid_coord(x, a) >= i, so
   * that a coordinate's column near a known one is found by comparisons (cgrid_coord_near); NULL
   * when the grid has more than CGRID_MAX_THRESHOLDS columns along the axis */
  double *t[2];
} cgrid_t;

#define CGRID_MAX_THRESHOLDS ((int64_t)1 << 22)

static int64_t cgrid_coord(const cgrid_t *g, double x, int a) {
  double f = floor((x - g->origin[a]) / g->cell);
  return f < 0 ? 0 : (f >= (double)g->dims[a] ? g->dims[a] - 1 : (int64_t)f);
}

static int cgrid_init(cgrid_t *g, double cell, const double origin[3], const int64_t dims[3]) {
  memset(g, 0, sizeof *g);
  g->cell = cell;
  memcpy(g->origin, origin, sizeof g->origin);
  memcpy(g->dims, dims, sizeof g->dims);
  size_t cols = (size_t)(dims[0] * dims[1]);
  g->head = malloc(sizeof(int32_t) * cols);
  if (!g->head) return 0;
  memset(g->head, 0xff, sizeof(int32_t) * cols);
  /* cgrid_coord(x, a) is nondecreasing in x (rounded subtraction and division by a positive
   * number are monotone, and so are floor and the clamps), so it is the number of thresholds at
   * or below x: each is found from the nominal boundary origin + i cell, a few ulps off at most,
   * by stepping to the neighbouring doubles until the column changes. */
  for (int a = 0; a < 2; a++) {
    if (dims[a] > CGRID_MAX_THRESHOLDS) continue;
    double *t = malloc(sizeof(double) * (size_t)dims[a]);
    if (!t) continue; /* cgrid_coord_near then divides */
    t[0] = -INFINITY;
    for (int64_t i = 1; i < dims[a]; i++) {
      double x = origin[a] + (double)i * cell;
      while (cgrid_coord(g, x, a) < i)
        x = nextafter(x, INFINITY);
      for (double y; (y = nextafter(x, -INFINITY), cgrid_coord(g, y, a) >= i);)
        x = y;
      t[i] = x;
    }
    g->t[a] = t;
  }
  return 1;
}

static void cgrid_destroy(cgrid_t *g) {
  free(g->head), free(g->xyz), free(g->next), free(g->t[0]), free(g->t[1]);
  memset(g, 0, sizeof *g);
}

/* cgrid_coord(x, a) for a = 0, 1, found from column `near` by comparing x with the thresholds
 * (the same value: see cgrid_init). The sampler's darts ask for columns within two of their
 * own, where this takes two or three comparisons instead of a division (about 40 instructions
 * a dart fewer in the feature layers, callgrind). */
static inline int64_t cgrid_coord_near(const cgrid_t *g, double x, int a, int64_t near) {
  const double *t = g->t[a];
  if (!t) return cgrid_coord(g, x, a);
  int64_t i = near;
  while (i > 0 && x < t[i])
    i--;
  while (i < g->dims[a] - 1 && x >= t[i + 1])
    i++;
  return i;
}

static int cgrid_insert(cgrid_t *g, const double p[3]) {
  if (g->n == g->ncap) {
    size_t nc = g->ncap ? 2 * g->ncap : 1024;
    double *xyz = karst_i_realloc_large(g->xyz, sizeof(double) * 3 * g->n, sizeof(double) * 3 * nc);
    if (!xyz) return 0;
    g->xyz = xyz;
    int32_t *next = karst_i_realloc_large(g->next, sizeof(int32_t) * g->n, sizeof(int32_t) * nc);
    if (!next) return 0;
    g->next = next, g->ncap = nc;
  }
  int64_t col = cgrid_coord(g, p[0], 0) + g->dims[0] * cgrid_coord(g, p[1], 1);
  int32_t e = (int32_t)g->n++;
  memcpy(g->xyz + 3 * e, p, 3 * sizeof(double));
  g->next[e] = g->head[col];
  g->head[col] = e;
  return 1;
}

/* Room for `extra` more entries, so that entries can be written at
 * reserved slots without reallocation (by several threads). */
static int cgrid_reserve(cgrid_t *g, size_t extra) {
  if (g->n + extra <= g->ncap) return 1;
  size_t nc = g->n + extra;
  double *xyz = karst_i_realloc_large(g->xyz, sizeof(double) * 3 * g->n, sizeof(double) * 3 * nc);
  if (!xyz) return 0;
  g->xyz = xyz;
  int32_t *next = karst_i_realloc_large(g->next, sizeof(int32_t) * g->n, sizeof(int32_t) * nc);
  if (!next) return 0;
  g->next = next, g->ncap = nc;
  return 1;
}

/* Entry e (reserved, e < ncap) holds p, linked into p's column. */
static void cgrid_put(cgrid_t *g, int32_t e, const double p[3]) {
  int64_t col = cgrid_coord(g, p[0], 0) + g->dims[0] * cgrid_coord(g, p[1], 1);
  memcpy(g->xyz + 3 * e, p, 3 * sizeof(double));
  g->next[e] = g->head[col];
  g->head[col] = e;
}

/* Whether cell (i, j, k) already holds a feature sample. */
static int cgrid_occupied(const cgrid_t *g, int64_t i, int64_t j, int64_t k) {
  for (int32_t e = g->head[i + g->dims[0] * j]; e >= 0; e = g->next[e])
    if (cgrid_coord(g, g->xyz[3 * e + 2], 2) == k) return 1;
  return 0;
}

/* An entry closer than r to p, or NULL; p lies in or near column (ci, cj), which only speeds
 * up finding the columns of p ± r (cgrid_coord_near). */
static const double *cgrid_conflict_near(const cgrid_t *g, const double p[3], double r, int64_t ci,
                                         int64_t cj) {
  if (g->n == 0) return NULL;
  int64_t i0 = cgrid_coord_near(g, p[0] - r, 0, ci), i1 = cgrid_coord_near(g, p[0] + r, 0, ci);
  int64_t j0 = cgrid_coord_near(g, p[1] - r, 1, cj), j1 = cgrid_coord_near(g, p[1] + r, 1, cj);
  double r2 = r * r;
  for (int64_t j = j0; j <= j1; j++)
    for (int64_t i = i0; i <= i1; i++)
      for (int32_t e = g->head[i + g->dims[0] * j]; e >= 0; e = g->next[e]) {
        const double *q = g->xyz + 3 * e;
        double dz = q[2] - p[2];
        if (dz * dz >= r2) continue;
        double dx = q[0] - p[0], dy = q[1] - p[1];
        if (dx * dx + dy * dy + dz * dz < r2) return q;
      }
  return NULL;
}

/* An entry closer than r to p, or NULL. */
static const double *cgrid_conflict(const cgrid_t *g, const double p[3], double r) {
  return cgrid_conflict_near(g, p, r, cgrid_coord(g, p[0], 0), cgrid_coord(g, p[1], 1));
}

/* The feature samples sorted by column (a CSR snapshot of the grid), for the fill: the feature
 * samples are all placed before the fill starts, and the fill's darts only ask whether one
 * lies within r, so the columns of one grid row within reach are one contiguous run. */
typedef struct ccsr {
  int32_t *start; /* per column + 1: column c holds entries [start[c], start[c + 1]) */
  double *xyz;
} ccsr_t;

static int ccsr_build(ccsr_t *c, const cgrid_t *g) {
  size_t cols = (size_t)(g->dims[0] * g->dims[1]), n = 0;
  c->start = malloc(sizeof(int32_t) * (cols + 1));
  if (!c->start) return 0;
  for (size_t col = 0; col < cols; col++) {
    c->start[col] = (int32_t)n;
    for (int32_t e = g->head[col]; e >= 0; e = g->next[e])
      n++;
  }
  c->start[cols] = (int32_t)n;
  c->xyz = malloc(sizeof(double) * 3 * (n + 1));
  if (!c->xyz) return 0;
  for (size_t col = 0, w = 0; col < cols; col++)
    for (int32_t e = g->head[col]; e >= 0; e = g->next[e], w++)
      memcpy(c->xyz + 3 * w, g->xyz + 3 * e, 3 * sizeof(double));
  return 1;
}

static void ccsr_destroy(ccsr_t *c) {
  free(c->start), free(c->xyz);
  memset(c, 0, sizeof *c);
}

/* Whether an entry of g lies closer than r to p: cgrid_conflict's columns and distance test, on
 * the snapshot c of g. */
static int ccsr_conflict(const ccsr_t *c, const cgrid_t *g, const double p[3], double r) {
  int64_t i0 = cgrid_coord(g, p[0] - r, 0), i1 = cgrid_coord(g, p[0] + r, 0);
  int64_t j0 = cgrid_coord(g, p[1] - r, 1), j1 = cgrid_coord(g, p[1] + r, 1);
  double r2 = r * r;
  for (int64_t j = j0; j <= j1; j++) {
    const double *q = c->xyz + 3 * (int64_t)c->start[i0 + g->dims[0] * j];
    const double *end = c->xyz + 3 * (int64_t)c->start[i1 + 1 + g->dims[0] * j];
    for (; q < end; q += 3) {
      double dz = q[2] - p[2];
      if (dz * dz >= r2) continue;
      double dx = q[0] - p[0], dy = q[1] - p[1];
      if (dx * dx + dy * dy + dz * dz < r2) return 1;
    }
  }
  return 0;
}

/* ------------------------------------------------------------------------ */
/* The sampler                                                               */
/* ------------------------------------------------------------------------ */
typedef struct sampler {
  karst_ctx_t *ctx;
  const karst_geology_t *geo;
  const karst_scenario_t *sc; /* the geology's */
  karst_rng_t *rng;
  karst_samples_t *s;
  double rf, rc, rm; /* feature radius, fill radius, min of both */
  double lo[3], hi[3];
  cgrid_t feat;
  ccsr_t feat_cols; /* feat by column, for the fill (sample_fill) */
  /* dense fill grid with a border of 2 empty cells on every side, so that
   * neighbours are found by adding a precomputed linear offset */
  double cc;
  /* per axis a and fill cell index i: corner[a][i] = lo[a] + i cc (i <= cd[a]), and the
   * cell's extent clipped to the box, [clo, chi] = [max(lo, corner[i]), min(hi, corner[i + 1])]:
   * the values cell_box would compute, read from a table by the fill's darts */
  double *corner[3], *clo[3], *chi[3];
  int64_t cd[3], pd[3]; /* cells per axis, without and with the border */
  int32_t *fill;        /* per cell: -1 empty, else its sample's slot in the fill's array */
  unsigned char *near;  /* 1 if a feature sample lies within rm of the cell */
  int n_off;
  int64_t
      delta[FILL_OFFSETS]; /* linear offsets of the cells that can hold a conflicting fill sample */
  const char *stage;       /* for messages */
  int excluding;           /* the geology has exclusion zones or insoluble strata */
} sampler_t;

/* Linear index of fill cell (i, j, k) in the bordered grid. */
static int64_t pidx(const sampler_t *S, int64_t i, int64_t j, int64_t k) {
  return (i + 2) + S->pd[0] * ((j + 2) + S->pd[1] * (k + 2));
}

/* The error when the samples would exceed sampling.max_samples. */
static karst_error_t too_many_samples(const sampler_t *S) {
  return karst_set_error(S->ctx, KARST_ERANGE,
                         "sampling needs more than sampling.max_samples = %lld samples "
                         "(reached while placing %s samples); increase fill_radius or "
                         "feature_radius, shrink the domain, or raise max_samples",
                         (long long)S->sc->sampling.max_samples, S->stage);
}

/* Append p to the samples and, for a feature sample, mark the fill cells a
 * later fill dart would have to check against it (p is already in the
 * feature grid, or is put there by add_sample). */
static karst_error_t record_sample(sampler_t *S, const double p[3], karst_sample_source_t src) {
  if (S->s->n >= S->sc->sampling.max_samples) return too_many_samples(S);
  if (karst_samples_add(S->s, p, src) != KARST_SUCCESS)
    return karst_set_error(S->ctx, KARST_ENOMEM, "no memory for %lld samples",
                           (long long)S->s->n + 1);
  if (src == KARST_SAMPLE_FILL || src == KARST_SAMPLE_POINTS || !S->near) return KARST_SUCCESS;
  int64_t lo[3], hi[3];
  for (int a = 0; a < 3; a++) {
    double l = floor((p[a] - S->rm - S->lo[a]) / S->cc),
           h = floor((p[a] + S->rm - S->lo[a]) / S->cc);
    lo[a] = l < 0 ? 0 : (int64_t)l;
    hi[a] = h >= (double)S->cd[a] ? S->cd[a] - 1 : (int64_t)h;
  }
  for (int64_t k = lo[2]; k <= hi[2]; k++)
    for (int64_t j = lo[1]; j <= hi[1]; j++)
      for (int64_t i = lo[0]; i <= hi[0]; i++)
        S->near[pidx(S, i, j, k)] = 1;
  return KARST_SUCCESS;
}

static karst_error_t add_sample(sampler_t *S, const double p[3], karst_sample_source_t src) {
  if (src != KARST_SAMPLE_FILL && src != KARST_SAMPLE_POINTS && !cgrid_insert(&S->feat, p))
    return karst_set_error(S->ctx, KARST_ENOMEM, "no memory for the feature sample grid");
  return record_sample(S, p, src);
}

static void shuffle(karst_rng_t *rng, int64_t *v, size_t n) {
  for (size_t i = n; i > 1; i--) {
    size_t j = (size_t)karst_rng_below(rng, (uint64_t)i);
    int64_t t = v[i - 1];
    v[i - 1] = v[j], v[j] = t;
  }
}

typedef struct cells {
  int64_t *v;
  size_t n, cap;
} cells_t;

static int cells_push(cells_t *c, int64_t x) {
  if (c->n == c->cap) {
    size_t nc = c->cap ? 2 * c->cap : 4096;
    int64_t *v = realloc(c->v, sizeof(int64_t) * nc);
    if (!v) return 0;
    c->v = v, c->cap = nc;
  }
  c->v[c->n++] = x;
  return 1;
}

/* A region sampled at the feature radius: a layer |z − L(x, y)| <= band
 * around a horizon (or a water table), or the permeable volume. */
typedef struct region {
  karst_sample_source_t src;
  const karst_i_surf_t *layer; /* NULL for the permeable volume */
  double band;
} region_t;

static int region_contains(const sampler_t *S, const region_t *R, const double p[3]) {
  if (R->layer) return fabs(p[2] - karst_i_surf_z(R->layer, p[0], p[1])) <= R->band;
  return karst_permeability_eval(&S->sc->permeability, p) < S->sc->sampling.permeable_threshold;
}

/* Conservative bounding box of {p : node value < t} ("all" = whole space). */
typedef struct aabb {
  double lo[3], hi[3];
  int empty;
} aabb_t;

static aabb_t aabb_all(void) {
  aabb_t b = {{-INFINITY, -INFINITY, -INFINITY}, {INFINITY, INFINITY, INFINITY}, 0};
  return b;
}
static aabb_t aabb_none(void) {
  aabb_t b = {{0, 0, 0}, {0, 0, 0}, 1};
  return b;
}

static aabb_t perm_region(const karst_perm_node_t *n, double bg, double t) {
  if (n->kind == KARST_PERM_SPHERE || n->kind == KARST_PERM_STRATUM) {
    if (bg < t) return aabb_all();
    if (!(n->resistance < t)) return aabb_none();
    aabb_t b = aabb_all();
    if (n->kind == KARST_PERM_SPHERE) {
      double r = n->radius + (n->falloff > 0 ? n->falloff : 0.0);
      for (int a = 0; a < 3; a++)
        b.lo[a] = n->center[a] - r, b.hi[a] = n->center[a] + r;
    } else {
      b.lo[2] = n->bottom, b.hi[2] = n->top;
    }
    return b;
  }
  if (n->n_children == 0) return bg < t ? aabb_all() : aabb_none();
  aabb_t acc = perm_region(&n->children[0], bg, t);
  for (int i = 1; i < n->n_children; i++) {
    aabb_t c = perm_region(&n->children[i], bg, t);
    if (n->kind == KARST_PERM_INTERSECTION) { /* max < t iff all children < t */
      if (acc.empty || c.empty) return aabb_none();
      for (int a = 0; a < 3; a++)
        acc.lo[a] = karst_i_fmax(acc.lo[a], c.lo[a]), acc.hi[a] = karst_i_fmin(acc.hi[a], c.hi[a]);
      for (int a = 0; a < 3; a++)
        if (acc.lo[a] > acc.hi[a]) return aabb_none();
    } else { /* min (union) or weighted mean (blend) < t needs some child < t */
      if (c.empty) continue;
      if (acc.empty) {
        acc = c;
        continue;
      }
      for (int a = 0; a < 3; a++)
        acc.lo[a] = karst_i_fmin(acc.lo[a], c.lo[a]), acc.hi[a] = karst_i_fmax(acc.hi[a], c.hi[a]);
    }
  }
  return acc;
}

/* Feature-grid cells (i, j, k) overlapping the region's bounds, in the box
 * and not entirely above the terrain, as linear keys i + nx (j + ny k),
 * grouped by tiles of FILL_TILE^2 columns (in tile order; see
 * sample_region). Each non-empty tile is recorded in *tiles. */
#define FILL_TILE 8
typedef struct ftile {
  size_t first, n; /* its remaining cells: cells[first .. first + n) */
  int colour;      /* parities of its tile coordinates */
  int32_t placed;  /* its samples, in feature-grid slots base + first .. */
} ftile_t;

static karst_error_t region_cells(sampler_t *S, const region_t *R, cells_t *out,
                                  ftile_t **tiles_out, size_t *n_tiles) {
  const cgrid_t *g = &S->feat;
  aabb_t box = aabb_all();
  ftile_t *tiles = NULL;
  karst_error_t err = KARST_SUCCESS;
  *tiles_out = NULL, *n_tiles = 0;
  if (!R->layer) {
    const karst_permeability_t *pm = &S->sc->permeability;
    box = pm->root
              ? perm_region(pm->root, pm->background, S->sc->sampling.permeable_threshold)
              : (pm->background < S->sc->sampling.permeable_threshold ? aabb_all() : aabb_none());
    if (box.empty) return KARST_SUCCESS;
  }
  int64_t lo[3], hi[3];
  for (int a = 0; a < 3; a++) {
    double l = karst_i_fmax(box.lo[a], S->lo[a]), h = karst_i_fmin(box.hi[a], S->hi[a]);
    if (l > h) return KARST_SUCCESS;
    lo[a] = cgrid_coord(g, l, a), hi[a] = cgrid_coord(g, h, a);
  }
  double limit = (double)KARST_SAMPLING_MAX_CELLS_PER_SAMPLE * (double)S->sc->sampling.max_samples;
  int64_t nti = (hi[0] - lo[0]) / FILL_TILE + 1, ntj = (hi[1] - lo[1]) / FILL_TILE + 1;
  tiles = malloc(sizeof(ftile_t) * (size_t)(nti * ntj));
  if (!tiles) {
    err = karst_set_error(S->ctx, KARST_ENOMEM, "no memory for the %s sampling cells", S->stage);
    goto cleanup;
  }
  for (int64_t t = 0; t < nti * ntj; t++) {
    size_t first = out->n;
    int64_t ti = lo[0] + t % nti * FILL_TILE, tj = lo[1] + t / nti * FILL_TILE;
    for (int64_t j = tj; j < tj + FILL_TILE && j <= hi[1]; j++)
      for (int64_t i = ti; i < ti + FILL_TILE && i <= hi[0]; i++) {
        double x0 = karst_i_fmax(S->lo[0], g->origin[0] + i * g->cell);
        double x1 = karst_i_fmin(S->hi[0], g->origin[0] + (i + 1) * g->cell);
        double y0 = karst_i_fmax(S->lo[1], g->origin[1] + j * g->cell);
        double y1 = karst_i_fmin(S->hi[1], g->origin[1] + (j + 1) * g->cell);
        double tlo, ztop;
        karst_i_surf_range(&S->geo->terrain, x0, x1, y0, y1, &tlo, &ztop);
        double zlo = karst_i_fmax(S->lo[2], box.lo[2]),
               zhi = karst_i_fmin(karst_i_fmin(S->hi[2], box.hi[2]), ztop);
        if (R->layer) {
          double llo, lhi;
          karst_i_surf_range_bound(R->layer, x0, x1, y0, y1, &llo, &lhi);
          if (!isfinite(llo) || !isfinite(lhi)) continue;
          zlo = karst_i_fmax(zlo, llo - R->band), zhi = karst_i_fmin(zhi, lhi + R->band);
        }
        if (zlo > zhi) continue;
        for (int64_t k = cgrid_coord(g, zlo, 2); k <= cgrid_coord(g, zhi, 2); k++) {
          if ((double)out->n >= limit) {
            err =
                karst_set_error(S->ctx, KARST_ERANGE,
                                "the %s samples need more than %.0f grid cells of %g m "
                                "(%d per allowed sample, sampling.max_samples = %lld): they "
                                "would exceed max_samples; increase feature_radius or max_samples",
                                S->stage, limit, g->cell, KARST_SAMPLING_MAX_CELLS_PER_SAMPLE,
                                (long long)S->sc->sampling.max_samples);
            goto cleanup;
          }
          if (!cells_push(out, i + g->dims[0] * (j + g->dims[1] * k))) {
            err = karst_set_error(S->ctx, KARST_ENOMEM, "no memory for the %s sampling cells",
                                  S->stage);
            goto cleanup;
          }
        }
      }
    if (out->n > first)
      tiles[(*n_tiles)++] =
          (ftile_t){first, out->n - first, (int)(t % nti % 2 + 2 * (t / nti % 2)), 0};
  }
cleanup:
  if (err != KARST_SUCCESS) free(tiles), tiles = NULL, *n_tiles = 0;
  *tiles_out = tiles;
  return err;
}

/* (i, j, k) of the linear key u = i + d0 (j + d1 k) of a grid of fewer than 2^32 cells, by 32-bit
 * divisions, several times faster than 64-bit ones (the feature layers' darts, the fill's). */
static inline void key_cell32(uint32_t u, uint32_t d0, uint32_t d1, int64_t c[3]) {
  uint32_t jk = u / d0;
  c[0] = (int64_t)(u - jk * d0), c[1] = (int64_t)(jk % d1), c[2] = (int64_t)(jk / d1);
}

/* The part of cell (i, j, k) of a grid within [zlo, zhi] and the box, where
 * its darts fall; 0 when empty. */
static inline __attribute__((always_inline)) int cell_box(const sampler_t *S,
                                                          const double origin[3], double cell,
                                                          const int64_t c[3], double zlo,
                                                          double zhi, double lo[3], double hi[3]) {
  for (int a = 0; a < 3; a++) {
    lo[a] = karst_i_fmax(S->lo[a], origin[a] + c[a] * cell);
    hi[a] = karst_i_fmin(S->hi[a], origin[a] + (c[a] + 1) * cell);
  }
  lo[2] = karst_i_fmax(lo[2], zlo), hi[2] = karst_i_fmin(hi[2], zhi);
  for (int a = 0; a < 3; a++)
    if (lo[a] > hi[a]) return 0;
  return 1;
}

/* Whether every corner of the box [lo, hi] is closer than r to q (the ball
 * is convex: then every later dart in the box conflicts with q). */
static int box_covered(const double lo[3], const double hi[3], const double q[3], double r) {
  for (int m = 0; m < 8; m++) {
    double d2 = 0;
    for (int a = 0; a < 3; a++) {
      double x = ((m >> a) & 1 ? hi[a] : lo[a]) - q[a];
      d2 += x * x;
    }
    if (!(d2 < r * r)) return 0;
  }
  return 1;
}

/* Feature regions are sampled like the fill (see "Fill" below): tiles of
 * FILL_TILE^2 columns coloured by the parities of their tile coordinates (4
 * colours), the tiles of one colour concurrently. A dart reads the columns
 * within 2 cells of its own (r_f spans less than 2 cells of r_f/√3) and
 * writes its own column's chain; same-colour tiles are a tile apart. Each
 * tile writes its samples into feature-grid slots reserved for it (one per
 * cell of the tile: at most one sample per cell) and draws from its own
 * stream, so the result does not depend on the thread count; the samples
 * are appended to the sample set in tile order at the end. */
typedef struct region_job {
  sampler_t *S;
  const region_t *R;
  ftile_t *tiles;
  int64_t *cells;
  const size_t *group; /* the tiles to process now */
  size_t n_group;
  int32_t base; /* feature-grid slot of cell 0 of the list */
  uint64_t seed;
  int pass; /* -1: shuffle the cell lists */
  int interrupted;
  int keys32; /* every cell key is below 2^32 */
} region_job_t;

static void region_tile_pass(region_job_t *J, size_t t) {
  sampler_t *S = J->S;
  const region_t *R = J->R;
  cgrid_t *g = &S->feat;
  ftile_t *T = &J->tiles[t];
  int64_t *cells = J->cells + T->first;
  karst_rng_t rng;
  karst_rng_derive(&rng, J->seed, (uint64_t)(J->pass + 1), (uint64_t)t);
  if (J->pass < 0) {
    shuffle(&rng, cells, T->n);
    return;
  }
  size_t w = 0;
  for (size_t q = 0; q < T->n; q++) {
    int64_t key = cells[q], c[3];
    if (J->keys32) {
      key_cell32((uint32_t)key, (uint32_t)g->dims[0], (uint32_t)g->dims[1], c);
    } else {
      c[0] = key % g->dims[0], c[1] = key / g->dims[0] % g->dims[1];
      c[2] = key / g->dims[0] / g->dims[1];
    }
    if (cgrid_occupied(g, c[0], c[1], c[2])) continue; /* at most one feature sample per cell */
    double zlo = -INFINITY, zhi = INFINITY, p[3];
    if (R->layer) {
      double x0 = g->origin[0] + c[0] * g->cell, y0 = g->origin[1] + c[1] * g->cell;
      karst_i_surf_range_bound(R->layer, x0, x0 + g->cell, y0, y0 + g->cell, &zlo, &zhi);
      if (!isfinite(zlo) || !isfinite(zhi)) continue;
      zlo -= R->band, zhi += R->band;
    }
    double blo[3], bhi[3];
    if (!cell_box(S, g->origin, g->cell, c, zlo, zhi, blo, bhi)) continue;
    cells[w++] = key;
    for (int a = 0; a < 3; a++)
      p[a] = karst_rng_uniform_range(&rng, blo[a], bhi[a]);
    if (!region_contains(S, R, p) || !karst_geology_in_bedrock(S->geo, p)) continue;
    const double *e = cgrid_conflict_near(g, p, S->rf, c[0], c[1]);
    if (e) {
      if (box_covered(blo, bhi, e, S->rf)) w--; /* never again */
      continue;
    }
    w--; /* taken */
    cgrid_put(g, J->base + (int32_t)T->first + T->placed++, p);
  }
  T->n = w;
}

static void task_region(void *arg, int tid, int nth) {
  region_job_t *J = arg;
  for (size_t i = (size_t)tid; i < J->n_group; i += (size_t)nth) {
    if ((i & 63) == 0 && karst_interrupted(J->S->ctx)) {
      J->interrupted = 1;
      return;
    }
    region_tile_pass(J, J->group[i]);
  }
}

static karst_error_t sample_region(sampler_t *S, const region_t *R) {
  cells_t cells = {0};
  ftile_t *tiles = NULL;
  size_t ntiles = 0, *group = NULL, gstart[5] = {0};
  cgrid_t *g = &S->feat;
  int nth = S->ctx && S->ctx->nthreads > 0 ? S->ctx->nthreads : 1;
  karst_error_t err = region_cells(S, R, &cells, &tiles, &ntiles);
  if (err != KARST_SUCCESS || cells.n == 0) goto cleanup;
  if ((double)g->n + (double)cells.n >= (double)INT32_MAX || !cgrid_reserve(g, cells.n) ||
      !(group = malloc(sizeof(size_t) * ntiles))) {
    err = karst_set_error(S->ctx, KARST_ENOMEM, "no memory for the %s sampling cells", S->stage);
    goto cleanup;
  }
  size_t ng = 0;
  for (int col = 0; col < 4; col++) {
    gstart[col] = ng;
    for (size_t t = 0; t < ntiles; t++)
      if (tiles[t].colour == col) group[ng++] = t;
  }
  gstart[4] = ng;
  region_job_t J = {S,
                    R,
                    tiles,
                    cells.v,
                    group,
                    ntiles,
                    (int32_t)g->n,
                    karst_rng_u64(S->rng),
                    -1,
                    0,
                    (double)g->dims[0] * (double)g->dims[1] * (double)g->dims[2] <= 4294967295.0};
  /* The reserved slots belong to the grid from now on (unused ones are
   * never linked into a column). */
  g->n += cells.n;
  karst_i_parallel_run(nth, task_region, &J);
  for (int pass = 0; pass < KARST_SAMPLING_DART_PASSES; pass++) {
    int64_t order[4] = {0, 1, 2, 3};
    shuffle(S->rng, order, 4);
    for (int o = 0; o < 4; o++) {
      J.group = group + gstart[order[o]], J.n_group = gstart[order[o] + 1] - gstart[order[o]];
      J.pass = pass;
      karst_i_parallel_run(nth, task_region, &J);
      if (J.interrupted) {
        err = karst_set_error(S->ctx, KARST_EINTERRUPTED, "sampling interrupted");
        goto cleanup;
      }
      double placed = (double)S->s->n;
      for (size_t t = 0; t < ntiles; t++)
        placed += tiles[t].placed;
      if (placed > (double)S->sc->sampling.max_samples) {
        err = too_many_samples(S);
        goto cleanup;
      }
    }
  }
  for (size_t t = 0; t < ntiles; t++)
    for (int32_t e = 0; e < tiles[t].placed; e++) {
      const double *p = g->xyz + 3 * (J.base + (int64_t)tiles[t].first + e);
      if ((err = record_sample(S, p, R->src)) != KARST_SUCCESS) goto cleanup;
    }
cleanup:
  free(cells.v);
  free(tiles);
  free(group);
  return err;
}

/* ------------------------------------------------------------------------ */
/* Fill: parallel dart throwing by tiles of cells                            */
/* ------------------------------------------------------------------------ */
/* The fill grid is cut into tiles of FILL_TILE^3 cells, coloured by the
 * parities of their tile coordinates (8 colours). A dart reads the cells
 * within 2 cells of its own and writes only its own cell, so two tiles of
 * one colour, a whole tile apart, never see each other's samples: the tiles
 * of a colour are processed concurrently, the colours one after the other,
 * in a random order drawn anew for each pass (the phase groups of Wei 2008,
 * "Parallel Poisson disk sampling", with tiles for memory locality). Each
 * tile draws from its own stream derived from (seed, pass, tile), so the
 * samples do not depend on the thread count. Each tile keeps its samples in
 * its own list (fill cells hold the index in that list) and the lists are
 * appended in tile order at the end. */
typedef struct tile {
  size_t first, n; /* its remaining cells: fill_cells[first .. first + n) */
  int32_t ns;      /* its samples, in slots first + [0, ns) of the job's xyz */
} tile_t;

typedef struct fill_job {
  sampler_t *S;
  tile_t *tiles;
  double *xyz;    /* the samples: tile t's in slots tiles[t].first + [0, tiles[t].ns) (at most one
                    per cell), so that a cell's index in the fill grid names the slot */
  int64_t *cells; /* bordered cell ids of all tiles, grouped by tile */
  int64_t nt[3];  /* tiles per axis */
  const int64_t *group; /* the tiles to process now */
  size_t n_group;
  uint64_t seed;
  int pass; /* -1: shuffle the cell lists */
  int interrupted;
} fill_job_t;

/* The fill sample in cells d[o0 .. o1) around f (in the offsets' order) first found closer
 * than sqrt(r2) to p, or NULL. Four cells at a time: most are empty (-1), and four empty cells
 * AND to a negative number. */
static inline const double *fill_first(const fill_job_t *J, const int32_t *restrict f,
                                       const int64_t *restrict d, int o0, int o1, const double p[3],
                                       double r2) {
  for (int o = o0; o < o1; o += 4) {
    int32_t e4[4] = {f[d[o]], f[d[o + 1]], f[d[o + 2]], f[d[o + 3]]};
    if ((e4[0] & e4[1] & e4[2] & e4[3]) < 0) continue;
    for (int i = 0; i < 4; i++) {
      if (e4[i] < 0) continue;
      const double *q = J->xyz + 3 * (int64_t)e4[i];
      double dx = q[0] - p[0], dy = q[1] - p[1], dz = q[2] - p[2];
      if (dx * dx + dy * dy + dz * dz < r2) return q;
    }
  }
  return NULL;
}

/* Conflict of a fill dart p in cell c (bordered id `id`): NULL and *feat = 0 when p is free;
 * else a conflicting fill sample, or NULL and *feat = 1 for a feature sample. The conflicting
 * fill sample returned decides whether the cell leaves the passes (cell_covered), so among the
 * cells that can hold a sample covering c it is the first in the offsets' order; beyond them any
 * conflict only keeps the cell, which is what a feature conflict does too, so the feature test,
 * the likelier to find a conflict near a feature layer, comes first there.
 *
 * Why the first FILL_COVER_OFFSETS cells are the only ones that matter: a cell is covered by q
 * when its farthest corner is closer than rc = √3 cc to q. Along an axis where q's cell is d != 0
 * cells away, q is at least |d| cc from the cell's far face (and at least cc / 2 from one face
 * where d = 0); in a cell with some |d| = 2 that is >= 2 cc along that axis alone,
 * (2 cc)^2 = 4 cc^2 > 3 cc^2 = rc^2, far beyond any rounding. So only the 26 cells with every
 * |d| <= 1 can cover c, and the offsets are sorted by d^2: they are the first 26. */
static const double *fill_conflict(const fill_job_t *J, const double p[3], int64_t id, int *feat) {
  const sampler_t *S = J->S;
  double r2 = S->rc * S->rc;
  *feat = 0;
  const int32_t *restrict f = S->fill + id;
  const int64_t *restrict d = S->delta;
  _Static_assert(FILL_OFFSETS % 4 == 0 && FILL_COVER_OFFSETS % 4 == 0,
                 "fill_conflict reads the offsets four at a time");
  const double *q = fill_first(J, f, d, 0, FILL_COVER_OFFSETS, p, r2);
  if (q) return q;
  if (S->near[id] && ccsr_conflict(&S->feat_cols, &S->feat, p, S->rm)) {
    *feat = 1;
    return NULL;
  }
  return fill_first(J, f, d, FILL_COVER_OFFSETS, FILL_OFFSETS, p, r2);
}

/* Whether the ball of radius rc around q covers cell c entirely (every
 * corner strictly inside; the ball is convex): no later dart can succeed.
 * Only the farthest corner is tested: per axis the larger square of the two
 * corner offsets, the same floating-point values as for every corner, and
 * rounded sums are monotonic, so its squared distance is the largest of the
 * eight as computed corner by corner. */
static int cell_covered(const sampler_t *S, const int64_t c[3], const double q[3]) {
  double d2 = 0;
  for (int a = 0; a < 3; a++) {
    double x0 = S->corner[a][c[a]] - q[a];
    double x1 = S->corner[a][c[a] + 1] - q[a];
    double s0 = x0 * x0, s1 = x1 * x1;
    d2 += s0 > s1 ? s0 : s1;
  }
  return d2 < S->rc * S->rc;
}

static int cmp_off(const void *a, const void *b) {
  const int *x = a, *y = b;
  int dx = x[0] * x[0] + x[1] * x[1] + x[2] * x[2], dy = y[0] * y[0] + y[1] * y[1] + y[2] * y[2];
  return (dx > dy) - (dx < dy);
}

/* One pass over one tile: a dart in each of its remaining cells, in the
 * tile's (shuffled) order; cells that can no longer take a sample leave. */
static void fill_tile_pass(fill_job_t *J, int64_t t) {
  sampler_t *S = J->S;
  tile_t *T = &J->tiles[t];
  karst_rng_t rng;
  karst_rng_derive(&rng, J->seed, (uint64_t)(J->pass + 1), (uint64_t)t);
  int64_t *cells = J->cells + T->first;
  if (J->pass < 0) {
    shuffle(&rng, cells, T->n);
    return;
  }
  size_t w = 0;
  for (size_t q = 0; q < T->n; q++) {
    int64_t id = cells[q];
    /* ids and dimensions are below 2^31 (MAX_GRID_CELLS): 32-bit divisions */
    int64_t c[3];
    key_cell32((uint32_t)id, (uint32_t)S->pd[0], (uint32_t)S->pd[1], c);
    for (int a = 0; a < 3; a++)
      c[a] -= 2; /* the border */
    double p[3];
    if (S->clo[0][c[0]] > S->chi[0][c[0]] || S->clo[1][c[1]] > S->chi[1][c[1]] ||
        S->clo[2][c[2]] > S->chi[2][c[2]])
      continue; /* as for cell_box: an empty box takes no dart */
    for (int a = 0; a < 3; a++)
      p[a] = karst_rng_uniform_range(&rng, S->clo[a][c[a]], S->chi[a][c[a]]);
    if (!(p[2] < karst_i_surf_z(&S->geo->terrain, p[0], p[1]))) {
      cells[w++] = id;
      continue;
    }
    if (S->excluding && karst_geology_exclusion_at(S->geo, p, NULL) != KARST_EXCLUDED_NONE) {
      cells[w++] = id; /* an exclusion zone holds no sample; the cell may take one elsewhere */
      continue;
    }
    int feat;
    const double *e = fill_conflict(J, p, id, &feat);
    if (e && cell_covered(S, c, e)) continue; /* never again */
    if (e || feat) {
      cells[w++] = id;
      continue;
    }
    int32_t slot = (int32_t)T->first + T->ns++;
    memcpy(J->xyz + 3 * (int64_t)slot, p, sizeof p);
    S->fill[id] = slot;
  }
  T->n = w; /* keep the cells that may still take a sample, in the same order */
}

static void task_fill(void *arg, int tid, int nth) {
  fill_job_t *J = arg;
  for (size_t i = (size_t)tid; i < J->n_group; i += (size_t)nth) {
    if ((i & 63) == 0 && karst_interrupted(J->S->ctx)) {
      J->interrupted = 1;
      return;
    }
    fill_tile_pass(J, J->group[i]);
  }
}

/* The fill's samples appended to the samples in tile order, each tile's in the order it drew
 * them (what adding them one by one would give), tiles copied by the threads from a prefix sum
 * of their counts into storage of large pages grown once. */
typedef struct append_job {
  const fill_job_t *J;
  const size_t *at; /* per tile: its first sample's index in the samples */
  size_t ntiles;
  karst_samples_t *s;
} append_job_t;

static void task_append(void *arg, int tid, int nth) {
  const append_job_t *A = arg;
  for (size_t t = A->ntiles * (size_t)tid / (size_t)nth;
       t < A->ntiles * (size_t)(tid + 1) / (size_t)nth; t++) {
    const tile_t *T = &A->J->tiles[t];
    memcpy(A->s->xyz + 3 * A->at[t], A->J->xyz + 3 * T->first, sizeof(double) * 3 * (size_t)T->ns);
    memset(A->s->source + A->at[t], KARST_SAMPLE_FILL, (size_t)T->ns);
  }
}

static karst_error_t append_fill(sampler_t *S, const fill_job_t *J, size_t ntiles) {
  karst_samples_t *s = S->s;
  size_t *at = malloc(sizeof(size_t) * (ntiles + 1));
  if (!at) return karst_set_error(S->ctx, KARST_ENOMEM, "no memory for the fill samples");
  size_t n = (size_t)s->n;
  for (size_t t = 0; t < ntiles; t++)
    at[t] = n, n += (size_t)J->tiles[t].ns;
  karst_error_t err = KARST_SUCCESS;
  if ((double)n > (double)S->sc->sampling.max_samples) {
    err = too_many_samples(S);
    goto cleanup;
  }
  if (n > (size_t)s->cap) {
    double *xyz =
        karst_i_realloc_large(s->xyz, sizeof(double) * 3 * (size_t)s->n, sizeof(double) * 3 * n);
    unsigned char *so = xyz ? realloc(s->source, n) : NULL;
    if (xyz) s->xyz = xyz;
    if (!so) {
      err = karst_set_error(S->ctx, KARST_ENOMEM, "no memory for %zu samples", n);
      goto cleanup;
    }
    s->source = so, s->cap = (karst_int_t)n;
  }
  append_job_t A = {J, at, ntiles, s};
  int nth = S->ctx && S->ctx->nthreads > 0 ? S->ctx->nthreads : 1;
  karst_i_parallel_run(n - (size_t)s->n < ((size_t)1 << 16) ? 1 : nth, task_append, &A);
  s->n = (karst_int_t)n;
cleanup:
  free(at);
  return err;
}

static karst_error_t sample_fill(sampler_t *S) {
  fill_job_t J;
  memset(&J, 0, sizeof J);
  J.S = S;
  int64_t *ktop = NULL, *group = NULL;
  size_t *gstart = NULL;
  karst_error_t err = KARST_SUCCESS;
  double limit = (double)KARST_SAMPLING_MAX_CELLS_PER_SAMPLE * (double)S->sc->sampling.max_samples;
  int nth = S->ctx && S->ctx->nthreads > 0 ? S->ctx->nthreads : 1;
  /* Active cells of each column: those starting below the highest terrain point. */
  ktop = malloc(sizeof(int64_t) * (size_t)(S->cd[0] * S->cd[1]));
  for (int a = 0; a < 3; a++)
    J.nt[a] = (S->cd[a] + FILL_TILE - 1) / FILL_TILE;
  size_t ntiles = (size_t)(J.nt[0] * J.nt[1] * J.nt[2]);
  J.tiles = calloc(ntiles, sizeof(tile_t));
  group = malloc(sizeof(int64_t) * ntiles);
  gstart = malloc(sizeof(size_t) * 9);
  if (!ktop || !J.tiles || !group || !gstart) goto nomem;
  double total = 0;
  for (int64_t j = 0; j < S->cd[1]; j++)
    for (int64_t i = 0; i < S->cd[0]; i++) {
      double x0 = S->lo[0] + i * S->cc, x1 = karst_i_fmin(S->hi[0], x0 + S->cc);
      double y0 = S->lo[1] + j * S->cc, y1 = karst_i_fmin(S->hi[1], y0 + S->cc);
      double tlo, ttop;
      karst_i_surf_range(&S->geo->terrain, x0, x1, y0, y1, &tlo, &ttop);
      double ztop = karst_i_fmin(S->hi[2], ttop);
      int64_t k = 0;
      while (k < S->cd[2] && S->lo[2] + k * S->cc < ztop)
        k++;
      ktop[i + S->cd[0] * j] = k;
      total += (double)k;
    }
  if (total > limit) {
    err = karst_set_error(S->ctx, KARST_ERANGE,
                          "the fill samples need %.0f grid cells of %g m, more than %d per "
                          "allowed sample (sampling.max_samples = %lld): they would exceed "
                          "max_samples; increase fill_radius or max_samples",
                          total, S->cc, KARST_SAMPLING_MAX_CELLS_PER_SAMPLE,
                          (long long)S->sc->sampling.max_samples);
    goto cleanup;
  }
  if (!ccsr_build(&S->feat_cols, &S->feat)) goto nomem;
  J.cells = karst_i_alloc_large(sizeof(int64_t) * ((size_t)total + 1));
  J.xyz = karst_i_alloc_large(sizeof(double) * 3 * ((size_t)total + 1));
  if (!J.cells || !J.xyz) goto nomem;
  /* Cell lists by tile; tiles grouped by colour (in tile order within one). */
  size_t nc = 0, ng = 0;
  for (int col = 0; col < 8; col++) {
    gstart[col] = ng;
    for (size_t t = 0; t < ntiles; t++) {
      int64_t ti = (int64_t)t % J.nt[0], tj = (int64_t)t / J.nt[0] % J.nt[1],
              tk = (int64_t)t / J.nt[0] / J.nt[1];
      if ((ti & 1) + 2 * (tj & 1) + 4 * (tk & 1) != col) continue;
      J.tiles[t].first = nc;
      for (int64_t k = tk * FILL_TILE; k < (tk + 1) * FILL_TILE && k < S->cd[2]; k++)
        for (int64_t j = tj * FILL_TILE; j < (tj + 1) * FILL_TILE && j < S->cd[1]; j++)
          for (int64_t i = ti * FILL_TILE; i < (ti + 1) * FILL_TILE && i < S->cd[0]; i++)
            if (k < ktop[i + S->cd[0] * j]) J.cells[nc++] = pidx(S, i, j, k);
      J.tiles[t].n = nc - J.tiles[t].first;
      if (J.tiles[t].n > 0) group[ng++] = (int64_t)t;
    }
  }
  gstart[8] = ng;
  /* One draw from the stage's stream seeds every tile's stream. */
  J.seed = karst_rng_u64(S->rng);
  J.group = group, J.n_group = ng, J.pass = -1;
  karst_i_parallel_run(nth, task_fill, &J);
  for (int pass = 0; pass < KARST_SAMPLING_DART_PASSES; pass++) {
    karst_progress(S->ctx, "sampling", pass, KARST_SAMPLING_DART_PASSES);
    int64_t order[8] = {0, 1, 2, 3, 4, 5, 6, 7};
    shuffle(S->rng, order, 8);
    for (int o = 0; o < 8; o++) {
      int col = (int)order[o];
      J.group = group + gstart[col], J.n_group = gstart[col + 1] - gstart[col], J.pass = pass;
      karst_i_parallel_run(nth, task_fill, &J);
      if (J.interrupted) {
        err = karst_set_error(S->ctx, KARST_EINTERRUPTED, "sampling interrupted");
        goto cleanup;
      }
      double placed = (double)S->s->n;
      for (size_t t = 0; t < ntiles; t++)
        placed += J.tiles[t].ns;
      if (placed > (double)S->sc->sampling.max_samples) {
        err = too_many_samples(S);
        goto cleanup;
      }
    }
  }
  err = append_fill(S, &J, ntiles);
  goto cleanup;
nomem:
  err = karst_set_error(S->ctx, KARST_ENOMEM, "no memory for the fill sampling cells");
cleanup:
  free(J.tiles);
  free(J.xyz);
  free(J.cells);
  free(group);
  free(gstart);
  free(ktop);
  ccsr_destroy(&S->feat_cols);
  return err;
}

/* The fill given as a point cloud (sampling.points) instead of drawn: each point of the file, in
 * the file's order, that lies in the bedrock and no closer than min(r_f, r_c) to a feature sample
 * (the distance a fill dart keeps from them) becomes a sample. The file's points are not tested
 * against one another: the cloud is the user's. */
static karst_error_t sample_points(sampler_t *S) {
  const karst_sampling_t *sp = &S->sc->sampling;
  karst_error_t err = KARST_SUCCESS;
  karst_int_t outside = 0, near = 0;
  if (!ccsr_build(&S->feat_cols, &S->feat)) {
    ccsr_destroy(&S->feat_cols);
    return karst_set_error(S->ctx, KARST_ENOMEM, "no memory for the feature sample columns");
  }
  for (karst_int_t i = 0; i < sp->n_points; i++) {
    const double *p = sp->points_xyz + 3 * i;
    if ((i & 65535) == 0 && karst_interrupted(S->ctx)) {
      err = karst_set_error(S->ctx, KARST_EINTERRUPTED, "sampling interrupted");
      break;
    }
    if (!karst_geology_in_bedrock(S->geo, p)) {
      outside++;
      continue;
    }
    if (ccsr_conflict(&S->feat_cols, &S->feat, p, S->rm)) {
      near++;
      continue;
    }
    if ((err = add_sample(S, p, KARST_SAMPLE_POINTS)) != KARST_SUCCESS) break;
  }
  ccsr_destroy(&S->feat_cols);
  if (err == KARST_SUCCESS)
    karst_log(S->ctx, KARST_LOG_INFO,
              "sampling.points: %lld of the %lld points of %s kept, %lld outside the bedrock, "
              "%lld closer than %g m to a feature sample",
              (long long)(sp->n_points - outside - near), (long long)sp->n_points, sp->points,
              (long long)outside, (long long)near, S->rm);
  return err;
}

/* Spread the low 21 bits of x so that two zero bits separate them. */
static uint64_t spread3(uint64_t x) {
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffULL;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}

/* The Morton order of one run of samples (morton_order), on the threads: the keys, then a
 * stable LSD radix sort of (key, index) pairs on the low 64 bits, 8 bits per pass, then the
 * coordinates gathered in that order. Each thread takes a contiguous part of the run; in a pass
 * it counts its part's digits, and its elements of each digit go after those of the threads
 * before it, so the sort stays stable and the order does not depend on the thread count. */
typedef struct morton_job {
  const karst_scenario_t *sc;
  const double *src; /* all samples' coordinates */
  double *dst;       /* the ordered coordinates */
  uint64_t *key[2];
  int32_t *idx[2];
  karst_int_t b, m; /* the run: samples b .. b + m − 1 */
  size_t *cnt;      /* 256 per thread: digit counts, then each digit's next slot */
  int phase, shift, cur;
} morton_job_t;

/* Runs shorter than this are ordered on one thread (starting threads would cost more). */
#define MORTON_MIN_PARALLEL ((karst_int_t)1 << 16)

enum { MORTON_KEYS, MORTON_COUNT, MORTON_SCATTER, MORTON_GATHER };

static void task_morton(void *arg, int tid, int nth) {
  morton_job_t *J = arg;
  const karst_int_t i0 = J->m * tid / nth, i1 = J->m * (tid + 1) / nth;
  uint64_t *k = J->key[J->cur];
  int32_t *ix = J->idx[J->cur];
  size_t *cnt = J->cnt + 256 * (size_t)tid;
  const int shift = J->shift;
  switch (J->phase) {
  case MORTON_KEYS: {
    const double scale = 2097151.0; /* 2^21 - 1 cells per axis */
    const double *lo = J->sc->domain_min, *hi = J->sc->domain_max;
    for (karst_int_t i = i0; i < i1; i++) {
      const double *p = J->src + 3 * (J->b + i);
      uint64_t c = 0;
      for (int a = 0; a < 3; a++) {
        double f = (p[a] - lo[a]) / (hi[a] - lo[a]);
        c |= spread3((uint64_t)(karst_i_fmin(karst_i_fmax(f, 0.0), 1.0) * scale)) << a;
      }
      k[i] = c, ix[i] = (int32_t)(J->b + i);
    }
    break;
  }
  case MORTON_COUNT:
    memset(cnt, 0, 256 * sizeof *cnt);
    for (karst_int_t i = i0; i < i1; i++)
      cnt[(k[i] >> shift) & 255]++;
    break;
  case MORTON_SCATTER: {
    uint64_t *k1 = J->key[1 - J->cur];
    int32_t *ix1 = J->idx[1 - J->cur];
    for (karst_int_t i = i0; i < i1; i++) {
      size_t d = cnt[(k[i] >> shift) & 255]++;
      k1[d] = k[i], ix1[d] = ix[i];
    }
    break;
  }
  default: /* MORTON_GATHER */
    for (karst_int_t i = i0; i < i1; i++)
      memcpy(J->dst + 3 * (J->b + i), J->src + 3 * (karst_int_t)ix[i], 3 * sizeof(double));
  }
}

/* Order each run of samples of one source (key points excepted: they keep
 * the scenario's order) along a Morton (Z-order) curve of the domain box.
 * Dart throwing visits cells in a random order; a space-filling order makes
 * the neighbour search, the graph rows and the paths stage cache-friendly.
 * Stable radix sort (ties keep the draw order): O(n), deterministic, the same
 * on any number of threads (task_morton). */
static karst_error_t morton_order(karst_ctx_t *ctx, const karst_scenario_t *sc,
                                  karst_samples_t *s) {
  karst_int_t n = s->n;
  uint64_t *key = karst_i_alloc_large(sizeof(uint64_t) * 2 * (size_t)n + 1);
  int32_t *idx = karst_i_alloc_large(sizeof(int32_t) * 2 * (size_t)n + 1);
  /* The ordered coordinates go to a new array of large pages: the searches read them at random
   * (the A* heuristic), and the grown array they come from is not. */
  double *xyz = karst_i_alloc_large(sizeof(double) * 3 * (size_t)(n > 0 ? n : 1));
  int nth = ctx && ctx->nthreads > 0 ? ctx->nthreads : 1;
  if (nth > KARST_I_MAX_THREADS) nth = KARST_I_MAX_THREADS;
  size_t *cnt = malloc(sizeof(size_t) * 256 * (size_t)nth);
  if (!key || !idx || !xyz || !cnt) {
    free(key), free(idx), free(xyz), free(cnt);
    return karst_set_error(ctx, KARST_ENOMEM, "no memory to order %lld samples", (long long)n);
  }
  memcpy(xyz, s->xyz, sizeof(double) * 3 * (size_t)s->n_key_points);
  morton_job_t J = {sc, s->xyz, xyz, {key, key + n}, {idx, idx + n}, 0, 0, cnt, 0, 0, 0};
  for (karst_int_t b = s->n_key_points; b < n;) {
    karst_int_t e = b;
    while (e < n && s->source[e] == s->source[b])
      e++;
    J.b = b, J.m = e - b, J.cur = 0;
    const int T = J.m < MORTON_MIN_PARALLEL ? 1 : nth;
    J.phase = MORTON_KEYS;
    karst_i_parallel_run(T, task_morton, &J);
    for (J.shift = 0; J.shift < 64; J.shift += 8) {
      J.phase = MORTON_COUNT;
      karst_i_parallel_run(T, task_morton, &J);
      size_t at = 0; /* digit by digit, thread by thread: each (thread, digit)'s first slot */
      for (int d = 0; d < 256; d++)
        for (int t = 0; t < T; t++) {
          size_t c = cnt[256 * (size_t)t + (size_t)d];
          cnt[256 * (size_t)t + (size_t)d] = at;
          at += c;
        }
      J.phase = MORTON_SCATTER;
      karst_i_parallel_run(T, task_morton, &J);
      J.cur = 1 - J.cur;
    }
    J.phase = MORTON_GATHER; /* 8 passes: the sorted pairs are back in key[0], idx[0] */
    karst_i_parallel_run(T, task_morton, &J);
    b = e;
  }
  free(cnt);
  free(key), free(idx), free(s->xyz);
  s->xyz = xyz;
  /* The capacity is now that of the new array (later additions grow it again). */
  unsigned char *so = realloc(s->source, (size_t)(n > 0 ? n : 1));
  if (so) s->source = so;
  s->cap = n > 0 ? n : 1;
  return KARST_SUCCESS;
}

static karst_error_t check_scenario(karst_ctx_t *ctx, const karst_geology_t *geo) {
  const karst_scenario_t *sc = geo->sc;
  const karst_sampling_t *sp = &sc->sampling;
  for (int a = 0; a < 3; a++)
    if (!isfinite(sc->domain_min[a]) || !isfinite(sc->domain_max[a]) ||
        !(sc->domain_min[a] < sc->domain_max[a]))
      return karst_set_error(ctx, KARST_EINVAL,
                             "domain: axis %c must have finite min < max, got [%g, %g]", "xyz"[a],
                             sc -> domain_min[a], sc -> domain_max[a]);
  if (!(isfinite(sp->fill_radius) && sp->fill_radius > 0))
    return karst_set_error(ctx, KARST_EINVAL, "sampling.fill_radius must be > 0, got %g",
                           sp->fill_radius);
  if (!(isfinite(sp->feature_radius) && sp->feature_radius > 0))
    return karst_set_error(ctx, KARST_EINVAL, "sampling.feature_radius must be > 0, got %g",
                           sp->feature_radius);
  if (!(isfinite(sp->feature_band) && sp->feature_band >= 0))
    return karst_set_error(ctx, KARST_EINVAL, "sampling.feature_band must be >= 0, got %g",
                           sp->feature_band);
  if (!(sp->permeable_threshold >= 0 && sp->permeable_threshold <= 1))
    return karst_set_error(ctx, KARST_EINVAL,
                           "sampling.permeable_threshold must be within [0, 1], got %g",
                           sp->permeable_threshold);
  if (sp->max_samples < 1 || sp->max_samples >= INT32_MAX)
    return karst_set_error(ctx, KARST_EINVAL,
                           "sampling.max_samples must be within [1, %d), got %lld", INT32_MAX,
                           (long long)sp->max_samples);
  for (int h = 0; h < sc->n_horizons; h++) {
    const karst_horizon_t *H = &sc->horizons[h];
    if (!(isfinite(H->radius) && H->radius > 0) || (!H->path && !isfinite(H->elevation)) ||
        !(H->dip >= 0 && H->dip < 90))
      return karst_set_error(ctx, KARST_EINVAL,
                             "horizon %d: radius must be > 0 and dip within [0, 90), got radius "
                             "%g, dip %g, elevation %g",
                             h + 1, H->radius, H->dip, H->elevation);
  }
  double bottom, top;
  karst_i_surf_range(&geo->terrain, sc->domain_min[0], sc->domain_max[0], sc->domain_min[1],
                     sc->domain_max[1], &bottom, &top);
  if (!(top > sc->domain_min[2]))
    return karst_set_error(ctx, KARST_EINVAL,
                           "the domain box (z from %g to %g m) lies entirely above the terrain "
                           "(highest terrain point over the box: %g m): there is no bedrock to "
                           "sample",
                           sc->domain_min[2], sc->domain_max[2], top);
  for (int i = 0; i < sc->n_key_points; i++) {
    const karst_keypoint_t *k = &sc->key_points[i];
    const double *p = k->p;
    if (karst_geology_in_bedrock(geo, p)) continue;
    int inbox = isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]);
    for (int a = 0; inbox && a < 3; a++)
      inbox = p[a] >= sc->domain_min[a] && p[a] <= sc->domain_max[a];
    if (!inbox)
      return karst_set_error(ctx, KARST_EINVAL,
                             "key point '%s' (%g, %g, %g) is outside the domain box", k->name, p[0],
                             p[1], p[2]);
    double h = karst_geology_terrain(geo, p[0], p[1]);
    if (p[2] > h)
      return karst_set_error(ctx, KARST_EINVAL,
                             "key point '%s' (%g, %g, %g) is above the terrain (terrain at %g m)",
                             k->name, p[0], p[1], p[2], h);
    return karst_set_error(ctx, KARST_EINVAL,
                           "key point '%s' (%g, %g, %g) is in an exclusion zone or an insoluble "
                           "stratum",
                           k->name, p[0], p[1], p[2]);
  }
  if (sc->n_key_points > sp->max_samples)
    return karst_set_error(ctx, KARST_ERANGE, "%d key points exceed sampling.max_samples = %lld",
                           sc->n_key_points, (long long)sp->max_samples);
  return KARST_SUCCESS;
}

/**
 * Adaptive Poisson-sphere sampling of the bedrock (Paris et al. 2021, §4.1,
 * Fig. 5), in this order, each sample tagged by its source:
 *  1. the key points, exactly and in order (samples 0 .. n_key_points-1);
 *  2. points along each prescribed path's straight segment, evenly spaced at
 *     >= feature_radius, so that low-cost edges exist there (§4.2);
 *  3. feature-radius Poisson samples within ±feature_band of each inception
 *     horizon, then of each spring's water table (once per distinct table);
 *  4. feature-radius Poisson samples where the resistance π is below
 *     sampling.permeable_threshold;
 *     (3 and 4 each only when sampling.refine names them: horizons, water_table,
 *     permeability; all three by default);
 *  5. fill samples at fill_radius elsewhere; or, with sampling.points, the points of that
 *     file that lie in the bedrock and no closer than min(r_f, r_c) to a feature sample.
 * Within each source the samples are then ordered along a Morton curve
 * (cache locality for the graph and path stages).
 * Only points in the bedrock are kept: inside the domain box, strictly below
 * the terrain, outside every exclusion zone and insoluble stratum.
 * Every random draw comes from @p rng or from streams derived from one draw
 * of it (same stream => same samples, for any ctx->nthreads).
 * @param ctx context (errors, progress, interrupt).
 * @param geo the geology of the realisation (validated here: radii, domain, key points).
 * @param rng the random stream of this stage.
 * @param out initialised sample set, replaced on success, unchanged on failure.
 * @return KARST_SUCCESS; KARST_EINVAL for an invalid scenario (e.g. a domain
 *         entirely above the terrain, a key point outside the bedrock);
 *         KARST_ERANGE when sampling.max_samples would be exceeded;
 *         KARST_ENOMEM; KARST_EINTERRUPTED.
 * Time complexity: O(V / r_c^3 + feature volume / r_f^3) with
 * KARST_SAMPLING_DART_PASSES darts per background cell, each checking O(1)
 * neighbouring cells; the fill is divided among ctx->nthreads threads.
 */
karst_error_t karst_sampling_run(karst_ctx_t *ctx, const karst_geology_t *geo, karst_rng_t *rng,
                                 karst_samples_t *out) {
  karst_samples_t s;
  karst_samples_init(&s);
  sampler_t S;
  memset(&S, 0, sizeof S);
  karst_error_t err = check_scenario(ctx, geo);
  if (err != KARST_SUCCESS) return err;
  const karst_scenario_t *sc = geo->sc;
  S.ctx = ctx, S.geo = geo, S.sc = sc, S.rng = rng, S.s = &s;
  S.excluding = sc->n_exclusions > 0 || geo->n_insoluble > 0;
  S.rf = sc->sampling.feature_radius;
  S.rc = sc->sampling.fill_radius;
  S.rm = karst_i_fmin(S.rf, S.rc);
  memcpy(S.lo, sc->domain_min, sizeof S.lo);
  memcpy(S.hi, sc->domain_max, sizeof S.hi);

  /* Grids: cells of r/√3 so that a cell's diagonal is r. */
  int64_t fd[3];
  double ncells_fill = 1.0, ncells_feat = 1.0;
  S.cc = S.rc / sqrt(3.0);
  double fcell = S.rf / sqrt(3.0);
  for (int a = 0; a < 3; a++) {
    double ext = S.hi[a] - S.lo[a];
    double nc = karst_i_fmax(1.0, ceil(ext / S.cc)), nf = karst_i_fmax(1.0, ceil(ext / fcell));
    ncells_fill *= nc + 4, ncells_feat *= nf;
    S.cd[a] = (int64_t)karst_i_fmin(nc, 1e18), fd[a] = (int64_t)karst_i_fmin(nf, 1e18);
    S.pd[a] = S.cd[a] + 4;
  }
  /* A point cloud (sampling.points) replaces the fill: no fill grid then. */
  const int fill = sc->sampling.points_xyz == NULL;
  if (fill && ncells_fill > MAX_GRID_CELLS) {
    err = karst_set_error(ctx, KARST_ERANGE,
                          "the domain box needs %.3g fill grid cells of %g m, more than %.0f: "
                          "increase sampling.fill_radius (%g m) or shrink the domain",
                          ncells_fill, S.cc, MAX_GRID_CELLS, S.rc);
    goto cleanup;
  }
  if ((double)fd[0] * (double)fd[1] > MAX_GRID_CELLS || ncells_feat > 4e18) {
    err = karst_set_error(ctx, KARST_ERANGE,
                          "sampling.feature_radius = %g m is too small for the domain box: "
                          "%.3g grid columns of %g m, more than %.0f",
                          S.rf, (double)fd[0] * (double)fd[1], fcell, MAX_GRID_CELLS);
    goto cleanup;
  }
  size_t nfill = fill ? (size_t)ncells_fill : 0;
  if (fill) {
    S.fill = karst_i_alloc_large(sizeof(int32_t) * nfill);
    S.near = karst_i_calloc_large(nfill, 1);
  }
  if ((fill && (!S.fill || !S.near)) || !cgrid_init(&S.feat, fcell, S.lo, fd)) {
    err = karst_set_error(ctx, KARST_ENOMEM, "no memory for a sampling grid of %.0f cells",
                          ncells_fill);
    goto cleanup;
  }
  if (fill) memset(S.fill, 0xff, sizeof(int32_t) * nfill);
  for (int a = 0; a < 3 && fill; a++) {
    size_t m = (size_t)S.cd[a] + 1;
    S.corner[a] = malloc(3 * m * sizeof(double));
    if (!S.corner[a]) {
      err = karst_set_error(ctx, KARST_ENOMEM, "no memory for a sampling grid of %.0f cells",
                            ncells_fill);
      goto cleanup;
    }
    S.clo[a] = S.corner[a] + m, S.chi[a] = S.corner[a] + 2 * m;
    for (int64_t i = 0; i <= S.cd[a]; i++) /* the expressions of cell_box and cell_covered */
      S.corner[a][i] = S.lo[a] + (double)i * S.cc;
    for (int64_t i = 0; i < S.cd[a]; i++)
      S.clo[a][i] = karst_i_fmax(S.lo[a], S.corner[a][i]),
      S.chi[a][i] = karst_i_fmin(S.hi[a], S.corner[a][i + 1]);
  }
  /* Offsets (di, dj, dk) in [-2, 2]^3 whose cells come closer than r_c to
   * the centre cell: the gap along an axis is (|d| − 1)+ cells, so at most
   * two coordinates may be ±2. Nearest first: conflicts are found sooner. */
  int off[125][3];
  for (int k = -2; k <= 2; k++)
    for (int j = -2; j <= 2; j++)
      for (int i = -2; i <= 2; i++) {
        int gap = (abs(i) == 2) + (abs(j) == 2) + (abs(k) == 2);
        if (gap == 3 || (i == 0 && j == 0 && k == 0)) continue;
        off[S.n_off][0] = i, off[S.n_off][1] = j, off[S.n_off][2] = k, S.n_off++;
      }
  assert(S.n_off == FILL_OFFSETS);
  qsort(off, (size_t)S.n_off, sizeof off[0], cmp_off);
  for (int o = 0; o < 26; o++) /* the cells that can cover the centre come first (fill_conflict) */
    assert(abs(off[o][0]) <= 1 && abs(off[o][1]) <= 1 && abs(off[o][2]) <= 1);
  _Static_assert(FILL_COVER_OFFSETS >= 26, "the 26 cells next to a fill cell can cover it");
  for (int o = 0; o < S.n_off; o++) {
    S.delta[o] = off[o][0] + S.pd[0] * (off[o][1] + S.pd[1] * off[o][2]);
  }

  S.stage = "key point";
  for (int i = 0; i < sc->n_key_points; i++)
    if ((err = add_sample(&S, sc->key_points[i].p, KARST_SAMPLE_KEYPOINT)) != KARST_SUCCESS)
      goto cleanup;
  s.n_key_points = sc->n_key_points;

  S.stage = "prescribed path";
  for (int i = 0; i < sc->n_prescribed; i++) {
    int ka = sc->prescribed[i].a, kb = sc->prescribed[i].b;
    if (ka < 0 || kb < 0 || ka >= sc->n_key_points || kb >= sc->n_key_points) {
      err = karst_set_error(ctx, KARST_EINVAL,
                            "prescribed path %d: key point indices (%d, %d) not within [0, %d)",
                            i + 1, ka, kb, sc->n_key_points);
      goto cleanup;
    }
    const double *P = sc->key_points[ka].p, *Q = sc->key_points[kb].p;
    double len = sqrt((Q[0] - P[0]) * (Q[0] - P[0]) + (Q[1] - P[1]) * (Q[1] - P[1]) +
                      (Q[2] - P[2]) * (Q[2] - P[2]));
    double m = floor(len / S.rf); /* spacing len / m >= r_f */
    for (double j = 1; j < m; j++) {
      double p[3];
      for (int a = 0; a < 3; a++)
        p[a] = P[a] + (j / m) * (Q[a] - P[a]);
      if (!karst_geology_in_bedrock(geo, p) || cgrid_conflict(&S.feat, p, S.rf)) continue;
      if ((err = add_sample(&S, p, KARST_SAMPLE_PRESCRIBED)) != KARST_SUCCESS) goto cleanup;
    }
  }

  /* sampling.refine names the features sampled at feature_radius (all three by default). */
  const unsigned refine = sc->sampling.refine;
  S.stage = "horizon";
  for (int h = 0; h < sc->n_horizons && (refine & KARST_REFINE_HORIZONS); h++) {
    region_t R = {KARST_SAMPLE_HORIZON, &geo->horizon[h], sc->sampling.feature_band};
    if ((err = sample_region(&S, &R)) != KARST_SUCCESS) goto cleanup;
  }
  S.stage = "water table";
  for (int w = 0; w < geo->n_springs && (refine & KARST_REFINE_WATER_TABLE); w++) {
    int seen = 0; /* springs sharing one water table sample it once */
    for (int v = 0; v < w && !seen; v++)
      seen = karst_i_surf_equal(&geo->water_table[v], &geo->water_table[w]);
    if (seen) continue;
    region_t R = {KARST_SAMPLE_WATER_TABLE, &geo->water_table[w], sc->sampling.feature_band};
    if ((err = sample_region(&S, &R)) != KARST_SUCCESS) goto cleanup;
  }
  S.stage = "permeability";
  if (refine & KARST_REFINE_PERMEABILITY) {
    region_t R = {KARST_SAMPLE_PERMEABILITY, NULL, 0.0};
    if ((err = sample_region(&S, &R)) != KARST_SUCCESS) goto cleanup;
  }
  if (!fill) {
    S.stage = "sampling.points";
    if ((err = sample_points(&S)) != KARST_SUCCESS) goto cleanup;
  } else {
    S.stage = "fill";
    if ((err = sample_fill(&S)) != KARST_SUCCESS) goto cleanup;
  }
  if ((err = morton_order(ctx, sc, &s)) != KARST_SUCCESS) goto cleanup;
  karst_progress(ctx, "sampling", 1, 1);
  karst_log(ctx, KARST_LOG_INFO, "sampling: %lld samples (%d key points)", (long long)s.n,
            sc->n_key_points);

  karst_samples_destroy(out);
  *out = s;
  karst_samples_init(&s);
cleanup:
  karst_samples_destroy(&s);
  cgrid_destroy(&S.feat);
  free(S.fill);
  free(S.near);
  for (int a = 0; a < 3; a++)
    free(S.corner[a]);
  return err;
}
