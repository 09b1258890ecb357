#!/usr/bin/env python3
"""Write the regional-scale benchmark scenario datasets/scenarios/massif.yaml and its terrain grid
massif/terrain.asc (run from datasets/scenarios/: python3 massif/make_massif.py).

A 5 x 5 km karst massif, 500 m thick: a plateau around 430 m cut by a valley along its
northern edge, three gently dipping inception horizons, three fracture families, three springs
on the valley sides and the eastern and western edges, 80 sinks on the plateau (a jittered
8 x 10 grid, each 1 m under the terrain). About 10 million samples at an 8.7 m fill radius.
Deterministic: no random module, a fixed linear congruential sequence for the jitter."""
import math

N = 101          # grid nodes per side
CELL = 50.0      # m
SIDE = 5000.0


def terrain(x, y):
    plateau = 430 + 25 * math.sin(2 * math.pi * x / 3100) * math.cos(2 * math.pi * y / 2700)
    valley = 70 * math.exp(-((y - 4700) / 350) ** 2)
    return plateau - valley


def write_terrain(path):
    with open(path, "w") as f:
        f.write(f"ncols        {N}\nnrows        {N}\nxllcorner    {-CELL / 2}\n"
                f"yllcorner    {-CELL / 2}\ncellsize     {CELL:g}\nNODATA_value -9999\n")
        for r in range(N):  # first row is the northern edge
            y = (N - 1 - r) * CELL
            f.write(" ".join(f"{terrain(c * CELL, y):.2f}" for c in range(N)) + "\n")


def lcg():
    s = 20261203
    while True:
        s = (1103515245 * s + 12345) % 2 ** 31
        yield s / 2 ** 31


def main():
    write_terrain("massif/terrain.asc")
    u = lcg()
    sinks = []
    for i in range(8):
        for j in range(10):
            x = 400 + i * 600 + (next(u) - 0.5) * 300
            y = 300 + j * 420 + (next(u) - 0.5) * 200
            y = min(y, 4200)  # on the plateau, south of the valley
            sinks.append((x, y, terrain(x, y) - 1.0))
    springs = [("east_spring", (4990, 1500, 180.0)), ("valley_spring", (2500, 4700, 300.0)),
               ("west_spring", (10, 2500, 220.0))]
    with open("massif.yaml", "w") as f:
        f.write("""# Regional-scale benchmark (issue 17; bench/bench_massif.c, docs/performance.md): a 5 x 5 km
# karst massif 500 m thick, about 10 million samples. Written by massif/make_massif.py.
name: massif
units: m

domain:
  min: [0, 0, 0]
  max: [5000, 5000, 500]

# 50 m grid: a plateau around 430 m cut by a valley along the northern edge.
terrain:
  heightfield: massif/terrain.asc

# Three inception horizons dipping gently to the east (bedding) and to the north.
horizons:
  - {elevation: 360, dip: 1.5, dip_direction: 90, origin: [2500, 2500], radius: 6}
  - {elevation: 260, dip: 1.5, dip_direction: 90, origin: [2500, 2500], radius: 6}
  - {elevation: 160, dip: 2, dip_direction: 0, origin: [2500, 2500], radius: 6}

# Two sub-vertical joint sets and the bedding.
fractures:
  - {dip_direction: 30, dip: 85, weight: 0.5}
  - {dip_direction: 120, dip: 85, weight: 0.5}
  - {dip_direction: 90, dip: 2, weight: 0.3}

permeability:
  background: 1

# 80 sinks on the plateau; three springs, each with the horizontal water table through it.
key_points:
""")
        for k, (x, y, z) in enumerate(sinks):
            f.write(f"  - {{name: sink{k + 1}, type: sink, position: [{x:.1f}, {y:.1f}, {z:.2f}]}}\n")
        for name, (x, y, z) in springs:
            f.write(f"  - {{name: {name}, type: spring, position: [{x:g}, {y:g}, {z:g}]}}\n")
        f.write("""
cost:
  w0: 1
  horizon: 1
  fracture: 0.5
  permeability: 0

sampling:
  fill_radius: 8.7
  feature_radius: 8.7
  feature_band: 1
  k: 40
  max_samples: 12000000

skeleton:
  gamma: 2.0
  reuse: 0.5

amplification:
  steps: 1
  points: 40
  dead_end_fraction: 0.7

random:
  seed: 17
""")


if __name__ == "__main__":
    main()
