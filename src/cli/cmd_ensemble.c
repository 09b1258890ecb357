/* karst ensemble: N realisations of a scenario, resumable, on threads and MPI ranks. */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

static int run(int argc, char **argv) {
  const char *scenario = NULL, *out = NULL;
  uint64_t seed = 0, n = 0;
  int have_seed = 0, have_n = 0, threads = 0, quiet = 0, status = CLI_OK;
  double max_memory = 0;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    int more = i + 1 < argc;
    if (strcmp(a, "-n") == 0 && more) {
      const char *v = argv[++i];
      if (cli_parse_u64(v, &n) || n < 1 || n > KARST_ENSEMBLE_MAX_MEMBERS)
        return cli_usage_error("ensemble",
                               "-n must be a whole number of realisations within [1, %d], got '%s'",
                               KARST_ENSEMBLE_MAX_MEMBERS, v);
      have_n = 1;
    } else if (strcmp(a, "-o") == 0 && more) {
      out = argv[++i];
    } else if (strcmp(a, "-j") == 0 && more) {
      const char *v = argv[++i];
      if (cli_parse_int(v, &threads) || threads < 1 || threads > KARST_ENSEMBLE_MAX_THREADS)
        return cli_usage_error("ensemble",
                               "-j must be a whole number of threads within [1, %d], got '%s'",
                               KARST_ENSEMBLE_MAX_THREADS, v);
    } else if (strcmp(a, "--seed") == 0 && more) {
      if (cli_parse_u64(argv[++i], &seed))
        return cli_usage_error("ensemble",
                               "--seed must be an integer from 0 to 18446744073709551615, got '%s'",
                               argv[i]);
      have_seed = 1;
    } else if (strcmp(a, "--max-memory") == 0) {
      if (!more || karst_budget_parse_size(argv[++i], &max_memory))
        return cli_usage_error("ensemble", "--max-memory needs a size such as 512M or 8G, got '%s'",
                               more ? argv[i] : "");
    } else if (strcmp(a, "--quiet") == 0 || strcmp(a, "-q") == 0) {
      quiet = 1;
    } else if (a[0] == '-' && a[1] != '\0') {
      return cli_usage_error("ensemble", "unknown option or missing value '%s'", a);
    } else if (!scenario) {
      scenario = a;
    } else {
      return cli_usage_error("ensemble", "more than one scenario given ('%s')", a);
    }
  }
  if (!scenario) return cli_usage_error("ensemble", "no scenario file given");
  if (!out) return cli_usage_error("ensemble", "no output directory given (-o DIR)");

  karst_ctx_t ctx;
  cli_ctx_init(&ctx, quiet, 0);
  int ranks = 1, rank = 0, mpi_init = 0;
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  char hash[17] = "";
  char *params = NULL;
  cli_count_progress_t ps;
  cli_count_progress_init(&ps, "ensemble", "realisations", 1);
  karst_error_t err = karst_ensemble_mpi_start(&ctx, &ranks, &rank, &mpi_init);
  if (err) {
    status = cli_fail("ensemble", &ctx, err);
    goto cleanup;
  }
  ctx.progress = (!quiet && rank == 0) ? cli_count_progress : NULL;
  ctx.progress_user = &ps;

  err = karst_scenario_load(&ctx, scenario, &sc);
  if (!err) err = karst_file_hash(&ctx, scenario, hash);
  /* one member's estimate, before any member runs (the check of karst generate) */
  if (!err) err = karst_budget_check(&ctx, &sc, 1, max_memory, NULL);
  if (err) {
    status = cli_fail("ensemble", &ctx, err);
    goto cleanup;
  }
  if (!have_n && sc.realisations > KARST_ENSEMBLE_MAX_MEMBERS) {
    fprintf(stderr, "karst ensemble: %s: random.realisations must be at most %d, got %" PRId64 "\n",
            scenario, KARST_ENSEMBLE_MAX_MEMBERS, (int64_t)sc.realisations);
    status = CLI_ERROR;
    goto cleanup;
  }
  params = karst_ensemble_parameters_json(&sc);
  karst_ensemble_options_t opt;
  karst_ensemble_options_init(&opt);
  opt.n = have_n ? (karst_int_t)n : sc.realisations;
  opt.seed = have_seed ? seed : sc.seed;
  opt.nthreads = threads > 0 ? threads : ctx.nthreads;
  if (opt.nthreads > KARST_ENSEMBLE_MAX_THREADS) opt.nthreads = KARST_ENSEMBLE_MAX_THREADS;
  opt.scenario_path = scenario;
  opt.scenario_hash = hash;
  opt.parameters_json = params;
  karst_ensemble_hooks_t hooks;
  karst_ensemble_pipeline_t pipe;
  err = karst_ensemble_hooks_pipeline(&ctx, &hooks, &pipe, &sc);
  karst_ensemble_summary_t sum;
  if (!err) err = karst_ensemble_run(&ctx, out, &opt, &hooks, &sum);
  status = cli_resumable_status("ensemble", &ctx, err, rank,
                                "the finished realisations are kept in %s; run the same command "
                                "again to compute only the missing ones",
                                out);
  if (!err && rank == 0 && !quiet) {
    fprintf(stderr,
            "karst ensemble: %" PRId64 " realisations in %s (%" PRId64 " computed, %" PRId64
            " already there) in %.1f s on %d thread(s) x %d process(es)\n",
            sum.n, out, sum.complete - sum.reused, sum.reused, sum.wall_seconds, opt.nthreads,
            sum.ranks);
  }
