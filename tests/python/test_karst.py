#!/usr/bin/python3
"""The karst Python package against the karst command, which the other tests check.

Run by ctest (tests/CMakeLists.txt) as
    PYTHONPATH=build/python KARST_CLI=build/karst KARST_SOURCE_DIR=. python3 -m unittest test_karst
Expected values come from the `karst` binary on the same inputs (metrics to the digit: its JSON
prints 17 significant digits, which round-trip exactly), from networkx's own algorithms on the
to_networkx() view, from numpy on the arrays, and from hand calculation on small networks.
"""
import csv
import json
import math
import os
import signal
import subprocess
import tempfile
import threading
import time
import unittest
import warnings
from pathlib import Path

import networkx as nx
import numpy as np

# Under ASan, run_python_tests.sh preloads the sanitizer runtime into this interpreter; it is
# loaded now, and the programs started from here (the karst binary links its own runtime,
# Survex's cavern has none) must not get it.
os.environ.pop("LD_PRELOAD", None)

import karst  # noqa: E402

CLI = os.environ["KARST_CLI"]
SRC = Path(os.environ["KARST_SOURCE_DIR"])
SCENARIO = SRC / "datasets/scenarios/branchwork.yaml"
SURVEYS = [SRC / "datasets/surveys/dowprov/DowProv.3d",
           SRC / "datasets/surveys/tatra/processed/all_survex1.4.4.3d",
           SRC / "datasets/surveys/karstnet/Sakany_nodes.dat",
           SRC / "datasets/surveys/karstnet/Huttes_links.dat",
           SRC / "datasets/surveys/karstnet/Monachou.pl",
           SRC / "datasets/surveys/karstnet/g_huttes.sql"]


def cli(*args, check=True):
    r = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True)
    if check and r.returncode != 0:
        raise AssertionError(f"karst {' '.join(map(str, args))}: {r.returncode}\n{r.stderr}")
    return r


def cli_metrics(path):
    row = json.loads(cli("metrics", path, "--format", "json").stdout)[0]
    return {k: row[k] for k in karst.METRICS}


INTEGER = {name for name, is_int in karst._karst.metric_fields() if is_int}


def same(a, b):
    """Equal to the digit (the CLI's JSON writes 2.0 as 2); undefined (None in the CLI's JSON,
    NaN in Python) on both sides."""
    undefined = lambda v: v is None or (isinstance(v, float) and math.isnan(v))
    if undefined(a) or undefined(b):
        return undefined(a) and undefined(b)
    return float(a) == float(b)


def check_metrics(test, got, want, what):
    test.assertEqual(list(got), karst.METRICS)
    for k in karst.METRICS:
        test.assertTrue(same(got[k], want[k]), f"{what}: {k} {got[k]!r} != {want[k]!r}")
        test.assertIsInstance(got[k], int if k in INTEGER else float, f"{what}: {k}")


class Tmp(unittest.TestCase):
    def setUp(self):
        self._tmp = tempfile.TemporaryDirectory(prefix="karst-py-")
        self.tmp = Path(self._tmp.name)

    def tearDown(self):
        self._tmp.cleanup()


