/* The replication operator of Paris et al. 2020, §5: the blocks of a tile
 * repeated in the virtual grid of cells of side s wherever the presence
 * function of a block copy is 1 at its anchor points,
 *     t(p) = min_i b_i(p mod s) over present copies (min: negative inside),
 * evaluated as an external node of a construction tree so that the
 * amplified terrain T ∪ R is one field for the polygonizer. Presence is
 * decided once per (tile, cell, block) before any evaluation. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "blocks/blocks_internal.h"
#include "core/parallel_internal.h"
#include "implicit/implicit_internal.h"

typedef struct tbins {
  double box[6]; /* union of the blocks' boxes grown by the cap */
  int nb[3];
  double cell[3];
  karst_int_t *start, *idx;
} tbins_t;

struct karst_blocks_replica {
  const karst_sdf_t *tree;
  karst_int_t terrain;
  int n_tiles;
  const karst_blocks_tile_t **tiles;
  tbins_t *bins;
  double s, cap;
  int64_t c0[3], nc[3];
  karst_int_t *toff;      /* per tile: offset of its (cell, block) bytes */
  unsigned char *present; /* toff[k] + cell * n_blocks + block */
  karst_int_t count;
  double box[6];
  /* presence inputs (used while building) */
  karst_blocks_stratum_fn stratum_of;
  void *stratum_arg;
  const int *stratum_tile;
  int n_strata;
  karst_blocks_presence_t pres;
};

void karst_blocks_presence_init(karst_blocks_presence_t *p) {
  p->dist_min = -1.0;
  p->dist_max = 2.0;
  p->max_slope = 0.5;
  p->n_anchors = 8;
  p->quorum = 0.5;
}

void karst_blocks_replica_free(karst_blocks_replica_t *r) {
  if (!r) return;
  if (r->bins)
    for (int k = 0; k < r->n_tiles; k++)
      free(r->bins[k].start), free(r->bins[k].idx);
  free(r->bins);
  free(r->tiles);
  free(r->toff);
  free(r->present);
  free(r);
}

karst_int_t karst_blocks_replica_count(const karst_blocks_replica_t *r) {
  return r ? r->count : 0;
}

/* The terrain field and its normalised gradient (central differences). */
static double terrain_at(const karst_blocks_replica_t *r, const double p[3], double g[3]) {
  double f = karst_sdf_eval_node(r->tree, r->terrain, p, NULL, NULL), h = KARST_I_BLOCKS_GRAD_STEP;
  if (g) {
    double n2 = 0;
    for (int a = 0; a < 3; a++) {
      double pp[3] = {p[0], p[1], p[2]}, pm[3] = {p[0], p[1], p[2]};
      pp[a] += h, pm[a] -= h;
      g[a] = (karst_sdf_eval_node(r->tree, r->terrain, pp, NULL, NULL) -
              karst_sdf_eval_node(r->tree, r->terrain, pm, NULL, NULL)) /
             (2 * h);
      n2 += g[a] * g[a];
    }
    double n = sqrt(n2);
    for (int a = 0; a < 3; a++)
      g[a] = n > 0 ? g[a] / n : 0;
  }
  return f;
}

/* Signed distance from @p a to the terrain surface, estimated by Newton
 * steps along the gradient, x <- x - f ∇f/|∇f|² (exact for a plane). The
 * field itself is a 1-Lipschitz bound that a heightfield scales down by
 * sqrt(1 + λ²) everywhere (λ its steepest slope): 16 m above a plateau next
 * to a wall of slope 12 it reads 1.3 m, which would place blocks in the air. */
static double surface_distance(const karst_blocks_replica_t *r, const double a[3], double f0) {
  double x[3] = {a[0], a[1], a[2]}, f = f0;
  for (int it = 0; it < KARST_I_BLOCKS_PROJECT_STEPS && f != 0; it++) {
    double G[3], n2 = 0, h = KARST_I_BLOCKS_GRAD_STEP;
    for (int k = 0; k < 3; k++) {
      double pp[3] = {x[0], x[1], x[2]}, pm[3] = {x[0], x[1], x[2]};
      pp[k] += h, pm[k] -= h;
      G[k] = (karst_sdf_eval_node(r->tree, r->terrain, pp, NULL, NULL) -
              karst_sdf_eval_node(r->tree, r->terrain, pm, NULL, NULL)) /
             (2 * h);
      n2 += G[k] * G[k];
    }
    if (!(n2 > 0)) break;
    for (int k = 0; k < 3; k++)
      x[k] -= f * G[k] / n2;
    f = karst_sdf_eval_node(r->tree, r->terrain, x, NULL, NULL);
  }
  double d = sqrt((x[0] - a[0]) * (x[0] - a[0]) + (x[1] - a[1]) * (x[1] - a[1]) +
                  (x[2] - a[2]) * (x[2] - a[2]));
  return f0 < 0 ? -d : d;
}

