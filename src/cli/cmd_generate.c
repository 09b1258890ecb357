/* karst generate: one realisation of a scenario, written to a directory. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

/* DIR/name into a fresh buffer (caller frees). */
static char *join(const char *dir, const char *name) {
  size_t n = strlen(dir) + strlen(name) + 2;
  char *p = malloc(n);
  if (p) snprintf(p, n, "%s/%s", dir, name);
  return p;
}

static int run(int argc, char **argv) {
  const char *scenario = NULL, *outdir = NULL;
  uint64_t seed = 0;
  int have_seed = 0, want_samples = 0, quiet = 0, verbose = 0, threads = 0;
  double max_memory = 0;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    if (cli_is_help(a)) {
      cli_print_help(cli_find_command("generate"));
      return CLI_OK;
    } else if (strcmp(a, "-o") == 0 || strcmp(a, "--output") == 0) {
      if (++i >= argc) return cli_usage_error("generate", "%s needs a directory", a);
      outdir = argv[i];
    } else if (strcmp(a, "--seed") == 0) {
      if (++i >= argc || cli_parse_u64(argv[i], &seed))
        return cli_usage_error("generate",
                               "--seed must be an integer from 0 to 18446744073709551615, got '%s'",
                               i < argc ? argv[i] : "");
      have_seed = 1;
    } else if (strcmp(a, "--threads") == 0) {
      if (++i >= argc || cli_parse_int(argv[i], &threads) || threads < 1 ||
          threads > KARST_ENSEMBLE_MAX_THREADS)
        return cli_usage_error("generate",
                               "--threads must be a whole number of threads within [1, %d], got "
                               "'%s'",
                               KARST_ENSEMBLE_MAX_THREADS, i < argc ? argv[i] : "");
    } else if (strcmp(a, "--max-memory") == 0) {
      if (++i >= argc || karst_budget_parse_size(argv[i], &max_memory))
        return cli_usage_error("generate", "--max-memory needs a size such as 512M or 8G, got '%s'",
                               i < argc ? argv[i] : "");
    } else if (strcmp(a, "--samples") == 0) {
      want_samples = 1;
    } else if (strcmp(a, "--quiet") == 0 || strcmp(a, "-q") == 0) {
      quiet = 1;
    } else if (strcmp(a, "--verbose") == 0 || strcmp(a, "-v") == 0) {
      verbose = 1;
    } else if (a[0] == '-' && a[1] != '\0') {
      return cli_usage_error("generate", "unknown option '%s'", a);
    } else if (!scenario) {
      scenario = a;
    } else {
      return cli_usage_error("generate", "more than one scenario given ('%s' and '%s')", scenario,
                             a);
    }
  }
  if (!scenario) return cli_usage_error("generate", "no scenario file given");
  if (!outdir) return cli_usage_error("generate", "no output directory given (-o DIR)");

  karst_ctx_t ctx;
  cli_ctx_init(&ctx, quiet, verbose);
  if (threads > 0) ctx.nthreads = threads;
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  karst_network_t net;
  karst_network_init(&net);
  karst_samples_t samples;
  karst_samples_init(&samples);
  karst_generate_stats_t stats;
  karst_fileset_t files;
  karst_fileset_init(&files);
  karst_geology_t *geo = NULL;
  karst_dir_lock_t lock = {-1, NULL};
  char *path = NULL, *prefix = NULL;
  char writing[4096] = "";
  int status = CLI_OK;
  karst_error_t err;
  if ((err = karst_scenario_load(&ctx, scenario, &sc))) goto fail;
  if ((err = karst_budget_check(&ctx, &sc, ctx.nthreads, max_memory, NULL))) goto fail;
  if (!have_seed) seed = sc.seed;
  /* One generate at a time in DIR (the lock of karst ensemble): two runs writing one set of
   * files would each rename its own into place, leaving a mixed set. */
  if ((err = karst_mkdir_p(&ctx, outdir))) goto fail;
  if ((err = karst_dir_lock(&ctx, outdir, KARST_GENERATE_LOCK_NAME, "generate", &lock))) goto fail;
  if ((err = karst_generate(&ctx, &sc, seed, 0, &net, want_samples ? &samples : NULL, &stats)))
    goto fail;
  /* The six files are one set: each is written to a temporary name, then all are renamed into
   * place with run.json last, so a run that fails leaves no new file, and a previous set in DIR
   * stays whole (karst_fileset_commit). A samples.vtp left by an earlier run with --samples goes
   * when this run writes none, so it never sits beside a network it does not belong to. */
  const char *tmp;
  if (!(path = join(outdir, "network.vtp"))) goto nomem;
  if ((err = karst_fileset_add(&ctx, &files, path, NULL, &tmp))) goto fail;
  snprintf(writing, sizeof writing, "%s", path);
  if ((err = karst_vtk_write_network(&ctx, tmp, &net))) goto fail_write;
  free(path);
  /* Karstnet's writer takes a prefix: temporaries PREFIX_nodes.dat and PREFIX_links.dat. */
  if (!(path = join(outdir, "network")) || !(prefix = karst_temp_name(path))) goto nomem;
  static const char *const dat[2] = {"_nodes.dat", "_links.dat"};
  for (int i = 0; i < 2; i++) {
    char *final = malloc(strlen(path) + 12), *t = malloc(strlen(prefix) + 12);
    if (final) sprintf(final, "%s%s", path, dat[i]);
    if (t) sprintf(t, "%s%s", prefix, dat[i]);
    err = final && t ? karst_fileset_add(&ctx, &files, final, t, NULL)
                     : karst_set_error(&ctx, KARST_ENOMEM, "out of memory");
    free(final);
    free(t);
    if (err) goto fail;
  }
  snprintf(writing, sizeof writing, "%s_nodes.dat and %s_links.dat", path, path);
  if ((err = karst_write_karstnet(&ctx, prefix, &net))) goto fail_write;
  free(path);
  if (!(path = join(outdir, "samples.vtp"))) goto nomem;
  if (want_samples) {
    if ((err = karst_fileset_add(&ctx, &files, path, NULL, &tmp))) goto fail;
    snprintf(writing, sizeof writing, "%s", path);
    if ((err = karst_vtk_write_samples(&ctx, tmp, &samples))) goto fail_write;
  } else if ((err = karst_fileset_add_stale(&ctx, &files, path))) {
    goto fail;
  }
  free(path);
  /* The geology that made the network (the same realisation's fracture discs). */
  if (!(path = join(outdir, "geology.vtp"))) goto nomem;
  if ((err = karst_geology_create(&ctx, &sc, seed, 0, &geo))) goto fail;
  if ((err = karst_fileset_add(&ctx, &files, path, NULL, &tmp))) goto fail;
  snprintf(writing, sizeof writing, "%s", path);
  if ((err = karst_geology_write_vtp(&ctx, geo, tmp))) goto fail_write;
  free(path);
  /* The ParaView script showing the network, the geology (and the samples) in karst's colours. */
  if (!(path = join(outdir, "network" KARST_VIEW_SCRIPT_SUFFIX))) goto nomem;
  if ((err = karst_fileset_add(&ctx, &files, path, NULL, &tmp))) goto fail;
  snprintf(writing, sizeof writing, "%s", path);
  {
    char *vtp = join(outdir, "network.vtp"), *gvtp = join(outdir, "geology.vtp"),
         *svtp = join(outdir, "samples.vtp");
    karst_view_item_t items[3] = {{vtp, KARST_VIEW_NETWORK, NULL},
                                  {gvtp, KARST_VIEW_GEOLOGY, NULL},
                                  {svtp, KARST_VIEW_SAMPLES, NULL}};
    err = vtp && gvtp && svtp
              ? karst_view_write_script(&ctx, tmp, path, items, want_samples ? 3 : 2)
              : karst_set_error(&ctx, KARST_ENOMEM, "out of memory");
    free(vtp);
    free(gvtp);
    free(svtp);
    if (err) goto fail_write;
  }
  free(path);
  if (!(path = join(outdir, "run.json"))) goto nomem;
  if ((err = karst_fileset_add(&ctx, &files, path, NULL, &tmp))) goto fail;
  snprintf(writing, sizeof writing, "%s", path);
  if ((err = karst_generate_write_run(&ctx, tmp, &sc, seed, 0, &stats))) goto fail_write;
  if ((err = karst_fileset_commit(&ctx, &files))) goto fail;
  if (!quiet)
    printf("%s: seed %llu: %lld samples, %lld key points, %lld skeleton paths, network of %lld "
           "nodes, %lld edges, %.1f m -> %s/\n",
           scenario, (unsigned long long)seed, (long long)stats.n_samples,
           (long long)stats.n_key_points, (long long)stats.n_skeleton_paths,
           (long long)stats.n_nodes, (long long)stats.n_edges, stats.total_length, outdir);
  goto cleanup;
