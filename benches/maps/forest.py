#!/usr/bin/env python3
"""Draws a "forest of blocks" map in the ROS map_server format (PGM + YAML), for the bake
benchmark (benches/bake.sh): square and oblong blocks of 0.4-3 m scattered at random (seeded)
over a free field with a one-cell border wall. Usage: forest.py OUT_STEM SIZE_CELLS CELL_M [SEED]
"""
import random
import sys


def main():
    stem, n, cell = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
    rng = random.Random(int(sys.argv[4]) if len(sys.argv) > 4 else 1)
    free, occ = 254, 0
    img = bytearray([free]) * (n * n)
    side_m = n * cell
    # About one block per 20 square metres.
    for _ in range(int(side_m * side_m / 20)):
        w = max(1, int(rng.uniform(0.4, 3.0) / cell))
        h = max(1, int(rng.uniform(0.4, 3.0) / cell))
        x, y = rng.randrange(n - w), rng.randrange(n - h)
        for r in range(y, y + h):
            img[r * n + x : r * n + x + w] = bytes([occ]) * w
    for i in range(n):
        img[i] = img[(n - 1) * n + i] = img[i * n] = img[i * n + n - 1] = occ
    with open(stem + ".pgm", "wb") as f:
        f.write(b"P5\n%d %d\n255\n" % (n, n))
        f.write(bytes(img))
    with open(stem + ".yaml", "w") as f:
        f.write(
            "image: %s.pgm\nmode: trinary\nresolution: %g\norigin: [0.0, 0.0, 0]\nnegate: 0\n"
            "occupied_thresh: 0.65\nfree_thresh: 0.25\n" % (stem.rsplit("/", 1)[-1], cell)
        )


if __name__ == "__main__":
    main()
