/* Networks between karst_network_t and Python: numpy arrays in a dict one way, the attributes
 * of a karst.Network (or any object with the same attributes) the other way, checked. */
#include "python/python_internal.h"

#include <math.h>
#include <stdarg.h>
#include <string.h>

/* A new (n, k) array, or (n,) when k == 1, of @p type, filled by the caller. */
static PyArrayObject *new_array(npy_intp n, int k, int type) {
  npy_intp dims[2] = {n, k};
  return (PyArrayObject *)PyArray_SimpleNew(k == 1 ? 1 : 2, dims, type);
}

/* An attribute as int64 when it is whole and finite everywhere, else float64. */
static PyObject *attr_array(const karst_attr_t *a, karst_int_t n) {
  size_t total = (size_t)n * (size_t)a->ncomp;
  int whole = a->integer;
  for (size_t i = 0; whole && i < total; i++)
    whole = isfinite(a->data[i]) && fabs(a->data[i]) < 9.0e18;
  PyArrayObject *arr = new_array((npy_intp)n, a->ncomp, whole ? NPY_INT64 : NPY_FLOAT64);
  if (!arr) return NULL;
  if (whole) {
    int64_t *d = PyArray_DATA(arr);
    for (size_t i = 0; i < total; i++)
      d[i] = (int64_t)a->data[i];
  } else if (total) {
    memcpy(PyArray_DATA(arr), a->data, total * sizeof(double));
  }
  return (PyObject *)arr;
}

static PyObject *attrs_dict(const karst_attr_t *attrs, int n_attrs, karst_int_t n) {
  PyObject *d = PyDict_New();
  for (int i = 0; d && i < n_attrs; i++) {
    PyObject *a = attr_array(&attrs[i], n);
    if (!a || PyDict_SetItemString(d, attrs[i].name, a) < 0) Py_CLEAR(d);
    Py_XDECREF(a);
  }
  return d;
}

static PyObject *str_or_none(const char *s) {
  if (!s) Py_RETURN_NONE;
  return PyUnicode_DecodeUTF8(s, (Py_ssize_t)strlen(s), "replace");
}

PyObject *karst_py_network_to_dict(const karst_network_t *net) {
  PyArrayObject *xyz = new_array((npy_intp)net->n_nodes, 3, NPY_FLOAT64);
  PyArrayObject *edges = new_array((npy_intp)net->n_edges, 2, NPY_INT64);
  PyObject *nd = attrs_dict(net->node_attrs, net->n_node_attrs, net->n_nodes);
  PyObject *ed = attrs_dict(net->edge_attrs, net->n_edge_attrs, net->n_edges);
  PyObject *labels = NULL, *crs = str_or_none(net->crs), *title = str_or_none(net->title);
  PyObject *out = NULL;
  if (!xyz || !edges || !nd || !ed || !crs || !title) goto cleanup;
  if (net->n_nodes) memcpy(PyArray_DATA(xyz), net->xyz, 3 * (size_t)net->n_nodes * sizeof(double));
  if (net->n_edges)
    memcpy(PyArray_DATA(edges), net->edges, 2 * (size_t)net->n_edges * sizeof(int64_t));
  if (net->node_labels) {
    labels = PyList_New((Py_ssize_t)net->n_nodes);
    for (karst_int_t i = 0; labels && i < net->n_nodes; i++) {
      PyObject *s = str_or_none(net->node_labels[i]);
      if (!s)
        Py_CLEAR(labels);
      else
        PyList_SET_ITEM(labels, (Py_ssize_t)i, s);
    }
    if (!labels) goto cleanup;
  } else {
    labels = Py_None;
    Py_INCREF(labels);
  }
  out = Py_BuildValue("{s:O,s:O,s:O,s:O,s:O,s:O,s:O}", "xyz", xyz, "edges", edges, "node_data", nd,
                      "edge_data", ed, "labels", labels, "crs", crs, "title", title);
cleanup:
  Py_XDECREF(xyz), Py_XDECREF(edges), Py_XDECREF(nd), Py_XDECREF(ed);
  Py_XDECREF(labels), Py_XDECREF(crs), Py_XDECREF(title);
  return out;
}

/* ------------------------------------------------------------------------ */
/* Python -> karst_network_t                                                 */
/* ------------------------------------------------------------------------ */

static int fail_value(PyObject *module, const char *fmt, ...) {
  char msg[512];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  karst_py_raise(module, KARST_EINVAL, msg);
  return -1;
}

/* @p obj as a C-contiguous array of @p type with @p ndim dims (a 1-D array is (n,) for
 * ndim_max 2); integer arrays refuse non-integer input rather than truncate it. */
