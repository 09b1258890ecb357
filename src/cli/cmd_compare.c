/* karst compare: where field surveys fall within an ensemble. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

static int run(int argc, char **argv) {
  const char *dir = NULL, *published = NULL, *outpath = NULL;
  const char **surveys = calloc((size_t)argc, sizeof *surveys);
  int n_surveys = 0, format = KARST_COMPARE_TABLE, in_surveys = 0, status = CLI_OK;
  if (!surveys) return CLI_ERROR;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    int more = i + 1 < argc;
    if (strcmp(a, "--survey") == 0) {
      in_surveys = 1;
      if (!more) {
        free(surveys);
        return cli_usage_error("compare", "--survey needs at least one file");
      }
    } else if (strcmp(a, "--format") == 0 && more) {
      in_surveys = 0;
      format = karst_compare_format_from_name(argv[++i]);
      if (format < 0) {
        free(surveys);
        return cli_usage_error("compare", "--format must be table, csv or json, got '%s'", argv[i]);
      }
    } else if (strcmp(a, "--published") == 0 && more) {
      in_surveys = 0;
      published = argv[++i];
    } else if (strcmp(a, "-o") == 0 && more) {
      in_surveys = 0;
      outpath = argv[++i];
    } else if (a[0] == '-' && a[1] != '\0') {
      free(surveys);
      return cli_usage_error("compare", "unknown option or missing value '%s'", a);
    } else if (in_surveys) {
      surveys[n_surveys++] = a;
    } else if (!dir) {
      dir = a;
    } else {
      free(surveys);
      return cli_usage_error("compare", "more than one ensemble directory given ('%s')", a);
    }
  }
  if (!dir) {
    free(surveys);
    return cli_usage_error("compare", "no ensemble directory given");
  }

  karst_ctx_t ctx;
  cli_ctx_init(&ctx, 0, 0);
  karst_ensemble_table_t table;
  karst_published_t pub;
  karst_compare_result_t *res = calloc((size_t)(n_surveys > 0 ? n_surveys : 1), sizeof *res);
  int n_res = 0;
  char pubpath[1024], *mpath = NULL;
  karst_ensemble_table_init(&table);
  karst_published_init(&pub);
  karst_error_t err = KARST_SUCCESS;
  if (!res) {
    status = CLI_ERROR;
    goto cleanup;
  }
  size_t len = strlen(dir) + 16;
  mpath = malloc(len);
  if (!mpath) {
    status = CLI_ERROR;
    goto cleanup;
  }
  snprintf(mpath, len, "%s/metrics.csv", dir);
  if (outpath) { /* -o must not replace an input (the ensemble's table, a survey, --published) */
    const char *ins[2] = {mpath, published};
    if ((status = cli_refuse_output_over_input("compare", outpath, ins, 2)) ||
        (status = cli_refuse_output_over_input("compare", outpath, (const char *const *)surveys,
                                               n_surveys)))
      goto cleanup;
  }
  err = karst_ensemble_table_read(&ctx, mpath, &table);
  if (!err && published) snprintf(pubpath, sizeof pubpath, "%s", published);
  if (!err && !published) err = karst_published_locate(&ctx, pubpath, sizeof pubpath);
  if (!err) err = karst_published_read(&ctx, pubpath, &pub);
  if (err) {
    status = cli_fail("compare", &ctx, err);
    goto cleanup;
  }
  for (int s = 0; s < (n_surveys > 0 ? n_surveys : 1); s++) {
    const char *names[64];
    double values[64];
    int nv = 0;
    if (n_surveys > 0) {
      err = karst_compare_survey_metrics(&ctx, surveys[s], 64, names, values, &nv);
      if (err) {
        status = cli_fail("compare", &ctx, err);
        goto cleanup;
      }
    }
    err = karst_compare_compute(&ctx, &table, n_surveys > 0 ? surveys[s] : NULL, names, values, nv,
                                &pub, &res[n_res]);
    if (err) {
      status = cli_fail("compare", &ctx, err);
      goto cleanup;
    }
    n_res++;
  }
  if (outpath) {
    karst_atomic_file_t f;
    err = karst_atomic_open(&ctx, &f, outpath, "wb");
    if (!err) {
      err = karst_compare_write(&ctx, f.fp, (karst_compare_format_t)format, res, n_res);
      if (err)
        karst_atomic_abort(&f);
      else
        err = karst_atomic_commit(&ctx, &f);
    }
  } else {
    err = karst_compare_write(&ctx, stdout, (karst_compare_format_t)format, res, n_res);
  }
  if (err) status = cli_fail("compare", &ctx, err);
cleanup:
  if (res)
    for (int s = 0; s < n_res; s++)
      karst_compare_result_destroy(&res[s]);
  free(res);
  free(mpath);
  free(surveys);
  karst_published_destroy(&pub);
  karst_ensemble_table_destroy(&table);
  return status;
}

const cli_command_t cli_cmd_compare = {
    "compare", run, "compare field surveys with an ensemble",
    "usage: karst compare ENSEMBLE_DIR [--survey FILE...] [--format table|csv|json]\n"
    "                     [--published FILE] [-o OUT]\n\n"
    "For each metric of the ensemble's metrics.csv: the survey's value, its percentile within\n"
    "the ensemble (100 x members <= value / n), the ensemble mean, standard deviation (divisor\n"
    "n - 1), 5th and 95th percentiles (linear interpolation, Hyndman & Fan type 7), the min-max\n"
    "of the 34 caves of Collon et al. 2017 (datasets/published_metrics.csv, or --published), and\n"
    "a flag when the survey lies outside the ensemble's 5-95 % band. Surveys are read like\n"
    "`karst metrics` reads them (.vtp, Karstnet .dat pair, .pl, .sql, .3d, .svx). Without\n"
    "--survey only the ensemble statistics are printed. See docs/ensembles.md.\n"};
