#!/usr/bin/env python3
"""Generates the synthetic Moving AI format maps and scenarios used by the planner tests.

The file format is the one of the Moving AI Lab grid benchmarks (N. Sturtevant, "Benchmarks
for Grid-Based Pathfinding", IEEE Trans. Computational Intelligence and AI in Games 4(2),
2012; https://movingai.com/benchmarks/, data under the Open Data Commons Attribution
licence). The maps here are NOT copies of those benchmarks: they are generated below with a
fixed seed, in the same four synthetic families (random, maze, room, warehouse).

Optimal lengths follow the benchmark's semantics: 8-connected, diagonal cost sqrt(2), no
corner cutting (a diagonal move needs both side cells passable). They are computed here by
an independent Dijkstra, so the planner under test is checked against a separate oracle.
"""
import heapq
import math
import os
import random

HERE = os.path.dirname(os.path.abspath(__file__))


def random_map(w, h, density, rng):
    return [["@" if rng.random() < density else "." for _ in range(w)] for _ in range(h)]


def maze_map(w, h, corridor, rng):
    # Recursive backtracker over a lattice of (corridor x corridor) cells with 1-cell walls.
    cells_x = (w - 1) // (corridor + 1)
    cells_y = (h - 1) // (corridor + 1)
    g = [["@"] * w for _ in range(h)]

    def carve(cx, cy):
        x0, y0 = 1 + cx * (corridor + 1), 1 + cy * (corridor + 1)
        for y in range(y0, y0 + corridor):
            for x in range(x0, x0 + corridor):
                g[y][x] = "."

    seen = {(0, 0)}
    stack = [(0, 0)]
    carve(0, 0)
    while stack:
        cx, cy = stack[-1]
        options = [(cx + dx, cy + dy, dx, dy) for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1))
                   if 0 <= cx + dx < cells_x and 0 <= cy + dy < cells_y and (cx + dx, cy + dy) not in seen]
        if not options:
            stack.pop()
            continue
        nx, ny, dx, dy = rng.choice(options)
        carve(nx, ny)
        # open the wall between the two cells
        x0, y0 = 1 + cx * (corridor + 1), 1 + cy * (corridor + 1)
        for k in range(corridor):
            if dx:
                g[y0 + k][x0 + (corridor if dx > 0 else -1)] = "."
            else:
                g[y0 + (corridor if dy > 0 else -1)][x0 + k] = "."
        seen.add((nx, ny))
        stack.append((nx, ny))
    return g


def room_map(w, h, room, rng):
    g = [["." for _ in range(w)] for _ in range(h)]
    for y in range(0, h, room + 1):
        for x in range(w):
            g[y][x] = "@"
    for x in range(0, w, room + 1):
        for y in range(h):
            g[y][x] = "@"
    # doors: one gap in each wall segment between neighbouring rooms (most of them)
    for ry in range(0, h - 1, room + 1):
        for rx in range(0, w - 1, room + 1):
            if rx + room + 1 < w and rng.random() < 0.85:
                g[min(ry + 1 + rng.randrange(room), h - 1)][rx + room + 1] = "."
            if ry + room + 1 < h and rng.random() < 0.85:
                g[ry + room + 1][min(rx + 1 + rng.randrange(room), w - 1)] = "."
    for x in range(w):
        g[0][x] = g[h - 1][x] = "@"
    for y in range(h):
        g[y][0] = g[y][w - 1] = "@"
    return g


def warehouse_map(w, h, rng):
    g = [["." for _ in range(w)] for _ in range(h)]
    # shelf blocks: 2 rows x 8 columns, in a grid with 2-cell aisles and wide cross aisles
    for top in range(4, h - 4, 4):
        for left in range(5, w - 10, 10):
            for y in range(top, top + 2):
                for x in range(left, left + 8):
                    g[y][x] = "@"
    for _ in range(w * h // 100):  # a few pallets left in the aisles
        g[rng.randrange(h)][rng.randrange(w)] = "T"
    return g


def passable(g, x, y):
    return 0 <= y < len(g) and 0 <= x < len(g[0]) and g[y][x] in ".GS"


def dijkstra(g, sx, sy):
    dist = {(sx, sy): 0.0}
    heap = [(0.0, sx, sy)]
    while heap:
        d, x, y = heapq.heappop(heap)
        if d > dist[(x, y)]:
            continue
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                if dx == 0 and dy == 0:
                    continue
                nx, ny = x + dx, y + dy
                if not passable(g, nx, ny):
                    continue
                if dx and dy and not (passable(g, x + dx, y) and passable(g, x, y + dy)):
                    continue
                nd = d + (math.sqrt(2.0) if dx and dy else 1.0)
                if nd < dist.get((nx, ny), math.inf):
                    dist[(nx, ny)] = nd
                    heapq.heappush(heap, (nd, nx, ny))
    return dist


def write(name, g, rng, count=24):
    h, w = len(g), len(g[0])
    with open(os.path.join(HERE, name + ".map"), "w") as f:
        f.write("type octile\nheight %d\nwidth %d\nmap\n" % (h, w))
        for row in g:
            f.write("".join(row) + "\n")
    free = [(x, y) for y in range(h) for x in range(w) if passable(g, x, y)]
    lines = []
    while len(lines) < count:
        sx, sy = rng.choice(free)
        dist = dijkstra(g, sx, sy)
        gx, gy = rng.choice(free)
        if (gx, gy) not in dist or (gx, gy) == (sx, sy):
            continue
        opt = dist[(gx, gy)]
        lines.append("%d\t%s.map\t%d\t%d\t%d\t%d\t%d\t%d\t%.8f\n" % (int(opt // 4), name, w, h, sx, sy, gx, gy, opt))
    lines.sort(key=lambda line: float(line.split("\t")[8]))
    with open(os.path.join(HERE, name + ".map.scen"), "w") as f:
        f.write("version 1\n")
        f.writelines(lines)


def main():
    rng = random.Random(20260601)
    write("random-32-32-10", random_map(32, 32, 0.10, rng), rng)
    write("random-64-64-20", random_map(64, 64, 0.20, rng), rng)
    write("maze-32-32-2", maze_map(32, 32, 2, rng), rng)
    write("room-32-32-4", room_map(32, 32, 4, rng), rng)
    write("warehouse-64-32", warehouse_map(64, 32, rng), rng)


if __name__ == "__main__":
    main()
