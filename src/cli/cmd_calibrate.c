/* karst calibrate: fit scenario parameters to a survey by ABC-SMC (src/calibrate/). */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"

/* What the per-generation lines need (the bar is cli_count_progress). */
typedef struct {
  int tty, quiet;
} cal_progress_t;

/* After each generation: one line (on a terminal it replaces the bar). */
static void show_generation(void *user, const karst_calibrate_generation_t *g) {
  cal_progress_t *ps = user;
  if (ps->quiet) return;
  if (ps->tty) fputs("\r\033[K", stderr);
  char acc[64] = "prior sample";
  if (g->generation > 0)
    snprintf(acc, sizeof acc, "acceptance %.3f (%" PRId64 " of %" PRId64 ")", g->acceptance,
             g->accepted, g->simulations);
  fprintf(stderr,
          "karst calibrate: generation %d of at most %d: %" PRId64 " simulations (%" PRId64
          " computed), %s, tolerance %.4g, ESS %.1f\n",
          g->generation, g->generations_max, g->simulations, g->computed, acc, g->tolerance,
          g->ess);
  fflush(stderr);
}

/* Split "a,b,c" into @p names (pointers into @p s, which is modified); returns the count or -1. */
static int split_list(char *s, const char **names, int max) {
  int n = 0;
  for (char *tok = strtok(s, ","); tok; tok = strtok(NULL, ",")) {
    if (n == max) return -1;
    names[n++] = tok;
  }
  return n;
}