class TestMetrics(Tmp):
    def test_shipped_surveys_equal_karst_metrics(self):
        for path in SURVEYS:
            with self.subTest(survey=path.name):
                want = cli_metrics(path)
                for got in (karst.metrics(path), karst.metrics(karst.read_survey(path))):
                    check_metrics(self, got, want, path.name)

    def test_known_values_of_dowprov(self):
        # karst metrics prints these for the shipped Dow-Providence survey (692 stations after
        # splays, surface and duplicate legs are dropped; tests/cli/test_metrics.sh).
        m = karst.metrics(SURVEYS[0])
        self.assertEqual((m["nodes"], m["edges"]), (692, 689))

    def test_networkx_view_agrees_with_networkx(self):
        net = karst.read_survey(SURVEYS[2])  # Sakany: no parallel legs
        g = net.to_networkx()
        m = karst.metrics(net)
        self.assertEqual(g.number_of_nodes(), net.n_nodes)
        self.assertEqual(g.number_of_edges(), net.n_edges)
        # Independent: networkx's components and cyclomatic number against karst's reduced graph,
        # which keeps both; the degrees against numpy's count of edge ends.
        comps = nx.number_connected_components(g)
        self.assertEqual(comps, m["components"])
        self.assertEqual(g.number_of_edges() - g.number_of_nodes() + comps, m["cycles"])
        deg = np.bincount(net.edges.ravel(), minlength=net.n_nodes)
        self.assertEqual([d for _, d in sorted(g.degree)], deg.tolist())
        self.assertAlmostEqual(sum(d["length"] for *_, d in g.edges(data=True)),
                               m["total_length"], delta=1e-9 * m["total_length"])
        self.assertEqual(sum(1 for _, d in g.degree if d == 1), m["extremities"])
        # Round trip through networkx: the same metrics to the digit.
        check_metrics(self, karst.metrics(g), m, "networkx round trip")

    def test_small_networks_by_hand(self):
        # A 3-4-5 right angle: lengths 3 and 4, total 7, mean 3.5; one component, no cycle.
        net = karst.Network([[0, 0, 0], [3, 0, 0], [3, 4, 0]], [[0, 1], [1, 2]])
        m = net.metrics()
        self.assertEqual((m["nodes"], m["edges"], m["components"], m["cycles"]), (3, 2, 1, 0))
        self.assertEqual(m["total_length"], 7.0)
        self.assertEqual(m["vertical_extent"], 0.0)
        np.testing.assert_array_equal(net.lengths, [3.0, 4.0])
        # Two disconnected edges, a single node and the empty network: as `karst metrics` says
        # for the same network written to a .vtp.
        cases = {
            "disconnected": karst.Network([[0, 0, 0], [1, 0, 0], [5, 5, 5], [5, 6, 5]], [[0, 1], [2, 3]]),
            "single": karst.Network([[1, 2, 3]], np.empty((0, 2), dtype=np.int64)),
            "empty": karst.Network(np.empty((0, 3)), np.empty((0, 2), dtype=np.int64)),
            "collinear": karst.Network([[0, 0, 0], [1, 1, 1], [2, 2, 2]], [[0, 1], [1, 2]]),
        }
        for name, n in cases.items():
            with self.subTest(network=name):
                path = self.tmp / f"{name}.vtp"
                n.write_vtp(path)
                r = cli("metrics", path, "--format", "json", check=False)
                if r.returncode != 0:
                    with self.assertRaises(karst.KarstError) as e:
                        n.metrics()
                    self.assertIn(str(e.exception), r.stderr)
                    continue
                check_metrics(self, n.metrics(), json.loads(r.stdout)[0], name)
        self.assertEqual(cases["disconnected"].metrics()["components"], 2)


