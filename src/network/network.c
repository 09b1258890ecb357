/* The network type: nodes, edges and named attribute arrays (include/karst/network.h). */
#include "karst/network.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char *const node_kind_names[] = {
#define KARST_X_NAME(code, name) name,
    KARST_NODE_KIND_LIST(KARST_X_NAME)
#undef KARST_X_NAME
};
static const char *const tunnel_type_names[] = {
#define KARST_X_NAME(code, name) name,
    KARST_TUNNEL_TYPE_LIST(KARST_X_NAME)
#undef KARST_X_NAME
};

const char *karst_node_kind_name(karst_node_kind_t kind) {
  return ((int)kind >= 0 && kind < KARST_NODE_KIND_COUNT) ? node_kind_names[kind] : "unknown";
}

const char *karst_tunnel_type_name(karst_tunnel_type_t type) {
  return ((int)type >= 0 && type < KARST_TUNNEL_TYPE_COUNT) ? tunnel_type_names[type] : "unknown";
}

int karst_tunnel_type_from_name(const char *name) {
  for (int i = 0; i < KARST_TUNNEL_TYPE_COUNT; i++)
    if (strcmp(name, tunnel_type_names[i]) == 0) return i;
  return -1;
}

void karst_network_init(karst_network_t *net) {
  memset(net, 0, sizeof *net);
}

static void free_attrs(karst_attr_t *a, int n) {
  for (int i = 0; i < n; i++)
    free(a[i].data);
  free(a);
}

void karst_network_destroy(karst_network_t *net) {
  free(net->xyz);
  free(net->edges);
  free_attrs(net->node_attrs, net->n_node_attrs);
  free_attrs(net->edge_attrs, net->n_edge_attrs);
  if (net->node_labels) {
    for (karst_int_t i = 0; i < net->node_cap; i++)
      free(net->node_labels[i]);
    free(net->node_labels);
  }
  free(net->crs);
  free(net->title);
  for (int i = 0; i < net->n_strings; i++) {
    for (int j = 0; j < net->strings[i].n; j++)
      free(net->strings[i].values[j]);
    free(net->strings[i].values);
  }
  free(net->strings);
  memset(net, 0, sizeof *net);
}

/* Grow every per-item array of one domain to @p cap items (new items zeroed). */
static karst_error_t grow(karst_network_t *net, karst_attr_domain_t dom, karst_int_t cap) {
  karst_int_t old = dom == KARST_ATTR_NODE ? net->node_cap : net->edge_cap;
  if (dom == KARST_ATTR_NODE) {
    double *xyz = realloc(net->xyz, (size_t)cap * 3 * sizeof *xyz);
    if (!xyz) return KARST_ENOMEM;
    net->xyz = xyz;
    if (net->node_labels) {
      char **l = realloc(net->node_labels, (size_t)cap * sizeof *l);
      if (!l) return KARST_ENOMEM;
      memset(l + old, 0, (size_t)(cap - old) * sizeof *l);
      net->node_labels = l;
    }
  } else {
    karst_int_t *e = realloc(net->edges, (size_t)cap * 2 * sizeof *e);
    if (!e) return KARST_ENOMEM;
    net->edges = e;
  }
  karst_attr_t *attrs = dom == KARST_ATTR_NODE ? net->node_attrs : net->edge_attrs;
  int na = dom == KARST_ATTR_NODE ? net->n_node_attrs : net->n_edge_attrs;
  for (int i = 0; i < na; i++) {
    double *d = realloc(attrs[i].data, (size_t)cap * attrs[i].ncomp * sizeof *d);
    if (!d) return KARST_ENOMEM;
    memset(d + (size_t)old * attrs[i].ncomp, 0, (size_t)(cap - old) * attrs[i].ncomp * sizeof *d);
    attrs[i].data = d;
  }
  if (dom == KARST_ATTR_NODE)
    net->node_cap = cap;
  else
    net->edge_cap = cap;
  return KARST_SUCCESS;
}

