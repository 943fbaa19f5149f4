#!/usr/bin/env python3
"""A small numpy particle simulation shown live as liquid, and recorded.

    python3 live_simulation.py [--steps 200] [--record splash.sluice] [--offscreen]

A block of water falls into a tank and splashes: gravity, a floor and walls
that bounce particles back with damping, the floor turning a landing
particle's fall into outward speed (the splash), and a soft push apart
between neighbours (on a hash grid) so the water spreads instead of piling
up. It is not SPH, just enough motion to watch. Each step pushes the positions
and speeds into a sluice.LiveView: a window (or offscreen with
--offscreen), never slowing the loop down; frames the view cannot keep up
with are dropped and counted. With --record the frames shown go into a
.sluice file that `sluice play` replays.
"""
import argparse
import sys
import time

import numpy as np
import numpy.typing as npt

import sluice

Array = npt.NDArray[np.float32]

TANK = np.array([1.6, 0.8, 1.0], dtype=np.float32)
SPACING = np.float32(0.025)


def initial_block() -> tuple[Array, Array]:
    n = tuple(int(k) for k in np.array([0.5, 0.5, 0.45]) / SPACING)
    g = np.indices(n).reshape(3, -1).T.astype(np.float32)
    x: Array = (g + 0.5) * SPACING + np.array([0.1, 0.15, 0.45], dtype=np.float32)
    return x, np.zeros_like(x)


def push_apart(x: Array, v: Array, dt: float) -> None:
    """Particles closer than the spacing push each other apart (grid cells of one spacing)."""
    cell = np.floor(x / SPACING).astype(np.int64)
    key = (cell[:, 0] * 73856093) ^ (cell[:, 1] * 19349663) ^ (cell[:, 2] * 83492791)
    order = np.argsort(key, kind="stable")
    sorted_key = key[order]
    # Pairs of particles in the same cell: each with the next ones of its run.
    for shift in (1, 2, 3):
        a, b = order[:-shift], order[shift:]
        same = sorted_key[:-shift] == sorted_key[shift:]
        a, b = a[same], b[same]
        d = x[a] - x[b]
        dist = np.linalg.norm(d, axis=1) + 1e-6
        push = np.clip(SPACING - dist, 0, None)[:, None] * d / dist[:, None] * (20.0 / dt)
        np.add.at(v, a, push * dt)
        np.add.at(v, b, -push * dt)


RNG = np.random.default_rng(1)


def step(x: Array, v: Array, dt: float) -> None:
    v[:, 2] -= 9.81 * dt
    push_apart(x, v, dt)
    x += v * dt
    landing = (x[:, 2] < 0) & (v[:, 2] < -0.2)
    if landing.any():
        # The splash: a landing particle's fall turns outward (from the
        # water's middle) and a little up, with some spread.
        out = x[landing, :2] - x[:, :2].mean(axis=0)
        out /= np.linalg.norm(out, axis=1, keepdims=True) + 1e-6
        fall = -v[landing, 2:3]
        v[landing, :2] += out * fall * 0.7 + RNG.normal(0, 0.15, (int(landing.sum()), 2)) * fall
        v[landing, 2] = fall[:, 0] * RNG.uniform(0.1, 0.5, int(landing.sum()))
    for axis in range(3):
        low, high = x[:, axis] < 0, x[:, axis] > TANK[axis]
        x[low, axis] = -x[low, axis] * 0.2
        x[high, axis] = TANK[axis] - (x[high, axis] - TANK[axis]) * 0.2
        v[low | high, axis] *= -0.3
    v *= 0.999


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--record", default=None, help="a .sluice file for the frames shown")
    parser.add_argument("--offscreen", action="store_true", help="no window (the last picture goes to --png)")
    parser.add_argument("--png", default=None, help="with --offscreen: write the last picture here")
    parser.add_argument("--keep-all", action="store_true", help="wait for the view instead of dropping frames")
    args = parser.parse_args()

    x, v = initial_block()
    dt = 1 / 120
    tank = (float(TANK[0]), float(TANK[1]), float(TANK[2]))
    view = sluice.LiveView(((0.0, 0.0, 0.0), tank), window=not args.offscreen, spacing=float(SPACING),
                           attributes=["speed"], color="speed", record=args.record, keep_all=args.keep_all,
                           fps=60, title="sluice: a falling block")
    start = time.monotonic()
    for i in range(args.steps):
        step(x, v, dt)
        if i % 2 == 0:  # 60 frames per simulated second
            if not view.push(x, time=i * dt, speed=np.linalg.norm(v, axis=1).astype(np.float32)):
                print("the window was closed")
                break
    view.close()
    seconds = time.monotonic() - start
    print(f"{len(x)} particles, {args.steps} steps in {seconds:.1f} s: pushed {view.pushed} frames, "
          f"shown {view.shown}, dropped {view.dropped}" + (f", recorded to {args.record}" if args.record else ""))
    if args.offscreen and args.png:
        import matplotlib.image

        matplotlib.image.imsave(args.png, view.image())
        print(f"wrote {args.png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
