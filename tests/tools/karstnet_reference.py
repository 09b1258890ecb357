#!/usr/bin/python3
"""Independent reference for the metrics of Collon et al. 2017 as Karstnet 1.2.0 computes them.

Written from the rules of METRICS.md (the project brief) and docs/metrics.md only, without
reading src/metrics/: plain Python 3 (no numpy, no networkx), so it runs on Debian's
/usr/bin/python3 as it comes. It reads a Karstnet node/link pair (X_nodes.dat "x y [z]",
X_links.dat "i j" 1-based) -- the shipped .dat files directly, and every other format through
build/tests/karst_export_network, which writes the network karst's readers return.

  karstnet_reference.py X_nodes.dat                 print every metric (%.17g)
  karstnet_reference.py X_nodes.dat --compare J     also compare with `karst metrics -f json`
                                                    output J, 1e-9 relative (exit 1 on a miss)
  karstnet_reference.py X_nodes.dat --expect NAME   compare with the values pinned below
                                                    (Monachou: METRICS.md, 1e-9 relative;
                                                    Sakany: published, to the printed digits)

The tests/cli/test_reference_metrics.sh ctest runs all of this on the shipped surveys.
"""
import json
import math
import sys
from collections import deque

NAN = float("nan")

# Karstnet 1.2.0's Monachou values, full precision (METRICS.md, "Expected values").
MONACHOU = {
    "nodes": 251, "edges": 258, "reduced_nodes": 80, "reduced_edges": 87, "cycles": 8,
    "mean_length": 8.464115572807527, "cv_length": 0.9032881766753411,
    "length_entropy": 0.5510231430687663, "tortuosity": 1.2432160789955717,
    "orientation_entropy": 0.9837612087146957, "aspl": 7.5810126582278485,
    "cpd": 0.40396221841503066, "mean_degree": 2.175, "cv_degree": 0.500321411333914,
    "correlation_vertex_degree": -0.2497381415531946,
}
# Sakany, datasets/published_metrics.csv (Collon et al. 2017 corrected 2021): (value, decimals).
SAKANY = {
    "nodes": (1716, 0), "edges": (1784, 0), "reduced_nodes": (344, 0), "reduced_edges": (412, 0),
    "components": (1, 0), "cycles": (69, 0),
    "orientation_entropy": (0.9924004495, 10), "mean_length": (20.70591431, 8),
    "length_entropy": (0.3770371929, 10), "cv_length": (0.914918698, 9),
    "tortuosity": (1.400939173, 9), "howard_alpha": (0.101, 3), "howard_beta": (1.2, 1),
    "howard_gamma": (0.4016, 4), "mean_degree": (2.395348837, 9), "cv_degree": (0.4708073225, 10),
    "correlation_vertex_degree": (-0.1680304631, 10), "aspl": (12.61890637, 8),
    "cpd": (0.267674075, 9), "vertical_extent": (141, 0),
}

KEYS = ["nodes", "edges", "total_length", "vertical_extent", "branches", "mean_length",
        "cv_length", "length_entropy", "tortuosity", "orientation_entropy", "reduced_nodes",
        "reduced_edges", "components", "cycles", "extremities", "junctions", "aspl", "cpd",
        "mean_degree", "cv_degree", "correlation_vertex_degree", "howard_alpha", "howard_beta",
        "howard_gamma"]


def read_karstnet(path):
    """Nodes [(x, y, z)] and 0-based links [(i, j)] of a Karstnet pair named by either file."""
    for suffix in ("_nodes.dat", "_links.dat"):
        if path.endswith(suffix):
            path = path[: -len(suffix)]
    nodes, links = [], []
    with open(path + "_nodes.dat") as f:
        for line in f:
            t = line.split("#")[0].split()
            if t:
                nodes.append((float(t[0]), float(t[1]), float(t[2]) if len(t) > 2 else 0.0))
    with open(path + "_links.dat") as f:
        for line in f:
            t = line.split("#")[0].split()
            if t:
                links.append((int(t[0]) - 1, int(t[1]) - 1))
    return nodes, links


