/* karst blocks: rock blocks from fractured tiles (Paris et al. 2020); the
 * method lives in src/blocks/, this file reads arguments and writes files. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cli.h"
#include "karst/blocks.h"

static double cli_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static int run(int argc, char **argv) {
  const char *scen = NULL, *outdir = NULL, *tile_name = NULL;
  uint64_t seed = 1;
  int have_seed = 0, quiet = 0, threads = 0, voxel_given = 0, resized = 0;
  double voxel = 0.25, tile_size = 0, poisson_radius = 0;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    int more = i + 1 < argc;
    if (cli_is_help(a)) {
      cli_print_help(cli_find_command("blocks"));
      return CLI_OK;
    } else if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
      if (!more) return cli_usage_error("blocks", "%s needs a directory", a);
      outdir = argv[++i];
    } else if (!strcmp(a, "--tile")) {
      if (!more) return cli_usage_error("blocks", "--tile needs a block type");
      tile_name = argv[++i];
    } else if (!strcmp(a, "--seed")) {
      if (!more || cli_parse_u64(argv[i + 1], &seed))
        return cli_usage_error("blocks",
                               "--seed must be an integer from 0 to 18446744073709551615, got '%s'",
                               more ? argv[i + 1] : "");
      have_seed = 1;
      i++;
    } else if (!strcmp(a, "--voxel")) {
      if (!more || cli_parse_double(argv[i + 1], &voxel) || !(voxel > 0))
        return cli_usage_error("blocks", "--voxel needs a size > 0 in metres, got '%s'",
                               more ? argv[i + 1] : "");
      voxel_given = 1;
      i++;
    } else if (!strcmp(a, "--tile-size") || !strcmp(a, "--poisson-radius")) {
      double *v = a[2] == 't' ? &tile_size : &poisson_radius;
      if (!more || cli_parse_double(argv[i + 1], v) || !(*v > 0))
        return cli_usage_error("blocks", "%s needs a length > 0 in metres, got '%s'", a,
                               more ? argv[i + 1] : "");
      resized = 1;
      i++;
    } else if (!strcmp(a, "-j") || !strcmp(a, "--threads")) {
      if (!more || cli_parse_int(argv[i + 1], &threads) || threads < 1 ||
          threads > KARST_ENSEMBLE_MAX_THREADS)
        return cli_usage_error("blocks",
                               "%s must be a whole number of threads within [1, %d], got '%s'", a,
                               KARST_ENSEMBLE_MAX_THREADS, more ? argv[i + 1] : "");
      i++;
    } else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) {
      quiet = 1;
    } else if (a[0] == '-' && a[1] != '\0') {
      return cli_usage_error("blocks", "unknown option '%s'", a);
    } else if (!scen) {
      scen = a;
    } else {
      return cli_usage_error("blocks", "more than one scenario given ('%s' and '%s')", scen, a);
    }
  }
  if (!outdir) return cli_usage_error("blocks", "no output directory given (-o DIR)");
  if (!tile_name && !scen)
    return cli_usage_error("blocks", "give a scenario with a blocks section, or --tile TYPE");
  if (tile_name && scen)
    return cli_usage_error("blocks", "--tile makes one tile without a scenario; give one of them");
  if (scen && have_seed)
    return cli_usage_error("blocks", "--seed goes with --tile; a scenario sets blocks.seed");
  if (scen && resized)
    return cli_usage_error("blocks", "--tile-size and --poisson-radius go with --tile; a scenario "
                                     "sets blocks.tile_size and blocks.poisson_radius");
  int type = -1;
  if (tile_name) {
    type = karst_block_type_from_name(tile_name);
    if (type < 0) {
      char list[256] = "";
      for (int t = 0; t < KARST_BLOCK_TYPE_COUNT; t++)
        snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", t ? ", " : "",
                 karst_block_type_name(t));
      return cli_usage_error("blocks", "--tile must be one of %s, got '%s'", list, tile_name);
    }
  }
  karst_ctx_t ctx;
  cli_ctx_init(&ctx, quiet, 0);
  if (threads > 0) ctx.nthreads = threads;
  karst_fileset_t outs;
  karst_fileset_init(&outs);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  karst_blocks_tile_t *tile = NULL;
  karst_blocks_amplified_t *amp = NULL;
  karst_sdf_t *tree = NULL;
  karst_mesh_t mesh;
  karst_mesh_init(&mesh);
  int *bid = NULL, *btype = NULL;
  char *extra = NULL;
  int status = CLI_OK;
  karst_error_t err;
  enum { MAX_OUT = KARST_BLOCK_TYPE_COUNT + 2 };
  char paths[MAX_OUT][4200], tiles_dir[4096];
  const char *tmps[MAX_OUT] = {NULL}, *writing = NULL;
  const karst_blocks_tile_t *const *tl = NULL;
  int n_tiles = 0;
  double tvoxel = voxel, tv0 = 0;
  if (strlen(outdir) > 3900 ||
      snprintf(tiles_dir, sizeof tiles_dir, "%s/tiles", outdir) >= (int)sizeof tiles_dir) {
    err = karst_set_error(&ctx, KARST_EINVAL, "output directory name too long: %s", outdir);
    goto fail;
  }
  if (scen) {
    if ((err = karst_scenario_load(&ctx, scen, &sc))) goto fail;
    if (!sc.blocks) {
      err = karst_set_error(&ctx, KARST_EINVAL,
                            "%s: no blocks section; add one (docs/blocks.md) or use --tile TYPE",
                            scen);
      goto fail;
    }
    if (!voxel_given) tvoxel = sc.blocks->tile_voxel;
  }
  karst_blocks_tile_params_t par;
  if (!scen) { /* checked before anything is written */
    karst_blocks_tile_params_init(&par, type);
    if (have_seed) par.seed = seed;
    if (resized) /* the paper's side and radius unless given; discs scale with the side */
      karst_blocks_tile_params_resize(&par, tile_size > 0 ? tile_size : par.size,
                                      poisson_radius > 0 ? poisson_radius : par.poisson_radius);
    if ((err = karst_blocks_tile_params_check(&ctx, &par))) goto fail;
  }
  /* every output checked and registered before any work */
  int n_out = 0;
  if (scen) {
    int seen[KARST_BLOCK_TYPE_COUNT] = {0};
    for (int i = 0; i < sc.blocks->n_strata; i++) {
      int t = sc.blocks->strata[i].tile;
      if (seen[t]++) continue;
      snprintf(paths[n_out++], sizeof paths[0], "%.4000s/%.32s.vtp", tiles_dir,
               karst_block_type_name(t));
    }
    snprintf(paths[n_out++], sizeof paths[0], "%.4000s/terrain_blocks.vtp", outdir);
  } else {
    snprintf(paths[n_out++], sizeof paths[0], "%.4000s/%.32s.vtp", tiles_dir,
             karst_block_type_name(type));
  }
  if (snprintf(paths[n_out++], sizeof paths[0], "%.4000s/run.json", outdir) >=
      (int)sizeof paths[0]) {
    err = karst_set_error(&ctx, KARST_EINVAL, "output directory name too long: %s", outdir);
    goto fail;
  }
  if (scen) { /* no output may replace the scenario or a file it reads (its relief image too) */
    char **sfiles = NULL;
    int nsf = 0, st = CLI_OK;
    if ((err = karst_scenario_files(&ctx, scen, &sfiles, &nsf))) goto fail;
    for (int i = 0; i < n_out && !st; i++)
      if (!(st = cli_refuse_output_over_input("blocks", paths[i], &scen, 1)))
        st = cli_refuse_output_over_input("blocks", paths[i], (const char *const *)sfiles, nsf);
    for (int k = 0; k < nsf; k++)
      free(sfiles[k]);
    free(sfiles);
    if (st) {
      status = st;
      goto done;
    }
  }
  if ((err = karst_mkdir_p(&ctx, tiles_dir))) goto fail;
  for (int i = 0; i < n_out; i++)
    if ((err = cli_add_output(&ctx, &outs, paths[i], &tmps[i]))) goto fail;
  if (scen) {
    if ((err = karst_sdf_create(&ctx, &tree))) goto fail;
    karst_int_t root;
    if ((err = karst_blocks_amplify(&ctx, &sc, tree, &amp, &root)) ||
        (err = karst_sdf_set_root(&ctx, tree, root)))
      goto fail;
    n_tiles = karst_blocks_amplified_tiles(amp, &tl);
  } else {
    if ((err = karst_blocks_tile_create(&ctx, &par, &tile))) goto fail;
    tl = (const karst_blocks_tile_t *const *)&tile;
    n_tiles = 1;
  }
  for (int k = 0; k < n_tiles; k++) {
    if ((err = karst_blocks_tile_mesh(&ctx, tl[k], tvoxel, &mesh))) goto fail;
    writing = paths[k];
    if ((err = karst_vtk_write_mesh(&ctx, tmps[k], &mesh))) goto fail_write;
    if (!quiet)
      printf("%s: %s tile, %lld points, %lld discs, %lld blocks (%.0f points per block) in "
             "%.2f s; %lld triangles at voxel %g m\n",
             paths[k], karst_block_type_name(tl[k]->par.type), (long long)tl[k]->stats.n_points,
             (long long)tl[k]->stats.n_discs, (long long)tl[k]->stats.n_blocks,
             tl[k]->stats.mean_points, tl[k]->stats.seconds, (long long)mesh.n_triangles, tvoxel);
  }
  char cmd[4400];
  if (scen) {
    double box[6];
    karst_blocks_amplified_box(amp, box);
    double v = voxel_given ? voxel : sc.blocks->voxel;
    tv0 = cli_now();
    if ((err = karst_mesh_polygonize(&ctx, tree, box, v, &mesh, NULL))) goto fail;
    double tpoly = cli_now() - tv0;
    bid = malloc((size_t)(mesh.n_triangles + 1) * sizeof *bid);
    btype = malloc((size_t)(mesh.n_triangles + 1) * sizeof *btype);
    if (!bid || !btype) {
      err = karst_set_error(&ctx, KARST_ENOMEM, "out of memory");
      goto fail;
    }
    karst_blocks_relabel_mesh(&ctx, tree, &mesh, bid, btype);
    free(mesh.tri_label);
    mesh.tri_label = NULL;
    const char *names[2] = {"block_id", "block_type"};
    const int *arrs[2] = {bid, btype};
    writing = paths[n_tiles];
    if ((err = karst_vtk_write_mesh_arrays(&ctx, tmps[n_tiles], &mesh, 2, names, arrs)))
      goto fail_write;
    karst_int_t on_blocks = 0;
    for (karst_int_t t = 0; t < mesh.n_triangles; t++)
      on_blocks += bid[t] >= 0;
    const karst_blocks_presence_t *P = &sc.blocks->presence;
    size_t cap = 4096 + 256 * (size_t)sc.blocks->n_strata;
    extra = malloc(cap);
    if (!extra) {
      err = karst_set_error(&ctx, KARST_ENOMEM, "out of memory");
      goto fail;
    }
    int len =
        snprintf(extra, cap,
                 "  \"scenario\": \"%s\",\n  \"replication\": {\"region\": [%.17g, %.17g, "
                 "%.17g, %.17g, %.17g, %.17g], \"voxel\": %.17g, \"tile_voxel\": %.17g, "
                 "\"distance\": [%.17g, %.17g], \"max_slope\": %.17g, \"anchors\": %d, "
                 "\"quorum\": %.17g, \"copies\": %lld, \"triangles\": %lld, "
                 "\"block_triangles\": %lld, \"polygonize_seconds\": %.3f,\n    \"strata\": [",
                 sc.path ? sc.path : scen, box[0], box[1], box[2], box[3], box[4], box[5], v,
                 tvoxel, P->dist_min, P->dist_max, P->max_slope, P->n_anchors, P->quorum,
                 (long long)karst_blocks_replica_count(karst_blocks_amplified_replica(amp)),
                 (long long)mesh.n_triangles, (long long)on_blocks, tpoly);
    for (int i = 0; i < sc.blocks->n_strata && len > 0 && (size_t)len < cap; i++) {
      const karst_blocks_stratum_t *st = &sc.blocks->strata[i];
      char below[64] = "null";
      if (isfinite(st->below)) snprintf(below, sizeof below, "%.17g", st->below);
      len += snprintf(extra + len, cap - (size_t)len,
                      "%s{\"name\": \"%s\", \"below\": %s, \"tile\": \"%s\"}", i ? ", " : "",
                      st->name, below, karst_block_type_name(st->tile));
    }
    if (len > 0 && (size_t)len < cap) snprintf(extra + len, cap - (size_t)len, "]}");
    snprintf(cmd, sizeof cmd, "karst blocks %s", scen);
    if (!quiet)
      printf("%s: %lld triangles (%lld on %lld block copies), voxel %g m, polygonized in %.2f s\n",
             paths[n_tiles], (long long)mesh.n_triangles, (long long)on_blocks,
             (long long)karst_blocks_replica_count(karst_blocks_amplified_replica(amp)), v, tpoly);
  } else {
    snprintf(cmd, sizeof cmd,
             "karst blocks --tile %s --seed %llu --voxel %g --tile-size %g --poisson-radius %g",
             karst_block_type_name(type), (unsigned long long)tl[0]->par.seed, tvoxel,
             tl[0]->par.size, tl[0]->par.poisson_radius);
  }
  writing = paths[n_out - 1];
  if ((err = karst_blocks_write_run(&ctx, tmps[n_out - 1], tl, n_tiles, cmd, extra)))
    goto fail_write;
  if (karst_interrupted(&ctx)) {
    err = karst_set_error(&ctx, KARST_EINTERRUPTED, "interrupted; no output was kept");
    goto fail;
  }
  if ((err = karst_fileset_commit(&ctx, &outs))) goto fail;
  goto done;
