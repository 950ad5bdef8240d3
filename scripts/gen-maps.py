#!/usr/bin/env python3
"""Maps of the kinds users bring (issue 42), generated with fixed seeds into a folder of PNGs
and a scenario file (nothing is committed):

    scripts/gen-maps.py OUT_DIR [--big]
    target/release/host-sim optimum --scenarios OUT_DIR/scenarios.toml --maps maze129

(--big takes about two minutes: the mazes are carved in plain Python.)

- maze129, maze511: perfect mazes of 1-cell corridors (depth-first carving), 1 m cells,
  start and goals in the corners;
- city1024: 1,024 x 1,024 cells of 1 m with 900 rectangular blocks of 8-40 cells a side;
- clutter512-10, clutter512-40: 512 x 512 cells of 1 m with 10 % and 40 % of the cells blocked
  at random (the MovingAI random maps), start and goals on the largest 4-connected free piece
  nearest the corners;
- rooms512: 512 x 512 cells at 0.25 m (128 m), rooms of 16 x 16 cells behind 1-cell walls, 1 m
  doors (4 cells) on a spanning tree of the rooms and on a third of the other walls (the
  MovingAI room maps);
- office4: the reference office (`../shared/maps/office.png`, when it is there) drawn at four
  times its cells, 0.25 m (800 x 800), its start and six goals (issue 42's "finer cells");
- house384, house500: small buildings drawn like SLAM maps at 0.05 m (as rooms4096 below,
  19.2 and 25 m a side), the size of the small SLAM maps of issue 42;
- with --big (issue 42's "any map up to 4096 x 4096 cells"): maze2047 and maze4095, mazes of
  1-cell corridors at 1 m; rooms4096, a building drawn like a SLAM map at 0.05 m (204.8 m a
  side): rooms split at random with 0.15 m walls and 0.9 m doors, furniture, and specks of
  sensor noise (one cell in 2,000).

The figures of the simulator guide's "Big maps" paragraph and of host-sim/src/metric/optimum.rs come from these.
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


def read_png(path):
    """Rows of 0/1 (occupied) from an 8-bit PNG, by the reference's rule: a pixel is occupied
    when its grey level is below the image's mean."""
    data = path.read_bytes()
    pos, idat = 8, b""
    while pos < len(data):
        n, tag = struct.unpack(">I4s", data[pos : pos + 8])
        body = data[pos + 8 : pos + 8 + n]
        if tag == b"IHDR":
            w, h, depth, kind = struct.unpack(">IIBB", body[:10])
        elif tag == b"IDAT":
            idat += body
        pos += 12 + n
    if depth != 8 or kind not in (0, 2, 4, 6):
        sys.exit(f"{path}: an 8-bit grey or RGB(A) PNG is needed")
    bpp = {0: 1, 2: 3, 4: 2, 6: 4}[kind]
    raw, stride, prev, rows = zlib.decompress(idat), w * bpp, bytearray(w * bpp), []
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1 : (y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b, c = prev[i], prev[i - bpp] if i >= bpp else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        prev = line
        if kind in (2, 6):
            rows.append([(299 * line[i] + 587 * line[i + 1] + 114 * line[i + 2]) / 1000 for i in range(0, stride, bpp)])
        else:
            rows.append([line[i] for i in range(0, stride, bpp)])
    mean = sum(map(sum, rows)) / (w * h)
    return [[1 if v < mean else 0 for v in r] for r in rows]


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


def rooms(w, seed):
    """A building at 0.05 m: walls of 3 cells split the floor into rooms (binary splits down
    to 4-20 m), each wall with one or two 18-cell doors; furniture; specks of noise."""
    rng = random.Random(seed)
    g = [bytearray(w) for _ in range(w)]

    def fill(x0, y0, x1, y1, v=1):
        for y in range(max(y0, 0), min(y1, w)):
            g[y][max(x0, 0) : min(x1, w)] = bytes([v]) * (min(x1, w) - max(x0, 0))

    fill(0, 0, w, 4)
    fill(0, w - 4, w, w)
    fill(0, 0, 4, w)
    fill(w - 4, 0, w, w)
    rooms_ = []

    def split(x0, y0, x1, y1):
        big = max(x1 - x0, y1 - y0)
        if big < 170 or (big < 400 and rng.random() < 0.4):
            rooms_.append((x0, y0, x1, y1))
            return
        vertical = (x1 - x0) >= (y1 - y0)
        if vertical:
            x = rng.randint(x0 + 80, x1 - 83)
            fill(x, y0, x + 3, y1)
            for _ in range(rng.randint(1, 2)):
                d = rng.randint(y0 + 4, max(y0 + 4, y1 - 22))
                fill(x, d, x + 3, d + 18, 0)
            split(x0, y0, x, y1)
            split(x + 3, y0, x1, y1)
        else:
            y = rng.randint(y0 + 80, y1 - 83)
            fill(x0, y, x1, y + 3)
            for _ in range(rng.randint(1, 2)):
                d = rng.randint(x0 + 4, max(x0 + 4, x1 - 22))
                fill(d, y, d + 18, y + 3, 0)
            split(x0, y0, x1, y)
            split(x0, y + 3, x1, y1)

    split(4, 4, w - 4, w - 4)
    for x0, y0, x1, y1 in rooms_:
        for _ in range(rng.randint(0, 4)):
            bw, bh = rng.randint(10, 40), rng.randint(10, 40)
            if x1 - x0 > bw + 40 and y1 - y0 > bh + 40:
                x, y = rng.randint(x0 + 20, x1 - bw - 20), rng.randint(y0 + 20, y1 - bh - 20)
                fill(x, y, x + bw, y + bh)
    for _ in range(w * w // 2000):
        g[rng.randrange(w)][rng.randrange(w)] = 1
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


def clutter(w, p, seed):
    """Random blocked cells; returns the grid and the cells of its largest 4-connected free
    piece nearest each corner (top-left, bottom-right, bottom-left, top-right)."""
    rng = random.Random(seed)
    g = [[1 if rng.random() < p else 0 for _ in range(w)] for _ in range(w)]
    label = [[0] * w for _ in range(w)]
    best, best_n, n_label = 0, 0, 0
    for y0 in range(w):
        for x0 in range(w):
            if g[y0][x0] or label[y0][x0]:
                continue
            n_label += 1
            label[y0][x0] = n_label
            stack, n = [(x0, y0)], 0
            while stack:
                x, y = stack.pop()
                n += 1
                for nx, ny in ((x + 1, y), (x - 1, y), (x, y + 1), (x, y - 1)):
                    if 0 <= nx < w and 0 <= ny < w and not g[ny][nx] and not label[ny][nx]:
                        label[ny][nx] = n_label
                        stack.append((nx, ny))
            if n > best_n:
                best, best_n = n_label, n
    ends = []
    for cx, cy in [(0, 0), (w - 1, w - 1), (0, w - 1), (w - 1, 0)]:
        ends.append(
            min(
                ((x, y) for y in range(w) for x in range(w) if label[y][x] == best),
                key=lambda c: (c[0] - cx) ** 2 + (c[1] - cy) ** 2,
            )
        )
    return g, ends


def room_grid(w, room, door, seed):
    """Rooms of `room` x `room` cells behind 1-cell walls; a door of `door` cells in every wall
    of a random spanning tree of the rooms and in a third of the others."""
    rng = random.Random(seed)
    n = (w - 1) // (room + 1)
    g = [[0] * w for _ in range(w)]
    for i in range(w):
        for j in range(0, w, room + 1):
            g[i][j] = g[j][i] = 1
    for j in range(w):
        g[w - 1][j] = g[j][w - 1] = 1
    parent = list(range(n * n))

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    walls = [(x, y, dx, dy) for y in range(n) for x in range(n) for dx, dy in ((1, 0), (0, 1))
             if x + dx < n and y + dy < n]
    rng.shuffle(walls)
    for x, y, dx, dy in walls:
        a, b = find(y * n + x), find((y + dy) * n + x + dx)
        if a != b or rng.random() < 1 / 3:
            parent[a] = b
            off = 1 + rng.randint(0, room - door)
            if dx:
                wx = (x + 1) * (room + 1)
                for k in range(door):
                    g[y * (room + 1) + off + k][wx] = 0
            else:
                wy = (y + 1) * (room + 1)
                for k in range(door):
                    g[wy][x * (room + 1) + off + k] = 0
    return g


def main():
    args = [a for a in sys.argv[1:] if a != "--big"]
    if len(args) != 1:
        sys.exit(__doc__)
    big = "--big" in sys.argv[1:]
    out = pathlib.Path(args[0])
    out.mkdir(parents=True, exist_ok=True)
    scenarios = []
    mazes = [("maze129", 64, 3), ("maze511", 255, 5)]
    if big:
        mazes += [("maze2047", 1023, 7), ("maze4095", 2047, 9)]
    for name, n, seed in mazes:
        g = maze(n, seed)
        png(out / f"{name}.png", g)
        far = len(g) - 1.5
        scenarios.append((name, [1.5, 1.5], [[far, far], [1.5, far], [far, 1.5]]))
    g = city(1024, 900, 11)
    png(out / "city1024.png", g)
    scenarios.append(("city1024", [2.5, 2.5], [[1021.5, 1021.5], [2.5, 1021.5], [1021.5, 2.5]]))
    for name, p, seed in [("clutter512-10", 0.1, 21), ("clutter512-40", 0.4, 23)]:
        g, ends = clutter(512, p, seed)
        png(out / f"{name}.png", g)
        m = [[x + 0.5, y + 0.5] for x, y in ends]
        scenarios.append((name, m[0], m[1:]))
    g = room_grid(512, 16, 4, 29)
    png(out / "rooms512.png", g)
    m = [[round((x + 0.5) * 0.25, 3), round((y + 0.5) * 0.25, 3)]
         for x, y in [(3, 3), (507, 507), (3, 507), (507, 3)]]
    scenarios.append(("rooms512", m[0], m[1:], 0.25))
    office = pathlib.Path(__file__).resolve().parent.parent.parent / "shared/maps/office.png"
    if office.exists():
        g = [[v for v in r for _ in range(4)] for r in read_png(office) for _ in range(4)]
        png(out / "office4.png", g)
        goals = [[125.6, 141.6], [162.6, 13.4], [170.8, 128.0], [60.0, 185.8], [23.8, 48.6], [185.0, 178.2]]
        scenarios.append(("office4", [79.0, 65.0], goals, 0.25))
    else:
        print(f"{office} is not there: no office4")
    buildings = [("house384", 384, 17), ("house500", 500, 19)]
    if big:
        buildings.append(("rooms4096", 4096, 13))
    for name, w, seed in buildings:
        g = rooms(w, seed)
        ends = [(10, 10), (w - 11, w - 11), (10, w - 11), (w - 11, 10)]
        for x, y in ends:
            for yy in range(y - 3, y + 4):
                g[yy][x - 3 : x + 4] = bytes(7)
        png(out / f"{name}.png", g)
        m = [[round((x + 0.5) * 0.05, 3), round((y + 0.5) * 0.05, 3)] for x, y in ends]
        scenarios.append((name, m[0], m[1:], 0.05))
    with open(out / "scenarios.toml", "w") as f:
        for name, start, goals, *cell in scenarios:
            f.write(
                f'[{name}]\nfile = "{name}.png"\nresolution_m = {(cell or [1.0])[0]}\n'
                f"start = {start}\ngoals = {goals}\n\n"
            )
    print(f"wrote {len(scenarios)} scenarios to {out / 'scenarios.toml'}")


if __name__ == "__main__":
    main()
