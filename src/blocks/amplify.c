/* A scenario's terrain amplified with blocks (Paris et al. 2020, §5): the
 * tiles of the strata's types, the replication over the terrain, and the
 * union T ∪ R as one node of a construction tree. Shared by `karst blocks`
 * and `karst mesh --blocks`. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "karst/blocks.h"

struct karst_blocks_amplified {
  karst_blocks_tile_t *tiles[KARST_BLOCK_TYPE_COUNT];
  int n_tiles;
  int *stratum_tile;
  karst_blocks_replica_t *rep;
  const karst_blocks_section_t *sec;
  char *image; /* the relief image, relative to the scenario */
  double box[6];
};

void karst_blocks_amplified_free(karst_blocks_amplified_t *a) {
  if (!a) return;
  for (int k = 0; k < a->n_tiles; k++)
    karst_blocks_tile_free(a->tiles[k]);
  free(a->stratum_tile);
  free(a->image);
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
  if (b->warp_image) { /* relative to the scenario's directory, as the heightfield */
    const char *path = sc->path ? sc->path : "", *slash = strrchr(path, '/');
    size_t dl = (b->warp_image[0] == '/' || !slash) ? 0 : (size_t)(slash - path) + 1;
    a->image = malloc(dl + strlen(b->warp_image) + 1);
    if (!a->image) {
      err = karst_set_error(ctx, KARST_ENOMEM, "blocks: out of memory");
      goto fail;
    }
    memcpy(a->image, path, dl);
    strcpy(a->image + dl, b->warp_image);
  }
  for (int i = 0; i < b->n_strata; i++) {
    int k = 0;
    while (k < a->n_tiles && a->tiles[k]->par.type != b->strata[i].tile)
      k++;
    if (k == a->n_tiles) {
      karst_blocks_tile_params_t par;
      karst_blocks_section_tile_params(b, b->strata[i].tile, seed, &par);
      par.warp.image = a->image;
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

/**
 * Split the labels of a polygonized amplified terrain into per-triangle
 * block_id and block_type (-1 on the terrain and other primitives), and put
 * -1 in the mesh's own labels where a block decided (so a tunnel_type array
 * keeps only tunnel types). @p id and @p type hold m->n_triangles values.
 * Time complexity: O(triangles).
 */
void karst_blocks_mesh_labels(karst_mesh_t *m, int *id, int *type) {
  for (karst_int_t t = 0; t < m->n_triangles; t++) {
    int l = m->tri_label ? m->tri_label[t] : -1, ty, i;
    if (karst_blocks_label_decode(l, &ty, &i)) {
      if (m->tri_label) m->tri_label[t] = -1;
    }
    id[t] = i, type[t] = ty;
  }
}
