/* Every arc's head of a graph as one array, adj[a] the head of arc a, read through the
 * library's row reader (karst_graph_arcs): lets a test index arcs at random. */
#ifndef KARST_TEST_GRAPH_HEADS_H
#define KARST_TEST_GRAPH_HEADS_H

#include <stdlib.h>

#include "karst.h"

/* Heads of all arcs of @p g (malloc'd, n_arcs + 1 entries; the caller frees), or NULL. */
static inline int32_t *fx_heads(const karst_graph_t *g) {
  int32_t *adj = malloc(sizeof *adj * ((size_t)g->n_arcs + 1));
  if (!adj) return NULL;
  for (karst_int_t v = 0; v < g->n; v++) {
    karst_arc_reader_t r = karst_graph_arcs(g, v);
    for (karst_int_t a = g->offsets[v]; a < g->offsets[v + 1]; a++)
      adj[a] = (int32_t)karst_arc_next(&r);
  }
  return adj;
}

#endif