karst_error_t karst_network_add_node(karst_network_t *net, double x, double y, double z,
                                     karst_int_t *index) {
  if (net->n_nodes == net->node_cap) {
    karst_error_t err = grow(net, KARST_ATTR_NODE, net->node_cap ? 2 * net->node_cap : 64);
    if (err) return err;
  }
  karst_int_t i = net->n_nodes++;
  net->xyz[3 * i] = x;
  net->xyz[3 * i + 1] = y;
  net->xyz[3 * i + 2] = z;
  if (index) *index = i;
  return KARST_SUCCESS;
}

karst_error_t karst_network_add_edge(karst_network_t *net, karst_int_t u, karst_int_t v,
                                     karst_int_t *index) {
  if (u < 0 || v < 0 || u >= net->n_nodes || v >= net->n_nodes) return KARST_EINVAL;
  if (net->n_edges == net->edge_cap) {
    karst_error_t err = grow(net, KARST_ATTR_EDGE, net->edge_cap ? 2 * net->edge_cap : 64);
    if (err) return err;
  }
  karst_int_t e = net->n_edges++;
  net->edges[2 * e] = u;
  net->edges[2 * e + 1] = v;
  if (index) *index = e;
  return KARST_SUCCESS;
}

karst_attr_t *karst_network_attr_find(const karst_network_t *net, karst_attr_domain_t domain,
                                      const char *name) {
  karst_attr_t *a = domain == KARST_ATTR_NODE ? net->node_attrs : net->edge_attrs;
  int n = domain == KARST_ATTR_NODE ? net->n_node_attrs : net->n_edge_attrs;
  for (int i = 0; i < n; i++)
    if (strcmp(a[i].name, name) == 0) return &a[i];
  return NULL;
}

karst_error_t karst_network_attr_add(karst_network_t *net, karst_attr_domain_t domain,
                                     const char *name, int ncomp, int integer, double **data) {
  if (ncomp < 1 || strlen(name) >= sizeof((karst_attr_t *)0)->name) return KARST_EINVAL;
  karst_attr_t *found = karst_network_attr_find(net, domain, name);
  if (found) {
    if (found->ncomp != ncomp) return KARST_EINVAL;
    if (data) *data = found->data;
    return KARST_SUCCESS;
  }
  karst_attr_t **arr = domain == KARST_ATTR_NODE ? &net->node_attrs : &net->edge_attrs;
  int *n = domain == KARST_ATTR_NODE ? &net->n_node_attrs : &net->n_edge_attrs;
  karst_int_t cap = domain == KARST_ATTR_NODE ? net->node_cap : net->edge_cap;
  double *d = calloc((size_t)(cap > 0 ? cap : 1) * ncomp, sizeof *d);
  if (!d) return KARST_ENOMEM;
  karst_attr_t *a = realloc(*arr, (size_t)(*n + 1) * sizeof *a);
  if (!a) {
    free(d);
    return KARST_ENOMEM;
  }
  *arr = a;
  karst_attr_t *na = &a[(*n)++];
  memset(na, 0, sizeof *na);
  strcpy(na->name, name);
  na->ncomp = ncomp;
  na->integer = integer;
  na->data = d;
  if (data) *data = d;
  return KARST_SUCCESS;
}

static char *dupstr(const char *s) {
  if (!s) return NULL;
  size_t n = strlen(s) + 1;
  char *d = malloc(n);
  if (d) memcpy(d, s, n);
  return d;
}

karst_error_t karst_network_set_label(karst_network_t *net, karst_int_t i, const char *label) {
  if (i < 0 || i >= net->n_nodes) return KARST_EINVAL;
  if (!net->node_labels) {
    net->node_labels = calloc((size_t)(net->node_cap > 0 ? net->node_cap : 1), sizeof(char *));
    if (!net->node_labels) return KARST_ENOMEM;
  }
  char *d = dupstr(label);
  if (label && !d) return KARST_ENOMEM;
  free(net->node_labels[i]);
  net->node_labels[i] = d;
  return KARST_SUCCESS;
}

karst_error_t karst_network_set_crs(karst_network_t *net, const char *crs) {
  char *d = dupstr(crs);
  if (crs && !d) return KARST_ENOMEM;
  free(net->crs);
  net->crs = d;
  return KARST_SUCCESS;
}

