/* Surface-only polygonization of a 1-Lipschitz field: marching tetrahedra on
 * the Kuhn split of a regular grid (a simplicial complex, so the piecewise
 * linear zero set is a closed 2-manifold when no grid value is exactly zero;
 * zero counts as outside, which is the same as a positive perturbation;
 * vertices keep a margin from the grid points so that no triangle collapses),
 * with empty blocks skipped by the Lipschitz bound, in parallel tiles merged
 * in a fixed order. See include/karst/mesh.h. */
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "implicit/implicit_internal.h"
#include "karst/mesh.h"
#include "mesh/mesh_internal.h"

/* Cells per side of a tile (the unit of parallel work). */
#define TILE 32
/* Blocks are split down to this many cells per side before polygonizing. */
#define LEAF 4
/* A block is skipped when |f(centre)| > half diagonal (1 + SKIP_REL) + SKIP_ABS:
 * margins against rounding in the field (absolute in metres). A wrongly
 * skipped block would leave a hole, so this errs on the safe side. */
#define SKIP_REL 1e-9
#define SKIP_ABS 1e-6
/* Largest grid accepted, in cells per axis and in total. */
#define MAX_AXIS_CELLS ((karst_int_t)1 << 21)
#define MAX_CELLS ((double)((karst_int_t)1 << 46))

void karst_mesh_init(karst_mesh_t *m) {
  memset(m, 0, sizeof *m);
}

void karst_mesh_destroy(karst_mesh_t *m) {
  if (!m) return;
  free(m->xyz);
  free(m->tri);
  free(m->tri_label);
  free(m->tri_feature);
  memset(m, 0, sizeof *m);
}

/* ---------------------------------------------------------------------- */
/* Hash map int64 key -> int64 value (open addressing, linear probing).    */
/* ---------------------------------------------------------------------- */

int karst_i_hmap_init(karst_i_hmap_t *h, karst_int_t expected) {
  karst_int_t cap = 64;
  while (cap < 2 * expected)
    cap *= 2;
  h->keys = malloc((size_t)cap * sizeof *h->keys);
  h->vals = malloc((size_t)cap * sizeof *h->vals);
  if (!h->keys || !h->vals) {
    free(h->keys), free(h->vals);
    h->keys = NULL, h->vals = NULL;
    return -1;
  }
  for (karst_int_t i = 0; i < cap; i++)
    h->keys[i] = -1;
  h->cap = cap;
  h->n = 0;
  return 0;
}

void karst_i_hmap_destroy(karst_i_hmap_t *h) {
  free(h->keys);
  free(h->vals);
  memset(h, 0, sizeof *h);
}

