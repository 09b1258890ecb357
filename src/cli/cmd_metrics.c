/* karst metrics: read networks or surveys, compute the metrics of Collon et al. 2017
 * (library: karst_metrics_compute) and print them as a table, CSV or JSON. */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"

extern const cli_command_t cli_cmd_metrics;

typedef enum { OUT_TABLE, OUT_CSV, OUT_JSON } out_format_t;

typedef struct {
  const char *file;
  karst_metrics_t m;
  int true_north;     /* rotation applied */
  double convergence; /* degrees, NAN when not applied */
  char *crs;          /* the file's coordinate system (e.g. the .3d CS string), or NULL */
} row_t;



static void csv_string(FILE *fp, const char *s) {
  if (!strpbrk(s, ",\"\n\r")) {
    fputs(s, fp);
    return;
  }
  fputc('"', fp);
  for (; *s; s++) {
    if (*s == '"') fputc('"', fp);
    fputc(*s, fp);
  }
  fputc('"', fp);
}

/* A value in machine formats: full precision so that nothing is lost; NAN -> @p undef. */
static void put_value(FILE *fp, const karst_metric_field_t *f, double v, const char *undef) {
  if (isnan(v) || isinf(v))
    fputs(undef, fp);
  else if (f->is_int)
    fprintf(fp, "%lld", (long long)v);
  else
    fprintf(fp, "%.17g", v);
}

static int outside(const karst_metrics_observed_t *obs, int k, double v) {
  return karst_metrics_observed_outside(obs, k, v);
}

static void write_json(FILE *fp, const row_t *rows, int nrows, const karst_metrics_observed_t *obs,
                       int true_north) {
  int nf;
  const karst_metric_field_t *f = karst_metric_fields(&nf);
  fputs("[\n", fp);
  for (int r = 0; r < nrows; r++) {
    fputs("{\"file\": ", fp);
    karst_json_string(fp, rows[r].file);
    fputs(", \"crs\": ", fp);
    karst_json_string(fp, rows[r].crs);
    for (int k = 0; k < nf; k++) {
      fprintf(fp, ", \"%s\": ", f[k].key);
      put_value(fp, &f[k], karst_metric_value(&rows[r].m, &f[k]), "null");
    }
    if (true_north) {
      fprintf(fp, ", \"true_north\": %s, \"meridian_convergence\": ",
              rows[r].true_north ? "true" : "false");
      if (rows[r].true_north)
        fprintf(fp, "%.17g", rows[r].convergence);
      else
        fputs("null", fp);
    }
    if (obs) {
      fputs(", \"observed\": {", fp);
      int first = 1;
      for (int k = 0; k < nf; k++) {
        if (isnan(obs->min[k])) continue;
        fprintf(fp, "%s\"%s\": {\"min\": %.17g, \"max\": %.17g, \"outside\": %s}",
                first ? "" : ", ", f[k].key, obs->min[k], obs->max[k],
                outside(obs, k, karst_metric_value(&rows[r].m, &f[k])) ? "true" : "false");
        first = 0;
      }
      fputs("}", fp);
    }
    fprintf(fp, "}%s\n", r + 1 < nrows ? "," : "");
  }
  fputs("]\n", fp);
}

