#!/usr/bin/env python3
"""Maps of the kinds users bring (issue 42), generated with fixed seeds into a folder of PNGs
and a scenario file (nothing is committed):

    scripts/gen-maps.py OUT_DIR
    target/release/host-sim optimum --scenarios OUT_DIR/scenarios.toml --scenario maze129

- maze129, maze511: perfect mazes of 1-cell corridors (depth-first carving), 1 m cells,
  start and goals in the corners;
- city1024: 1,024 x 1,024 cells of 1 m with 900 rectangular blocks of 8-40 cells a side.

The figures of README's "Big maps" paragraph and of host-sim/src/optimum.rs come from these.
"""

import pathlib
import random
import struct
import sys
import zlib


def png(path, rows):
    """A greyscale PNG: occupied cells black, free white."""
    raw = b"".join(b"\x00" + bytes(0 if v else 255 for v in r) for r in rows)

    def chunk(tag, data):
        body = tag + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", len(rows[0]), len(rows), 8, 0, 0, 0, 0)
    path.write_bytes(
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(raw, 9))
        + chunk(b"IEND", b"")
    )


def maze(n, seed):
    """A perfect maze of n x n rooms with 1-cell corridors: 2n + 1 cells a side."""
    rng = random.Random(seed)
    w = 2 * n + 1
    g = [[1] * w for _ in range(w)]
    stack, seen = [(0, 0)], {(0, 0)}
    g[1][1] = 0
    while stack:
        x, y = stack[-1]
        nb = [
            (x + dx, y + dy)
            for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1))
            if 0 <= x + dx < n and 0 <= y + dy < n and (x + dx, y + dy) not in seen
        ]
        if not nb:
            stack.pop()
            continue
        nx, ny = rng.choice(nb)
        seen.add((nx, ny))
        g[y + ny + 1][x + nx + 1] = 0
        g[2 * ny + 1][2 * nx + 1] = 0
        stack.append((nx, ny))
    return g


def city(w, blocks, seed):
    rng = random.Random(seed)
    g = [[0] * w for _ in range(w)]
    for _ in range(blocks):
        bw, bh = rng.randint(8, 40), rng.randint(8, 40)
        x, y = rng.randint(0, w - bw - 1), rng.randint(0, w - bh - 1)
        for yy in range(y, y + bh):
            for xx in range(x, x + bw):
                g[yy][xx] = 1
    for x, y in [(2, 2), (w - 3, w - 3), (2, w - 3), (w - 3, 2)]:
        g[y][x] = 0
    return g


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    out = pathlib.Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    scenarios = []
    for name, n, seed in [("maze129", 64, 3), ("maze511", 255, 5)]:
        g = maze(n, seed)
        png(out / f"{name}.png", g)
        far = len(g) - 1.5
        scenarios.append((name, [1.5, 1.5], [[far, far], [1.5, far], [far, 1.5]]))
    g = city(1024, 900, 11)
    png(out / "city1024.png", g)
    scenarios.append(("city1024", [2.5, 2.5], [[1021.5, 1021.5], [2.5, 1021.5], [1021.5, 2.5]]))
    with open(out / "scenarios.toml", "w") as f:
        for name, start, goals in scenarios:
            f.write(
                f'[{name}]\nfile = "{name}.png"\nresolution_m = 1.0\nstart = {start}\n'
                f"goals = {goals}\n\n"
            )
    print(f"wrote {len(scenarios)} scenarios to {out / 'scenarios.toml'}")


if __name__ == "__main__":
    main()
