/* A scenario's terrain amplified with blocks (Paris et al. 2020, §5): the
 * tiles of the strata's types, the replication over the terrain, and the
 * union T ∪ R as one node of a construction tree. Shared by `karst blocks`
 * and `karst mesh --blocks`. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/parallel_internal.h"
#include "karst/blocks.h"

struct karst_blocks_amplified {
  karst_blocks_tile_t *tiles[KARST_BLOCK_TYPE_COUNT];
  int n_tiles;
  int *stratum_tile;
  karst_blocks_replica_t *rep;
  const karst_blocks_section_t *sec;
  karst_sdf_t *authored;       /* the section's authored blocks, borrowed by the tiles */
  karst_int_t *authored_nodes; /* their nodes, tile by tile */
  karst_blocks_disc_t *discs;  /* the section's user discs, tile by tile, borrowed by the tiles */
  double box[6];
};

void karst_blocks_amplified_free(karst_blocks_amplified_t *a) {
  if (!a) return;
  for (int k = 0; k < a->n_tiles; k++)
    karst_blocks_tile_free(a->tiles[k]);
  karst_sdf_free(a->authored);
  free(a->authored_nodes);
  free(a->discs);
  free(a->stratum_tile);
  karst_blocks_replica_free(a->rep);
  free(a);
}

int karst_blocks_amplified_tiles(const karst_blocks_amplified_t *a,
                                 const karst_blocks_tile_t *const **tiles) {
  *tiles = (const karst_blocks_tile_t *const *)a->tiles;
  return a->n_tiles;
}

const karst_blocks_replica_t *karst_blocks_amplified_replica(const karst_blocks_amplified_t *a) {
  return a->rep;
}

void karst_blocks_amplified_box(const karst_blocks_amplified_t *a, double box[6]) {
  memcpy(box, a->box, 6 * sizeof *box);
}

/**
 * Build the tiles of the blocks section of @p sc (one per distinct tile type
 * of its strata, seed the section's or the scenario's), replicate them over
 * the scenario's terrain within the section's region (default: the domain)
 * and add T ∪ R to @p tree; *node is that union. @p sc and @p tree must
 * outlive *out. Progress "blocks". Time: the tiles plus the presence test of
 * every (cell, block) of the region.
 * @return KARST_SUCCESS, KARST_EINVAL (no blocks section), the tiles' and
 *         the replication's errors; *out is NULL on failure.
 */
karst_error_t karst_blocks_amplify(karst_ctx_t *ctx, const karst_scenario_t *sc, karst_sdf_t *tree,
                                   karst_blocks_amplified_t **out, karst_int_t *node) {
  *out = NULL;
  const karst_blocks_section_t *b = sc->blocks;
  if (!b)
    return karst_set_error(ctx, KARST_EINVAL, "%s: the scenario has no blocks section",
                           sc->path ? sc->path : "scenario");
  karst_error_t err = KARST_SUCCESS;
  karst_blocks_amplified_t *a = calloc(1, sizeof *a);
  if (!a) return karst_set_error(ctx, KARST_ENOMEM, "blocks: out of memory");
  a->sec = b;
  a->stratum_tile = malloc((size_t)(b->n_strata + 1) * sizeof *a->stratum_tile);
  if (!a->stratum_tile) {
    err = karst_set_error(ctx, KARST_ENOMEM, "blocks: out of memory");
    goto fail;
  }
  uint64_t seed = b->has_seed ? b->seed : sc->seed;
  if (b->n_authored) {
    if ((err = karst_sdf_create(ctx, &a->authored))) goto fail;
    a->authored_nodes = malloc((size_t)b->n_authored * sizeof *a->authored_nodes);
    if (!a->authored_nodes) {
      err = karst_set_error(ctx, KARST_ENOMEM, "blocks: out of memory");
      goto fail;
    }
  }
  if (b->n_user_discs) {
    a->discs = malloc((size_t)b->n_user_discs * sizeof *a->discs);
    if (!a->discs) {
      err = karst_set_error(ctx, KARST_ENOMEM, "blocks: out of memory");
      goto fail;
    }
  }
  int used = 0, used_discs = 0;
  for (int i = 0; i < b->n_strata; i++) {
    int k = 0;
    while (k < a->n_tiles && a->tiles[k]->par.type != b->strata[i].tile)
      k++;
    if (k == a->n_tiles) {
      karst_blocks_tile_params_t par;
      karst_blocks_section_tile_params(b, b->strata[i].tile, seed, &par);
      if (a->authored) { /* this type's authored blocks (tile coordinates) */
        if ((err = karst_blocks_section_authored(ctx, b, par.type, a->authored,
                                                 a->authored_nodes + used, &par.n_authored)))
          goto fail;
        par.authored = a->authored;
        par.authored_nodes = a->authored_nodes + used;
        used += par.n_authored;
      }
      if (a->discs) { /* this type's user-placed discs (tile coordinates) */
        par.user_discs = a->discs + used_discs;
        par.n_user_discs = karst_blocks_section_user_discs(b, par.type, a->discs + used_discs);
        used_discs += par.n_user_discs;
        if (!par.n_user_discs) par.user_discs = NULL;
      }
      if ((err = karst_blocks_tile_create(ctx, &par, &a->tiles[k]))) goto fail;
      a->n_tiles++;
    }
    a->stratum_tile[i] = k;
  }
  for (int c = 0; c < 2; c++) {
    a->box[c] = b->has_region ? b->region[c] : sc->domain_min[c];
    a->box[c + 3] = b->has_region ? b->region[c + 2] : sc->domain_max[c];
  }
  a->box[2] = sc->domain_min[2], a->box[5] = sc->domain_max[2];
  karst_int_t tn, rn, kids[2];
  if ((err = karst_sdf_terrain(ctx, tree, &sc->terrain, &tn))) goto fail;
  if ((err = karst_blocks_replicate(ctx, tree, tn, (const karst_blocks_tile_t *const *)a->tiles,
                                    a->n_tiles, karst_blocks_section_stratum, (void *)b,
                                    a->stratum_tile, b->n_strata, &b->presence, a->box, &a->rep)))
    goto fail;
  if ((err = karst_blocks_replica_node(ctx, a->rep, tree, &rn))) goto fail;
  kids[0] = tn, kids[1] = rn;
  if ((err = karst_sdf_union(ctx, tree, 2, kids, node))) goto fail;
  *out = a;
  return KARST_SUCCESS;
fail:
  karst_blocks_amplified_free(a);
  return err;
}

