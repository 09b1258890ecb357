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
      if (++i >= argc || cli_parse_int(argv[i], &threads) || threads < 1)
        return cli_usage_error("generate", "--threads needs an integer >= 1, got '%s'",
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
  char *path = NULL;
  int status = CLI_OK;
  karst_error_t err;
  if ((err = karst_scenario_load(&ctx, scenario, &sc))) goto fail;
  if (!have_seed) seed = sc.seed;
  if ((err = karst_generate(&ctx, &sc, seed, 0, &net, want_samples ? &samples : NULL, &stats)))
    goto fail;
  if ((err = karst_mkdir_p(&ctx, outdir))) goto fail;
  if (!(path = join(outdir, "network.vtp"))) goto nomem;
  if ((err = karst_vtk_write_network(&ctx, path, &net))) goto fail;
  free(path);
  if (!(path = join(outdir, "network"))) goto nomem;
  if ((err = karst_write_karstnet(&ctx, path, &net))) goto fail;
  free(path);
  path = NULL;
  if (want_samples) {
    if (!(path = join(outdir, "samples.vtp"))) goto nomem;
    if ((err = karst_vtk_write_samples(&ctx, path, &samples))) goto fail;
    free(path);
    path = NULL;
  }
  if (!(path = join(outdir, "run.json"))) goto nomem;
  if ((err = karst_generate_write_run(&ctx, path, &sc, seed, 0, &stats))) goto fail;
  if (!quiet)
    printf("%s: seed %llu: %lld samples, %lld key points, %lld skeleton paths, network of %lld "
           "nodes, %lld edges, %.1f m -> %s/\n",
           scenario, (unsigned long long)seed, (long long)stats.n_samples,
           (long long)stats.n_key_points, (long long)stats.n_skeleton_paths,
           (long long)stats.n_nodes, (long long)stats.n_edges, stats.total_length, outdir);
  goto cleanup;
nomem:
  err = karst_set_error(&ctx, KARST_ENOMEM, "out of memory");
fail:
  status = cli_fail("generate", &ctx, err);
cleanup:
  free(path);
  karst_samples_destroy(&samples);
  karst_network_destroy(&net);
  karst_scenario_destroy(&sc);
  return status;
}

const cli_command_t cli_cmd_generate = {
    "generate", run, "generate a cave network from a scenario (Paris et al. 2021)",
    "usage: karst generate SCENARIO.yaml -o DIR [--seed S] [--samples] [--threads N] [--quiet]\n\n"
    "Runs one realisation of the scenario (sampling, graph, least-cost paths, gamma-skeleton,\n"
    "amplification, classification; docs/generation.md) and writes, each file atomically:\n"
    "  DIR/network.vtp                    the network for ParaView (point data: kind,\n"
    "                                     water_table_distance; cell data: tunnel_type, radius,\n"
    "                                     cost, vadose, branch_id, amplification_step)\n"
    "  DIR/network_nodes.dat, _links.dat  the network in Karstnet's format\n"
    "  DIR/samples.vtp                    the sample cloud tagged by source (with --samples)\n"
    "  DIR/run.json                       scenario path and hash, seed, every effective\n"
    "                                     parameter, counts and stage wall times\n\n"
    "  --seed S     base seed (default: the scenario's seed). The same seed gives byte-identical\n"
    "               files (timings are only in run.json); another seed another network.\n"
    "  --threads N  worker threads (default: all cores); the result does not depend on N.\n"
    "  --samples    also write samples.vtp.\n"
    "  --quiet      no progress bar and no summary line.\n"};