static int run(int argc, char **argv) {
  const char *scenario = NULL, *out = NULL, *survey = NULL, *published = NULL;
  char *metrics_arg = NULL;
  const char *metric_names[KARST_CALIBRATE_MAX_METRICS];
  int n_metrics = 0;
  karst_calibrate_param_t params[KARST_CALIBRATE_MAX_PARAMS];
  int n_params = 0, threads = 0, quiet = 0, status = CLI_OK, have_seed = 0;
  double max_memory = 0;
  uint64_t seed = 0;
  karst_calibrate_options_t opt;
  karst_calibrate_options_init(&opt);
  karst_ctx_t pctx;
  karst_ctx_init(&pctx);
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    int more = i + 1 < argc;
    if (strcmp(a, "--vary") == 0 && more) {
      if (n_params == KARST_CALIBRATE_MAX_PARAMS)
        return cli_usage_error("calibrate", "at most %d --vary parameters",
                               KARST_CALIBRATE_MAX_PARAMS);
      if (karst_calibrate_param_parse(&pctx, argv[++i], &params[n_params]))
        return cli_usage_error("calibrate", "--vary %s", pctx.errmsg);
      n_params++;
    } else if (strcmp(a, "--survey") == 0 && more) {
      survey = argv[++i];
    } else if (strcmp(a, "-o") == 0 && more) {
      out = argv[++i];
    } else if (strcmp(a, "--metrics") == 0 && more) {
      free(metrics_arg);
      metrics_arg = strdup(argv[++i]);
      if (!metrics_arg) return CLI_ERROR;
      n_metrics = split_list(metrics_arg, metric_names, KARST_CALIBRATE_MAX_METRICS);
      if (n_metrics < 1 || karst_calibrate_check_metrics(&pctx, n_metrics, metric_names)) {
        status =
            cli_usage_error("calibrate", "--metrics '%s': %s", argv[i],
                            n_metrics < 1 ? "give metric names separated by commas" : pctx.errmsg);
        free(metrics_arg);
        return status;
      }
    } else if (strcmp(a, "--particles") == 0 && more) {
      uint64_t v;
      if (cli_parse_u64(argv[++i], &v) || v < 4 || v > KARST_CALIBRATE_MAX_PARTICLES)
        return cli_usage_error("calibrate",
                               "--particles must be a whole number within [4, %d], got '%s'",
                               KARST_CALIBRATE_MAX_PARTICLES, argv[i]);
      opt.particles = (karst_int_t)v;
    } else if (strcmp(a, "--alpha") == 0 && more) {
      if (cli_parse_double(argv[++i], &opt.alpha) || !(opt.alpha > 0 && opt.alpha < 1))
        return cli_usage_error("calibrate", "--alpha must be a number within (0, 1), got '%s'",
                               argv[i]);
    } else if (strcmp(a, "--generations") == 0 && more) {
      if (cli_parse_int(argv[++i], &opt.generations) || opt.generations < 0 ||
          opt.generations > KARST_CALIBRATE_MAX_GENERATIONS)
        return cli_usage_error("calibrate",
                               "--generations must be a whole number within [0, %d], got '%s'",
                               KARST_CALIBRATE_MAX_GENERATIONS, argv[i]);
    } else if (strcmp(a, "--min-acceptance") == 0 && more) {
      if (cli_parse_double(argv[++i], &opt.min_acceptance) ||
          !(opt.min_acceptance >= 0 && opt.min_acceptance <= 1))
        return cli_usage_error(
            "calibrate", "--min-acceptance must be a number within [0, 1], got '%s'", argv[i]);
    } else if (strcmp(a, "--best-members") == 0 && more) {
      if (cli_parse_int(argv[++i], &opt.best_members) || opt.best_members < 0 ||
          opt.best_members > KARST_ENSEMBLE_MAX_MEMBERS)
        return cli_usage_error("calibrate",
                               "--best-members must be a whole number within [0, %d], got '%s'",
                               KARST_ENSEMBLE_MAX_MEMBERS, argv[i]);
    } else if (strcmp(a, "--published") == 0 && more) {
      published = argv[++i];
    } else if (strcmp(a, "-j") == 0 && more) {
      if (cli_parse_int(argv[++i], &threads) || threads < 1 || threads > KARST_ENSEMBLE_MAX_THREADS)
        return cli_usage_error("calibrate",
                               "-j must be a whole number of threads within [1, %d], got '%s'",
                               KARST_ENSEMBLE_MAX_THREADS, argv[i]);
    } else if (strcmp(a, "--max-memory") == 0) {
      if (!more || karst_budget_parse_size(argv[++i], &max_memory))
        return cli_usage_error("calibrate",
                               "--max-memory needs a size such as 512M or 8G, got '%s'",
                               more ? argv[i] : "");
    } else if (strcmp(a, "--seed") == 0 && more) {
      if (cli_parse_u64(argv[++i], &seed))
        return cli_usage_error("calibrate",
                               "--seed must be an integer from 0 to 18446744073709551615, got '%s'",
                               argv[i]);
      have_seed = 1;
    } else if (strcmp(a, "--quiet") == 0 || strcmp(a, "-q") == 0) {
      quiet = 1;
    } else if (a[0] == '-' && a[1] != '\0') {
      free(metrics_arg);
      return cli_usage_error("calibrate", "unknown option or missing value '%s'", a);
    } else if (!scenario) {
      scenario = a;
    } else {
      free(metrics_arg);
      return cli_usage_error("calibrate", "more than one scenario given ('%s')", a);
    }
  }
  const char *missing = !scenario   ? "no scenario file given"
                        : !survey   ? "no survey given (--survey FILE)"
                        : !n_params ? "no parameter to vary given (--vary KEY=LO:HI)"
                        : !out      ? "no output directory given (-o DIR)"
                                    : NULL;
  if (missing) {
    free(metrics_arg);
    return cli_usage_error("calibrate", "%s", missing);
  }

  karst_ctx_t ctx;
  cli_ctx_init(&ctx, quiet, 0);
  int ranks = 1, rank = 0, mpi_init = 0;
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  cal_progress_t ps = {isatty(STDERR_FILENO), quiet};
  karst_error_t err = karst_ensemble_mpi_start(&ctx, &ranks, &rank, &mpi_init);
  if (err) {
    status = cli_fail("calibrate", &ctx, err);
    goto cleanup;
  }
  /* On a terminal, rank 0 only: the members of each generation, counted (not the stages of
   * one member, which run on worker threads without progress). */
  cli_count_progress_t bar;
  cli_count_progress_init(&bar, "calibrate", "simulations", 0);
  ctx.progress = (!quiet && rank == 0 && bar.tty) ? cli_count_progress : NULL;
  ctx.progress_user = &bar;
  /* A broken scenario is an error of the file (exit 1); a --vary key it does not have, or
   * that holds no number, is a usage error (exit 2). */
  err = karst_scenario_load(&ctx, scenario, &sc);
  /* the scenario as the file gives it, before any simulation (the check of karst generate) */
  if (!err) err = karst_budget_check(&ctx, &sc, 1, max_memory, NULL);
  if (err) {
    status = cli_fail("calibrate", &ctx, err);
    goto cleanup;
  }
  err = karst_calibrate_check_params(&ctx, scenario, n_params, params);
  if (err) {
    status = cli_usage_error("calibrate", "%s", ctx.errmsg);
    goto cleanup;
  }
  opt.scenario_path = scenario;
  opt.survey_path = survey;
  opt.n_params = n_params;
  opt.params = params;
  opt.n_metrics = n_metrics;
  opt.metrics = metric_names;
  opt.seed = have_seed ? seed : sc.seed;
  opt.nthreads = threads > 0 ? threads : ctx.nthreads;
  if (opt.nthreads > KARST_ENSEMBLE_MAX_THREADS) opt.nthreads = KARST_ENSEMBLE_MAX_THREADS;
  opt.published_path = published;
  opt.on_generation = show_generation;
  opt.on_generation_user = &ps;
  karst_calibrate_summary_t sum;
  err = karst_calibrate_run(&ctx, out, &opt, &sum);
  if (ps.tty && !quiet && rank == 0 && err) fputs("\r\033[K", stderr);
  status = cli_resumable_status("calibrate", &ctx, err, rank,
                                "every finished simulation is kept in %s; run the same command "
                                "again to continue",
                                out);
  if (!err && rank == 0 && !quiet) {
    fprintf(stderr,
            "karst calibrate: %d generation(s) after the prior sample (%s), %" PRId64
            " simulations (%" PRId64 " computed) in %.1f s on %d thread(s) x %d process(es); "
            "final tolerance %.4g\n",
            sum.generations,
            sum.stop == KARST_CALIBRATE_STOP_ACCEPTANCE ? "acceptance reached the minimum"
                                                        : "the most generations",
            sum.simulations, sum.computed, sum.wall_seconds, opt.nthreads, sum.ranks,
            sum.tolerance);
    for (int k = 0; k < n_params; k++)
      fprintf(stderr, "  %s: median %.6g, 90%% credible interval [%.6g, %.6g]\n", params[k].key,
              sum.median[k], sum.low[k], sum.high[k]);
    fprintf(stderr,
            "Outputs in %s: posterior.csv, best.yaml (karst generate %s/best.yaml), "
            "report.html\n",
            out, out);
  }