class TestGenerate(Tmp):
    def test_equals_karst_generate(self):
        cli("generate", SCENARIO, "-o", self.tmp / "g", "--seed", "7", "-q")
        want = karst.read_survey(self.tmp / "g/network.vtp")
        got = karst.generate(SCENARIO, seed=7)
        np.testing.assert_array_equal(got.xyz, want.xyz)
        np.testing.assert_array_equal(got.edges, want.edges)
        self.assertEqual(sorted(got.edge_data), sorted(want.edge_data))
        for d, w in ((got.edge_data, want.edge_data), (got.node_data, want.node_data)):
            for k in w:
                np.testing.assert_array_equal(d[k], w[k], err_msg=k)
        run = json.loads((self.tmp / "g/run.json").read_text())
        self.assertEqual(got.stats["seed"], 7)
        for k in ("samples", "key_points", "skeleton_paths", "network_nodes", "network_edges"):
            self.assertEqual(got.stats[k], run["counts"][k], k)
        self.assertEqual(got.stats["network_edges"], got.n_edges)
        self.assertEqual(got.edge_data["tunnel_type"].dtype, np.int64)
        self.assertEqual(set(got.names("tunnel_type")) - set(karst.TUNNEL_TYPES), set())

    def test_default_seed_threads_and_samples(self):
        a = karst.generate(SCENARIO, threads=1, samples=True)
        b = karst.generate(SCENARIO, threads=2)
        self.assertEqual(a.stats["seed"], 2021)  # branchwork.yaml's random.seed
        np.testing.assert_array_equal(a.xyz, b.xyz)
        np.testing.assert_array_equal(a.edges, b.edges)
        self.assertEqual(len(a.samples), a.stats["samples"])
        self.assertEqual(a.samples.n_key_points, a.stats["key_points"])
        np.testing.assert_array_equal(a.samples.source[:a.samples.n_key_points], 0)
        c = karst.generate(SCENARIO, seed=8)
        self.assertFalse(c.n_nodes == a.n_nodes and np.array_equal(c.xyz, a.xyz))

    def test_write_vtp_round_trip(self):
        net = karst.generate(SCENARIO, seed=3)
        net.write_vtp(self.tmp / "n.vtp")
        back = karst.read_survey(self.tmp / "n.vtp")
        np.testing.assert_array_equal(back.xyz, net.xyz)
        for k, v in net.edge_data.items():
            np.testing.assert_array_equal(back.edge_data[k], v)
        self.assertEqual(cli_metrics(self.tmp / "n.vtp")["aspl"], net.metrics()["aspl"])


class TestErrors(Tmp):
    def check_same_message(self, call, cmd, exc=karst.KarstError):
        r = cli(*cmd, check=False)
        self.assertEqual(r.returncode, 1, r.stderr)
        with self.assertRaises(exc) as e:
            call()
        self.assertEqual(r.stderr, f"karst {cmd[0]}: {e.exception}\n")
        return e.exception

    def test_scenario_errors_have_the_cli_messages(self):
        bad = sorted((SRC / "tests/data/scenarios/bad").glob("*.yaml"))
        self.assertGreater(len(bad), 20)
        for path in bad:
            with self.subTest(scenario=path.name):
                self.check_same_message(lambda: karst.generate(path),
                                        ("generate", path, "-o", self.tmp / "x", "-q"))
        e = self.check_same_message(lambda: karst.generate(self.tmp / "missing.yaml"),
                                    ("generate", self.tmp / "missing.yaml", "-o", self.tmp / "x"))
        self.assertIsInstance(e, OSError)
        self.assertEqual(e.code, "KARST_EIO")

    def test_survey_errors_have_the_cli_messages(self):
        (self.tmp / "bad.pl").write_text("GOCAD PLine 1\nVRTX 1 0 0 nan\n")
        (self.tmp / "bad_nodes.dat").write_text("0 0 0\n1 1\n")
        (self.tmp / "bad_links.dat").write_text("1 2\n")
        for f in ("bad.pl", "bad_nodes.dat", "nothing.3d", "x.unknown"):
            with self.subTest(file=f):
                self.check_same_message(lambda: karst.read_survey(self.tmp / f),
                                        ("metrics", self.tmp / f))
                self.check_same_message(lambda: karst.metrics(self.tmp / f),
                                        ("metrics", self.tmp / f))
        e = self.check_same_message(lambda: karst.read_survey(SRC / "tests/data/surveys/bad.svx"),
                                    ("metrics", SRC / "tests/data/surveys/bad.svx"))
        self.assertEqual(e.code, "KARST_EEXTERNAL")

    def test_argument_errors(self):
        with self.assertRaisesRegex(karst.RangeError, "seed must be an integer from 0 to 18446744073709551615, got -1"):
            karst.generate(SCENARIO, seed=-1)
        with self.assertRaisesRegex(karst.RangeError, r"n must be a whole number of realisations within \[1, 100000000\], got 0"):
            karst.ensemble(SCENARIO, n=0)
        with self.assertRaisesRegex(karst.InvalidValueError, "edge 0 names node 5; nodes are numbered 0 to 1"):
            karst.metrics(karst.Network([[0, 0, 0], [1, 0, 0]], [[0, 5]]))
        with self.assertRaisesRegex(karst.InvalidValueError, r"node 1: coordinates must be finite"):
            karst.metrics(karst.Network([[0, 0, 0], [1, np.nan, 0]], [[0, 1]]))
        with self.assertRaisesRegex(karst.InvalidValueError, "edge_data\\['radius'\\] has 3 rows"):
            karst.metrics(karst.Network([[0, 0, 0], [1, 0, 0]], [[0, 1]], edge_data={"radius": [1, 2, 3]}))
        with self.assertRaises(TypeError):
            karst.metrics(42)
        self.assertTrue(issubclass(karst.ParseError, ValueError))
        self.assertTrue(issubclass(karst.NotFoundError, FileNotFoundError))


