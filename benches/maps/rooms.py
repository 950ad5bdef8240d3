#!/usr/bin/env python3
"""Draws a small fine map of issue 23's case 2 kind in the ROS map_server format (PGM + YAML)
and a scenario file beside it: 20 m x 20 m at 0.05 m (400 x 400 cells), the start in a 4 m room
whose ways out are a 0.6 m and a 1 m gap, two long walls that make the way to the goal zig-zag
(the room and the walls of tests/promise_4_goals_join.rs), and a second room with a 0.8 m door around goal 2.
Usage: rooms.py OUT_DIR   (writes rooms.pgm, rooms.yaml, scenarios.toml)
"""
import os
import sys

CELL = 0.05
N = 400
# Walls as [x0, x1) x [y0, y1) in metres, y up from the lower-left corner (the map frame).
WALLS = [
    (1.0, 1.0, 5.1, 1.1), (1.0, 5.0, 2.0, 5.1), (2.6, 5.0, 5.1, 5.1),
    (1.0, 1.0, 1.1, 5.1), (5.0, 1.0, 5.1, 2.0), (5.0, 3.0, 5.1, 5.1),
    (0.0, 8.0, 17.0, 8.2), (3.0, 14.0, 20.0, 14.2),
    # A room around goal 2: (12, 2) to (18, 6), door 0.8 m in its left wall.
    (12.0, 2.0, 18.1, 2.1), (12.0, 6.0, 18.1, 6.1), (18.0, 2.0, 18.1, 6.1),
    (12.0, 2.0, 12.1, 3.6), (12.0, 4.4, 12.1, 6.1),
]


def main():
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    img = bytearray([254]) * (N * N)
    for row in range(N):
        y = (N - 1 - row + 0.5) * CELL  # image rows go down, the frame's y goes up
        for col in range(N):
            x = (col + 0.5) * CELL
            if any(x0 <= x < x1 and y0 <= y < y1 for x0, y0, x1, y1 in WALLS):
                img[row * N + col] = 0
    with open(os.path.join(out, "rooms.pgm"), "wb") as f:
        f.write(b"P5\n%d %d\n255\n" % (N, N))
        f.write(bytes(img))
    with open(os.path.join(out, "rooms.yaml"), "w") as f:
        f.write("image: rooms.pgm\nmode: trinary\nresolution: 0.05\norigin: [0.0, 0.0, 0]\n"
                "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.25\n")
    with open(os.path.join(out, "scenarios.toml"), "w") as f:
        f.write('# Drawn by benches/maps/rooms.py (issue 23, case 2 kind).\n[rooms]\n'
                'file = "rooms.yaml"\nstart = [3.0, 3.0]\n'
                'goals = [[18.0, 18.0], [15.0, 4.0], [3.0, 11.0]]\n')


if __name__ == "__main__":
    main()