/** Set (or replace) the string list @p name (at most 47 bytes) to copies of @p values. O(n). */
karst_error_t karst_network_set_strings(karst_network_t *net, const char *name, int n,
                                        const char *const *values) {
  if (!name || strlen(name) >= sizeof net->strings[0].name || n < 0) return KARST_EINVAL;
  char **v = calloc((size_t)(n > 0 ? n : 1), sizeof *v);
  if (!v) return KARST_ENOMEM;
  for (int j = 0; j < n; j++)
    if (!(v[j] = dupstr(values[j] ? values[j] : ""))) {
      for (int k = 0; k < j; k++)
        free(v[k]);
      free(v);
      return KARST_ENOMEM;
    }
  int i = 0;
  while (i < net->n_strings && strcmp(net->strings[i].name, name) != 0)
    i++;
  if (i == net->n_strings) {
    karst_strings_t *ns = realloc(net->strings, (size_t)(i + 1) * sizeof *ns);
    if (!ns) {
      for (int k = 0; k < n; k++)
        free(v[k]);
      free(v);
      return KARST_ENOMEM;
    }
    net->strings = ns;
    memset(&ns[i], 0, sizeof ns[i]);
    strcpy(ns[i].name, name);
    net->n_strings++;
  }
  for (int k = 0; k < net->strings[i].n; k++)
    free(net->strings[i].values[k]);
  free(net->strings[i].values);
  net->strings[i].values = v;
  net->strings[i].n = n;
  return KARST_SUCCESS;
}

karst_error_t karst_network_copy(karst_network_t *dst, const karst_network_t *src) {
  karst_network_t n;
  karst_network_init(&n);
  karst_error_t err = KARST_SUCCESS;
  if ((err = grow(&n, KARST_ATTR_NODE, src->node_cap > 0 ? src->node_cap : 1))) goto fail;
  if ((err = grow(&n, KARST_ATTR_EDGE, src->edge_cap > 0 ? src->edge_cap : 1))) goto fail;
  memcpy(n.xyz, src->xyz, (size_t)src->n_nodes * 3 * sizeof(double));
  memcpy(n.edges, src->edges, (size_t)src->n_edges * 2 * sizeof(karst_int_t));
  n.n_nodes = src->n_nodes;
  n.n_edges = src->n_edges;
  for (int dom = 0; dom < 2; dom++) {
    const karst_attr_t *a = dom == 0 ? src->node_attrs : src->edge_attrs;
    int na = dom == 0 ? src->n_node_attrs : src->n_edge_attrs;
    karst_int_t cnt = dom == 0 ? src->n_nodes : src->n_edges;
    for (int i = 0; i < na; i++) {
      double *d;
      if ((err = karst_network_attr_add(&n, (karst_attr_domain_t)dom, a[i].name, a[i].ncomp,
                                        a[i].integer, &d)))
        goto fail;
      memcpy(d, a[i].data, (size_t)cnt * a[i].ncomp * sizeof(double));
    }
  }
  if (src->node_labels)
    for (karst_int_t i = 0; i < src->n_nodes; i++)
      if (src->node_labels[i] && (err = karst_network_set_label(&n, i, src->node_labels[i])))
        goto fail;
  if ((err = karst_network_set_crs(&n, src->crs))) goto fail;
  for (int i = 0; i < src->n_strings; i++)
    if ((err = karst_network_set_strings(&n, src->strings[i].name, src->strings[i].n,
                                         (const char *const *)src->strings[i].values)))
      goto fail;
  if (src->title && !(n.title = dupstr(src->title))) {
    err = KARST_ENOMEM;
    goto fail;
  }
  *dst = n;
  return KARST_SUCCESS;
fail:
  karst_network_destroy(&n);
  return err;
}

double karst_network_edge_length(const karst_network_t *net, karst_int_t e) {
  const double *a = net->xyz + 3 * net->edges[2 * e];
  const double *b = net->xyz + 3 * net->edges[2 * e + 1];
  return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
              (a[2] - b[2]) * (a[2] - b[2]));
}