nomem:
  err = karst_set_error(&ctx, KARST_ENOMEM, "out of memory");
  goto fail;
fail_write:
  cli_note_failed_output(&ctx, err, writing);
fail:
  status = cli_fail("generate", &ctx, err);
cleanup:
  karst_fileset_abort(&files);
  karst_dir_unlock(&lock);
  free(path);
  free(prefix);
  karst_samples_destroy(&samples);
  karst_network_destroy(&net);
  karst_geology_free(geo);
  karst_scenario_destroy(&sc);
  return status;
}

const cli_command_t cli_cmd_generate = {
    "generate", run, "generate a cave network from a scenario (Paris et al. 2021)",
    "usage: karst generate SCENARIO.yaml -o DIR [--seed S] [--samples] [--threads N]\n"
    "                      [--max-memory SIZE] [--quiet]\n\n"
    "Runs one realisation of the scenario (sampling, graph, least-cost paths, gamma-skeleton,\n"
    "amplification, classification; docs/generation.md) and writes these files as one set\n"
    "(all to temporary names first, then renamed into place, run.json last; a failed run\n"
    "leaves none of them, and a previous set in DIR as it was):\n"
    "  DIR/network.vtp                    the network for ParaView (point data: kind,\n"
    "                                     water_table_distance, spring; cell data: tunnel_type,\n"
    "                                     radius, zone, vadose, spring, cost, branch_id,\n"
    "                                     amplification_step)\n"
    "  DIR/geology.vtp                    the geology: terrain, horizons, water tables, strata,\n"
    "                                     faults, fracture discs, exclusion zones (cell data:\n"
    "                                     feature, feature_id)\n"
    "  DIR/network_nodes.dat, _links.dat  the network in Karstnet's format\n"
    "  DIR/samples.vtp                    the sample cloud tagged by source (with --samples)\n"
    "  DIR/network.paraview.py            a ParaView script showing them with karst's colours,\n"
    "                                     category names and units (karst view DIR)\n"
    "  DIR/run.json                       scenario path and hash, seed, every effective\n"
    "                                     parameter, counts and stage wall times\n\n"
    "  --seed S     base seed (default: the scenario's seed). The same seed gives byte-identical\n"
    "               files (timings are only in run.json); another seed another network.\n"
    "  --threads N  worker threads, 1 to 1024 (default: all cores); the result does not depend\n"
    "               on N.\n"
    "  --samples    also write samples.vtp.\n"
    "  --max-memory SIZE  refuse, before any work, a scenario whose estimated memory (samples,\n"
    "               graph edges, path searches; docs/scenario.md, \"Resource limits\") exceeds\n"
    "               SIZE (e.g. 512M, 8G; default: the machine's memory). DIR is locked\n"
    "               (DIR/.generate.lock) while generate writes it: a second generate into DIR\n"
    "               is refused.\n"
    "  --quiet      no progress bar and no summary line.\n"};
