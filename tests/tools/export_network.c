/* karst_export_network INPUT PREFIX: read INPUT with karst's readers (format from the
 * extension) and write the network as the Karstnet pair PREFIX_nodes.dat / PREFIX_links.dat
 * (%.17g, bit for bit), so that tests/tools/karstnet_reference.py measures exactly the graph
 * karst measures without sharing any of its metric code. */
#include <stdio.h>

#include "karst.h"

int main(int argc, char **argv) {
  if (argc != 3) {
    fprintf(stderr, "usage: %s INPUT PREFIX\n", argv[0]);
    return 2;
  }
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_network_t net;
  karst_network_init(&net);
  karst_error_t err = karst_read_network(&ctx, argv[1], KARST_FORMAT_AUTO, &net);
  if (!err) err = karst_write_karstnet(&ctx, argv[2], &net);
  if (err) fprintf(stderr, "%s\n", ctx.errmsg);
  karst_network_destroy(&net);
  return err ? 1 : 0;
}