/* One anchor passes (§5): distance range, slope, and its stratum's tile. */
static int anchor_ok(const karst_blocks_replica_t *r, int tile, const double a[3]) {
  double g[3], f = terrain_at(r, a, g);
  if (!(f <= r->pres.dist_max)) return 0; /* f is a lower bound of the distance */
  if (!(fabs(g[2]) < r->pres.max_slope)) return 0;
  double d = surface_distance(r, a, f);
  if (!(d >= r->pres.dist_min && d <= r->pres.dist_max)) return 0;
  int st = r->stratum_of ? r->stratum_of(r->stratum_arg, a) : 0;
  if (st < 0 || st >= r->n_strata) return 0;
  return r->stratum_tile[st] == tile;
}

typedef struct pres_job {
  karst_blocks_replica_t *r;
  int64_t ncells;
} pres_job_t;

static void task_presence(void *arg, int tid, int nth) {
  pres_job_t *J = arg;
  karst_blocks_replica_t *r = J->r;
  int A = r->pres.n_anchors;
  for (int64_t c = tid; c < J->ncells; c += nth) {
    int64_t C[3] = {r->c0[0] + c % r->nc[0], r->c0[1] + (c / r->nc[0]) % r->nc[1],
                    r->c0[2] + c / (r->nc[0] * r->nc[1])};
    for (int k = 0; k < r->n_tiles; k++) {
      const karst_blocks_tile_t *t = r->tiles[k];
      for (karst_int_t i = 0; i < t->n_blocks; i++) {
        const karst_blocks_block_t *B = &t->blocks[i];
        int pass = 0, tried = 0;
        for (int j = 0; j < A; j++) {
          double a[3];
          /* an authored block's points are not in the members: its anchor only */
          if (j == 0 || B->n_points < A || B->kind == KARST_BLOCK_AUTHORED) {
            if (j > 0) break;
            memcpy(a, B->anchor, sizeof a);
          } else { /* sample points spread through the block, in its frame */
            karst_int_t m = B->first + (karst_int_t)((double)j * (double)B->n_points / A);
            memcpy(a, t->unwrapped + 3 * m, sizeof a);
          }
          for (int d = 0; d < 3; d++)
            a[d] += r->s * (double)C[d];
          pass += anchor_ok(r, k, a);
          tried++;
        }
        r->present[r->toff[k] + c * t->n_blocks + i] = pass > r->pres.quorum * tried;
      }
    }
  }
}

static karst_error_t make_bins(karst_ctx_t *ctx, const karst_blocks_tile_t *t, double cap,
                               tbins_t *b) {
  for (int a = 0; a < 3; a++)
    b->box[a] = INFINITY, b->box[a + 3] = -INFINITY;
  for (karst_int_t i = 0; i < t->n_blocks; i++)
    for (int a = 0; a < 3; a++) {
      b->box[a] = fmin(b->box[a], t->blocks[i].box[a] - cap);
      b->box[a + 3] = fmax(b->box[a + 3], t->blocks[i].box[a + 3] + cap);
    }
  size_t nbins = 1;
  for (int a = 0; a < 3; a++) {
    b->nb[a] = 12;
    b->cell[a] = (b->box[a + 3] - b->box[a]) / b->nb[a];
    nbins *= (size_t)b->nb[a];
  }
  b->start = calloc(nbins + 1, sizeof *b->start);
  if (!b->start) return karst_set_error(ctx, KARST_ENOMEM, "blocks: out of memory (bins)");
  for (int pass = 0; pass < 2; pass++) {
    karst_int_t *fill = NULL;
    if (pass) {
      for (size_t k = 0; k < nbins; k++)
        b->start[k + 1] += b->start[k];
      b->idx = malloc((size_t)(b->start[nbins] + 1) * sizeof *b->idx);
      fill = malloc(nbins * sizeof *fill);
      if (!b->idx || !fill) {
        free(fill);
        return karst_set_error(ctx, KARST_ENOMEM, "blocks: out of memory (bins)");
      }
      memcpy(fill, b->start, nbins * sizeof *fill);
    }
    for (karst_int_t i = 0; i < t->n_blocks; i++) {
      int lo[3], hi[3];
      for (int a = 0; a < 3; a++) {
        lo[a] = (int)floor((t->blocks[i].box[a] - cap - b->box[a]) / b->cell[a]);
        hi[a] = (int)floor((t->blocks[i].box[a + 3] + cap - b->box[a]) / b->cell[a]);
        lo[a] = lo[a] < 0 ? 0 : lo[a], hi[a] = hi[a] >= b->nb[a] ? b->nb[a] - 1 : hi[a];
      }
      for (int z = lo[2]; z <= hi[2]; z++)
        for (int y = lo[1]; y <= hi[1]; y++)
          for (int x = lo[0]; x <= hi[0]; x++) {
            size_t k = (size_t)x + (size_t)b->nb[0] * ((size_t)y + (size_t)b->nb[1] * (size_t)z);
            if (pass)
              b->idx[fill[k]++] = i;
            else
              b->start[k + 1]++;
          }
    }
    free(fill);
  }
  return KARST_SUCCESS;
}

