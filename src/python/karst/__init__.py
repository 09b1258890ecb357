"""karst: stochastic 3-D karst cave networks from geology, and their metrics, from Python.

The same library as the ``karst`` command (docs/python.md)::

    import karst
    net = karst.generate("datasets/scenarios/branchwork.yaml", seed=7)
    karst.metrics(net)["orientation_entropy"]
    survey = karst.read_survey("datasets/surveys/dowprov/DowProv.3d")
    ens = karst.ensemble("datasets/scenarios/branchwork.yaml", n=20)
    ens.metrics["mean_degree"]            # a numpy array over the members
    ens.compare(survey)["mean_degree"]    # as `karst compare`
    g = net.to_networkx()

Errors raise :class:`KarstError` subclasses whose message is the one the ``karst`` command
prints (after its "karst COMMAND: " prefix); long calls release the GIL, and Ctrl-C (or a
notebook's interrupt) stops them with KeyboardInterrupt.
"""

import os
import sys
import tempfile

import numpy as np

from . import _karst
from ._karst import (BusyError, ExternalError, InvalidValueError, KarstError, KarstIOError,
                     KarstWarning, NotFoundError, NotImplementedKarstError, ParseError,
                     RangeError, UnreachableError, UnsupportedError)
from ._ensemble import Ensemble
from ._network import Network, Samples

__version__ = _karst.__version__

__all__ = [
    "generate", "metrics", "read_survey", "ensemble", "read_ensemble", "export_gpkg",
    "published", "versions", "describe", "palette", "colours", "Network", "Samples", "Ensemble",
    "METRICS", "TUNNEL_TYPES", "NODE_KINDS", "KarstError", "KarstWarning", "InvalidValueError",
    "KarstIOError", "ParseError", "RangeError", "NotFoundError", "UnsupportedError",
    "UnreachableError", "ExternalError", "BusyError", "NotImplementedKarstError",
]

#: The metric names, in the order of ``karst metrics`` (docs/metrics.md).
METRICS = [name for name, _ in _karst.metric_fields()]
#: The names of the tunnel_type codes 0, 1, ... (Paris et al. 2021, §5.3).
TUNNEL_TYPES = _karst.tunnel_type_names()
#: The names of the node kind codes 0, 1, ...
NODE_KINDS = _karst.node_kind_names()


def _threads(threads):
    if threads is None:
        return 0
    if not isinstance(threads, int) or isinstance(threads, bool) or threads < 1:
        raise InvalidValueError(f"threads must be a whole number >= 1, got {threads!r}")
    return threads


class _TextProgress:
    """progress=True: one line on standard error, redrawn (a notebook shows it too)."""

    def __call__(self, stage, done, total):
        frac = done / total if total > 0 else 1.0
        bar = "#" * int(30 * frac) + "." * (30 - int(30 * frac))
        end = "\n" if total > 0 and done >= total else ""
        sys.stderr.write(f"\r{stage:<14} [{bar}] {100 * frac:5.1f}% ({done:.0f}/{total:.0f}){end}")
        sys.stderr.flush()


def _progress(progress):
    if progress is True:
        return _TextProgress()
    if progress in (None, False):
        return None
    if not callable(progress):
        raise TypeError("progress must be True, False, None or a callable(stage, done, total)")
    return progress


def generate(scenario, seed=None, realisation=0, threads=None, samples=False, progress=None):
    """One realisation of a scenario, as ``karst generate SCENARIO -o DIR --seed SEED``.

    scenario     path of the scenario file (docs/scenario.md)
    seed         base seed (default: the scenario's random.seed); the same seed gives the
                 same network whatever ``threads``
    realisation  realisation index of the stream (seed, realisation); ``karst generate`` uses 0
    threads      worker threads (default: every processor)
    samples      also return the sample cloud as ``network.samples``
    progress     True for a progress line on standard error, or a callable(stage, done, total)
    Returns a :class:`Network` with ``stats`` (seed, counts, stage wall times).
    """
    d, stats, smp = _karst.generate(os.fspath(scenario), seed, realisation, _threads(threads),
                                    bool(samples), _progress(progress))
    net = Network._from_dict(d)
    net.title = stats["scenario_name"] or None
    net.stats = stats
    if smp is not None:
        net.samples = Samples(*smp)
    return net


def read_survey(path):
    """A network or survey file as a :class:`Network`, as ``karst metrics`` reads it: karst's
    .vtp, Karstnet X_nodes.dat / X_links.dat (either file), GOCAD .pl, Therion .sql, Survex
    .3d and .svx (through Debian's ``cavern``). Station names become ``labels``, the survey's
    coordinate system ``crs``."""
    return Network._from_dict(_karst.read_network(os.fspath(path)))


def _network_argument(obj):
    if isinstance(obj, (str, bytes, os.PathLike, Network)):
        return obj
    if hasattr(obj, "nodes") and hasattr(obj, "edges") and hasattr(obj, "graph"):
        return Network.from_networkx(obj)  # a networkx graph
    raise TypeError(f"expected a karst.Network, a networkx graph or a path, got {type(obj).__name__}")


def metrics(network, azimuth_rotation=0.0, threads=None):
    """The metrics of Collon et al. 2017 exactly as Karstnet 1.2.0 computes them, as
    ``karst metrics`` prints them (docs/metrics.md).

    network           a :class:`Network`, a networkx graph with 3-D ``pos``, or a path
    azimuth_rotation  degrees added (clockwise) to every azimuth before the orientation
                      entropy, e.g. a meridian convergence for true north (default 0)
    threads           threads for the betweenness (default: every processor; the result does
                      not depend on it)
    Returns {metric: value} in the order of :data:`METRICS`: counts as int, the others as
    float, NaN where undefined (``karst metrics`` prints "undefined").
    """
    return _karst.metrics(_network_argument(network), float(azimuth_rotation), _threads(threads))


