"""karst.Ensemble: the members and metrics of an ensemble directory as numpy arrays."""

import json
import os
import shutil
import weakref
from pathlib import Path

import numpy as np

from . import _karst

__all__ = ["Ensemble"]


class Ensemble:
    """An ensemble directory written by :func:`karst.ensemble` or ``karst ensemble``.

    directory     the directory (DIR/realisations/NNNN/network.vtp, DIR/metrics.csv,
                  DIR/ensemble.json; docs/ensembles.md)
    info          ensemble.json as a dict (scenario, seed, parameters, versions)
    log           ensemble_log.json as a dict (wall_seconds, computed, reused, threads, ranks),
                  or None when the directory has none
    index, seeds  (n,) member indices and member seeds (``karst generate --seed`` with a
                  member's seed reproduces it)
    metric_names  the metric columns, in the order of ``karst metrics``
    values        (n, k) float64 metric values, NaN where undefined
    metrics       {metric: (n,) array}, the columns of ``values``

    ``len(ens)``, ``ens[i]`` (the Network of member i, read from its network.vtp) and
    iteration over the members.
    """

    def __init__(self, directory, _temporary=False):
        self.directory = Path(directory)
        names, self.index, self.seeds, self.values = _karst.ensemble_table(
            self.directory / "metrics.csv")
        self.metric_names = list(names)
        self.metrics = {n: self.values[:, k] for k, n in enumerate(self.metric_names)}
        with open(self.directory / "ensemble.json", encoding="utf-8") as f:
            self.info = json.load(f)
        self.log = None
        if (self.directory / "ensemble_log.json").is_file():
            with open(self.directory / "ensemble_log.json", encoding="utf-8") as f:
                self.log = json.load(f)
        self._finalizer = None
        if _temporary:
            # An ensemble made without an output directory lives as long as this object.
            self._finalizer = weakref.finalize(self, shutil.rmtree, str(self.directory), True)

    def __len__(self):
        return int(self.index.shape[0])

    def __repr__(self):
        return (f"<karst.Ensemble {self.info.get('parameters', {}).get('name', '')!r}: "
                f"{len(self)} members, seed {self.info.get('seed')}, {self.directory}>")

    def member_directory(self, i):
        """DIR/realisations/NNNN of member i (at least four digits)."""
        return self.directory / "realisations" / f"{int(self.index[i]):04d}"

    def __getitem__(self, i):
        if not -len(self) <= i < len(self):
            raise IndexError(f"member {i} of an ensemble of {len(self)}")
        from . import read_survey
        net = read_survey(self.member_directory(i % len(self)) / "network.vtp")
        net.stats = {"seed": int(self.seeds[i]), "member": int(self.index[i])}
        return net

    def __iter__(self):
        for i in range(len(self)):
            yield self[i]

    def compare(self, survey, published=True):
        """Where a survey falls within the ensemble, as ``karst compare DIR --survey FILE``.

        survey     a path (any format karst reads), a :class:`karst.Network`, a networkx graph,
                   a dict of metric values, or None for the ensemble statistics alone.
        published  True: the ranges of the 34 caves of Collon et al. 2017
                   (:func:`karst.published`), a path to such a table, or False.
        Returns {metric: row}, each row a dict with survey, percentile (100 x members <= value
        / n), n, mean, sd (divisor n - 1), p05, p95 (type 7), min, max, published_min,
        published_max, published_n and outside_5_95, exactly as ``karst compare`` prints them.
        """
        from . import metrics, published as published_table
        label, names, values = None, [], []
        if survey is not None:
            m = survey if isinstance(survey, dict) else metrics(survey)
            label = os.fspath(survey) if isinstance(survey, (str, os.PathLike)) else "survey"
            names, values = list(m), [float(v) for v in m.values()]
        pub = None
        if published is True:
            pub = published_table()["path"]
        elif published:
            pub = os.fspath(published)
        rows = _karst.compare(self.directory / "metrics.csv", label, names, values, pub)
        return {r["metric"]: r for r in rows}

    def statistics(self):
        """{metric: {mean, sd, p05, p95, min, max, n}} of the ensemble (``karst compare DIR``)."""
        return {k: {f: r[f] for f in ("n", "mean", "sd", "p05", "p95", "min", "max")}
                for k, r in self.compare(None, published=False).items()}

    def keep(self):
        """Keep the directory of an ensemble made without ``output`` after this object is
        gone (otherwise it is removed with the object); returns the directory."""
        if self._finalizer is not None:
            self._finalizer.detach()
        return self.directory