static PyArrayObject *as_array(PyObject *module, PyObject *obj, int type, int ndim_min,
                               int ndim_max, const char *what) {
  PyArrayObject *in = (PyArrayObject *)PyArray_FROMANY(obj, NPY_NOTYPE, ndim_min, ndim_max, 0);
  if (!in) {
    PyErr_Clear();
    fail_value(module, "%s must be an array of %d to %d dimensions", what, ndim_min, ndim_max);
    return NULL;
  }
  int k = PyArray_TYPE(in);
  int ok = type == NPY_INT64
               ? PyTypeNum_ISINTEGER(k) || PyTypeNum_ISBOOL(k) || (PyArray_SIZE(in) == 0)
               : PyTypeNum_ISNUMBER(k) || PyTypeNum_ISBOOL(k);
  if (!ok) {
    Py_DECREF(in);
    fail_value(module, "%s must hold %s, got dtype %s", what,
               type == NPY_INT64 ? "integers" : "numbers",
               PyArray_DESCR(in) ? PyArray_DESCR(in)->typeobj->tp_name : "?");
    return NULL;
  }
  PyArrayObject *out = (PyArrayObject *)PyArray_FROMANY((PyObject *)in, type, ndim_min, ndim_max,
                                                        NPY_ARRAY_IN_ARRAY | NPY_ARRAY_FORCECAST);
  Py_DECREF(in);
  return out;
}

/* Attributes of @p dict (name -> array of n rows) into @p net's @p domain. */
static int attrs_from_dict(PyObject *module, PyObject *dict, karst_network_t *net,
                           karst_attr_domain_t domain, karst_int_t n) {
  const char *what = domain == KARST_ATTR_NODE ? "node_data" : "edge_data";
  if (dict == Py_None) return 0;
  if (!PyDict_Check(dict)) return fail_value(module, "%s must be a dict of arrays", what);
  PyObject *key, *value;
  Py_ssize_t pos = 0;
  while (PyDict_Next(dict, &pos, &key, &value)) {
    const char *name = PyUnicode_Check(key) ? PyUnicode_AsUTF8(key) : NULL;
    if (!name) {
      PyErr_Clear();
      return fail_value(module, "%s keys must be strings", what);
    }
    if (!*name || strlen(name) >= sizeof net->node_attrs->name)
      return fail_value(module, "%s: attribute name '%s' must have 1 to %d characters", what, name,
                        (int)sizeof net->node_attrs->name - 1);
    char label[128];
    snprintf(label, sizeof label, "%s['%s']", what, name);
    PyArrayObject *probe = (PyArrayObject *)PyArray_FROMANY(value, NPY_NOTYPE, 1, 2, 0);
    if (!probe) {
      PyErr_Clear();
      return fail_value(module, "%s must be an array of 1 or 2 dimensions", label);
    }
    int integer = PyTypeNum_ISINTEGER(PyArray_TYPE(probe)) || PyTypeNum_ISBOOL(PyArray_TYPE(probe));
    Py_DECREF(probe);
    PyArrayObject *a = as_array(module, value, NPY_FLOAT64, 1, 2, label);
    if (!a) return -1;
    npy_intp rows = PyArray_DIM(a, 0);
    int ncomp = PyArray_NDIM(a) == 2 ? (int)PyArray_DIM(a, 1) : 1;
    if (rows != (npy_intp)n || ncomp < 1) {
      Py_DECREF(a);
      return fail_value(module, "%s has %lld rows and %d columns; the network has %lld %s", label,
                        (long long)rows, ncomp, (long long)n,
                        domain == KARST_ATTR_NODE ? "nodes" : "edges");
    }
    double *data;
    karst_error_t err = karst_network_attr_add(net, domain, name, ncomp, integer, &data);
    if (!err && n) memcpy(data, PyArray_DATA(a), (size_t)n * (size_t)ncomp * sizeof(double));
    Py_DECREF(a);
    if (err) {
      karst_py_raise(module, err, "out of memory");
      return -1;
    }
  }
  return 0;
}

static int optional_string(PyObject *module, PyObject *obj, const char *name, char **out) {
  *out = NULL;
  PyObject *v = PyObject_GetAttrString(obj, name);
  if (!v) return -1;
  int rc = 0;
  if (v != Py_None) {
    const char *s = PyUnicode_Check(v) ? PyUnicode_AsUTF8(v) : NULL;
    if (!s) {
      PyErr_Clear();
      rc = fail_value(module, "%s must be a string or None", name);
    } else if (!(*out = strdup(s))) {
      PyErr_NoMemory();
      rc = -1;
    }
  }
  Py_DECREF(v);
  return rc;
}