/**
 * Prepare the replication (Paris et al. 2020, §5); see blocks.h.
 * @return KARST_SUCCESS, KARST_EINVAL (no tiles, tiles of different sizes,
 *         bad region or criteria), KARST_ERANGE (more than 2^24 cells),
 *         KARST_ENOMEM. Time: O(cells × blocks × anchors × terrain cost).
 */
karst_error_t karst_blocks_replicate(karst_ctx_t *ctx, const karst_sdf_t *tree, karst_int_t terrain,
                                     const karst_blocks_tile_t *const *tiles, int n_tiles,
                                     karst_blocks_stratum_fn stratum_of, void *stratum_arg,
                                     const int *stratum_tile, int n_strata,
                                     const karst_blocks_presence_t *presence,
                                     const double region[6], karst_blocks_replica_t **out) {
  *out = NULL;
  if (!tree || terrain < 0 || terrain >= tree->n_nodes)
    return karst_set_error(ctx, KARST_EINVAL, "blocks: the terrain node does not exist");
  if (n_tiles < 1 || !tiles) return karst_set_error(ctx, KARST_EINVAL, "blocks: no tiles given");
  double s = tiles[0]->par.size;
  for (int k = 1; k < n_tiles; k++)
    if (tiles[k]->par.size != s)
      return karst_set_error(ctx, KARST_EINVAL,
                             "blocks: all tiles must have the same size (%g m and %g m)", s,
                             tiles[k]->par.size);
  for (int a = 0; a < 3; a++)
    if (!isfinite(region[a]) || !isfinite(region[a + 3]) || !(region[a] < region[a + 3]))
      return karst_set_error(ctx, KARST_EINVAL, "blocks: region axis %d is [%g, %g]", a, region[a],
                             region[a + 3]);
  const karst_blocks_presence_t *P = presence;
  if (!(P->dist_min <= P->dist_max) || !isfinite(P->dist_min) || !isfinite(P->dist_max) ||
      !(P->max_slope > 0 && P->max_slope <= 1) || P->n_anchors < 1 || P->n_anchors > 1000 ||
      !(P->quorum >= 0 && P->quorum < 1))
    return karst_set_error(ctx, KARST_EINVAL,
                           "blocks: presence needs distance min <= max, 0 < max_slope <= 1, "
                           "1..1000 anchors and quorum in [0, 1)");
  karst_error_t err = KARST_SUCCESS;
  karst_blocks_replica_t *r = calloc(1, sizeof *r);
  if (!r) return karst_set_error(ctx, KARST_ENOMEM, "blocks: out of memory");
  r->tree = tree, r->terrain = terrain, r->n_tiles = n_tiles, r->s = s;
  r->cap = KARST_I_BLOCKS_CAP_REL * s;
  r->stratum_of = stratum_of, r->stratum_arg = stratum_arg;
  r->stratum_tile = stratum_tile, r->n_strata = n_strata, r->pres = *P;
  r->tiles = malloc((size_t)n_tiles * sizeof *r->tiles);
  r->bins = calloc((size_t)n_tiles, sizeof *r->bins);
  r->toff = malloc(((size_t)n_tiles + 1) * sizeof *r->toff);
  if (!r->tiles || !r->bins || !r->toff) goto nomem;
  double ncells = 1;
  for (int a = 0; a < 3; a++) {
    r->c0[a] = (int64_t)floor(region[a] / s) - 1;
    r->nc[a] = (int64_t)floor(region[a + 3] / s) + 1 - r->c0[a] + 1;
    ncells *= (double)r->nc[a];
  }
  if (ncells > (double)(1 << 24)) {
    err = karst_set_error(ctx, KARST_ERANGE,
                          "blocks: the region holds %.0f cells of %g m; use a smaller region",
                          ncells, s);
    goto fail;
  }
  r->toff[0] = 0;
  for (int k = 0; k < n_tiles; k++) {
    r->tiles[k] = tiles[k];
    r->toff[k + 1] = r->toff[k] + (karst_int_t)ncells * tiles[k]->n_blocks;
    if ((err = make_bins(ctx, tiles[k], r->cap, &r->bins[k]))) goto fail;
  }
  r->present = calloc((size_t)r->toff[n_tiles] + 1, 1);
  if (!r->present) goto nomem;
  pres_job_t J = {r, (int64_t)ncells};
  karst_i_parallel_run(ctx && ctx->nthreads > 0 ? ctx->nthreads : 1, task_presence, &J);
  for (karst_int_t i = 0; i < r->toff[n_tiles]; i++)
    r->count += r->present[i];
  for (int a = 0; a < 3; a++) {
    r->box[a] = s * (double)r->c0[a] - s;
    r->box[a + 3] = s * (double)(r->c0[a] + r->nc[a]) + s;
  }
  *out = r;
  return KARST_SUCCESS;
nomem:
  err = karst_set_error(ctx, KARST_ENOMEM, "blocks: out of memory for the replication");
fail:
  karst_blocks_replica_free(r);
  return err;
}

