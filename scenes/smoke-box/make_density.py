"""Writes density.vol: a 32³ scalar grid (Mitsuba's .vol format, version 3, float32) of a smoke
plume, a sum of Gaussian puffs rising along y with a little swirl, values in [0, 1]. Deterministic;
run `python3 make_density.py` to rebuild it."""
import math, struct

N = 32
puffs = []
for i in range(9):
    t = i / 8.0
    puffs.append((0.5 + 0.18 * math.sin(5.0 * t), 0.15 + 0.7 * t, 0.5 + 0.18 * math.cos(4.0 * t), 0.05 + 0.05 * t))
data = []
for z in range(N):
    for y in range(N):
        for x in range(N):
            p = ((x + 0.5) / N, (y + 0.5) / N, (z + 0.5) / N)
            v = 0.0
            for (cx, cy, cz, r) in puffs:
                d2 = (p[0] - cx) ** 2 + (p[1] - cy) ** 2 + (p[2] - cz) ** 2
                v += math.exp(-d2 / (2 * r * r))
            data.append(min(max(v - 0.05, 0.0) / 0.95, 1.0))
with open("density.vol", "wb") as f:
    f.write(b"VOL" + bytes([3]))
    f.write(struct.pack("<iiiii", 1, N, N, N, 1))
    f.write(struct.pack("<6f", 0, 0, 0, 1, 1, 1))
    f.write(struct.pack("<%df" % len(data), *data))