int karst_py_network_from_object(PyObject *module, PyObject *obj, karst_network_t *net) {
  PyObject *xyz_o = NULL, *edges_o = NULL, *nd = NULL, *ed = NULL, *labels = NULL;
  PyArrayObject *xyz = NULL, *edges = NULL;
  char *crs = NULL, *title = NULL;
  int rc = -1;
  if (!(xyz_o = PyObject_GetAttrString(obj, "xyz")) ||
      !(edges_o = PyObject_GetAttrString(obj, "edges")))
    goto cleanup;
  if (!(xyz = as_array(module, xyz_o, NPY_FLOAT64, 2, 2, "xyz"))) goto cleanup;
  if (!(edges = as_array(module, edges_o, NPY_INT64, 2, 2, "edges"))) goto cleanup;
  npy_intp n = PyArray_DIM(xyz, 0), m = PyArray_DIM(edges, 0);
  if (PyArray_DIM(xyz, 1) != 3) {
    fail_value(module, "xyz must have shape (n, 3), got (%lld, %lld)", (long long)n,
               (long long)PyArray_DIM(xyz, 1));
    goto cleanup;
  }
  if (PyArray_DIM(edges, 1) != 2) {
    fail_value(module, "edges must have shape (m, 2), got (%lld, %lld)", (long long)m,
               (long long)PyArray_DIM(edges, 1));
    goto cleanup;
  }
  const double *p = PyArray_DATA(xyz);
  for (npy_intp i = 0; i < n; i++)
    if (!isfinite(p[3 * i]) || !isfinite(p[3 * i + 1]) || !isfinite(p[3 * i + 2])) {
      fail_value(module, "node %lld: coordinates must be finite, got (%g, %g, %g)", (long long)i,
                 p[3 * i], p[3 * i + 1], p[3 * i + 2]);
      goto cleanup;
    }
  const int64_t *e = PyArray_DATA(edges);
  for (npy_intp j = 0; j < 2 * m; j++)
    if (e[j] < 0 || e[j] >= n) {
      fail_value(module, "edge %lld names node %lld; nodes are numbered 0 to %lld",
                 (long long)(j / 2), (long long)e[j], (long long)n - 1);
      goto cleanup;
    }
  for (npy_intp i = 0; i < n; i++)
    if (karst_network_add_node(net, p[3 * i], p[3 * i + 1], p[3 * i + 2], NULL)) goto nomem;
  for (npy_intp j = 0; j < m; j++)
    if (karst_network_add_edge(net, e[2 * j], e[2 * j + 1], NULL)) goto nomem;
  if (!(nd = PyObject_GetAttrString(obj, "node_data")) ||
      attrs_from_dict(module, nd, net, KARST_ATTR_NODE, (karst_int_t)n) < 0)
    goto cleanup;
  if (!(ed = PyObject_GetAttrString(obj, "edge_data")) ||
      attrs_from_dict(module, ed, net, KARST_ATTR_EDGE, (karst_int_t)m) < 0)
    goto cleanup;
  if (!(labels = PyObject_GetAttrString(obj, "labels"))) goto cleanup;
  if (labels != Py_None) {
    PyObject *seq = PySequence_Fast(labels, "labels must be a sequence of strings or None");
    if (!seq) goto cleanup;
    if (PySequence_Fast_GET_SIZE(seq) != n) {
      Py_DECREF(seq);
      fail_value(module, "labels has %lld entries; the network has %lld nodes",
                 (long long)PySequence_Size(labels), (long long)n);
      goto cleanup;
    }
    for (npy_intp i = 0; i < n; i++) {
      PyObject *s = PySequence_Fast_GET_ITEM(seq, i);
      if (s == Py_None) continue;
      const char *t = PyUnicode_Check(s) ? PyUnicode_AsUTF8(s) : NULL;
      if (!t) {
        PyErr_Clear();
        Py_DECREF(seq);
        fail_value(module, "label %lld must be a string or None", (long long)i);
        goto cleanup;
      }
      if (karst_network_set_label(net, (karst_int_t)i, t)) {
        Py_DECREF(seq);
        goto nomem;
      }
    }
    Py_DECREF(seq);
  }
  if (optional_string(module, obj, "crs", &crs) < 0 ||
      optional_string(module, obj, "title", &title) < 0)
    goto cleanup;
  if (karst_network_set_crs(net, crs)) goto nomem;
  if (title) {
    net->title = title;
    title = NULL;
  }
  rc = 0;
  goto cleanup;
nomem:
  PyErr_NoMemory();
cleanup:
  free(crs);
  free(title);
  Py_XDECREF(xyz_o), Py_XDECREF(edges_o), Py_XDECREF(nd), Py_XDECREF(ed), Py_XDECREF(labels);
  Py_XDECREF(xyz), Py_XDECREF(edges);
  return rc;
}
