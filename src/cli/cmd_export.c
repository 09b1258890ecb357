/* karst export: a network as a GeoPackage for QGIS (library: karst_export_gpkg). */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

/* OUT.gpkg -> OUT.qml (malloc'ed). */
static char *style_name(const char *gpkg) {
  size_t n = strlen(gpkg);
  char *q = malloc(n + 5);
  if (!q) return NULL;
  memcpy(q, gpkg, n + 1);
  if (n > 5 && strcmp(q + n - 5, ".gpkg") == 0) q[n - 5] = '\0';
  strcat(q, ".qml");
  return q;
}

/* SOURCE_DATE_EPOCH (reproducible-builds.org): the time to stamp the GeoPackage with, a
 * decimal number of seconds since 1970-01-01 UTC; unset or empty: the export's time. */
static karst_error_t source_date_epoch(karst_ctx_t *ctx, int64_t *timestamp) {
  const char *v = getenv("SOURCE_DATE_EPOCH");
  *timestamp = KARST_EXPORT_TIME_NOW;
  if (!v || !*v) return KARST_SUCCESS;
  char *end = NULL;
  errno = 0;
  long long t = strtoll(v, &end, 10);
  if (v[0] < '0' || v[0] > '9' || *end != '\0' || errno == ERANGE)
    return karst_set_error(ctx, KARST_EINVAL,
                           "SOURCE_DATE_EPOCH: '%s' is not a number of seconds since "
                           "1970-01-01 UTC",
                           v);
  *timestamp = (int64_t)t;
  return KARST_SUCCESS;
}

static int run(int argc, char **argv) {
  const char *input = NULL, *gpkg = NULL, *crs = NULL, *qml = NULL;
  int quiet = 0;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    if (strcmp(a, "--gpkg") == 0 || strcmp(a, "--crs") == 0 || strcmp(a, "--qml") == 0) {
      if (++i >= argc) return cli_usage_error("export", "%s needs a value", a);
      if (!argv[i][0]) return cli_usage_error("export", "%s needs a non-empty value", a);
      *(a[2] == 'g' ? &gpkg : a[2] == 'c' ? &crs : &qml) = argv[i];
    } else if (strcmp(a, "--quiet") == 0 || strcmp(a, "-q") == 0) {
      quiet = 1;
    } else if (a[0] == '-' && a[1] != '\0') {
      return cli_usage_error("export", "unknown option '%s'", a);
    } else if (!input) {
      input = a;
    } else {
      return cli_usage_error("export", "more than one input given ('%s' and '%s')", input, a);
    }
  }
  if (!input) return cli_usage_error("export", "no directory or network file given");
  if (!gpkg) return cli_usage_error("export", "no output given (--gpkg OUT.gpkg)");

  karst_ctx_t ctx;
  cli_ctx_init(&ctx, quiet, 0);
  karst_export_source_t src;
  karst_export_source_init(&src);
  karst_export_options_t opt;
  karst_export_options_init(&opt);
  char *style = qml ? NULL : style_name(gpkg);
  int status = CLI_OK;
  karst_error_t err;
  if (!qml && !style) {
    err = karst_set_error(&ctx, KARST_ENOMEM, "out of memory");
    goto fail;
  }
  opt.crs = crs;
  opt.qml_path = qml ? qml : style;
  { /* neither output may replace what the export reads (karst_export_source_load) */
    char net[4200], run_json[4200], ens[4200], key[4200];
    snprintf(net, sizeof net, "%.4000s/network.vtp", input);
    snprintf(run_json, sizeof run_json, "%.4000s/run.json", input);
    snprintf(ens, sizeof ens, "%.4000s/../../ensemble.json", input);
    snprintf(key, sizeof key, "%.4000s/../ensemble.key", input);
    const char *ins[5] = {input, net, run_json, ens, key};
    const char *outs[2] = {gpkg, opt.qml_path};
    for (int o = 0; o < 2 && status == CLI_OK; o++)
      status = cli_refuse_output_over_input("export", outs[o], ins, 5);
    if (status != CLI_OK) goto cleanup;
  }
  if ((err = source_date_epoch(&ctx, &opt.timestamp))) goto fail;
  if ((err = karst_export_source_load(&ctx, input, &src))) goto fail;
  if ((err = karst_export_gpkg(&ctx, gpkg, &src, &opt))) goto fail;
  if (!quiet) {
    const char *c = crs ? crs : src.crs;
    printf("%s -> %s: %lld conduits, %lld nodes, %d key points; coordinate system %s%s%s%s; "
           "style %s\n",
           input, gpkg, (long long)src.net.n_edges, (long long)src.net.n_nodes, src.n_key_points,
           c ? c : "undefined (none in the input; give one with --crs)", c ? " (from " : "",
           c ? (crs ? "--crs" : src.crs_where) : "", c ? ")" : "", opt.qml_path);
  }
  goto cleanup;
fail:
  status = cli_fail("export", &ctx, err);
cleanup:
  free(style);
  karst_export_source_destroy(&src);
  return status;
}

const cli_command_t cli_cmd_export = {
    "export", run, "write a network as a GeoPackage for QGIS, with its style",
    "usage: karst export DIR|FILE --gpkg OUT.gpkg [--crs CRS] [--qml STYLE.qml] [--quiet]\n\n"
    "Writes the network of DIR (a directory of `karst generate`, or an ensemble member\n"
    "DIR/realisations/NNNN) or of FILE (any network or survey `karst metrics` reads) as a\n"
    "GeoPackage (docs/gis.md) with the layers\n"
    "  conduits    one 3-D LineString per edge with every edge attribute (tunnel_type and its\n"
    "              name, radius, ...), its length and its end nodes\n"
    "  nodes       one 3-D point per node with every node attribute (kind, ...) and label\n"
    "  key_points  the sinks, springs and waypoints of run.json, with their names\n"
    "in the coordinate system of run.json's \"crs\" (or the survey's own); none is written\n"
    "when the input has none. QGIS applies the styles stored in the GeoPackage when it opens\n"
    "a layer; the conduits' style is also written to OUT.qml (tunnel types in the colours of\n"
    "the report and of ParaView). Both files are written to temporary names and renamed\n"
    "into place together: a failed export leaves neither. The file's only clock readings\n"
    "(gpkg_contents.last_change, layer_styles.update_time) are the export's time, or\n"
    "SOURCE_DATE_EPOCH (seconds since 1970-01-01 UTC) when that is set: the same input\n"
    "then gives a byte-identical GeoPackage.\n\n"
    "  --gpkg OUT.gpkg  the GeoPackage to write (the name must end in .gpkg)\n"
    "  --crs CRS        coordinate system to write instead of the input's: EPSG:2154, a WKT\n"
    "                   or PROJ string (anything GDAL's OSRSetFromUserInput reads)\n"
    "  --qml FILE       where to write the conduits' style (default: OUT.qml)\n"
    "  --quiet          no summary line\n"};