fail_write:
  cli_note_failed_output(&ctx, err, writing);
fail:
  status = cli_fail("blocks", &ctx, err);
done:
  karst_fileset_abort(&outs);
  karst_mesh_destroy(&mesh);
  karst_blocks_tile_free(tile);
  karst_blocks_amplified_free(amp);
  karst_sdf_free(tree);
  karst_scenario_destroy(&sc);
  free(bid);
  free(btype);
  free(extra);
  return status;
}

const cli_command_t cli_cmd_blocks = {
    "blocks", run, "rock blocks from fractured periodic tiles (Paris et al. 2020)",
    "usage: karst blocks SCENARIO.yaml -o DIR [--voxel H] [-j THREADS] [--quiet]\n"
    "       karst blocks --tile TYPE -o DIR [--seed S] [--voxel H] [--tile-size S]\n"
    "                    [--poisson-radius R] [-j THREADS] [--quiet]\n\n"
    "With a scenario, builds one tile per block type of the strata of its blocks section,\n"
    "replicates them over the scenario's terrain where the presence criteria hold (Paris et al.\n"
    "2020, §5: distance to the terrain, slope, stratum) and writes\n"
    "  DIR/tiles/TYPE.vtp       each tile's blocks, cell array block_id\n"
    "  DIR/terrain_blocks.vtp   the amplified terrain, cell arrays block_id and block_type\n"
    "                           (-1 on the bare terrain)\n"
    "  DIR/run.json             every parameter and the Table 1 statistics per tile\n\n"
    "With --tile, "
    "makes one periodic tile of rock blocks of TYPE (equidimensional, prismatic, polyhedral,\n"
    "rhombohedral, tabular or columnar) with the defaults of docs/blocks.md (Paris et al. 2020,\n"
    "§4: a 20 m tile, about 14 500 Poisson points, fracture discs per type, clusters split\n"
    "until mutually visible, convex blocks with smooth edges), and writes\n"
    "  DIR/tiles/TYPE.vtp   every block polygonized, closed, with the cell array block_id\n"
    "  DIR/run.json         every parameter and the Table 1 statistics of the tile\n\n"
    "  --seed S       seed of the tile (default 1)\n"
    "  --tile-size S  side of the --tile tile in metres (default 20); the fracture discs'\n"
    "                 sizes and spacings scale with it, their counts stay the paper's\n"
    "  --poisson-radius R  smallest distance between sample points of the --tile tile in\n"
    "                 metres (default 0.69: about 14 500 points in 20 m)\n"
    "  --voxel H      polygonization step in metres (default: blocks.tile_voxel and\n"
    "                 blocks.voxel of the scenario, 0.25 for --tile)\n"
    "  -j THREADS     worker threads, 1 to 1024 (default: all processors); the output does not\n"
    "                 depend on it\n"
    "  --quiet        no progress and no summary\n\n"
    "The method and its departures from the paper are described in docs/blocks.md.\n"};