cleanup:
  free(metrics_arg);
  karst_scenario_destroy(&sc);
  karst_ensemble_mpi_finish(mpi_init);
  return status;
}

const cli_command_t cli_cmd_calibrate = {
    "calibrate", run, "fit scenario parameters to a survey (ABC-SMC, resumable, threads, MPI)",
    "usage: karst calibrate SCENARIO.yaml --survey FILE --vary KEY=LO:HI[:log] [--vary ...]\n"
    "                       -o DIR [--metrics LIST] [--particles N] [--alpha A]\n"
    "                       [--generations G] [--min-acceptance P] [--best-members M]\n"
    "                       [--published CSV] [-j THREADS] [--seed S]\n"
    "                       [--max-memory SIZE] [--quiet]\n\n"
    "Fits the varied scenario keys so that the generated networks' metrics match the survey's,\n"
    "by approximate Bayesian computation with sequential Monte Carlo: the adaptive population\n"
    "Monte Carlo ABC of Lenormand, Jabot & Deffuant (2013) with the weights and Gaussian\n"
    "kernel of Beaumont et al. (2009). See docs/calibration.md.\n\n"
    "  --survey FILE      the cave to fit: any file karst metrics reads (.3d, .svx, .th\n"
    "                     SQL export, Karstnet _nodes.dat/_links.dat, .pl, .vtp)\n"
    "  --vary KEY=LO:HI   a numeric scenario key by its path (skeleton.gamma, tortuosity,\n"
    "                     amplification.steps, cost.fracture, fractures[0].weight, domain.max[2]\n"
    "                     ...) with a uniform prior on [LO, HI]; KEY=LO:HI:log for a log-uniform\n"
    "                     prior (LO > 0). Integer keys take whole bounds and integer values.\n"
    "  --metrics LIST     metrics of the distance, separated by commas (default: the ten of\n"
    "                     Collon et al. 2017, mean_length ... correlation_vertex_degree); each\n"
    "                     is standardised by its spread over the prior sample\n"
    "  --particles N      particles simulated per generation, 4 to 1000000 (default 200)\n"
    "  --alpha A          fraction kept as the population, in (0, 1) (default 0.5); later\n"
    "                     generations simulate N - floor(A N) particles\n"
    "  --generations G    most generations after the prior sample, 0 to 999 (default 10)\n"
    "  --min-acceptance P stop once a generation's acceptance rate is <= P (default 0.05)\n"
    "  --best-members M   members of the ensemble of best.yaml shown in the report (default 20;\n"
    "                     0: none)\n"
    "  --published CSV    the table of the 34 caves (default: datasets/published_metrics.csv)\n"
    "  -j THREADS         worker threads, 1 to 1024 (default: the number of processors)\n"
    "  --max-memory SIZE  refuse, before any simulation, a scenario (as the file gives it) that\n"
    "                     needs more memory than SIZE by the estimate of karst validate (e.g.\n"
    "                     512M, 8G; default: the machine's memory)\n"
    "  --seed S           base seed (default: random.seed of the scenario)\n"
    "  --quiet            no progress display\n\n"
    "Writes DIR/posterior.csv (the population of every generation: values, weights,\n"
    "distances), DIR/generations.csv (acceptance, tolerance, effective sample size),\n"
    "DIR/best.yaml (the scenario at the posterior median: karst generate DIR/best.yaml),\n"
    "DIR/best/ (its ensemble), DIR/report.html and DIR/calibration.json; the simulations of\n"
    "generation T are the ensemble DIR/generations/TTT.\n\n"
    "The same seed gives the same bytes whatever -j or the number of MPI processes.\n"
    "Interrupting (Ctrl-C, kill) loses no finished simulation; the same command continues,\n"
    "and with a larger --generations it extends a finished calibration.\n"
    "Under Open MPI: mpirun -np P karst calibrate ... splits each generation across the P\n"
    "processes (as root add --allow-run-as-root, beyond the core count --oversubscribe).\n"};
