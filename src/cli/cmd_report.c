/* karst report: one self-contained HTML page about an ensemble. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

static int run(int argc, char **argv) {
  const char *dir = NULL, *out = NULL, *published = NULL;
  const char **files = calloc((size_t)argc, sizeof *files);
  int n_files = 0, in_surveys = 0, members = 4, status = CLI_OK;
  if (!files) return CLI_ERROR;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    int more = i + 1 < argc;
    if (strcmp(a, "--survey") == 0) {
      in_surveys = 1;
    } else if (strcmp(a, "-o") == 0 && more) {
      in_surveys = 0;
      out = argv[++i];
    } else if (strcmp(a, "--published") == 0 && more) {
      in_surveys = 0;
      published = argv[++i];
    } else if (strcmp(a, "--members") == 0 && more) {
      in_surveys = 0;
      if (cli_parse_int(argv[++i], &members) || members < 0) {
        free(files);
        return cli_usage_error("report", "--members needs a count >= 0, got '%s'", argv[i]);
      }
    } else if (a[0] == '-' && a[1] != '\0') {
      free(files);
      return cli_usage_error("report", "unknown option or missing value '%s'", a);
    } else if (in_surveys) {
      files[n_files++] = a;
    } else if (!dir) {
      dir = a;
    } else {
      free(files);
      return cli_usage_error("report", "more than one ensemble directory given ('%s')", a);
    }
  }
  if (!dir || !out) {
    free(files);
    return cli_usage_error("report", !dir ? "no ensemble directory given"
                                          : "no output file given (-o report.html)");
  }
  karst_ctx_t ctx;
  cli_ctx_init(&ctx, 0, 0);
  karst_report_survey_t *sv = calloc((size_t)(n_files > 0 ? n_files : 1), sizeof *sv);
  int n_sv = 0;
  karst_error_t err = KARST_SUCCESS;
  if (!sv) {
    status = CLI_ERROR;
    goto cleanup;
  }
  for (int s = 0; s < n_files; s++) {
    err = karst_report_survey_load(&ctx, files[s], &sv[s]);
    if (err) {
      status = cli_fail("report", &ctx, err);
      goto cleanup;
    }
    n_sv++;
  }
  karst_report_options_t opt;
  karst_report_options_init(&opt);
  opt.surveys = sv;
  opt.n_surveys = n_sv;
  opt.published_path = published;
  opt.members_drawn = members;
  err = karst_report_write(&ctx, dir, out, &opt);
  if (err) status = cli_fail("report", &ctx, err);
cleanup:
  if (sv)
    for (int s = 0; s < n_sv; s++)
      karst_report_survey_destroy(&sv[s]);
  free(sv);
  free(files);
  return status;
}

const cli_command_t cli_cmd_report = {
    "report", run, "write a self-contained HTML report of an ensemble",
    "usage: karst report ENSEMBLE_DIR [--survey FILE...] -o report.html [--members K]\n"
    "                    [--published FILE]\n\n"
    "One HTML file (inline SVG and CSS, no scripts, no external requests): scenario summary and\n"
    "seed, the comparison table, a histogram per metric with the survey value and the range of\n"
    "the 34 published caves (metrics constant over the members as values), an equal-area\n"
    "orientation rose, a stereonet of conduit orientations with the fracture families, the\n"
    "degree distribution, a plan, two sections and an oblique view of the first K members\n"
    "(default 4) coloured by tunnel type, with the survey, and the software versions. Files are\n"
    "named relative to the page. See docs/ensembles.md.\n"};