/* Task of karst_blocks_relabel_mesh: triangles t = tid, tid + nth, ... */
typedef struct relabel_job {
  const karst_sdf_t *tree;
  karst_mesh_t *m;
  int *id, *type;
} relabel_job_t;

static void task_relabel(void *arg, int tid, int nth) {
  relabel_job_t *J = arg;
  karst_mesh_t *m = J->m;
  for (karst_int_t t = tid; t < m->n_triangles; t += nth) {
    const double *a = m->xyz + 3 * m->tri[3 * t], *b = m->xyz + 3 * m->tri[3 * t + 1],
                 *c = m->xyz + 3 * m->tri[3 * t + 2];
    double e1[3], e2[3], n[3], q[3], len = 0;
    for (int k = 0; k < 3; k++)
      e1[k] = b[k] - a[k], e2[k] = c[k] - a[k];
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    double nl = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int k = 0; k < 3; k++)
      len += fabs(e1[k]) + fabs(e2[k]);
    /* a point just inside the solid, as the polygonizer's inside corner */
    double d = KARST_BLOCKS_RELABEL_DEPTH * len / 3;
    for (int k = 0; k < 3; k++)
      q[k] = (a[k] + b[k] + c[k]) / 3 - (nl > 0 ? d * n[k] / nl : 0);
    int lab = KARST_SDF_NO_LABEL, ty, i;
    (void)karst_sdf_eval(J->tree, q, &lab);
    int blk = karst_blocks_label_decode(lab, &ty, &i);
    if (m->tri_label) m->tri_label[t] = blk ? KARST_SDF_NO_LABEL : lab;
    if (J->id) J->id[t] = i;
    if (J->type) J->type[t] = ty;
  }
}

/**
 * Label the triangles of a mesh polygonized from @p tree (whose root holds
 * block copies) by the primitive that decides the field just inside each
 * triangle (a step of KARST_BLOCKS_RELABEL_DEPTH times its size along the
 * inward normal): @p id and @p type (may be NULL) receive the block id and
 * type (-1 elsewhere); m->tri_label keeps tunnel types and is -1 on blocks.
 * The polygonizer stores labels in 8 bits, too few for block labels.
 * Runs on ctx->nthreads threads. Time: O(triangles × field cost).
 */
void karst_blocks_relabel_mesh(karst_ctx_t *ctx, const karst_sdf_t *tree, karst_mesh_t *m, int *id,
                               int *type) {
  relabel_job_t J = {tree, m, id, type};
  karst_i_parallel_run(ctx && ctx->nthreads > 0 ? ctx->nthreads : 1, task_relabel, &J);
}
