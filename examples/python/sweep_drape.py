"""Sweeps the bend stiffness of the sheet and the friction of the sphere in
examples/drape_sphere.toml (3 x 3 samples of 90 frames: a minute or so on 2 cores) and plots
the final height profile of each sample, along the sheet's middle line, into a PNG.

    pip install ./crates/drapery-py matplotlib
    python examples/python/sweep_drape.py --output out/sweep_drape

Running it again skips the samples already done (delete a sample's folder to redo it).
The same sweep from the shell:

    drapery-sweep examples/drape_sphere.toml --output out/sweep_drape \\
        --param cloth.sheet.bend_stiffness=0.005,0.5,50 --param collider.0.friction=0,0.3,0.9
"""

import argparse
import sys
from pathlib import Path

import numpy as np

import drapery

SCENE = Path(__file__).resolve().parents[1] / "drape_sphere.toml"
PARAMS = {
    "cloth.sheet.bend_stiffness": [0.005, 0.5, 50.0],
    "collider.0.friction": [0.0, 0.3, 0.9],
}


def middle_line(out, sample_id):
    """The final (x, y) of the vertices that start on the sheet's middle line z = 0, by x."""
    with np.load(out / sample_id / "frames.npz") as z:
        x = z["positions"]
    start, final = x[0], x[-1]
    row = np.abs(start[:, 2]) < 1e-9
    order = np.argsort(start[row, 0])
    return final[row][order, 0], final[row][order, 1]


def plot(out, records, png):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    frictions = PARAMS["collider.0.friction"]
    fig, axes = plt.subplots(1, len(frictions), figsize=(4.2 * len(frictions), 3.6), sharey=True)
    theta = np.linspace(0.0, np.pi, 100)
    for ax, mu in zip(axes, frictions):
        ax.fill_between(0.25 * np.cos(theta), 0.25 - 0.25 * np.sin(theta), 0.25 + 0.25 * np.sin(theta), color="0.85", label="sphere")
        for r in records:
            if r["status"] != "ok" or r["params"]["collider.0.friction"] != mu:
                continue
            xs, ys = middle_line(out, r["id"])
            ax.plot(xs, ys, marker=".", label=f"bend {r['params']['cloth.sheet.bend_stiffness']:g}")
        ax.set_title(f"sphere friction {mu:g}")
        ax.set_xlabel("x (m)")
        ax.set_aspect("equal")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("final height y (m)")
    axes[-1].legend(fontsize=8)
    fig.suptitle("drape_sphere: the sheet's middle line at t = 1.5 s")
    fig.tight_layout()
    fig.savefig(png, dpi=110)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--output", default="out/sweep_drape", help="the sweep's folder")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--backend", choices=["local", "ray"], default="local")
    args = ap.parse_args()
    out = Path(args.output)
    records = drapery.sweep(SCENE, PARAMS, out, backend=args.backend, workers=args.workers)
    for r in records:
        print(f"{r['id']} {r['status']:6} {r['wall_time']:6.1f} s  {r['params']}  {r.get('error', '')}")
    try:
        png = out / "profiles.png"
        plot(out, records, png)
        print(f"wrote {png}")
    except ImportError:
        print("matplotlib is not installed: no plot (pip install matplotlib)", file=sys.stderr)


if __name__ == "__main__":
    main()