def dist(a, b):
    return math.sqrt((a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2 + (a[2] - b[2]) ** 2)


def mean(v):
    return sum(v) / len(v)


def sample_std(v):
    m = mean(v)
    return math.sqrt(sum((x - m) ** 2 for x in v) / (len(v) - 1))


def histogram(values, weights, nbins, hi):
    """numpy.histogram on [0, hi] with nbins equal bins: a value on a boundary goes to the
    upper bin, the last bin is closed. Edges are hi*i/nbins, exact for hi = 100, 180."""
    edges = [hi * i / nbins for i in range(nbins + 1)]
    h = [0.0] * nbins
    for x, w in zip(values, weights):
        assert 0.0 <= x <= hi, x
        b = min(int(x // (hi / nbins)), nbins - 1)
        while b > 0 and x < edges[b]:
            b -= 1
        while b < nbins - 1 and x >= edges[b + 1]:
            b += 1
        h[b] += w
    return h


def entropy(h, base):
    t = sum(h)
    return -sum(c / t * math.log(c / t) for c in h if c > 0) / math.log(base)


def components(adj, nodes):
    seen, comps = set(), []
    for s in nodes:
        if s in seen:
            continue
        seen.add(s)
        comp, q = [s], deque([s])
        while q:
            v = q.popleft()
            for w in adj[v]:
                if w not in seen:
                    seen.add(w)
                    comp.append(w)
                    q.append(w)
        comps.append(comp)
    return comps


def compute(xyz, links, info=None):
    """Every metric of KEYS (NaN when undefined); @p info, a dict, receives diagnostics."""
    m = {k: NAN for k in KEYS}
    if info is None:
        info = {}
    info.update(azimuth_bin_disagreements=0, loop_branches=0, parallel_branches=0,
                coinciding_gs_edges=0)
    # Input graph: undirected simple graph from the edge list (networkx.Graph.add_edges_from).
    edges = sorted({(min(i, j), max(i, j)) for i, j in links})
    used = sorted({v for e in edges for v in e})
    m["nodes"], m["edges"] = len(used), len(edges)
    for k in ("reduced_nodes", "reduced_edges", "components", "cycles", "extremities",
              "junctions", "branches"):
        m[k] = 0
    if not edges:
        return m
    inc = {v: [] for v in used}  # incident edge ids, a self-loop twice
    for e, (i, j) in enumerate(edges):
        inc[i].append(e)
        inc[j].append(e)
    deg = {v: len(inc[v]) for v in used}
    elen = [dist(xyz[i], xyz[j]) for i, j in edges]
    m["total_length"] = sum(elen)
    zs = [xyz[v][2] for v in used]
    m["vertical_extent"] = max(zs) - min(zs)

    # Branches: walk from every node of degree != 2 (one node per ring) through degree-2 nodes.
    adj_full = {v: set() for v in used}
    for i, j in edges:
        adj_full[i].add(j)
        adj_full[j].add(i)
    starts = [v for v in used if deg[v] != 2]
    for comp in components(adj_full, used):
        if all(deg[v] == 2 for v in comp):
            starts.append(min(comp))
    edge_used = [False] * len(edges)
    branches = []  # (list of nodes, length)
    for s in starts:
        for e0 in inc[s]:
            if edge_used[e0]:
                continue
            path, length, v, e = [s], 0.0, s, e0
            while True:
                edge_used[e] = True
                length += elen[e]
                i, j = edges[e]
                v = j if v == i else i
                path.append(v)
                if deg[v] != 2 or v == s:
                    break
                e = inc[v][0] if inc[v][1] == e else inc[v][1]
            branches.append((path, length))
    assert all(edge_used), "an edge on no branch"
    m["branches"] = len(branches)
    lengths = [b[1] for b in branches]
    m["mean_length"] = mean(lengths)
    m["cv_length"] = sample_std(lengths) / m["mean_length"] if len(lengths) > 1 else NAN
    pos = [x for x in lengths if x > 0]
    if len(pos) <= 1:
        m["length_entropy"] = 0.0
    else:
        top = max(pos)
        x = [v / top * 100.0 for v in pos]
        m["length_entropy"] = entropy(histogram(x, [1.0] * len(x), 10, 100.0), 10)
    tort = []
    for path, length in branches:
        chord = dist(xyz[path[0]], xyz[path[-1]])
        if chord > 0:
            tort.append(length / chord)
    m["tortuosity"] = mean(tort) if tort else NAN

    # Orientation entropy: azimuth clockwise from grid north (+y), folded into [0, 180).
    az, w = [], []
    for i, j in edges:
        dx, dy = xyz[j][0] - xyz[i][0], xyz[j][1] - xyz[i][1]
        l2d = math.sqrt(dx * dx + dy * dy)
        if l2d > 0:
            az.append(math.fmod(math.degrees(math.atan2(dx, dy)) + 360.0, 180.0))
            w.append(l2d)
            # Karstnet's own operations (docs/metrics.md); METRICS.md says atan2 gives the
            # same bins on real data: check it edge by edge rather than assume it.
            a = abs(dx) / l2d
            k = math.asin(a) * 180 / math.pi if dx * dy > 0 else 90 + math.acos(a) * 180 / math.pi
            if int(math.fmod(k, 180.0) // 10) != int(az[-1] // 10):
                info["azimuth_bin_disagreements"] += 1
    m["orientation_entropy"] = entropy(histogram(az, w, 18, 180.0), 18) if len(az) >= 2 else 0.0

    # Reduced graph Gs: one edge per branch, loops cut in 3, parallel branches cut in 2.
    pair_count = {}
    for path, _ in branches:
        key = (min(path[0], path[-1]), max(path[0], path[-1]))
        pair_count[key] = pair_count.get(key, 0) + 1
    gs_edges = []
    for path, _ in branches:
        n = len(path)
        a, b = path[0], path[-1]
        if a == b:
            info["loop_branches"] += 1
        elif pair_count[(min(a, b), max(a, b))] > 1:
            info["parallel_branches"] += 1
        if a == b and n > 2:
            if n == 3:
                gs_edges += [(a, path[1]), (path[1], b)]
            else:
                k = n // 3
                gs_edges += [(a, path[k]), (path[k], path[2 * k]), (path[2 * k], b)]
        elif a != b and pair_count[(min(a, b), max(a, b))] > 1 and n > 2:
            k = n // 2
            gs_edges += [(a, path[k]), (path[k], b)]
        else:
            gs_edges.append((a, b))
    gs = sorted({(min(a, b), max(a, b)) for a, b in gs_edges})
    # Two loops on one node, or a loop beside a parallel pair, could collapse edges here:
    # METRICS.md does not say what then, so say it rather than guess.
    info["coinciding_gs_edges"] = len(gs_edges) - len(gs)
    gnodes = sorted({v for e in gs for v in e})
    adj = {v: [] for v in gnodes}
    gdeg = {v: 0 for v in gnodes}
    for a, b in gs:
        gdeg[a] += 1
        gdeg[b] += 1
        if a != b:
            adj[a].append(b)
            adj[b].append(a)
    N, S = len(gnodes), len(gs)
    comps = components(adj, gnodes)
    m["reduced_nodes"], m["reduced_edges"], m["components"] = N, S, len(comps)
    m["cycles"] = S - N + len(comps)
    m["extremities"] = sum(1 for v in gnodes if gdeg[v] == 1)
    m["junctions"] = sum(1 for v in gnodes if gdeg[v] > 2)
    m["howard_beta"] = S / N
    if N >= 3:
        m["howard_alpha"] = m["cycles"] / (2 * N - 5)
        m["howard_gamma"] = S / (3 * (N - 2))

    # aspl and betweenness: one BFS per source (Brandes 2001), hop counts.
    comp_of = {}
    for c, comp in enumerate(comps):
        for v in comp:
            comp_of[v] = c
    dsum = [0] * len(comps)
    bet = {v: 0.0 for v in gnodes}
    for s in gnodes:
        order, sigma, d, preds = [], {s: 1}, {s: 0}, {s: []}
        q = deque([s])
        while q:
            v = q.popleft()
            order.append(v)
            for x in adj[v]:
                if x not in d:
                    d[x] = d[v] + 1
                    sigma[x] = 0
                    preds[x] = []
                    q.append(x)
                if d[x] == d[v] + 1:
                    sigma[x] += sigma[v]
                    preds[x].append(v)
        dsum[comp_of[s]] += sum(d.values())
        delta = {v: 0.0 for v in order}
        for x in reversed(order):
            for v in preds[x]:
                delta[v] += sigma[v] / sigma[x] * (1.0 + delta[x])
            if x != s:
                bet[x] += delta[x]
    aspl = 0.0
    for c, comp in enumerate(comps):
        nc = len(comp)
        if nc > 1:
            aspl += nc * (dsum[c] / (nc * (nc - 1)))
    m["aspl"] = aspl / N
    if N > 1:
        # bet sums ordered pairs (s, t): that is the unordered-pair count times 2.
        scale = 1.0 / ((N - 1) * (N - 2)) if N > 2 else 0.5
        b = [bet[v] * scale for v in gnodes]
        top = max(b)
        m["cpd"] = sum(top - x for x in b) / (N - 1)

    degs = [gdeg[v] for v in gnodes]
    m["mean_degree"] = 2 * S / N
    m["cv_degree"] = sample_std(degs) / mean(degs) if N > 1 else NAN
    if N > 1:
        xs, ys = [], []
        for a, b in gs:
            if a == b:
                xs.append(gdeg[a])
                ys.append(gdeg[a])
            else:
                xs += [gdeg[a], gdeg[b]]
                ys += [gdeg[b], gdeg[a]]
        mx, my = mean(xs), mean(ys)
        sxy = sum((x - mx) * (y - my) for x, y in zip(xs, ys))
        sxx = sum((x - mx) ** 2 for x in xs)
        syy = sum((y - my) ** 2 for y in ys)
        m["correlation_vertex_degree"] = 1.0 if sxx == 0 or syy == 0 else sxy / math.sqrt(sxx * syy)
    return m


def rel_ok(a, b, rel):
    if isinstance(a, float) and math.isnan(a) or b is None or isinstance(b, float) and math.isnan(b):
        return (a is None or math.isnan(a)) and (b is None or math.isnan(b))
    return abs(a - b) <= rel * max(abs(a), abs(b))


def main(argv):
    if len(argv) < 2 or argv[1].startswith("-"):
        sys.stderr.write(__doc__)
        return 2
    xyz, links = read_karstnet(argv[1])
    info = {}
    m = compute(xyz, links, info)
    for k in KEYS:
        print("%-26s %.17g" % (k, m[k]))
    for k, v in info.items():
        print("# %s: %d" % (k, v))
    # Either would make the numbers depend on a rule METRICS.md does not spell out.
    bad = info["azimuth_bin_disagreements"] + info["coinciding_gs_edges"]
    if len(argv) == 4 and argv[2] == "--compare":
        with open(argv[3]) as f:
            karst = json.load(f)[0]
        for k in KEYS:
            if not rel_ok(m[k], karst[k], 1e-9):
                print("MISMATCH %s: reference %.17g, karst %r" % (k, m[k], karst[k]))
                bad += 1
        print("compare with %s: %d of %d keys agree to 1e-9" % (argv[3], len(KEYS) - bad, len(KEYS)))
    elif len(argv) == 4 and argv[2] == "--expect":
        for k, want in {"monachou": {k: (v, None) for k, v in MONACHOU.items()},
                        "sakany": SAKANY}[argv[3]].items():
            v, dec = want
            ok = rel_ok(m[k], v, 1e-9) if dec is None else abs(m[k] - v) <= 0.5 * 10 ** -dec * (1 + 1e-9)
            if not ok:
                print("MISMATCH %s: reference %.17g, expected %r" % (k, m[k], v))
                bad += 1
        print("expected values of %s: %d mismatches" % (argv[3], bad))
    elif len(argv) != 2:
        sys.stderr.write(__doc__)
        return 2
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
