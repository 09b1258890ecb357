/* The functions of karst._karst: each parses its arguments with the GIL held, runs the library
 * with the GIL released (karst_py_call_*), and converts the result. */
#include "python/python_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A seed argument: None (-> *have = 0) or an int in [0, 2^64), refused as `karst generate
 * --seed` refuses it. */
static int parse_seed(PyObject *module, PyObject *obj, uint64_t *seed, int *have) {
  *have = 0;
  if (!obj || obj == Py_None) return 0;
  unsigned long long v = PyLong_Check(obj) ? PyLong_AsUnsignedLongLong(obj) : 0;
  if (!PyLong_Check(obj) || (v == (unsigned long long)-1 && PyErr_Occurred())) {
    PyErr_Clear();
    PyObject *r = PyObject_Repr(obj);
    const char *text = r ? PyUnicode_AsUTF8(r) : NULL;
    char msg[256];
    snprintf(msg, sizeof msg, "seed must be an integer from 0 to 18446744073709551615, got %.180s",
             text ? text : "?");
    Py_XDECREF(r);
    PyErr_Clear();
    karst_py_raise(module, KARST_ERANGE, msg);
    return -1;
  }
  *seed = v;
  *have = 1;
  return 0;
}

static PyObject *stats_dict(const karst_generate_stats_t *st, uint64_t seed, uint64_t realisation,
                            const karst_scenario_t *sc) {
  PyObject *stages = PyDict_New();
  for (int s = 0; stages && s < KARST_STAGE_COUNT; s++) {
    PyObject *v = PyFloat_FromDouble(st->stage_seconds[s]);
    if (!v || PyDict_SetItemString(stages, karst_stage_name(s), v) < 0) Py_CLEAR(stages);
    Py_XDECREF(v);
  }
  if (!stages) return NULL;
  return Py_BuildValue("{s:K,s:K,s:s,s:z,s:L,s:L,s:L,s:L,s:L,s:L,s:d,s:L,s:d,s:N}", "seed",
                       (unsigned long long)seed, "realisation", (unsigned long long)realisation,
                       "scenario_name", sc->name ? sc->name : "", "scenario", sc->path, "samples",
                       (long long)st->n_samples, "graph_edges", (long long)st->n_graph_edges,
                       "key_points", (long long)st->n_key_points, "skeleton_paths",
                       (long long)st->n_skeleton_paths, "network_nodes", (long long)st->n_nodes,
                       "network_edges", (long long)st->n_edges, "total_length", st->total_length,
                       "skeleton_nodes", (long long)st->n_skeleton_nodes, "skeleton_length",
                       st->skeleton_length, "stage_seconds", stages);
}

static PyObject *samples_tuple(const karst_samples_t *s) {
  npy_intp dims[2] = {(npy_intp)s->n, 3};
  PyArrayObject *xyz = (PyArrayObject *)PyArray_SimpleNew(2, dims, NPY_FLOAT64);
  PyArrayObject *src = (PyArrayObject *)PyArray_SimpleNew(1, dims, NPY_INT64);
  if (!xyz || !src) {
    Py_XDECREF(xyz), Py_XDECREF(src);
    return NULL;
  }
  if (s->n) memcpy(PyArray_DATA(xyz), s->xyz, 3 * (size_t)s->n * sizeof(double));
  int64_t *d = PyArray_DATA(src);
  for (karst_int_t i = 0; i < s->n; i++)
    d[i] = s->source[i];
  return Py_BuildValue("(NNL)", xyz, src, (long long)s->n_key_points);
}

/**
 * generate(scenario, seed=None, realisation=0, threads=0, samples=False, progress=None)
 * -> (network dict, stats dict, samples (xyz, source, n_key_points) or None).
 * karst_generate on the scenario file; seed None: the scenario's random.seed.
 */
PyObject *karst_py_generate(PyObject *module, PyObject *args, PyObject *kw) {
  static char *kwlist[] = {"scenario", "seed",     "realisation", "threads",
                           "samples",  "progress", NULL};
  PyObject *path_o, *seed_o = Py_None, *progress = Py_None, *path;
  unsigned long long realisation = 0;
  int threads = 0, want_samples = 0;
  if (!PyArg_ParseTupleAndKeywords(args, kw, "O|OKipO", kwlist, &path_o, &seed_o, &realisation,
                                   &threads, &want_samples, &progress))
    return NULL;
  uint64_t seed = 0;
  int have_seed;
  if (parse_seed(module, seed_o, &seed, &have_seed) < 0 || !(path = karst_py_path(path_o)))
    return NULL;
  karst_py_call_t c;
  karst_py_call_begin(&c, module, threads, progress);
  karst_scenario_t sc;
  karst_network_t net;
  karst_samples_t samples;
  karst_generate_stats_t stats;
  karst_scenario_init(&sc);
  karst_network_init(&net);
  karst_samples_init(&samples);
  karst_error_t err;
  Py_BEGIN_ALLOW_THREADS;
  err = karst_scenario_load(&c.ctx, PyBytes_AS_STRING(path), &sc);
  if (!err && !have_seed) seed = sc.seed;
  if (!err)
    err = karst_generate(&c.ctx, &sc, seed, realisation, &net, want_samples ? &samples : NULL,
                         &stats);
  Py_END_ALLOW_THREADS;
  Py_DECREF(path);
  PyObject *out = NULL;
  if (karst_py_call_finish(&c, err) == 0) {
    PyObject *n = karst_py_network_to_dict(&net), *st = stats_dict(&stats, seed, realisation, &sc);
    PyObject *sm = want_samples ? samples_tuple(&samples) : (Py_INCREF(Py_None), Py_None);
    if (n && st && sm) out = Py_BuildValue("(OOO)", n, st, sm);
    Py_XDECREF(n), Py_XDECREF(st), Py_XDECREF(sm);
  }
  karst_samples_destroy(&samples);
  karst_network_destroy(&net);
  karst_scenario_destroy(&sc);
  return out;
}

/* The one argument "path" of read_network and ensemble_table, as bytes (NULL on error). */
static PyObject *path_argument(PyObject *args, PyObject *kw) {
  static char *kwlist[] = {"path", NULL};
  PyObject *path_o;
  if (!PyArg_ParseTupleAndKeywords(args, kw, "O", kwlist, &path_o)) return NULL;
  return karst_py_path(path_o);
}

/** read_network(path) -> network dict (any format karst_read_network reads). */
PyObject *karst_py_read_network(PyObject *module, PyObject *args, PyObject *kw) {
  PyObject *path = path_argument(args, kw);
  if (!path) return NULL;
  karst_py_call_t c;
  karst_py_call_begin(&c, module, 1, NULL);
  karst_network_t net;
  karst_network_init(&net);
  karst_error_t err;
  Py_BEGIN_ALLOW_THREADS;
  err = karst_read_network(&c.ctx, PyBytes_AS_STRING(path), KARST_FORMAT_AUTO, &net);
  Py_END_ALLOW_THREADS;
  Py_DECREF(path);
  PyObject *out = karst_py_call_finish(&c, err) == 0 ? karst_py_network_to_dict(&net) : NULL;
  karst_network_destroy(&net);
  return out;
}

/* A network argument: a path (read with karst_read_network, GIL released) or an object with
 * the attributes of karst.Network. */
static int network_argument(PyObject *module, PyObject *obj, karst_network_t *net,
                            karst_py_call_t *c, karst_error_t *err) {
  *err = KARST_SUCCESS;
  if (PyUnicode_Check(obj) || PyBytes_Check(obj) || PyObject_HasAttrString(obj, "__fspath__")) {
    PyObject *path = karst_py_path(obj);
    if (!path) return -1;
    Py_BEGIN_ALLOW_THREADS;
    *err = karst_read_network(&c->ctx, PyBytes_AS_STRING(path), KARST_FORMAT_AUTO, net);
    Py_END_ALLOW_THREADS;
    Py_DECREF(path);
    return 0;
  }
  return karst_py_network_from_object(module, obj, net);
}

/**
 * metrics(network_or_path, azimuth_rotation=0.0, threads=0, progress=None) -> {metric: value}
 * in the order of karst_metric_fields (integers as int, others as float, NaN when undefined).
 */
PyObject *karst_py_metrics(PyObject *module, PyObject *args, PyObject *kw) {
  static char *kwlist[] = {"network", "azimuth_rotation", "threads", "progress", NULL};
  PyObject *obj, *progress = Py_None;
  double rotation = 0;
  int threads = 0;
  if (!PyArg_ParseTupleAndKeywords(args, kw, "O|diO", kwlist, &obj, &rotation, &threads, &progress))
    return NULL;
  if (!isfinite(rotation))
    return karst_py_raise(module, KARST_EINVAL, "azimuth_rotation must be a finite number");
  karst_py_call_t c;
  karst_py_call_begin(&c, module, threads, progress);
  karst_network_t net;
  karst_network_init(&net);
  karst_metrics_t m;
  karst_error_t err;
  if (network_argument(module, obj, &net, &c, &err) < 0) {
    karst_py_call_finish(&c, KARST_SUCCESS);
    karst_network_destroy(&net);
    return NULL;
  }
  if (!err) {
    karst_metrics_options_t opt;
    karst_metrics_options_init(&opt);
    opt.azimuth_rotation = rotation;
    Py_BEGIN_ALLOW_THREADS;
    err = karst_metrics_compute(&c.ctx, &net, &opt, &m);
    Py_END_ALLOW_THREADS;
  }
  karst_network_destroy(&net);
  if (karst_py_call_finish(&c, err) < 0) return NULL;
  int nf = 0;
  const karst_metric_field_t *f = karst_metric_fields(&nf);
  PyObject *d = PyDict_New();
  for (int k = 0; d && k < nf; k++) {
    double v = karst_metric_value(&m, &f[k]);
    PyObject *o =
        f[k].is_int && isfinite(v) ? PyLong_FromLongLong((long long)v) : PyFloat_FromDouble(v);
    if (!o || PyDict_SetItemString(d, f[k].key, o) < 0) Py_CLEAR(d);
    Py_XDECREF(o);
  }
  return d;
}

/** write_vtp(network, path): karst_vtk_write_network (atomic). */
PyObject *karst_py_write_vtp(PyObject *module, PyObject *args, PyObject *kw) {
  static char *kwlist[] = {"network", "path", NULL};
  PyObject *obj, *path_o, *path;
  if (!PyArg_ParseTupleAndKeywords(args, kw, "OO", kwlist, &obj, &path_o)) return NULL;
  karst_network_t net;
  karst_network_init(&net);
  if (karst_py_network_from_object(module, obj, &net) < 0 || !(path = karst_py_path(path_o))) {
    karst_network_destroy(&net);
    return NULL;
  }
  karst_py_call_t c;
  karst_py_call_begin(&c, module, 1, NULL);
  karst_error_t err;
  Py_BEGIN_ALLOW_THREADS;
  err = karst_vtk_write_network(&c.ctx, PyBytes_AS_STRING(path), &net);
  Py_END_ALLOW_THREADS;
  Py_DECREF(path);
  karst_network_destroy(&net);
  if (karst_py_call_finish(&c, err) < 0) return NULL;
  Py_RETURN_NONE;
}

/**
 * ensemble(scenario, output, n=None, seed=None, threads=0, progress=None) -> summary dict.
 * karst_ensemble_run with the real pipeline into @p output, as `karst ensemble` runs it: the
 * same files, resumable, members independent of the thread count. MPI is not used.
 */
PyObject *karst_py_ensemble(PyObject *module, PyObject *args, PyObject *kw) {
  static char *kwlist[] = {"scenario", "output", "n", "seed", "threads", "progress", NULL};
  PyObject *scen_o, *out_o, *n_o = Py_None, *seed_o = Py_None, *progress = Py_None;
  int threads = 0;
  if (!PyArg_ParseTupleAndKeywords(args, kw, "OO|OOiO", kwlist, &scen_o, &out_o, &n_o, &seed_o,
                                   &threads, &progress))
    return NULL;
  long long n = 0;
  if (n_o != Py_None) {
    n = PyLong_Check(n_o) ? PyLong_AsLongLong(n_o) : -1;
    if (PyErr_Occurred()) PyErr_Clear(), n = -1;
    if (n < 1 || n > KARST_ENSEMBLE_MAX_MEMBERS) {
      PyObject *r = PyObject_Repr(n_o);
      char msg[160];
      snprintf(msg, sizeof msg, "n must be a whole number of realisations within [1, %d], got %s",
               KARST_ENSEMBLE_MAX_MEMBERS, r ? PyUnicode_AsUTF8(r) : "?");
      Py_XDECREF(r);
      return karst_py_raise(module, KARST_ERANGE, msg);
    }
  }
  if (threads < 0 || threads > KARST_ENSEMBLE_MAX_THREADS) {
    char msg[128];
    snprintf(msg, sizeof msg, "threads must be a whole number within [1, %d], got %d",
             KARST_ENSEMBLE_MAX_THREADS, threads);
    return karst_py_raise(module, KARST_ERANGE, msg);
  }
  uint64_t seed = 0;
  int have_seed;
  if (parse_seed(module, seed_o, &seed, &have_seed) < 0) return NULL;
  PyObject *scen = karst_py_path(scen_o), *out = scen ? karst_py_path(out_o) : NULL;
  if (!scen || !out) {
    Py_XDECREF(scen);
    return NULL;
  }
  karst_py_call_t c;
  karst_py_call_begin(&c, module, threads, progress);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  char hash[17] = "";
  char *params = NULL;
  karst_ensemble_summary_t sum;
  memset(&sum, 0, sizeof sum);
  karst_ensemble_options_t opt;
  karst_ensemble_options_init(&opt);
  karst_error_t err;
  Py_BEGIN_ALLOW_THREADS;
  err = karst_scenario_load(&c.ctx, PyBytes_AS_STRING(scen), &sc);
  if (!err) err = karst_file_hash(&c.ctx, PyBytes_AS_STRING(scen), hash);
  if (!err && n_o == Py_None && sc.realisations > KARST_ENSEMBLE_MAX_MEMBERS)
    err = karst_set_error(
        &c.ctx, KARST_ERANGE, "%s: random.realisations must be at most %d, got %lld",
        PyBytes_AS_STRING(scen), KARST_ENSEMBLE_MAX_MEMBERS, (long long)sc.realisations);
  if (!err && !(params = karst_ensemble_parameters_json(&sc)))
    err = karst_set_error(&c.ctx, KARST_ENOMEM, "out of memory");
  if (!err) {
    opt.n = n_o != Py_None ? (karst_int_t)n : sc.realisations;
    opt.seed = have_seed ? seed : sc.seed;
    opt.nthreads =
        c.ctx.nthreads > KARST_ENSEMBLE_MAX_THREADS ? KARST_ENSEMBLE_MAX_THREADS : c.ctx.nthreads;
    opt.use_mpi = 0;
    opt.scenario_path = PyBytes_AS_STRING(scen);
    opt.scenario_hash = hash;
    opt.parameters_json = params;
    karst_ensemble_hooks_t hooks;
    karst_ensemble_pipeline_t pipe;
    err = karst_ensemble_hooks_pipeline(&c.ctx, &hooks, &pipe, &sc);
    if (!err) err = karst_ensemble_run(&c.ctx, PyBytes_AS_STRING(out), &opt, &hooks, &sum);
  }
  Py_END_ALLOW_THREADS;
  free(params);
  karst_scenario_destroy(&sc);
  PyObject *res = NULL;
  if (karst_py_call_finish(&c, err) == 0)
    res = Py_BuildValue("{s:O,s:L,s:K,s:L,s:L,s:L,s:d,s:i}", "directory", out_o, "n",
                        (long long)sum.n, "seed", (unsigned long long)opt.seed, "computed",
                        (long long)sum.computed, "reused", (long long)sum.reused, "complete",
                        (long long)sum.complete, "wall_seconds", sum.wall_seconds, "threads",
                        opt.nthreads);
  Py_DECREF(scen);
  Py_DECREF(out);
  return res;
}

/** ensemble_table(path) -> (names, index int64 (n,), seed uint64 (n,), values float64 (n, k)). */
PyObject *karst_py_ensemble_table(PyObject *module, PyObject *args, PyObject *kw) {
  PyObject *path = path_argument(args, kw);
  if (!path) return NULL;
  karst_py_call_t c;
  karst_py_call_begin(&c, module, 1, NULL);
  karst_ensemble_table_t t;
  karst_ensemble_table_init(&t);
  karst_error_t err;
  Py_BEGIN_ALLOW_THREADS;
  err = karst_ensemble_table_read(&c.ctx, PyBytes_AS_STRING(path), &t);
  Py_END_ALLOW_THREADS;
  Py_DECREF(path);
  PyObject *out = NULL;
  if (karst_py_call_finish(&c, err) == 0) {
    npy_intp dims[2] = {(npy_intp)t.n_rows, t.n_cols};
    PyArrayObject *idx = (PyArrayObject *)PyArray_SimpleNew(1, dims, NPY_INT64);
    PyArrayObject *seed = (PyArrayObject *)PyArray_SimpleNew(1, dims, NPY_UINT64);
    PyArrayObject *val = (PyArrayObject *)PyArray_SimpleNew(2, dims, NPY_FLOAT64);
    PyObject *names = PyList_New(t.n_cols);
    for (int k = 0; names && k < t.n_cols; k++) {
      PyObject *s = PyUnicode_FromString(t.names[k]);
      if (!s)
        Py_CLEAR(names);
      else
        PyList_SET_ITEM(names, k, s);
    }
    if (idx && seed && val && names) {
      size_t n = (size_t)t.n_rows;
      if (n) {
        memcpy(PyArray_DATA(idx), t.index, n * sizeof(int64_t));
        memcpy(PyArray_DATA(seed), t.seed, n * sizeof(uint64_t));
      }
      if (n > 0 && t.n_cols > 0)
        memcpy(PyArray_DATA(val), t.values, n * (size_t)t.n_cols * sizeof(double));
      out = Py_BuildValue("(OOOO)", names, idx, seed, val);
    }
    Py_XDECREF(idx), Py_XDECREF(seed), Py_XDECREF(val), Py_XDECREF(names);
  }
  karst_ensemble_table_destroy(&t);
  return out;
}

static PyObject *num(double v) {
  return PyFloat_FromDouble(v);
}

/**
 * compare(metrics_csv, label, names, values, published=None) -> [row dict]: karst_compare_compute
 * of one survey's metric values (names/values; label None and empty lists for the ensemble
 * alone) against the ensemble's metrics.csv and the published table (a path, or None: none).
 */
PyObject *karst_py_compare(PyObject *module, PyObject *args, PyObject *kw) {
  static char *kwlist[] = {"metrics_csv", "label", "names", "values", "published", NULL};
  PyObject *csv_o, *names_o, *values_o, *pub_o = Py_None, *csv, *pub = NULL;
  const char *label = NULL;
  if (!PyArg_ParseTupleAndKeywords(args, kw, "OzOO|O", kwlist, &csv_o, &label, &names_o, &values_o,
                                   &pub_o))
    return NULL;
  PyObject *names_seq = PySequence_Fast(names_o, "names must be a sequence of strings");
  PyObject *values_seq = names_seq ? PySequence_Fast(values_o, "values must be a sequence") : NULL;
  if (!values_seq) {
    Py_XDECREF(names_seq);
    return NULL;
  }
  Py_ssize_t nv = PySequence_Fast_GET_SIZE(names_seq);
  if (nv != PySequence_Fast_GET_SIZE(values_seq) || nv > KARST_ENSEMBLE_MAX_METRICS) {
    Py_DECREF(names_seq), Py_DECREF(values_seq);
    return karst_py_raise(module, KARST_EINVAL,
                          "names and values must have the same length, at most 64");
  }
  const char *names[KARST_ENSEMBLE_MAX_METRICS];
  double values[KARST_ENSEMBLE_MAX_METRICS];
  for (Py_ssize_t i = 0; i < nv; i++) {
    names[i] = PyUnicode_AsUTF8(PySequence_Fast_GET_ITEM(names_seq, i));
    values[i] = PyFloat_AsDouble(PySequence_Fast_GET_ITEM(values_seq, i));
    if (!names[i] || PyErr_Occurred()) {
      Py_DECREF(names_seq), Py_DECREF(values_seq);
      return NULL;
    }
  }
  if (!(csv = karst_py_path(csv_o)) || (pub_o != Py_None && !(pub = karst_py_path(pub_o)))) {
    Py_XDECREF(csv);
    Py_DECREF(names_seq), Py_DECREF(values_seq);
    return NULL;
  }
  karst_py_call_t c;
  karst_py_call_begin(&c, module, 1, NULL);
  karst_ensemble_table_t t;
  karst_published_t published;
  karst_compare_result_t res;
  karst_ensemble_table_init(&t);
  karst_published_init(&published);
  karst_compare_result_init(&res);
  karst_error_t err;
  Py_BEGIN_ALLOW_THREADS;
  err = karst_ensemble_table_read(&c.ctx, PyBytes_AS_STRING(csv), &t);
  if (!err && pub) err = karst_published_read(&c.ctx, PyBytes_AS_STRING(pub), &published);
  if (!err)
    err = karst_compare_compute(&c.ctx, &t, label, names, values, (int)nv, pub ? &published : NULL,
                                &res);
  Py_END_ALLOW_THREADS;
  Py_DECREF(names_seq), Py_DECREF(values_seq), Py_DECREF(csv), Py_XDECREF(pub);
  PyObject *list = NULL;
  if (karst_py_call_finish(&c, err) == 0) {
    list = PyList_New(res.n_rows);
    for (int i = 0; list && i < res.n_rows; i++) {
      const karst_compare_row_t *r = &res.rows[i];
      PyObject *row = Py_BuildValue(
          "{s:s,s:N,s:N,s:L,s:N,s:N,s:N,s:N,s:N,s:N,s:N,s:N,s:i,s:O}", "metric", r->metric,
          "survey", num(r->survey), "percentile", num(r->percentile), "n", (long long)r->ens.n,
          "mean", num(r->ens.mean), "sd", num(r->ens.sd), "p05", num(r->ens.p05), "p95",
          num(r->ens.p95), "min", num(r->ens.min), "max", num(r->ens.max), "published_min",
          num(r->has_published ? r->published_min : NAN), "published_max",
          num(r->has_published ? r->published_max : NAN), "published_n", r->published_n,
          "outside_5_95", r->outside ? Py_True : Py_False);
      if (!row)
        Py_CLEAR(list);
      else
        PyList_SET_ITEM(list, i, row);
    }
  }
  karst_compare_result_destroy(&res);
  karst_published_destroy(&published);
  karst_ensemble_table_destroy(&t);
  return list;
}

/**
 * export_gpkg(source, path, crs=None, qml=None, timestamp=-1) -> summary dict:
 * karst_export_source_load of a directory or file (or a karst.Network, without key points) and
 * karst_export_gpkg; timestamp in seconds since 1970 UTC, -1 (KARST_EXPORT_TIME_NOW): now.
 */
PyObject *karst_py_export_gpkg(PyObject *module, PyObject *args, PyObject *kw) {
  static char *kwlist[] = {"source", "path", "crs", "qml", "timestamp", NULL};
  PyObject *src_o, *path_o, *qml_o = Py_None, *path, *qml = NULL, *src_path = NULL;
  const char *crs = NULL;
  long long timestamp = KARST_EXPORT_TIME_NOW;
  if (!PyArg_ParseTupleAndKeywords(args, kw, "OO|zOL", kwlist, &src_o, &path_o, &crs, &qml_o,
                                   &timestamp))
    return NULL;
  karst_export_source_t src;
  karst_export_source_init(&src);
  int is_path =
      PyUnicode_Check(src_o) || PyBytes_Check(src_o) || PyObject_HasAttrString(src_o, "__fspath__");
  if (is_path ? !(src_path = karst_py_path(src_o))
              : karst_py_network_from_object(module, src_o, &src.net) < 0)
    goto early;
  if (!is_path && !(src.network_path = strdup("<Python karst.Network>"))) {
    PyErr_NoMemory();
    goto early;
  }
  if (!is_path && src.net.crs &&
      (!(src.crs = strdup(src.net.crs)) || !(src.crs_where = strdup("Network.crs")))) {
    PyErr_NoMemory();
    goto early;
  }
  if (!(path = karst_py_path(path_o))) goto early;
  if (qml_o != Py_None && !(qml = karst_py_path(qml_o))) {
    Py_DECREF(path);
    goto early;
  }
  karst_py_call_t c;
  karst_py_call_begin(&c, module, 1, NULL);
  karst_export_options_t opt;
  karst_export_options_init(&opt);
  opt.crs = crs;
  opt.qml_path = qml ? PyBytes_AS_STRING(qml) : NULL;
  opt.timestamp = (int64_t)timestamp;
  karst_error_t err = KARST_SUCCESS;
  Py_BEGIN_ALLOW_THREADS;
  if (src_path) err = karst_export_source_load(&c.ctx, PyBytes_AS_STRING(src_path), &src);
  if (!err) err = karst_export_gpkg(&c.ctx, PyBytes_AS_STRING(path), &src, &opt);
  Py_END_ALLOW_THREADS;
  Py_DECREF(path);
  Py_XDECREF(qml);
  PyObject *out = NULL;
  if (karst_py_call_finish(&c, err) == 0) {
    const char *used = crs ? crs : src.crs;
    out = Py_BuildValue("{s:L,s:L,s:i,s:z,s:z}", "conduits", (long long)src.net.n_edges, "nodes",
                        (long long)src.net.n_nodes, "key_points", src.n_key_points, "crs", used,
                        "crs_source", crs ? "crs argument" : src.crs_where);
  }
  Py_XDECREF(src_path);
  karst_export_source_destroy(&src);
  return out;
early:
  Py_XDECREF(src_path);
  karst_export_source_destroy(&src);
  return NULL;
}