class TestEnsemble(Tmp):
    def test_equals_karst_ensemble_and_compare(self):
        cli("ensemble", SCENARIO, "-n", "3", "--seed", "5", "-j", "1", "-o", self.tmp / "cli", "-q")
        ens = karst.ensemble(SCENARIO, n=3, seed=5, threads=2, output=self.tmp / "py")
        self.assertEqual(len(ens), 3)
        rows = list(csv.DictReader((self.tmp / "cli/metrics.csv").read_text().splitlines()))
        np.testing.assert_array_equal(ens.index, [int(r["index"]) for r in rows])
        np.testing.assert_array_equal(ens.seeds, np.array([int(r["seed"]) for r in rows], dtype=np.uint64))
        self.assertEqual(ens.metric_names, karst.METRICS)
        for k in karst.METRICS:
            want = np.array([float(r[k]) if r[k] else np.nan for r in rows])
            np.testing.assert_array_equal(ens.metrics[k], want, err_msg=k)
        self.assertEqual((self.tmp / "py/metrics.csv").read_bytes(), (self.tmp / "cli/metrics.csv").read_bytes())
        member = ens[1]
        gen = karst.generate(SCENARIO, seed=int(ens.seeds[1]))
        np.testing.assert_array_equal(member.xyz, gen.xyz)
        # compare: as `karst compare DIR --survey FILE --format json`
        survey = SURVEYS[0]
        want = json.loads(cli("compare", self.tmp / "cli", "--survey", survey, "--format", "json").stdout)
        got = ens.compare(survey)
        self.assertEqual(want[0]["survey"], str(survey))
        self.assertEqual(list(got), list(want[0]["metrics"]))
        for metric, w in want[0]["metrics"].items():
            g = got[metric]
            for key, value in w.items():
                if key == "outside_5_95":
                    self.assertIs(g[key], value, metric)
                elif value is None:
                    self.assertTrue(math.isnan(g[key]), f"{metric} {key}")
                else:
                    self.assertEqual(float(g[key]), float(value), f"{metric} {key}")

    def test_temporary_ensemble_is_removed(self):
        ens = karst.ensemble(SCENARIO, n=2, seed=1, threads=1)
        d = ens.directory
        self.assertTrue((d / "ensemble.json").is_file())
        self.assertEqual(ens.info["realisations"], 2)
        self.assertNotIn("timings", ens.info)  # the run log is ensemble_log.json
        self.assertEqual(ens.log["computed"], 2)
        self.assertEqual(ens.info["versions"]["karst"], karst.__version__)
        del ens
        import gc
        gc.collect()
        self.assertFalse(d.exists())

    def test_progress_and_failing_callback(self):
        seen = []
        karst.ensemble(SCENARIO, n=2, seed=2, threads=1, output=self.tmp / "p",
                       progress=lambda s, d, t: seen.append((s, d, t)))
        self.assertEqual(seen[-1], ("ensemble", 2.0, 2.0))
        self.assertEqual([d for _, d, _ in seen], sorted(d for _, d, _ in seen))

        class Stop(Exception):
            pass

        def stop(stage, done, total):
            raise Stop(stage)
        with self.assertRaises(Stop):
            karst.ensemble(SCENARIO, n=50, seed=3, threads=1, output=self.tmp / "s", progress=stop)
        self.assertFalse((self.tmp / "s/metrics.csv").exists())


