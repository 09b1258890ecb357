"""Render the Markdown tables of paper/ from `karst calibrate` outputs (standard library only).

calibration_tables.py posterior SCEN SURVEY SURVEY_FILE DIR [...]
    per calibration (DIR/calibration/calibration.json): every varied parameter, its prior, the
    scenario's own value, the posterior median and 90 % credible interval.
calibration_tables.py before_after SCEN SURVEY SURVEY_FILE DIR [...]
    per calibration: each metric of the survey next to the mean (5-95 %) of the ensemble of the
    scenario as shipped (DIR/before/metrics.csv) and of the calibrated best.yaml
    (DIR/calibration/best/metrics.csv); the standardised distance |mean - survey| / scale with the
    calibration's scales.
calibration_tables.py coverage TRUTHS.csv DIR [...]
    self-consistency: the fraction of true values inside the 90 % interval, per parameter.
"""
import csv
import json
import math
import os
import sys


def q7(xs, p):
    """Hyndman & Fan type-7 quantile (karst compare's definition)."""
    xs = sorted(xs)
    h = (len(xs) - 1) * p
    lo = math.floor(h)
    return xs[lo] if lo + 1 >= len(xs) else xs[lo] + (h - lo) * (xs[lo + 1] - xs[lo])


def column(path, name):
    vals = []
    for r in csv.DictReader(open(path)):
        if r.get(name, "") != "":
            vals.append(float(r[name]))
    return vals


def fmt(v):
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "–"
    return f"{v:.4g}"


def runs(args):
    if len(args) % 4:
        sys.exit("expected groups of SCENARIO SURVEY SURVEY_FILE DIR")
    for i in range(0, len(args), 4):
        yield args[i], args[i + 1], args[i + 2], args[i + 3]


def posterior(args):
    print("| scenario | survey | parameter | prior | shipped | posterior median | 90 % interval |"
          " generations, final ε |")
    print("|---|---|---|---|---|---|---|---|")
    sizes = set()
    for scen, survey, _, d in runs(args):
        j = json.load(open(os.path.join(d, "calibration", "calibration.json")))
        gens = len(j["generations"]) - 1
        sizes.add(f"{scen} {j['scenario_hash'][:10]}: {j['particles']} particles")
        eps = j["generations"][-1]["tolerance"]
        for p in j["parameters"]:
            prior = f"{p['prior']} {p['low']:g}–{p['high']:g}" + (", integer" if p["integer"] else "")
            shipped = p.get("scenario_value") or "default"
            print(f"| {scen} | {survey} | {p['key']} | {prior} | {shipped} | {fmt(p['median'])} | "
                  f"{fmt(p['q05'])} – {fmt(p['q95'])} | {gens}, {eps:.3g} |")
    print()
    print("Weighted posterior median and 5–95 % quantiles of the last generation "
          "(`karst calibrate`, `analysis/calibrate_surveys.sh`; scenario file hash and particles "
          "per generation: " + "; ".join(sorted(sizes)) + ").")


def before_after(args):
    print("| scenario vs survey | metric | survey | shipped: mean (5–95 %) | calibrated: mean "
          "(5–95 %) | \\|z\\| shipped → calibrated |")
    print("|---|---|---|---|---|---|")
    notes = []
    for scen, survey, _, d in runs(args):
        j = json.load(open(os.path.join(d, "calibration", "calibration.json")))
        before = os.path.join(d, "before", "metrics.csv")
        after = os.path.join(d, "calibration", "best", "metrics.csv")
        members = len(column(after, "mean_length"))
        closer = total = 0
        zb_sum = za_sum = 0.0
        for m in j["metrics"]:
            name, y, s = m["name"], m["survey"], m["scale"]
            b, a = column(before, name), column(after, name)
            if not b or not a:
                continue
            mb, ma = sum(b) / len(b), sum(a) / len(a)
            cell_b = f"{mb:.4g} ({q7(b, 0.05):.4g}–{q7(b, 0.95):.4g})"
            cell_a = f"{ma:.4g} ({q7(a, 0.05):.4g}–{q7(a, 0.95):.4g})"
            if s:
                zb, za = abs(mb - y) / s, abs(ma - y) / s
                zcell = f"{zb:.2f} → {za:.2f}"
                total += 1
                closer += za < zb
                zb_sum += zb * zb
                za_sum += za * za
            else:
                zcell = "not in the distance"
            print(f"| {scen} vs {survey} | {name} | {y:.4g} | {cell_b} | {cell_a} | {zcell} |")
        notes.append(f"{scen} vs {survey} ({members} members each): calibrated closer in "
                     f"{closer} of {total} metrics; "
                     f"distance of the ensemble mean {math.sqrt(zb_sum):.2f} → "
                     f"{math.sqrt(za_sum):.2f}")
    print()
    print("z = (ensemble mean − survey) / scale, the scale being the spread of the metric over the "
          "calibration's prior sample. " + "; ".join(notes) + ". Both ensembles use the same "
          "member seeds (the scenario's random.seed).")


def coverage(args):
    truths = list(csv.DictReader(open(args[0])))
    dirs = args[1:]
    keys = [k for k in truths[0].keys() if k != "replicate"]
    inside = {k: 0 for k in keys}
    width = {k: 0.0 for k in keys}
    n = 0
    for t, d in zip(truths, dirs):
        j = json.load(open(os.path.join(d, "calibration.json")))
        n += 1
        for p in j["parameters"]:
            k = p["key"]
            v = float(t[k])
            inside[k] += p["q05"] <= v <= p["q95"]
            if p["prior"] == "log-uniform":
                width[k] += math.log(p["q95"] / p["q05"]) / math.log(p["high"] / p["low"])
            else:
                cell = 1 if p["integer"] else 0
                width[k] += (p["q95"] - p["q05"] + cell) / (p["high"] - p["low"] + cell)
    print("| parameter | prior | true value inside the 90 % interval | mean interval width (share "
          "of the prior) |")
    print("|---|---|---|---|")
    j = json.load(open(os.path.join(dirs[0], "calibration.json")))
    for p in j["parameters"]:
        k = p["key"]
        prior = f"{p['prior']} {p['low']:g}–{p['high']:g}" + (", integer" if p["integer"] else "")
        print(f"| {k} | {prior} | {inside[k]} of {n} ({100 * inside[k] / n:.0f} %) | "
              f"{100 * width[k] / n:.0f} % |")
    print()
    print(f"{n} synthetic surveys, each generated from parameter values drawn from the prior; "
          f"{j['particles']} particles per generation, {len(j['generations']) - 1} generations "
          "(`analysis/calibration_selfconsistency.sh`). A correct sampler puts about 90 % of the "
          "true values inside their 90 % intervals; ABC with a tolerance above 0 is expected to "
          "be conservative (more than 90 %).")


if __name__ == "__main__":
    cmd = sys.argv[1]
    if cmd == "posterior":
        posterior(sys.argv[2:])
    elif cmd == "before_after":
        before_after(sys.argv[2:])
    elif cmd == "coverage":
        coverage(sys.argv[2:])
    else:
        sys.exit(f"unknown table {cmd}")