cleanup:
  free(params);
  karst_scenario_destroy(&sc);
  karst_ensemble_mpi_finish(mpi_init);
  return status;
}

const cli_command_t cli_cmd_ensemble = {
    "ensemble", run, "generate an ensemble of realisations (resumable, threads, MPI)",
    "usage: karst ensemble SCENARIO.yaml -n N -o DIR [-j THREADS] [--seed S]\n"
    "                      [--max-memory SIZE] [--quiet]\n\n"
    "Generates N realisations of the scenario. Realisation i uses only the seed derived from\n"
    "(S, i) (column 'seed' of metrics.csv; `karst generate --seed` with it reproduces the\n"
    "member), so every file is the same whatever -j or the number of MPI processes.\n\n"
    "  -n N          realisations, 1 to 100000000 (default: random.realisations of the scenario)\n"
    "  -o DIR        output directory\n"
    "  -j THREADS    worker threads, 1 to 1024 (default: the number of processors)\n"
    "  --seed S      base seed (default: random.seed of the scenario)\n"
    "  --max-memory SIZE  refuse, before any work, a scenario one member of which needs more\n"
    "                memory than SIZE by the estimate of karst validate (e.g. 512M, 8G;\n"
    "                default: the machine's memory)\n"
    "  --quiet       no progress display\n\n"
    "Writes DIR/realisations/NNNN/{network.vtp,network_nodes.dat,network_links.dat,metrics.csv},\n"
    "DIR/ensemble.pvd (open in ParaView and step through the members), DIR/metrics.csv (one row\n"
    "per realisation: index, seed, every metric of `karst metrics`) and DIR/ensemble.json\n"
    "(scenario hash, parameters, N: byte-identical for a resumed run), DIR/ensemble_log.json\n"
    "(wall time, members computed and reused, threads, ranks of the last run).\n\n"
    "Interrupting (Ctrl-C, kill) loses nothing: finished realisations are kept, unfinished ones\n"
    "leave no file; running the same command again computes only the missing ones.\n"
    "One run at a time per DIR: a second one is refused while DIR/.ensemble.lock is held.\n\n"
    "Under Open MPI: mpirun -np P karst ensemble ... splits the realisations across the P\n"
    "processes (as root add --allow-run-as-root, beyond the core count --oversubscribe).\n"
    "See docs/ensembles.md.\n"};