class TestGilAndInterrupt(Tmp):
    def test_gil_is_released(self):
        # While another thread runs a long karst call, this thread keeps running: the largest
        # gap between its ticks stays far below the call's duration (with the GIL held during
        # the call, the gap would be the whole call).
        result = {}

        def work():
            t0 = time.monotonic()
            karst.ensemble(SCENARIO, n=4, seed=9, threads=1, output=self.tmp / "gil")
            result["seconds"] = time.monotonic() - t0
        t = threading.Thread(target=work)
        ticks = []
        t.start()
        while t.is_alive():
            ticks.append(time.monotonic())
            time.sleep(0.001)
        t.join()
        gaps = np.diff(ticks) if len(ticks) > 1 else np.array([result["seconds"]])
        self.assertGreater(result["seconds"], 0.5)
        self.assertLess(gaps.max(), 0.25 * result["seconds"], f"longest gap {gaps.max():.3f} s")

    def test_ctrl_c_stops_a_call(self):
        full = time.monotonic()
        timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
        timer.start()
        t0 = time.monotonic()
        with self.assertRaises(KeyboardInterrupt):
            karst.ensemble(SCENARIO, n=200, seed=4, threads=1, output=self.tmp / "int")
        timer.join()
        self.assertLess(time.monotonic() - t0, 60)
        # Nothing half-written: the finished members are complete, the run resumes.
        done = sorted(p.name for p in (self.tmp / "int/realisations").iterdir() if p.is_dir())
        self.assertLess(len(done), 200)
        for d in done:
            self.assertTrue((self.tmp / "int/realisations" / d / "metrics.csv").is_file(), d)
        self.assertIs(signal.getsignal(signal.SIGINT), signal.default_int_handler)
        del full


