"""Water poured into the paper's soft cup (scenes/paper/cup.json, coarse), then the cup pushed
sideways by its base (a moving pinned region, like a tool): plots the rim's displacement and
the water kept inside the cup against time, to a PNG.

    PYTHONPATH=build/release/python python3 examples/python/push_cup.py --out push_cup.png
"""

import argparse
import pathlib

import matplotlib

matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt
import numpy as np

import sphfem

ROOT = pathlib.Path(__file__).resolve().parents[2]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="push_cup.png", help="the PNG to write")
    ap.add_argument("--radius", type=float, default=0.006, help="particle radius, m")
    ap.add_argument("--fill", type=float, default=0.8, help="s of pouring before the push")
    ap.add_argument("--push", type=float, default=0.4, help="s the push lasts")
    ap.add_argument("--distance", type=float, default=0.04, help="m the base moves along x")
    ap.add_argument("--settle", type=float, default=0.3, help="s after the push")
    args = ap.parse_args()

    scene = sphfem.load_scene(ROOT / "scenes/paper/cup.json")
    scene["fluid"]["particle_radius"] = args.radius
    scene["fluid"]["emitters"][0]["end"] = args.fill  # the pour stops when the push begins
    scene["bodies"][0]["resolution"] = 6
    cup = scene["bodies"][0]
    sim = sphfem.Simulation(scene, path=str(ROOT / "scenes/paper/cup.json"))

    base = sim.pinned_nodes("cup")
    rest = sim.rest_positions
    nodes = sim.body_nodes("cup")  # the cup's slice of the node arrays
    top = rest[nodes, 1].max()
    rim = nodes.start + np.flatnonzero(rest[nodes, 1] > top - 1e-4)  # the rim: its top nodes
    times, rim_dx, kept = [], [], []

    def measure():
        # The water kept: particles within the cup's inner radius and height, around the
        # base's present centre.
        centre = sim.body_positions[base].mean(axis=0)
        x = sim.positions
        r = np.hypot(x[:, 0] - centre[0], x[:, 2] - centre[2])
        inside = (r < cup["inner_radius"]) & (x[:, 1] < centre[1] + cup["height"])
        times.append(sim.time)
        rim_dx.append(1000 * (sim.body_positions[rim, 0] - rest[rim, 0]).mean())
        kept.append(int(inside.sum()))

    frame = 1 / scene["output"]["fps"]
    while sim.time < args.fill - 1e-9:
        sim.advance(frame)
        measure()
    t0 = sim.time
    while sim.time < t0 + args.push - 1e-9:  # the base slides at constant speed, step by step
        s = min(1.0, (sim.time - t0) / args.push)
        sim.move_pinned(base, rest[base] + [args.distance * s, 0, 0])
        sim.step()
        if abs(sim.time / frame - round(sim.time / frame)) < 1e-6:
            measure()
    sim.move_pinned(base, rest[base] + [args.distance, 0, 0])
    while sim.time < t0 + args.push + args.settle - 1e-9:
        sim.advance(frame)
        measure()

    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(times, rim_dx, color="tab:red")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("rim displacement along x (mm)", color="tab:red")
    ax.axvspan(t0, t0 + args.push, color="0.9", label="base pushed")
    ax2 = ax.twinx()
    ax2.plot(times, kept, color="tab:blue")
    ax2.set_ylabel("particles inside the cup", color="tab:blue")
    ax.set_title(f"soft cup pushed {1000 * args.distance:.0f} mm by its base")
    ax.legend(loc="upper left")
    fig.tight_layout()
    fig.savefig(args.out, dpi=100)
    print(f"{args.out}: {len(times)} frames, {sim.steps} steps, {sim.n_particles} particles, "
          f"{kept[-1]} inside the cup at t = {sim.time:.2f} s, rim moved "
          f"{rim_dx[-1]:.1f} mm")


if __name__ == "__main__":
    main()