/* The replication field (external node callback; contract in implicit.h). */
static double replica_field(const void *arg, const double p[3], double ub, int *label) {
  const karst_blocks_replica_t *r = arg;
  double s = r->s, best = ub < r->cap ? ub : r->cap, q[3];
  int64_t c[3];
  int lab = KARST_SDF_NO_LABEL;
  for (int a = 0; a < 3; a++) {
    c[a] = (int64_t)floor(p[a] / s);
    q[a] = p[a] - s * (double)c[a];
  }
  for (int k = 0; k < r->n_tiles; k++) {
    const tbins_t *b = &r->bins[k];
    const karst_blocks_tile_t *t = r->tiles[k];
    int lo[3], hi[3];
    for (int a = 0; a < 3; a++) { /* copies whose grown box can hold p */
      lo[a] = (int)ceil((q[a] - b->box[a + 3]) / s);
      hi[a] = (int)floor((q[a] - b->box[a]) / s);
    }
    for (int lz = lo[2]; lz <= hi[2]; lz++)
      for (int ly = lo[1]; ly <= hi[1]; ly++)
        for (int lx = lo[0]; lx <= hi[0]; lx++) {
          int64_t C[3] = {c[0] + lx, c[1] + ly, c[2] + lz}, cell = 0, mul = 1;
          int ok = 1;
          for (int a = 0; a < 3; a++) {
            int64_t i = C[a] - r->c0[a];
            if (i < 0 || i >= r->nc[a]) ok = 0;
            cell += i * mul;
            mul *= r->nc[a];
          }
          if (!ok) continue;
          double x[3] = {q[0] - s * lx, q[1] - s * ly, q[2] - s * lz};
          int bi[3];
          for (int a = 0; a < 3; a++) {
            bi[a] = (int)floor((x[a] - b->box[a]) / b->cell[a]);
            if (bi[a] < 0 || bi[a] >= b->nb[a]) ok = 0;
          }
          if (!ok) continue;
          size_t bin =
              (size_t)bi[0] + (size_t)b->nb[0] * ((size_t)bi[1] + (size_t)b->nb[1] * bi[2]);
          const unsigned char *pr = r->present + r->toff[k] + cell * t->n_blocks;
          for (karst_int_t j = b->start[bin]; j < b->start[bin + 1]; j++) {
            karst_int_t i = b->idx[j];
            if (!pr[i] || karst_i_sdbox(t->blocks[i].box, x) >= best) continue;
            int l;
            double v = karst_i_blocks_block_eval(t, i, x, best, &l);
            if (v < best) best = v, lab = l;
          }
        }
  }
  if (label) *label = lab;
  return best;
}

/**
 * Add the replication field to @p tree as an external node (see blocks.h).
 * Time complexity: O(1); one evaluation costs O(copies near p × planes).
 */
karst_error_t karst_blocks_replica_node(karst_ctx_t *ctx, const karst_blocks_replica_t *rep,
                                        karst_sdf_t *tree, karst_int_t *node) {
  if (!rep) return karst_set_error(ctx, KARST_EINVAL, "blocks: no replication given");
  return karst_sdf_external(ctx, tree, replica_field, rep, rep->box, KARST_SDF_NO_LABEL, node);
}