static uint64_t mix64(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

static int hmap_grow(karst_i_hmap_t *h) {
  karst_i_hmap_t g;
  if (karst_i_hmap_init(&g, h->cap)) return -1; /* twice the capacity */
  for (karst_int_t i = 0; i < h->cap; i++)
    if (h->keys[i] >= 0) {
      karst_int_t v;
      karst_i_hmap_find_or_insert(&g, h->keys[i], h->vals[i], &v);
    }
  karst_i_hmap_destroy(h);
  *h = g;
  return 0;
}

int karst_i_hmap_find(const karst_i_hmap_t *h, karst_int_t key) {
  if (h->cap == 0) return 0;
  karst_int_t mask = h->cap - 1;
  karst_int_t i = (karst_int_t)(mix64((uint64_t)key) & (uint64_t)mask);
  while (h->keys[i] >= 0) {
    if (h->keys[i] == key) return 1;
    i = (i + 1) & mask;
  }
  return 0;
}

/* Find @p key; insert it with @p val when absent. Returns 1 when inserted,
 * 0 when found (value in *out), -1 when out of memory. */
int karst_i_hmap_find_or_insert(karst_i_hmap_t *h, karst_int_t key, karst_int_t val,
                                karst_int_t *out) {
  if (2 * (h->n + 1) > h->cap && hmap_grow(h)) return -1;
  karst_int_t mask = h->cap - 1;
  karst_int_t i = (karst_int_t)(mix64((uint64_t)key) & (uint64_t)mask);
  while (h->keys[i] >= 0) {
    if (h->keys[i] == key) {
      *out = h->vals[i];
      return 0;
    }
    i = (i + 1) & mask;
  }
  h->keys[i] = key;
  h->vals[i] = val;
  h->n++;
  *out = val;
  return 1;
}

/* ---------------------------------------------------------------------- */
/* The grid and the field.                                                 */
/* ---------------------------------------------------------------------- */

typedef struct {
  const karst_sdf_t *sdf;
  karst_int_t root;
  double origin[3], h;
  double clip[6];    /* the box shrunk by half a voxel */
  karst_int_t n[3];  /* cells per axis */
  karst_int_t nt[3]; /* tiles per axis */
} grid_t;

/* g = max(f, sdbox(clip)): the solid intersected with the clip box. */
static double field(const grid_t *g, const double p[3], int *label) {
  int lab;
  double f = karst_sdf_eval_node(g->sdf, g->root, p, &lab, NULL);
  double c = karst_i_sdbox(g->clip, p);
  if (c >= f) {
    f = c;
    lab = KARST_SDF_NO_LABEL;
  }
  *label = lab;
  return f;
}

/**
 * The grid of karst_mesh_polygonize and karst_mesh_sample: ceil(length /
 * voxel) cells along each axis of @p box (see mesh.h). Time complexity: O(1).
 */
karst_error_t karst_mesh_grid(karst_ctx_t *ctx, const double box[6], double voxel,
                              karst_int_t cells[3]) {
  if (!(voxel > 0) || !isfinite(voxel))
    return karst_set_error(ctx, KARST_EINVAL, "polygonize: voxel size %g must be > 0", voxel);
  double total = 1;
  for (int a = 0; a < 3; a++) {
    if (!isfinite(box[a]) || !isfinite(box[a + 3]) || !(box[a] < box[a + 3]))
      return karst_set_error(ctx, KARST_EINVAL, "polygonize: box axis %d is [%g, %g]", a, box[a],
                             box[a + 3]);
    double len = box[a + 3] - box[a];
    if (len < 2 * voxel)
      return karst_set_error(ctx, KARST_ERANGE,
                             "polygonize: box axis %d is %g m long, less than two voxels of %g m",
                             a, len, voxel);
    double n = ceil(len / voxel);
    if (n > (double)MAX_AXIS_CELLS)
      return karst_set_error(ctx, KARST_ERANGE,
                             "polygonize: %.0f cells along axis %d (voxel %g m) exceed %lld", n, a,
                             voxel, (long long)MAX_AXIS_CELLS);
    cells[a] = (karst_int_t)n;
    total *= n;
  }
  if (total > MAX_CELLS)
    return karst_set_error(ctx, KARST_ERANGE, "polygonize: %.3g cells exceed the limit %.3g", total,
                           MAX_CELLS);
  return KARST_SUCCESS;
}

static karst_error_t grid_setup(karst_ctx_t *ctx, const karst_sdf_t *sdf, const double box[6],
                                double voxel, grid_t *g) {
  memset(g, 0, sizeof *g);
  if (!sdf || sdf->root < 0)
    return karst_set_error(ctx, KARST_EINVAL, "polygonize: the construction tree has no root");
  karst_error_t err = karst_mesh_grid(ctx, box, voxel, g->n);
  if (err) return err;
  for (int a = 0; a < 3; a++) {
    g->nt[a] = (g->n[a] + TILE - 1) / TILE;
    g->origin[a] = box[a];
    g->clip[a] = box[a] + 0.5 * voxel;
    g->clip[a + 3] = box[a + 3] - 0.5 * voxel;
  }
  g->sdf = sdf;
  g->root = sdf->root;
  g->h = voxel;
  return KARST_SUCCESS;
}

/* ---------------------------------------------------------------------- */
/* One tile.                                                               */
/* ---------------------------------------------------------------------- */

typedef struct {
  karst_int_t nv, cap_v;
  karst_int_t *vkey;
  double *vxyz;
  karst_int_t nt, cap_t;
  int32_t *tri; /* tile-local vertex indices (a tile has fewer than 2^31 vertices) */
  int *label;
} tile_out_t;

typedef struct {
  const grid_t *g;
  karst_int_t t0[3]; /* first cell of the tile */
  karst_int_t tn[3]; /* cells of the tile per axis */
  double *val;       /* (TILE+1)^3 corner cache */
  signed char *lab;
  unsigned char *have;
  karst_i_hmap_t map; /* edge key -> tile-local vertex */
  tile_out_t *out;
  karst_polygonize_stats_t st;
  int oom;
} tile_work_t;

#define CIDX(i, j, k) (((k) * (TILE + 1) + (j)) * (TILE + 1) + (i))

static double corner(tile_work_t *w, karst_int_t i, karst_int_t j, karst_int_t k, int *label) {
  karst_int_t c = CIDX(i, j, k);
  if (!w->have[c]) {
    const grid_t *g = w->g;
    double p[3] = {g->origin[0] + (double)(w->t0[0] + i) * g->h,
                   g->origin[1] + (double)(w->t0[1] + j) * g->h,
                   g->origin[2] + (double)(w->t0[2] + k) * g->h};
    int l;
    w->val[c] = field(g, p, &l);
    w->lab[c] = (signed char)l;
    w->have[c] = 1;
    w->st.n_evals++;
  }
  *label = w->lab[c];
  return w->val[c];
}

static int out_vertex(tile_work_t *w, karst_int_t key, const double p[3], karst_int_t *idx) {
  tile_out_t *o = w->out;
  int r = karst_i_hmap_find_or_insert(&w->map, key, o->nv, idx);
  if (r < 0) return -1;
  if (r == 0) return 0;
  if (o->nv == o->cap_v) {
    karst_int_t c = o->cap_v ? 2 * o->cap_v : 1024;
    karst_int_t *k = realloc(o->vkey, (size_t)c * sizeof *k);
    if (k) o->vkey = k;
    double *x = realloc(o->vxyz, (size_t)c * 3 * sizeof *x);
    if (x) o->vxyz = x;
    if (!k || !x) return -1;
    o->cap_v = c;
  }
  o->vkey[o->nv] = key;
  memcpy(o->vxyz + 3 * o->nv, p, 3 * sizeof *p);
  o->nv++;
  return 0;
}

static int out_triangle(tile_work_t *w, const karst_int_t v[3], int label) {
  tile_out_t *o = w->out;
  if (o->nt == o->cap_t) {
    karst_int_t c = o->cap_t ? 2 * o->cap_t : 2048;
    int32_t *t = realloc(o->tri, (size_t)c * 3 * sizeof *t);
    if (t) o->tri = t;
    int *l = realloc(o->label, (size_t)c * sizeof *l);
    if (l) o->label = l;
    if (!t || !l) return -1;
    o->cap_t = c;
  }
  for (int k = 0; k < 3; k++)
    o->tri[3 * o->nt + k] = (int32_t)v[k];
  o->label[o->nt] = label;
  o->nt++;
  return 0;
}

/* The six Kuhn tetrahedra of a cube: chains 0 ⊂ a ⊂ a|b ⊂ 7 of corner
 * bitmasks (bit 0: +x, bit 1: +y, bit 2: +z). */
static const int kuhn[6][4] = {{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7},
                               {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}};

/* Vertex on the edge between tet corners lo ⊂ hi of the cell at (ci, cj, ck),
 * interpolated linearly from lo to hi (the same arithmetic wherever the
 * edge is met, so shared vertices coincide exactly). */
static int edge_vertex(tile_work_t *w, karst_int_t ci, karst_int_t cj, karst_int_t ck, int lo,
                       int hi, const double *val, karst_int_t *idx) {
  const grid_t *g = w->g;
  karst_int_t gi = w->t0[0] + ci + (lo & 1), gj = w->t0[1] + cj + ((lo >> 1) & 1),
              gk = w->t0[2] + ck + ((lo >> 2) & 1);
  int d = lo ^ hi;
  karst_int_t key = ((gk * (g->n[1] + 1) + gj) * (g->n[0] + 1) + gi) * 8 + d;
  double fl = val[lo], fh = val[hi];
  double t = fl / (fl - fh);
  /* keep the vertex off the grid points: where the field is 0 (or tiny) at
   * a grid point, the vertices of all its edges would coincide and make
   * zero-area triangles (mesh.h, KARST_MESH_EDGE_MARGIN) */
  t = fmin(fmax(t, KARST_MESH_EDGE_MARGIN), 1 - KARST_MESH_EDGE_MARGIN);
  double p[3] = {g->origin[0] + ((double)gi + t * (d & 1)) * g->h,
                 g->origin[1] + ((double)gj + t * ((d >> 1) & 1)) * g->h,
                 g->origin[2] + ((double)gk + t * ((d >> 2) & 1)) * g->h};
  return out_vertex(w, key, p, idx);
}

/* Doubled integer coordinates of corner c: (2 bx, 2 by, 2 bz). */
static void ccoord(int c, long x[3]) {
  x[0] = 2 * (c & 1), x[1] = 2 * ((c >> 1) & 1), x[2] = 2 * ((c >> 2) & 1);
}

/* Emit triangle (e0, e1, e2), each e an edge {lo, hi} of the tet, oriented
 * so that its normal points from the inside corners to the outside ones.
 * The orientation is decided on the edge midpoints (exact integers, never
 * degenerate), so it is consistent whatever the interpolated positions. */
static int emit(tile_work_t *w, karst_int_t ci, karst_int_t cj, karst_int_t ck, const int e[3][2],
                const double *val, const long dir[3], int label) {
  long m[3][3];
  for (int k = 0; k < 3; k++) {
    long a[3], b[3];
    ccoord(e[k][0], a);
    ccoord(e[k][1], b);
    for (int c = 0; c < 3; c++)
      m[k][c] = a[c] + b[c];
  }
  long u[3] = {m[1][0] - m[0][0], m[1][1] - m[0][1], m[1][2] - m[0][2]};
  long v[3] = {m[2][0] - m[0][0], m[2][1] - m[0][1], m[2][2] - m[0][2]};
  long n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  long s = n[0] * dir[0] + n[1] * dir[1] + n[2] * dir[2];
  karst_int_t idx[3];
  for (int k = 0; k < 3; k++) {
    int lo = e[k][0] < e[k][1] ? e[k][0] : e[k][1], hi = e[k][0] ^ e[k][1] ^ lo;
    if (edge_vertex(w, ci, cj, ck, lo, hi, val, &idx[k])) return -1;
  }
  if (s < 0) {
    karst_int_t tmp = idx[1];
    idx[1] = idx[2];
    idx[2] = tmp;
  }
  return out_triangle(w, idx, label);
}

static int polygonize_cell(tile_work_t *w, karst_int_t ci, karst_int_t cj, karst_int_t ck) {
  double val[8];
  int lab[8], nin = 0;
  for (int c = 0; c < 8; c++) {
    val[c] = corner(w, ci + (c & 1), cj + ((c >> 1) & 1), ck + ((c >> 2) & 1), &lab[c]);
    nin += val[c] < 0;
  }
  if (nin == 0 || nin == 8) return 0;
  w->st.n_cells++;
  for (int t = 0; t < 6; t++) {
    const int *tv = kuhn[t];
    int in[4], out[4], ni = 0, no = 0;
    for (int k = 0; k < 4; k++) {
      if (val[tv[k]] < 0)
        in[ni++] = tv[k];
      else
        out[no++] = tv[k];
    }
    if (ni == 0 || no == 0) continue;
    /* inside-to-outside direction: |in| Σ out - |out| Σ in (doubled coordinates) */
    long dir[3] = {0, 0, 0};
    for (int k = 0; k < no; k++) {
      long x[3];
      ccoord(out[k], x);
      for (int c = 0; c < 3; c++)
        dir[c] += ni * x[c];
    }
    for (int k = 0; k < ni; k++) {
      long x[3];
      ccoord(in[k], x);
      for (int c = 0; c < 3; c++)
        dir[c] -= no * x[c];
    }
    int label = lab[in[0]];
    if (ni == 1 || ni == 3) {
      int lone = ni == 1 ? in[0] : out[0];
      const int *others = ni == 1 ? out : in;
      int e[3][2] = {{lone, others[0]}, {lone, others[1]}, {lone, others[2]}};
      if (emit(w, ci, cj, ck, e, val, dir, label)) return -1;
    } else {
      /* quad (a,c) (a,d) (b,d) (b,c) with in = {a, b}, out = {c, d} */
      int a = in[0], b = in[1], c = out[0], d = out[1];
      int e1[3][2] = {{a, c}, {a, d}, {b, d}};
      int e2[3][2] = {{a, c}, {b, d}, {b, c}};
      if (emit(w, ci, cj, ck, e1, val, dir, label)) return -1;
      if (emit(w, ci, cj, ck, e2, val, dir, label)) return -1;
    }
  }
  return 0;
}

/* Recursive block test: cells [c0, c1) of the tile. */
static int block(tile_work_t *w, const karst_int_t c0[3], const karst_int_t c1[3]) {
  const grid_t *g = w->g;
  karst_int_t d[3] = {c1[0] - c0[0], c1[1] - c0[1], c1[2] - c0[2]};
  if (d[0] <= 0 || d[1] <= 0 || d[2] <= 0) return 0;
  double p[3];
  for (int a = 0; a < 3; a++)
    p[a] = g->origin[a] + ((double)(w->t0[a] + c0[a]) + 0.5 * (double)d[a]) * g->h;
  double hd = 0.5 * g->h * sqrt((double)(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
  int l;
  double v = field(g, p, &l);
  w->st.n_evals++;
  w->st.n_blocks++;
  if (fabs(v) > hd * (1 + SKIP_REL) + SKIP_ABS) {
    w->st.n_skipped++;
    return 0;
  }
  if (d[0] <= LEAF && d[1] <= LEAF && d[2] <= LEAF) {
    for (karst_int_t k = c0[2]; k < c1[2]; k++)
      for (karst_int_t j = c0[1]; j < c1[1]; j++)
        for (karst_int_t i = c0[0]; i < c1[0]; i++)
          if (polygonize_cell(w, i, j, k)) return -1;
    return 0;
  }
  karst_int_t mid[3];
  for (int a = 0; a < 3; a++)
    mid[a] = d[a] > LEAF ? c0[a] + d[a] / 2 : c1[a];
  for (int oct = 0; oct < 8; oct++) {
    karst_int_t b0[3], b1[3];
    int skip = 0;
    for (int a = 0; a < 3; a++) {
      int hi = (oct >> a) & 1;
      if (hi && mid[a] == c1[a]) skip = 1;
      b0[a] = hi ? mid[a] : c0[a];
      b1[a] = hi ? c1[a] : mid[a];
    }
    if (skip) continue;
    if (block(w, b0, b1)) return -1;
  }
  return 0;
}

/* First cell and cell counts of tile t. */
static void tile_range(const grid_t *g, karst_int_t t, karst_int_t t0[3], karst_int_t tn[3]) {
  karst_int_t tc[3] = {t % g->nt[0], (t / g->nt[0]) % g->nt[1], t / (g->nt[0] * g->nt[1])};
  for (int a = 0; a < 3; a++) {
    t0[a] = tc[a] * TILE;
    tn[a] = g->n[a] - t0[a];
    if (tn[a] > TILE) tn[a] = TILE;
  }
}

/* ---------------------------------------------------------------------- */
/* Threads.                                                                */
/* ---------------------------------------------------------------------- */

typedef struct {
  const grid_t *g;
  karst_ctx_t *ctx;
  tile_out_t *outs;
  karst_int_t ntiles;
  atomic_llong next, done;
  atomic_int stop; /* 1: interrupted, 2: out of memory */
} shared_t;

typedef struct {
  shared_t *sh;
  int id;
  karst_polygonize_stats_t st;
} worker_t;

static void *worker(void *arg) {
  worker_t *wk = arg;
  shared_t *sh = wk->sh;
  const grid_t *g = sh->g;
  tile_work_t w;
  memset(&w, 0, sizeof w);
  w.g = g;
  size_t nc = (size_t)(TILE + 1) * (TILE + 1) * (TILE + 1);
  w.val = malloc(nc * sizeof *w.val);
  w.lab = malloc(nc);
  w.have = malloc(nc);
  if (!w.val || !w.lab || !w.have || karst_i_hmap_init(&w.map, 4096)) {
    atomic_store(&sh->stop, 2);
    goto done;
  }
  for (;;) {
    if (atomic_load(&sh->stop)) break;
    if (karst_interrupted(sh->ctx)) {
      atomic_store(&sh->stop, 1);
      break;
    }
    karst_int_t t = atomic_fetch_add(&sh->next, 1);
    if (t >= sh->ntiles) break;
    tile_range(g, t, w.t0, w.tn);
    memset(w.have, 0, nc);
    for (karst_int_t i = 0; i < w.map.cap; i++)
      w.map.keys[i] = -1;
    w.map.n = 0;
    w.out = &sh->outs[t];
    karst_int_t c0[3] = {0, 0, 0};
    if (block(&w, c0, w.tn)) {
      atomic_store(&sh->stop, 2);
      break;
    }
    long long d = atomic_fetch_add(&sh->done, 1) + 1;
    if (wk->id == 0) karst_progress(sh->ctx, "polygonize", (double)d, (double)sh->ntiles);
  }
done:
  wk->st = w.st;
  free(w.val);
  free(w.lab);
  free(w.have);
  karst_i_hmap_destroy(&w.map);
  return NULL;
}

static void free_outs(tile_out_t *o, karst_int_t n) {
  if (!o) return;
  for (karst_int_t i = 0; i < n; i++) {
    free(o[i].vkey);
    free(o[i].vxyz);
    free(o[i].tri);
    free(o[i].label);
  }
  free(o);
}

/**
 * Polygonize the root of a construction tree; see include/karst/mesh.h.
 * Time complexity: O(B + S c), B blocks tested, S surface cells, c the cost of
 * one field evaluation (O(log n) for n primitives with the hierarchy).
 */
karst_error_t karst_mesh_polygonize(karst_ctx_t *ctx, const karst_sdf_t *sdf, const double box[6],
                                    double voxel, karst_mesh_t *out,
                                    karst_polygonize_stats_t *stats) {
  karst_error_t err = KARST_SUCCESS;
  grid_t g;
  shared_t sh;
  worker_t *wk = NULL;
  pthread_t *th = NULL;
  int nth = 0, started = 0;
  karst_i_hmap_t gmap = {0};
  karst_int_t *remap = NULL;
  karst_mesh_t m;
  karst_mesh_init(&m);
  memset(&sh, 0, sizeof sh);
  if (stats) memset(stats, 0, sizeof *stats);
  if (!out) return karst_set_error(ctx, KARST_EINVAL, "polygonize: no output mesh given");
  karst_mesh_destroy(out);
  if ((err = grid_setup(ctx, sdf, box, voxel, &g))) return err;
  sh.g = &g;
  sh.ctx = ctx;
  sh.ntiles = g.nt[0] * g.nt[1] * g.nt[2];
  atomic_init(&sh.next, 0);
  atomic_init(&sh.done, 0);
  atomic_init(&sh.stop, 0);
  sh.outs = calloc((size_t)sh.ntiles, sizeof *sh.outs);
  nth = ctx && ctx->nthreads > 1 ? ctx->nthreads : 1;
  if (nth > sh.ntiles) nth = (int)sh.ntiles;
  wk = calloc((size_t)nth, sizeof *wk);
  th = calloc((size_t)nth, sizeof *th);
  if (!sh.outs || !wk || !th) {
    err = karst_set_error(ctx, KARST_ENOMEM, "polygonize: out of memory for %lld tiles",
                          (long long)sh.ntiles);
    goto cleanup;
  }
  karst_progress(ctx, "polygonize", 0, (double)sh.ntiles);
  for (int i = 0; i < nth; i++) {
    wk[i].sh = &sh;
    wk[i].id = i;
  }
  for (started = 1; started < nth; started++)
    if (pthread_create(&th[started], NULL, worker, &wk[started]) != 0) break;
  worker(&wk[0]);
  for (int i = 1; i < started; i++)
    pthread_join(th[i], NULL);
  karst_polygonize_stats_t st;
  memset(&st, 0, sizeof st);
  for (int i = 0; i < nth; i++) {
    st.n_blocks += wk[i].st.n_blocks;
    st.n_skipped += wk[i].st.n_skipped;
    st.n_cells += wk[i].st.n_cells;
    st.n_evals += wk[i].st.n_evals;
  }
  for (int a = 0; a < 3; a++)
    st.cells[a] = g.n[a];
  st.n_tiles = sh.ntiles;
  if (atomic_load(&sh.stop) == 1) {
    err =
        karst_set_error(ctx, KARST_EINTERRUPTED, "polygonize: interrupted after %lld of %lld tiles",
                        (long long)atomic_load(&sh.done), (long long)sh.ntiles);
    goto cleanup;
  }
  if (atomic_load(&sh.stop) == 2) {
    err = karst_set_error(ctx, KARST_ENOMEM, "polygonize: out of memory");
    goto cleanup;
  }
  /* Merge the tiles in their order, numbering vertices by first occurrence, so
   * the output is independent of the thread count. A vertex can be shared
   * with another tile only when its edge lies on the tile's boundary, that is
   * when the edge's lower grid point is on a boundary plane of the tile: only
   * those go through the hash map. */
  karst_int_t nv = 0, nt = 0, maxv = 0, nb = 0;
  const karst_int_t gx = g.n[0] + 1, gy = g.n[1] + 1;
#define ON_TILE_BOUNDARY(key, t0, tn)                                                              \
  (((key) / 8 % gx == (t0)[0]) || ((key) / 8 % gx == (t0)[0] + (tn)[0]) ||                         \
   ((key) / 8 / gx % gy == (t0)[1]) || ((key) / 8 / gx % gy == (t0)[1] + (tn)[1]) ||               \
   ((key) / 8 / gx / gy == (t0)[2]) || ((key) / 8 / gx / gy == (t0)[2] + (tn)[2]))
  for (karst_int_t t = 0; t < sh.ntiles; t++) {
    tile_out_t *o = &sh.outs[t];
    nv += o->nv;
    nt += o->nt;
    if (o->nv > maxv) maxv = o->nv;
    karst_int_t t0[3], tn[3];
    tile_range(&g, t, t0, tn);
    for (karst_int_t i = 0; i < o->nv; i++)
      nb += ON_TILE_BOUNDARY(o->vkey[i], t0, tn);
  }
  if (karst_i_hmap_init(&gmap, nb) ||
      !(remap = malloc((size_t)(maxv > 0 ? maxv : 1) * sizeof *remap)) ||
      !(m.xyz = malloc((size_t)(nv > 0 ? nv : 1) * 3 * sizeof *m.xyz)) ||
      !(m.tri = malloc((size_t)(nt > 0 ? nt : 1) * 3 * sizeof *m.tri)) ||
      !(m.tri_label = malloc((size_t)(nt > 0 ? nt : 1) * sizeof *m.tri_label)) ||
      !(m.tri_feature = malloc((size_t)(nt > 0 ? nt : 1) * sizeof *m.tri_feature))) {
    err = karst_set_error(ctx, KARST_ENOMEM, "polygonize: out of memory for %lld vertices",
                          (long long)nv);
    goto cleanup;
  }
  for (karst_int_t t = 0; t < sh.ntiles; t++) {
    tile_out_t *o = &sh.outs[t];
    karst_int_t t0[3], tn[3];
    tile_range(&g, t, t0, tn);
    for (karst_int_t i = 0; i < o->nv; i++) {
      karst_int_t id = m.n_vertices;
      int r = 1;
      if (ON_TILE_BOUNDARY(o->vkey[i], t0, tn)) {
        r = karst_i_hmap_find_or_insert(&gmap, o->vkey[i], m.n_vertices, &id);
        if (r < 0) {
          err = karst_set_error(ctx, KARST_ENOMEM, "polygonize: out of memory");
          goto cleanup;
        }
      }
      if (r == 1) {
        memcpy(m.xyz + 3 * m.n_vertices, o->vxyz + 3 * i, 3 * sizeof *m.xyz);
        m.n_vertices++;
      }
      remap[i] = id;
    }
    for (karst_int_t i = 0; i < o->nt; i++) {
      for (int k = 0; k < 3; k++)
        m.tri[3 * m.n_triangles + k] = remap[o->tri[3 * i + k]];
      m.tri_label[m.n_triangles] = KARST_SDF_LABEL_TYPE(o->label[i]);
      m.tri_feature[m.n_triangles] = KARST_SDF_LABEL_FEATURE(o->label[i]);
      m.n_triangles++;
    }
    free(o->vkey), free(o->vxyz), free(o->tri), free(o->label);
    memset(o, 0, sizeof *o);
  }
#undef ON_TILE_BOUNDARY
  m.tri_label_name = "tunnel_type";
  st.n_vertices = m.n_vertices;
  st.n_triangles = m.n_triangles;
  if (stats) *stats = st;
  *out = m;
  karst_mesh_init(&m);
  karst_progress(ctx, "polygonize", (double)sh.ntiles, (double)sh.ntiles);
cleanup:
  free_outs(sh.outs, sh.ntiles);
  free(wk);
  free(th);
  free(remap);
  karst_i_hmap_destroy(&gmap);
  karst_mesh_destroy(&m);
  return err;
}

/* ---------------------------------------------------------------------- */
/* Sampling the field on the grid (for --sdf).                             */
/* ---------------------------------------------------------------------- */

typedef struct {
  const grid_t *g;
  float *v;
  karst_int_t k0, k1;
} sample_job_t;

static void *sample_worker(void *arg) {
  sample_job_t *j = arg;
  const grid_t *g = j->g;
  karst_int_t nx = g->n[0] + 1, ny = g->n[1] + 1;
  for (karst_int_t k = j->k0; k < j->k1; k++)
    for (karst_int_t jj = 0; jj < ny; jj++)
      for (karst_int_t i = 0; i < nx; i++) {
        double p[3] = {g->origin[0] + (double)i * g->h, g->origin[1] + (double)jj * g->h,
                       g->origin[2] + (double)k * g->h};
        int l;
        j->v[(k * ny + jj) * nx + i] = (float)field(g, p, &l);
      }
  return NULL;
}

/**
 * Sample the (clipped) field at the polygonizer's grid points; see mesh.h.
 * Slabs of z are shared among ctx->nthreads threads.
 * Time complexity: O(points × field cost).
 */
karst_error_t karst_mesh_sample(karst_ctx_t *ctx, const karst_sdf_t *sdf, const double box[6],
                                double voxel, int dims[3], double origin[3], float **values) {
  grid_t g;
  karst_error_t err = grid_setup(ctx, sdf, box, voxel, &g);
  if (err) return err;
  double pts = (double)(g.n[0] + 1) * (double)(g.n[1] + 1) * (double)(g.n[2] + 1);
  if (pts > (double)KARST_MESH_SAMPLE_MAX)
    return karst_set_error(ctx, KARST_ERANGE,
                           "sampling: the grid of %lld x %lld x %lld cells (%.0f points, voxel %g "
                           "m) exceeds the limit of %lld points; use a larger voxel or a smaller "
                           "box",
                           (long long)g.n[0], (long long)g.n[1], (long long)g.n[2], pts, voxel,
                           (long long)KARST_MESH_SAMPLE_MAX);
  float *v = malloc((size_t)pts * sizeof *v);
  if (!v) return karst_set_error(ctx, KARST_ENOMEM, "sampling: out of memory for %.0f points", pts);
  int nth = ctx && ctx->nthreads > 1 ? ctx->nthreads : 1;
  if (nth > g.n[2] + 1) nth = (int)(g.n[2] + 1);
  sample_job_t jobs[64];
  pthread_t th[64];
  if (nth > 64) nth = 64;
  karst_int_t nz = g.n[2] + 1;
  int started = 1;
  for (int i = 0; i < nth; i++) {
    jobs[i].g = &g;
    jobs[i].v = v;
    jobs[i].k0 = nz * i / nth;
    jobs[i].k1 = nz * (i + 1) / nth;
  }
  for (; started < nth; started++)
    if (pthread_create(&th[started], NULL, sample_worker, &jobs[started]) != 0) break;
  /* slabs whose thread did not start are done here */
  for (int i = 0; i < nth; i++)
    if (i == 0 || i >= started) sample_worker(&jobs[i]);
  for (int i = 1; i < started; i++)
    pthread_join(th[i], NULL);
  for (int a = 0; a < 3; a++) {
    dims[a] = (int)(g.n[a] + 1);
    origin[a] = g.origin[a];
  }
  *values = v;
  return KARST_SUCCESS;
}

/**
 * Sample the field and write it as .vti (array "sdf") through
 * karst_vtk_write_image. Time complexity: as karst_mesh_sample.
 */
karst_error_t karst_mesh_write_sdf(karst_ctx_t *ctx, const char *path, const karst_sdf_t *sdf,
                                   const double box[6], double voxel) {
  int dims[3];
  double origin[3], spacing[3] = {voxel, voxel, voxel};
  float *v = NULL;
  karst_error_t err = karst_mesh_sample(ctx, sdf, box, voxel, dims, origin, &v);
  if (err) return err;
  err = karst_vtk_write_image(ctx, path, dims, origin, spacing, v, "sdf");
  free(v);
  return err;
}