static void write_csv(FILE *fp, const row_t *rows, int nrows, const karst_metrics_observed_t *obs,
                      int true_north) {
  int nf;
  const karst_metric_field_t *f = karst_metric_fields(&nf);
  fputs("file,crs", fp);
  for (int k = 0; k < nf; k++)
    fprintf(fp, ",%s", f[k].key);
  if (true_north) fputs(",true_north,meridian_convergence", fp);
  if (obs)
    for (int k = 0; k < nf; k++)
      if (!isnan(obs->min[k]))
        fprintf(fp, ",%s_observed_min,%s_observed_max,%s_outside", f[k].key, f[k].key, f[k].key);
  fputc('\n', fp);
  for (int r = 0; r < nrows; r++) {
    csv_string(fp, rows[r].file);
    fputc(',', fp);
    if (rows[r].crs) csv_string(fp, rows[r].crs);
    for (int k = 0; k < nf; k++) {
      fputc(',', fp);
      put_value(fp, &f[k], karst_metric_value(&rows[r].m, &f[k]), "");
    }
    if (true_north) {
      fprintf(fp, ",%s,", rows[r].true_north ? "true" : "false");
      if (rows[r].true_north) fprintf(fp, "%.17g", rows[r].convergence);
    }
    if (obs)
      for (int k = 0; k < nf; k++)
        if (!isnan(obs->min[k]))
          fprintf(fp, ",%.17g,%.17g,%s", obs->min[k], obs->max[k],
                  outside(obs, k, karst_metric_value(&rows[r].m, &f[k])) ? "true" : "false");
    fputc('\n', fp);
  }
}

static void write_table(FILE *fp, const row_t *rows, int nrows, const karst_metrics_observed_t *obs,
                        int true_north) {
  int nf;
  const karst_metric_field_t *f = karst_metric_fields(&nf);
  for (int r = 0; r < nrows; r++) {
    fprintf(fp, "%s%s\n", r ? "\n" : "", rows[r].file);
    if (rows[r].crs) fprintf(fp, "  coordinate system: %s\n", rows[r].crs);
    if (true_north) {
      if (rows[r].true_north)
        fprintf(fp, "  azimuths rotated to true north by %.6f degrees\n", rows[r].convergence);
      else
        fprintf(fp, "  azimuths relative to grid north (not convertible to true north)\n");
    }
    if (obs) fprintf(fp, "  %-27s %14s   %-23s\n", "metric", "value", "observed (Collon 2017)");
    for (int k = 0; k < nf; k++) {
      double v = karst_metric_value(&rows[r].m, &f[k]);
      char val[64];
      if (isnan(v))
        snprintf(val, sizeof val, "undefined");
      else if (f[k].is_int)
        snprintf(val, sizeof val, "%lld", (long long)v);
      else
        snprintf(val, sizeof val, "%.6g", v);
      fprintf(fp, "  %-27s %14s", f[k].key, val);
      if (obs && !isnan(obs->min[k]))
        fprintf(fp, "   [%.4g, %.4g]%s", obs->min[k], obs->max[k],
                outside(obs, k, v) ? "  <- outside" : "");
      fputc('\n', fp);
    }
  }
  if (obs)
    fprintf(fp,
            "\nobserved: min and max over the %d caves of Collon et al. 2017 (corrected "
            "2021)\n",
            obs->n_caves);
}

/* Mean horizontal position of the nodes: where the meridian convergence is taken. */
static void centroid(const karst_network_t *net, double *x, double *y) {
  double sx = 0, sy = 0;
  for (karst_int_t i = 0; i < net->n_nodes; i++) {
    sx += net->xyz[3 * i];
    sy += net->xyz[3 * i + 1];
  }
  *x = net->n_nodes ? sx / (double)net->n_nodes : 0;
  *y = net->n_nodes ? sy / (double)net->n_nodes : 0;
}