class TestGis(Tmp):
    def test_export_gpkg(self):
        cli("generate", SCENARIO, "-o", self.tmp / "g", "-q")
        s = karst.export_gpkg(self.tmp / "g", self.tmp / "g.gpkg", crs="EPSG:2154")
        self.assertEqual((s["conduits"], s["key_points"], s["crs"]), (karst.read_survey(self.tmp / "g/network.vtp").n_edges, 17, "EPSG:2154"))
        self.assertTrue((self.tmp / "g.qml").is_file())
        net = karst.read_survey(SURVEYS[0])
        s = net.export_gpkg(self.tmp / "dow.gpkg")
        self.assertEqual((s["nodes"], s["crs"]), (692, "EPSG:7405"))
        with self.assertRaisesRegex(karst.InvalidValueError, "must end in .gpkg"):
            karst.export_gpkg(self.tmp / "g", self.tmp / "g.shp")

    def test_export_timestamp_is_reproducible(self):
        # A fixed timestamp gives the file `SOURCE_DATE_EPOCH=... karst export` writes, byte for
        # byte (the CLI is the independent writer), as seconds or as an aware datetime
        # (1700000000 s = 2023-11-14 22:13:20 UTC by hand); bad values are refused.
        import datetime
        src = SURVEYS[0]  # a survey with its own CS: no generation needed (ASan time)
        env = dict(os.environ, SOURCE_DATE_EPOCH="1700000000")
        subprocess.run([CLI, "export", src, "--gpkg", self.tmp / "c.gpkg", "-q"],
                       env=env, check=True)
        utc = datetime.timezone.utc
        stamps = (1700000000, datetime.datetime(2023, 11, 14, 22, 13, 20, tzinfo=utc),
                  datetime.datetime(2023, 11, 15, 0, 13, 20,
                                    tzinfo=datetime.timezone(datetime.timedelta(hours=2))))
        for i, ts in enumerate(stamps):
            karst.export_gpkg(src, self.tmp / f"p{i}.gpkg", timestamp=ts)
            self.assertEqual((self.tmp / f"p{i}.gpkg").read_bytes(),
                             (self.tmp / "c.gpkg").read_bytes(), ts)
        old = os.environ.get("SOURCE_DATE_EPOCH")
        try:
            os.environ["SOURCE_DATE_EPOCH"] = "1700000000"
            karst.export_gpkg(src, self.tmp / "e.gpkg")
            self.assertEqual((self.tmp / "e.gpkg").read_bytes(), (self.tmp / "c.gpkg").read_bytes())
            os.environ["SOURCE_DATE_EPOCH"] = "12x"
            r = subprocess.run([CLI, "export", src, "--gpkg", self.tmp / "x.gpkg"],
                               capture_output=True, text=True)
            with self.assertRaises(karst.InvalidValueError) as e:
                karst.export_gpkg(src, self.tmp / "x.gpkg")
            self.assertEqual("karst export: " + str(e.exception), r.stderr.strip())
            self.assertEqual(e.exception.code, "KARST_EINVAL")
        finally:
            if old is None:
                os.environ.pop("SOURCE_DATE_EPOCH", None)
            else:
                os.environ["SOURCE_DATE_EPOCH"] = old
        for bad in (-5, 1.5, True, "1700000000", datetime.datetime(2023, 11, 14)):
            with self.assertRaises(ValueError, msg=repr(bad)):
                karst.export_gpkg(src, self.tmp / "x.gpkg", timestamp=bad)
        self.assertFalse((self.tmp / "x.gpkg").exists())

    def test_describe_agrees_with_the_files(self):
        # The unit and meaning of each array, as network.vtp's field data "array_units" states
        # them, read with VTK's own reader (python3-vtk9).
        net = karst.generate(SCENARIO, seed=3)
        net.write_vtp(self.tmp / "n.vtp")
        from vtkmodules.vtkIOXML import vtkXMLPolyDataReader
        r = vtkXMLPolyDataReader()
        r.SetFileName(str(self.tmp / "n.vtp"))
        r.Update()
        t = r.GetOutput().GetFieldData().GetAbstractArray("array_units")
        rows = [(t.GetValue(3 * i), t.GetValue(3 * i + 1), t.GetValue(3 * i + 2))
                for i in range(t.GetNumberOfTuples())]
        self.assertGreater(len(rows), 5)
        for name, unit, meaning in rows:
            d = karst.describe(name)
            if d is None:  # an array arrays.h does not know yet: the file says so too
                self.assertEqual(unit, "unknown", name)
            else:
                self.assertEqual((d["unit"], d["meaning"]), (unit, meaning), name)
        self.assertGreater(sum(karst.describe(n) is not None for n, _, _ in rows), 5)
        self.assertEqual(karst.describe("water_table_distance")["unit"], "m")
        self.assertIsNone(karst.describe("no such array"))

    def test_palette_and_versions(self):
        pal = karst.palette("tunnel_type")
        self.assertEqual([n for c, n, _ in pal if c >= 0], karst.TUNNEL_TYPES)
        self.assertEqual(len(set(karst.colours("tunnel_type").values())), len(pal))
        v = karst.versions()
        lines = cli("--version").stdout.splitlines()
        for line in lines:
            name, version = line.split(" ", 1)
            self.assertEqual(v[name], version)
        self.assertEqual(v["numpy"], np.__version__)


if __name__ == "__main__":
    unittest.main()
