/* One entry point for every network file format: pick the reader from the
 * extension, or from the first bytes when the extension says nothing. */
#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "io/input_internal.h"
#include "karst/readers.h"
#include "karst/vtk.h"

static int ends_with_ci(const char *s, const char *suffix) {
  size_t n = strlen(s), k = strlen(suffix);
  return n >= k && strcasecmp(s + n - k, suffix) == 0;
}

static karst_format_t format_from_name(const char *path) {
  if (ends_with_ci(path, ".vtp")) return KARST_FORMAT_VTP;
  if (ends_with_ci(path, "_nodes.dat") || ends_with_ci(path, "_links.dat"))
    return KARST_FORMAT_KARSTNET;
  if (ends_with_ci(path, ".pl")) return KARST_FORMAT_PLINE;
  if (ends_with_ci(path, ".sql")) return KARST_FORMAT_THERION_SQL;
  if (ends_with_ci(path, ".3d")) return KARST_FORMAT_SURVEX_3D;
  if (ends_with_ci(path, ".svx")) return KARST_FORMAT_SURVEX_SVX;
  return KARST_FORMAT_AUTO;
}

/* Magic bytes: Survex .3d starts "Survex 3D Image File", GOCAD "GOCAD PLine",
 * VTK XML "<?xml" or "<VTKFile". */
static karst_format_t format_from_magic(const char *head, size_t n) {
  if (n >= 20 && memcmp(head, "Survex 3D Image File", 20) == 0) return KARST_FORMAT_SURVEX_3D;
  if (n >= 11 && memcmp(head, "GOCAD PLine", 11) == 0) return KARST_FORMAT_PLINE;
  if ((n >= 5 && memcmp(head, "<?xml", 5) == 0) || (n >= 8 && memcmp(head, "<VTKFile", 8) == 0))
    return KARST_FORMAT_VTP;
  return KARST_FORMAT_AUTO;
}

/**
 * Read a network from any supported file.
 *
 * @param ctx    context (the reader's "FILE:LINE: message" on failure)
 * @param path   the file (for a Karstnet pair, either file or the common prefix)
 * @param format KARST_FORMAT_AUTO: from the extension, then from the first
 *               bytes; otherwise the reader to use
 * @param net    initialised network, filled by the reader
 * @return the reader's result; KARST_EUNSUPPORTED when the format cannot be told.
 * Time complexity: that of the reader.
 */
karst_error_t karst_read_network(karst_ctx_t *ctx, const char *path, karst_format_t format,
                                 karst_network_t *net) {
  if (format == KARST_FORMAT_AUTO) format = format_from_name(path);
  if (format == KARST_FORMAT_AUTO) {
    char head[32];
    size_t n = 0;
    struct stat st;
    if (stat(path, &st) == 0) {
      /* Sniff the first bytes through the guarded opening: a FIFO or a device
       * named without an extension is refused here instead of blocking. */
      FILE *fp;
      karst_error_t err = karst_i_open_regular(ctx, path, "network", KARST_VTP_MAX_BYTES, &fp);
      if (err) return err;
      n = fread(head, 1, sizeof head, fp);
      fclose(fp);
      format = format_from_magic(head, n);
    } else {
      /* maybe the prefix X of a Karstnet pair X_nodes.dat + X_links.dat */
      int e = errno;
      char nodes[4096];
      snprintf(nodes, sizeof nodes, "%s_nodes.dat", path);
      if (stat(nodes, &st) == 0) {
        format = KARST_FORMAT_KARSTNET;
      } else {
        return karst_set_error(ctx, e == ENOENT ? KARST_ENOTFOUND : KARST_EIO,
                               "%s: cannot open: %s", path, strerror(e));
      }
    }
  }
  switch (format) {
  case KARST_FORMAT_VTP:
    return karst_vtk_read_network(ctx, path, net);
  case KARST_FORMAT_KARSTNET:
    return karst_read_karstnet(ctx, path, net);
  case KARST_FORMAT_PLINE:
    return karst_read_pline(ctx, path, net);
  case KARST_FORMAT_THERION_SQL:
    return karst_read_therion_sql(ctx, path, net);
  case KARST_FORMAT_SURVEX_3D:
    return karst_read_survex3d(ctx, path, net);
  case KARST_FORMAT_SURVEX_SVX:
    return karst_read_svx(ctx, path, net);
  case KARST_FORMAT_AUTO:
    break;
  }
  return karst_set_error(ctx, KARST_EUNSUPPORTED,
                         "%s: unknown network format (expected .vtp, X_nodes.dat / X_links.dat, "
                         ".pl, .sql, .3d or .svx)",
                         path);
}