static int run(int argc, char **argv) {
  out_format_t format = OUT_TABLE;
  const char *out_path = NULL, *table_path = NULL;
  int observed = 0, true_north = 0, quiet = 0, nthreads = 0, nfiles = 0;
  char **files = calloc((size_t)argc, sizeof *files);
  row_t *rows = calloc((size_t)argc, sizeof *rows);
  int status = CLI_OK, nrows = 0;
  if (!files || !rows) {
    free(files);
    free(rows);
    fprintf(stderr, "karst metrics: out of memory\n");
    return CLI_ERROR;
  }
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    if (cli_is_help(a)) {
      cli_print_help(&cli_cmd_metrics);
      goto done;
    } else if (strcmp(a, "--format") == 0 || strcmp(a, "-f") == 0) {
      if (++i >= argc) {
        status = cli_usage_error("metrics", "%s needs table, csv or json", a);
        goto done;
      }
      if (strcmp(argv[i], "table") == 0)
        format = OUT_TABLE;
      else if (strcmp(argv[i], "csv") == 0)
        format = OUT_CSV;
      else if (strcmp(argv[i], "json") == 0)
        format = OUT_JSON;
      else {
        status = cli_usage_error("metrics", "unknown format '%s' (table, csv or json)", argv[i]);
        goto done;
      }
    } else if (strcmp(a, "-o") == 0 || strcmp(a, "--output") == 0) {
      if (++i >= argc) {
        status = cli_usage_error("metrics", "%s needs a file name", a);
        goto done;
      }
      out_path = argv[i];
    } else if (strcmp(a, "--observed") == 0) {
      observed = 1;
    } else if (strcmp(a, "--observed-table") == 0) {
      if (++i >= argc) {
        status = cli_usage_error("metrics", "%s needs a CSV file", a);
        goto done;
      }
      observed = 1;
      table_path = argv[i];
    } else if (strcmp(a, "--true-north") == 0) {
      true_north = 1;
    } else if (strcmp(a, "--threads") == 0 || strcmp(a, "-j") == 0) {
      if (++i >= argc || cli_parse_int(argv[i], &nthreads) || nthreads < 1 ||
          nthreads > KARST_ENSEMBLE_MAX_THREADS) {
        status = cli_usage_error("metrics",
                                 "%s must be a whole number of threads within [1, %d], got '%s'", a,
                                 KARST_ENSEMBLE_MAX_THREADS, i < argc ? argv[i] : "");
        goto done;
      }
    } else if (strcmp(a, "-q") == 0 || strcmp(a, "--quiet") == 0) {
      quiet = 1;
    } else if (a[0] == '-' && a[1] != '\0') {
      status = cli_usage_error("metrics", "unknown option '%s'", a);
      goto done;
    } else {
      files[nfiles++] = argv[i];
    }
  }
  if (nfiles == 0) {
    status = cli_usage_error("metrics", "no network file given");
    goto done;
  }
  if ((status =
           cli_refuse_output_over_input("metrics", out_path, (const char *const *)files, nfiles)) ||
      (table_path && (status = cli_refuse_output_over_input("metrics", out_path, &table_path, 1))))
    goto done;
  karst_ctx_t ctx;
  cli_ctx_init(&ctx, quiet, 0);
  if (nthreads > 0) ctx.nthreads = nthreads;
  karst_metrics_observed_t obs;
  if (observed) {
    char found[PATH_MAX];
    if (!table_path) {
      if (karst_published_locate(&ctx, found, sizeof found)) {
        fprintf(stderr, "karst metrics: --observed: %s (or use --observed-table FILE)\n",
                ctx.errmsg);
        status = CLI_ERROR;
        goto done;
      }
      table_path = found;
    }
    karst_error_t err = karst_metrics_observed_load(&ctx, table_path, &obs);
    if (err) {
      status = cli_fail("metrics", &ctx, err);
      goto done;
    }
  }
  for (int i = 0; i < nfiles; i++) {
    karst_network_t net;
    karst_network_init(&net);
    karst_error_t err = karst_read_network(&ctx, files[i], KARST_FORMAT_AUTO, &net);
    karst_metrics_options_t opt;
    karst_metrics_options_init(&opt);
    row_t *row = &rows[nrows];
    row->file = files[i];
    row->convergence = NAN;
    if (!err && true_north) {
      double x, y, gamma;
      centroid(&net, &x, &y);
      if (!net.crs) {
        fprintf(stderr,
                "karst metrics: warning: %s: --true-north: the file has no coordinate system; "
                "azimuths stay relative to grid north\n",
                files[i]);
      } else if (karst_crs_convergence(&ctx, net.crs, x, y, &gamma) == KARST_SUCCESS) {
        opt.azimuth_rotation = gamma;
        row->true_north = 1;
        row->convergence = gamma;
      } else {
        /* ctx.errmsg names the coordinate system and says why it is not converted. */
        fprintf(stderr,
                "karst metrics: warning: %s: --true-north: %s; azimuths stay relative to grid "
                "north\n",
                files[i], ctx.errmsg);
      }
    }
    if (!err) err = karst_metrics_compute(&ctx, &net, &opt, &row->m);
    if (!err && net.crs && !(row->crs = strdup(net.crs))) err = KARST_ENOMEM;
    karst_network_destroy(&net);
    if (err) {
      cli_fail("metrics", &ctx, err);
      status = CLI_ERROR;
      if (err == KARST_EINTERRUPTED) break;
      continue;
    }
    nrows++;
  }
  if (nrows > 0 || format != OUT_TABLE) {
    karst_atomic_file_t af;
    FILE *fp = stdout;
    if (out_path) {
      karst_error_t err = karst_atomic_open(&ctx, &af, out_path, "w");
      if (err) {
        status = cli_fail("metrics", &ctx, err);
        goto done;
      }
      fp = af.fp;
    }
    const karst_metrics_observed_t *po = observed ? &obs : NULL;
    if (format == OUT_JSON)
      write_json(fp, rows, nrows, po, true_north);
    else if (format == OUT_CSV)
      write_csv(fp, rows, nrows, po, true_north);
    else
      write_table(fp, rows, nrows, po, true_north);
    if (out_path) {
      karst_error_t err = karst_atomic_commit(&ctx, &af);
      if (err) status = cli_fail("metrics", &ctx, err);
    } else {
      fflush(stdout);
    }
  }
