"""karst.Network: a cave network as numpy arrays, and its networkx view."""

import numpy as np

from . import _karst

__all__ = ["Network", "Samples"]


def _names(array):
    """{code: name} of a categorical array of the shared palette (tunnel_type, kind, ...)."""
    cats = _karst.palette(array)
    return {code: name for code, name, _ in cats} if cats else None


class Network:
    """A cave network: 3-D nodes, undirected edges and named attribute arrays.

    The one type karst's generator writes, its survey readers return and its metrics consume
    (include/karst/network.h), held as numpy arrays:

    xyz        (n, 3) float64 node coordinates in metres (x east, y north, z up)
    edges      (m, 2) int64 node indices (0-based) of each edge
    node_data  {name: array}: per-node attributes, shape (n,) or (n, k) (e.g. ``kind``,
               ``water_table_distance`` in metres, positive above the water table)
    edge_data  {name: array}: per-edge attributes, shape (m,) or (m, k) (e.g. ``tunnel_type``,
               ``radius`` in metres); integer attributes are int64
    labels     station names (a list of n strings or None), or None
    crs        the coordinate system ("EPSG:32634", a Survex CS string ...), or None
    title      the survey's title, or None

    Networks from :func:`karst.generate` also carry ``stats`` (counts, seed, stage wall times)
    and ``samples`` (a :class:`Samples`, with ``samples=True``).
    """

    def __init__(self, xyz, edges, node_data=None, edge_data=None, labels=None, crs=None,
                 title=None):
        self.xyz = np.ascontiguousarray(np.asarray(xyz, dtype=np.float64).reshape(-1, 3))
        edges = np.asarray(edges)
        if edges.size == 0:
            edges = np.empty((0, 2), dtype=np.int64)
        if not np.issubdtype(edges.dtype, np.integer):
            raise TypeError(f"edges must hold integers, got dtype {edges.dtype}")
        self.edges = np.ascontiguousarray(edges.astype(np.int64).reshape(-1, 2))
        self.node_data = {k: np.asarray(v) for k, v in (node_data or {}).items()}
        self.edge_data = {k: np.asarray(v) for k, v in (edge_data or {}).items()}
        self.labels = list(labels) if labels is not None else None
        self.crs = crs
        self.title = title
        self.stats = None
        self.samples = None

    @classmethod
    def _from_dict(cls, d):
        return cls(d["xyz"], d["edges"], d["node_data"], d["edge_data"], d["labels"], d["crs"],
                   d["title"])

    @property
    def n_nodes(self):
        return int(self.xyz.shape[0])

    @property
    def n_edges(self):
        return int(self.edges.shape[0])

    def __len__(self):
        return self.n_edges

    def __repr__(self):
        what = self.title or (self.stats or {}).get("scenario_name") or "network"
        return (f"<karst.Network {what!r}: {self.n_nodes} nodes, {self.n_edges} edges, "
                f"{self.lengths.sum():.1f} m>")

    @property
    def lengths(self):
        """(m,) 3-D length of each edge, in metres."""
        if self.n_edges == 0:
            return np.zeros(0)
        d = self.xyz[self.edges[:, 1]] - self.xyz[self.edges[:, 0]]
        return np.sqrt((d * d).sum(axis=1))

    def names(self, attribute):
        """The category names of an integer attribute (``tunnel_type``, ``kind``, ``vadose``)
        as an array of strings, from the shared palette; None for codes without a name."""
        data = self.edge_data.get(attribute)
        if data is None:
            data = self.node_data.get(attribute)
        if data is None:
            raise KeyError(f"no node or edge attribute {attribute!r}")
        names = _names(attribute)
        if names is None:
            raise KeyError(f"{attribute!r} is not a categorical attribute of karst's palette")
        return np.array([names.get(int(v)) for v in data], dtype=object)

    def metrics(self, **options):
        """:func:`karst.metrics` of this network."""
        from . import metrics
        return metrics(self, **options)

    def write_vtp(self, path):
        """Write the network as a .vtp file for ParaView (atomically), as ``karst generate``."""
        _karst.write_vtp(self, path)

    def export_gpkg(self, path, crs=None, qml=None, timestamp=None):
        """Write the network as a GeoPackage for QGIS (:func:`karst.export_gpkg`)."""
        from . import export_gpkg
        return export_gpkg(self, path, crs=crs, qml=qml, timestamp=timestamp)

    def to_networkx(self, multigraph=False):
        """The network as a networkx graph.

        Nodes are 0 .. n-1 with ``pos`` (x, y, z), ``x``, ``y``, ``z``, ``label`` (when the
        network has labels) and every node attribute (several components as a tuple); edges
        carry ``edge`` (their index), ``length`` (m) and every edge attribute; categorical
        attributes also get their name (``tunnel_type_name``, ``kind_name``). A plain
        ``networkx.Graph`` keeps one of several parallel edges (surveys may have them: the
        last one); ``multigraph=True`` keeps them all in a ``networkx.MultiGraph``.
        """
        import networkx as nx

        g = nx.MultiGraph() if multigraph else nx.Graph()
        if self.title:
            g.graph["title"] = self.title
        g.graph["crs"] = self.crs

        def columns(data, n):
            out = []
            for name, a in data.items():
                vals = a.tolist()
                out.append((name, vals))
                names = _names(name) if a.ndim == 1 and np.issubdtype(a.dtype, np.integer) else None
                if names:
                    out.append((name + "_name", [names.get(v) for v in vals]))
            return out

        ncols = columns(self.node_data, self.n_nodes)
        for i, (x, y, z) in enumerate(self.xyz.tolist()):
            attrs = {"pos": (x, y, z), "x": x, "y": y, "z": z}
            if self.labels is not None:
                attrs["label"] = self.labels[i]
            for name, vals in ncols:
                v = vals[i]
                attrs[name] = tuple(v) if isinstance(v, list) else v
            g.add_node(i, **attrs)
        ecols = columns(self.edge_data, self.n_edges)
        lengths = self.lengths.tolist()
        for e, (u, v) in enumerate(self.edges.tolist()):
            attrs = {"edge": e, "length": lengths[e]}
            for name, vals in ecols:
                val = vals[e]
                attrs[name] = tuple(val) if isinstance(val, list) else val
            g.add_edge(u, v, **attrs)
        return g

    @classmethod
    def from_networkx(cls, graph, pos="pos"):
        """A Network from a networkx graph whose nodes carry their 3-D position.

        Each node needs ``pos`` (x, y, z) (another key with ``pos=``; a 2-D position gets
        z = 0), or ``x``, ``y`` and ``z``. Numeric node and edge attributes present on every node
        (edge) become node_data (edge_data); ``label`` becomes the labels. Karstnet's graphs
        (``pos3d``) read with ``pos="pos3d"``.
        """
        nodes = list(graph.nodes)
        index = {u: i for i, u in enumerate(nodes)}
        xyz = np.zeros((len(nodes), 3))
        for i, u in enumerate(nodes):
            a = graph.nodes[u]
            if pos in a:
                p = tuple(a[pos])
                if len(p) not in (2, 3):
                    raise ValueError(f"node {u!r}: {pos} must have 2 or 3 coordinates, got {p}")
                xyz[i, :len(p)] = p
            elif all(k in a for k in "xyz"):
                xyz[i] = (a["x"], a["y"], a["z"])
            else:
                raise ValueError(f"node {u!r} has no {pos!r} attribute and no x, y, z")
        edges = np.array([(index[u], index[v]) for u, v, *_ in graph.edges], dtype=np.int64)
        skip_nodes = {pos, "x", "y", "z", "label"}
        skip_edges = {"edge", "length"}

        def table(items, skip):
            keys = None
            for a in items:
                k = {n for n, v in a.items() if n not in skip and isinstance(v, (int, float))
                     and not isinstance(v, bool) and not n.endswith("_name")}
                keys = k if keys is None else keys & k
            return {k: np.array([a[k] for a in items]) for k in sorted(keys or ())}

        node_attrs = [graph.nodes[u] for u in nodes]
        edge_attrs = [d for *_, d in graph.edges(data=True)]
        labels = None
        if node_attrs and all("label" in a for a in node_attrs):
            labels = [a["label"] for a in node_attrs]
        return cls(xyz, edges.reshape(-1, 2), table(node_attrs, skip_nodes),
                   table(edge_attrs, skip_edges), labels, graph.graph.get("crs"),
                   graph.graph.get("title"))


class Samples:
    """The sample cloud of a realisation: ``xyz`` (n, 3), ``source`` (n,) codes (key_point,
    horizon, water_table, permeability, fill, amplification, prescribed_path) and
    ``n_key_points`` (the first samples are the key points)."""

    def __init__(self, xyz, source, n_key_points):
        self.xyz, self.source, self.n_key_points = xyz, source, int(n_key_points)

    def __len__(self):
        return int(self.xyz.shape[0])

    def __repr__(self):
        return f"<karst.Samples: {len(self)} samples, {self.n_key_points} key points>"

