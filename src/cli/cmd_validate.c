/* karst validate: read and check scenario files without running them. */
#include <stdio.h>
#include <string.h>

#include "cli.h"

static const char *plural(int n, const char *one, const char *many) {
  return n == 1 ? one : many;
}

static int run(int argc, char **argv) {
  int status = CLI_OK, nfiles = 0;
  double max_memory = 0;
  for (int i = 1; i < argc; i++) {
    if (strcmp(argv[i], "--max-memory") == 0) {
      if (i + 1 >= argc || karst_budget_parse_size(argv[i + 1], &max_memory))
        return cli_usage_error("validate", "--max-memory needs a size such as 512M or 8G, got '%s'",
                               i + 1 < argc ? argv[i + 1] : "");
      argv[i] = argv[i + 1] = NULL;
      i++;
    } else if (argv[i][0] == '-' && argv[i][1] != '\0') {
      return cli_usage_error("validate", "unknown option '%s'", argv[i]);
    } else {
      nfiles++;
    }
  }
  if (nfiles == 0) return cli_usage_error("validate", "no scenario file given");
  for (int i = 1; i < argc; i++) {
    if (!argv[i]) continue;
    karst_ctx_t ctx;
    cli_ctx_init(&ctx, 0, 0);
    karst_scenario_t sc;
    karst_scenario_init(&sc);
    karst_error_t err = karst_scenario_load(&ctx, argv[i], &sc);
    /* what the run would need, before the geology builds anything */
    karst_budget_t budget;
    if (!err) err = karst_budget_check(&ctx, &sc, ctx.nthreads, max_memory, &budget);
    if (!err) { /* what only the geology can say: key points in exclusion zones, surfaces ... */
      karst_geology_t *geo = NULL;
      err = karst_geology_create(&ctx, &sc, sc.seed, 0, &geo);
      karst_geology_free(geo);
    }
    if (err) {
      fprintf(stderr, "%s\n", ctx.errmsg[0] ? ctx.errmsg : karst_strerror(err));
      status = CLI_ERROR;
    } else {
      int sinks = 0, springs = 0, waypoints = 0;
      char mem[48];
      for (int k = 0; k < sc.n_key_points; k++) {
        sinks += sc.key_points[k].type == KARST_KEYPOINT_SINK;
        springs += sc.key_points[k].type == KARST_KEYPOINT_SPRING;
        waypoints += sc.key_points[k].type == KARST_KEYPOINT_WAYPOINT;
      }
      char sampling[160] = "", names[64]; /* what the summary says of sampling.points and .refine */
      if (sc.sampling.points)
        snprintf(sampling, sizeof sampling, "a cloud of %lld points (sampling.points), ",
                 (long long)sc.sampling.n_points);
      if (sc.sampling.refine != KARST_REFINE_ALL)
        snprintf(sampling + strlen(sampling), sizeof sampling - strlen(sampling),
                 "sampling.refine [%s], ",
                 karst_refine_names(sc.sampling.refine, ", ", names, sizeof names));
      printf("%s: ok: '%s', domain %.6g x %.6g x %.6g m, %d %s, %d %s, %d %s, %d %s, %d %s, "
             "%sgamma %.6g, theta %.6g, seed %llu; needs about %.4g samples, %.4g graph edges, "
             "%.4g path searches, %s of memory\n",
             argv[i], sc.name ? sc.name : "", sc.domain_max[0] - sc.domain_min[0],
             sc.domain_max[1] - sc.domain_min[1], sc.domain_max[2] - sc.domain_min[2], sinks,
             plural(sinks, "sink", "sinks"), springs, plural(springs, "spring", "springs"),
             waypoints, plural(waypoints, "waypoint", "waypoints"), sc.n_horizons,
             plural(sc.n_horizons, "horizon", "horizons"), sc.n_fractures,
             plural(sc.n_fractures, "fracture family", "fracture families"), sampling, sc.gamma,
             sc.tortuosity, (unsigned long long)sc.seed, budget.samples, budget.edges,
             budget.searches, karst_budget_format_size(budget.bytes, mem, sizeof mem));
    }
    karst_scenario_destroy(&sc);
  }
  return status;
}

const cli_command_t cli_cmd_validate = {
    "validate", run, "check a scenario file without running it",
    "usage: karst validate [--max-memory SIZE] SCENARIO.yaml...\n\n"
    "Reads each scenario, checks every field and every cross-field rule (key points inside\n"
    "the domain, below the terrain and outside every exclusion zone, a spring present,\n"
    "surfaces covering the domain, ...) and prints a one-line summary.\n"
    "It also estimates what a run would need (samples, graph edges, path searches, memory;\n"
    "docs/scenario.md, \"Resource limits\") and refuses a scenario beyond the limit, or with\n"
    "a sample count or amplification no run could finish, at the key that drives it.\n"
    "  --max-memory SIZE  the memory limit, e.g. 512M or 8G (default: the machine's memory)\n"
    "Errors are printed as FILE:LINE:COLUMN: message. Exit code 1 when any file fails.\n"
    "The scenario format is documented in docs/scenario.md.\n"};
