/* What `karst blocks` writes besides the meshes: run.json with every
 * parameter of every tile and the statistics of Table 1 of Paris et al. 2020. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "karst/blocks.h"
#include "karst/io.h"

static void num(FILE *fp, const char *key, double v, int last) {
  if (isfinite(v))
    fprintf(fp, "\"%s\": %.17g%s", key, v, last ? "" : ", ");
  else
    fprintf(fp, "\"%s\": null%s", key, last ? "" : ", ");
}

/**
 * Write the parameters and Table 1 statistics of @p n tiles as JSON (an
 * atomic file). @p extra, when not NULL, is written verbatim as further
 * members of the top object (e.g. the replication's figures), without a
 * leading comma. Time complexity: O(n + user discs).
 */
karst_error_t karst_blocks_write_run(karst_ctx_t *ctx, const char *path,
                                     const karst_blocks_tile_t *const *tiles, int n,
                                     const char *command, const char *extra) {
  karst_atomic_file_t f;
  karst_error_t err = karst_atomic_open(ctx, &f, path, "w");
  if (err) return err;
  FILE *fp = f.fp;
  fprintf(fp, "{\n  \"command\": ");
  karst_json_string(fp, command ? command : "karst blocks");
  fprintf(fp, ",\n  \"method\": \"Paris et al. 2020, Modeling rocky scenery using implicit blocks, "
              "sections 4-5\",\n  \"tiles\": [\n");
  for (int i = 0; i < n; i++) {
    const karst_blocks_tile_t *t = tiles[i];
    const karst_blocks_tile_params_t *p = &t->par;
    fprintf(fp, "    {\"type\": \"%s\", \"seed\": %llu, ", karst_block_type_name(p->type),
            (unsigned long long)p->seed);
    num(fp, "tile_size", p->size, 0);
    num(fp, "poisson_radius", p->poisson_radius, 0);
    num(fp, "graph_radius", p->graph_radius, 0);
    num(fp, "smooth_radius", p->smooth_radius, 0);
    num(fp, "aperture", p->aperture, 0);
    num(fp, "hull_margin", p->hull_margin, 0);
    num(fp, "degenerate_radius", p->degenerate_radius, 0);
    fprintf(fp, "\"discs\": %d, ", p->n_discs);
    num(fp, "disc_spacing", p->disc_spacing, 0);
    num(fp, "disc_radius_min", p->disc_radius_min, 0);
    num(fp, "disc_radius_max", p->disc_radius_max, 0);
    num(fp, "tilt", p->tilt, 0);
    fprintf(fp, "\"bedding\": %d, ", p->n_bedding);
    num(fp, "bedding_spacing", p->bedding_spacing, 0);
    fprintf(fp, "\"dart_passes\": %d, \"user_discs\": %d, \"authored_blocks\": %d,\n",
            p->dart_passes, p->n_user_discs, p->n_authored);
    fprintf(fp, "     \"table1\": {\"points\": %lld, \"discs\": %lld, \"blocks\": %lld, ",
            (long long)t->stats.n_points, (long long)t->stats.n_discs,
            (long long)t->stats.n_blocks);
    num(fp, "mean_points_per_block", t->stats.mean_points, 0);
    num(fp, "seconds", t->stats.seconds, 1);
    fprintf(fp,
            "},\n     \"edges\": %lld, \"cut_edges\": %lld, \"splits\": %lld, "
            "\"degenerate_blocks\": %lld}%s\n",
            (long long)t->stats.n_edges, (long long)t->stats.n_cut, (long long)t->stats.n_splits,
            (long long)t->stats.n_thick, i + 1 < n ? "," : "");
  }
  fprintf(fp, "  ]%s%s\n}\n", extra ? ",\n" : "", extra ? extra : "");
  return karst_atomic_commit(ctx, &f);
}