done:
  for (int i = 0; rows && i < nrows; i++) free(rows[i].crs);
  free(files);
  free(rows);
  return status;
}

const cli_command_t cli_cmd_metrics = {
    "metrics", run, "compute Collon et al. 2017 metrics of networks and cave surveys",
    "usage: karst metrics FILE... [--format table|csv|json] [-o OUT] [--observed]\n"
    "                     [--observed-table CSV] [--true-north] [--threads N] [-q]\n\n"
    "Reads each network or survey and prints the metrics of Collon et al. 2017 exactly as\n"
    "Karstnet 1.2.0 computes them (docs/metrics.md): mean_length, cv_length, length_entropy,\n"
    "tortuosity, orientation_entropy, aspl, cpd, mean_degree, cv_degree,\n"
    "correlation_vertex_degree, and the counts of the full and reduced graphs.\n\n"
    "Files: karst's network.vtp, Karstnet pairs X_nodes.dat + X_links.dat (either file),\n"
    "GOCAD PLine .pl, Therion SQL exports .sql, Survex .3d and .svx (through cavern).\n\n"
    "Options:\n"
    "  --format F        table (for people, default), csv (one row per file) or json\n"
    "                    (an array holding one object per file); undefined values are\n"
    "                    'undefined', empty and null.\n"
    "  -o OUT            write to OUT (atomically) instead of standard output\n"
    "  --observed        add the min / max of each metric over the 34 caves of Collon et\n"
    "                    al. 2017 (datasets/published_metrics.csv, found through\n"
    "                    $KARST_DATA_DIR, the source tree, the installed share/karst or\n"
    "                    ./datasets) and mark values\n"
    "                    outside that range\n"
    "  --observed-table CSV   the same with another table\n"
    "  --true-north      rotate azimuths by the meridian convergence of the file's coordinate\n"
    "                    system before the orientation entropy; files without a convertible\n"
    "                    system are reported and keep grid north\n"
    "  --threads N       threads for the betweenness, 1 to 1024 (default: all cores)\n"
    "  -q                quiet\n\n"
    "Exit code 1 when a file cannot be read (the others are still measured), 2 for usage "
    "errors.\n"};