def ensemble(scenario, n=None, output=None, seed=None, threads=None, progress=None):
    """N realisations of a scenario, as ``karst ensemble SCENARIO -n N -o OUTPUT``.

    n         members (default: the scenario's random.realisations)
    output    the ensemble directory (the files of ``karst ensemble``; an existing complete
              ensemble of the same scenario and seed is reused, an interrupted one completed).
              Default: a temporary directory removed with the returned object (see
              :meth:`Ensemble.keep`).
    seed      base seed (default: the scenario's random.seed); member i uses the seed derived
              from (seed, i), so members do not depend on ``threads``
    threads   worker threads (default: every processor)
    progress  True for a progress line on standard error, or a callable(stage, done, total)
    Returns an :class:`Ensemble`.
    """
    temporary = output is None
    out = tempfile.mkdtemp(prefix="karst-ensemble-") if temporary else os.fspath(output)
    try:
        _karst.ensemble(os.fspath(scenario), out, n, seed, _threads(threads), _progress(progress))
        return Ensemble(out, _temporary=temporary)
    except BaseException:
        if temporary:
            import shutil
            shutil.rmtree(out, ignore_errors=True)
        raise


def read_ensemble(directory):
    """An ensemble directory written by ``karst ensemble`` or :func:`ensemble`."""
    return Ensemble(os.fspath(directory))


def export_gpkg(source, path, crs=None, qml=None, timestamp=None):
    """A GeoPackage for QGIS, as ``karst export SOURCE --gpkg PATH`` (docs/gis.md).

    source  a ``karst generate`` directory, an ensemble member directory, a network or survey
            file, or a :class:`Network` (no key points then)
    path    the GeoPackage (name ending in .gpkg), replaced atomically
    crs     coordinate system to write instead of the source's ("EPSG:2154", WKT, PROJ)
    qml     where to write the conduits' QGIS style (default: PATH with .qml)
    timestamp  the file's clock readings (gpkg_contents.last_change, layer_styles.update_time)
            as seconds since 1970-01-01 UTC or a timezone-aware datetime: the same input then
            gives a byte-identical file; default: $SOURCE_DATE_EPOCH when set (as the CLI),
            else the time of the export
    Returns {conduits, nodes, key_points, crs, crs_source}.
    """
    path = os.fspath(path)
    if qml is None:
        qml = (path[:-5] if path.endswith(".gpkg") else path) + ".qml"
    if not isinstance(source, Network):
        source = os.fspath(source)
    if timestamp is None:
        epoch = os.environ.get("SOURCE_DATE_EPOCH", "")
        if epoch and not (epoch.isascii() and epoch.isdigit()):
            err = InvalidValueError(
                "SOURCE_DATE_EPOCH: '%s' is not a number of seconds since 1970-01-01 UTC" % epoch)
            err.code = "KARST_EINVAL"
            raise err
        timestamp = int(epoch) if epoch else -1
    elif hasattr(timestamp, "timestamp"):
        if timestamp.utcoffset() is None:
            raise ValueError("export_gpkg: timestamp is a naive datetime; give its timezone")
        timestamp = int(timestamp.timestamp())
    elif isinstance(timestamp, bool) or not isinstance(timestamp, int) or timestamp < 0:
        raise ValueError("export_gpkg: timestamp must be seconds since 1970-01-01 UTC (an int "
                         ">= 0) or a datetime, not %r" % (timestamp,))
    return _karst.export_gpkg(source, path, crs, os.fspath(qml), timestamp)


def published(path=None):
    """The published ranges of the 34 caves of Collon et al. 2017 (corrected 2021), as
    ``karst metrics --observed`` uses them: {"path", "n_caves", "ranges": {metric: (n, min,
    max)}}. Without ``path``: datasets/published_metrics.csv found through $KARST_DATA_DIR, the
    source tree this package was built from, or the installed share/karst."""
    if path is None:
        from . import _config
        dirs = [os.environ.get("KARST_DATA_DIR")] + list(_config.DATA_DIRS)
        for d in dirs:
            if d and os.path.isfile(os.path.join(d, "published_metrics.csv")):
                path = os.path.join(d, "published_metrics.csv")
                break
    return _karst.published(None if path is None else os.fspath(path))


def versions():
    """{component: version}: those of ``karst --version`` (karst, the compiler, every library)
    and of Python, numpy and networkx."""
    v = dict(_karst.versions())
    v["Python"] = sys.version.split()[0]
    v["numpy"] = np.__version__
    try:
        import networkx
        v["networkx"] = networkx.__version__
    except ImportError:
        v["networkx"] = "not installed"
    return v


def describe(array):
    """What an array karst writes means: {"unit", "title", "meaning", "where"} (the unit "m",
    "1" for a ratio, "category", "index" ...; the title "conduit radius (m)"; the meaning with
    its sign convention, e.g. water_table_distance positive above), as the files state it
    (docs/arrays.md); None for an array karst does not describe."""
    return _karst.array_info(array)


def palette(array):
    """[(code, name, "#RRGGBB")] of a categorical array (tunnel_type, kind, source, vadose ...),
    the colours of the report, the ParaView scripts and the QGIS styles; None for others."""
    return _karst.palette(array)


def colours(role_or_array):
    """{code: "#RRGGBB"} of a categorical array, or the colour of a role of comparison plots
    ("ensemble", "survey", "published", "none", "structure")."""
    cats = _karst.palette(role_or_array)
    if cats is not None:
        return {code: colour for code, _, colour in cats}
    return _karst.role_colour(role_or_array)
